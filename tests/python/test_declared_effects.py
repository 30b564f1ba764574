"""Only the declared effects are simulated: what a scene leaves out costs
nothing, measured in the run's counters (never asserted by hand)."""

from __future__ import annotations

import numpy as np
import pytest

import nvib

from _registry import scheme_variants

# The central-difference family: one force evaluation per step (PIM, also explicit, makes more).
CD_FAMILY = {"LCDM": nvib.CentralDifference(), "LCDM-half_step": nvib.CentralDifference(velocity="half_step"),
             "CEMDTS": nvib.CEMDTS(), "Zhai": nvib.Zhai()}
IMPLICIT = scheme_variants(explicit=False)
IMPLICIT["Newmark-modified"] = nvib.Newmark(iteration="modified")


def vehicle_toml_without_static_equilibrium(tmp_path, u0):
    """The vehicle scene with its initial displacement given explicitly, so
    that effects holding it up can be left out."""
    path = nvib.load_scene("vehicle").scene["path"]
    with open(path) as fh:
        text = fh.read()
    assert 'u = "static_equilibrium"' in text
    text = text.replace('u = "static_equilibrium"', "u = [" + ", ".join(repr(float(x)) for x in u0) + "]")
    out = tmp_path / "vehicle_given_u.toml"
    out.write_text(text)
    return str(out)


# ---------------------------------------------------------------------------
# flags of the built-in scenes


def test_scene_flags():
    b = nvib.load_scene("building")
    assert b.uses_time and not b.uses_velocity and not b.is_linear
    for name in ("hardening", "pendulum", "pendulum_ic2"):
        m = nvib.load_scene(name)
        assert not m.uses_time and not m.uses_velocity and not m.is_linear, name
    v = nvib.load_scene("vehicle")
    assert v.uses_velocity and not v.uses_time and not v.is_linear
    # flags follow what is left out
    assert not nvib.load_scene("building", without=["ground"]).uses_time
    assert not nvib.load_scene("vehicle", without=["primary_damping", "secondary_damping"]).uses_velocity
    assert not nvib.load_scene("vehicle", without=["damper"]).uses_velocity
    assert nvib.load_scene("vehicle", without=["contact", "gravity"]).is_linear


def test_no_velocity_dependent_effect_no_damping_tangent():
    for name in ("building", "hardening", "pendulum"):
        m = nvib.load_scene(name)
        rng = np.random.default_rng(0)
        _, C = m.tangent_matrices(rng.normal(0, 0.01, m.n), rng.normal(size=m.n), 0.3)
        assert np.all(C == 0.0)


# ---------------------------------------------------------------------------
# what is evaluated each step


def test_num_evaluated_effects_of_the_scenes():
    # springs, dampers and constant loads are assembled once (K, C, a constant vector)
    assert nvib.load_scene("hardening")._core.num_evaluated_effects == 1
    assert nvib.load_scene("building")._core.num_evaluated_effects == 7  # six storeys + the ground
    assert nvib.load_scene("building", without=["ground"])._core.num_evaluated_effects == 6
    v = nvib.load_scene("vehicle")
    assert v._core.num_evaluated_effects == 4  # the four contacts; 7 loads, 8 springs, 8 dampers assembled
    vl = nvib.load_scene("vehicle", without=["contact", "gravity"])
    assert vl._core.num_evaluated_effects == 0 and vl.is_linear


@pytest.mark.parametrize("params, evaluated", [
    ({"type": "spring", "k": 1.0}, 0),
    ({"type": "damper", "c": 1.0}, 0),
    ({"type": "constant_force", "value": 1.0}, 0),
    ({"type": "hardening_spring", "k0": 1.0, "a": 1.0}, 1),
    ({"type": "cubic_spring", "k3": 1.0}, 1),
    ({"type": "power_damper", "c": 1.0, "p": 2.0}, 1),
    ({"type": "pendulum_gravity", "m": 1.0, "g": 9.8, "l": 1.0}, 1),
    ({"type": "hertz_contact", "G": 1e-3}, 1),
    ({"type": "harmonic_force", "amplitude": 1.0, "omega": 1.0}, 1),
    ({"type": "ground_acceleration", "signal": {"kind": "sine", "amplitude": 1.0, "omega": 1.0}}, 1),
], ids=lambda x: x["type"] if isinstance(x, dict) else str(x))
def test_num_evaluated_effects_per_type(params, evaluated):
    m = nvib.Model([1.0, 1.0], effects=[dict(params, measure={"u0": 1.0, "u1": -1.0})])
    assert m._core.num_evaluated_effects == evaluated


def test_vehicle_without_contact_has_no_static_equilibrium():
    # with the contacts left out nothing holds the vehicle up against gravity: the model
    # has no static equilibrium, so the scene starts from the full scene's and says so
    model = nvib.load_scene("vehicle", without=["contact"])
    with pytest.raises(nvib.ArgumentError, match="static_equilibrium did not converge") as info:
        model.static_equilibrium()
    assert info.value.argument == "initial"
    np.testing.assert_array_equal(model.u0, nvib.load_scene("vehicle").u0)
    assert model.scene["initial_u"] == "static equilibrium of the full scene"
    assert any("static equilibrium" in note for note in model.scene["notes"])


def test_vehicle_without_contact_is_linear(tmp_path):
    full = nvib.load_scene("vehicle")
    path = vehicle_toml_without_static_equilibrium(tmp_path, full.u0)
    same = nvib.load_scene(path)
    np.testing.assert_array_equal(same.u0, full.u0)
    assert same._core.num_evaluated_effects == full._core.num_evaluated_effects == 4
    lin = nvib.load_scene(path, without=["contact"])
    assert lin.is_linear and not full.is_linear
    assert lin._core.num_evaluated_effects == 0 < full._core.num_evaluated_effects
    assert lin.uses_velocity and not lin.uses_time


# ---------------------------------------------------------------------------
# counts


@pytest.mark.parametrize("scheme", list(CD_FAMILY.values()), ids=list(CD_FAMILY))
@pytest.mark.parametrize("name", ["hardening", "pendulum", "pendulum_ic2", "building"])
def test_one_force_evaluation_per_explicit_step(name, scheme):
    m = nvib.load_scene(name)
    assert not m.uses_velocity
    res = nvib.solve(m, scheme, dt=m.scene["dt"], t_end=min(m.scene["t_end"], 2.0))
    s = res.stats
    assert s.num_steps == res.num_steps_requested > 0
    assert s.num_force_evals == s.num_steps + 1  # one per step plus a0
    assert s.num_tangent_evals == s.num_factorizations == s.num_newton_iters == s.num_linear_solves == 0


def linear_model():
    eff = [
        {"type": "spring", "measure": {"x": 1.0}, "k": 400.0},
        {"type": "spring", "measure": {"y": 1.0, "x": -1.0}, "k": 150.0},
        {"type": "spring", "measure": {"z": 1.0, "y": -1.0, "x": 0.5}, "k": 90.0},
        {"type": "damper", "measure": {"y": 1.0, "x": -1.0}, "c": 0.7},
        {"type": "damper", "measure": {"z": 1.0}, "c": 0.2},
        {"type": "constant_force", "measure": {"z": 1.0}, "value": 9.81},
        {"type": "harmonic_force", "measure": {"x": 1.0}, "amplitude": 2.0, "omega": 3.0},
        {"type": "ground_acceleration", "signal": {"kind": "table", "t": [0.0, 0.5, 1.0], "values": [0, 1.0, 0]}},
    ]
    return nvib.Model([1.0, 2.0, 0.5], effects=eff, dofs=["x", "y", "z"], u0=[0.01, 0.0, -0.02], v0=[0, 0.1, 0])


@pytest.mark.parametrize("scheme", list(IMPLICIT.values()), ids=list(IMPLICIT))
def test_all_linear_model_factorises_once(scheme):
    m = linear_model()
    assert m.is_linear and m.uses_velocity and m.uses_time
    res = nvib.solve(m, scheme, dt=1e-3, t_end=1.0)
    s = res.stats
    assert s.num_steps == 1000
    assert s.num_factorizations == 1
    assert s.num_newton_iters == s.num_steps  # Newton converges in one iteration
    assert s.num_force_evals == s.num_steps + 1


@pytest.mark.parametrize("scheme", [cls() for cls in nvib.schemes().values() if not cls.is_explicit],
                         ids=lambda s: type(s).__name__)
def test_linear_vehicle_factorises_once(scheme):
    veh = nvib.load_scene("vehicle")
    lin = nvib.load_scene("vehicle", without=["contact", "gravity"])
    res = nvib.solve(lin, scheme, dt=1e-4, t_end=0.1, v0=veh.v0)
    s = res.stats
    assert s.num_factorizations == 1 and s.num_newton_iters == s.num_steps == 1000
    assert s.num_force_evals == s.num_steps + 1


@pytest.mark.parametrize("scheme", [cls() for cls in nvib.schemes().values() if not cls.is_explicit],
                         ids=lambda s: type(s).__name__)
def test_removing_the_nonlinear_effect_removes_its_cost(tmp_path, scheme):
    full = nvib.load_scene("vehicle")
    lin = nvib.load_scene(vehicle_toml_without_static_equilibrium(tmp_path, full.u0), without=["contact"])
    kw = dict(dt=1e-4, t_end=0.1)
    a = nvib.solve(full, scheme, **kw).stats
    b = nvib.solve(lin, scheme, **kw).stats
    assert a.num_steps == b.num_steps == 1000
    # the contacts need Newton iterations and new tangents; without them one solve per step
    assert a.num_newton_iters > a.num_steps  # a nonlinear step takes two or more (measured: 1.33 per step)
    assert a.num_factorizations + a.num_reused_factorizations == a.num_newton_iters
    # while a wheel is off the rail its contact's tangent is zero: the iteration matrix repeats and keeps its
    # factors (measured: 546 factorisations for 1332 iterations)
    assert 0 < a.num_reused_factorizations and a.num_factorizations > a.num_steps / 2
    assert b.num_newton_iters == b.num_steps and b.num_factorizations == 1
    assert b.num_force_evals == b.num_steps + 1 < a.num_force_evals


def test_explicit_counts_do_not_depend_on_what_is_declared():
    # an explicit step costs one force evaluation however many effects there are
    full = nvib.load_scene("vehicle")
    few = nvib.load_scene("vehicle", without=["contact", "gravity", "damper"])
    for m in (full, few):
        s = nvib.solve(m, nvib.CEMDTS(), dt=1e-4, t_end=0.1, v0=full.v0).stats
        assert s.num_force_evals == s.num_steps + 1 == 1001
