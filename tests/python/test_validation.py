"""Bad input at the public entry points raises ValueError/TypeError naming the
argument; cases that used to slip through (generic pybind11 errors, silently
dropped imaginary parts, parsed strings, a start that carried inf)."""

from __future__ import annotations

import numpy as np
import pytest

import nvib

SCHEME_CALLS = [
    (lambda: nvib.CEMDTS(foo=1), TypeError, r"^foo: unknown parameter of CEMDTS \(expected eta\)"),
    (lambda: nvib.CEMDTS("0.3"), TypeError, r"^eta: expected a real number, got str"),
    (lambda: nvib.CEMDTS(None), TypeError, r"^eta: expected a real number"),
    (lambda: nvib.CEMDTS(0.1, 0.2), TypeError, r"^CEMDTS: takes at most 1 positional argument"),
    (lambda: nvib.CEMDTS(0.1, eta=0.2), TypeError, r"^eta: given twice"),
    (lambda: nvib.Zhai(psi=[0.5]), TypeError, r"^psi: expected a real number"),
    (lambda: nvib.Zhai(chi=0.5), TypeError, r"^chi: unknown parameter of Zhai \(expected psi, phi\)"),
    (lambda: nvib.CentralDifference("half_step"), TypeError, r"^CentralDifference: .* velocity must be given by name"),
    (lambda: nvib.CentralDifference(velocity=1), TypeError, r"^velocity: expected one of"),
    (lambda: nvib.Newmark(iteration=None), TypeError,
     r"^iteration: expected one of 'newton', 'modified', 'initial', 'incremental' or 'one_iteration', got NoneType"),
    (lambda: nvib.Newmark(iteration="none"), ValueError, r"^iteration: 'none' is now 'one_iteration'"),
    (lambda: nvib.Newton(max_iter=2.0), TypeError, r"^max_iter: expected an integer, got float"),
    (lambda: nvib.Newton(max_iter=10**30), ValueError, r"^max_iter: Newton needs 1 <= max_iter <= 1000"),
    (lambda: nvib.Newmark(max_iter=5), TypeError, r"^max_iter: unknown parameter of Newmark \(expected beta, gamma, "
                                                  r"newton\)"),
    (lambda: nvib.Newmark(beta=10**400), ValueError, r"^beta: must be finite"),
    (lambda: nvib.Newmark(tol=1e-8), TypeError, r"^tol: unknown parameter of Newmark"),
    (lambda: nvib.GeneralizedAlpha(alpha=0.5), TypeError, r"^alpha: unknown parameter of GeneralizedAlpha"),
    (lambda: nvib.Newton(rtol="small"), TypeError, r"^rtol: expected a real number"),
    (lambda: nvib.GeneralizedAlpha(newton=nvib.Newton(), iteration="newton"), TypeError, r"^iteration: give the iteration"),
    (lambda: nvib.GeneralizedAlpha.from_rho_inf(), TypeError, r"^rho_inf: missing"),
    (lambda: nvib.GeneralizedAlpha.from_rho_inf(rho=0.5), TypeError, r"^rho: unknown parameter of "
                                                                       r"GeneralizedAlpha\.from_rho_inf"),
    (lambda: nvib.GeneralizedAlpha.from_rho_inf(0.5, "none"), TypeError, r"^GeneralizedAlpha\.from_rho_inf: takes "
                                                                         r"1 positional argument \(rho_inf\), got 2"),
    (lambda: nvib.GeneralizedAlpha.hht(None), TypeError, r"^alpha: expected a real number"),
    (lambda: nvib.GeneralizedAlpha.wbz(-0.1, jacobian=3), TypeError, r"^jacobian: unknown parameter of "
                                                                      r"GeneralizedAlpha\.wbz"),
    (lambda: nvib.GeneralizedAlpha.wbz(-0.1, newton=nvib.Newton(jacobian=3)), TypeError, r"^jacobian: expected one of"),
    (lambda: nvib.PreciseIntegration(interpolation=2.0), TypeError, r"^interpolation: expected an integer, got float"),
    (lambda: nvib.PreciseIntegration(order=3), TypeError, r"^order: renamed interpolation in PreciseIntegration "
                                                          r"\(polynomial degree of the interpolation of the remainder "
                                                          r"\(not the order of accuracy\)\): give interpolation=3$"),
    (lambda: nvib.PreciseIntegration(20), TypeError, r"^PreciseIntegration: takes at most 0 positional"),
    (lambda: nvib.PreciseIntegration(steps=3), TypeError, r"^steps: unknown parameter of PreciseIntegration"),
]


@pytest.mark.parametrize("call, error, match", SCHEME_CALLS)
def test_scheme_constructor_errors_name_the_argument(call, error, match):
    with pytest.raises(error, match=match):
        call()


def test_scheme_classes_keep_their_behaviour():
    """The Python classes are the C++ schemes: same values, names, and accepted by solve()."""
    cases = [
        (nvib.CEMDTS(0.3), nvib._core.CEMDTS(0.3)),
        (nvib.Zhai(0.6, 0.7), nvib._core.Zhai(0.6, 0.7)),
        (nvib.CentralDifference(velocity="half_step"), nvib._core.CentralDifference(velocity="half_step")),
        (nvib.Newmark(0.3, 0.6, newton=nvib.Newton(iteration="modified", max_iter=7, rtol=1e-8, atol=1e-9,
                                                   jacobian="finite_difference")),
         nvib._core.Newmark(0.3, 0.6, newton=nvib._core.Newton(iteration="modified", max_iter=7, rtol=1e-8, atol=1e-9,
                                                               jacobian="finite_difference"))),
        (nvib.GeneralizedAlpha.from_rho_inf(0.8, iteration="one_iteration"),
         nvib._core.GeneralizedAlpha.from_rho_inf(0.8, iteration="one_iteration")),
        (nvib.GeneralizedAlpha.hht(-0.1), nvib._core.GeneralizedAlpha.hht(-0.1)),
        (nvib.GeneralizedAlpha.wbz(-0.2, newton=nvib.Newton(max_iter=5)),
         nvib._core.GeneralizedAlpha.wbz(-0.2, newton=nvib._core.Newton(max_iter=5))),
        (nvib.PreciseIntegration(interpolation=3, corrections=2), nvib._core.PreciseIntegration(interpolation=3, corrections=2)),
    ]
    model = nvib.Model([1.0], effects=[{"type": "hardening_spring", "measure": {"x": 1.0}, "k0": 100.0, "a": 30.0}],
                       dofs=["x"], u0=[1.5])
    for py, core in cases:
        assert isinstance(py, type(core)) and repr(py) == repr(core) == py.name
        assert isinstance(py, getattr(nvib, type(core).__name__))
        a = nvib.solve(model, py, dt=1e-3, t_end=0.05)
        b = nvib.solve(model, core, dt=1e-3, t_end=0.05)
        assert np.array_equal(a.u, b.u) and np.array_equal(a.v, b.v)
    ga = nvib.GeneralizedAlpha.from_rho_inf(0.8)
    core = nvib._core.GeneralizedAlpha.from_rho_inf(0.8)
    assert (ga.alpha_m, ga.alpha_f, ga.beta, ga.gamma) == (core.alpha_m, core.alpha_f, core.beta, core.gamma)
    assert nvib.CEMDTS(np.float64(0.2)).eta == 0.2 and nvib.PreciseIntegration(interpolation=np.int64(1)).interpolation == 1


@pytest.mark.parametrize("kwargs, error, match", [
    (dict(mass=[1 + 1j]), TypeError, r"^mass: expected real numbers"),
    (dict(mass=np.array([2.0 + 0.5j])), TypeError, r"^mass: expected real numbers"),
    (dict(mass=["1.0"]), TypeError, r"^mass: expected real numbers"),
    (dict(mass=[True]), TypeError, r"^mass: expected real numbers"),
    (dict(mass=[[1.0], [1.0, 2.0]]), ValueError, r"^mass: expected a regular array"),
    (dict(mass=[1e-320]), ValueError, r"^mass: entry 0 is .*too small for its inverse"),
    (dict(mass=[1.0], u0=[1j]), TypeError, r"^u0: expected real numbers"),
    (dict(mass=[1.0], v0=["0.5"]), TypeError, r"^v0: expected real numbers"),
    (dict(mass=[1.0, 1.0], K=np.eye(2) * (1 + 0j)), TypeError, r"^K: expected real numbers"),
    (dict(mass=[1.0, 1.0], dofs=5), TypeError, r"^dofs: expected a list of 2 names"),
    (dict(mass=[1.0, 1.0], dofs="ab"), TypeError, r"^dofs: expected a list of 2 names"),
])
def test_model_arrays_must_be_real(kwargs, error, match):
    with pytest.raises(error, match=match):
        nvib.Model(**kwargs)


def test_signal_table_must_be_real():
    spec = {"type": "ground_acceleration", "signal": {"kind": "table", "t": ["a", "b"], "values": [0.0, 1.0]}}
    with pytest.raises(TypeError, match=r"^effects\[0\]\.signal\.t: expected real numbers"):
        nvib.Model([1.0], effects=[spec])


def test_a_start_whose_forces_overflow_is_refused():
    """u0 = 1e120 with a cubic spring: k3 u^3 overflows, so a0 is not finite. The
    run used to start and report a row 0 holding inf; now the start is refused."""
    model = nvib.Model([1.0], effects=[{"type": "cubic_spring", "measure": {"x": 1.0}, "k3": 10.0}], dofs=["x"],
                       u0=[1e120])
    for scheme in (nvib.CentralDifference(), nvib.Newmark(), nvib.PreciseIntegration()):
        with pytest.raises(ValueError, match=r"^u0, v0: the initial acceleration is not finite \(a\[0\] = -inf\)"):
            nvib.solve(model, scheme, dt=1e-3, t_end=0.01)
        with pytest.raises(ValueError, match=r"^u0, v0:"):
            nvib.Stepper(model, scheme, 1e-3)


def test_real_checks_reject_huge_integers_and_accept_numpy_scalars():
    with pytest.raises(ValueError, match=r"^dt: must be finite"):
        nvib.solve(nvib.Model([1.0], K=[[1.0]]), nvib.CEMDTS(), dt=10**400, t_end=1.0)
    res = nvib.solve(nvib.Model([1.0], K=[[1.0]], u0=[1.0]), nvib.CEMDTS(np.float32(0.25)), dt=np.float64(0.01),
                     t_end=np.int64(1), save_every=np.int32(10))
    assert res.success and len(res.t) == 11


@pytest.mark.parametrize("line, match", [
    ('dt = "fast"', r"\[scene\] dt: expected a real number, got str"),
    ("dt = -0.1", r"\[scene\] dt: must be > 0"),
    ("t_end = nan", r"\[scene\] t_end: must be finite"),
])
def test_scene_settings_are_checked(tmp_path, line, match):
    path = tmp_path / "s.toml"
    path.write_text(f'[scene]\n{line}\n[dofs]\nnames = ["x"]\nmass = [1.0]\n')
    with pytest.raises(nvib.SceneError, match=match):
        nvib.load_scene(str(path))


@pytest.mark.parametrize("body, match", [
    ('[dofs]\nnames = ["x"]\nmass = ["heavy"]\n', r"\[dofs\] mass: expected real numbers"),
    ('[dofs]\nnames = ["x"]\nmass = [1.0]\n[initial]\nu = ["a"]\n', r"\[initial\] u: expected real numbers"),
    ('[dofs]\nnames = ["x"]\nmass = [1.0]\n[initial]\nv = { x = "fast" }\n',
     r"\[initial\] v\.x: expected a real number"),
])
def test_scene_values_must_be_real(tmp_path, body, match):
    path = tmp_path / "s.toml"
    path.write_text(body)
    with pytest.raises(nvib.SceneError, match=match) as info:
        nvib.load_scene(str(path))
    assert str(info.value).startswith(str(path))


def test_default_divergence_bound_is_the_cpp_one():
    """solve() with no max_displacement uses the same bound in Python and C++:
    1e10 x max(1, max|u0|, max|v0| T)."""
    assert nvib.default_max_displacement([2.0, -3.0], [0.0, 1.0], 10.0) == 1e11
    assert nvib.default_max_displacement([2.0, -3.0], [0.0, 0.1], 10.0) == 3e10
    assert nvib.default_max_displacement(3.0, 0.0, 1.0) == 3e10
    model = nvib.Model([1.0], K=[[1e4]], u0=[2.0], dofs=["x"])
    res = nvib.solve(model, nvib.CentralDifference(), dt=0.03, t_end=100.0, throw=False)
    assert "beyond the bound 2e+10" in res.failure.message


@pytest.mark.parametrize("args, error, match", [
    (("a",), TypeError, r"^A: expected real numbers"),
    (([[1j]],), TypeError, r"^A: expected real numbers"),
    ((np.ones(3),), ValueError, r"^A: expected a square matrix"),
    ((np.eye(2), "x"), TypeError, r"^squarings: expected an integer"),
    ((np.eye(2), 2.5), TypeError, r"^squarings: expected an integer"),
    ((np.eye(2), 10**30), ValueError, r"^squarings: needs 0 <= squarings <= 60"),
    ((np.eye(2) * 1e300,), ValueError, r"^A: e\^A overflows"),
])
def test_expm_arguments(args, error, match):
    with pytest.raises(error, match=match):
        nvib.expm(*args)


@pytest.mark.parametrize("call, error, match", [
    (lambda: nvib.exact.linear_sdof([0.0], m=0.0, k=1.0), ValueError, r"^m: must be > 0"),
    (lambda: nvib.exact.linear_sdof([0.0], m=1.0, k=-1.0), ValueError, r"^k: must be > 0"),
    (lambda: nvib.exact.linear_sdof(["a"], m=1.0, k=1.0), TypeError, r"^t: expected real numbers"),
    (lambda: nvib.exact.hardening([0.0], a=-1.0), ValueError, r"^a: must be >= 0"),
    (lambda: nvib.exact.hardening([float("nan")]), ValueError, r"^t: contains NaN"),
    (lambda: nvib.exact.hardening_period(x0="1"), TypeError, r"^x0: expected a real number"),
    (lambda: nvib.exact.hardening_energy([1.0], [0.0], m=-2.0), ValueError, r"^m: must be > 0"),
    (lambda: nvib.Model([1.0], K=[[1.0]]).evaluate_force([0.0], [0.0], "t"), TypeError, r"^t: expected a real"),
    (lambda: nvib.Model([1.0], K=[[1.0]]).static_equilibrium(max_iter=0), ValueError, r"^max_iter: must be >= 1"),
    (lambda: nvib.default_max_displacement("u", [0.0], 1.0), TypeError, r"^u: expected real numbers"),
])
def test_helpers_name_their_arguments(call, error, match):
    with pytest.raises(error, match=match):
        call()


def test_without_takes_a_single_name():
    eff = [{"type": "spring", "name": "s", "measure": {"x": 1.0}, "k": 1.0},
           {"type": "constant_force", "name": "gravity", "measure": {"x": 1.0}, "value": 1.0}]
    one = nvib.Model([1.0], effects=eff, dofs=["x"], without="gravity")
    assert [e.name for e in one.effects] == ["s"]
