"""Commits equal accepted steps, exactly: the internal variables a run records at every step are those of
the law driven alone (nvib.drive) along the recorded deformations, bit for bit, in every scheme; a step
that fails leaves every internal variable as it was; Stepper.state()/set_state() carry them and a run
continues bit for bit; a copied or pickled model gives the same runs; threads give what serial runs do."""

from __future__ import annotations

import copy
import pickle

import numpy as np
import pytest

import nvib

from _hysteresis import (LAW_CASES, MEMORY_NAMES, SCHEME_IDS, chain, law_type, laws_with_memory, memory_chain, scheme,
                         step_until_it_fails)

MEMORY_CASES = [c for c in LAW_CASES if law_type(c) in laws_with_memory()]


@pytest.mark.parametrize("name", SCHEME_IDS)
@pytest.mark.parametrize("case", MEMORY_CASES)
def test_recorded_internal_variables_are_the_law_driven_along_the_run(case, name):
    """Each accepted step commits one trial from the committed state at the accepted deformation (these
    laws read the deformation only), and nothing else: drive() does exactly that along the recorded
    deformations, so every internal variable at every step agrees bit for bit, whatever the scheme's
    iterations, alpha-point or predictor tried in between. (The incremental format included: however
    inaccurate its steps, each accepted one is committed so.)"""
    params, _ = LAW_CASES[case]
    res = nvib.solve(chain(case), scheme(name), dt=2e-3, t_end=1.5, record=["law"], save_every=1)
    rec = res.effects["law"]
    assert len(rec.measure) == 751
    driven = nvib.drive(dict(params, type=law_type(case)), rec.measure)
    assert set(driven.state) == set(rec.state) == set(rec.state_names)
    for key in rec.state_names:
        np.testing.assert_array_equal(rec.state[key], driven.state[key], err_msg=key)
    # the recorded force is the law at its committed state: the driven force, to round-off (a new trial
    # of zero increment recomputes k (d - dp) where the driven trial subtracted the slip)
    np.testing.assert_allclose(rec.force, driven.force, rtol=1e-12, atol=1e-12 * np.abs(driven.force).max())
    assert LAW_CASES[case][1](rec)  # and it did yield on the way


# ---------------------------------------------------------------------------
# a failed step


FAILING = [
    # (id, scheme): Newton allowed too few iterations for a yielding step
    ("Newmark-newton-1_iteration", nvib.Newmark(newton=nvib.Newton(max_iter=1))),
    ("Newmark-modified-2_iterations", nvib.Newmark(newton=nvib.Newton(iteration="modified", max_iter=2))),
    ("Newmark-initial-2_iterations", nvib.Newmark(newton=nvib.Newton(iteration="initial", max_iter=2))),
    ("GeneralizedAlpha-1_iteration", nvib.GeneralizedAlpha(newton=nvib.Newton(max_iter=1))),
    ("HHT-1_iteration", nvib.GeneralizedAlpha.hht(-0.1, newton=nvib.Newton(max_iter=1))),
]


def _enough(sch):
    """The same scheme with Newton's defaults (20 iterations)."""
    if isinstance(sch, nvib.Newmark):
        return nvib.Newmark(newton=nvib.Newton(iteration=sch.newton.iteration))
    return nvib.GeneralizedAlpha(sch.alpha_m, sch.alpha_f, sch.beta, sch.gamma)


def check_the_failed_step_changed_nothing(st, before, t, k, model):
    assert st.t == t and st.step_index == k
    np.testing.assert_array_equal(st.state(), before)  # u, v, a and every internal variable, bit for bit
    with pytest.raises(nvib.ConvergenceError):  # the same step fails again, the same way ...
        st.step()
    np.testing.assert_array_equal(st.state(), before)  # ... and still changes nothing
    assert before[-model._core.state_size:].size == model._core.state_size


@pytest.mark.parametrize("sch", [f[1] for f in FAILING], ids=[f[0] for f in FAILING])
def test_a_failed_step_leaves_every_internal_variable(sch):
    """The chain yields under the default Newton for 0.3 s; a stepper allowed too few iterations is
    given that state and steps until a yielding step fails."""
    model = memory_chain()
    good = nvib.Stepper(model, _enough(sch), 1e-3)
    good.step(300)
    x, t0 = good.state(), good.t
    st = nvib.Stepper(model, sch, 1e-3)
    st.set_state(x, t=t0)
    before, t, k = step_until_it_fails(st)
    check_the_failed_step_changed_nothing(st, before, t, k, model)
    internal = before[-model._core.state_size:]
    assert internal[0] != 0.0  # the bilinear storey's plastic deformation: it had yielded
    # up to the failure it ran as the default Newton does (each step converged in the iterations it had);
    # that stepper takes the failed step from the same state. The initial-tangent mode is the exception:
    # the fresh stepper's tangent is the one at the restored state (the storeys yielding), the run's the
    # one at t = 0 (elastic), so the two agree to Newton's tolerance, not bit for bit.
    good.step(k) if k > 0 else None
    if sch.newton.iteration == "initial":
        np.testing.assert_allclose(good.state(), before, rtol=0, atol=1e-8 * np.abs(before).max())
    else:
        np.testing.assert_array_equal(good.state(), before)
    good.step()


def test_a_too_large_step_leaves_every_internal_variable():
    """Generalized-alpha at dt = 0.3 s on an IMK law softening steeply past its capping point: Newton
    cycles between the law's branches and gives up at step 45; nothing of the step remains."""
    model = nvib.Model([1.0], dofs=["x"], v0=[3.0], effects=[
        {"type": "imk_peak_oriented", "measure": {"x": 1.0}, "k": 100.0, "fy": 2.0, "up": 0.01, "upc": 0.02,
         "uu": 5.0, "fcap_fy": 1.1, "fres_fy": 0.5}])
    st = nvib.Stepper(model, nvib.GeneralizedAlpha(), 0.3)
    before, t, k = step_until_it_fails(st)
    assert k == 44
    check_the_failed_step_changed_nothing(st, before, t, k, model)
    assert before[-3] != 0.0  # the IMK law's accumulated energy (its third-to-last internal variable)


def test_a_failed_step_within_a_run():
    """solve() stops on the failed step with the history up to the step before it."""
    sch = nvib.Newmark(newton=nvib.Newton(max_iter=1))
    model = memory_chain(shaking=8.0, v0=[0.0, 0.0, 0.0])
    res = nvib.solve(model, sch, dt=1e-3, t_end=2.0, throw=False, record=MEMORY_NAMES)
    assert res.status == nvib.Status.newton_failed and len(res.t) > 10
    assert res.failure.step == len(res.t) and "did not converge" in res.failure.message
    st = nvib.Stepper(model, sch, 1e-3)
    st.step(len(res.t) - 1)
    np.testing.assert_array_equal(st.u, res.u[-1])
    # the internal variables at the last saved state are the stepper's, grouped by law in the order of the
    # registry (nvib._core.laws()), effects in their declared order within a law
    last = [res.effects[n].state[k][-1] for n in ("bilinear", "bouc_wen", "bouc_wen_euler", "friction", "imk")
            for k in res.effects[n].state_names]
    np.testing.assert_array_equal(st.state()[-len(last):], last)


# ---------------------------------------------------------------------------
# state() / set_state()


@pytest.mark.parametrize("name", SCHEME_IDS)
def test_set_state_continues_bit_for_bit(name):
    """From the carried state (u, v, a, the scheme's history, the internal variables) a run continues
    exactly: on the same stepper rewound to it, and on a fresh stepper given it. The model has neither
    loads nor time, so the restarted clock (t + k dt, not (n + k) dt) cannot enter."""
    model = memory_chain()
    sch = scheme(name)
    st = nvib.Stepper(model, sch, 1e-3)
    st.step(300)
    x, t = st.state(), st.t
    assert x.size == len(st.state()) and np.any(x[-model._core.state_size:] != 0.0)
    st.step(300)
    end = st.state()
    st.set_state(x, t=t)  # rewound
    np.testing.assert_array_equal(st.state(), x)
    st.step(300)
    np.testing.assert_array_equal(st.state(), end)
    fresh = nvib.Stepper(model, sch, 1e-3)
    fresh.set_state(x, t=t)
    fresh.step(300)
    if name == "Newmark-initial":
        # its iteration matrix is formed once, at the first step a stepper takes: the fresh one forms
        # it at x, the run formed it at t = 0; both converge, to within Newton's tolerance
        np.testing.assert_allclose(fresh.state(), end, rtol=1e-8, atol=1e-10)
    else:
        np.testing.assert_array_equal(fresh.state(), end)


def test_set_state_with_other_internal_variables_changes_the_run():
    """The internal variables in the state are used: a different plastic deformation moves the storey."""
    model = memory_chain(v0=[0.0, 0.0, 0.0])
    st = nvib.Stepper(model, nvib.Newmark(), 1e-3)
    x = st.state()
    n = model.n
    x[3 * n] = 0.005  # the bilinear storey's plastic deformation (its force 400 (0 - 0.005), within fy = 4)
    x[2 * n] = 2.0    # and the acceleration it gives the first mass: -(-2) / 1
    st.set_state(x, t=0.0)
    st.step(10)
    assert st.u[0] == pytest.approx(0.5 * 2.0 * 0.01**2, rel=0.05)  # pulled toward the offset
    assert st.state()[3 * n] == 0.005
    rest = nvib.Stepper(model, nvib.Newmark(), 1e-3)
    rest.step(10)
    np.testing.assert_array_equal(rest.u, np.zeros(3))  # at rest it stays at rest


# ---------------------------------------------------------------------------
# copies, pickles, threads


def same_run(a, b):
    for key in ("t", "u", "v", "a"):
        np.testing.assert_array_equal(getattr(a, key), getattr(b, key), err_msg=key)
    assert a.status == b.status
    for name in MEMORY_NAMES:
        for key in a.effects[name].state_names:
            np.testing.assert_array_equal(a.effects[name].state[key], b.effects[name].state[key])
    if a.energy is not None:
        np.testing.assert_array_equal(a.energy.hysteretic, b.energy.hysteretic)


RUN = dict(dt=1e-3, t_end=2.0, record=MEMORY_NAMES, energy=True)


@pytest.mark.parametrize("name", ["CEMDTS", "Newmark-newton", "GeneralizedAlpha", "PreciseIntegration"])
def test_copied_and_pickled_models_give_the_same_run(name):
    model = memory_chain()
    ref = nvib.solve(model, scheme(name), **RUN)
    for other in (pickle.loads(pickle.dumps(model)), copy.copy(model), copy.deepcopy(model)):
        assert other._core is not model._core and other._core.state_size == model._core.state_size
        same_run(nvib.solve(other, scheme(name), **RUN), ref)
    # a run leaves the model's own committed states alone: it runs on a copy
    st = nvib.Stepper(model, scheme(name), 1e-3)
    st.step(500)
    same_run(nvib.solve(model, scheme(name), **RUN), ref)
    same_run(nvib.solve(pickle.loads(pickle.dumps(model)), scheme(name), **RUN), ref)


@pytest.mark.parametrize("name", ["CEMDTS", "Newmark-newton", "GeneralizedAlpha"])
def test_threads_give_the_serial_runs(name):
    """One model object shared by every run of a thread pool (each run copies it, states and all) and
    models that differ: two threads give the serial runs bit for bit."""
    model = memory_chain()
    models = [model] * 4 + [memory_chain(v0=[1.5 * s, -1.0, 2.0 * s]) for s in (0.5, 0.8, 1.2, 1.4)]
    kw = dict(dt=2e-4, t_end=2.0, save_every=10, record=MEMORY_NAMES, energy=True, progress=False)
    serial = nvib.solve_many(models, scheme(name), threads=1, **kw)
    threaded = nvib.solve_many(models, scheme(name), threads=2, **kw)
    assert not serial.failed and not threaded.failed
    for a, b in zip(serial, threaded):
        same_run(a, b)
    for k in range(1, 4):  # the shared model's runs are one run
        same_run(serial[0], serial[k])
    alone = nvib.solve(models[5], scheme(name), **{k: v for k, v in kw.items() if k != "progress"})
    same_run(alone, threaded[5])
