"""Closed-form solutions used as references.

- ``linear_sdof``: m x'' + c x' + k x = 0, under-damped or undamped.
- ``hardening``: m x'' + k0 (1 + a x^2) x = 0 from rest at x0 (the hardening
  oscillator of Yang et al. 2017, section 4.2) is the undamped Duffing
  oscillator x'' + alpha x + beta x^3 = 0 with alpha = k0/m, beta = k0 a/m,
  whose solution is x = x0 cn(w t | m_e) with w^2 = alpha + beta x0^2 and
  parameter m_e = beta x0^2 / (2 w^2) (scipy's ellipj takes the parameter
  m = k^2, not the modulus k).
"""

from __future__ import annotations

import math

import numpy as np


def _params(**kw):
    """Named checks: masses and stiffnesses > 0, the rest finite (a, c >= 0)."""
    from ._checks import real

    out = []
    for name, x in kw.items():
        x = real(name, x, positive=name in ("m", "k", "k0"))
        if name in ("a", "c") and x < 0.0:
            raise ValueError(f"{name}: must be >= 0, got {x}")
        out.append(x)
    return out


def _times(t):
    from ._checks import real_array

    t = real_array("t", t)
    if not np.all(np.isfinite(t)):
        raise ValueError("t: contains NaN or Inf")
    return t


def linear_sdof(t, *, m: float, k: float, c: float = 0.0, x0: float = 1.0, v0: float = 0.0):
    """Displacement and velocity of the free linear oscillator (0 <= damping ratio < 1)."""
    m, k, c, x0, v0 = _params(m=m, k=k, c=c, x0=x0, v0=v0)
    t = _times(t)
    w = math.sqrt(k / m)
    xi = c / (2.0 * m * w)
    if not 0.0 <= xi < 1.0:
        raise ValueError(f"c: the closed form needs a damping ratio in [0, 1), got {xi}")
    wd = w * math.sqrt(1.0 - xi * xi)
    B = (v0 + xi * w * x0) / wd
    env = np.exp(-xi * w * t)
    cos, sin = np.cos(wd * t), np.sin(wd * t)
    x = env * (x0 * cos + B * sin)
    v = env * ((-xi * w) * (x0 * cos + B * sin) + wd * (-x0 * sin + B * cos))
    return x, v


def hardening(t, *, m: float = 1.0, k0: float = 100.0, a: float = 30.0, x0: float = 1.5):
    """Displacement and velocity of m x'' + k0 (1 + a x^2) x = 0, x(0) = x0, x'(0) = 0."""
    from scipy import special

    m, k0, a, x0 = _params(m=m, k0=k0, a=a, x0=x0)
    t = _times(t)
    alpha, beta = k0 / m, k0 * a / m
    w = math.sqrt(alpha + beta * x0 * x0)
    me = beta * x0 * x0 / (2.0 * w * w)
    sn, cn, dn, _ = special.ellipj(w * t, me)
    return x0 * cn, -x0 * w * sn * dn


def hardening_period(*, m: float = 1.0, k0: float = 100.0, a: float = 30.0, x0: float = 1.5) -> float:
    """Period 4 K(m_e) / w of the hardening oscillator."""
    from scipy import special

    m, k0, a, x0 = _params(m=m, k0=k0, a=a, x0=x0)
    alpha, beta = k0 / m, k0 * a / m
    w = math.sqrt(alpha + beta * x0 * x0)
    me = beta * x0 * x0 / (2.0 * w * w)
    return 4.0 * float(special.ellipk(me)) / w


def hardening_energy(x, v, *, m: float = 1.0, k0: float = 100.0, a: float = 30.0):
    """Kinetic plus potential energy m v^2/2 + k0 (x^2/2 + a x^4/4)."""
    from ._checks import real_array

    m, k0, a = _params(m=m, k0=k0, a=a)
    x = real_array("x", x)
    v = real_array("v", v)
    return 0.5 * m * v * v + k0 * (0.5 * x * x + 0.25 * a * x ** 4)
