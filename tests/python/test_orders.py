"""Every scheme of the registry, with its defaults, has the global orders it
declares: the fitted orders of displacement and velocity equal order_u and
order_v (+-0.1) on the forced damped linear oscillator and on the hardening
oscillator, both against closed forms. Variants are in test_scheme_<key>.py."""

from __future__ import annotations

import pytest

from _orders import check_declared_orders


@pytest.mark.parametrize("problem", ["forced", "hardening"])
def test_declared_orders(scheme_class, problem):
    check_declared_orders(scheme_class(), problem)
