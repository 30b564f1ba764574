"""Ctrl-C stops a long run of a C++-only model (no Python in the loop, the GIL
released): the C++ work polls for signals on a clock, about every 50 ms of
work, at every factorisation and between the products of PIM's set-up. A
real SIGINT is sent to the process from another thread while the main thread
is inside the C++ loop."""

from __future__ import annotations

import os
import signal
import threading
import time

import numpy as np
import pytest

import nvib

pytestmark = pytest.mark.skipif(not hasattr(signal, "pthread_kill"), reason="needs POSIX signals")

DELAY = 0.3  # s before the signal


def hardening():
    model = nvib.load_scene("hardening")
    assert not model._core.has_python  # C++ only: the GIL is released during the run
    return model


@pytest.fixture
def python_sigint_handler():
    """The interpreter's own SIGINT handler (KeyboardInterrupt), whatever the test runner installed."""
    old = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, old)


def interrupt_after(delay: float) -> dict:
    sent = {}

    def fire():
        sent["at"] = time.perf_counter()
        os.kill(os.getpid(), signal.SIGINT)

    threading.Timer(delay, fire).start()
    return sent


@pytest.mark.parametrize("scheme", [nvib.CentralDifference(), nvib.Newmark(), nvib.PreciseIntegration()],
                         ids=lambda s: type(s).__name__)
def test_sigint_stops_a_long_cpp_only_solve(scheme, python_sigint_handler):
    # 1e13 steps: days of work, so only the interrupt can end it
    model = hardening()  # before the timer starts: a failure here must not leave a signal in flight
    sent = interrupt_after(DELAY)
    with pytest.raises(KeyboardInterrupt) as info:
        nvib.solve(model, scheme, dt=1e-3, t_end=1e10, save_every=10**12)
    assert "at" in sent
    # stopped inside the C++ loop, which hands over the steps it took: some, far fewer than 1e13
    steps = info.value.result.stats.num_steps
    assert 0 < steps < 10**12, steps


def test_sigint_stops_stepper_integrate_and_the_stepper_stays_usable(python_sigint_handler):
    st = nvib.Stepper(hardening(), nvib.CEMDTS(), 1e-3)  # before the timer starts
    sent = interrupt_after(DELAY)
    with pytest.raises(KeyboardInterrupt) as info:
        st.integrate(1e10, save_every=10**12)
    assert "at" in sent
    assert 0 < info.value.result.stats.num_steps < 10**12
    # the stepper holds the state reached when the run stopped, and continues from it
    t = st.t
    assert t > 0.0
    res = st.integrate(t + 0.01)
    assert res.success and res.t[0] == t


@pytest.mark.skipif(not hasattr(signal, "pthread_kill"), reason="needs POSIX signals")
def test_sigint_stops_a_run_whose_steps_take_a_second(python_sigint_handler):
    """Signals are polled on a clock (about every 50 ms of work, and at every factorisation), not every
    few thousand steps: a 160,000-DOF lattice whose Newmark steps take about a second (two sparse
    factorisations each) stops long before the end of its 1000 steps. How soon after the signal it
    stops is not asserted: that would be a bound on wall time."""
    model = nvib.scenes.lattice(400, 400)
    u0 = np.full(model.n, 1e-3)
    t = time.perf_counter()
    nvib.Stepper(model, nvib.Newmark(), 1e-3, u0=u0).step()
    step = time.perf_counter() - t  # only to send the signal after the first steps
    sent = interrupt_after(max(1.0, 1.5 * step))
    with pytest.raises(KeyboardInterrupt) as info:
        nvib.solve(model, nvib.Newmark(), dt=1e-3, t_end=1.0, u0=u0, save_every=10**6)
    assert "at" in sent
    steps = info.value.result.stats.num_steps
    assert steps < 1000 and info.value.result.stats.num_factorizations >= 1, steps


def test_sigint_stops_the_set_up_of_precise_integration(python_sigint_handler):
    """PIM's dense set-up (O(n^3), tens of seconds at 600 DOFs) polls between its matrix products.
    Stopped in the set-up, the run has taken no step and no history comes with the KeyboardInterrupt;
    had the set-up not polled, the signal would have been taken in the 10^4 steps after it (seconds
    of dense products), and the interrupt would carry the steps taken as ``result``."""
    model = nvib.scenes.chain(600)
    sent = interrupt_after(DELAY)
    with pytest.raises(KeyboardInterrupt) as info:
        nvib.solve(model, nvib.PreciseIntegration(), dt=1e-3, t_end=10.0, save_every=10**6)
    assert "at" in sent
    assert not hasattr(info.value, "result"), info.value.result.stats


def _check_partial(res, dt: float, save_every: int) -> None:
    """A partial history: saved states every save_every steps from t = 0, all finite, counters of the steps taken."""
    assert isinstance(res, nvib.Result) and len(res.t) >= 2
    np.testing.assert_allclose(res.t, dt * save_every * np.arange(len(res.t)), rtol=1e-12, atol=1e-15)
    assert np.all(np.isfinite(res.u)) and res.stats.num_steps >= (len(res.t) - 1) * save_every
    assert res.units == ["m"] and res.stats.wall_time > 0.0
    # it does not claim success: the status says it was interrupted, the failure where
    assert res.status == nvib.Status.interrupted and not res.success
    f = res.failure
    assert f.status == nvib.Status.interrupted and f.t == res.t[-1] and f.step > res.stats.num_steps - 1
    assert f.message.startswith(f"interrupted after step {f.step - 1} of ") and f"saved up to t = {res.t[-1]:g}" in f.message


@pytest.mark.parametrize("via", ["solve", "stepper"])
def test_sigint_keeps_the_history_saved_before_it(via, python_sigint_handler):
    """What a run saved before Ctrl-C is not lost: the KeyboardInterrupt carries it as ``result``."""
    model = hardening()  # 1e9 steps (seconds of work), 1e6 states saved: only the interrupt ends it
    stepper = nvib.Stepper(model, nvib.CentralDifference(), 1e-3)  # before the timer starts
    sent = interrupt_after(DELAY)
    with pytest.raises(KeyboardInterrupt) as info:
        if via == "solve":
            nvib.solve(model, nvib.CentralDifference(), dt=1e-3, t_end=1e6, save_every=1000)
        else:
            stepper.integrate(1e6, save_every=1000)
    assert "at" in sent
    _check_partial(info.value.result, 1e-3, 1000)


def test_an_exception_in_a_python_force_keeps_the_history_saved_before_it():
    """An error raised by a Python callback mid-run (here a KeyboardInterrupt raised by the force itself,
    as Ctrl-C does in Python code) carries the history saved before it."""
    def force(u, v, t):
        if t > 0.05:
            raise KeyboardInterrupt
        return 100.0 * u

    model = nvib.Model([1.0], force=force, u0=[1.0], uses_velocity=False, uses_time=True)
    with pytest.raises(KeyboardInterrupt) as info:
        nvib.solve(model, nvib.CentralDifference(), dt=1e-3, t_end=1.0, save_every=10)
    res = info.value.result
    _check_partial(res, 1e-3, 10)
    assert res.t[-1] <= 0.05 + 1e-12 and len(res.t) == 6  # saved at 0, 0.01, ..., 0.05
