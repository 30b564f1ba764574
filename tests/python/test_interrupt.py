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
    with pytest.raises(KeyboardInterrupt):
        nvib.solve(model, scheme, dt=1e-3, t_end=1e10, save_every=10**12)
    stopped = time.perf_counter()
    assert "at" in sent
    assert stopped - sent["at"] < 5.0, f"stopped {stopped - sent['at']:.2f} s after the signal"


def test_sigint_stops_stepper_integrate_and_the_stepper_stays_usable(python_sigint_handler):
    st = nvib.Stepper(hardening(), nvib.CEMDTS(), 1e-3)  # before the timer starts
    sent = interrupt_after(DELAY)
    with pytest.raises(KeyboardInterrupt):
        st.integrate(1e10, save_every=10**12)
    assert time.perf_counter() - sent["at"] < 5.0
    # the stepper holds the state reached when the run stopped, and continues from it
    t = st.t
    assert t > 0.0
    res = st.integrate(t + 0.01)
    assert res.success and res.t[0] == t


@pytest.mark.skipif(not hasattr(signal, "pthread_kill"), reason="needs POSIX signals")
def test_sigint_stops_a_run_whose_steps_take_a_second_within_one_step(python_sigint_handler):
    """Signals are polled on a clock (about every 50 ms of work, and at every factorisation), not every
    few thousand steps: a 160,000-DOF lattice whose Newmark steps take about a second (two sparse
    factorisations each) stops within one step of Ctrl-C."""
    model = nvib.scenes.lattice(400, 400)
    u0 = np.full(model.n, 1e-3)
    st = nvib.Stepper(model, nvib.Newmark(), 1e-3, u0=u0)
    t = time.perf_counter()
    st.step()
    step = time.perf_counter() - t
    sent = interrupt_after(max(1.0, 1.5 * step))
    with pytest.raises(KeyboardInterrupt):
        nvib.solve(model, nvib.Newmark(), dt=1e-3, t_end=1.0, u0=u0, save_every=10**6)
    stopped = time.perf_counter()
    assert "at" in sent
    assert stopped - sent["at"] < step + 0.5, f"stopped {stopped - sent['at']:.2f} s after the signal; a step {step:.2f} s"


def test_sigint_stops_the_set_up_of_precise_integration(python_sigint_handler):
    """PIM's dense set-up (O(n^3), tens of seconds at 600 DOFs) polls between its matrix products."""
    model = nvib.scenes.chain(600)
    sent = interrupt_after(DELAY)
    t = time.perf_counter()
    with pytest.raises(KeyboardInterrupt):
        nvib.solve(model, nvib.PreciseIntegration(), dt=1e-3, t_end=0.01)
    stopped = time.perf_counter()
    assert "at" in sent and stopped - t < 10.0
    assert stopped - sent["at"] < 2.0, f"stopped {stopped - sent['at']:.2f} s after the signal"
