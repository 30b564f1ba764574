"""solve_many: every way of making runs gives the same results as the runs made one by one, in input
order, on threads or processes; failures stay in their own result; summaries equal what the
history says; a Dask cluster gives the same results (skipped without dask.distributed)."""

import os
import pickle
import signal

import numpy as np
import pytest

import nvib
from nvib import GroundMotion


def two_storeys(signal=None, a=50.0):
    """Two hardening storeys (a = 0: linear ones) on a shaking ground, by default the "decay" motion."""
    signal = motions()[0] if signal is None else signal
    return nvib.Model([1e3, 1e3], dofs=["x1", "x2"], effects=[
        {"type": "hardening_spring", "name": "storey1", "measure": {"x1": 1.0}, "k0": 4e5, "a": a},
        {"type": "hardening_spring", "name": "storey2", "measure": {"x2": 1.0, "x1": -1.0}, "k0": 3e5, "a": a},
        {"type": "damper", "name": "d1", "measure": {"x1": 1.0}, "c": 500.0},
        {"type": "ground_acceleration", "name": "ground", "signal": signal}])


def motions():
    t = np.arange(400) * 0.005
    return [GroundMotion.from_array(np.sin(5 * t) * np.exp(-t), dt=0.005, name="decay"),
            GroundMotion.from_array(np.sign(np.sin(13 * t)), dt=0.005, name="square")]


RUN = dict(dt=1e-3, t_end=2.5)


def same(a, b):
    for key in ("t", "u", "v", "a"):
        np.testing.assert_array_equal(getattr(a, key), getattr(b, key))
    assert a.status == b.status


def test_motions_times_scales_equal_single_runs():
    base = two_storeys({"kind": "sine", "amplitude": 1.0, "omega": 2.0})
    scales = [0.5, 2.0, 4.0]
    batch = nvib.solve_many(base, nvib.CEMDTS(), ground_motions=motions(), scales=scales, progress=False, **RUN)
    assert len(batch) == 6 and not batch.failed
    k = 0
    for gm in motions():
        for s in scales:
            assert batch.labels[k] == {"ground_motion": gm.name, "scale": s, "scheme": "CEMDTS(0.45)"}
            same(batch[k], nvib.solve(two_storeys(gm.scaled(s)), nvib.CEMDTS(), **RUN))
            k += 1


def test_scales_alone_scale_the_model_own_signal():
    base = two_storeys({"kind": "sine", "amplitude": 1.0, "omega": 2.0})
    batch = nvib.solve_many(base, nvib.Newmark(), scales=[3.0], progress=False, **RUN)
    same(batch[0], nvib.solve(two_storeys({"kind": "sine", "amplitude": 3.0, "omega": 2.0}), nvib.Newmark(), **RUN))


def consistent_mass_bar(signal, n=30):
    """A fixed-free bar of n two-node elements with its consistent mass (not lumped: factorised by Cholesky),
    Rayleigh damping, a hardening spring at the tip and the ground shaking it."""
    import scipy.sparse as sp

    k, m = 2e6, 1.0
    main, off = np.full(n, 2.0), np.full(n - 1, -1.0)
    main[-1] = 1.0
    K = sp.diags([off, main, off], [-1, 0, 1], format="csc") * k
    mm, mo = np.full(n, 4.0), np.full(n - 1, 1.0)
    mm[-1] = 2.0
    M = sp.diags([mo, mm, mo], [-1, 0, 1], format="csc") * (m / 6.0)
    return nvib.Model(M, K=K, C=0.5 * M + 1e-4 * K, effects=[
        {"type": "hardening_spring", "name": "tip", "measure": {n - 1: 1.0}, "k0": 1e5, "a": 1e4},
        {"type": "ground_acceleration", "name": "ground", "measure": {i: float(M[i].sum()) for i in range(n)},
         "signal": signal}])


def test_a_batch_model_shares_its_factorised_mass_and_runs_as_a_model_built_anew():
    """The models of a batch are the given one with other signals or parameters: they share its mass,
    factorised once, and run bit for bit as a model built from the same arguments; the shared mass outlives
    the model it came from."""
    import gc

    base = consistent_mass_bar({"kind": "sine", "amplitude": 1.0, "omega": 20.0})
    assert base._core.mass_kind == "sparse"
    changed = [dict(e) for e in base._init[1]["effects"]]
    changed[0]["k0"] = 2e5
    changed[1]["signal"] = {"kind": "sine", "amplitude": 3.0, "omega": 20.0}
    derived = base._rebuilt(effects=changed)
    fresh = nvib.Model(base._init[0], **{**base._init[1], "effects": changed})
    for scheme, dt in ((nvib.CentralDifference(), 1e-4), (nvib.Newmark(), 1e-3)):
        run = dict(dt=dt, t_end=0.05)
        expected = nvib.solve(fresh, scheme, **run)
        same(nvib.solve(derived, scheme, **run), expected)
    del base
    gc.collect()
    same(nvib.solve(derived, nvib.Newmark(), dt=1e-3, t_end=0.05), expected)
    batch = nvib.solve_many(derived, nvib.Newmark(), scales=[0.5, 2.0], progress=False, dt=1e-3, t_end=0.05)
    for s, res in zip([0.5, 2.0], batch):
        spec = [dict(e) for e in changed]
        spec[1]["signal"] = {"kind": "sine", "amplitude": 3.0 * s, "omega": 20.0}
        same(res, nvib.solve(nvib.Model(derived._init[0], **{**derived._init[1], "effects": spec}), nvib.Newmark(),
                             dt=1e-3, t_end=0.05))
    with pytest.raises(ValueError, match="keeps the mass"):
        derived._rebuilt(mass=np.ones(30))


def test_variations_and_one_scheme_per_run():
    base = two_storeys(motions()[0])
    ks = [2e5, 4e5, 8e5]
    schemes = [nvib.CentralDifference(), nvib.Zhai(), nvib.GeneralizedAlpha()]
    batch = nvib.solve_many(base, schemes, variations={"storey1.k0": ks, "d1.c": [0.0, 100.0, 900.0]},
                            progress=False, **RUN)
    for k, (kk, c, sc) in enumerate(zip(ks, [0.0, 100.0, 900.0], schemes)):
        m = two_storeys(motions()[0])
        spec = m._init[1]["effects"]
        spec[0]["k0"], spec[2]["c"] = kk, c
        same(batch[k], nvib.solve(nvib.Model(m._init[0], **m._init[1]), sc, **RUN))
        assert batch.labels[k]["storey1.k0"] == kk and batch.labels[k]["scheme"] == nvib.scheme_label(sc)


def test_threads_match_one_thread_and_processes():
    base = two_storeys(motions()[1])
    kw = dict(scales=list(np.linspace(0.2, 3.0, 9)), progress=False, **RUN)
    one = nvib.solve_many(base, nvib.CEMDTS(), threads=1, **kw)
    for other in (nvib.solve_many(base, nvib.CEMDTS(), threads=2, **kw),
                  nvib.solve_many(base, nvib.CEMDTS(), threads=2, processes=True, **kw)):
        for a, b in zip(one, other):
            same(a, b)


def duffing(u, v, t):  # module level: a model calling Python goes to processes, which pickle it
    return 4.0 * u + 0.2 * v + u ** 3 - np.cos(1.3 * t)


def test_python_models_run_in_processes():
    models = [nvib.Model([1.0], force=duffing, u0=[x]) for x in (0.0, 0.5, 1.0)]
    batch = nvib.solve_many(models, nvib.CEMDTS(), threads=2, progress=False, dt=0.01, t_end=3.0)
    for m, r in zip(models, batch):
        same(r, nvib.solve(m, nvib.CEMDTS(), dt=0.01, t_end=3.0))
    assert [lab["model"] for lab in batch.labels] == [0, 1, 2]


def lambda_models():
    """A lambda force and a closure law (the README's own style): they go to processes by value."""
    stiffness = 100.0

    def law(d, dd, t):  # a closure over stiffness
        return stiffness * d + 0.1 * d ** 3

    lam = nvib.Model([1.0], force=lambda u, v, t: 4.0 * u + 0.1 * v, u0=[0.5])
    closure = nvib.Model([1.0], effects=[{"type": "callable", "measure": {0: 1.0}, "law": law},
                                         {"type": "ground_acceleration",
                                          "signal": {"kind": "sine", "amplitude": 1.0, "omega": 3.0}}])
    return lam, closure


def test_lambdas_and_closures_run_in_processes_as_serially():
    lam, closure = lambda_models()
    run = dict(progress=False, dt=0.01, t_end=1.0)
    for kw in (dict(threads=2), dict(threads=2, processes=True)):
        batch = nvib.solve_many([lam, closure], nvib.CEMDTS(), **kw, **run)
        for m, r in zip((lam, closure), batch):
            same(r, nvib.solve(m, nvib.CEMDTS(), dt=0.01, t_end=1.0))
    batch = nvib.solve_many(closure, nvib.CEMDTS(), scales=[1.0, 2.0], threads=2, **run)
    serial = nvib.solve_many(closure, nvib.CEMDTS(), scales=[1.0, 2.0], threads=1, **run)
    for a, b in zip(batch, serial):
        same(a, b)


def test_a_callable_that_cannot_travel_is_named_before_any_process_starts():
    """A callable that refers to what cannot be pickled (a lock) cannot go to a worker process: the error
    names it and what to do, instead of a bare PicklingError out of the pool. Threads take it as it is."""
    import threading

    good = nvib.Model([1.0], force=duffing, u0=[0.5])
    lock = threading.Lock()

    def locked(u, v, t):
        with lock:
            return 4.0 * u

    bad = nvib.Model([1.0], force=locked, u0=[0.5])
    with pytest.raises(nvib.ArgumentTypeError) as exc:
        nvib.solve_many([good, bad], nvib.CEMDTS(), threads=2, progress=False, dt=0.01, t_end=0.1)
    assert exc.value.argument == "models[1].force"
    assert "locked cannot be pickled" in str(exc.value) and "_thread.lock" in str(exc.value)
    assert "threads=1, or processes=False" in str(exc.value)

    def law(d, dd, t):
        with lock:
            return 100.0 * d

    one = nvib.Model([1.0], effects=[{"type": "callable", "measure": {0: 1.0}, "law": law},
                                     {"type": "ground_acceleration", "signal": {"kind": "sine", "amplitude": 1.0,
                                                                                "omega": 3.0}}])
    with pytest.raises(nvib.ArgumentTypeError) as exc:
        nvib.solve_many(one, nvib.CEMDTS(), scales=[1.0, 2.0], threads=2, progress=False, dt=0.01, t_end=0.1)
    assert exc.value.argument == "models.effects[0].law" and "law cannot be pickled" in str(exc.value)
    for kw in (dict(threads=1), dict(threads=2, processes=False)):
        batch = nvib.solve_many([good, bad], nvib.CEMDTS(), progress=False, dt=0.01, t_end=0.1, **kw)
        assert batch.failed == []


def exits(u, v, t):  # module level, so that it pickles: the worker running it ends
    os._exit(3)


def killed(u, v, t):
    os.kill(os.getpid(), signal.SIGKILL)


@pytest.mark.skipif(os.name != "posix", reason="SIGKILL")
def test_a_worker_that_dies_names_its_run_and_the_others_are_kept():
    models = [nvib.Model([1.0], force=duffing, u0=[0.1 * k]) for k in range(8)]
    models[2] = nvib.Model([1.0], force=exits, u0=[0.2])
    models[5] = nvib.Model([1.0], force=killed, u0=[0.5])
    batch = nvib.solve_many(models, nvib.CEMDTS(), threads=2, progress=False, dt=0.01, t_end=1.0)
    assert batch.failed == [2, 5]
    assert isinstance(batch[2], nvib.RunError) and batch[2].label["model"] == 2
    assert "its worker process died (exited with status 3)" in batch[2].message
    assert "its worker process died (killed by SIGKILL)" in batch[5].message
    for k in (0, 1, 3, 4, 6, 7):
        same(batch[k], nvib.solve(models[k], nvib.CEMDTS(), dt=0.01, t_end=1.0))


def test_a_failed_run_keeps_its_status_and_the_others_go_on():
    base = two_storeys(motions()[0])
    batch = nvib.solve_many(base, nvib.CentralDifference(), variations={"storey1.k0": [4e5, 4e12, "soft"]},
                            threads=2, progress=False, **RUN)
    assert batch[0].success and batch.failed == [1, 2]
    assert batch[1].status == nvib.Status.diverged and "diverged" in batch[1].failure.message
    assert isinstance(batch[2], nvib.RunError) and "effects[0].k0" in batch[2].message
    back = pickle.loads(pickle.dumps(batch))
    assert back.labels == batch.labels and back.failed == batch.failed


def test_peaks_summary_equals_the_history():
    base = two_storeys(motions()[0])
    hist = nvib.solve_many(base, nvib.CEMDTS(), scales=[1.0, 2.0], progress=False, energy=True, **RUN)
    peaks = nvib.solve_many(base, nvib.CEMDTS(), scales=[1.0, 2.0], keep="peaks", progress=False, energy=True, **RUN)
    for h, p in zip(hist, peaks):
        assert isinstance(p, nvib.RunSummary) and p.success and p.label["scale"] in (1.0, 2.0)
        np.testing.assert_array_equal(p.peak_u, np.max(np.abs(h.u), axis=0))
        assert p.peak_measures["storey1"] == np.max(np.abs(h.u[:, 0]))
        assert p.peak_measures["storey2"] == np.max(np.abs(h.u[:, 1] - h.u[:, 0]))
        assert "ground" not in p.peak_measures  # a load has no measure worth a peak
        np.testing.assert_array_equal(p.u_final, h.u[-1])
        assert p.t_final == h.t[-1] and p.energy_error == h.energy.relative_balance_error() < 0.05


def test_arguments_are_checked_and_named():
    base = two_storeys(motions()[0])
    cases = [(dict(keep="all"), "keep"), (dict(variations={"storey9.k0": [1.0]}), "variations['storey9.k0']"),
             (dict(variations={"storey1.zz": [1.0]}), "variations['storey1.zz']"),
             (dict(variations={"storey1.k0": [1.0], "d1.c": [1.0, 2.0]}), "variations")]
    for kw, arg in cases:
        with pytest.raises(nvib.ArgumentError) as exc:
            nvib.solve_many(base, nvib.CEMDTS(), progress=False, **kw, **RUN)
        assert exc.value.argument == arg
    with pytest.raises(nvib.ArgumentError) as exc:
        nvib.solve_many([base, base], nvib.CEMDTS(), scales=[2.0], **RUN)
    assert exc.value.argument == "scales"
    with pytest.raises(nvib.ArgumentError) as exc:
        nvib.solve_many([base, base], [nvib.CEMDTS()] * 3, **RUN)
    assert exc.value.argument == "scheme"
    # a model without a ground acceleration cannot be scaled: that run's RunError says so
    r = nvib.solve_many(nvib.Model([1.0], effects=[{"type": "spring", "measure": {0: 1.0}, "k": 1.0}]),
                        nvib.CEMDTS(), scales=[2.0], threads=1, progress=False, **RUN)[0]
    assert isinstance(r, nvib.RunError) and "no ground_acceleration effect" in r.message


def test_dask_local_cluster_gives_the_same_results():
    distributed = pytest.importorskip("dask.distributed")
    base = two_storeys(motions()[0])
    kw = dict(scales=[0.5, 1.0, 1.5, 2.0, 2.5], progress=False, **RUN)
    local = nvib.solve_many(base, nvib.CEMDTS(), **kw)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        remote = nvib.solve_many(base, nvib.CEMDTS(), client=client, **kw)
    assert remote.labels == local.labels
    for a, b in zip(local, remote):
        same(a, b)
    # models with a lambda and a closure go to the workers by value
    lam, closure = lambda_models()
    run = dict(progress=False, dt=0.01, t_end=1.0)
    serial = nvib.solve_many([lam, closure], nvib.CEMDTS(), threads=1, **run)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        remote = nvib.solve_many([lam, closure], nvib.CEMDTS(), client=client, **run)
    for a, b in zip(serial, remote):
        same(a, b)


def test_each_run_may_have_its_own_end_time():
    base = two_storeys()
    ends = [0.3, 0.7]
    batch = nvib.solve_many(base, nvib.CEMDTS(), dt=1e-3, t_end=ends, ground_motions=motions(), progress=False)
    for gm, end, res in zip(motions(), ends, batch):
        same(res, nvib.solve(two_storeys(gm), nvib.CEMDTS(), dt=1e-3, t_end=end))
    for t_end, arg in (([0.3], "t_end"), ([0.3, -1.0], "t_end[1]"), ([0.3, float("nan")], "t_end[1]")):
        with pytest.raises(nvib.ArgumentError) as exc:
            nvib.solve_many(base, nvib.CEMDTS(), dt=1e-3, t_end=t_end, ground_motions=motions(), progress=False)
        assert exc.value.argument == arg
