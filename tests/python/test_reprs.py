"""Informative reprs: Model (size, DOFs, mass, linear parts, effects by type, callables, flags), Stepper,
Energy and GroundMotion, each one line and short whatever the model's size."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

import nvib


def test_model_repr_lists_size_dofs_mass_effects_by_type_and_flags():
    r = repr(nvib.load_scene("vehicle"))
    assert r.startswith("Model('vehicle', 10 DOFs [z_c, beta_c, z_t1, beta_t1, ..., z_w4]; mass diagonal; units m/rad")
    assert "effects: constant_force x7, spring x6, damper x6, hertz_contact x4" in r
    assert "K with 34 nonzeros" in r and r.endswith("; uses_velocity)")
    r = repr(nvib.load_scene("building"))
    assert "effects: hardening_spring x6, ground_acceleration; uses_time)" in r and "units m;" in r


def test_model_repr_of_python_callables_and_linear_models():
    r = repr(nvib.Model([1.0, 2.0], force=lambda u, v, t: u, uses_time=False, units=["m", "rad"]))
    assert r == "Model(2 DOFs [u0, u1]; mass diagonal; units m/rad; force callable; uses_velocity)"
    law = {"type": "callable", "measure": {"x": 1.0}, "law": lambda d, dd, t: d, "uses_velocity": False,
           "uses_time": False}
    r = repr(nvib.Model([1.0], dofs=["x"], effects=[law], name="one"))
    assert r == "Model('one', 1 DOF [x]; mass diagonal; units m; 1 Python law)"
    K = sp.diags([2.0, 2.0, 2.0])
    consistent = sp.diags([[1.0, 1.0], [4.0, 4.0, 4.0], [1.0, 1.0]], [-1, 0, 1], format="csc") / 6.0
    r = repr(nvib.Model(consistent, K=K, uses_velocity=False, uses_time=False))
    assert r == "Model(3 DOFs [u0, u1, u2]; mass sparse; units m; K with 3 nonzeros; linear)"


def test_model_repr_stays_short_for_a_large_model_and_counts_effect_arrays():
    r = repr(nvib.scenes.chain(100_000))
    assert len(r) < 300 and "100000 DOFs [x1, x2, x3, x4, ..., x100000]" in r
    assert "hardening_spring x100000" in r and "damper x100000" in r


def test_stepper_repr_shows_scheme_step_and_time():
    st = nvib.Stepper(nvib.load_scene("hardening"), nvib.Newmark(), 1e-3)
    st.step(7)
    assert repr(st) == (f"Stepper({nvib.Newmark()!r}, dt=0.001 s, t=0.007 s, step 7; model 'hardening', 1 DOF)")


def test_energy_repr_shows_the_end_state_and_the_balance_error():
    res = nvib.solve(nvib.load_scene("hardening"), nvib.CentralDifference(), dt=1e-3, t_end=0.3, energy=True)
    e = res.energy
    r = repr(e)
    assert r.startswith("Energy(301 states; at the end: kinetic ")
    assert f"potential {e.potential[-1]:.6g}" in r and "work in 0, dissipated 0" in r
    assert r.endswith(f"relative balance error {e.relative_balance_error():.3g})")


def test_ground_motion_repr_shows_its_size_and_peak():
    g = nvib.GroundMotion(0.01 * np.arange(4), np.array([0.0, 1.0, -2.0, 0.5]), name="test", units="m/s^2")
    assert repr(g) == "GroundMotion('test', 4 samples, dt=0.01 s, duration=0.03 s, pga=2 m/s^2)"
