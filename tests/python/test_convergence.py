"""Observed order of accuracy of every scheme against closed-form solutions.

The order is the least-squares slope of log(max error) against log(dt) over
four step sizes halving from omega*dt = 0.1 (linear) or 0.05 (hardening)
down, i.e. in the asymptotic regime but far above round-off.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import nvib

# ---------------------------------------------------------------------------
# Linear oscillator m x'' + c x' + k x = 0 (omega = 10 rad/s, period 0.63 s)
M, K = 1.0, 100.0
OMEGA = math.sqrt(K / M)
X0, V0 = 1.0, 0.5
XI = 0.05
C_DAMPED = 2.0 * XI * OMEGA * M
T_END = 2.0  # a little over three periods
OMEGA_DT = (0.1, 0.05, 0.025, 0.0125)
DTS = tuple(w / OMEGA for w in OMEGA_DT)

ORDER_TOL = 0.1


def fitted_order(dts, errors) -> float:
    return float(np.polyfit(np.log(dts), np.log(errors), 1)[0])


SCHEMES = {
    "CentralDifference": lambda: nvib.CentralDifference(),
    "Zhai(0.5,0.5)": lambda: nvib.Zhai(0.5, 0.5),
    "CEMDTS(0)": lambda: nvib.CEMDTS(eta=0.0),
    "CEMDTS(1/12)": lambda: nvib.CEMDTS(eta=1.0 / 12.0),
    "CEMDTS(0.45)": lambda: nvib.CEMDTS(eta=0.45),
    "CEMDTS(0.5)": lambda: nvib.CEMDTS(eta=0.5),
    "Newmark-newton": lambda: nvib.Newmark(0.25, 0.5, iteration="newton"),
    "Newmark-one_iteration": lambda: nvib.Newmark(0.25, 0.5, iteration="one_iteration"),
    "GeneralizedAlpha-paper": lambda: nvib.GeneralizedAlpha(),
    "GeneralizedAlpha-rho0.8": lambda: nvib.GeneralizedAlpha.from_rho_inf(0.8),
    "HHT(-0.1)": lambda: nvib.GeneralizedAlpha.hht(-0.1),
    "WBZ(-0.1)": lambda: nvib.GeneralizedAlpha.wbz(-0.1),
}
HALF_STEP = lambda: nvib.CentralDifference(velocity="half_step")  # noqa: E731
PIM_ORDERS = (1, 2, 3)


def linear_model(damping: str) -> nvib.Model:
    """'none', 'matrix' (C matrix) or 'damper' (built-in damper effect)."""
    if damping == "none":
        return nvib.Model([M], K=[[K]], u0=[X0], v0=[V0])
    if damping == "matrix":
        return nvib.Model([M], K=[[K]], C=[[C_DAMPED]], u0=[X0], v0=[V0])
    assert damping == "damper"
    return nvib.Model([M], effects=[{"type": "spring", "measure": {"x": 1.0}, "k": K},
                                    {"type": "damper", "measure": {"x": 1.0}, "c": C_DAMPED}],
                      dofs=["x"], u0=[X0], v0=[V0])


def damping_coefficient(damping: str) -> float:
    return 0.0 if damping == "none" else C_DAMPED


def linear_errors(scheme_factory, damping: str):
    model = linear_model(damping)
    c = damping_coefficient(damping)
    eu, ev = [], []
    for dt in DTS:
        res = nvib.solve(model, scheme_factory(), dt=dt, t_end=T_END)
        assert res.status == nvib.Status.success
        xe, ve = nvib.exact.linear_sdof(res.t, m=M, k=K, c=c, x0=X0, v0=V0)
        eu.append(np.max(np.abs(res.u[:, 0] - xe)))
        ev.append(np.max(np.abs(res.v[:, 0] - ve)))
    return np.array(eu), np.array(ev)


@pytest.mark.parametrize("damping", ["none", "matrix", "damper"])
@pytest.mark.parametrize("name", list(SCHEMES))
def test_linear_order_two(name, damping):
    eu, ev = linear_errors(SCHEMES[name], damping)
    pu, pv = fitted_order(DTS, eu), fitted_order(DTS, ev)
    assert abs(pu - 2.0) <= ORDER_TOL, f"{name}, damping={damping}: displacement order {pu:.3f}, errors {eu}"
    assert abs(pv - 2.0) <= ORDER_TOL, f"{name}, damping={damping}: velocity order {pv:.3f}, errors {ev}"
    # Sanity: the errors are real truncation errors, not round-off.
    assert eu[-1] > 1e-9 and ev[-1] > 1e-9


@pytest.mark.parametrize("damping", ["none", "matrix", "damper"])
def test_linear_order_two_half_step_displacement(damping):
    """The half-step variant reports v_{n+1/2}: only its displacement is measured."""
    eu, _ = linear_errors(HALF_STEP, damping)
    pu = fitted_order(DTS, eu)
    assert abs(pu - 2.0) <= ORDER_TOL, (
        f"CentralDifference(half_step), damping={damping}: displacement order {pu:.3f} "
        f"(scheme.order = {HALF_STEP().order}), errors {eu}")


def test_half_step_velocity_is_the_midpoint_velocity():
    """Undamped: the reported velocity at t_{n+1} is v(t_{n+1/2}) to second order."""
    model = linear_model("none")
    errs = []
    for dt in DTS:
        res = nvib.solve(model, HALF_STEP(), dt=dt, t_end=T_END)
        _, ve = nvib.exact.linear_sdof(res.t[1:] - 0.5 * dt, m=M, k=K, x0=X0, v0=V0)
        errs.append(np.max(np.abs(res.v[1:, 0] - ve)))
    p = fitted_order(DTS, errs)
    assert abs(p - 2.0) <= ORDER_TOL, f"half-step velocity order {p:.3f}, errors {errs}"


@pytest.mark.parametrize("damping", ["none", "matrix", "damper"])
@pytest.mark.parametrize("order", PIM_ORDERS)
def test_pim_exact_on_linear_models(order, damping):
    """The linear part sits entirely in the exponential, so PIM is exact (any interpolation order)."""
    model = linear_model(damping)
    c = damping_coefficient(damping)
    for dt in (DTS[0], DTS[-1]):
        res = nvib.solve(model, nvib.PreciseIntegration(order=order), dt=dt, t_end=T_END)
        xe, ve = nvib.exact.linear_sdof(res.t, m=M, k=K, c=c, x0=X0, v0=V0)
        ru = np.max(np.abs(res.u[:, 0] - xe)) / np.max(np.abs(xe))
        rv = np.max(np.abs(res.v[:, 0] - ve)) / np.max(np.abs(ve))
        assert ru <= 1e-12 and rv <= 1e-12, f"PIM order {order}, dt={dt}: rel. errors u {ru:.2e}, v {rv:.2e}"


# ---------------------------------------------------------------------------
# Forced damped linear oscillator m x'' + c x' + k x = A sin(W t + phi): the
# load is what PIM interpolates, so its interpolation order shows here.
A_LOAD, W_LOAD, PHASE = 50.0, 7.0, 0.3


def forced_exact(t):
    d = K - M * W_LOAD ** 2
    p, q = np.linalg.solve([[d, -C_DAMPED * W_LOAD], [C_DAMPED * W_LOAD, d]], [A_LOAD, 0.0])

    def particular(tt):
        th = W_LOAD * tt + PHASE
        return p * np.sin(th) + q * np.cos(th), W_LOAD * (p * np.cos(th) - q * np.sin(th))

    xp, vp = particular(np.asarray(t, dtype=float))
    xp0, vp0 = particular(0.0)
    xh, vh = nvib.exact.linear_sdof(t, m=M, k=K, c=C_DAMPED, x0=X0 - xp0, v0=V0 - vp0)
    return xp + xh, vp + vh


def forced_model() -> nvib.Model:
    return nvib.Model([M], effects=[
        {"type": "spring", "measure": {"x": 1.0}, "k": K},
        {"type": "damper", "measure": {"x": 1.0}, "c": C_DAMPED},
        {"type": "harmonic_force", "measure": {"x": 1.0}, "amplitude": A_LOAD, "omega": W_LOAD, "phase": PHASE},
    ], dofs=["x"], u0=[X0], v0=[V0])


def forced_errors(scheme_factory):
    model = forced_model()
    eu, ev = [], []
    for dt in DTS:
        res = nvib.solve(model, scheme_factory(), dt=dt, t_end=T_END)
        xe, ve = forced_exact(res.t)
        eu.append(np.max(np.abs(res.u[:, 0] - xe)))
        ev.append(np.max(np.abs(res.v[:, 0] - ve)))
    return np.array(eu), np.array(ev)


def test_forced_reference_satisfies_the_equation():
    t = np.linspace(0.0, T_END, 4001)
    x, v = forced_exact(t)
    assert x[0] == pytest.approx(X0, abs=1e-13) and v[0] == pytest.approx(V0, abs=1e-12)
    acc = np.gradient(v, t, edge_order=2)
    res = M * acc + C_DAMPED * v + K * x - A_LOAD * np.sin(W_LOAD * t + PHASE)
    assert np.max(np.abs(res[2:-2])) < 1e-3 * A_LOAD


@pytest.mark.parametrize("name", list(SCHEMES))
def test_forced_order_two(name):
    eu, ev = forced_errors(SCHEMES[name])
    pu, pv = fitted_order(DTS, eu), fitted_order(DTS, ev)
    assert abs(pu - 2.0) <= ORDER_TOL, f"{name}: displacement order {pu:.3f}, errors {eu}"
    assert abs(pv - 2.0) <= ORDER_TOL, f"{name}: velocity order {pv:.3f}, errors {ev}"


@pytest.mark.parametrize("order, expected", [(1, 2.0), (2, 3.0)])
def test_forced_pim_order(order, expected):
    """Interpolating the load with degree p gives order p + 1 (order 1 -> 2, order 2 -> 3)."""
    eu, ev = forced_errors(lambda: nvib.PreciseIntegration(order=order))
    pu, pv = fitted_order(DTS, eu), fitted_order(DTS, ev)
    assert abs(pu - expected) <= ORDER_TOL, f"PIM order {order}: displacement order {pu:.3f}, errors {eu}"
    assert abs(pv - expected) <= ORDER_TOL, f"PIM order {order}: velocity order {pv:.3f}, errors {ev}"


# ---------------------------------------------------------------------------
# Hardening oscillator m x'' + k0 (1 + a x^2) x = 0 (Yang et al. 2017, 4.2)
HM, HK0, HA, HX0 = 1.0, 100.0, 30.0, 1.5
H_OMEGA = math.sqrt(HK0 / HM * (1.0 + HA * HX0 ** 2))  # linearised at the amplitude
H_PERIOD = nvib.exact.hardening_period(m=HM, k0=HK0, a=HA, x0=HX0)
H_DTS = tuple(w / H_OMEGA for w in (0.05, 0.025, 0.0125, 0.00625))
H_ORDER_TOL = 0.15


def hardening_errors(scheme_factory):
    model = nvib.Model([HM], effects=[{"type": "hardening_spring", "measure": {"x": 1.0}, "k0": HK0, "a": HA}],
                       dofs=["x"], u0=[HX0])
    eu, ev = [], []
    for dt in H_DTS:
        res = nvib.solve(model, scheme_factory(), dt=dt, t_end=3.0 * H_PERIOD)
        xe, ve = nvib.exact.hardening(res.t, m=HM, k0=HK0, a=HA, x0=HX0)
        eu.append(np.max(np.abs(res.u[:, 0] - xe)))
        ev.append(np.max(np.abs(res.v[:, 0] - ve)))
    return np.array(eu), np.array(ev)


def test_hardening_reference_is_consistent():
    t = np.linspace(0.0, 3.0 * H_PERIOD, 20001)
    x, v = nvib.exact.hardening(t, m=HM, k0=HK0, a=HA, x0=HX0)
    e = nvib.exact.hardening_energy(x, v, m=HM, k0=HK0, a=HA)
    assert np.max(np.abs(e - e[0])) <= 1e-12 * e[0]
    xp, _ = nvib.exact.hardening(H_PERIOD, m=HM, k0=HK0, a=HA, x0=HX0)
    assert float(xp) == pytest.approx(HX0, rel=1e-12)


@pytest.mark.parametrize("name", list(SCHEMES))
def test_hardening_order_two(name):
    eu, ev = hardening_errors(SCHEMES[name])
    pu, pv = fitted_order(H_DTS, eu), fitted_order(H_DTS, ev)
    assert abs(pu - 2.0) <= H_ORDER_TOL, f"{name}: displacement order {pu:.3f}, errors {eu}"
    assert abs(pv - 2.0) <= H_ORDER_TOL, f"{name}: velocity order {pv:.3f}, errors {ev}"


def test_hardening_order_two_half_step_displacement():
    eu, _ = hardening_errors(HALF_STEP)
    pu = fitted_order(H_DTS, eu)
    assert abs(pu - 2.0) <= H_ORDER_TOL, f"half-step displacement order {pu:.3f}, errors {eu}"


def test_hardening_pim_order_one():
    eu, ev = hardening_errors(lambda: nvib.PreciseIntegration(order=1))
    pu, pv = fitted_order(H_DTS, eu), fitted_order(H_DTS, ev)
    assert abs(pu - 2.0) <= H_ORDER_TOL, f"PIM(order=1): displacement order {pu:.3f}, errors {eu}"
    assert abs(pv - 2.0) <= H_ORDER_TOL, f"PIM(order=1): velocity order {pv:.3f}, errors {ev}"


def test_hardening_pim_order_two():
    eu, ev = hardening_errors(lambda: nvib.PreciseIntegration(order=2))
    pu, pv = fitted_order(H_DTS, eu), fitted_order(H_DTS, ev)
    assert pu >= 1.9, f"PIM(order=2): displacement order {pu:.3f}, errors {eu}"
    assert pv >= 1.9, f"PIM(order=2): velocity order {pv:.3f}, errors {ev}"
