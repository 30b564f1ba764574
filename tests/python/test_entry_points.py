"""Every public entry point refuses an unknown keyword argument and a non-finite float, naming it.

The entry points are found, not listed by hand: the callables of ``nvib.__all__``, of ``nvib.exact``,
``nvib.stability``, ``nvib.scenes`` and ``nvib.fragility``, and the public methods of the model, the stepper and the records.
Each needs a minimal valid call in CALLS below (a test fails for an entry point that has none, so a new one
is covered when it is added); SKIP holds the exceptions and the result types, which take no settings. Then,
one argument at a time: ``bogus_kw=1`` must raise TypeError naming ``bogus_kw``; NaN and Inf in each float
parameter (read from the signature: a float default or a ``float`` annotation, plus FLOATS) must raise an
error whose ``.argument`` (or message) names that parameter. A parameter where Inf means "no limit" is in
INF_ALLOWED: NaN must still be refused there.
"""

from __future__ import annotations

import inspect
import math
import os

import numpy as np
import pytest

import nvib
from nvib import GroundMotion
from nvib.analysis import exact, stability

# Exceptions and what the library hands back (results, summaries, containers): built by nvib, not by a caller
# with settings. Functions without arguments (folders, names) have nothing to refuse.
SKIP = {"ArgumentError", "ArgumentTypeError", "ConvergenceError", "DivergenceError", "NvibError", "RecordError",
        "SceneError", "SingularMatrixError", "Batch", "Energy", "Estimate", "Failure", "Fragility", "IDA", "LawCheck", "LawResponse",
        "InelasticSpectrum", "Reference", "Result", "RunError", "RunSummary", "Spectrum", "Stats", "Status", "cmake_dir",
        "include_dir",
        "scene_names", "schemes", "stability.NvibError", "stability.Model", "stability.Stepper", "stability.StepLimit",
        "fragility.Fragility"}

# Parameters that take a float without saying so in their signature.
FLOATS = {"rayleigh": ["zeta"], "rayleigh_coefficients": ["zeta"], "solve_many": ["t0", "max_displacement",
                                                                                   "max_energy_error",
                                                                                   "warn_energy_error",
                                                                                   "warn_error",
                                                                                   "collapse_deformation"],
          "stability.damping_ratio": ["omega_h"], "stability.period_error": ["omega_h"],
          "stability.principal_eigenvalue": ["omega_h"], "stability.spectral_radius": ["omega_h"],
          "stability.amplification_matrix": ["omega_h"], "GroundMotion.scaled": ["factor"],
          "GroundMotion.exact_response": ["damping"],
          "default_max_displacement": ["duration"]}

# Inf is a documented value here ("no limit"); NaN is still refused.
INF_ALLOWED = {"max_displacement", "max_energy_error", "warn_energy_error", "warn_error"}


def oscillator():
    return nvib.Model([1.0], effects=[{"type": "spring", "name": "s", "measure": {0: 1.0}, "k": 100.0}], u0=[0.1],
                      dofs=["x"])


def storey():
    t = np.arange(100) * 0.01
    record = GroundMotion.from_array(np.sin(8 * t), dt=0.01, name="r")
    model = nvib.Model([1.0], dofs=["x"], effects=[
        {"type": "spring", "name": "storey", "measure": {"x": 1.0}, "k": 100.0},
        {"type": "ground_acceleration", "name": "ground", "signal": record}])
    return model, record


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    d = tmp_path_factory.mktemp("entry_points")
    np.savetxt(d / "rec.txt", np.sin(0.07 * np.arange(200)))
    res = nvib.solve(oscillator(), nvib.Newmark(), dt=0.01, t_end=0.1)
    res.save(str(d / "res.npz"))
    rows = nvib.cost(oscillator(), [nvib.Newmark()], [0.01, 0.005], t_end=0.2, repeats=1)
    at2 = os.path.join(os.path.dirname(nvib.__file__), "scenes", "records", "sgm1.AT2")
    return {"dir": d, "rec": str(d / "rec.txt"), "res": str(d / "res.npz"), "rows": rows, "at2": at2}


def calls(files) -> dict:
    """name -> (callable, args, kwargs): a minimal valid call of each entry point."""
    model, record = storey()
    osc = oscillator()
    stepper = nvib.Stepper(osc, nvib.Newmark(), 0.01)
    run = dict(dt=0.01, t_end=0.1)
    rows = files["rows"]
    # an IDA's table as nvib.ida makes it (two records, three scales, one collapse), without the runs
    levels, none = np.array([1.0, 2.0, 3.0]), [""] * 3
    curves = [nvib.analysis.ida.Curve(name, levels, np.array(d), np.isinf(d), [""] * 2 + [cause], levels,
                                      np.full(3, np.nan), none, none, np.where(np.isinf(d), np.nan, d),
                                      np.full(3, np.nan))
              for name, d, cause in (("a", [0.01, 0.03, np.inf], "strength lost"), ("b", [0.025, 0.015, 0.04], ""))]
    measure = np.vstack([c.demand for c in curves])
    ida = nvib.IDA(["a", "b"], curves, levels, measure, np.isinf(measure), "peak storey drift", "m",
                   "scale factor of the records", "-", "CEMDTS", 0.01, None, [], 6, 0.0)
    return {
        "CEMDTS": (nvib.CEMDTS, (), {}), "CentralDifference": (nvib.CentralDifference, (), {}),
        "GeneralizedAlpha": (nvib.GeneralizedAlpha, (), {}), "Newmark": (nvib.Newmark, (), {}),
        "PreciseIntegration": (nvib.PreciseIntegration, (), {}), "Zhai": (nvib.Zhai, (), {}),
        "Newton": (nvib.Newton, (), {}),
        "GroundMotion": (GroundMotion, ([0.0, 0.1], [0.0, 1.0]), {}),
        "GroundMotion.from_array": (GroundMotion.from_array, ([0.0, 1.0, 0.0], 0.01), {}),
        "GroundMotion.from_file": (GroundMotion.from_file, (files["rec"],), {"dt": 0.01}),
        "GroundMotion.from_at2": (GroundMotion.from_at2, (files["at2"],), {}),
        "GroundMotion.scaled": (record.scaled, (2.0,), {}),
        "GroundMotion.from_spec": (GroundMotion.from_spec, ("signal", {"kind": "record", "file": files["rec"],
                                                                       "dt": 0.01}), {}),
        "GroundMotion.signal": (record.signal, (), {}),
        "GroundMotion.psa": (record.psa, ([0.5, 1.0],), {}),
        "GroundMotion.exact_response": (record.exact_response, ([0.5, 1.0], 0.05), {}),
        "GroundMotion.scaled_to_sa": (record.scaled_to_sa, (0.5, 0.3), {}),
        "Model": (nvib.Model, ([1.0],), {}),
        "Model.evaluate_force": (osc.evaluate_force, ([0.1], [0.0]), {}),
        "Model.static_equilibrium": (osc.static_equilibrium, (), {}),
        "Model.tangent_matrices": (osc.tangent_matrices, ([0.1], [0.0]), {}),
        "Model.linearized_frequencies": (osc.linearized_frequencies, (), {}),
        "Model.unit": (osc.unit, ("x",), {}),
        "Stepper": (nvib.Stepper, (osc, nvib.Newmark(), 0.01), {}),
        "Stepper.step": (stepper.step, (), {}),
        "Stepper.integrate": (stepper.integrate, (1.0,), {}),
        "Stepper.set_state": (stepper.set_state, (stepper.state(),), {}),
        "Stepper.state": (stepper.state, (), {}),
        "cheapest": (nvib.cheapest, (rows, 1.0), {}),
        "time_at_error": (nvib.time_at_error, (rows, 1e-3), {}),
        "markdown_table": (nvib.markdown_table, (rows,), {}),
        "plot_work_precision": (nvib.plot_work_precision, (rows, str(files["dir"] / "wp.png")), {}),
        "cost": (nvib.cost, (osc, [nvib.Newmark()], [0.01]), {"t_end": 0.1, "repeats": 1}),
        "cost_scipy": (nvib.cost_scipy, (osc, ("RK45",), (1e-3,)), {"t_end": 0.1, "repeats": 1}),
        "default_max_displacement": (nvib.default_max_displacement, ([0.1], [0.0], 1.0), {}),
        "drive": (nvib.drive, ({"type": "spring", "k": 2.0}, [0.0, 0.1]), {}),
        "check_law": (nvib.check_law, ({"type": "callable", "law": lambda d, dd, t: 2.0 * d,
                                        "tangent": lambda d, dd, t: (2.0, 0.0)}, [0.0, 0.1]), {}),
        "estimate": (nvib.estimate, (osc, nvib.Newmark()), dict(run)),
        "expm": (nvib.expm, (np.eye(2),), {}),
        "ida": (nvib.ida, (model, [record], [1.0]), {"dt": 0.01, "im": "scale", "measure": "peak_drift",
                                                     "check": False, "progress": False}),
        "load_result": (nvib.load_result, (files["res"],), {}),
        "load_scene": (nvib.load_scene, ("pendulum",), {}),
        "rayleigh": (nvib.rayleigh, (osc,), {"zeta": 0.05, "omegas": [5.0, 20.0]}),
        "rayleigh_coefficients": (nvib.rayleigh_coefficients, (0.05, [5.0, 20.0]), {}),
        "reference": (nvib.reference, (osc, 0.1), {}),
        "scheme_label": (nvib.scheme_label, (nvib.Newmark(),), {}),
        "solve": (nvib.solve, (osc, nvib.Newmark()), dict(run)),
        "solve_many": (nvib.solve_many, ([osc], nvib.Newmark()), dict(run, threads=1, progress=False)),
        "spectrum": (nvib.spectrum, (record, [0.5]), {"scheme": nvib.Newmark(), "max_halvings": 0}),
        "inelastic_spectrum": (nvib.inelastic_spectrum, (record, [0.5]), {"ductility": [2.0], "max_halvings": 0}),
        "exact.forced_linear_sdof": (exact.forced_linear_sdof, ([0.0, 0.1],), {"m": 1.0, "k": 4.0, "amplitude": 1.0,
                                                                             "omega": 3.0}),
        "exact.hardening": (exact.hardening, ([0.0, 0.1],), {}),
        "exact.hardening_energy": (exact.hardening_energy, (1.0, 0.0), {}),
        "exact.hardening_period": (exact.hardening_period, (), {}),
        "exact.linear_sdof": (exact.linear_sdof, ([0.0, 0.1],), {"m": 1.0, "k": 4.0}),
        "exact.pendulum": (exact.pendulum, ([0.0, 0.1],), {"theta0": 0.5}),
        "exact.pendulum_period": (exact.pendulum_period, (), {"theta0": 0.5}),
        "stability.amplification_matrix": (stability.amplification_matrix, (nvib.Newmark(), 0.1), {}),
        "stability.check_scheme": (stability.check_scheme, ("scheme", nvib.Newmark()), {}),
        "stability.step_limit": (stability.step_limit, (osc, nvib.CentralDifference()), {}),
        "stability.step_warning": (stability.step_warning, (osc, nvib.CentralDifference(), 0.01), {}),
        "stability.critical_omega_h": (stability.critical_omega_h, (nvib.CEMDTS(),), {}),
        "stability.damping_ratio": (stability.damping_ratio, (nvib.Newmark(), 0.1), {}),
        "stability.period_error": (stability.period_error, (nvib.Newmark(), 0.1), {}),
        "stability.principal_eigenvalue": (stability.principal_eigenvalue, (nvib.Newmark(), 0.1), {}),
        "stability.spectral_radius": (stability.spectral_radius, (nvib.Newmark(), 0.1), {}),
        "stability.plot_spectral_radius": (stability.plot_spectral_radius, ([nvib.Newmark()],
                                                                           str(files["dir"] / "rho.png")),
                                           {"omega_h": [0.1, 1.0]}),
        "stability.stability_figure": (stability.stability_figure, ([nvib.Newmark()],), {"omega_h": [0.1, 1.0]}),
        "stability.scheme_label": (stability.scheme_label, (nvib.Newmark(),), {}),
        "fragility.fit_collapse_ims": (nvib.fragility.fit_collapse_ims, ([0.8, 1.2],), {"censored": [1.5]}),
        "fragility.fit_stripes": (nvib.fragility.fit_stripes, ([0.5, 1.0, 1.5], 4, [0, 2, 3]), {}),
        "fragility.from_ida": (nvib.fragility.from_ida, (ida,), {"demand_limit": 0.02}),
        "fragility.markdown_table": (nvib.fragility.markdown_table, ([nvib.fragility.fit_stripes([1.0, 2.0], 4,
                                                                                                [1, 3])],), {}),
        "scenes.chain": (nvib.scenes.chain, (2,), {}),
        "scenes.lattice": (nvib.scenes.lattice, (2, 2), {}),
    }


def entry_points() -> list[str]:
    """The names of the public callables, found in the package."""
    names = []
    for name in nvib.__all__:
        obj = getattr(nvib, name)
        if callable(obj) and not inspect.ismodule(obj):
            names.append(name)
    for prefix, module in (("exact", exact), ("stability", stability), ("scenes", nvib.scenes),
                           ("fragility", nvib.fragility)):
        public = getattr(module, "__all__", None) or [n for n in dir(module) if not n.startswith("_")]
        for name in public:
            obj = getattr(module, name)
            if (inspect.isfunction(obj) or inspect.isclass(obj)) and not name.startswith("_"):
                names.append(f"{prefix}.{name}")
    for owner, cls in (("Model", nvib.Model), ("Stepper", nvib.Stepper), ("GroundMotion", GroundMotion)):
        for name, obj in vars(cls).items():
            if name.startswith("_") or isinstance(obj, property):
                continue
            if callable(obj) or isinstance(obj, (classmethod, staticmethod)):
                names.append(f"{owner}.{name}")
    return sorted(n for n in names if n not in SKIP and n.split(".")[0] not in SKIP - {"Model", "Stepper"})


def float_parameters(name: str, fn) -> list[str]:
    """The parameters of ``fn`` that take a float: a float default, a 'float' annotation, or FLOATS."""
    out = list(FLOATS.get(name, []))
    try:
        params = inspect.signature(fn).parameters.values()
    except (TypeError, ValueError):  # a compiled class
        return out
    for p in params:
        if p.kind in (p.VAR_POSITIONAL, p.VAR_KEYWORD) or p.name in out:
            continue
        annotation = p.annotation if isinstance(p.annotation, str) else getattr(p.annotation, "__name__", "")
        default_float = isinstance(p.default, float) and not isinstance(p.default, bool)
        if default_float or "float" in str(annotation):
            out.append(p.name)
    return out


def names_it(exc: BaseException, param: str) -> bool:
    argument = getattr(exc, "argument", None)
    if argument is not None and param in [a.strip() for a in str(argument).split(",")] + [str(argument)]:
        return True
    if argument is not None and str(argument).startswith(param):  # "zeta" of "zeta[1]"
        return True
    text = str(exc)
    return text.startswith(f"{param}:") or f" {param}:" in text or f"'{param}'" in text or f"{param} " in text[:80]


def bind(fn, args, kwargs, param, value):
    """The call with ``param`` set to ``value``: in kwargs, or in place of the positional argument of that name."""
    sig = inspect.signature(fn)
    names = [p.name for p in sig.parameters.values() if p.kind in (p.POSITIONAL_ONLY, p.POSITIONAL_OR_KEYWORD)]
    if param in names and names.index(param) < len(args):
        args = list(args)
        args[names.index(param)] = value
        return tuple(args), dict(kwargs)
    return tuple(args), {**kwargs, param: value}


def test_every_entry_point_has_a_minimal_call(files):
    missing = [n for n in entry_points() if n not in calls(files)]
    assert not missing, f"entry points without a minimal call in CALLS: {missing}"


def test_the_minimal_calls_are_valid(files):
    for name, (fn, args, kwargs) in calls(files).items():
        fn(*args, **kwargs)


def _cases(kind):
    return [pytest.param(n, id=n) for n in entry_points()]


@pytest.mark.parametrize("name", _cases("kw"))
def test_an_unknown_keyword_is_refused_naming_it(name, files):
    fn, args, kwargs = calls(files)[name]
    with pytest.raises(TypeError) as exc:
        fn(*args, **kwargs, bogus_kw=1)
    assert "bogus_kw" in str(exc.value), f"{name}: {exc.value}"


def float_cases():
    out = []
    for name in entry_points():
        fn = _callable_for_signature(name)
        for param in float_parameters(name, fn):
            for value in (math.nan, math.inf, -math.inf):
                out.append(pytest.param(name, param, value, id=f"{name}-{param}-{value}"))
    return out


def _callable_for_signature(name: str):
    if "." not in name:
        return getattr(nvib, name)
    owner, attr = name.split(".", 1)
    home = {"exact": exact, "stability": stability, "scenes": nvib.scenes, "fragility": nvib.fragility,
            "Model": nvib.Model,
            "Stepper": nvib.Stepper, "GroundMotion": GroundMotion}[owner]
    return getattr(home, attr)


@pytest.mark.parametrize("name, param, value", float_cases())
def test_a_non_finite_float_is_refused_naming_it(name, param, value, files):
    if value == math.inf and param in INF_ALLOWED:
        pytest.skip(f"{param} = inf means no limit")
    fn, args, kwargs = calls(files)[name]
    args, kwargs = bind(fn, args, kwargs, param, value)
    with pytest.raises((ValueError, TypeError)) as exc:
        fn(*args, **kwargs)
    assert names_it(exc.value, param), f"{name}({param}={value}): {type(exc.value).__name__}: {exc.value}"
