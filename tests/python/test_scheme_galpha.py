"""Generalized-alpha: second order when gamma = 1/2 - alpha_m + alpha_f, in every member (rho_inf, HHT, WBZ)."""

from __future__ import annotations

import numpy as np
import pytest

import nvib
from _orders import check_declared_orders, hardening_model


@pytest.mark.parametrize("make", [
    lambda: nvib.GeneralizedAlpha.from_rho_inf(0.8), lambda: nvib.GeneralizedAlpha.from_rho_inf(0.5),
    lambda: nvib.GeneralizedAlpha.hht(-0.1), lambda: nvib.GeneralizedAlpha.wbz(-0.1),
    lambda: nvib.GeneralizedAlpha(iteration="modified"), lambda: nvib.GeneralizedAlpha(iteration="one_iteration"),
])
# Fitted u/v orders at the problems' own steps: forced 1.999 to 2.000; hardening 2.000/2.004 (rho_inf 0.8,
# modified) to 2.043/2.051 (WBZ), 2.019/2.023 (rho_inf 0.5), 2.018/2.025 (HHT), 2.027/2.029 (one_iteration).
@pytest.mark.parametrize("problem", ["forced", "hardening"])
def test_second_order_members(make, problem):
    assert make().order_u == 2
    check_declared_orders(make(), problem)


def test_first_order_off_the_second_order_gamma():
    s = nvib.GeneralizedAlpha(0.0, 0.2, 0.36, 0.8)  # gamma = 0.8 != 1/2 + 0.2
    assert (s.order_u, s.order_v) == (1, 1)
    check_declared_orders(s, "forced")  # fitted 0.991/0.989


def test_incremental_format_with_equal_alphas_is_newmarks():
    """With alpha_m = alpha_f the incremental equation is Newmark's divided by (1 - alpha_m)."""
    model = hardening_model()
    a = nvib.solve(model, nvib.GeneralizedAlpha(iteration="incremental"), dt=1e-3, t_end=0.3)
    b = nvib.solve(model, nvib.Newmark(iteration="incremental"), dt=1e-3, t_end=0.3)
    assert np.max(np.abs(a.u - b.u)) <= 1e-12 * np.max(np.abs(b.u))
    assert nvib.GeneralizedAlpha(iteration="incremental").order_u == 1
