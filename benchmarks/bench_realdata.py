"""Calibration on real third-party recordings: the held-out calibration against plain polynomials.

Of the 40 recordings the 39 pairs below use, 2 are in fsrlab's repository: the capacitive insole's
``left_t34_calibration`` and ``left_t34_validation1`` (tests/data/real/belli-insole/, BSD-3-Clause), enough
for one pair alone (the calibration run's halves). The others are not: three of the five sources
(LucasWestfal, Lupasic, TAMS: 25 recordings) have no licence, so they cannot be redistributed, and the
force plate's (MIT) and the rest of the insole's are not committed either. ``scripts/prepare_realdata.py``
builds all 40 on your machine from local copies of the five
sources into a directory of CSV files ``time_s,reading,force_n`` (time [s], the raw readout as recorded, the
reference [N]); point ``FSRLAB_REALDATA`` at it. Without it this benchmark says "skipped". Nothing is
downloaded. Sources (docs/calibration.md; conversions in prepare_realdata.py's docstring, e.g. the
westfal session 06 taken as logged): an FSR in a divider read by ``analogRead`` with an HX711 load cell,
hand-loaded and servo-driven (LucasWestfal/FSR_calibration_techniques); a Velostat film pressed by a UR5e
arm against a Futek load cell (Lupasic/tactile-sensor-velostat); FSRs under a phantom pressed by hand on a
force plate (priyanshum17/pressure, MIT); a piezoresistive taxel read through a divider with the authors'
force conversion (TAMS-Group/tams_tactile_sensor_array_hardware); one taxel of a capacitive insole (8-bit
counts) in an air chamber whose pressure times the taxel's area is the reference
(ami-iit/paper_belli_2023_sensors_insole-calibration, BSD-3-Clause).

The first :data:`DEVELOPED_ON` pairs are those the calibration was developed on; the others were added later
and only measured. Every table and summary shows the two groups apart.

For each train → test pair: :func:`fsrlab.calibrate` (what ``fsrlab calibrate TRAIN.csv --x reading
--reference force_n [--compensate]`` runs) on the training runs, then :func:`fsrlab.apply` (``fsrlab
apply``) on the test run; RMSE over the loaded rows (reference above 5 % of the test's maximum) in % of the
test's reference span. Peers, all fitted on the same training rows:

- the best plain polynomial (degree 1–5 in the raw readout, the degree that is best **on the test run**: an
  oracle the calibration does not have); the ratios in the pair tables are against it;
- the polynomial a user without the test's reference can fit: its degree chosen on the training runs alone
  (leave one recording out, or the first 70 % of one run fitted and the rest scored), in the raw reading;
- the same in the variable the physics names (:func:`physics_variable`: 1/reading when the training reading
  is positive, spans more than a decade and falls as the force rises, as a resistance does; else the
  reading), the peer of the acceptance criteria.

Also: the share of loaded rows whose error lies within ±2u (the criterion applies to the pairs recorded in
one session, :data:`SAME_SESSION`, marked S); the share of loaded rows left without an estimate.

Then a robustness table: a few of those pairs with their reference logged ``k`` readings late (the
readout's first ``k`` rows and the reference's last ``k`` dropped, in the training and the test runs
alike, as when a load cell is logged by another device and joined by time stamps): the compensated
estimate's RMSE as a multiple of the same pair's with ``k = 0``, and the delay the calibration found.

Last, every pair again with a fault a user's logger adds (:data:`FAULTS`, in the training and the
test runs alike): 1 % of the readings replaced by a number drawn from the run's range (a serial line
that garbles a value), readings in ADC counts written as volts (``x·5/1023``: a sketch that prints
volts; no ``--rail``, so no conductance variable), time stamps of an unsteady loop (each step ×0.7 to
×1.3), and beside a readout of 20/s or more a reference held between the conversions of an amplifier
at 10/s (each row the mean force of the last conversion ended: stair steps up to 0.2 s late). Each
against the best polynomial fitted on the same altered rows, so the table says how much
the calibration loses to a fault that a plain polynomial also meets.
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

import numpy as np

TITLE = "Calibration on real recordings (held-out selection vs plain polynomials)"

#: (name, train files or (file, part), test files or (file, part)); part: "first half" / "second half".
PAIRS = (
    ("FSR divider + HX711, hand: first half → second half", [("westfal_fsr__s02_manual", 0)],
     [("westfal_fsr__s02_manual", 1)]),
    ("same FSR: hand → servo triangle", ["westfal_fsr__s02_manual"], ["westfal_fsr__s02_motor"]),
    ("second FSR: hand → servo triangle", ["westfal_fsr__s06_manual"], ["westfal_fsr__s06_motor"]),
    ("servo triangle → hand", ["westfal_fsr__s02_motor"], ["westfal_fsr__s02_manual"]),
    ("second FSR: servo triangle → hand", ["westfal_fsr__s06_motor"], ["westfal_fsr__s06_manual"]),
    ("FSR: two hand sessions → a third", ["westfal_fsr__s04_manual", "westfal_fsr__s05_manual"],
     ["westfal_fsr__s03_manual"]),
    ("Velostat, robot presses: first half → second half", [("lupasic_velostat__pike1_force_20_exp1", 0)],
     [("lupasic_velostat__pike1_force_20_exp1", 1)]),
    ("Velostat, robot: run 1 → its repeat", ["lupasic_velostat__pike1_force_40_exp1"],
     ["lupasic_velostat__pike1_force_40_exp2"]),
    ("force plate FSR: first half → second half", [("forceplate__exp13cQ2_fsr2", 0)],
     [("forceplate__exp13cQ2_fsr2", 1)]),
    ("second FSR, hand: first half → second half", [("westfal_fsr__s06_manual", 0)], [("westfal_fsr__s06_manual", 1)]),
    ("FSR, hand: one session → the next", ["westfal_fsr__s03_manual"], ["westfal_fsr__s04_manual"]),
    ("FSR, hand: session 5 → session 6", ["westfal_fsr__s05_manual"], ["westfal_fsr__s06_manual"]),
    ("FSR: hand + servo of one session → servo of another", ["westfal_fsr__s02_manual", "westfal_fsr__s02_motor"],
     ["westfal_fsr__s06_motor"]),
    ("Velostat, robot 20 N: run 1 → its repeat", ["lupasic_velostat__pike1_force_20_exp1"],
     ["lupasic_velostat__pike1_force_20_exp2"]),
    ("Velostat, robot: 10 N and 30 N runs → a 20 N run", ["lupasic_velostat__pike1_force_10_exp1",
                                                           "lupasic_velostat__pike1_force_30_exp1"],
     ["lupasic_velostat__pike1_force_20_exp1"]),
    ("Velostat, other indenter, 40 N: run 1 → its repeat", ["lupasic_velostat__pike5_force_40_exp1"],
     ["lupasic_velostat__pike5_force_40_exp2"]),
    ("Velostat, robot: a 40 N run → a 10 N run", ["lupasic_velostat__pike1_force_40_exp1"],
     ["lupasic_velostat__pike1_force_10_exp1"]),
    ("force plate, one FSR: one experiment → another", ["forceplate__exp7a_fsr3"], ["forceplate__exp13a_fsr3"]),
    ("force plate, another FSR: first half → second half", [("forceplate__exp12b_fsr1", 0)],
     [("forceplate__exp12b_fsr1", 1)]),
    ("taxel (TAMS), bare → under a thin silicone layer", ["tams_tactile__r10k_nosil"], ["tams_tactile__r10k_thinsil"]),
    ("taxel (TAMS), bare: first half → second half", [("tams_tactile__r10k_nosil", 0)],
     [("tams_tactile__r10k_nosil", 1)]),
    # the pairs below were added after the calibration had been developed on those above (DEVELOPED_ON)
    ("force plate, one FSR: the other experiment → the first", ["forceplate__exp13a_fsr3"], ["forceplate__exp7a_fsr3"]),
    ("force plate, that FSR: first half → second half", [("forceplate__exp13a_fsr3", 0)],
     [("forceplate__exp13a_fsr3", 1)]),
    ("force plate, that FSR, other experiment: first half → second half", [("forceplate__exp7a_fsr3", 0)],
     [("forceplate__exp7a_fsr3", 1)]),
    ("FSR, hand, one session: first half → second half", [("westfal_fsr__s03_manual", 0)],
     [("westfal_fsr__s03_manual", 1)]),
    ("FSR, hand: session 4 → session 5", ["westfal_fsr__s04_manual"], ["westfal_fsr__s05_manual"]),
    ("Velostat, robot 5 N: run 1 → its repeat", ["lupasic_velostat__pike1_force_5_exp1"],
     ["lupasic_velostat__pike1_force_5_exp2"]),
    ("Velostat, robot 1 N: run 1 → its repeat", ["lupasic_velostat__pike1_force_1_exp1"],
     ["lupasic_velostat__pike1_force_1_exp2"]),
    ("Velostat, robot 30 N: run 2 → run 1", ["lupasic_velostat__pike1_force_30_exp2"],
     ["lupasic_velostat__pike1_force_30_exp1"]),
    ("Velostat, other indenter, 10 N: run 1 → its repeat", ["lupasic_velostat__pike5_force_10_exp1"],
     ["lupasic_velostat__pike5_force_10_exp2"]),
    ("taxel (TAMS) under thick silicone: first half → second half", [("tams_tactile__r10k_thicksil", 0)],
     [("tams_tactile__r10k_thicksil", 1)]),
    ("taxel (TAMS) under thin silicone: first half → second half", [("tams_tactile__r10k_thinsil", 0)],
     [("tams_tactile__r10k_thinsil", 1)]),
    ("capacitive insole taxel, air chamber: calibration run → three validation runs",
     ["belli_insole__left_t34_calibration"],
     ["belli_insole__left_t34_validation1", "belli_insole__left_t34_validation2",
      "belli_insole__left_t34_validation3"]),
    ("capacitive insole taxel: loading staircase → unloading staircase", [("belli_insole__left_t34_calibration", 0)],
     [("belli_insole__left_t34_calibration", 1)]),
    ("capacitive insole taxel: slow staircase → fast rises on a preload", ["belli_insole__left_t34_steps1"],
     ["belli_insole__left_t34_dynamic2"]),
    ("capacitive insole taxel: calibration run → two runs of another day", ["belli_insole__left_t34_calibration"],
     ["belli_insole__left_t34_steps1", "belli_insole__left_t34_dynamic1"]),
    ("capacitive insole taxel: one slow ramp → a validation run", ["belli_insole__left_t34_dynamic1"],
     ["belli_insole__left_t34_validation1"]),
    ("capacitive insole, another taxel: calibration run → a validation run", ["belli_insole__left_t53_calibration"],
     ["belli_insole__left_t53_validation1"]),
    ("capacitive insole, other dielectric: one day → the next", ["belli_insole__right_t126_dyn2sep_a"],
     ["belli_insole__right_t126_dyn3sep"]),
)


#: The first pairs of PAIRS, those the calibration was developed on; the others were added later and
#: only measured (their figures are summed up apart, as the less flattering check).
DEVELOPED_ON = 21

#: Indices of PAIRS whose training and test rows come from one session (the ±2u criterion applies to them):
#: halves of one run, a repeat recorded minutes later on the same mounting (the robot's Velostat series,
#: 25 Nov 2021, 13:58-15:19, one mounting per indenter), hand and servo runs of one numbered FSR session.
#: Not: another FSR session, another cover on the taxel (bare vs silicone), another force-plate experiment
#: (the phantom placed again), the insole's runs after a restart of its logger (another clock base) or
#: another day.
SAME_SESSION = frozenset({0, 1, 2, 3, 4, 6, 7, 8, 9, 13, 14, 15, 16, 18, 20, 22, 23, 24, 26, 27, 28, 29, 30, 31, 33})


#: Pairs (by name) and reference delays [readings] of the robustness table.
LATE_PAIRS = ("FSR divider + HX711, hand: first half → second half", "second FSR, hand: first half → second half",
              "taxel (TAMS), bare: first half → second half", "Velostat, robot: run 1 → its repeat",
              "Velostat, robot 20 N: run 1 → its repeat")
LATE_ROWS = (3, 6, 12)


def _write(out: Path, t, x, y) -> Path:
    """A run of the columns ``time_s,reading,force_n`` (an empty cell where a value is missing)."""
    with out.open("w") as fh:
        fh.write("time_s,reading,force_n\n")
        for ti, xi, yi in zip(t, x, y, strict=True):
            fh.write(f"{ti:.6f}," + ",".join(f"{v:.10g}" if np.isfinite(v) else "" for v in (xi, yi)) + "\n")
    return out


def _late(path: Path, k: int, tmp: Path, tag: str) -> Path:
    """A copy of the run ``path`` with its reference ``k`` readings late."""
    d = np.genfromtxt(path, delimiter=",", names=True)
    return _write(tmp / f"late{k}-{tag}.csv", d["time_s"][k:], d["reading"][k:], d["force_n"][:d.size - k])


def _glitches(t, x, y, rng):
    """1 % of the readings replaced by a number drawn from the run's range (whole when the readings are)."""
    x = x.copy()
    hit = rng.random(x.size) < 0.01
    lo, hi = np.nanmin(x), np.nanmax(x)
    v = rng.uniform(lo, hi, int(hit.sum()))
    whole = bool(np.all(x[np.isfinite(x)] == np.round(x[np.isfinite(x)])))
    x[hit] = np.round(v) if whole else v
    return t, x, y


def _volts(t, x, y, rng):
    """ADC counts (0..1023) written as volts of a 5 V supply; None for readings that are not such counts."""
    ok = np.isfinite(x)
    if not (np.all(x[ok] == np.round(x[ok])) and x[ok].min() >= 0 and x[ok].max() <= 1023):
        return None
    return t, x * 5.0 / 1023.0, y


def _jitter(t, x, y, rng):
    """Each time step ×0.7 to ×1.3 at random (an unsteady loop)."""
    return np.cumsum(np.r_[t[0], np.diff(t) * rng.uniform(0.7, 1.3, t.size - 1)]), x, y


def _held(t, x, y, rng):
    """The reference of a load-cell amplifier converting at 10/s beside a faster readout (20/s or more): each
    row carries the mean force of the last conversion ended, held until the next (empty before the first)."""
    k = int(round(0.1 / float(np.median(np.diff(t)))))
    if k < 2:
        return None
    out = np.full(y.size, np.nan)
    for a in range(0, y.size - k, k):
        seg = y[a:a + k]
        if np.isfinite(seg).any():
            out[a + k:a + 2 * k] = np.nanmean(seg)
    return t, x, out


#: Logger faults of the last table: name -> what it does to (time, reading, reference) of one run, given a
#: random generator (seeded per run); ``None`` where the fault does not apply to the run.
FAULTS = {"1 % of the readings garbled": _glitches, "ADC counts written as volts (no --rail)": _volts,
          "time steps ×0.7–1.3": _jitter, "reference held between conversions at 10/s": _held}


def _faulty(path: Path, fault, tmp: Path, tag: str, seed: int) -> Path | None:
    """A copy of the run ``path`` with ``fault`` applied (None where it does not apply)."""
    d = np.genfromtxt(path, delimiter=",", names=True)
    got = fault(d["time_s"].astype(float), d["reading"].astype(float), d["force_n"].astype(float),
                np.random.default_rng(seed))
    return None if got is None else _write(tmp / f"fault-{tag}.csv", *got)


def _read(root: Path, spec, tmp: Path) -> Path | None:
    name, part = (spec, None) if isinstance(spec, str) else spec
    src = root / f"{name}.csv"
    if not src.exists():
        return None
    if part is None:
        return src
    d = np.genfromtxt(src, delimiter=",", names=True)
    n = d.size // 2
    rows = d[:n] if part == 0 else d[n:]
    return _write(tmp / f"{name}-{part}.csv", rows["time_s"] - rows["time_s"][0], rows["reading"], rows["force_n"])


def _columns(path: Path):
    d = np.genfromtxt(path, delimiter=",", names=True)
    return d["reading"].astype(float), d["force_n"].astype(float)


def _best_polynomial(train, test) -> tuple[float, int]:
    xs = np.concatenate([_columns(p)[0] for p in train])
    ys = np.concatenate([_columns(p)[1] for p in train])
    ok = np.isfinite(xs) & np.isfinite(ys)
    x, y = (np.concatenate(v) for v in zip(*(_columns(p) for p in test), strict=True))
    loaded = y > 0.05 * np.nanmax(y)
    span = np.nanmax(y) - np.nanmin(y)
    best = None
    for d in range(1, 6):
        p = np.polynomial.Polynomial.fit(xs[ok], ys[ok], d)
        e = 100 * np.sqrt(np.mean((p(x[loaded]) - y[loaded]) ** 2)) / span
        best = (e, d) if best is None or e < best[0] else best
    return best


def _as(x: np.ndarray, variable: str) -> np.ndarray:
    """The reading in ``variable``: itself (``reading``) or its reciprocal (``1/reading``, NaN where ≤ 0)."""
    if variable == "reading":
        return x
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(x > 0, 1.0 / x, np.nan)


def physics_variable(train) -> str:
    """``1/reading`` when the pooled training reading is positive, spans more than a decade and falls as the
    force rises (Spearman ρ < 0: a resistance, whose conductance follows the force), else ``reading``."""
    x, y = (np.concatenate(v) for v in zip(*(_columns(p) for p in train), strict=True))
    ok = np.isfinite(x) & np.isfinite(y)
    x, y = x[ok], y[ok]
    if x.size < 3 or x.min() <= 0 or x.max() / x.min() <= 10:
        return "reading"
    def rank(v):
        return np.argsort(np.argsort(v, kind="stable"), kind="stable").astype(float)

    return "1/reading" if np.corrcoef(rank(x), rank(y))[0, 1] < 0 else "reading"


def _fair_polynomial(train, test, variable: str = "reading") -> tuple[float, int]:
    """(RMSE [% of the test's span] over the loaded test rows, degree) of the plain polynomial in ``variable``
    (``reading`` or ``1/reading``) whose degree 1–5 is chosen on the training runs alone, as a user without
    the test's reference must: by leave-one-recording-out mean squared error with two or more runs, else
    fitted on the first 70 % of the run and scored on the rest. Test rows where the variable is undefined
    are left out."""
    cols = []
    for p in train:
        x, y = _columns(p)
        x = _as(x, variable)
        ok = np.isfinite(x) & np.isfinite(y)
        cols.append((x[ok], y[ok]))

    def heldout(d: int) -> float:
        if len(cols) > 1:
            errs = []
            for k, (xk, yk) in enumerate(cols):
                xs = np.concatenate([c[0] for j, c in enumerate(cols) if j != k])
                ys = np.concatenate([c[1] for j, c in enumerate(cols) if j != k])
                errs.append(np.mean((np.polynomial.Polynomial.fit(xs, ys, d)(xk) - yk) ** 2))
            return float(np.mean(errs))
        x, y = cols[0]
        n = int(0.7 * x.size)
        return float(np.mean((np.polynomial.Polynomial.fit(x[:n], y[:n], d)(x[n:]) - y[n:]) ** 2))

    degree = min(range(1, 6), key=heldout)
    xs, ys = (np.concatenate(v) for v in zip(*cols, strict=True))
    x, y = (np.concatenate(v) for v in zip(*(_columns(p) for p in test), strict=True))
    loaded = y > 0.05 * np.nanmax(y)
    e = np.polynomial.Polynomial.fit(xs, ys, degree)(_as(x[loaded], variable)) - y[loaded]
    e = e[np.isfinite(e)]
    return 100 * float(np.sqrt(np.mean(e ** 2))) / (np.nanmax(y) - np.nanmin(y)), degree


def _applied(cal, test) -> tuple:
    """The estimate's error, its uncertainty (NaN where the calibration gives none) and the reference, over
    the test runs, each calibrated by ``cal`` (what ``fsrlab apply`` writes)."""
    import fsrlab as fl

    errs, us, ys = [], [], []
    for p in test:
        run = fl.apply(cal, fl.load_run(str(p)))
        y = np.asarray(run["force_n"], float)
        errs.append(np.asarray(run["force_n_estimate"], float) - y)
        u = run["force_n_uncertainty"] if "force_n_uncertainty" in run else np.full(y.size, np.nan)
        us.append(np.asarray(u, float))
        ys.append(y)
    return tuple(np.concatenate(v) for v in (errs, us, ys))


def late_scores(root: Path, tmp: Path, train_specs, test_specs) -> list | None:
    """(k, RMSE of the compensated estimate as a multiple of k = 0's, delay found [readings]) for k = 0 and
    each of :data:`LATE_ROWS`; an entry's ratio is None where ``calibrate`` refused the shifted runs."""
    import fsrlab as fl

    train = [_read(root, s, tmp) for s in train_specs]
    test = [_read(root, s, tmp) for s in test_specs]
    if any(p is None for p in train + test):
        return None
    out, base = [], None
    for k in (0,) + LATE_ROWS:
        tr = [_late(p, k, tmp, f"train{i}") for i, p in enumerate(train)]
        te = [_late(p, k, tmp, f"test{i}") for i, p in enumerate(test)]
        try:
            cal = fl.calibrate([str(p) for p in tr], x="reading", reference="force_n", compensate=True)
        except ValueError:
            out.append((k, None, None))
            continue
        e, _, y = _applied(cal, te)
        got = (y > 0.05 * np.nanmax(y)) & np.isfinite(e)
        rmse = float(np.sqrt(np.mean(e[got] ** 2)))
        base = rmse if base is None else base
        out.append((k, rmse / base, cal.model.delay_s / cal.model.row_s))
    return out


def pair_scores(root: Path, tmp: Path, train_specs, test_specs) -> dict | None:
    """Ratios, coverage and missing share of one pair (None when a file is absent)."""
    train = [_read(root, s, tmp) for s in train_specs]
    test = [_read(root, s, tmp) for s in test_specs]
    if any(p is None for p in train + test):
        return None
    poly, degree = _best_polynomial(train, test)
    fair, fair_degree = _fair_polynomial(train, test)
    variable = physics_variable(train)
    phys, phys_degree = (fair, fair_degree) if variable == "reading" else _fair_polynomial(train, test, variable)
    out = {"poly": poly, "degree": degree, "fair": fair, "fair_degree": fair_degree, "phys": phys,
           "phys_degree": phys_degree, "phys_variable": variable}
    for comp in (False, True):
        out["comp" if comp else "plain"] = _scored(train, test, poly, comp)
    return out


def _scored(train, test, poly: float, compensate: bool) -> dict:
    """``fsrlab.calibrate`` on ``train`` applied to ``test``: ratio to ``poly`` [% of span], coverage, missing share."""
    import fsrlab as fl

    cal = fl.calibrate([str(p) for p in train], x="reading", reference="force_n", compensate=compensate)
    e, u, y = _applied(cal, test)
    loaded = y > 0.05 * np.nanmax(y)
    span = np.nanmax(y) - np.nanmin(y)
    got = loaded & np.isfinite(e)
    rmse = 100 * np.sqrt(np.mean(e[got] ** 2)) / span
    return {"ratio": rmse / poly, "coverage": float(np.mean(np.abs(e[got]) <= 2 * u[got])),
            "missing": float(np.mean(~np.isfinite(e[loaded]))), "model": cal.model_name,
            "delay_rows": cal.model.delay_s / cal.model.row_s, "steps": [s for s in cal.selection.steps if "kept" in s]}


def fault_scores(root: Path, tmp: Path, fault) -> list:
    """(pair index, compensated ratio, ±2u coverage) with ``fault`` in the training and test runs, for every
    pair the fault applies to (against the best polynomial on the same altered rows)."""
    out = []
    for i, (_, tr, te) in enumerate(PAIRS):
        train = [_read(root, s, tmp) for s in tr]
        test = [_read(root, s, tmp) for s in te]
        if any(p is None for p in train + test):
            continue
        bad = [_faulty(p, fault, tmp, f"{i}-{j}", seed=1000 * i + j) for j, p in enumerate(train + test)]
        if any(p is None for p in bad):
            continue
        poly, _ = _best_polynomial(bad[:len(train)], bad[len(train):])
        s = _scored(bad[:len(train)], bad[len(train):], poly, True)
        out.append((i, s["ratio"], s["coverage"]))
    return out


PAIR_HEADER = ("| # | pair | S | best polynomial (degree) | polynomial, degree chosen on training: reading (degree) | "
               "same in the physics variable (variable, degree) | plain ×, ±2u | `--compensate` ×, ±2u, missing | "
               "compensated / plain | model chosen |")
PAIR_RULE = "|---:|---|:-:|---:|---:|---:|---:|---:|---:|---|"


def _pair_row(i: int, name: str, s: dict) -> str:
    p, c = s["plain"], s["comp"]
    delay = f", delay {c['delay_rows']:.2g} rows" if c["delay_rows"] else ""
    return (f"| {i} | {name} | {'S' if i in SAME_SESSION else ''} | {s['poly']:.2f} % ({s['degree']}) | "
            f"{s['fair']:.2f} % ({s['fair_degree']}) | {s['phys']:.2f} % ({s['phys_variable']}, {s['phys_degree']}) | "
            f"×{p['ratio']:.2f}, {100 * p['coverage']:.0f} % | "
            f"×{c['ratio']:.2f}, {100 * c['coverage']:.0f} %, {100 * c['missing']:.1f} % | "
            f"{c['ratio'] / p['ratio']:.3f} | {c['model']}{delay} |")


def _summary(scores: dict) -> list[str]:
    """The summary table: the acceptance criteria's figures for the pairs developed on, those added later, and all."""
    groups = ((f"first {DEVELOPED_ON} (developed on)", lambda i: i < DEVELOPED_ON),
              (f"later {len(PAIRS) - DEVELOPED_ON} (measured only)", lambda i: i >= DEVELOPED_ON),
              ("all", lambda i: True))
    cols = []
    for label, member in groups:
        got = {i: s for i, s in scores.items() if s is not None and member(i)}
        if not got:
            cols.append((label, None))
            continue
        idx = sorted(got)
        comp = np.array([got[i]["comp"]["ratio"] for i in idx])
        plain = np.array([got[i]["plain"]["ratio"] for i in idx])
        oracle = np.array([got[i]["poly"] for i in idx])
        fair = np.array([got[i]["fair"] for i in idx]) / oracle
        phys = np.array([got[i]["phys"] for i in idx]) / oracle
        same = [i for i in idx if i in SAME_SESSION]

        def gm(v):
            return f"×{np.exp(np.mean(np.log(v))):.3f}"

        def worst(v, idx=idx):
            return f"×{v.max():.2f} (#{idx[int(np.argmax(v))]})"

        cp = comp / plain
        cols.append((label, {
            "pairs": str(len(idx)),
            "compensated / plain: worst; pairs above ×1.05": f"{worst(cp)}; {int((cp > 1.05).sum())}",
            "`--compensate` vs the oracle: geometric mean; worst": f"{gm(comp)}; {worst(comp)}",
            "`--compensate` vs the polynomial in the physics variable, degree chosen on training: "
            "geometric mean; worst":
                f"{gm(comp / phys)}; {worst(comp / phys)}",
            "same, plain calibration": f"{gm(plain / phys)}; {worst(plain / phys)}",
            "`--compensate` vs the polynomial in the raw reading, degree chosen on training: geometric mean; worst":
                f"{gm(comp / fair)}; {worst(comp / fair)}",
            "±2u (compensated) ≥ 90 %, same-session pairs":
                f"{sum(got[i]['comp']['coverage'] >= 0.9 for i in same)} of {len(same)}",
            "loaded rows without an estimate: largest share":
                f"{100 * max(got[i]['comp']['missing'] for i in idx):.1f} %",
        }))
    keys = next((list(v) for _, v in cols if v), [])
    out = [("**Summary** (the criteria: compensated ≤ ×1.05 plain on every pair; geometric mean ≤ ×0.80 and "
            "worst ≤ ×1.25 against the polynomial in the physics variable; ±2u ≥ 90 % on same-session pairs; "
            "≤ 2 % of loaded rows without an estimate):"), "", "| | " + " | ".join(label for label, _ in cols) + " |",
           "|---|" + "---|" * len(cols)]
    out += [f"| {k} | " + " | ".join(v[k] if v else "—" for _, v in cols) + " |" for k in keys]
    return out


def run() -> str:
    root = os.environ.get("FSRLAB_REALDATA")
    if not root or not Path(root).is_dir():
        return ("skipped: set FSRLAB_REALDATA to a directory of real recordings (time_s,reading,force_n CSV files; "
                "see this module's docstring)\n")
    rows, scores = {}, {}
    with tempfile.TemporaryDirectory() as tmp:
        for i, (name, tr, te) in enumerate(PAIRS):
            s = pair_scores(Path(root), Path(tmp), tr, te)
            scores[i] = s
            rows[i] = f"| {i} | {name} | not found | | | | | | | |" if s is None else _pair_row(i, name, s)
    lines = []
    for title, idx in ((f"Pairs the calibration was developed on (the first {DEVELOPED_ON})", range(DEVELOPED_ON)),
                       (f"Pairs added later, measured only ({len(PAIRS) - DEVELOPED_ON})",
                        range(DEVELOPED_ON, len(PAIRS)))):
        lines += [f"**{title}.** Ratios are RMSE over the best polynomial's (the oracle, first column); S: "
                  "training and test recorded in one session.", "", PAIR_HEADER, PAIR_RULE]
        lines += [rows[i] for i in idx] + [""]
    lines += _summary(scores)
    unaltered = {i: (s["comp"]["ratio"], s["comp"]["coverage"]) for i, s in scores.items() if s is not None}
    lines += ["", "The reference logged k readings late (robustness): the compensated estimate's RMSE as a multiple of "
              "the same pair's with k = 0, and the delay found [readings].", "",
              "| pair | k = 0: delay | " + " | ".join(f"k = {k}" for k in LATE_ROWS) + " |",
              "|---|---:|" + "---:|" * len(LATE_ROWS)]
    with tempfile.TemporaryDirectory() as tmp:
        for name, tr, te in (p for p in PAIRS if p[0] in LATE_PAIRS):
            s = late_scores(Path(root), Path(tmp), tr, te)
            if s is None:
                continue
            cells = [f"×{r:.2f}, delay {d:.3g}" if r is not None else "refused (no response left)" for _, r, d in s[1:]]
            lines.append(f"| {name} | {s[0][2]:.3g} | " + " | ".join(cells) + " |")
    lines += ["", "Every pair with a logger's fault in its training and test runs (robustness): the `--compensate` "
              "ratios against the best polynomial on the same altered rows, beside the same pairs unaltered.", "",
              "| fault | pairs | geometric mean (unaltered) | worst (unaltered) | at most ×1.00 (unaltered) | "
              "±2u coverage ≥ 90 % (unaltered) |", "|---|---:|---:|---:|---:|---:|"]
    with tempfile.TemporaryDirectory() as tmp:
        for name, fault in FAULTS.items():
            s = fault_scores(Path(root), Path(tmp), fault)
            if not s:
                continue
            r1, c1 = np.asarray([v[1:] for v in s]).T
            r0, c0 = np.asarray([unaltered[v[0]] for v in s]).T
            n = len(s)
            lines.append(f"| {name} | {n} | ×{np.exp(np.mean(np.log(r1))):.3f} (×{np.exp(np.mean(np.log(r0))):.3f}) | "
                         f"×{r1.max():.2f} (×{r0.max():.2f}) | {int((r1 <= 1).sum())} ({int((r0 <= 1).sum())}) | "
                         f"{int((c1 >= 0.9).sum())} ({int((c0 >= 0.9).sum())}) |")
    return "\n".join(lines) + "\n"
