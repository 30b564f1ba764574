"""Newmark: second order with gamma = 1/2 in every mode that solves the step's equation; gamma != 1/2 and
the textbook incremental format (on nonlinear models) are first order."""

from __future__ import annotations

import pytest

import nvib
from _orders import check_declared_orders


@pytest.mark.parametrize("make, order", [
    (lambda: nvib.Newmark(), 2),
    (lambda: nvib.Newmark(1.0 / 6.0, 0.5), 2),             # linear acceleration
    (lambda: nvib.Newmark(0.3025, 0.6), 1),                 # gamma != 1/2
    (lambda: nvib.Newmark(iteration="modified"), 2),
    (lambda: nvib.Newmark(iteration="initial"), 2),
    (lambda: nvib.Newmark(iteration="one_iteration"), 2),
    (lambda: nvib.Newmark(iteration="incremental"), 1),
])
def test_declared_order(make, order):
    s = make()
    assert (s.order_u, s.order_v) == (order, order)


@pytest.mark.parametrize("make", [
    lambda: nvib.Newmark(1.0 / 6.0, 0.5), lambda: nvib.Newmark(0.3025, 0.6), lambda: nvib.Newmark(iteration="modified"),
    lambda: nvib.Newmark(iteration="initial"), lambda: nvib.Newmark(iteration="one_iteration"),
])
@pytest.mark.parametrize("problem", ["forced", "hardening"])
def test_orders(make, problem):
    check_declared_orders(make(), problem)


def test_incremental_format_is_first_order_on_a_nonlinear_model():
    # Its asymptotic regime starts late: the steps are 2^-5 of the others.
    check_declared_orders(nvib.Newmark(iteration="incremental"), "hardening", refine=5)
