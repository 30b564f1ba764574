"""Closed-form solutions used as references.

- ``linear_sdof``: m x'' + c x' + k x = 0, under-damped or undamped.
- ``forced_linear_sdof``: the same under a harmonic force A sin(W t + phase).
- ``hardening``: m x'' + k0 (1 + a x^2) x = 0 (the hardening oscillator of
  Yang et al. 2017, section 4.2) is the undamped Duffing oscillator
  x'' + alpha x + beta x^3 = 0 with alpha = k0/m, beta = k0 a/m. From rest at
  x0 its solution is x = x0 cn(w t | m_e) with w^2 = alpha + beta x0^2 and
  parameter m_e = beta x0^2 / (2 w^2); from any other start it is
  A cn(w (t + tau) | m_e) with the amplitude A given by the energy and the
  phase tau by an incomplete elliptic integral.
- ``pendulum``: theta'' + w0^2 sin(theta) = 0 while it swings (libration,
  k^2 = sin^2(theta0/2) + theta0'^2/(4 w0^2) < 1):
  theta = 2 arcsin(k sn(w0 t + u0 | k^2)).

scipy's ellipj, ellipk and ellipkinc take the parameter m = k^2, not the
modulus k.
"""

from __future__ import annotations

import math

import numpy as np

from .. import _checks


def _params(**kw):
    """Named checks: masses and stiffnesses > 0, the rest finite (a, c >= 0)."""
    from .._checks import real

    out = []
    for name, x in kw.items():
        x = real(name, x, positive=name in ("m", "k", "k0"))
        if name in ("a", "c") and x < 0.0:
            raise _checks.value_error(name, f"must be >= 0, got {x}")
        out.append(x)
    return out


def _times(t):
    from .._checks import real_array

    t = real_array("t", t)
    if not np.all(np.isfinite(t)):
        raise _checks.value_error("t", "contains NaN or Inf")
    return t


def linear_sdof(t, *, m: float, k: float, c: float = 0.0, x0: float = 1.0, v0: float = 0.0):
    """Displacement and velocity of the free linear oscillator (0 <= damping ratio < 1)."""
    m, k, c, x0, v0 = _params(m=m, k=k, c=c, x0=x0, v0=v0)
    t = _times(t)
    w = math.sqrt(k / m)
    xi = c / (2.0 * m * w)
    if not 0.0 <= xi < 1.0:
        raise _checks.value_error("c", f"the closed form needs a damping ratio in [0, 1), got {xi}")
    wd = w * math.sqrt(1.0 - xi * xi)
    B = (v0 + xi * w * x0) / wd
    env = np.exp(-xi * w * t)
    cos, sin = np.cos(wd * t), np.sin(wd * t)
    x = env * (x0 * cos + B * sin)
    v = env * ((-xi * w) * (x0 * cos + B * sin) + wd * (-x0 * sin + B * cos))
    return x, v


def _hardening_parameters(m: float, k0: float, a: float, x0: float, v0: float) -> tuple[float, float, float, float]:
    """(amplitude A, frequency w, parameter m_e, phase w tau) of x = A cn(w (t + tau) | m_e)."""
    from scipy import special

    m, k0, a, x0, v0 = _params(m=m, k0=k0, a=a, x0=x0, v0=v0)
    if v0 == 0.0:
        amp = abs(x0)
    else:
        # k0 (A^2/2 + a A^4/4) = E, a quadratic in A^2
        energy = 0.5 * m * v0 * v0 + k0 * (0.5 * x0 * x0 + 0.25 * a * x0 ** 4)
        amp2 = (math.sqrt(1.0 + 4.0 * a * energy / k0) - 1.0) / a if a > 0 else 2.0 * energy / k0
        amp = math.sqrt(amp2)
    w = math.sqrt((k0 + k0 * a * amp * amp) / m)
    me = k0 * a * amp * amp / (2.0 * m * w * w)
    if amp == 0.0:
        return 0.0, w, me, 0.0
    # cn(w tau) = x0 / A with sn(w tau) >= 0 gives x'(0) <= 0; a rising start takes -tau
    phi = math.acos(min(1.0, max(-1.0, x0 / amp)))
    phase = float(special.ellipkinc(phi, me))
    return amp, w, me, -phase if v0 > 0 else phase


def forced_linear_sdof(t, *, m: float, k: float, c: float = 0.0, x0: float = 1.0, v0: float = 0.0,
                       amplitude: float, omega: float, phase: float = 0.0):
    """Displacement and velocity of m x'' + c x' + k x = amplitude sin(omega t + phase) from (x0, v0)
    (0 <= damping ratio < 1, not at resonance): the steady state plus the free response that matches the start."""
    m, k, c, x0, v0 = _params(m=m, k=k, c=c, x0=x0, v0=v0)
    amplitude, omega, phase = (_checks.real(n, x) for n, x in (("amplitude", amplitude), ("omega", omega),
                                                                ("phase", phase)))
    d = k - m * omega ** 2
    det = d * d + (c * omega) ** 2
    if det == 0.0:
        raise _checks.value_error("omega", "undamped resonance (omega^2 = k/m): no steady state")
    p, q = amplitude * d / det, -amplitude * c * omega / det  # x_p = p sin(th) + q cos(th), th = omega t + phase

    def particular(tt):
        th = omega * tt + phase
        return p * np.sin(th) + q * np.cos(th), omega * (p * np.cos(th) - q * np.sin(th))

    t = _times(t)
    xp, vp = particular(t)
    xp0, vp0 = particular(0.0)
    xh, vh = linear_sdof(t, m=m, k=k, c=c, x0=x0 - xp0, v0=v0 - vp0)
    return xp + xh, vp + vh


def hardening(t, *, m: float = 1.0, k0: float = 100.0, a: float = 30.0, x0: float = 1.5, v0: float = 0.0):
    """Displacement and velocity of m x'' + k0 (1 + a x^2) x = 0, x(0) = x0, x'(0) = v0."""
    from scipy import special

    t = _times(t)
    amp, w, me, phase = _hardening_parameters(m, k0, a, x0, v0)
    sn, cn, dn, _ = special.ellipj(w * t + phase, me)
    return amp * cn, -amp * w * sn * dn


def hardening_period(*, m: float = 1.0, k0: float = 100.0, a: float = 30.0, x0: float = 1.5,
                     v0: float = 0.0) -> float:
    """Period 4 K(m_e) / w of the hardening oscillator."""
    from scipy import special

    _, w, me, _ = _hardening_parameters(m, k0, a, x0, v0)
    return 4.0 * float(special.ellipk(me)) / w


def _pendulum_parameters(omega0: float, theta0: float, v0: float) -> tuple[float, float]:
    """(modulus k, phase u0) of theta = 2 arcsin(k sn(w0 t + u0 | k^2))."""
    from scipy import special
    from .._checks import real

    omega0 = real("omega0", omega0, positive=True)
    theta0, v0 = _params(theta0=theta0, v0=v0)
    s = math.sin(0.5 * theta0)
    k2 = s * s + v0 * v0 / (4.0 * omega0 * omega0)
    if not k2 < 1.0:
        raise _checks.value_error("theta0, v0", f"the pendulum goes over the top (k^2 = {k2:.6g} >= 1); "
                         "the closed form here covers the swinging pendulum only")
    k = math.sqrt(k2)
    if k == 0.0:
        return 0.0, 0.0
    u0 = float(special.ellipkinc(math.asin(max(-1.0, min(1.0, s / k))), k2))
    if v0 < 0:  # sn(2K - u) = sn(u), cn(2K - u) = -cn(u)
        u0 = 2.0 * float(special.ellipk(k2)) - u0
    return k, u0


def pendulum(t, *, omega0: float = 1.0, theta0: float, v0: float = 0.0):
    """Angle and angular velocity of theta'' + omega0^2 sin(theta) = 0, theta(0) = theta0,
    theta'(0) = v0, for a swinging pendulum (it does not go over the top)."""
    from scipy import special

    t = _times(t)
    k, u0 = _pendulum_parameters(omega0, theta0, v0)
    sn, cn, _, _ = special.ellipj(omega0 * t + u0, k * k)
    return 2.0 * np.arcsin(k * sn), 2.0 * k * omega0 * cn


def pendulum_period(*, omega0: float = 1.0, theta0: float, v0: float = 0.0) -> float:
    """Period 4 K(k^2) / omega0 of the swinging pendulum."""
    from scipy import special

    k, _ = _pendulum_parameters(omega0, theta0, v0)
    return 4.0 * float(special.ellipk(k * k)) / omega0


def hardening_energy(x, v, *, m: float = 1.0, k0: float = 100.0, a: float = 30.0):
    """Kinetic plus potential energy m v^2/2 + k0 (x^2/2 + a x^4/4)."""
    from .._checks import real_array

    m, k0, a = _params(m=m, k0=k0, a=a)
    x = real_array("x", x)
    v = real_array("v", v)
    return 0.5 * m * v * v + k0 * (0.5 * x * x + 0.25 * a * x ** 4)
