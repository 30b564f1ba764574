"""Figures of runs: units on every axis, ground-relative labels, a storey drift plotted as an effect's
measure (nvib run --measure), a zoom panel for dense oscillation, mixed units in one panel."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

import nvib

pytest.importorskip("matplotlib")
from nvib.plot import DENSE_CYCLES, ZOOM_CYCLES, cycles, run_figure  # noqa: E402


def _labels(fig) -> list[tuple[str, str, str]]:
    return [(ax.get_title(), ax.get_xlabel(), ax.get_ylabel()) for ax in fig.axes]


def test_every_axis_of_a_run_figure_has_a_unit():
    model = nvib.load_scene("pendulum")
    res = nvib.solve(model, nvib.CEMDTS(), dt=0.1, t_end=5.0, energy=True)
    labels = _labels(run_figure(res, model, "theta"))
    assert [(x, y) for _, x, y in labels] == [("t [s]", "theta [rad]"), ("theta [rad]", "dtheta/dt [rad/s]"),
                                              ("t [s]", "energy [J]")]
    assert all("relative to the ground" not in title for title, _, _ in labels)


def test_building_axes_say_relative_to_the_ground_but_a_drift_does_not():
    model = nvib.load_scene("building")
    res = nvib.solve(model, nvib.CentralDifference(), dt=1e-3, t_end=2.0)
    titles = [t for t, _, _ in _labels(run_figure(res, model, "x1"))]
    assert titles[0] == "Displacement of x1 relative to the ground"
    assert titles[1].startswith("Ground acceleration") and "relative" not in titles[1]  # the ground's own, absolute
    assert titles[2] == "Other DOFs relative to the ground"
    labels = _labels(run_figure(res, model, "x1", measure="storey2"))
    assert labels[0] == ("Measure storey2 (hardening_spring: d = x2 - x1)", "t [s]", "storey2 [m]")
    assert labels[-1][2] == "dstorey2/dt [m/s]" and "relative" not in labels[-1][0]
    # the first storey's spring measures x1 alone: it moves with the ground
    assert run_figure(res, model, "x1", measure="storey1").axes[0].get_title().endswith("relative to the ground")


def test_measure_values_are_the_effect_measure():
    model = nvib.load_scene("building")
    res = nvib.solve(model, nvib.CentralDifference(), dt=1e-3, t_end=1.0)
    line = run_figure(res, model, "x1", measure="storey3").axes[0].lines[0]
    np.testing.assert_array_equal(line.get_ydata(), res.u[:, 2] - res.u[:, 1])


def test_unknown_or_unsaved_measure_is_refused_naming_it():
    model = nvib.load_scene("building")
    res = nvib.solve(model, nvib.CentralDifference(), dt=1e-3, t_end=0.1, dofs=["x1", "x2"])
    with pytest.raises(ValueError, match="no effect named 'roof'") as info:
        run_figure(res, model, "x1", measure="roof")
    assert info.value.argument == "measure"
    with pytest.raises(ValueError, match="'storey3' measures 'x3', which this result did not save"):
        run_figure(res, model, "x1", measure="storey3")


def test_cycles_counts_oscillations():
    t = np.linspace(0.0, 1.0, 100_001)
    assert cycles(np.sin(2 * np.pi * 37 * t + 0.1)) == pytest.approx(37, abs=0.5)
    assert cycles(np.full(10, 2.0)) == 0 and cycles(np.array([1.0, 2.0])) == 0


def test_dense_oscillation_gets_a_zoom_panel_on_its_first_cycles():
    """500 cycles in one second draw as a solid band: a second panel shows the first few at full resolution."""
    f = 500.0
    model = nvib.Model([1.0], K=np.array([[(2 * np.pi * f) ** 2]]), u0=[1e-3], dofs=["z"], units="m")
    res = nvib.solve(model, nvib.CentralDifference(), dt=2e-5, t_end=1.0)
    assert cycles(res.u[:, 0]) > DENSE_CYCLES
    fig = run_figure(res, model, "z")
    zoom = fig.axes[1]
    assert zoom.get_title().startswith(f"First {ZOOM_CYCLES} of 50") and zoom.get_ylabel() == "z [m]"
    t = zoom.lines[0].get_xdata()
    assert t[-1] == pytest.approx(ZOOM_CYCLES / f, rel=0.02)  # exactly those cycles, every saved step
    slow = nvib.Model([1.0], K=np.array([[(2 * np.pi * 5) ** 2]]), u0=[1e-3], dofs=["z"])
    res = nvib.solve(slow, nvib.CentralDifference(), dt=1e-3, t_end=1.0)
    assert len(run_figure(res, slow, "z").axes) == 2  # 5 cycles: no zoom


def test_other_dofs_in_mixed_units_say_so_in_the_legend():
    model = nvib.load_scene("vehicle")
    res = nvib.solve(model, nvib.CEMDTS(), dt=1e-3, t_end=0.2)
    fig = run_figure(res, model, "z_w1")
    others = fig.axes[1]
    names = [t.get_text() for t in others.get_legend().get_texts()]
    if any("beta" in n for n in names):
        assert others.get_ylabel() == "u [see legend]" and all(n.endswith(("[m]", "[rad]")) for n in names)
    else:
        assert others.get_ylabel() == "u [m]"


def test_cli_measure_option(tmp_path):
    png = tmp_path / "drift.png"
    run = [sys.executable, "-m", "nvib", "run", "building", "--t-end", "1"]
    p = subprocess.run(run + ["--measure", "storey2", "--plot", str(png)], capture_output=True, text=True)
    assert p.returncode == 0 and png.stat().st_size > 10_000, p.stderr
    p = subprocess.run(run + ["--measure", "roof", "--plot", str(png)], capture_output=True, text=True)
    assert p.returncode == 2 and "argument --measure: no effect named 'roof' in scene 'building'" in p.stderr
    assert "storey1, storey2" in p.stderr
    p = subprocess.run(run + ["--measure", "storey2"], capture_output=True, text=True)
    assert p.returncode == 2 and "give --plot too" in p.stderr
