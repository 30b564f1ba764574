"""Pickling and copying: models, schemes, results, counters, failures, ground motions and errors go
to another process and back unchanged (what process pools and Dask need)."""

import copy
import pickle

import numpy as np
import pytest
import scipy.sparse as sp

import nvib


def round_trips(obj):
    return [pickle.loads(pickle.dumps(obj)), copy.copy(obj), copy.deepcopy(obj)]


def python_force(u, v, t):  # module level, so that it pickles by reference
    return 4.0 * u + 0.1 * v + u ** 3


def models():
    n = 50
    i = np.arange(n)
    yield "building", nvib.load_scene("building")
    yield "vehicle (static equilibrium)", nvib.load_scene("vehicle")
    yield "generated chain (names made on demand)", nvib.scenes.chain(200)
    yield "arrays", nvib.Model(np.full(n, 2.0), effects=[
        {"type": "hardening_spring", "i": i, "j": i - 1, "k0": 1e3, "a": np.linspace(1, 3, n)},
        {"type": "damper", "i": i, "j": i - 1, "c": 1.0},
        {"type": "ground_acceleration", "signal": {"kind": "sine", "amplitude": 1.0, "omega": 3.0}}])
    yield "consistent mass, sparse K", nvib.Model(sp.diags([1.0, 4.0, 1.0], [-1, 0, 1], shape=(n, n)) / 6.0,
                                                  K=sp.diags([-1.0, 2.0, -1.0], [-1, 0, 1], shape=(n, n)) * 1e3,
                                                  u0=np.sin(i / 7.0))
    yield "Python force", nvib.Model([1.0, 2.0], force=python_force, u0=[0.1, -0.2], dofs=["a", "b"])
    yield "record", nvib.Model([1.0], effects=[
        {"type": "spring", "measure": {0: 1.0}, "k": 100.0},
        {"type": "ground_acceleration", "signal": nvib.GroundMotion.from_array([0, 1, -1, 0.5, 0], dt=0.05)}])


@pytest.mark.parametrize("name, model", list(models()), ids=[name for name, _ in models()])
def test_model_round_trip_gives_the_same_run(name, model):
    ref = nvib.solve(model, nvib.CEMDTS(), dt=1e-3, t_end=0.2)
    for other in round_trips(model):
        assert other is not model and other._core is not model._core  # a model of its own
        assert other.n == model.n and list(other.dofs) == list(model.dofs) and other.name == model.name
        np.testing.assert_array_equal(other.u0, model.u0)
        assert getattr(other, "scene", None) == getattr(model, "scene", None)
        res = nvib.solve(other, nvib.CEMDTS(), dt=1e-3, t_end=0.2)
        np.testing.assert_array_equal(res.u, ref.u)
        np.testing.assert_array_equal(res.v, ref.v)


def test_a_lambda_force_and_a_closure_law_travel_by_value():
    """A model's lambdas and closures pickle by value (cloudpickle), so the model runs the same elsewhere;
    one that refers to what cannot be pickled (a lock) says what."""
    import threading

    k = 4.0
    model = nvib.Model([1.0], u0=[0.5], force=lambda u, v, t: k * u, effects=[
        {"type": "callable", "measure": {0: 1.0}, "law": lambda d, dd, t: k * d ** 3}])
    other = pickle.loads(pickle.dumps(model))
    np.testing.assert_array_equal(nvib.solve(other, nvib.CEMDTS(), dt=0.01, t_end=1.0).u,
                                  nvib.solve(model, nvib.CEMDTS(), dt=0.01, t_end=1.0).u)
    lock = threading.Lock()
    locked = nvib.Model([1.0], force=lambda u, v, t: lock.locked() * u)
    with pytest.raises(TypeError, match="lock"):
        pickle.dumps(locked)


def test_every_scheme_round_trips(scheme_class):
    s = scheme_class()
    for other in round_trips(s):
        assert type(other) is type(s) and repr(other) == repr(s)


def test_result_stats_and_failure_round_trip():
    model = nvib.load_scene("building")
    res = nvib.solve(model, nvib.Newmark(), dt=1e-3, t_end=0.05, save_every=3, dofs=["x2", "x5"], energy=True)
    for other in round_trips(res):
        for key in ("t", "u", "v", "a"):
            np.testing.assert_array_equal(getattr(other, key), getattr(res, key))
        np.testing.assert_array_equal(other.energy.balance_error, res.energy.balance_error)
        assert other.dofs == res.dofs and other.dof_indices == res.dof_indices
        assert other.stats.as_dict() == res.stats.as_dict() and other.stats.linear_solver == "banded LDLT"
        assert other.status == res.status and other.failure is None
        assert other.max_residual == res.max_residual and other.dt == res.dt and repr(other.scheme) == repr(res.scheme)

    failed = nvib.solve(model, nvib.CentralDifference(), dt=0.05, t_end=5.0, throw=False)
    assert failed.status == nvib.Status.diverged
    for other in round_trips(failed):
        f, g = other.failure, failed.failure
        assert (f.status, f.step, f.t, f.dof, f.message, list(f.residuals)) == (g.status, g.step, g.t, g.dof, g.message,
                                                                              list(g.residuals))
    assert pickle.loads(pickle.dumps(failed.stats)).as_dict() == failed.stats.as_dict()


def test_errors_keep_their_failure_result_and_argument(tmp_path):
    with pytest.raises(nvib.DivergenceError) as exc:
        nvib.solve(nvib.load_scene("building"), nvib.CentralDifference(), dt=0.05, t_end=5.0)
    e = pickle.loads(pickle.dumps(exc.value))
    assert type(e) is nvib.DivergenceError and str(e) == str(exc.value)
    assert (e.step, e.dof, e.t) == (exc.value.step, exc.value.dof, exc.value.t)
    np.testing.assert_array_equal(e.result.u, exc.value.result.u)

    with pytest.raises(nvib.ArgumentError) as exc:
        nvib.CEMDTS(eta=3.0)
    e = pickle.loads(pickle.dumps(exc.value))
    assert type(e) is nvib.ArgumentError and e.argument == "eta" and str(e) == str(exc.value)

    with pytest.raises(nvib.RecordError) as exc:
        nvib.GroundMotion.from_at2(tmp_path / "none.AT2")
    e = pickle.loads(pickle.dumps(exc.value))
    assert str(e) == str(exc.value) and e.path == exc.value.path and e.line is None

    bad = tmp_path / "bad.toml"
    bad.write_text("[dofs]\nnames = [\"x\"]\n", encoding="utf-8")
    with pytest.raises(nvib.SceneError) as exc:
        nvib.load_scene(str(bad))
    e = pickle.loads(pickle.dumps(exc.value))
    assert type(e) is nvib.SceneError and str(e) == str(exc.value)


def test_batch_objects_round_trip():
    import sys
    import os

    sys.path.insert(0, os.path.dirname(__file__))
    from test_batch import motions, two_storeys

    base = two_storeys(motions()[0])
    summaries = nvib.solve_many(base, nvib.CEMDTS(), variations={"storey1.k0": [4e5, "soft"]}, keep="peaks", threads=1,
                                progress=False,
                                dt=1e-3, t_end=0.5)
    spectrum = nvib.spectrum(motions()[0], [0.2, 1.0])
    ida = nvib.ida(base, motions(), [1.0, 2.0], im="scale", measure="peak_drift", dt=1e-3, progress=False)
    for obj in (summaries, summaries[0], summaries[1], spectrum, ida, nvib.Newton(rtol=1e-9, iteration="modified")):
        for other in round_trips(obj):
            assert type(other) is type(obj) and same_state(other, obj)


def same_state(a, b) -> bool:
    """Equal field by field: dataclasses, lists, dicts, arrays, counters, errors."""
    import dataclasses

    if type(a) is not type(b):
        return False
    if dataclasses.is_dataclass(a):
        return all(same_state(getattr(a, f.name), getattr(b, f.name)) for f in dataclasses.fields(a))
    if isinstance(a, (list, tuple)):
        return len(a) == len(b) and all(same_state(x, y) for x, y in zip(a, b)) and \
            same_state(getattr(a, "labels", None), getattr(b, "labels", None))
    if isinstance(a, dict):
        return a.keys() == b.keys() and all(same_state(a[k], b[k]) for k in a)
    if isinstance(a, np.ndarray):
        return np.array_equal(a, b)
    if isinstance(a, nvib.Stats):
        return a.as_dict() == b.as_dict()
    if isinstance(a, BaseException):
        return str(a) == str(b)
    if isinstance(a, nvib.Newton):
        return repr(a) == repr(b)
    return a == b or (isinstance(a, float) and np.isnan(a) and np.isnan(b))
