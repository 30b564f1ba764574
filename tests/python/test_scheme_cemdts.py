"""CEMDTS: second order in u and v for every eta (its velocity is locally third order only at eta = 1/12)."""

from __future__ import annotations

import pytest

import nvib
from _orders import check_declared_orders


# Fitted u/v orders at the problems' own steps: forced 2.010/1.992 to 2.010/2.007, hardening 2.000/1.992 to
# 2.000/2.003 over the four eta.
@pytest.mark.parametrize("eta", [0.0, 1.0 / 12.0, 0.5, 1.0])
@pytest.mark.parametrize("problem", ["forced", "hardening"])
def test_orders_for_every_eta(eta, problem):
    check_declared_orders(nvib.CEMDTS(eta), problem)


def test_eta_range():
    with pytest.raises(nvib.ArgumentError, match=r"^eta: CEMDTS needs 0 <= eta <= 1, got 1\.5") as exc:
        nvib.CEMDTS(1.5)
    assert exc.value.argument == "eta"
