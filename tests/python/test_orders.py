"""Every scheme of the registry, with its defaults, has the global orders it
declares: the fitted orders of displacement and velocity equal order_u and
order_v (+-0.1) on the forced damped linear oscillator and on the hardening
oscillator, both against closed forms. Variants are in test_scheme_<key>.py."""

from __future__ import annotations

import pytest

import nvib

from _orders import check_declared_orders


# Fitted u/v orders at the problems' own steps (forced; hardening): lcdm 2.010/2.007; 2.000/2.003,
# cemdts and zhai 2.010/1.992; 2.000/1.992, newmark 2.000/2.000; 2.000/2.004, galpha 2.000/2.000;
# 2.000/2.004, pim (declared 3) 3.002/3.003; 2.997/3.004.
@pytest.mark.parametrize("problem", ["forced", "hardening"])
def test_declared_orders(scheme_class, problem):
    check_declared_orders(scheme_class(), problem)


class _DeclaresSecondOrder(nvib.Zhai):
    """Zhai(0.6, 0.6) is first order; this one claims second order for both u and v."""
    order_u = property(lambda self: 2)
    order_v = property(lambda self: 2)


@pytest.mark.parametrize("problem", ["forced", "hardening", "free-matrix"])
def test_a_wrongly_declared_order_fails(problem):
    with pytest.raises(AssertionError, match="order"):
        check_declared_orders(_DeclaresSecondOrder(0.6, 0.6), problem)
