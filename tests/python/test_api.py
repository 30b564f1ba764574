"""Public API: argument validation (every error names its argument), saving,
DOF selection, failure reporting, dense mass and step-by-step integration."""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys

import numpy as np
import pytest

import nvib

from _registry import is_implicit, scheme_variants


def linear_model():
    return nvib.Model([1.0], K=[[100.0]], u0=[1.0], dofs=["x"])


def hardening_model():
    return nvib.Model([1.0], effects=[{"type": "hardening_spring", "measure": {"x": 1.0}, "k0": 100.0, "a": 30.0}],
                      dofs=["x"], u0=[1.5])


def chain_effects(damped=True):
    eff = [{"type": "spring", "measure": {"a": 1.0}, "k": 300.0},
           {"type": "hardening_spring", "measure": {"b": 1.0, "a": -1.0}, "k0": 120.0, "a": 15.0},
           {"type": "cubic_spring", "measure": {"c": 1.0, "b": -1.0}, "k3": 500.0},
           {"type": "spring", "measure": {"c": 1.0, "b": -1.0}, "k": 60.0},
           {"type": "pendulum_gravity", "measure": {"c": 1.0}, "m": 1.0, "g": 9.81, "l": 0.5},
           {"type": "constant_force", "measure": {"a": 1.0}, "value": 2.0},
           {"type": "harmonic_force", "measure": {"c": 1.0}, "amplitude": 10.0, "omega": 6.0}]
    if damped:
        eff.append({"type": "damper", "measure": {"b": 1.0, "a": -1.0}, "c": 0.9})
    return eff


MASSES = [1.0, 2.0, 1.5]
U0, V0 = [0.1, -0.2, 0.3], [0.0, 0.5, -0.4]


def chain_model(mass=None, damped=True):
    return nvib.Model(MASSES if mass is None else mass, effects=chain_effects(damped), dofs=["a", "b", "c"],
                      u0=U0, v0=V0)


ALL_SCHEMES = scheme_variants()
# omega = 100 rad/s at dt = 0.03 s: Omega = 3, beyond the stability limit of these
CONDITIONALLY_STABLE = [name for name, s in ALL_SCHEMES.items() if nvib.stability.critical_omega_h(s) < 3.0]


# --------------------------------------------------------------------------- solve() arguments
@pytest.mark.parametrize("kwargs, name", [
    (dict(dt=0.0), "dt"),
    (dict(dt=-1e-3), "dt"),
    (dict(dt=float("nan")), "dt"),
    (dict(dt=float("inf")), "dt"),
    (dict(t_end=0.0), "t_end"),
    (dict(t_end=-1.0), "t_end"),
    (dict(t0=2.0, t_end=1.0), "t_end"),
    (dict(t_end=float("nan")), "t_end"),
    (dict(t0=float("nan")), "t0"),
    (dict(save_every=0), "save_every"),
    (dict(save_every=-3), "save_every"),
    (dict(u0=[1.0, 2.0]), "u0"),
    (dict(u0=[[1.0]]), "u0"),
    (dict(u0=[float("nan")]), "u0"),
    (dict(v0=[float("inf")]), "v0"),
    (dict(v0=[1.0, 2.0]), "v0"),
    (dict(dofs=["nope"]), "dofs"),
    (dict(dofs=[3]), "dofs"),
    (dict(max_displacement=-1.0), "max_displacement"),
])
def test_solve_validation_names_the_argument(kwargs, name):
    args = dict(dt=1e-3, t_end=0.1)
    args.update(kwargs)
    with pytest.raises(ValueError, match=rf"^{name}\b"):
        nvib.solve(linear_model(), nvib.CentralDifference(), **args)


@pytest.mark.parametrize("kwargs, name", [
    (dict(dt="0.1"), "dt"),
    (dict(save_every=1.5), "save_every"),
    (dict(u0="abc"), "u0"),
])
def test_solve_type_errors_name_the_argument(kwargs, name):
    args = dict(dt=1e-3, t_end=0.1)
    args.update(kwargs)
    with pytest.raises((TypeError, ValueError), match=rf"^{name}\b"):
        nvib.solve(linear_model(), nvib.CentralDifference(), **args)


def test_solve_rejects_wrong_model_and_scheme_types():
    with pytest.raises(TypeError, match=r"^scheme\b"):
        nvib.solve(linear_model(), "CentralDifference", dt=1e-3, t_end=0.1)
    with pytest.raises(TypeError, match=r"^model\b"):
        nvib.solve(object(), nvib.CentralDifference(), dt=1e-3, t_end=0.1)


def test_stepper_validation():
    with pytest.raises(ValueError, match=r"^dt\b"):
        nvib.Stepper(linear_model(), nvib.Newmark(), 0.0)
    with pytest.raises(ValueError, match=r"^u0\b"):
        nvib.Stepper(linear_model(), nvib.Newmark(), 1e-3, u0=[1.0, 2.0])
    st = nvib.Stepper(linear_model(), nvib.Newmark(), 1e-3)
    with pytest.raises(ValueError, match=r"^n\b"):
        st.step(0)


# --------------------------------------------------------------------------- Model arguments
@pytest.mark.parametrize("mass", [
    [-1.0], [1.0, 0.0], [1.0, float("nan")], [[1.0, 2.0], [0.0, 1.0]], [[1.0, 2.0], [2.0, 1.0]],
    [[1.0, 0.0], [0.0, -1.0]], np.zeros((2, 3)), np.ones((2, 2, 2)), [],
], ids=["negative", "zero", "nan", "non-symmetric", "indefinite", "negative-diagonal", "non-square", "3-D",
        "empty"])
def test_bad_mass_names_mass(mass):
    with pytest.raises(ValueError, match=r"^mass\b"):
        nvib.Model(mass, K=None)


def test_model_argument_errors():
    with pytest.raises(ValueError, match=r"^K\b"):
        nvib.Model([1.0, 1.0], K=np.eye(3))
    with pytest.raises(ValueError, match=r"^C\b"):
        nvib.Model([1.0], C=[[float("nan")]])
    with pytest.raises(ValueError, match=r"^u0\b"):
        nvib.Model([1.0], u0=[float("nan")])
    with pytest.raises(ValueError, match=r"^v0\b"):
        nvib.Model([1.0], v0=[1.0, 2.0])
    with pytest.raises(ValueError, match=r"^dofs\b"):
        nvib.Model([1.0, 1.0], dofs=["a"])
    with pytest.raises(ValueError, match=r"^dofs\b"):
        nvib.Model([1.0, 1.0], dofs=["a", "a"])
    with pytest.raises(TypeError, match=r"^force\b"):
        nvib.Model([1.0], force=3.0)
    with pytest.raises(ValueError, match=r"^tangent\b"):
        nvib.Model([1.0], tangent=lambda u, v, t: (None, None))


def test_force_and_effects_act_together():
    """A force callable given with effects adds to them (it used to be refused)."""
    spring = {"type": "spring", "measure": {"u0": 1.0}, "k": 4.0}
    model = nvib.Model([1.0], force=lambda u, v, t: 3.0 * u**3, effects=[spring], uses_velocity=False)
    np.testing.assert_allclose(model.evaluate_force([0.5], [0.0], 0.0), [4.0 * 0.5 + 3.0 * 0.125], rtol=1e-15)
    assert not model.uses_velocity and not model.is_linear


@pytest.mark.parametrize("effect, name", [
    ({"type": "foo", "measure": {"x": 1.0}}, r"effects\[0\]\.type"),
    ({"measure": {"x": 1.0}, "k": 1.0}, r"effects\[0\]\.type"),
    ({"type": "spring", "measure": {"y": 1.0}, "k": 1.0}, r"effects\[0\]\.measure"),
    ({"type": "spring", "measure": {5: 1.0}, "k": 1.0}, r"effects\[0\]\.measure"),
    ({"type": "spring", "measure": {}, "k": 1.0}, r"effects\[0\]\.measure"),
    ({"type": "spring", "k": 1.0}, r"effects\[0\]\.measure"),
    ({"type": "spring", "measure": {"x": 1.0}}, r"effects\[0\]\.k\b"),
    ({"type": "hardening_spring", "measure": {"x": 1.0}, "k0": 1.0}, r"effects\[0\]\.a\b"),
    ({"type": "harmonic_force", "measure": {"x": 1.0}, "amplitude": 1.0}, r"effects\[0\]\.omega\b"),
    ({"type": "pendulum_gravity", "measure": {"x": 1.0}, "m": 1.0, "g": 9.81}, r"effects\[0\]\.l\b"),
    ({"type": "spring", "measure": {"x": 1.0}, "k": 1.0, "c": 2.0}, r"effects\[0\]\.c\b"),
    ({"type": "spring", "measure": {"x": 1.0}, "k": float("nan")}, r"effects\[0\]\.k\b"),
    ({"type": "spring", "measure": {"x": float("inf")}, "k": 1.0}, r"effects\[0\]\.measure"),
])
def test_effect_errors_name_the_effect_and_field(effect, name):
    with pytest.raises(ValueError, match=rf"^{name}"):
        nvib.Model([1.0], effects=[effect], dofs=["x"])


def test_effect_error_names_the_right_index():
    good = {"type": "spring", "measure": {"x": 1.0}, "k": 1.0}
    with pytest.raises(ValueError, match=r"^effects\[2\]\.type"):
        nvib.Model([1.0], effects=[good, good, {"type": "bar", "measure": {"x": 1.0}}], dofs=["x"])
    with pytest.raises(TypeError, match=r"^effects\[1\]"):
        nvib.Model([1.0], effects=[good, "spring"], dofs=["x"])


# --------------------------------------------------------------------------- scheme parameters
@pytest.mark.parametrize("make, name", [
    (lambda: nvib.CEMDTS(eta=-1.0), "eta"),
    (lambda: nvib.CEMDTS(eta=1.5), "eta"),
    (lambda: nvib.CEMDTS(eta=float("nan")), "eta"),
    (lambda: nvib.Zhai(psi=-0.1), "psi"),
    (lambda: nvib.Zhai(phi=1.5), "phi"),
    (lambda: nvib.CentralDifference(velocity="leapfrog"), "velocity"),
    (lambda: nvib.Newmark(beta=0.0), "beta"),
    (lambda: nvib.Newmark(beta=-0.25), "beta"),
    (lambda: nvib.Newmark(gamma=0.4), "gamma"),
    (lambda: nvib.Newmark(iteration="foo"), "iteration"),
    (lambda: nvib.Newton(jacobian="complex_step"), "jacobian"),
    (lambda: nvib.Newton(max_iter=0), "max_iter"),
    (lambda: nvib.Newton(rtol=-1.0), "rtol"),
    (lambda: nvib.Newton(atol=float("nan")), "atol"),
    (lambda: nvib.Newton(rtol=0.0, atol=0.0), "rtol"),
    (lambda: nvib.Newton(iteration="none"), "iteration"),
    (lambda: nvib.GeneralizedAlpha(alpha_f=0.6), "alpha_f"),
    (lambda: nvib.GeneralizedAlpha(alpha_m=0.0, alpha_f=0.0, beta=0.0), "beta"),
    (lambda: nvib.GeneralizedAlpha(alpha_m=0.0, alpha_f=0.0, gamma=0.4), "gamma"),
    (lambda: nvib.GeneralizedAlpha(alpha_m=0.5, alpha_f=0.4), "alpha_m"),
    (lambda: nvib.GeneralizedAlpha(alpha_m=0.0, alpha_f=0.4, beta=0.25), "beta"),
    (lambda: nvib.GeneralizedAlpha(iteration="foo"), "iteration"),
    (lambda: nvib.GeneralizedAlpha.from_rho_inf(2.0), "rho_inf"),
    (lambda: nvib.GeneralizedAlpha.from_rho_inf(-0.1), "rho_inf"),
    (lambda: nvib.GeneralizedAlpha.from_rho_inf(0.5, iteration="foo"), "iteration"),
    (lambda: nvib.GeneralizedAlpha.hht(0.1), "alpha"),
    (lambda: nvib.GeneralizedAlpha.hht(-0.5), "alpha"),
    (lambda: nvib.GeneralizedAlpha.wbz(0.1), "alpha"),
    (lambda: nvib.GeneralizedAlpha.wbz(-1.5), "alpha"),
    (lambda: nvib.PreciseIntegration(interpolation=5), "interpolation"),
    (lambda: nvib.PreciseIntegration(interpolation=0), "interpolation"),
    (lambda: nvib.PreciseIntegration(squarings=0), "squarings"),
    (lambda: nvib.PreciseIntegration(corrections=-1), "corrections"),
])
def test_bad_scheme_parameters(make, name):
    with pytest.raises(ValueError, match=rf"^{name}\b"):
        make()


@pytest.mark.parametrize("make, name", [
    (lambda: nvib.Newmark(newton="newton"), "newton"),
    (lambda: nvib.Newmark(iteration=1), "iteration"),
    (lambda: nvib.Newmark(iteration="newton", newton=nvib.Newton()), "iteration"),
    (lambda: nvib.Newmark(max_iter=5), "max_iter"),
    (lambda: nvib.Newton(max_iter=2.5), "max_iter"),
])
def test_scheme_parameters_of_the_wrong_type(make, name):
    with pytest.raises(TypeError, match=rf"^{name}\b"):
        make()


def test_scheme_parameter_round_trip():
    ga = nvib.GeneralizedAlpha.from_rho_inf(0.8)
    assert ga.alpha_m == pytest.approx(1.0 / 3.0) and ga.alpha_f == pytest.approx(4.0 / 9.0)
    assert ga.gamma == pytest.approx(0.5 - 1.0 / 3.0 + 4.0 / 9.0)
    assert ga.beta == pytest.approx(0.25 * (1.0 - 1.0 / 3.0 + 4.0 / 9.0) ** 2)
    one = nvib.GeneralizedAlpha.from_rho_inf(1.0)
    paper = nvib.GeneralizedAlpha()
    assert (one.alpha_m, one.alpha_f, one.beta, one.gamma) == pytest.approx(
        (paper.alpha_m, paper.alpha_f, paper.beta, paper.gamma))
    hht = nvib.GeneralizedAlpha.hht(-0.1)
    assert (hht.alpha_m, hht.alpha_f, hht.beta, hht.gamma) == pytest.approx((0.0, 0.1, 0.3025, 0.6))
    wbz = nvib.GeneralizedAlpha.wbz(-0.1)
    assert (wbz.alpha_m, wbz.alpha_f, wbz.beta, wbz.gamma) == pytest.approx((-0.1, 0.0, 0.3025, 0.6))
    nw = nvib.Newton(iteration="modified", max_iter=7, rtol=1e-8, atol=1e-9, jacobian="finite_difference")
    nm = nvib.Newmark(0.3, 0.6, newton=nw)
    assert (nm.beta, nm.gamma, nm.iteration, nm.newton.max_iter, nm.newton.rtol, nm.newton.atol,
            nm.newton.jacobian) == (0.3, 0.6, "modified", 7, 1e-8, 1e-9, "finite_difference")
    assert nm.newton == nw and nvib.Newmark(0.3, 0.6, iteration="modified").newton == nvib.Newton(iteration="modified")
    assert nvib.CEMDTS().eta == 0.45 and nvib.Zhai().psi == 0.5 and nvib.Zhai().phi == 0.5
    pim = nvib.PreciseIntegration()
    assert (pim.squarings, pim.interpolation, pim.corrections) == (20, 2, 1)
    assert nvib.CentralDifference().velocity == "synchronized"


def test_schemes_compare_by_value():
    a, b = nvib.GeneralizedAlpha(-0.0, -0.0), nvib.GeneralizedAlpha(0.0, 0.0)
    assert a == b and hash(a) == hash(b) and a != nvib.GeneralizedAlpha(0.0, 0.1, 0.3025, 0.6)
    assert nvib.GeneralizedAlpha.hht(0.0) == nvib.GeneralizedAlpha.wbz(-0.0) == nvib.GeneralizedAlpha(0.0, 0.0)
    for s in (nvib.GeneralizedAlpha.hht(0.0), nvib.GeneralizedAlpha.wbz(-0.0)):
        assert "-0" not in repr(s) and "-0" not in s.label and eval(repr(s), vars(nvib)) == s
    assert nvib.Newmark(newton=nvib.Newton(rtol=1e-8)) != nvib.Newmark()
    assert len({nvib.CEMDTS(0.45), nvib.CEMDTS(), nvib.CEMDTS(0.5)}) == 2


# --------------------------------------------------------------------------- saving
@pytest.mark.parametrize("nsteps, k", [(10, 1), (10, 3), (12, 3), (12, 12), (12, 20), (1, 1), (7, 2)])
def test_save_every_semantics(nsteps, k):
    dt = 0.01
    full = nvib.solve(chain_model(), nvib.CentralDifference(), dt=dt, t_end=nsteps * dt)
    res = nvib.solve(chain_model(), nvib.CentralDifference(), dt=dt, t_end=nsteps * dt, save_every=k)
    idx = list(range(0, nsteps + 1, k))
    if idx[-1] != nsteps:
        idx.append(nsteps)  # the last step is always saved
    assert full.t.shape == (nsteps + 1,)
    assert np.allclose(res.t, np.array(idx) * dt, rtol=0, atol=1e-15)
    for attr in ("u", "v", "a"):
        arr = getattr(res, attr)
        assert arr.shape == (len(idx), 3)
        assert arr.flags["C_CONTIGUOUS"] and arr.dtype == np.float64
        assert np.array_equal(arr, getattr(full, attr)[idx])
    assert res.stats.num_steps == nsteps
    assert np.array_equal(res.u[0], U0) and np.array_equal(res.v[0], V0)


def test_run_ends_at_first_multiple_of_dt_past_t_end():
    res = nvib.solve(linear_model(), nvib.CentralDifference(), dt=0.01, t_end=0.105)
    assert res.stats.num_steps == 11
    assert res.t[-1] == pytest.approx(0.11)
    res = nvib.solve(linear_model(), nvib.CentralDifference(), dt=0.1, t_end=0.3)  # 0.3/0.1 = 2.9999999999999996
    assert res.stats.num_steps == 3


def test_t0_offsets_time():
    res = nvib.solve(linear_model(), nvib.Newmark(), dt=0.01, t0=5.0, t_end=5.1)
    assert res.t[0] == 5.0 and res.t[-1] == pytest.approx(5.1) and len(res.t) == 11
    ref = nvib.solve(linear_model(), nvib.Newmark(), dt=0.01, t_end=0.1)
    assert np.array_equal(res.u, ref.u)  # autonomous model: a time shift changes nothing


def test_initial_state_overrides_the_model_default():
    res = nvib.solve(chain_model(), nvib.Newmark(), dt=0.01, t_end=0.05, u0=[0.0, 0.0, 0.2], v0=[1.0, 0.0, 0.0])
    assert np.array_equal(res.u[0], [0.0, 0.0, 0.2]) and np.array_equal(res.v[0], [1.0, 0.0, 0.0])


@pytest.mark.parametrize("dofs, cols", [
    (["b"], [1]), (["c", "a"], [2, 0]), ([2], [2]), ("a", [0]), (1, [1]), (["a", "b", "c"], [0, 1, 2]),
])
def test_dofs_selects_columns(dofs, cols):
    full = nvib.solve(chain_model(), nvib.Newmark(), dt=0.01, t_end=0.2)
    res = nvib.solve(chain_model(), nvib.Newmark(), dt=0.01, t_end=0.2, dofs=dofs, save_every=4)
    assert res.dofs == [["a", "b", "c"][c] for c in cols]
    idx = list(range(0, 21, 4))
    for attr in ("u", "v", "a"):
        arr = getattr(res, attr)
        assert arr.shape == (len(idx), len(cols)) and arr.flags["C_CONTIGUOUS"]
        assert np.array_equal(arr, getattr(full, attr)[idx][:, cols])


# --------------------------------------------------------------------------- failures
def stiff_model():
    # omega = 100 rad/s; with dt = 0.03, omega dt = 3 > 2: central differences blow up
    return nvib.Model([1.0], K=[[1e4]], u0=[1.0], dofs=["x"])


@pytest.mark.parametrize("bound", ["default", "none"])
@pytest.mark.parametrize("name", CONDITIONALLY_STABLE)
def test_divergence_without_throw_returns_partial_history(name, bound):
    kw = {} if bound == "default" else {"max_displacement": math.inf}
    res = nvib.solve(stiff_model(), ALL_SCHEMES[name], dt=0.03, t_end=100.0, throw=False, **kw)
    assert res.status == nvib.Status.diverged and not res.success
    f = res.failure
    assert f.dof == 0 and 1 < f.step < res.num_steps_requested
    assert f.t == pytest.approx(f.step * 0.03)
    # every step before the failed one is in the history, all finite
    assert res.u.shape == (f.step, 1) and len(res.t) == f.step
    assert np.all(np.isfinite(res.u)) and np.all(np.isfinite(res.v))
    if bound == "default":  # 1e10 x max|u0| with u0 = 1: stops when |u| first exceeds 1e10
        assert "beyond the bound 1e+10" in f.message
        assert 1.0 < np.abs(res.u[-1, 0]) <= 1e10
    else:  # no bound: runs until the state is no longer finite
        assert "not finite" in f.message
        assert np.abs(res.u[-1, 0]) > 1e100
    assert res.stats.num_steps == f.step


def test_default_bound_scales_with_the_initial_state():
    assert nvib.default_max_displacement(np.zeros(2), np.zeros(2), 5.0) == 1e10
    assert nvib.default_max_displacement(np.array([0.0, -3.0]), np.zeros(2), 5.0) == 3e10
    assert nvib.default_max_displacement(np.zeros(2), np.array([2.0, 0.0]), 5.0) == 1e11


def test_divergence_error_carries_details():
    with pytest.raises(nvib.DivergenceError) as info:
        nvib.solve(stiff_model(), nvib.CentralDifference(), dt=0.03, t_end=100.0)
    e = info.value
    assert isinstance(e, nvib.NvibError) and isinstance(e, RuntimeError)
    assert e.step > 1 and e.t == pytest.approx(e.step * 0.03) and e.dof == 0
    assert e.result is not None and e.result.status == nvib.Status.diverged
    assert e.result.u.shape == (e.step, 1)
    assert "diverged" in str(e)


def test_max_displacement_bound():
    res = nvib.solve(stiff_model(), nvib.CentralDifference(), dt=0.03, t_end=100.0, throw=False,
                     max_displacement=50.0)
    assert res.status == nvib.Status.diverged
    assert np.all(np.abs(res.u) <= 50.0)
    assert res.failure.step == len(res.t)
    # within the bound nothing happens
    ok = nvib.solve(stiff_model(), nvib.CentralDifference(), dt=0.001, t_end=1.0, max_displacement=1.5)
    assert ok.status == nvib.Status.success


def test_divergence_reports_the_offending_dof():
    md = nvib.Model([1.0, 1.0, 1.0], K=np.diag([1.0, 1.0, 1e4]), u0=[1.0, 1.0, 1.0], dofs=["p", "q", "r"])
    res = nvib.solve(md, nvib.CentralDifference(), dt=0.03, t_end=100.0, throw=False)
    assert res.status == nvib.Status.diverged and res.failure.dof == 2


def test_stable_implicit_run_of_the_same_problem_succeeds():
    res = nvib.solve(stiff_model(), nvib.Newmark(), dt=0.03, t_end=3.0)
    assert res.success and np.max(np.abs(res.u)) <= 1.0 + 1e-9


# --------------------------------------------------------------------------- dense mass
def same_up_to_roundoff_tolerance(name):
    """Explicit schemes and PIM reproduce each other to round-off. The
    Newmark-type schemes agree only to the Newton tolerance (rtol = 1e-10,
    modified Newton stops just below it) and recover the acceleration from
    (u_{n+1} - u_n - h v_n)/(beta h^2), which amplifies round-off in u by
    1/(beta h^2): measured differences reach ~2e-10 relative."""
    return 1e-9 if is_implicit(ALL_SCHEMES[name]) else 1e-12


@pytest.mark.parametrize("name", list(ALL_SCHEMES))
def test_dense_mass_equal_to_diagonal(name):
    """A dense mass matrix that is numerically diagonal (tiny off-diagonal
    entries keep it on the dense Cholesky path) gives the diagonal result."""
    rel = same_up_to_roundoff_tolerance(name)
    dense = np.diag(MASSES)
    dense[0, 1] = dense[1, 0] = 1e-300
    r1 = nvib.solve(chain_model(), ALL_SCHEMES[name], dt=1e-3, t_end=1.0)
    r2 = nvib.solve(chain_model(dense), ALL_SCHEMES[name], dt=1e-3, t_end=1.0)
    r3 = nvib.solve(chain_model(np.diag(MASSES)), ALL_SCHEMES[name], dt=1e-3, t_end=1.0)
    for attr in ("u", "v", "a"):
        ref = getattr(r1, attr)
        scale = np.max(np.abs(ref))
        assert np.max(np.abs(getattr(r2, attr) - ref)) <= rel * scale, attr
        assert np.max(np.abs(getattr(r3, attr) - ref)) <= rel * scale, attr


@pytest.mark.parametrize("name", list(ALL_SCHEMES))
def test_genuinely_dense_mass_by_change_of_coordinates(name):
    """x = T q turns the diagonal chain into one with a full mass T^T M T;
    every scheme is invariant under linear changes of coordinates."""
    T = np.array([[1.0, 0.3, 0.0], [0.2, 1.0, -0.4], [0.0, 0.5, 1.0]])
    Ti = np.linalg.inv(T)

    def transformed(eff):
        out = []
        for e in eff:
            g = np.zeros(3)
            for k, c in e["measure"].items():
                g["abc".index(k)] = c
            gq = g @ T
            e2 = dict(e)
            e2["measure"] = {name: float(c) for name, c in zip("abc", gq) if c != 0.0}
            out.append(e2)
        return out

    Mq = T.T @ np.diag(MASSES) @ T
    mq = nvib.Model(Mq, effects=transformed(chain_effects()), dofs=["a", "b", "c"], u0=Ti @ U0, v0=Ti @ V0)
    rx = nvib.solve(chain_model(), ALL_SCHEMES[name], dt=1e-3, t_end=1.0)
    rq = nvib.solve(mq, ALL_SCHEMES[name], dt=1e-3, t_end=1.0)
    for attr in ("u", "v", "a"):
        ref = getattr(rx, attr)
        got = getattr(rq, attr) @ T.T
        assert np.max(np.abs(got - ref)) <= same_up_to_roundoff_tolerance(name) * np.max(np.abs(ref)), attr


# --------------------------------------------------------------------------- Stepper
@pytest.mark.parametrize("name", list(ALL_SCHEMES))
def test_stepper_continues_exactly_like_solve(name):
    dt, n = 1e-3, 300
    ref = nvib.solve(chain_model(), ALL_SCHEMES[name], dt=dt, t_end=n * dt)
    st = nvib.Stepper(chain_model(), ALL_SCHEMES[name], dt)
    assert st.t == 0.0 and np.array_equal(st.u, U0) and np.array_equal(st.v, V0)
    assert np.array_equal(st.a, ref.a[0])
    st.step()
    st.step(99)
    assert st.step_index == 100 and st.t == pytest.approx(100 * dt)
    assert np.array_equal(st.u, ref.u[100]) and np.array_equal(st.v, ref.v[100]) and np.array_equal(st.a, ref.a[100])
    for _ in range(200):
        st.step()
    assert np.array_equal(st.u, ref.u[-1]) and np.array_equal(st.v, ref.v[-1]) and np.array_equal(st.a, ref.a[-1])
    assert st.stats.num_steps == ref.stats.num_steps
    assert st.stats.num_force_evals == ref.stats.num_force_evals


@pytest.mark.parametrize("name", list(ALL_SCHEMES))
def test_stepper_integrate_continues_the_run(name):
    dt = 1e-3
    ref = nvib.solve(chain_model(), ALL_SCHEMES[name], dt=dt, t_end=0.4)
    st = nvib.Stepper(chain_model(), ALL_SCHEMES[name], dt)
    st.step(150)
    part = st.integrate(0.4, save_every=50)
    assert part.t[0] == pytest.approx(0.15)
    assert np.array_equal(part.u[0], ref.u[150])
    assert np.array_equal(part.u[-1], ref.u[-1])
    assert part.stats.num_steps == 250
    assert np.array_equal(st.u, ref.u[-1])
    with pytest.raises(ValueError, match=r"^t_end\b"):
        st.integrate(0.3)


def test_stepper_with_t0_and_initial_state():
    st = nvib.Stepper(chain_model(), nvib.Newmark(), 0.01, t0=2.0, u0=[0.0, 0.1, 0.0], v0=[0.0, 0.0, 1.0])
    ref = nvib.solve(chain_model(), nvib.Newmark(), dt=0.01, t0=2.0, t_end=2.1, u0=[0.0, 0.1, 0.0],
                     v0=[0.0, 0.0, 1.0])
    st.step(10)
    assert st.t == pytest.approx(2.1) and np.array_equal(st.u, ref.u[-1])


def test_stepper_divergence_raises():
    st = nvib.Stepper(stiff_model(), nvib.CentralDifference(), 0.03)
    with pytest.raises(nvib.DivergenceError) as info:
        st.step(10_000)
    assert info.value.step is not None and info.value.step > 1


def test_progress_callback_and_result_repr():
    calls = []
    res = nvib.solve(linear_model(), nvib.CentralDifference(), dt=1e-4, t_end=1.0,
                     progress=lambda i, n: calls.append((i, n)))
    assert calls and all(n == 10_000 for _, n in calls) and calls[-1][0] <= 10_000
    assert [i for i, _ in calls] == sorted(i for i, _ in calls)
    assert "success" in repr(res)
    with pytest.raises(TypeError, match=r"^progress\b"):
        nvib.solve(linear_model(), nvib.CentralDifference(), dt=1e-3, t_end=0.1, progress=3)


def test_progress_exception_propagates():
    class Stop(Exception):
        pass

    def progress(i, n):
        raise Stop("stop")

    with pytest.raises(Stop):
        nvib.solve(linear_model(), nvib.CentralDifference(), dt=1e-5, t_end=1.0, progress=progress)


def test_model_flags():
    assert linear_model().is_linear and not linear_model().uses_velocity and not linear_model().uses_time
    md = chain_model()
    assert not md.is_linear and md.uses_velocity and md.uses_time
    md2 = chain_model(damped=False)
    assert not md2.uses_velocity
    f = nvib.Model([1.0], force=lambda u, v, t: u, uses_velocity=False, uses_time=False)
    assert not f.uses_velocity and not f.uses_time and not f.is_linear


def test_evaluate_force_matches_the_laws():
    md = chain_model()
    u, v, t = np.array([0.1, -0.2, 0.4]), np.array([0.3, 0.0, -0.1]), 0.7
    d_ba, d_cb = u[1] - u[0], u[2] - u[1]
    f_h = 120.0 * (1.0 + 15.0 * d_ba ** 2) * d_ba
    f_c = 500.0 * d_cb ** 3 + 60.0 * d_cb
    f_d = 0.9 * (v[1] - v[0])
    expected = np.array([
        300.0 * u[0] - f_h - f_d - 2.0,
        f_h + f_d - f_c,
        f_c + 1.0 * 9.81 * 0.5 * math.sin(u[2]) - 10.0 * math.sin(6.0 * t),
    ])
    assert np.allclose(md.evaluate_force(u, v, t), expected, rtol=1e-13, atol=1e-13)


# The public names of a fresh `import nvib` (a new process: other tests import more submodules):
# its own subpackages, never a module it merely uses (os) nor the `annotations` feature that
# `from __future__ import annotations` binds.
PUBLIC_SUBPACKAGES = {"analysis": "nvib.analysis", "exact": "nvib.analysis.exact",
                      "stability": "nvib.analysis.stability", "scenes": "nvib.scenes",
                      "fragility": "nvib.analysis.fragility"}


def test_namespace_holds_no_stray_modules_or_future_features():
    code = ("import json, types, __future__, nvib\n"
            "print(json.dumps({n: [type(v).__name__, getattr(v, '__name__', None)] for n, v in vars(nvib).items()"
            " if isinstance(v, (types.ModuleType, __future__._Feature))}))")
    package_parent = os.path.dirname(os.path.dirname(nvib.__file__))  # the nvib this test imported
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(filter(None, [package_parent, os.environ.get("PYTHONPATH")])))
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, env=env).stdout
    found = json.loads(out)
    assert "annotations" not in dir(nvib) and not any(kind == "_Feature" for kind, _ in found.values()), found
    public = {n: mod for n, (_, mod) in found.items() if not n.startswith("_")}
    assert public == PUBLIC_SUBPACKAGES  # what nvib uses itself goes under a private name (_os, _core)
