"""Hysteresis error of eq. (13), for model curves and for sampled data.

For data, :func:`check_response` first asks whether the readout responds to the stress at all: a
dead sensor's constant readout would otherwise score a perfect 0 %.

References
----------
Matute et al., J. Sensors 2018, 6561901, doi:10.1155/2018/6561901, eq. (13), Table 2.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from scipy.constants import e, epsilon_0, h, m_e
from scipy.optimize import minimize_scalar

from fsrlab.errors import ParameterError
from fsrlab.physics.electrical import capacitance_per_area, resistance_per_area
from fsrlab.physics.params import (
    PAPER,
    PaperParameters,
    check_between,
    check_int,
    check_positive,
    float_array,
    paired_series,
)
from fsrlab.physics.separation import _loading, _unloading, separation_loading, separation_unloading
from fsrlab.physics.tunneling import _eq12

__all__ = [
    "HysteresisResult",
    "check_response",
    "hysteresis_error",
    "hysteresis_error_curves",
    "CycleErrors",
    "model_cycle_errors",
]


@dataclass
class HysteresisResult:
    """Outcome of eq. (13).

    Parameters
    ----------
    percent : float
        HE = 100 % · |Q_u(σd) − Q_l(σd)| / |Q(σf)|. [%]
    stress_at_max_pa : float
        σd, the stress of the largest difference between the branches. [Pa]
    difference : float
        Q_u(σd) − Q_l(σd), in the quantity's unit.
    full_scale : float
        |Q(σf)|, the loading branch at the largest stress, in the quantity's unit.
    sigma_f_pa : float
        σf, the largest stress. [Pa]
    method : str
        How the branches were compared.
    stress_pa, q_load, q_unload : ndarray or None
        The stresses the branches were compared at [Pa] and both branches there (the quantity's
        unit), for :meth:`plot`.
    """

    percent: float
    stress_at_max_pa: float
    difference: float
    full_scale: float
    sigma_f_pa: float
    method: str
    stress_pa: np.ndarray | None = field(default=None, repr=False, compare=False)
    q_load: np.ndarray | None = field(default=None, repr=False, compare=False)
    q_unload: np.ndarray | None = field(default=None, repr=False, compare=False)

    def plot(self, ax=None, label: str = "Q"):
        """Draw the loading and unloading branches and the largest difference, σd, of eq. (13).

        Parameters
        ----------
        ax : matplotlib.axes.Axes, optional
            Where to draw (default: a new figure).
        label : str
            Name of the quantity, for the axis label.

        Returns
        -------
        matplotlib.axes.Axes
            Lines in order: loading branch, unloading branch, the difference at σd (a vertical
            segment from the loading to the unloading branch).
        """
        if self.stress_pa is None:
            raise ParameterError("this result holds no branches to plot (no cycle was found)")
        if ax is None:
            import matplotlib.pyplot as plt

            _, ax = plt.subplots()
        _draw_branches(ax, self, label)
        ax.set_title(f"hysteresis error (eq. 13): {self.percent:.2f} %")
        return ax


def _draw_branches(ax, res: HysteresisResult, label: str = "Q", **style) -> None:
    """Draw a result's loading and unloading branches and its difference at σd on ``ax``."""
    at = float(np.interp(res.stress_at_max_pa, res.stress_pa, res.q_load))
    ax.plot(res.stress_pa, res.q_load, "-", color="tab:blue", label="loading", **style)
    ax.plot(res.stress_pa, res.q_unload, "-", color="tab:orange", label="unloading", **style)
    ax.plot([res.stress_at_max_pa] * 2, [at, at + res.difference], "k-", lw=2,
            label=f"largest difference, HE {res.percent:.2f} %", **style)
    ax.set_xlabel("stress [Pa]")
    ax.set_ylabel(label)
    ax.legend()


def _branch(stress, q, stress_name: str, q_name: str) -> tuple[np.ndarray, np.ndarray]:
    """One branch sorted by stress, repeated stresses averaged; errors name the argument at fault."""
    x = float_array(stress_name, stress).ravel()
    y = float_array(q_name, q).ravel()
    if x.size < 2:
        raise ParameterError(f"needs at least 2 samples, got {x.size}", parameter=stress_name)
    if x.shape != y.shape:
        raise ParameterError(f"must have the same length as {stress_name} ({x.size}), got {y.size}", parameter=q_name)
    if not np.all(np.isfinite(x)):
        raise ParameterError("must be finite", parameter=stress_name)
    if not np.all(np.isfinite(y)):
        raise ParameterError("must be finite", parameter=q_name)
    # Sort by stress and average repeated stresses so that interpolation is well defined.
    xs, inverse = np.unique(x, return_inverse=True)
    ys = np.bincount(inverse, weights=y) / np.bincount(inverse)
    if xs.size < 2:
        raise ParameterError("needs at least 2 distinct stresses", parameter=stress_name)
    return xs, ys


def hysteresis_error(stress_load_pa, q_load, stress_unload_pa, q_unload) -> HysteresisResult:
    """Hysteresis error of eq. (13) from sampled loading and unloading branches.

    Parameters
    ----------
    stress_load_pa, q_load : array_like
        Loading branch: stresses [Pa] and the quantity Q at them (any unit, any order).
    stress_unload_pa, q_unload : array_like
        Unloading branch, sampled at stresses that need not match the loading ones.

    Returns
    -------
    HysteresisResult

    Notes
    -----
    Eq. (13): ``HE = 100 % |Q_u(σd) − Q_l(σd)| / |Q(σf)|``. The two branches rarely share their
    stresses, so each branch is sorted by stress (readings at a repeated stress are averaged) and
    interpolated piecewise-linearly onto the union of both branches' stresses inside the range they
    share; σd is the grid stress with the largest ``|Q_u − Q_l|``. Q(σf) is the loading branch at its
    largest stress (both branches meet there in the model; a measured reading at the peak belongs to
    loading).

    References
    ----------
    Matute et al., J. Sensors 2018, 6561901, doi:10.1155/2018/6561901.
    """
    xl, yl = _branch(stress_load_pa, q_load, "stress_load_pa", "q_load")
    xu, yu = _branch(stress_unload_pa, q_unload, "stress_unload_pa", "q_unload")
    lo, hi = max(xl[0], xu[0]), min(xl[-1], xu[-1])
    if not hi > lo:
        raise ParameterError(f"the branches share no stress range (loading {xl[0]:g}–{xl[-1]:g} Pa, "
                             f"unloading {xu[0]:g}–{xu[-1]:g} Pa)", parameter="stress_unload_pa")
    grid = np.union1d(xl[(xl >= lo) & (xl <= hi)], xu[(xu >= lo) & (xu <= hi)])
    q_l, q_u = np.interp(grid, xl, yl), np.interp(grid, xu, yu)
    diff = q_u - q_l
    i = int(np.argmax(np.abs(diff)))
    full = abs(float(yl[-1]))
    if full == 0:
        raise ParameterError("is 0 at the largest stress: eq. (13) needs Q(σf) ≠ 0", parameter="q_load")
    return HysteresisResult(
        percent=100 * abs(float(diff[i])) / full,  # Eq. (13); Python floats: a tiny Q(σf) gives inf, no warning
        stress_at_max_pa=float(grid[i]),
        difference=float(diff[i]),
        full_scale=float(full),
        sigma_f_pa=float(xl[-1]),
        method=f"linear interpolation of both branches onto the union of their {grid.size} stresses "
               f"in the shared range {lo:g}–{hi:g} Pa",
        stress_pa=grid, q_load=q_l, q_unload=q_u,
    )


def check_response(stress_pa, q, name: str = "the readout", fraction: float = 0.2) -> None:
    """Raise ParameterError when a readout does not respond to the stress (a dead or disconnected sensor).

    Parameters
    ----------
    stress_pa, q : array_like, shape (n,)
        Reference stress [Pa] and the readout [any unit]; readings where either is NaN are ignored.
    name : str
        The readout's name, for the message.
    fraction : float
        Share of the stress range at each end whose readings are compared, in (0, 0.5]. [1]

    Raises
    ------
    fsrlab.errors.ParameterError
        (parameter ``q``) The readout does not respond: the difference Δ between its medians over the lowest and
        over the highest ``fraction`` of the stress range is not larger than its resolution (the
        smallest difference between two of its readings) or not larger than
        ``5 s √(1/n_low + 1/n_high)``, where ``s`` is its scatter within those two ends (1.4826 ×
        the median absolute deviation from each end's median). A constant readout (Δ = 0) and one
        that only flickers by noise or by one quantization step fail; eq. (13) would report a
        hysteresis error of a sensor that does not sense.

    Notes
    -----
    The scatter within the ends includes the sensor's hysteresis, so a hysteretic sensor is not
    taken for noise (its Δ is most of its full scale). Pure noise of a few hundred readings passes
    with a probability of about 0.1 % (Δ beyond 4 standard errors of a difference of medians).
    """
    x, y = paired_series("stress_pa", stress_pa, "q", q)
    check_between("fraction", fraction, 0.0, 0.5, lower_open=True, scalar=True)
    ok = np.isfinite(x) & np.isfinite(y)
    x, y = x[ok], y[ok]
    if y.size < 2:
        raise ParameterError(f"{name}: fewer than 2 readings with a reference stress", parameter="q")
    values = np.unique(y)
    if values.size == 1:
        raise ParameterError(f"{name} does not respond to the stress: it reads {values[0]:g} throughout "
                             f"({y.size} readings); a dead or disconnected sensor?", parameter="q")
    resolution = float(np.min(np.diff(values)))
    lo, hi = float(x.min()), float(x.max())
    low, high = y[x <= lo + fraction * (hi - lo)], y[x >= hi - fraction * (hi - lo)]
    ml, mh = float(np.median(low)), float(np.median(high))
    dev = np.concatenate([np.abs(low - ml), np.abs(high - mh)])
    limit = max(resolution, 5 * 1.4826 * float(np.median(dev)) * np.sqrt(1 / low.size + 1 / high.size))
    if not abs(mh - ml) > limit:
        raise ParameterError(f"{name} does not respond to the stress: its median changes by {mh - ml:.4g} from the "
                             f"lowest to the highest {fraction:.0%} of the stress range, not more than its resolution "
                             f"and noise ({limit:.4g}); a dead or disconnected sensor?", parameter="q")


def hysteresis_error_curves(
    q_load: Callable, q_unload: Callable, sigma_f_pa: float, n: int = 4001, refine: bool = True
) -> HysteresisResult:
    """Hysteresis error of eq. (13) for model branches given as functions of stress.

    Parameters
    ----------
    q_load, q_unload : callable
        Vectorised functions of stress [Pa] giving Q on each branch.
    sigma_f_pa : float
        Final stress σf; both branches are compared on [0, σf]. [Pa]
    n : int
        Points of the search grid, ≥ 3.
    refine : bool
        Refine σd by a bounded scalar search around the best grid point.

    Returns
    -------
    HysteresisResult
    """
    check_positive("sigma_f_pa", sigma_f_pa, "Pa", scalar=True)
    n = check_int("n", n, 3)
    for name, f in (("q_load", q_load), ("q_unload", q_unload)):
        if not callable(f):
            raise TypeError(f"{name}: must be a function of stress (a callable), got {type(f).__name__}")
    x = np.linspace(0.0, sigma_f_pa, n)
    return _curves_on_grid(x, q_load(x), q_unload(x), q_load, q_unload, refine)


def _curves_on_grid(x, ql, qu, q_load, q_unload, refine: bool, i: int | None = None) -> HysteresisResult:
    """Eq. (13) from both branches evaluated on the grid ``x`` = [0 … σf]; functions refine σd.

    ``i``: the grid index of the largest |qu − ql| when the caller found it already.
    """
    n, sigma_f_pa = x.size, float(x[-1])
    if i is None:
        i = int(np.nanargmax(np.abs(np.asarray(qu, dtype=float) - np.asarray(ql, dtype=float))))
    sd, d = float(x[i]), float(qu[i] - ql[i])
    method = f"both branches evaluated on {n} stresses in [0, σf]"
    if refine and 0 < i < n - 1:
        res = minimize_scalar(lambda t: -abs(float(q_unload(t)) - float(q_load(t))),
                              bounds=(x[i - 1], x[i + 1]), method="bounded", options={"xatol": 1e-9 * sigma_f_pa})
        if -res.fun >= abs(d):
            sd = float(res.x)
            d = float(q_unload(sd)) - float(q_load(sd))
        method += ", σd refined by a bounded scalar search"
    full = abs(float(q_load(sigma_f_pa)))
    return HysteresisResult(percent=100 * abs(d) / full, stress_at_max_pa=sd, difference=d,  # Eq. (13)
                            full_scale=full, sigma_f_pa=sigma_f_pa, method=method,
                            stress_pa=x, q_load=np.asarray(ql, dtype=float), q_unload=np.asarray(qu, dtype=float))


@dataclass
class CycleErrors:
    """Hysteresis errors of R_A and C_A over one model cycle 0 → σf → 0 (the paper's Table 2).

    Parameters
    ----------
    u_v : float
        Voltage across the composite. [V]
    resistance : HysteresisResult
        HE of R_A (eqs. 16–18).
    capacitance : HysteresisResult
        HE of C_A (eq. 15).
    regime : int
        Tunnelling equation used for R_A (10, 11 or 12).
    """

    u_v: float
    resistance: HysteresisResult
    capacitance: HysteresisResult
    regime: int


def model_cycle_errors(u_v: float, params: PaperParameters = PAPER, n: int = 4001) -> CycleErrors:
    """Hysteresis errors of R_A and C_A for one cycle of the paper's model (Table 2).

    Parameters
    ----------
    u_v : float
        Voltage across the composite u, > 0. [V]
    params : PaperParameters
        Material and cycle parameters (default: Table 1 with k = 2).
    n : int
        Points of the search grid.

    Returns
    -------
    CycleErrors

    Notes
    -----
    Loading by eq. (1), unloading by eq. (9), R_A by eqs. (16)–(18) with the regime the paper's
    thresholds select, C_A by eq. (15), HE by eq. (13).
    """
    check_positive("u_v", u_v, "V")
    if not isinstance(params, PaperParameters):
        raise TypeError(f"params: must be a PaperParameters (fsrlab.physics.params.PAPER), got {type(params).__name__}")
    n = check_int("n", n, 3)
    p = params

    def s_l(x):
        return separation_loading(x, p.s0_m, p.modulus_pa)

    def s_u(x):
        return separation_unloading(x, p.sigma_f_pa, p.s0_m, p.modulus_pa, p.k)

    _, regime = resistance_per_area(u_v, p.s0_m, p.phi0_j, return_regime=True)
    x = np.linspace(0.0, p.sigma_f_pa, n)
    if regime == 12:
        return _model_cycle_errors_eq12(float(u_v), p, x)
    sl, su = s_l(x), s_u(x)  # the separations, shared by R_A and C_A

    def r_l(t):
        return resistance_per_area(u_v, s_l(t), p.phi0_j)

    def r_u(t):
        return resistance_per_area(u_v, s_u(t), p.phi0_j)

    def c_l(t):
        return capacitance_per_area(s_l(t), p.eps_r)

    def c_u(t):
        return capacitance_per_area(s_u(t), p.eps_r)

    he_r = _curves_on_grid(x, resistance_per_area(u_v, sl, p.phi0_j), resistance_per_area(u_v, su, p.phi0_j),
                           r_l, r_u, refine=True)
    he_c = _curves_on_grid(x, capacitance_per_area(sl, p.eps_r), capacitance_per_area(su, p.eps_r),
                           c_l, c_u, refine=True)
    return CycleErrors(u_v=float(u_v), resistance=he_r, capacitance=he_c, regime=int(regime))


#: Stresses per chunk of the Table 2 kernel: its few temporaries stay in the CPU cache.
_CHUNK = 16384


class _BracketNotPositive(Exception):
    """Eq. (12)'s bracket is not positive somewhere on the cycle: the exact path gives its NaN or 0."""


def _kernel_range(u: float, p: PaperParameters, x: np.ndarray, lo: int, hi: int, rl, ru, cl, cu):
    """R_A and C_A of both branches for ``x[lo:hi]``, chunk by chunk, constants folded.

    Per stress and branch: the separation, −B = k1·s, exp(−B), exp(−B√r), the bracket, R_A = k3·s²/bracket
    (eqs. 12, 16–18 with u/J folded into one constant) and C_A = ε·ε0/s (eq. 15): 11 passes and four
    exponentials per stress over cached chunks. Returns the largest |ΔR_A| and |ΔC_A| of the range with
    their indices (the first of equal maxima).
    """
    phi0 = p.phi0_j
    k1 = -8 * np.pi * np.sqrt(2 * m_e) * phi0**1.5 / (2.96 * h * e * u)  # −B per metre of separation
    r = 1 + 2 * e * u / phi0
    sqrt_r = np.sqrt(r)
    k3 = 8 * np.pi * h * phi0 / (2.2 * e**3 * u)  # R_A = u/J = k3·s²/bracket
    c_num = p.eps_r * epsilon_0
    s_f = p.s0_m * (1.0 - p.sigma_f_pa / p.modulus_pa)  # Eq. (3)
    size = min(hi - lo, _CHUNK)
    w1, w2, s_l, s_u = (np.empty(size) for _ in range(4))
    best_r, best_c = (-np.inf, lo), (-np.inf, lo)
    for a in range(lo, hi, _CHUNK):
        xs = x[a:min(a + _CHUNK, hi)]
        m, chunk = xs.size, slice(a, a + xs.size)
        sl, su, t1, t2 = s_l[:m], s_u[:m], w1[:m], w2[:m]
        np.multiply(xs, -p.s0_m / p.modulus_pa, out=sl)
        sl += p.s0_m  # Eq. (1)
        np.multiply(xs, -1.0 / p.sigma_f_pa, out=su)
        su += 1.0
        np.power(su, p.k, out=su)
        su *= p.s0_m - s_f
        su += s_f  # Eq. (9), simplified
        for s, r_out, c_out in ((sl, rl, cl), (su, ru, cu)):
            neg_b = np.multiply(s, k1, out=t1)
            t = np.multiply(neg_b, sqrt_r, out=t2)
            np.exp(neg_b, out=neg_b)
            np.exp(t, out=t)
            t *= r
            bracket = np.subtract(neg_b, t, out=t)
            if not bracket.min() > 0:  # NaN, 0 or negative: not this path's business
                raise _BracketNotPositive
            q = np.square(s, out=r_out[chunk])
            q *= k3
            q /= bracket
            np.divide(c_num, s, out=c_out[chunk])
        for key, q_l, q_u in (("r", rl, ru), ("c", cl, cu)):
            d = np.subtract(q_u[chunk], q_l[chunk], out=t1)
            np.abs(d, out=d)
            k = int(np.argmax(d))
            if key == "r" and d[k] > best_r[0]:
                best_r = (float(d[k]), a + k)
            elif key == "c" and d[k] > best_c[0]:
                best_c = (float(d[k]), a + k)
    return best_r, best_c


def _model_cycle_errors_eq12(u: float, p: PaperParameters, x: np.ndarray) -> CycleErrors:
    """:func:`model_cycle_errors` when eq. (12) applies (u > φ0/e, Table 2's voltages), fused.

    The grid is split between the cores (numpy's loops release the GIL), each range computed chunk by
    chunk with the constants folded (:func:`_kernel_range`): the numbers agree with the public functions
    (separation_loading/unloading, resistance_per_area, capacitance_per_area) to a few units in the last
    place (tests/physics/test_kernel.py). Where eq. (12)'s bracket is not positive somewhere on the cycle
    (thin films at high voltage), the exact in-place path takes over and gives the public functions'
    NaN to the bit (:func:`_model_cycle_errors_eq12_exact`).
    """
    import os
    from concurrent.futures import ThreadPoolExecutor

    n = x.size
    rl, ru, cl, cu = np.empty(n), np.empty(n), np.empty(n), np.empty(n)
    parts = max(1, min(os.cpu_count() or 1, n // (4 * _CHUNK)))
    bounds = [n * i // parts for i in range(parts + 1)]
    try:
        with np.errstate(over="ignore", under="ignore"):
            if parts == 1:
                results = [_kernel_range(u, p, x, 0, n, rl, ru, cl, cu)]
            else:
                with ThreadPoolExecutor(max_workers=parts) as pool:
                    results = list(pool.map(lambda i: _kernel_range(u, p, x, bounds[i], bounds[i + 1], rl, ru, cl, cu),
                                            range(parts)))
    except _BracketNotPositive:
        return _model_cycle_errors_eq12_exact(u, p, x)
    # The largest difference over the ranges; the first range wins ties, as one pass in order would.
    i_r = max(results, key=lambda res: (res[0][0], -res[0][1]))[0][1]
    i_c = max(results, key=lambda res: (res[1][0], -res[1][1]))[1][1]
    return _errors_from_curves(u, p, x, rl, ru, cl, cu, i_r, i_c)


def _errors_from_curves(u, p, x, rl, ru, cl, cu, i_r, i_c) -> CycleErrors:
    """HE of R_A and C_A from the grid's curves and σd's grid points, refined with scalar evaluations."""
    c_num = p.eps_r * epsilon_0

    def s_l(t):
        return _loading(t, p.s0_m, p.modulus_pa)

    def s_u(t):
        return _unloading(t, p.sigma_f_pa, p.s0_m, p.modulus_pa, p.k)

    def scalar(fn):
        def q(t):
            with np.errstate(over="ignore", under="ignore", invalid="ignore", divide="ignore"):
                return float(fn(t))
        return q

    he_r = _curves_on_grid(x, rl, ru, scalar(lambda t: u / _eq12(u, s_l(t), p.phi0_j)),
                           scalar(lambda t: u / _eq12(u, s_u(t), p.phi0_j)), refine=True, i=i_r)
    he_c = _curves_on_grid(x, cl, cu, scalar(lambda t: c_num / s_l(t)), scalar(lambda t: c_num / s_u(t)),
                           refine=True, i=i_c)
    return CycleErrors(u_v=u, resistance=he_r, capacitance=he_c, regime=12)


def _model_cycle_errors_eq12_exact(u: float, p: PaperParameters, x: np.ndarray) -> CycleErrors:
    """The Table 2 kernel evaluated exactly as the public functions do, where eq. (12) fails somewhere.

    The same operations in the same order as the public functions (separation_loading/unloading,
    resistance_per_area, capacitance_per_area, all checked once by the caller), evaluated chunk by
    chunk in place: the numbers are equal to the bit. x lies in [0, σf] with σf < M, inside both
    branches' domains, so no NaN mask is needed.
    """
    n = x.size
    rl, ru, cl, cu = np.empty(n), np.empty(n), np.empty(n), np.empty(n)
    c_num = p.eps_r * epsilon_0

    def s_l(t):
        return _loading(t, p.s0_m, p.modulus_pa)

    def s_u(t):
        return _unloading(t, p.sigma_f_pa, p.s0_m, p.modulus_pa, p.k)

    # The largest |Q_u − Q_l| of each quantity as np.nanargmax would find it (first of equal maxima).
    best = {"r": (-np.inf, None), "c": (-np.inf, None)}

    def track(key, a, q_l, q_u, work):
        d = np.subtract(q_u, q_l, out=work[:q_l.size])
        np.abs(d, out=d)
        np.fmax(d, -np.inf, out=d)  # NaN → −inf, as nanargmax does
        k = int(np.argmax(d))
        if d[k] > best[key][0]:
            best[key] = (d[k], a + k)

    work = np.empty(min(n, _CHUNK))
    with np.errstate(over="ignore", under="ignore", invalid="ignore", divide="ignore"):
        for a in range(0, n, _CHUNK):
            xs, chunk = x[a:a + _CHUNK], slice(a, a + _CHUNK)
            for s, r_out, c_out in ((s_l(xs), rl, cl), (s_u(xs), ru, cu)):
                np.divide(u, _eq12(u, s, p.phi0_j), out=r_out[chunk])  # Eqs. (16)-(18)
                np.divide(c_num, s, out=c_out[chunk])  # Eq. (15)
            track("r", a, rl[chunk], ru[chunk], work)
            track("c", a, cl[chunk], cu[chunk], work)
    if best["r"][1] is None or best["c"][1] is None:
        # np.nanargmax's words, as on the public path
        raise ParameterError(f"the model gives no finite R_A or C_A on the cycle at {u:g} V (All-NaN slice "
                             "encountered: eq. (12) fails on every separation)", parameter="u_v")
    return _errors_from_curves(u, p, x, rl, ru, cl, cu, best["r"][1], best["c"][1])
