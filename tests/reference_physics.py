"""Scalar reference implementation of the paper's model with the ``math`` module and typed-in
CODATA 2018 constants: independent of fsrlab's vectorised code. Used by tests and by the Table 2
benchmark's plain-loop baseline."""

import math

E, ME, H, EPS0 = 1.602176634e-19, 9.1093837015e-31, 6.62607015e-34, 8.8541878128e-12
# scipy carries CODATA 2022: m_e differs by 1.4e-9 and ε0 by 1e-10 relative; inside exponents of
# 20-40 that becomes < 1e-7, so results must agree with fsrlab's to 1e-6.
REL = 1e-6

TABLE1 = dict(modulus=4.73e6, sigma_f=322e3, s0=4.418e-9, phi0=0.223 * E, eps_r=7.0)


def j12(u, s, phi0=TABLE1["phi0"]):
    """Eq. (12)."""
    b = 8 * math.pi * s * math.sqrt(2 * ME) * phi0 ** 1.5 / (2.96 * H * E * u)
    r = 1 + 2 * E * u / phi0
    return 2.2 * E**3 * u**2 / (8 * math.pi * H * phi0 * s**2) * (math.exp(-b) - r * math.exp(-b * math.sqrt(r)))


def j11(u, s, phi0=TABLE1["phi0"]):
    """Eq. (11)."""
    a = 4 * math.pi * s / H * math.sqrt(2 * ME)
    lo, hi = phi0 - E * u / 2, phi0 + E * u / 2
    return E / (2 * math.pi * H * s**2) * (lo * math.exp(-a * math.sqrt(lo)) - hi * math.exp(-a * math.sqrt(hi)))


def s_loading(x, s0=TABLE1["s0"], modulus=TABLE1["modulus"]):
    """Eq. (1)."""
    return s0 * (1 - x / modulus)


def s_unloading(x, sigma_f=TABLE1["sigma_f"], s0=TABLE1["s0"], modulus=TABLE1["modulus"], k=2):
    """Eq. (9) as printed (a, b from eqs. 7-8)."""
    a = modulus * sigma_f ** (1 - k) / (modulus - sigma_f)
    return s0 * (1 - sigma_f / modulus) * (1 + a * (x - sigma_f) ** k / modulus)


def table2_row(u, n, phi0=TABLE1["phi0"], k=2):
    """(HE of R_A, HE of C_A) in percent over n + 1 evenly spaced stresses, brute force (eq. 13)."""
    sf = TABLE1["sigma_f"]
    best_r = best_c = 0.0
    r_f = c_f = None
    for i in range(n + 1):
        x = sf * i / n
        sl, su = s_loading(x), s_unloading(x, k=k)
        rl, ru = u / j12(u, sl, phi0), u / j12(u, su, phi0)
        cl, cu = TABLE1["eps_r"] * EPS0 / sl, TABLE1["eps_r"] * EPS0 / su
        best_r = max(best_r, abs(ru - rl))
        best_c = max(best_c, abs(cu - cl))
        r_f, c_f = rl, cl
    return 100 * best_r / abs(r_f), 100 * best_c / abs(c_f)
