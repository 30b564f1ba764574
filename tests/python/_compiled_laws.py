"""Laws of nvib.LAW_SIGNATURE written in Python, with the arithmetic of built-in laws: compiled by Numba in
the tests that have it, and called through ctypes pointers (no compiler) where the contract alone is tested."""

from __future__ import annotations

import ctypes

from nvib._compiled import ctypes_law


def hardening_py(p, s, d, dd, t, out, trial):
    """HardeningSpring's arithmetic: f = k0 (1 + a d^2) d, df/dd = k0 (1 + 3 a d^2)."""
    k0, a = p[0], p[1]
    out[0] = k0 * (1.0 + a * d * d) * d
    out[1] = k0 * (1.0 + 3.0 * a * d * d)
    out[2] = 0.0
    return 0


def bilinear_py(p, s, d, dd, t, out, trial):
    """Bilinear's trial (kinematic hardening, its return mapping and committed-point slope), state (dp,
    dissipated, d), the same operations in the same order."""
    k, fy, b = p[0], p[1], p[2]
    H = b * k / (1.0 - b)
    kt = k * H / (k + H)
    dp, dis, dc = s[0], s[1], s[2]
    f = k * (d - dp)
    kd = k
    ndp, ndis = dp, dis
    xi = f - H * dp
    excess = abs(xi) - fy
    if d == dc:
        if excess >= -1e-9 * fy:
            kd = kt
    elif excess > 0.0:
        slip = excess / (k + H)
        sgn = 1.0 if xi > 0.0 else -1.0
        f -= k * slip * sgn
        kd = kt
        ndp += sgn * slip
        ndis += fy * slip
    out[0] = f
    out[1] = kd
    out[2] = 0.0
    trial[0] = ndp
    trial[1] = ndis
    trial[2] = d
    return 0


# ctypes pointers, kept alive for the session: their addresses are the laws' "address" parameter
HARDENING = ctypes_law(hardening_py)
BILINEAR = ctypes_law(bilinear_py)


def address(law) -> float:
    return float(ctypes.cast(law, ctypes.c_void_p).value)
