"""The command line: ``nvib scenes``, ``nvib run`` (outputs, plots, failures, bad input), the progress bar."""

import io
import os
import re
import subprocess
import sys

import numpy as np
import pytest

import nvib

from _cli import run_cli
from nvib._progress import ProgressBar, format_duration

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
SCHEMES = {key: cls() for key, cls in nvib.schemes().items()}  # each registry key with its defaults




def summary(out: str) -> dict:
    """The run summary as {key: value} (lines 'key   value')."""
    pairs = (re.split(r"\s{2,}", line, maxsplit=1) for line in out.splitlines())
    return {p[0]: p[1] for p in pairs if len(p) == 2}


def _env():
    """PYTHONPATH that finds this nvib both in the source layout and when installed."""
    env = dict(os.environ)
    root = os.path.dirname(os.path.dirname(os.path.abspath(nvib.__file__)))
    env["PYTHONPATH"] = os.pathsep.join([root] + ([env["PYTHONPATH"]] if env.get("PYTHONPATH") else []))
    return env


# ---------------------------------------------------------------- nvib scenes

def test_scenes_lists_every_builtin_scene(capsys):
    code, out, _ = run_cli(capsys, "scenes")
    assert code == 0
    table = out.split("sources:")[0]
    rows = {line.split()[0]: line for line in table.splitlines() if line.strip()}
    for name in nvib.scene_names():
        assert name in rows
    # the paper's five and the three with memory (building_inelastic, building_collapse, isolated)
    assert set(nvib.scene_names()) == {"building", "hardening", "pendulum", "pendulum_ic2", "vehicle",
                                       "building_inelastic", "building_collapse", "isolated"}
    assert "hardening_spring x6" in rows["building"] and "ground_acceleration" in rows["building"]
    assert "hertz_contact x4" in rows["vehicle"] and rows["vehicle"].split()[1] == "10"
    assert "Yang et al. 2017" in out  # the sources


def test_existing_flags_and_demo_still_work(capsys):
    code, out, _ = run_cli(capsys, "--version")
    assert code == 0 and nvib.__version__ in out
    code, out, _ = run_cli(capsys, "--cmake-dir")
    assert code == 0 and out.strip() == nvib.cmake_dir()
    code, out, _ = run_cli(capsys, "--include-dir")
    assert code == 0 and out.strip() == nvib.include_dir()
    code, out, _ = run_cli(capsys, "demo", "--repeats", "1")
    assert code == 0 and "CEMDTS(0.45)" in out
    code, out, _ = run_cli(capsys)
    assert code == 2 and "run" in out and "scenes" in out


# ---------------------------------------------------------------- nvib run

@pytest.mark.parametrize("scheme", sorted(SCHEMES))
def test_run_hardening_with_every_scheme(capsys, scheme):
    code, out, err = run_cli(capsys, "run", "hardening", "--scheme", scheme, "--t-end", "0.05", "--energy")
    assert code == 0, err
    ref = nvib.solve(nvib.load_scene("hardening"), SCHEMES[scheme], dt=1e-3, t_end=0.05)
    s = summary(out)
    assert s["scheme"] == repr(SCHEMES[scheme])
    assert s["status"] == "success"
    assert s["steps"].startswith(f"{ref.stats.num_steps} of {ref.stats.num_steps}, dt = 0.001 s")
    assert f"u = {ref.u[-1, 0]:.9g}" in s["final x"]  # the final state of the plot DOF
    assert f"force_evals {ref.stats.num_force_evals}," in s["counters"]
    assert s["energy"].startswith("relative balance error")


def test_scheme_parameters_reach_the_scheme(capsys):
    code, out, _ = run_cli(capsys, "run", "hardening", "--scheme", "galpha", "--rho-inf", "0.5", "--t-end", "0.01")
    assert code == 0 and summary(out)["scheme"] == repr(nvib.GeneralizedAlpha.from_rho_inf(0.5))
    code, out, _ = run_cli(capsys, "run", "hardening", "--scheme", "cemdts", "--eta", "1/12", "--t-end", "0.01")
    assert code == 0 and summary(out)["scheme"] == repr(nvib.CEMDTS(1 / 12))
    code, out, _ = run_cli(capsys, "run", "hardening", "--scheme", "newmark", "--iteration", "one_iteration",
                           "--beta", "0.3", "--gamma", "0.6", "--t-end", "0.01")
    assert code == 0 and summary(out)["scheme"] == repr(nvib.Newmark(0.3, 0.6, iteration="one_iteration"))


def test_out_npz_round_trip(capsys, tmp_path):
    path = tmp_path / "run.npz"
    code, out, err = run_cli(capsys, "run", "vehicle", "--scheme", "newmark", "--t-end", "0.2", "--energy",
                             "--save-every", "3", "--out", path)
    assert code == 0, err
    assert f"wrote {path}" in out
    model = nvib.load_scene("vehicle")
    ref = nvib.solve(model, nvib.Newmark(), dt=1e-3, t_end=0.2, save_every=3, energy=True)
    with np.load(path) as data:
        for key in ("t", "u", "v", "a"):
            np.testing.assert_array_equal(data[key], getattr(ref, key))
        assert list(data["dofs"]) == model.dofs
        for key, val in ref.stats.as_dict().items():
            if key != "wall_time":
                assert data[key] == val, key
        for key, val in ref.energy.as_dict().items():
            np.testing.assert_array_equal(data[f"energy_{key}"], val)
        assert str(data["status"]) == "success" and str(data["scene"]) == "vehicle"
        assert float(data["dt"]) == 1e-3 and int(data["save_every"]) == 3


def test_out_csv_round_trip(capsys, tmp_path):
    path = tmp_path / "run.csv"
    code, _, err = run_cli(capsys, "run", "building", "--scheme", "pim", "--t-end", "0.5", "--out", path)
    assert code == 0, err
    model = nvib.load_scene("building")
    ref = nvib.solve(model, nvib.PreciseIntegration(), dt=7e-4, t_end=0.5)
    head = path.read_text().splitlines()[0].split(",")
    assert head[:13] == ["t"] + [f"u:{d}" for d in model.dofs] + [f"v:{d}" for d in model.dofs]
    table = np.loadtxt(path, delimiter=",", skiprows=1)
    n = model.n
    np.testing.assert_array_equal(table[:, 0], ref.t)  # written with 17 digits: exact
    np.testing.assert_array_equal(table[:, 1:1 + n], ref.u)
    np.testing.assert_array_equal(table[:, 1 + n:1 + 2 * n], ref.v)
    np.testing.assert_array_equal(table[:, 1 + 2 * n:1 + 3 * n], ref.a)


def test_plot_writes_a_png(capsys, tmp_path):
    path = tmp_path / "run.png"
    code, out, err = run_cli(capsys, "run", "vehicle", "--t-end", "0.3", "--energy", "--plot", path)
    assert code == 0, err
    data = path.read_bytes()
    assert data[:8] == PNG_SIGNATURE and len(data) > 10_000


def test_plot_run_is_reusable(tmp_path):
    from nvib.plot import plot_run

    model = nvib.load_scene("building")
    res = nvib.solve(model, nvib.CEMDTS(), dt=7e-4, t_end=0.5, dofs=["x1", "x6"])
    plot_run(res, model, "x6", tmp_path / "a.png", title="two storeys")
    assert (tmp_path / "a.png").read_bytes()[:8] == PNG_SIGNATURE
    with pytest.raises(ValueError, match="dof: 'x3'"):
        plot_run(res, model, "x3", tmp_path / "b.png")


def test_without_gravity_leaves_the_pendulum_a_free_mass(capsys):
    model = nvib.load_scene("pendulum")
    code, out, err = run_cli(capsys, "run", "pendulum", "--without", "gravity")
    assert code == 0, err
    assert "no effects left" in err
    assert f"u = {model.u0[0]:.9g} rad, v = 0 rad/s," in summary(out)["final theta"]  # v0 = 0: it stays put


def test_free_particle_scene_file(capsys, tmp_path):
    scene = tmp_path / "particle.toml"
    scene.write_text('[dofs]\nnames = ["x"]\nmass = [2.0]\n\n[initial]\nu = [1.0]\nv = [0.5]\n')
    code, _, err = run_cli(capsys, "run", scene)
    assert code == 2 and "argument --dt" in err  # the file sets no dt
    out_path = tmp_path / "p.npz"
    code, out, err = run_cli(capsys, "run", scene, "--dt", "0.1", "--t-end", "2", "--out", out_path)
    assert code == 0, err
    with np.load(out_path) as data:
        np.testing.assert_allclose(data["u"][:, 0], 1.0 + 0.5 * data["t"], rtol=1e-14)


def test_without_contact_on_the_vehicle(capsys):
    code, out, err = run_cli(capsys, "run", "vehicle", "--without", "contact", "--t-end", "0.1", "--dof", "z_c")
    assert code == 0, err
    assert "no static equilibrium" in err
    s = summary(out)
    assert s["without"] == "contact" and s["status"] == "success" and "final z_c" in s
    code, out, err = run_cli(capsys, "run", "vehicle", "--without", "gravity", "hertz_contact", "--t-end", "0.1")
    assert code == 0, err


@pytest.mark.parametrize("argv, argument", [
    (["run", "hardening", "--scheme", "rk4"], "argument --scheme"),
    (["run", "hardening", "--dof", "y"], "argument --dof"),
    (["run", "hardening", "--without", "gravity"], "argument --without"),
    (["run", "no_such_scene"], "argument SCENE"),
    (["run", "missing/scene.toml"], "argument SCENE"),
    (["run", "hardening", "--out", "run.txt"], "argument --out"),
    (["run", "hardening", "--plot", "run.jpg"], "argument --plot"),
    (["run", "hardening", "--eta", "2"], "argument --eta"),
    (["run", "hardening", "--scheme", "lcdm", "--eta", "0.3"], "argument --eta"),
    (["run", "hardening", "--scheme", "galpha", "--rho-inf", "0.5", "--beta", "0.3"], "argument --rho-inf"),
    (["run", "hardening", "--scheme", "newmark", "--beta", "0"], "argument --beta"),
    (["run", "hardening", "--dt", "-1e-3"], "argument --dt"),
    (["run", "hardening", "--dt", "abc"], "argument --dt"),
    (["run", "hardening", "--save-every", "0"], "argument --save-every"),
    (["run", "hardening", "--dt", "1e-15", "--save-every", "1"], "argument --save-every"),
])
def test_bad_input_exits_2_naming_the_argument(capsys, argv, argument):
    code, out, err = run_cli(capsys, *argv)
    assert code == 2
    assert argument in err
    assert err.strip().splitlines()[-1].startswith("nvib run: error:")


def test_diverging_run_exits_1_and_keeps_the_partial_outputs(capsys, tmp_path):
    npz, png = tmp_path / "div.npz", tmp_path / "div.png"
    code, out, err = run_cli(capsys, "run", "hardening", "--scheme", "lcdm", "--dt", "0.05", "--energy",
                             "--out", npz, "--plot", png)
    assert code == 1
    lines = err.strip().splitlines()
    # the default bound, 1e10 x max|u0| = 1.5e10, is crossed at step 3 (|u| = 9.8e12)
    assert len(lines) == 1 and "diverged" in lines[0] and "diverged at t = 0.15 (step 3)" in lines[0]
    assert "beyond the bound 1.5e+10" in lines[0]
    assert summary(out)["status"] == "diverged"
    with np.load(npz) as data:
        assert str(data["status"]) == "diverged" and len(data["t"]) == 3
    assert png.read_bytes()[:8] == PNG_SIGNATURE


def test_max_displacement_stops_the_run(capsys):
    code, out, err = run_cli(capsys, "run", "hardening", "--scheme", "lcdm", "--dt", "0.05", "--max-displacement", "10")
    assert code == 1 and "diverged at t = 0.05 (step 1)" in err and "beyond the bound 10" in err


def test_newton_failure_exits_1(capsys):
    code, _, err = run_cli(capsys, "run", "vehicle", "--scheme", "newmark", "--iteration", "modified", "--dt", "0.01")
    assert code == 1
    assert "Newton did not converge in 20 iterations at t = 0.01 (step 1; residual" in err
    assert err.rstrip().endswith("try a smaller --dt or --iteration newton")


def test_python_dash_m_runs_the_cli(tmp_path):
    ok = subprocess.run([sys.executable, "-m", "nvib", "run", "pendulum_ic2", "--scheme", "zhai", "--out",
                         str(tmp_path / "p.csv")], capture_output=True, text=True, env=_env(), timeout=60)
    assert ok.returncode == 0, ok.stderr
    assert summary(ok.stdout)["status"] == "success" and (tmp_path / "p.csv").stat().st_size > 0
    bad = subprocess.run([sys.executable, "-m", "nvib", "run", "hardening", "--scheme", "lcdm", "--dt", "0.05"],
                         capture_output=True, text=True, env=_env(), timeout=60)
    assert bad.returncode == 1 and "diverged" in bad.stderr and "Traceback" not in bad.stderr


# ---------------------------------------------------------------- progress bar

class FakeClock:
    def __init__(self):
        self.now = 0.0

    def __call__(self):
        return self.now


def test_progress_bar_stays_silent_on_short_runs():
    clock, stream = FakeClock(), io.StringIO()
    bar = ProgressBar(stream, clock=clock)
    clock.now = 0.05
    bar(4096, 10_000)  # 41 % after 0.05 s: the run will take ~0.12 s
    bar.close()
    assert stream.getvalue() == "" and not bar.drawn


def test_progress_bar_draws_and_finishes_long_runs():
    clock, stream = FakeClock(), io.StringIO()
    bar = ProgressBar(stream, clock=clock, width=10)
    clock.now = 0.5
    bar(1000, 10_000)  # 10 % after 0.5 s: 4.5 s to go
    assert stream.getvalue() == "\r[#.........]  10%  ETA 4.5 s"
    clock.now = 2.25
    bar(4500, 10_000)
    assert stream.getvalue().endswith("\r[####......]  45%  ETA 2.8 s")
    clock.now = 5.0
    bar.close(done=True)
    assert stream.getvalue().endswith("\r[##########] 100%  in 5.0 s \n")  # padded over the longer line
    bar(9000, 10_000)  # closed: no more drawing
    assert stream.getvalue().endswith("\n")


def test_progress_bar_disabled_and_durations():
    stream = io.StringIO()
    bar = ProgressBar(stream, enabled=False, min_duration=0.0)
    bar(1, 2)
    bar.close()
    assert stream.getvalue() == ""
    assert format_duration(3.21) == "3.2 s"
    assert format_duration(65) == "1 min 05 s"
    assert format_duration(7380) == "2 h 03 min"


def test_run_passes_the_progress_bar_to_solve(capsys, monkeypatch):
    seen = []

    def fake_solve(*args, progress=None, **kw):
        seen.append(progress)
        return real_solve(*args, progress=progress, **kw)

    real_solve = nvib.solve
    monkeypatch.setattr(nvib, "solve", fake_solve)
    assert run_cli(capsys, "run", "hardening", "--progress", "--t-end", "0.01")[0] == 0
    assert run_cli(capsys, "run", "hardening", "--no-progress", "--t-end", "0.01")[0] == 0
    assert isinstance(seen[0], ProgressBar) and seen[1] is None


def test_renamed_scheme_option_is_refused_naming_the_new_one(capsys):
    code, out, err = run_cli(capsys, "run", "hardening", "--scheme", "pim", "--order", "3")
    assert code == 2 and "argument --order: renamed --interpolation (polynomial degree of the interpolation" in err
    code, out, _ = run_cli(capsys, "run", "hardening", "--scheme", "pim", "--interpolation", "3")
    assert code == 0 and "PreciseIntegration(squarings=20, interpolation=3, corrections=1)" in out


# ---------------------------------------------------------------- laws with memory on the command line

def test_run_collapse_scene_says_which_effect_and_exits_0(capsys, tmp_path):
    """building_collapse: a collapse is the model's answer, not a failure of the run: status collapsed,
    a warning naming the storey, exit status 0, the recorded storey (the scene's record list) in the
    summary and in --out."""
    out_file = tmp_path / "c.npz"
    code, out, err = run_cli(capsys, "run", "building_collapse", "--scheme", "newmark", "--out", out_file)
    assert code == 0, err
    s = summary(out)
    assert s["status"] == "collapsed"
    assert re.match(r"collapsed at t = 10\.2\d* \(step \d+\): storey1 \(imk_peak_oriented\) lost its strength",
                    s["warning"]), s["warning"]
    assert s["storey1"].startswith("imk_peak_oriented: peak |d| 0.25")
    res = nvib.load_result(out_file)
    assert res.status == nvib.Status.collapsed and list(res.effects) == ["storey1"]
    assert res.effects["storey1"].state["failed"][-1] == 1.0


def test_run_record_effect_and_collapse_deformation(capsys, tmp_path):
    out_file = tmp_path / "b.csv"
    code, out, err = run_cli(capsys, "run", "building_inelastic", "--scheme", "newmark", "--t-end", "12",
                             "--record-effect", "storey2", "pdelta2", "--collapse-deformation", "0.05", "--out",
                             out_file)
    assert code == 0, err
    s = summary(out)
    assert s["status"] == "collapsed"
    assert "storey1 (bilinear) deformed to" in s["warning"] and "beyond the collapse limit 0.05" in s["warning"]
    assert s["storey2"].startswith("bilinear: peak |d|") and "dissipated" in s["storey2"]
    assert s["pdelta2"].startswith("p_delta: peak |d|")
    head = out_file.read_text().splitlines()[0].split(",")
    assert {"effect:storey2:force", "effect:storey2:plastic_deformation", "effect:pdelta2:force"} <= set(head)


def test_run_measure_draws_the_loop(capsys, tmp_path):
    png = tmp_path / "loop.png"
    code, out, err = run_cli(capsys, "run", "isolated", "--scheme", "newmark", "--t-end", "5", "--measure",
                             "bearings", "--plot", png)
    assert code == 0, err
    assert png.read_bytes()[:8] == PNG_SIGNATURE
    assert summary(out)["bearings"].startswith("bouc_wen: peak |d|")


@pytest.mark.parametrize("argv, flag, match", [
    (["--record-effect", "storey9"], "--record-effect", "no effect named 'storey9'"),
    (["--collapse-deformation", "-1"], "--collapse-deformation", ""),
])
def test_run_bad_memory_options(capsys, argv, flag, match):
    code, _, err = run_cli(capsys, "run", "building_inelastic", "--t-end", "0.1", *argv)
    assert code == 2 and flag in err and match in err
