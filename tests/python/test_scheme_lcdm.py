"""CentralDifference (LCDM): the half-step variant reports v_{n+1/2}, first order against v(t_{n+1})."""

from __future__ import annotations

import numpy as np
import pytest

import nvib
from _orders import LINEAR_DTS, LINEAR_T_END, K, M, V0, X0, check_declared_orders, free_model, hardening_model, slope


def test_declared_orders_of_the_variants():
    half = nvib.CentralDifference(velocity="half_step")
    assert (half.order_u, half.order_v) == (2, 1)
    assert (nvib.CentralDifference().order_u, nvib.CentralDifference().order_v) == (2, 2)


# Fitted u/v orders: forced 2.010/0.976, hardening 2.000/1.002.
@pytest.mark.parametrize("problem", ["forced", "hardening"])
def test_half_step_orders(problem):
    check_declared_orders(nvib.CentralDifference(velocity="half_step"), problem)


def test_both_velocities_share_their_displacements():
    model = hardening_model()
    a = nvib.solve(model, nvib.CentralDifference(), dt=1e-3, t_end=0.3)
    b = nvib.solve(model, nvib.CentralDifference(velocity="half_step"), dt=1e-3, t_end=0.3)
    assert np.max(np.abs(a.u - b.u)) <= 1e-12 * np.max(np.abs(a.u))


def test_half_step_velocity_is_the_midpoint_velocity():
    """Undamped: the reported velocity at t_{n+1} is v(t_{n+1/2}) to second order."""
    model = free_model("none")
    errs = []
    for dt in LINEAR_DTS:
        res = nvib.solve(model, nvib.CentralDifference(velocity="half_step"), dt=dt, t_end=LINEAR_T_END)
        _, ve = nvib.exact.linear_sdof(res.t[1:] - 0.5 * dt, m=M, k=K, x0=X0, v0=V0)
        errs.append(np.max(np.abs(res.v[1:, 0] - ve)))
    p = slope(LINEAR_DTS, errs)
    assert abs(p - 2.0) <= 0.1, f"half-step velocity order {p:.3f}, errors {errs}"
