"""Units of the DOFs (Model.units, scene [dofs] units, Result.units), ground-relative results and
Result.warnings (an energy balance error above 5 % in a run that did not fail)."""

from __future__ import annotations

import math
import pickle
import subprocess
import sys

import numpy as np
import pytest

import nvib


def test_model_units_default_to_metres_and_take_one_string_or_one_per_dof():
    assert nvib.Model([1.0, 2.0]).units == ["m", "m"]
    assert nvib.Model([1.0, 2.0], units="mm").units == ["mm", "mm"]
    md = nvib.Model([1.0, 2.0], dofs=["x", "phi"], units=["m", "rad"])
    assert md.units == ["m", "rad"] and md.unit("phi") == "rad" and md.unit(0) == "m"


@pytest.mark.parametrize("units, argument, message", [
    (["m"], "units", r"expected 2 units \(one per DOF\), got 1"),
    ("", "units", "empty string"),
    (["m", 3], "units[1]", "got 3"),
    (["m", " "], "units[1]", "got ' '"),
    (5, "units", "got int"),
])
def test_bad_units_are_refused_naming_the_argument(units, argument, message):
    with pytest.raises((ValueError, TypeError), match=message) as info:
        nvib.Model([1.0, 2.0], units=units)
    assert info.value.argument == argument


def test_built_in_scenes_declare_si_units_by_dof_kind():
    assert nvib.load_scene("pendulum").units == ["rad"]
    assert nvib.load_scene("building").units == ["m"] * 6
    vehicle = nvib.load_scene("vehicle")
    kinds = {d: u for d, u in zip(vehicle.dofs, vehicle.units)}
    assert all(kinds[d] == "rad" for d in vehicle.dofs if d.startswith("beta"))
    assert all(kinds[d] == "m" for d in vehicle.dofs if d.startswith("z"))


def test_scene_units_must_match_the_dofs(tmp_path):
    scene = tmp_path / "two.toml"
    scene.write_text('[dofs]\nnames = ["x", "y"]\nmass = [1.0, 1.0]\nunits = ["m"]\n', encoding="utf-8")
    with pytest.raises(nvib.SceneError, match=r"two.toml: \[dofs\] units: expected 2 units"):
        nvib.load_scene(str(scene))
    scene.write_text('[dofs]\nnames = ["x", "y"]\nmass = [1.0, 1.0]\nunit = "m"\n', encoding="utf-8")
    with pytest.raises(nvib.SceneError, match=r"unknown key \(expected names, mass, units\)"):
        nvib.load_scene(str(scene))


def test_result_units_follow_the_saved_dofs_and_survive_pickling_and_files(tmp_path):
    vehicle = nvib.load_scene("vehicle")
    res = nvib.solve(vehicle, nvib.CentralDifference(), dt=1e-4, t_end=1e-3, dofs=["beta_c", "z_w1"])
    assert res.units == ["rad", "m"]
    assert pickle.loads(pickle.dumps(res)).units == ["rad", "m"]
    res.save(tmp_path / "r.npz")
    assert nvib.load_result(tmp_path / "r.npz").units == ["rad", "m"]


def test_displacements_under_a_ground_motion_are_marked_relative():
    building = nvib.solve(nvib.load_scene("building"), nvib.CentralDifference(), dt=1e-3, t_end=0.01)
    free = nvib.solve(nvib.load_scene("hardening"), nvib.CentralDifference(), dt=1e-3, t_end=0.01)
    assert building.relative_to_ground and not free.relative_to_ground
    stepped = nvib.Stepper(nvib.load_scene("building"), nvib.CentralDifference(), 1e-3).integrate(0.01)
    assert stepped.relative_to_ground


def test_tables_carry_units_and_the_ground_flag(tmp_path):
    pd = pytest.importorskip("pandas")
    res = nvib.solve(nvib.load_scene("pendulum"), nvib.CentralDifference(), dt=0.1, t_end=1.0)
    df = res.to_pandas()
    assert isinstance(df, pd.DataFrame)
    assert df.attrs["units"]["u:theta"] == "rad" and df.attrs["units"]["a:theta"] == "rad/s^2"
    assert df.attrs["units"]["t"] == "s" and df.attrs["relative_to_ground"] == 0


def test_netcdf_keeps_units_and_the_ground_flag(tmp_path):
    pytest.importorskip("xarray")
    res = nvib.solve(nvib.load_scene("building"), nvib.CentralDifference(), dt=1e-3, t_end=0.01)
    ds = res.to_xarray()
    assert list(ds["unit"].values) == ["m"] * 6 and ds["time"].attrs["units"] == "s"
    res.save(tmp_path / "b.nc")
    back = nvib.load_result(tmp_path / "b.nc")
    assert back.units == ["m"] * 6 and back.relative_to_ground


PIM_LONG = dict(dt=0.3, t_end=1800.0, energy=True, save_every=100)  # PIM order 2 loses the pendulum's energy


def test_a_run_that_ends_with_a_large_energy_error_warns():
    res = nvib.solve(nvib.load_scene("pendulum"), nvib.PreciseIntegration(), **PIM_LONG)
    assert res.success  # it does not diverge: the balance error stays below the stop level (0.5) ...
    rel = res.energy.relative_balance_error()
    assert 0.05 < rel < nvib.DEFAULT_MAX_ENERGY_ERROR
    assert len(res.warnings) == 1  # ... but it is far from accurate, and the result says so
    assert f"{rel:.1%}" in res.warnings[0] and "above 5%" in res.warnings[0]
    assert pickle.loads(pickle.dumps(res)).warnings == res.warnings


def test_warning_threshold_is_an_argument():
    model = nvib.load_scene("pendulum")
    assert nvib.solve(model, nvib.PreciseIntegration(), warn_energy_error=math.inf, **PIM_LONG).warnings == []
    assert nvib.solve(model, nvib.PreciseIntegration(), warn_energy_error=0.9, **PIM_LONG).warnings == []
    with pytest.raises(ValueError) as info:
        nvib.solve(model, nvib.PreciseIntegration(), warn_energy_error=0.0, **PIM_LONG)
    assert info.value.argument == "warn_energy_error"


def test_an_accurate_run_has_no_warning_and_a_run_without_energy_is_not_judged():
    model = nvib.load_scene("pendulum")
    good = nvib.solve(model, nvib.CEMDTS(), dt=0.01, t_end=15.0, energy=True)
    assert good.energy.relative_balance_error() < 1e-3 and good.warnings == []
    assert nvib.solve(model, nvib.PreciseIntegration(), dt=0.3, t_end=1800.0).warnings == []


def test_cli_summary_shows_the_warning_and_units():
    out = subprocess.run([sys.executable, "-m", "nvib", "run", "pendulum", "--scheme", "pim", "--t-end", "1800",
                          "--energy"], capture_output=True, text=True, check=True).stdout
    lines = {ln.split("  ", 1)[0]: ln.split("  ", 1)[1].strip() for ln in out.splitlines() if "  " in ln}
    assert lines["status"] == "success"
    assert lines["warning"].startswith("the energy balance error reached 4") and "above 5%" in lines["warning"]
    assert " rad, v = " in lines["final theta"] and "rad/s^2" in lines["final theta"]
    out = subprocess.run([sys.executable, "-m", "nvib", "run", "building", "--t-end", "0.1"],
                         capture_output=True, text=True, check=True).stdout
    assert "m/s^2 (relative to the ground)" in out and "warning" not in out
