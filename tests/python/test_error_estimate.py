"""Result.error_estimate: every run's estimate of its own error relative to each DOF's peak.

The estimate (cpp/include/nvib/solve/error_estimate.hpp) is the leading phase error of the scheme on
each mode, c h^2 tau |da/dt|; the full comparison with the true error is
benchmarks/results/error_estimate.md. Here: its order in dt, its ratio to the true error on a subset
of that table (measured ratios in the comments), the warning, and the switch."""

from __future__ import annotations

import math
import pickle

import numpy as np
import pytest

import nvib
from nvib.analysis.reference import reference

from _accuracy import true_error as _true_error

SECOND_ORDER = [nvib.CentralDifference(), nvib.CEMDTS(), nvib.Zhai(), nvib.Newmark(), nvib.GeneralizedAlpha(),
                nvib.GeneralizedAlpha.from_rho_inf(0.8)]


@pytest.mark.parametrize("scheme", SECOND_ORDER + [nvib.Newmark(beta=0.3025, gamma=0.6)], ids=lambda s: s.label)
def test_the_estimate_falls_at_the_schemes_order(scheme):
    model = nvib.load_scene("hardening")
    dts = [1e-3, 5e-4, 2.5e-4]
    est = [nvib.solve(model, scheme, dt=dt, t_end=0.3).error_estimate.max for dt in dts]
    slope = np.polyfit(np.log(dts), np.log(est), 1)[0]
    assert abs(slope - scheme.order_u) <= 0.2, (est, slope)


def test_a_first_order_scheme_is_estimated_as_one():
    assert nvib.Newmark(beta=0.3025, gamma=0.6).order_u == 1  # the parametrised test above covers its slope


# (scene, scheme, dt): the estimate within a factor 3 of the true error. Measured estimate / true
# (benchmarks/results/error_estimate.md):
#   building LCDM 0.84, Newmark 0.84 (a many-mode undamped response: the jerk keeps the modes' signs)
#   pendulum_ic2 LCDM 1.43, Newmark 0.80, generalized-alpha 1.49
#   vehicle LCDM at dt/2 1.33, Newmark at dt/2 1.37 (at the scene's dt LCDM is at 3.00: true 25 %,
#   estimate 74 %, and warns)
#   building_inelastic LCDM 1.37, Newmark 1.82 at the scene's step over 30 s (Newmark at dt/128 the reference)
WITHIN_THREE = [
    ("building", nvib.CentralDifference(), 7e-4),
    ("building", nvib.Newmark(), 7e-4),
    ("pendulum_ic2", nvib.CentralDifference(), 0.3),
    ("pendulum_ic2", nvib.Newmark(), 0.3),
    ("pendulum_ic2", nvib.GeneralizedAlpha(), 0.3),
    ("vehicle", nvib.CentralDifference(), 5e-4),
    ("vehicle", nvib.Newmark(), 5e-4),
]


@pytest.mark.parametrize("scene, scheme, dt", WITHIN_THREE, ids=lambda x: getattr(x, "label", str(x)))
def test_the_estimate_is_within_three_of_the_true_error(scene, scheme, dt):
    model = nvib.load_scene(scene)
    t_end = model.scene["t_end"]
    res = nvib.solve(model, scheme, dt=dt, t_end=t_end)
    true = _true_error(res, reference(model, t_end))
    assert 1 / 3 <= res.error_estimate.max / true <= 3, (res.error_estimate.max, true)


def test_the_estimate_on_a_building_with_memory():
    model = nvib.load_scene("building_inelastic")
    t_end, dt = 10.0, model.scene["dt"]
    fine = nvib.solve(model, nvib.Newmark(), dt=dt / 64, t_end=t_end)
    for scheme in (nvib.CentralDifference(), nvib.Newmark()):
        res = nvib.solve(model, scheme, dt=dt, t_end=t_end)
        u_ref = fine.u[::64]
        peak = np.max(np.abs(u_ref), axis=0)
        true = float(np.max(np.max(np.abs(res.u - u_ref), axis=0) / peak))
        assert 1 / 3 <= res.error_estimate.max / true <= 3, (scheme.label, res.error_estimate.max, true)


def test_a_strongly_anharmonic_oscillator_is_over_estimated_by_a_measured_factor():
    # A measured pin, not a theorem: on the hardening oscillator (stiffness 1 + 30 x^2 at x = 1.5 m) the
    # jerk's peaks at the stiff turning points over-state the phase error; measured 3.31 for every
    # second-order scheme at dt = 5e-4 s and 2.5e-4 s (2.75 at 1e-3 s, where a sample missed the peak),
    # except generalized-alpha (0.75).
    model = nvib.load_scene("hardening")
    res = nvib.solve(model, nvib.Newmark(), dt=5e-4, t_end=0.3)
    ratio = res.error_estimate.max / _true_error(res, reference(model, 0.3))
    assert 3.2 <= ratio <= 3.45, ratio


def test_the_default_vehicle_run_warns_with_the_step_that_would_meet_it():
    model = nvib.load_scene("vehicle")
    res = nvib.solve(model, nvib.CentralDifference(), dt=model.scene["dt"], t_end=model.scene["t_end"])
    est = res.error_estimate
    assert est.max > 0.1  # 74 %; the true error is 25 % on the worst DOF (DOP853 with contact events)
    notes = [w for w in res.warnings if "estimated error" in w]
    assert len(notes) == 1 and est.dof in notes[0]
    dt = est.dt_for(nvib.ERROR_WARNING)
    assert f"{dt:.3g}" in notes[0]
    assert dt == pytest.approx(model.scene["dt"] * (nvib.ERROR_WARNING / est.max) ** 0.5)


def test_warn_error_sets_the_level_and_a_quiet_run_does_not_warn():
    model = nvib.load_scene("building")
    res = nvib.solve(model, nvib.Newmark(), dt=7e-4, t_end=10.0)
    assert not [w for w in res.warnings if "estimated error" in w]  # 1.2e-4
    loud = nvib.solve(model, nvib.Newmark(), dt=7e-4, t_end=10.0, warn_error=1e-5)
    assert [w for w in loud.warnings if "estimated error" in w]
    with pytest.raises(nvib.ArgumentError, match="warn_error"):
        nvib.solve(model, nvib.Newmark(), dt=7e-4, t_end=1.0, warn_error=-1.0)


def test_the_estimate_can_be_switched_off_and_travels_with_the_result():
    model = nvib.load_scene("building")
    assert nvib.solve(model, nvib.Newmark(), dt=7e-4, t_end=1.0, error_estimate=False).error_estimate is None
    res = nvib.solve(model, nvib.Newmark(), dt=7e-4, t_end=1.0)
    again = pickle.loads(pickle.dumps(res))
    np.testing.assert_array_equal(again.error_estimate.per_dof, res.error_estimate.per_dof)
    assert set(res.error_estimate.as_dict()) == set(model.dofs)
    # the switch changes no state
    off = nvib.solve(model, nvib.Newmark(), dt=7e-4, t_end=1.0, error_estimate=False)
    np.testing.assert_array_equal(off.u, res.u)


# PIM follows its own error: each step's interpolation error of the remainder, propagated by its
# exponential (error_estimate.hpp). Measured estimate / true (benchmarks/results/error_estimate.md):
#   building 0.39, pendulum_ic2 0.73 at dt/2; the vehicle at the scene's step (true 94 %) warns.
@pytest.mark.parametrize("scene, dt, low, high", [("building", 7e-4, 1 / 3, 3), ("pendulum_ic2", 0.15, 1 / 3, 3)])
def test_the_precise_integration_methods_own_estimate(scene, dt, low, high):
    model = nvib.load_scene(scene)
    t_end = model.scene["t_end"]
    res = nvib.solve(model, nvib.PreciseIntegration(), dt=dt, t_end=t_end)
    true = _true_error(res, reference(model, t_end))
    assert low <= res.error_estimate.max / true <= high, (res.error_estimate.max, true)


def test_the_precise_integration_method_warns_on_the_vehicle():
    model = nvib.load_scene("vehicle")
    res = nvib.solve(model, nvib.PreciseIntegration(), dt=model.scene["dt"], t_end=model.scene["t_end"])
    assert res.error_estimate.max > 0.1 and [w for w in res.warnings if "estimated error" in w]


def test_the_precise_integration_method_misses_a_hardening_phase_drift_by_a_measured_factor():
    # A measured pin of a known limit, not a theorem: the propagation is the linear part's at rest, so
    # the phase drift of the hardening oscillator's amplitude-dependent frequency escapes it. Over 0.3 s
    # the estimate is 0.46 of the true error at dt = 5e-4 s; over 1 s the true error has grown tenfold
    # (2.9e-3) and the estimate has not (1.4e-4): measured 0.048.
    model = nvib.load_scene("hardening")
    res = nvib.solve(model, nvib.PreciseIntegration(), dt=5e-4, t_end=1.0)
    ratio = res.error_estimate.max / _true_error(res, reference(model, 1.0))
    assert 0.04 <= ratio <= 0.06, ratio


def test_solve_many_reports_every_runs_estimate():
    model = nvib.load_scene("building")
    for keep in ("history", "peaks"):
        batch = nvib.solve_many(model, nvib.Newmark(), dt=7e-4, t_end=2.0, scales=[1.0, 3.0], keep=keep)
        alone = [nvib.solve(nvib._batch._derived(model, None, s, {}), nvib.Newmark(), dt=7e-4, t_end=2.0)
                 for s in (1.0, 3.0)]
        np.testing.assert_array_equal(batch.error_estimates, [r.error_estimate.max for r in alone])
        assert f"largest error estimate {max(r.error_estimate.max for r in alone):.2g}" in repr(batch)
    pim = nvib.solve_many(model, nvib.PreciseIntegration(), dt=7e-4, t_end=0.1, scales=[1.0, 2.0], keep="peaks")
    alone = nvib.solve(model, nvib.PreciseIntegration(), dt=7e-4, t_end=0.1)
    assert pim.error_estimates[0] == alone.error_estimate.max and pim[0].error_estimate == alone.error_estimate.max
