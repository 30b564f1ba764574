"""Fitted orders of accuracy against closed forms: the least-squares slope of
log(max error over the run) against log(dt) over four halvings of the step,
in the asymptotic regime and far above round-off."""

from __future__ import annotations

import math

import numpy as np

import nvib

ORDER_TOL = 0.1

# Forced damped linear oscillator m x'' + c x' + k x = A sin(W t + phase): the
# load is what PIM interpolates, so its order shows here too.
M, K, XI = 1.0, 100.0, 0.05
OMEGA = math.sqrt(K / M)
C = 2.0 * XI * OMEGA * M
X0, V0 = 1.0, 0.5
LOAD = dict(amplitude=50.0, omega=7.0, phase=0.3)
LINEAR_T_END = 2.0
LINEAR_DTS = tuple(w / OMEGA for w in (0.1, 0.05, 0.025, 0.0125))

# Hardening oscillator m x'' + k0 (1 + a x^2) x = 0 (Yang et al. 2017, section 4.2).
# Started off a turning point (v0 != 0): from rest the problem is symmetric in time about t = 0, and
# some schemes' errors then cancel to a higher order than they have in general.
HM, HK0, HA, HX0, HV0 = 1.0, 100.0, 30.0, 1.5, 30.0
H_OMEGA = math.sqrt(HK0 / HM * (1.0 + HA * HX0 ** 2))  # linearised at x0
H_T_END = 3.0 * nvib.exact.hardening_period(m=HM, k0=HK0, a=HA, x0=HX0, v0=HV0)
H_DTS = tuple(w / H_OMEGA for w in (0.05, 0.025, 0.0125, 0.00625))


def slope(dts, errors) -> float:
    return float(np.polyfit(np.log(dts), np.log(errors), 1)[0])


def forced_model() -> nvib.Model:
    return nvib.Model([M], effects=[
        {"type": "spring", "measure": {"x": 1.0}, "k": K},
        {"type": "damper", "measure": {"x": 1.0}, "c": C},
        {"type": "harmonic_force", "measure": {"x": 1.0}, **LOAD},
    ], dofs=["x"], u0=[X0], v0=[V0])


def free_model(damping: str) -> nvib.Model:
    """The free linear oscillator (the forced one without its load): damping 'none', 'matrix' (a C
    matrix) or 'damper' (a damper effect)."""
    if damping == "none":
        return nvib.Model([M], K=[[K]], u0=[X0], v0=[V0])
    if damping == "matrix":
        return nvib.Model([M], K=[[K]], C=[[C]], u0=[X0], v0=[V0])
    assert damping == "damper", damping
    return nvib.Model([M], effects=[{"type": "spring", "measure": {"x": 1.0}, "k": K},
                                    {"type": "damper", "measure": {"x": 1.0}, "c": C}],
                      dofs=["x"], u0=[X0], v0=[V0])


def hardening_model() -> nvib.Model:
    return nvib.Model([HM], effects=[{"type": "hardening_spring", "measure": {"x": 1.0}, "k0": HK0, "a": HA}],
                      dofs=["x"], u0=[HX0], v0=[HV0])


def errors(problem: str, scheme, *, refine: int = 0) -> tuple[np.ndarray, np.ndarray, tuple]:
    """Max errors of u and v over the run for each step of the problem ('forced', 'hardening', or the free
    linear oscillator 'free-none', 'free-matrix', 'free-damper'); refine halves the steps that many times
    (for schemes whose asymptotic regime starts later)."""
    if problem.startswith("free-"):
        model, dts, t_end = free_model(problem[5:]), LINEAR_DTS, LINEAR_T_END
    elif problem == "forced":
        model, dts, t_end = forced_model(), LINEAR_DTS, LINEAR_T_END
    else:
        model, dts, t_end = hardening_model(), H_DTS, H_T_END
    dts = tuple(dt / 2 ** refine for dt in dts)
    eu, ev = [], []
    for dt in dts:
        res = nvib.solve(model, scheme, dt=dt, t_end=t_end)
        if problem.startswith("free-"):
            xe, ve = nvib.exact.linear_sdof(res.t, m=M, k=K, c=0.0 if problem == "free-none" else C, x0=X0, v0=V0)
        elif problem == "forced":
            xe, ve = nvib.exact.forced_linear_sdof(res.t, m=M, k=K, c=C, x0=X0, v0=V0, **LOAD)
        else:
            xe, ve = nvib.exact.hardening(res.t, m=HM, k0=HK0, a=HA, x0=HX0, v0=HV0)
        eu.append(np.max(np.abs(res.u[:, 0] - xe)))
        ev.append(np.max(np.abs(res.v[:, 0] - ve)))
    return np.array(eu), np.array(ev), dts


def check_declared_orders(scheme, problem: str, *, refine: int = 0) -> None:
    """The fitted orders of u and v equal the scheme's declared order_u and order_v to ORDER_TOL.

    The fit is over four step sizes, refine halvings below the problem's own. There is no search for
    a window that passes: a scheme whose asymptotic regime starts later is given a larger refine by
    its test, with the fitted orders measured at the coarser windows quoted in a comment there."""
    eu, ev, dts = errors(problem, scheme, refine=refine)
    assert eu[-1] > 1e-10 and ev[-1] > 1e-10, f"{scheme!r} on {problem}: errors at round-off {eu}, {ev}"
    pu, pv = slope(dts, eu), slope(dts, ev)
    assert abs(pu - scheme.order_u) <= ORDER_TOL, \
        f"{scheme!r} on {problem}: displacement order {pu:.3f}, declared {scheme.order_u}; errors {eu} " \
        f"(refine {refine})"
    assert abs(pv - scheme.order_v) <= ORDER_TOL, \
        f"{scheme!r} on {problem}: velocity order {pv:.3f}, declared {scheme.order_v}; errors {ev} " \
        f"(refine {refine})"
