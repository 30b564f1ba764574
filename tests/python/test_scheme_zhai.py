"""Zhai's two-step method: second order only with phi = 1/2 (psi does not change the order)."""

from __future__ import annotations

import pytest

import nvib
from _orders import check_declared_orders


@pytest.mark.parametrize("psi, phi, order", [(0.5, 0.5, 2), (0.6, 0.6, 1), (0.5, 0.6, 1), (0.6, 0.5, 2)])
def test_declared_order(psi, phi, order):
    s = nvib.Zhai(psi, phi)
    assert (s.order_u, s.order_v) == (order, order)


@pytest.mark.parametrize("psi, phi", [(0.6, 0.6), (0.5, 0.6)])
@pytest.mark.parametrize("problem", ["forced", "hardening"])
def test_first_order_when_phi_is_not_half(psi, phi, problem):
    # on the hardening oscillator the velocity fits 0.90, 0.96, 0.98 from 0, 1, 2 halvings down
    check_declared_orders(nvib.Zhai(psi, phi), problem, refine=1 if problem == "hardening" else 0)


def test_psi_alone_keeps_second_order():
    # On the hardening oscillator psi = 0.6 is still pre-asymptotic at these steps (fitted 2.7).
    check_declared_orders(nvib.Zhai(0.6, 0.5), "forced")
