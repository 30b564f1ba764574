"""A Python callable as an effect: a scalar law on a measure, mixed with built-in
effects, with its own flags, tangent and error messages."""

from __future__ import annotations

import numpy as np
import pytest

import nvib

from _registry import scheme_variants, with_newton

K0, A = 100.0, 30.0


def hardening_law(d, dd, t):
    return K0 * (1.0 + A * d * d) * d


def hardening_tangent(d, dd, t):
    return K0 * (1.0 + 3.0 * A * d * d), 0.0


def two_mass(effect, extra=()):
    """Two masses, a built-in spring to the ground and `effect` between them."""
    return nvib.Model([1.0, 2.0], dofs=["x1", "x2"], u0=[0.3, -0.4], effects=[
        {"type": "spring", "measure": {"x1": 1.0}, "k": 50.0}, effect, *extra])


BUILTIN = {"type": "hardening_spring", "measure": {"x2": 1.0, "x1": -1.0}, "k0": K0, "a": A}
CALLABLE = {"type": "callable", "measure": {"x2": 1.0, "x1": -1.0}, "law": hardening_law,
            "tangent": hardening_tangent, "uses_velocity": False, "uses_time": False}

SCHEMES = scheme_variants()


@pytest.mark.parametrize("scheme", SCHEMES)
def test_callable_law_matches_the_builtin_effect(scheme):
    # one linear solver for both (a model with a Python law has only a dense tangent): the comparison is
    # of the laws, not of the solvers' round-off
    sch = with_newton(SCHEMES[scheme], linear_solver="dense")  # (explicit schemes as they are)
    ref = nvib.solve(two_mass(BUILTIN), sch, dt=1e-3, t_end=0.5)
    got = nvib.solve(two_mass(CALLABLE), sch, dt=1e-3, t_end=0.5)
    np.testing.assert_allclose(got.u, ref.u, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(got.v, ref.v, rtol=1e-12, atol=1e-13)
    assert got.stats.num_force_evals == ref.stats.num_force_evals


def test_callable_law_without_tangent_uses_finite_differences():
    law = dict(CALLABLE)
    del law["tangent"]
    ref = nvib.solve(two_mass(BUILTIN), nvib.Newmark(), dt=1e-3, t_end=0.5)
    got = nvib.solve(two_mass(law), nvib.Newmark(), dt=1e-3, t_end=0.5)
    np.testing.assert_allclose(got.u, ref.u, rtol=1e-8, atol=1e-10)
    assert got.stats.num_fd_force_evals > 0 and ref.stats.num_fd_force_evals == 0


def test_callable_storey_in_the_building():
    """The building with storey 3 replaced by the same law in Python gives the same trajectory."""
    scene = nvib.load_scene("building")
    spec = [{"type": "hardening_spring", "name": f"storey{i + 1}", "k0": 1e8, "a": 10.0,
             "measure": {f"x{i + 1}": 1.0, **({f"x{i}": -1.0} if i else {})}} for i in range(6)]
    ground = {"type": "ground_acceleration", "signal": {"kind": "sine", "amplitude": 10.0, "omega": np.pi}}
    spec[2] = {"type": "callable", "name": "storey3", "measure": spec[2]["measure"],
               "law": lambda d, dd, t: 1e8 * (1.0 + 10.0 * d * d) * d, "uses_velocity": False, "uses_time": False}
    model = nvib.Model(scene.mass_matrix.diagonal(), dofs=scene.dofs, effects=spec + [ground])
    assert model.python_laws == ["effects[2]"]
    ref = nvib.solve(scene, nvib.CEMDTS(), dt=1e-3, t_end=2.0, save_every=10)
    got = nvib.solve(model, nvib.CEMDTS(), dt=1e-3, t_end=2.0, save_every=10)
    np.testing.assert_allclose(got.u, ref.u, rtol=1e-11, atol=1e-12 * np.abs(ref.u).max())


def test_declared_flags_reach_the_schemes():
    # velocity-independent: one force evaluation per explicit step, no damping tangent
    model = two_mass(CALLABLE)
    assert not model.uses_velocity and not model.uses_time and not model.is_linear
    res = nvib.solve(model, nvib.CEMDTS(), dt=1e-3, t_end=0.1)
    assert res.stats.num_force_evals == res.stats.num_steps + 1
    # the default declares velocity and time: the law then receives the measure's rate
    seen = []

    def damper(d, dd, t):
        seen.append(dd)
        return 3.0 * dd

    model = two_mass({"type": "callable", "measure": {"x2": 1.0, "x1": -1.0}, "law": damper})
    assert model.uses_velocity and model.uses_time
    nvib.solve(model, nvib.CentralDifference(), dt=1e-3, t_end=0.01, v0=[1.0, 0.0])
    assert seen[0] == -1.0  # d' = v2 - v1 at t = 0


def test_force_callable_and_callable_effect_together():
    model = nvib.Model([1.0, 2.0], dofs=["x1", "x2"], force=lambda u, v, t: np.array([u[0] ** 3, 0.0]),
                       uses_velocity=False, uses_time=False, effects=[CALLABLE])
    u = np.array([0.2, 0.5])
    d = 0.5 - 0.2
    f = hardening_law(d, 0.0, 0.0)
    np.testing.assert_allclose(model.evaluate_force(u, [0.0, 0.0]), [0.2**3 - f, f], rtol=1e-14)


def test_without_removes_a_callable_effect_by_name():
    named = dict(CALLABLE, name="coupling")
    model = nvib.Model([1.0, 2.0], dofs=["x1", "x2"], effects=[named], without=["coupling"])
    assert model.python_laws == [] and model.is_linear
    np.testing.assert_array_equal(model.evaluate_force([0.1, 0.7], [0.0, 0.0]), [0.0, 0.0])


def test_energy_accounting_refuses_a_callable_effect():
    with pytest.raises(ValueError, match="energy"):
        nvib.solve(two_mass(CALLABLE), nvib.CEMDTS(), dt=1e-3, t_end=0.01, energy=True)


class LawError(Exception):
    pass


def raising_law(d, dd, t):
    if t > 0.005:
        raise LawError("law says no")
    return d


@pytest.mark.parametrize("spec, error, match", [
    (dict(CALLABLE, law=3.0), TypeError, r"^effects\[1\]\.law"),
    (dict(CALLABLE, tangent="no"), TypeError, r"^effects\[1\]\.tangent"),
    (dict(CALLABLE, measure={"x9": 1.0}), ValueError, r"^effects\[1\]\.measure"),
    (dict(CALLABLE, measure={}), ValueError, r"^effects\[1\]\.measure"),
    (dict(CALLABLE, k=1.0), ValueError, r"^effects\[1\]\.k\b"),
    (dict(CALLABLE, uses_velocity="yes"), TypeError, r"^effects\[1\]\.uses_velocity"),
    (dict(CALLABLE, name=3), TypeError, r"^effects\[1\]\.name"),
])
def test_bad_callable_effect_names_the_key(spec, error, match):
    with pytest.raises(error, match=match):
        two_mass(spec)


@pytest.mark.parametrize("law, error, match", [
    (lambda d, dd, t: "1.0", TypeError, r"effects\[1\]\.law must return real numbers"),
    (lambda d, dd, t: None, TypeError, r"effects\[1\]\.law returned None"),
    (lambda d, dd, t: [1.0, 2.0], ValueError, r"effects\[1\]\.law returned shape \(2,\)"),
    (lambda d, dd, t: float("nan"), ValueError, r"effects\[1\]\.law returned a non-finite value"),
    (raising_law, LawError, r"law says no"),
])
def test_misbehaving_law_raises_naming_the_effect(law, error, match):
    with pytest.raises(error, match=match):
        nvib.solve(two_mass(dict(CALLABLE, law=law)), nvib.CentralDifference(), dt=1e-3, t_end=0.02)


@pytest.mark.parametrize("tangent, error, match", [
    (lambda d, dd, t: 1.0, TypeError, r"effects\[1\]\.tangent must return a tuple"),
    (lambda d, dd, t: (1.0, 2.0, 3.0), TypeError, r"effects\[1\]\.tangent must return a tuple \(K, C\) of length 2"),
    (lambda d, dd, t: (float("inf"), 0.0), ValueError, r"effects\[1\]\.tangent returned non-finite"),
    (lambda d, dd, t: ("a", 0.0), TypeError, r"effects\[1\]\.tangent \(df/dd\)"),
])
def test_misbehaving_tangent_raises_naming_the_effect(tangent, error, match):
    with pytest.raises(error, match=match):
        nvib.solve(two_mass(dict(CALLABLE, tangent=tangent)), nvib.Newmark(), dt=1e-3, t_end=0.02)
