"""Precise integration: order p + 1 for interpolation degree p, up to 3 (the start-up steps leave an
O(h^3) error); without a corrector, 2."""

from __future__ import annotations

import pytest

import nvib
from _orders import check_declared_orders


@pytest.mark.parametrize("order, corrections, declared", [(1, 1, 2), (2, 1, 3), (3, 1, 3), (3, 2, 3), (2, 0, 2),
                                                          (1, 0, 2)])
def test_declared_order(order, corrections, declared):
    s = nvib.PreciseIntegration(order=order, corrections=corrections)
    assert (s.order_u, s.order_v) == (declared, declared)


@pytest.mark.parametrize("order", [1, 2, 3])
def test_orders_on_the_forced_oscillator(order):
    check_declared_orders(nvib.PreciseIntegration(order=order), "forced")


@pytest.mark.parametrize("order, refine", [(1, 0), (2, 0), (3, 2)])
def test_orders_on_the_hardening_oscillator(order, refine):
    # interpolation 3 reaches its asymptotic order 3 later (3.18, 3.11, 3.06 starting 0, 1, 2 halvings down)
    check_declared_orders(nvib.PreciseIntegration(order=order), "hardening", refine=refine)


def test_without_corrector_second_order():
    # on the hardening oscillator, started at rest, it happens to show 3 (its first step's error vanishes)
    check_declared_orders(nvib.PreciseIntegration(corrections=0), "forced")
