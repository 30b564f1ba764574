"""One place for each check and each definition: the time step is checked by the C++ core alone, a run's
options have their defaults once, Stats and Result are listed once (and so in the type stub), a result is
written one way, and Newton's iteration has one name."""

import ast
import inspect
from pathlib import Path

import numpy as np
import pytest

import nvib
from nvib import _core
from nvib._solve import RUN_OPTIONS

STUB = Path(nvib.__file__).with_name("_core.pyi")


def stub_class(name: str) -> set:
    if not STUB.is_file():
        pytest.skip("no _core.pyi beside the package")
    tree = ast.parse(STUB.read_text(encoding="utf-8"))
    (cls,) = [n for n in tree.body if isinstance(n, ast.ClassDef) and n.name == name]
    out = set()
    for node in cls.body:
        if isinstance(node, ast.AnnAssign):
            out.add(node.target.id)
        elif isinstance(node, ast.FunctionDef):
            out.add(node.name)
    return out


def public(cls) -> set:
    return {k for k in dir(cls) if not k.startswith("_")}


def test_the_stub_lists_every_member_of_result_and_no_other():
    assert {k for k in stub_class("Result") if not k.startswith("_")} == public(nvib.Result)


def test_the_stub_lists_every_field_of_stats():
    s = nvib.Stats()
    assert stub_class("Stats") == public(nvib.Stats)
    assert set(s.as_dict()) | {"wall_time", "linear_solver"} == public(nvib.Stats) - {"as_dict"}


def test_results_python_members_are_defined_in_one_module():
    for name in ("relative_to_ground", "units", "warnings", "absolute_a", "to_pandas", "to_xarray", "save"):
        member = inspect.getattr_static(nvib.Result, name)
        f = member.fget if isinstance(member, property) else member
        assert f is not None
    text = {p.name: p.read_text(encoding="utf-8") for p in Path(nvib.__file__).parent.glob("*.py")}
    patched = {name for name, t in text.items() if "Result." in t and any(
        line.startswith("Result.") and "=" in line and "__module__" not in line for line in t.splitlines())}
    assert patched == {"_result.py"}


# ---- the time step: checked once, in C++, with one message -------------------------------------------------

MODEL = nvib.Model([1.0], K=[[4.0]], u0=[0.1])
DT_MESSAGE = r"^dt: the time step must be finite and > 0, got "


@pytest.mark.parametrize("dt", [0.0, -1e-3, float("nan"), float("inf")])
@pytest.mark.parametrize("call", [
    lambda dt: nvib.solve(MODEL, nvib.Newmark(), dt=dt, t_end=1.0),
    lambda dt: nvib.Stepper(MODEL, nvib.Newmark(), dt),
    lambda dt: nvib.estimate(MODEL, nvib.Newmark(), dt=dt, t_end=1.0),
    lambda dt: _core.steps_to_reach(0.0, 1.0, dt),
], ids=["solve", "Stepper", "estimate", "steps_to_reach"])
def test_a_bad_time_step_gets_the_one_message_of_the_core(call, dt):
    with pytest.raises(nvib.ArgumentError, match=DT_MESSAGE) as exc:
        call(dt)
    assert exc.value.argument == "dt" and exc.value.reason.startswith("the time step must be finite and > 0")


def test_a_time_step_of_the_wrong_type_is_refused_by_python_naming_dt():
    with pytest.raises(nvib.ArgumentTypeError, match=r"^dt: expected a real number, got str") as exc:
        nvib.solve(MODEL, nvib.Newmark(), dt="0.1", t_end=1.0)
    assert exc.value.argument == "dt"


def test_python_keeps_the_reason_of_a_core_error_without_taking_the_message_apart():
    with pytest.raises(nvib.ArgumentError) as exc:
        nvib.Model([1.0], effects=[{"type": "bilinear", "measure": {0: 1.0}, "k": 1.0, "fy": 0.0, "b": 0.1}])
    assert exc.value.argument == "effects[0].fy" and str(exc.value) == "effects[0].fy: must be > 0, got 0"
    assert exc.value.reason == "must be > 0, got 0"


# ---- a run's options: defaults once --------------------------------------------------------------------

def test_the_loops_defaults_come_from_the_core():
    for key, value in _core.RUN_DEFAULTS.items():
        assert RUN_OPTIONS[key] == value or (value is None and RUN_OPTIONS[key] is None)
    assert RUN_OPTIONS["save_every"] == 1 and RUN_OPTIONS["max_displacement"] is None


@pytest.mark.parametrize("f", [nvib.solve, nvib.Stepper.integrate], ids=["solve", "Stepper.integrate"])
def test_solve_and_integrate_show_every_option_with_its_one_default(f):
    params = inspect.signature(f).parameters
    shown = {k: p.default for k, p in params.items() if k in RUN_OPTIONS}
    assert shown == RUN_OPTIONS


def test_estimate_takes_its_defaults_from_the_runs():
    params = inspect.signature(nvib.estimate).parameters
    for k in ("save_every", "dofs", "energy"):
        assert params[k].default == RUN_OPTIONS[k]


@pytest.mark.parametrize("call", [
    lambda: nvib.solve(MODEL, nvib.Newmark(), dt=0.1, t_end=1.0, save_evry=2),
    lambda: nvib.Stepper(MODEL, nvib.Newmark(), 0.1).integrate(1.0, save_evry=2),
    lambda: nvib.solve_many([MODEL, MODEL], nvib.Newmark(), dt=0.1, t_end=1.0, save_evry=2, progress=False),
], ids=["solve", "integrate", "solve_many"])
def test_an_unknown_option_is_refused_naming_it_and_the_closest(call):
    with pytest.raises(TypeError, match=r"^save_evry: not an option of a run; did you mean 'save_every'\?") as exc:
        call()
    assert exc.value.argument == "save_evry"


def test_options_given_reach_the_run():
    res = nvib.solve(MODEL, nvib.Newmark(), dt=0.1, t_end=1.0, save_every=3, energy=True)
    assert len(res.t) == 1 + 3 + 1 and res.energy is not None
    st = nvib.Stepper(MODEL, nvib.Newmark(), 0.1)
    part = st.integrate(1.0, save_every=5)
    assert np.allclose(part.t, [0.0, 0.5, 1.0])


# ---- one way to write a result, one name for Newton's iteration -------------------------------------------

def test_a_result_is_written_one_way(tmp_path):
    assert not hasattr(nvib, "save_result")
    res = nvib.solve(MODEL, nvib.Newmark(), dt=0.1, t_end=1.0)
    res.save(tmp_path / "r.npz", {"scene": "one"})
    with np.load(tmp_path / "r.npz") as f:
        assert str(f["scene"]) == "one"
    with pytest.raises(nvib.ArgumentError, match=r"^path: expected a file ending in .npz, .csv or .nc"):
        res.save(tmp_path / "r.txt")


def test_newtons_iteration_has_one_name():
    n = nvib.Newton(iteration="modified")
    assert n.iteration == "modified" and nvib.Newmark(iteration="modified").newton == n
    assert nvib.Newmark(newton=n).iteration == "modified" and "iteration='modified'" in repr(n)
    assert [p["name"] for p in nvib.Newton.parameters()][0] == "iteration"
    with pytest.raises(TypeError, match=r"^mode: renamed iteration in Newton"):
        nvib.Newton(mode="modified")
