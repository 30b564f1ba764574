"""Compiled laws: a law compiled elsewhere (Numba's cfunc, or any C function pointer of nvib.LAW_SIGNATURE)
runs as a built-in law does, with no Python in the loop. A compiled law doing a built-in law's arithmetic
gives its trajectories bit for bit under the six schemes, as one effect and as an array; one with memory
follows the trial/commit contract (a failed Newton step leaves its state as it was); an error code stops
the run naming the point; bad input names the argument. The Numba tests skip without Numba (the
``nvib[numba]`` extra); the contract itself is also tested through a ctypes pointer, which needs no compiler."""

from __future__ import annotations

import ctypes

import numpy as np
import pytest

import nvib
from nvib._compiled import ctypes_law

from _compiled_laws import bilinear_py, hardening_py

from _hysteresis import SCHEME_IDS, chain, scheme, step_until_it_fails

SIX = [nvib.CentralDifference(), nvib.CEMDTS(), nvib.Zhai(), nvib.Newmark(), nvib.GeneralizedAlpha(),
       nvib.PreciseIntegration()]
SIX_IDS = ["lcdm", "cemdts", "zhai", "newmark", "galpha", "pim"]


def building_with(law, *, array=False):
    """The paper's building with its storeys' hardening springs as ``law`` (compiled), one effect each or
    one array of six."""
    base = nvib.load_scene("building")
    mass, kw = base._init
    effects, storeys = [], []
    for e in kw["effects"]:
        if e["type"] == "hardening_spring":
            storeys.append(e)
            if not array:
                effects.append({"type": "compiled", "name": e["name"], "measure": e["measure"], "law": law,
                                "params": [e["k0"], e["a"]], "uses_time": False})
        else:
            effects.append(e)
    if array:  # storey k between DOF k and k-1 (the ground for the first)
        n = len(storeys)
        effects.append({"type": "compiled", "i": list(range(n)), "j": [-1] + list(range(n - 1)), "law": law,
                        "params": [[s["k0"] for s in storeys], [s["a"] for s in storeys]], "uses_time": False})
    model = nvib.Model(mass, **{**kw, "effects": effects})
    model.u0, model.v0 = base.u0, base.v0
    return base, model


# ---- with Numba ------------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def numba_laws():
    numba = pytest.importorskip("numba")
    sig = nvib.LAW_SIGNATURE
    return {"hardening": numba.cfunc(sig)(hardening_py), "bilinear": numba.cfunc(sig)(bilinear_py),
            "fails": numba.cfunc(sig)(fails_py)}


def fails_py(p, s, d, dd, t, out, trial):
    """Code 7 beyond d = p[0]; no force before."""
    if d > p[0]:
        return 7
    out[0] = 0.0
    out[1] = 0.0
    out[2] = 0.0
    return 0


@pytest.mark.parametrize("array", [False, True], ids=["effects", "array"])
@pytest.mark.parametrize("sch", SIX, ids=SIX_IDS)
def test_a_compiled_hardening_spring_is_the_built_in_one_bit_for_bit(numba_laws, sch, array):
    base, model = building_with(numba_laws["hardening"], array=array)
    assert not model._core.has_python  # no Python in the loop: the GIL is released
    a = nvib.solve(base, sch, dt=2e-3, t_end=1.0)
    b = nvib.solve(model, sch, dt=2e-3, t_end=1.0)
    np.testing.assert_array_equal(a.u, b.u)
    np.testing.assert_array_equal(a.v, b.v)


@pytest.mark.parametrize("name", SCHEME_IDS)
def test_a_compiled_bilinear_law_is_the_built_in_one_bit_for_bit(numba_laws, name):
    built_in = chain("bilinear")
    mass, kw = built_in._init
    effects = [dict(e) for e in kw["effects"]]
    law = next(e for e in effects if e.get("name") == "law")
    effects[effects.index(law)] = {"type": "compiled", "name": "law", "measure": law["measure"],
                                   "law": numba_laws["bilinear"], "params": [law["k"], law["fy"], law.get("b", 0.0)],
                                   "state": [0.0, 0.0, 0.0], "uses_time": False}
    compiled = nvib.Model(mass, **{**kw, "effects": effects})
    a = nvib.solve(built_in, scheme(name), dt=2e-3, t_end=1.5, record=["law"])
    b = nvib.solve(compiled, scheme(name), dt=2e-3, t_end=1.5, record=["law"])
    np.testing.assert_array_equal(a.u, b.u)
    np.testing.assert_array_equal(a.effects["law"].state["plastic_deformation"], b.effects["law"].state["s0"])
    assert np.ptp(b.effects["law"].state["s0"]) > 0  # it yielded


def test_a_failed_newton_step_leaves_a_compiled_state_as_it_was(numba_laws):
    model = nvib.Model([1.0], dofs=["x"], v0=[2.0], effects=[
        {"type": "compiled", "measure": {"x": 1.0}, "law": numba_laws["bilinear"], "params": [400.0, 4.0, 0.05],
         "state": [0.0, 0.0, 0.0], "uses_time": False}])
    st = nvib.Stepper(model, nvib.Newmark(newton=nvib.Newton(max_iter=1)), 2e-2)
    before, t, _ = step_until_it_fails(st)
    assert st.t == t
    np.testing.assert_array_equal(st.state(), before)  # u, v, a and the law's internal variables
    # the step that failed yields: taken with Newton's default iterations, it moves the plastic deformation
    good = nvib.Stepper(model, nvib.Newmark(), 2e-2)
    good.set_state(before, t=t)
    good.step()
    dp = -model._core.state_size  # the first internal variable
    assert before[dp] == 0.0 and good.state()[dp] != 0.0


def test_an_error_code_stops_the_run_naming_it(numba_laws):
    model = nvib.Model([1.0], u0=[0.5], effects=[
        {"type": "compiled", "measure": {0: 1.0}, "law": numba_laws["fails"], "params": [0.1]},
        {"type": "spring", "measure": {0: 1.0}, "k": 10.0}])
    with pytest.raises(RuntimeError, match=r"a compiled law returned 7 \(not 0\) at d = 0\.5"):
        nvib.solve(model, nvib.CentralDifference(), dt=1e-2, t_end=0.1)
    with pytest.raises(nvib.ArgumentError) as exc:  # its stored energy is not known
        nvib.solve(model, nvib.CentralDifference(), dt=1e-2, t_end=0.1, u0=[0.0], energy=True)
    assert exc.value.argument == "energy" and "compiled law" in str(exc.value)


def test_compiled_laws_run_on_threads_as_serially(numba_laws):
    _, model = building_with(numba_laws["hardening"])
    run = dict(dt=2e-3, t_end=0.5, progress=False, scales=[0.5, 1.0, 1.5, 2.0])
    serial = nvib.solve_many(model, nvib.Newmark(), threads=1, **run)
    threaded = nvib.solve_many(model, nvib.Newmark(), threads=2, **run)
    for a, b in zip(serial, threaded):
        np.testing.assert_array_equal(a.u, b.u)


def test_a_cfunc_of_another_signature_is_refused(numba_laws):
    numba = pytest.importorskip("numba")
    other = numba.cfunc("float64(float64)")(lambda x: x)
    with pytest.raises(nvib.ArgumentTypeError) as exc:
        nvib.Model([1.0], effects=[{"type": "compiled", "measure": {0: 1.0}, "law": other}])
    assert exc.value.argument == "effects[0].law" and "LAW_SIGNATURE" in str(exc.value)


# ---- the contract through a ctypes pointer (no compiler) -------------------------------------------

def test_a_ctypes_pointer_follows_the_contract():
    law = ctypes_law(bilinear_py)
    built_in = chain("bilinear")
    mass, kw = built_in._init
    effects = [dict(e) for e in kw["effects"]]
    spec = next(e for e in effects if e.get("name") == "law")
    effects[effects.index(spec)] = {"type": "compiled", "name": "law", "measure": spec["measure"], "law": law,
                                    "params": [spec["k"], spec["fy"], spec.get("b", 0.0)], "state": [0.0] * 3}
    compiled = nvib.Model(mass, **{**kw, "effects": effects})
    for sch in (nvib.CentralDifference(), nvib.Newmark()):
        a = nvib.solve(built_in, sch, dt=2e-3, t_end=0.5)
        b = nvib.solve(compiled, sch, dt=2e-3, t_end=0.5)
        np.testing.assert_array_equal(a.u, b.u)
    address = ctypes.cast(law, ctypes.c_void_p).value  # the same law by its address
    effects[effects.index(next(e for e in effects if e.get("name") == "law"))]["law"] = address
    by_address = nvib.Model(mass, **{**kw, "effects": effects})
    np.testing.assert_array_equal(nvib.solve(by_address, nvib.Newmark(), dt=2e-3, t_end=0.5).u, b.u)


@pytest.mark.parametrize("change, arg", [
    ({"law": lambda d, dd, t: d}, "effects[0].law"),
    ({"law": -5}, "effects[0].law"),
    ({"params": list(range(9))}, "effects[0].params"),
    ({"state": [0.0] * 9}, "effects[0].state"),
    ({"state": []}, "effects[0].state"),
    ({"uses_time": 1}, "effects[0].uses_time"),
    ({"tangent": None}, "effects[0].tangent"),
])
def test_bad_input_names_the_argument(change, arg):
    spec = {"type": "compiled", "measure": {0: 1.0}, "law": ctypes_law(hardening_py), "params": [1.0, 0.0]}
    with pytest.raises((nvib.ArgumentError, nvib.ArgumentTypeError)) as exc:
        nvib.Model([1.0], effects=[{**spec, **change}])
    assert exc.value.argument == arg


# ---- batches -----------------------------------------------------------------------------------------

def test_a_numba_law_travels_as_its_python_function_compiled_again(numba_laws):
    """A cfunc's machine code does not pickle: a model travels with the law's Python function, compiled again
    where it lands, so processes and Dask give the runs made here."""
    import pickle

    _, model = building_with(numba_laws["hardening"])
    here = nvib.solve(model, nvib.Newmark(), dt=2e-3, t_end=0.5)
    np.testing.assert_array_equal(nvib.solve(pickle.loads(pickle.dumps(model)), nvib.Newmark(), dt=2e-3,
                                             t_end=0.5).u, here.u)
    run = dict(dt=2e-3, t_end=0.5, progress=False, scales=[0.5, 1.0])
    serial = nvib.solve_many(model, nvib.Newmark(), threads=1, **run)
    for other in (nvib.solve_many(model, nvib.Newmark(), threads=2, processes=True, **run),):
        for a, b in zip(serial, other):
            np.testing.assert_array_equal(a.u, b.u)


def test_a_numba_law_runs_on_a_dask_cluster(numba_laws):
    distributed = pytest.importorskip("dask.distributed")
    _, model = building_with(numba_laws["hardening"])
    run = dict(dt=2e-3, t_end=0.5, progress=False, scales=[0.5, 1.0, 1.5])
    serial = nvib.solve_many(model, nvib.Newmark(), threads=1, **run)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        remote = nvib.solve_many(model, nvib.Newmark(), client=client, **run)
    for a, b in zip(serial, remote):
        np.testing.assert_array_equal(a.u, b.u)


def test_a_law_given_by_its_address_stays_in_its_process():
    """A ctypes pointer (or an address) names code in this process only: going to processes is refused before
    any starts, naming the law; threads run it."""
    _, model = building_with(ctypes_law(hardening_py))
    run = dict(dt=2e-3, t_end=0.05, progress=False, scales=[0.5, 1.0])
    with pytest.raises(nvib.ArgumentTypeError) as exc:
        nvib.solve_many(model, nvib.Newmark(), threads=2, processes=True, **run)
    assert exc.value.argument == "models.effects[0].law" and "by its address" in str(exc.value)
    assert not nvib.solve_many(model, nvib.Newmark(), threads=2, **run).failed


def test_a_python_function_given_as_a_compiled_law_says_how_to_compile_it(monkeypatch):
    import importlib.util

    spec = {"type": "compiled", "measure": {0: 1.0}, "law": hardening_py, "params": [1.0, 0.0]}
    real = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec", lambda name, *a: None if name == "numba" else real(name, *a))
    with pytest.raises(nvib.ArgumentTypeError) as exc:
        nvib.Model([1.0], effects=[spec])
    assert exc.value.argument == "effects[0].law" and 'pip install "nvib[numba]"' in str(exc.value)
