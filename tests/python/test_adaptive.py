"""Adaptive steps: solve(..., tol=): the step chosen each step so that the error estimate stays within
tol, rejection, and steps that land on the declared events (cpp/include/nvib/solve/adaptive.hpp).

That a retaken step equals the step taken once, bit for bit, for every scheme and every law with
memory, is tested in C++ (tests/cpp/test_memory.cpp, rejections_leave_no_trace)."""

from __future__ import annotations

import numpy as np
import pytest

import nvib
from nvib.analysis.reference import reference

from _accuracy import true_error as _true_error


# (scene, scheme, tol): the true error within 3 tol. Measured true / tol: building Newmark 1.74 (tol 1e-3)
# and 1.72 (1e-4); pendulum_ic2 LCDM 2.47, Newmark 2.74 (1e-4). Not yet within 3 tol (the issue stays
# open): the hardening oscillator (LCDM 4.5-7, Newmark 3.8), the pendulum of IC1 (LCDM 45-86) and
# the vehicle (LCDM 240-500, Newmark 36-59), where the estimate under-states the error of strongly
# anharmonic motion and of the wheel impacts.
WITHIN = [("building", nvib.Newmark(), 1e-3), ("building", nvib.Newmark(), 1e-4),
          ("pendulum_ic2", nvib.CentralDifference(), 1e-4), ("pendulum_ic2", nvib.Newmark(), 1e-4)]


@pytest.mark.parametrize("scene, scheme, tol", WITHIN, ids=lambda x: getattr(x, "label", str(x)))
def test_an_adaptive_run_meets_its_tolerance(scene, scheme, tol):
    model = nvib.load_scene(scene)
    t_end = model.scene["t_end"]
    res = nvib.solve(model, scheme, dt=model.scene["dt"], t_end=t_end, tol=tol)
    assert res.t[-1] == pytest.approx(t_end, rel=1e-12)
    true = _true_error(res, reference(model, t_end))
    assert true <= 3.0 * tol
    # the estimate of an adaptive run is the fixed-step one with the age integral of h^2, within a factor
    # 3 of the true error (measured: 0.85 on the building, 1.4-1.7 on the pendulum)
    assert true / 3.0 <= res.error_estimate.max <= 3.0 * true


def test_a_tighter_tolerance_takes_more_steps_and_is_more_accurate():
    model = nvib.load_scene("pendulum_ic2")
    ref = reference(model, model.scene["t_end"])
    runs = [nvib.solve(model, nvib.Newmark(), dt=model.scene["dt"], t_end=model.scene["t_end"], tol=tol)
            for tol in (1e-3, 1e-4, 1e-5)]
    steps = [r.stats.num_steps for r in runs]
    errors = [_true_error(r, ref) for r in runs]
    assert steps[0] < steps[1] < steps[2]
    assert errors[0] > errors[1] > errors[2]
    # second order: tol / 10 costs about 10^(1/2) = 3.2 times the steps
    assert 2.5 < steps[2] / steps[1] < 4.0


def _bouncing():
    """A mass on a spring that strikes a stop: the gap closes at d = -0.05 (a slope jump 100 -> 1e5 N/m)."""
    return nvib.Model([1.0], effects=[{"type": "spring", "k": 100.0, "measure": {0: 1.0}},
                                      {"type": "gap", "k": 1e5, "gap": 0.05, "measure": {0: 1.0}}], u0=[0.2])


@pytest.mark.parametrize("scheme", [nvib.CentralDifference(), nvib.CEMDTS(), nvib.Newmark(),
                                    nvib.GeneralizedAlpha()], ids=lambda s: s.label)
def test_steps_land_on_the_gap_closing_and_opening(scheme):
    res = nvib.solve(_bouncing(), scheme, dt=1e-3, t_end=2.0, tol=1e-4)
    g = res.u[:, 0] + 0.05  # the event value: 0 where the gap closes or opens
    on = np.abs(g) <= 1e-12 * 0.2  # on the event: the measure 0 to round-off (0.0 or 1e-16 measured)
    # every closing and opening is a saved state on the event, never a step across it
    assert res.stats.num_events >= 8
    assert np.count_nonzero(on) == res.stats.num_events
    straddled = [k for k in range(1, len(g)) if g[k - 1] * g[k] < 0.0 and not on[k - 1] and not on[k]]
    assert straddled == []


def test_the_fixed_step_run_is_the_default_and_unchanged():
    model = nvib.load_scene("hardening")
    a = nvib.solve(model, nvib.CEMDTS(), dt=1e-3, t_end=0.3)
    b = nvib.solve(model, nvib.CEMDTS(), dt=1e-3, t_end=0.3, tol=None)
    assert np.array_equal(a.u, b.u) and a.stats.num_rejected_steps == 0 and a.stats.num_events == 0
    assert np.allclose(np.diff(a.t), 1e-3)


def test_bad_adaptive_settings_name_their_argument():
    model = nvib.load_scene("hardening")
    with pytest.raises(nvib.ArgumentError, match="tol"):
        nvib.solve(model, nvib.Newmark(), dt=1e-3, t_end=0.3, tol=2.0)
    with pytest.raises(nvib.ArgumentError, match="tol"):  # no estimate to control PIM's step with
        nvib.solve(model, nvib.PreciseIntegration(), dt=1e-3, t_end=0.3, tol=1e-4)
    with pytest.raises(nvib.ArgumentError, match="min_dt"):
        nvib.solve(model, nvib.Newmark(), dt=1e-3, t_end=0.3, tol=1e-4, min_dt=1e-2, max_dt=1e-3)
    with pytest.raises(nvib.ArgumentError, match="tol"):
        nvib.solve(model, nvib.Newmark(), dt=1e-3, t_end=0.3, tol=-1e-4)


def test_the_smallest_step_stops_the_run_with_a_message():
    model = nvib.load_scene("hardening")
    res = nvib.solve(model, nvib.Newmark(), dt=1e-3, t_end=0.3, tol=1e-9, min_dt=1e-4, throw=False)
    assert res.status == nvib.Status.diverged
    assert "min_dt" in res.failure.message and "tol" in res.failure.message


def test_the_cli_runs_adaptive(capsys):
    from nvib.cli import main

    assert main(["run", "pendulum_ic2", "--scheme", "newmark", "--tol", "1e-4"]) == 0
    out = capsys.readouterr().out
    assert "adaptive, tol 0.0001" in out
