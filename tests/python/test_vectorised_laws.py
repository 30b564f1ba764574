"""Vectorised Python laws: one Python call per evaluation for all the effects of an array (d, d', t and the
states as arrays). They follow the built-in laws they write out to round-off (the sums of the forces are
taken in another order) under the six schemes, with and without memory; a failed Newton step leaves their
states as they were; what they return is checked, naming the effect; they travel to processes."""

from __future__ import annotations

import numpy as np
import pytest

import nvib

from _hysteresis import step_until_it_fails

SIX = [nvib.CentralDifference(), nvib.CEMDTS(), nvib.Zhai(), nvib.Newmark(), nvib.GeneralizedAlpha(),
       nvib.PreciseIntegration()]
SIX_IDS = ["lcdm", "cemdts", "zhai", "newmark", "galpha", "pim"]


def hardening_chain(n: int, vectorised: bool) -> nvib.Model:
    """nvib.scenes.chain(n) (hardening storeys, dampers, a ground motion), its storeys as the built-in array
    or as one vectorised Python law doing the same arithmetic."""
    base = nvib.scenes.chain(n)
    mass, kw = base._init
    effects = []
    for e in kw["effects"]:
        if e["type"] == "hardening_spring" and vectorised:
            k0, a = e["k0"], e["a"]
            effects.append({"type": "callable", "name": "storeys", "i": e["i"], "j": e["j"], "uses_velocity": False,
                            "uses_time": False, "law": lambda d, dd, t: k0 * (1.0 + a * d * d) * d,
                            "tangent": lambda d, dd, t: (k0 * (1.0 + 3.0 * a * d * d), None)})
        else:
            effects.append(e)
    model = nvib.Model(mass, **{**kw, "effects": effects})
    model.u0, model.v0 = base.u0, base.v0
    return model


def close(a, b, tol=1e-12):
    assert np.max(np.abs(a.u - b.u)) <= tol * np.max(np.abs(a.u)), np.max(np.abs(a.u - b.u)) / np.max(np.abs(a.u))


@pytest.mark.parametrize("sch", SIX, ids=SIX_IDS)
def test_a_vectorised_hardening_array_follows_the_built_in_one(sch):
    built_in, vectorised = hardening_chain(8, False), hardening_chain(8, True)
    assert vectorised.python_laws == ["effects[0]"]
    dt = 2e-4 if sch.is_explicit else 1e-3
    close(nvib.solve(built_in, sch, dt=dt, t_end=0.4), nvib.solve(vectorised, sch, dt=dt, t_end=0.4))


K, FY, B = 300.0, 3.0, 0.05


def bilinear(d, dd, t, state):
    """Bilinear's return mapping for every effect at once; state columns (dp, dissipated, d)."""
    H = B * K / (1.0 - B)
    kt = K * H / (K + H)
    dp, dis = state[:, 0], state[:, 1]
    f = K * (d - dp)
    xi = f - H * dp
    excess = np.abs(xi) - FY
    slip = np.where(excess > 0.0, excess / (K + H), 0.0)
    s = np.sign(xi)
    return f - K * slip * s, np.column_stack([dp + s * slip, dis + FY * slip, d])


def bilinear_slopes(d, dd, t, state):
    H = B * K / (1.0 - B)
    kt = K * H / (K + H)
    dp = state[:, 0]
    xi = K * (d - dp) - H * dp
    at_surface = (d == state[:, 2]) & (np.abs(xi) - FY >= -1e-9 * FY)
    return np.where((np.abs(xi) > FY) | at_surface, kt, K), None


def two_bilinear_storeys(vectorised: bool) -> nvib.Model:
    spec = {"i": [0, 1], "j": [-1, 0]}
    law = ({"type": "callable", **spec, "law": bilinear, "tangent": bilinear_slopes, "state": [0.0, 0.0, 0.0],
            "uses_velocity": False, "uses_time": False} if vectorised else
           {"type": "bilinear", **spec, "k": K, "fy": FY, "b": B})
    return nvib.Model([1.0, 1.0], effects=[
        law, {"type": "damper", "i": [0, 1], "j": [-1, 0], "c": 0.5},
        {"type": "ground_acceleration", "signal": {"kind": "sine", "amplitude": 6.0, "omega": 7.0}}])


@pytest.mark.parametrize("sch", SIX, ids=SIX_IDS)
def test_a_vectorised_law_with_memory_follows_the_built_in_one(sch):
    a = nvib.solve(two_bilinear_storeys(False), sch, dt=2e-3, t_end=1.5)
    b = nvib.solve(two_bilinear_storeys(True), sch, dt=2e-3, t_end=1.5)
    close(a, b)  # measured 6e-17 (LCDM) to 7.4e-15 (generalized-alpha) of the peak
    assert np.max(np.abs(a.u)) > 3 * FY / K  # it yields


def test_a_failed_newton_step_leaves_the_states_as_they_were():
    model = two_bilinear_storeys(True)
    st = nvib.Stepper(model, nvib.Newmark(newton=nvib.Newton(max_iter=1)), 2e-2)
    before, t, _ = step_until_it_fails(st)
    assert st.t == t
    np.testing.assert_array_equal(st.state(), before)


@pytest.mark.parametrize("law, error, match", [
    (lambda d, dd, t: d[:1], ValueError, r"effects\[0\]\.law returned shape \(1,\)"),
    (lambda d, dd, t: None, TypeError, r"effects\[0\]\.law returned None"),
    (lambda d, dd, t: d * np.nan, ValueError, r"effects\[0\]\.law \(effect 0\) returned a non-finite value"),
])
def test_what_a_vectorised_law_returns_is_checked(law, error, match):
    model = nvib.Model([1.0, 1.0], u0=[0.1, 0.2], effects=[{"type": "callable", "i": [0, 1], "law": law}])
    with pytest.raises(error, match=match):
        nvib.solve(model, nvib.CentralDifference(), dt=1e-2, t_end=0.1)


def test_states_of_the_wrong_shape_are_refused_naming_the_effect():
    with pytest.raises(nvib.ArgumentError) as exc:
        nvib.Model([1.0, 1.0], effects=[{"type": "callable", "i": [0, 1], "law": bilinear, "state": [[0.0], [0.0],
                                                                                                    [0.0]]}])
    assert exc.value.argument == "effects[0].state"
    model = nvib.Model([1.0, 1.0], u0=[0.1, 0.2], effects=[
        {"type": "callable", "i": [0, 1], "law": lambda d, dd, t, s: (d, s[:, :1]), "state": [0.0, 0.0]}])
    with pytest.raises(ValueError, match=r"effects\[0\]\.law returned states of shape \(2, 1\), expected \(2, 2\)"):
        nvib.solve(model, nvib.CentralDifference(), dt=1e-2, t_end=0.1)


def test_a_vectorised_lambda_law_runs_in_processes_as_serially():
    model = hardening_chain(4, True)
    run = dict(dt=1e-3, t_end=0.2, progress=False, scales=[0.5, 1.0])
    serial = nvib.solve_many(model, nvib.CEMDTS(), threads=1, **run)
    for a, b in zip(serial, nvib.solve_many(model, nvib.CEMDTS(), threads=2, **run)):
        np.testing.assert_array_equal(a.u, b.u)
