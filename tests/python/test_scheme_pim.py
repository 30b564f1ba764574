"""Precise integration: order p + 1 for interpolation degree p, up to 3 (the start-up steps leave an
O(h^3) error); without a corrector, 2."""

from __future__ import annotations

import numpy as np
import pytest

import nvib
from _orders import LINEAR_DTS, LINEAR_T_END, C, K, M, V0, X0, check_declared_orders, free_model


@pytest.mark.parametrize("interpolation, corrections, declared", [(1, 1, 2), (2, 1, 3), (3, 1, 3), (3, 2, 3),
                                                                  (2, 0, 2), (1, 0, 2)])
def test_declared_order(interpolation, corrections, declared):
    s = nvib.PreciseIntegration(interpolation=interpolation, corrections=corrections)
    assert (s.order_u, s.order_v) == (declared, declared)


# Fitted u/v orders measured at 0, 1, 2 halvings below the problem's own steps:
#   interpolation 1: forced 2.000/1.999, hardening 2.015/2.016, 2.003/2.003
#   interpolation 2 (the default, declared 3): forced 3.002/3.003, hardening 2.997/3.004
#   interpolation 3: forced 3.072/3.072, 3.038/3.040, 3.020/3.021;
#                    hardening 2.953/2.956, 2.975/2.979, 2.987/2.988
# Interpolation 3 approaches its order more slowly, so its fit starts one halving down.
@pytest.mark.parametrize("interpolation, refine", [(1, 0), (2, 0), (3, 1)])
def test_orders_on_the_forced_oscillator(interpolation, refine):
    check_declared_orders(nvib.PreciseIntegration(interpolation=interpolation), "forced", refine=refine)


@pytest.mark.parametrize("interpolation, refine", [(1, 0), (2, 0), (3, 1)])
def test_orders_on_the_hardening_oscillator(interpolation, refine):
    check_declared_orders(nvib.PreciseIntegration(interpolation=interpolation), "hardening", refine=refine)


@pytest.mark.parametrize("problem, refine", [("forced", 0), ("hardening", 5)])
def test_without_corrector_second_order(problem, refine):
    # Forced: fitted 1.977/1.995 at the problem's own steps. On the hardening oscillator the error is
    # not monotone at first: fitted u/v orders 1.936/1.939, 1.332/1.436, 1.720/1.732, 1.883/1.889,
    # 1.946/1.948, 1.974/1.975, 1.990/1.990 from 0 to 6 halvings down; the fit starts 5 halvings down.
    # Further down it rises past 2 (2.013 at 7, 2.156 at 8 halvings, errors 3e-9 to 6e-10).
    check_declared_orders(nvib.PreciseIntegration(corrections=0), problem, refine=refine)


@pytest.mark.parametrize("damping", ["none", "matrix", "damper"])
@pytest.mark.parametrize("interpolation", [1, 2, 3])
def test_exact_on_linear_models(interpolation, damping):
    """The linear part sits entirely in the exponential, so PIM is exact (any interpolation degree)."""
    model = free_model(damping)
    c = 0.0 if damping == "none" else C
    for dt in (LINEAR_DTS[0], LINEAR_DTS[-1]):
        res = nvib.solve(model, nvib.PreciseIntegration(interpolation=interpolation), dt=dt, t_end=LINEAR_T_END)
        xe, ve = nvib.exact.linear_sdof(res.t, m=M, k=K, c=c, x0=X0, v0=V0)
        ru = np.max(np.abs(res.u[:, 0] - xe)) / np.max(np.abs(xe))
        rv = np.max(np.abs(res.v[:, 0] - ve)) / np.max(np.abs(ve))
        assert ru <= 1e-12 and rv <= 1e-12, \
            f"PIM interpolation {interpolation}, dt={dt}: rel. errors u {ru:.2e}, v {rv:.2e}"
