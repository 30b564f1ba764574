"""Every command with input it cannot use, each run through ``python -m nvib`` in a subprocess: a path that
is a loop of symbolic links, a folder, /dev/zero, an empty file or nothing; non-finite numbers; periods too
short or too long for the memory. Bad input exits 2 with one line naming the argument, a run that fails
exits 1 with its message, and neither prints a traceback."""

from __future__ import annotations

import os

import numpy as np
import pytest

from _cli import nvib_subprocess

pytestmark = pytest.mark.skipif(os.name != "posix", reason="symbolic links and /dev/zero")

SCENE = ('[scene]\nt_end = 0.5\ndt = 0.01\n\n[dofs]\nnames = ["x"]\nmass = [1.0]\n\n'
         '[[effect]]\ntype = "spring"\nmeasure = {{ x = 1.0 }}\nk = 100.0\n\n'
         '[[effect]]\ntype = "ground_acceleration"\nsignal = {{ kind = "record", file = "{record}", dt = 0.01 }}\n')


@pytest.fixture(scope="module")
def paths(tmp_path_factory) -> dict:
    """A good record and scene, and the bad paths by kind."""
    d = tmp_path_factory.mktemp("bad_input")
    (d / "loop_a").symlink_to(d / "loop_b")
    (d / "loop_b").symlink_to(d / "loop_a")
    (d / "loop.toml").symlink_to(d / "loop2.toml")
    (d / "loop2.toml").symlink_to(d / "loop.toml")
    (d / "dangling").symlink_to(d / "nowhere")
    (d / "folder").mkdir()
    (d / "folder.toml").mkdir()
    for name in ("out.csv", "out.npz", "out.png", "out.md"):
        (d / "folder" / name).mkdir()
    (d / "loop.csv").symlink_to(d / "loop3.csv")
    (d / "loop3.csv").symlink_to(d / "loop.csv")
    (d / "empty.txt").write_text("")
    (d / "empty.toml").write_text("")
    (d / "a_file").write_text("x")
    np.savetxt(d / "rec.txt", np.sin(0.07 * np.arange(200)))
    np.savetxt(d / "rec40.txt", np.sin(0.07 * np.arange(4000)))  # 40 s at dt = 0.01
    (d / "scene.toml").write_text(SCENE.format(record=d / "rec.txt"))
    bad = {"a loop of symbolic links": d / "loop_a", "a folder": d / "folder", "/dev/zero": "/dev/zero",
           "an empty file": d / "empty.txt", "missing": d / "nowhere.txt", "a link to nothing": d / "dangling"}
    return {"dir": d, "bad": bad}


def assert_bad_input(p, command: str, argument: str) -> str:
    """Exit status 2, no traceback, the last line 'nvib COMMAND: error: argument ARGUMENT: ...'."""
    assert "Traceback" not in p.stderr, p.stderr
    assert p.returncode == 2, p.stderr
    last = p.stderr.strip().splitlines()[-1]
    assert last.startswith(f"nvib {command}: error: argument {argument}: "), last
    return last


def assert_failed_run(p, command: str) -> str:
    assert "Traceback" not in p.stderr, p.stderr
    assert p.returncode == 1, p.stderr
    last = p.stderr.strip().splitlines()[-1]
    assert last.startswith(f"nvib {command}: error: "), last
    return last


BAD_PATHS = ["a loop of symbolic links", "a folder", "/dev/zero", "an empty file", "missing", "a link to nothing"]
REASONS = {"a loop of symbolic links": "a loop of symbolic links", "a folder": "is a folder, not a",
           "/dev/zero": "is a device, not a", "an empty file": "", "missing": "no such file",
           "a link to nothing": "which does not exist"}


@pytest.mark.parametrize("kind", BAD_PATHS)
def test_spectrum_record_that_cannot_be_read(paths, kind):
    path = paths["bad"][kind]
    last = assert_bad_input(nvib_subprocess("spectrum", path, "--dt", "0.01"), "spectrum", "record")
    assert str(path) in last and REASONS[kind] in last


@pytest.mark.parametrize("command", ["run", "cost"])
@pytest.mark.parametrize("kind", BAD_PATHS)
def test_scene_that_cannot_be_read(paths, command, kind):
    path = paths["bad"][kind]
    if kind == "an empty file":
        path = paths["dir"] / "empty.toml"
    last = assert_bad_input(nvib_subprocess(command, path, "--t-end", "0.1"), command, "SCENE")
    assert str(path) in last and REASONS[kind] in last


@pytest.mark.parametrize("name", ["loop.toml", "folder.toml", "loop_a"])
def test_scene_named_without_a_folder(paths, name):
    """A name without a folder is a scene file when one of that name is there, even a broken one."""
    last = assert_bad_input(nvib_subprocess("run", name, cwd=paths["dir"]), "run", "SCENE")
    assert name in last and "unknown scene" not in last


@pytest.mark.parametrize("kind", BAD_PATHS)
def test_scene_whose_record_cannot_be_read(paths, kind):
    scene = paths["dir"] / f"record_{BAD_PATHS.index(kind)}.toml"
    scene.write_text(SCENE.format(record=paths["bad"][kind]))
    for command in ("run", "cost"):
        last = assert_bad_input(nvib_subprocess(command, scene, "--dt", "0.01", "--no-scipy", "--schemes", "newmark")
                                if command == "cost" else nvib_subprocess(command, scene), command, "SCENE")
        assert str(scene) in last and str(paths["bad"][kind]) in last and REASONS[kind] in last


@pytest.mark.parametrize("kind, path", [("a loop of symbolic links", "loop_a"), ("a link to nothing", "dangling"),
                                        ("/dev/zero", "/dev/zero"), ("a file", "a_file"),
                                        ("under a file", "a_file/figures")])
def test_paper_outdir_that_cannot_be_a_folder(paths, kind, path):
    assert_bad_input(nvib_subprocess("paper", path, cwd=paths["dir"]), "paper", "OUTDIR")


OUTPUTS = [(["run", "hardening"], "--out", "out.npz"), (["run", "hardening"], "--plot", "out.png"),
           (["spectrum", "rec.txt", "--dt", "0.01"], "--out", "out.csv"),
           (["spectrum", "rec.txt", "--dt", "0.01"], "--plot", "out.png"),
           (["cost", "hardening"], "--plot", "out.png"), (["cost", "hardening"], "--table", "out.md"),
           (["demo"], "--plot", "out.png"), (["stability"], "--plot", "out.png")]


@pytest.mark.parametrize("argv, flag, name", OUTPUTS, ids=[f"{a[0]} {f}" for a, f, _ in OUTPUTS])
def test_output_that_is_a_folder_or_a_loop(paths, argv, flag, name):
    if flag == "--plot":
        pytest.importorskip("matplotlib")
    d = paths["dir"]
    p = nvib_subprocess(*argv, flag, d / "folder" / name, cwd=d)
    assert "is a folder" in assert_bad_input(p, argv[0], flag)
    if name == "out.csv":
        p = nvib_subprocess(*argv, flag, d / "loop.csv", cwd=d)
        assert "loop of symbolic links" in assert_bad_input(p, argv[0], flag)
    assert not list(d.glob("cost_*"))  # refused before anything ran


NON_FINITE = [
    (["run", "hardening", "--dt", "inf"], "--dt"), (["run", "hardening", "--dt", "nan"], "--dt"),
    (["run", "hardening", "--t-end", "inf"], "--t-end"), (["run", "hardening", "--max-displacement", "nan"],
                                                           "--max-displacement"),
    (["run", "hardening", "--collapse-deformation", "inf"], "--collapse-deformation"),
    (["run", "hardening", "--scheme", "newmark", "--beta", "nan"], "--beta"),
    (["cost", "hardening", "--dt", "nan"], "--dt"), (["cost", "hardening", "--t-end", "inf"], "--t-end"),
    (["cost", "hardening", "--rtol", "inf"], "--rtol"), (["cost", "hardening", "--target", "nan"], "--target"),
    (["cost", "hardening", "--max-time", "inf"], "--max-time"),
    (["demo", "--dt", "nan"], "--dt"),
    (["stability", "--xi", "nan"], "--xi"), (["stability", "--omega-min", "inf"], "--omega-min"),
    (["stability", "--omega-max", "nan"], "--omega-max"), (["stability", "--beta", "inf"], "--beta"),
    (["spectrum", "rec.txt", "--dt", "inf"], "--dt"), (["spectrum", "rec.txt", "--dt", "0.01", "--scale", "nan"],
                                                       "--scale"),
    (["spectrum", "rec.txt", "--dt", "0.01", "--damping", "inf"], "--damping"),
    (["spectrum", "rec.txt", "--dt", "0.01", "--scheme", "newmark", "--accuracy", "nan"], "--accuracy"),
    (["spectrum", "rec.txt", "--dt", "0.01", "--periods", "0.1,inf"], "--periods"),
    (["spectrum", "rec.txt", "--dt", "0.01", "--periods", "0.1,nan"], "--periods"),
    (["spectrum", "rec.txt", "--dt", "0.01", "--periods", "0.1:inf:3"], "--periods"),
    (["spectrum", "rec.txt", "--dt", "0.01", "--periods", "nan:1:3"], "--periods"),
    (["spectrum", "rec.txt", "--dt", "0.01", "--periods", "0.1:1:1000000000000"], "--periods"),
]


@pytest.mark.parametrize("argv, flag", NON_FINITE, ids=[" ".join(a[:1] + a[-2:]) for a, _ in NON_FINITE])
def test_non_finite_numbers_name_the_option(paths, argv, flag):
    assert_bad_input(nvib_subprocess(*argv, cwd=paths["dir"]), argv[0], flag)


@pytest.mark.parametrize("argv, flag, needle", [
    (["rec40.txt", "--periods", "1e-6"], "--periods", "T = 1e-06 s takes 2.29e+09 steps"),
    (["rec.txt", "--periods", "1e300"], "--periods", "T = 1e+300 s takes 2e+302 steps"),
    (["rec.txt", "--periods", "0.1,1e12"], "--periods", "the longest period, 1e+12 s"),
    (["rec.txt", "--accuracy", "1e-300"], "--accuracy", "must be >= 1e-09"),
])
def test_spectrum_refuses_runs_that_cannot_be_made(paths, argv, flag, needle):
    """Periods whose runs would not fit in memory, and an accuracy below round-off, are refused before
    any run, naming the option (not the dt the spectrum derives from them)."""
    p = nvib_subprocess("spectrum", *argv, "--dt", "0.01", "--scheme", "newmark", cwd=paths["dir"], timeout=60)
    last = assert_bad_input(p, "spectrum", flag)
    assert needle in last and "argument --dt" not in last


def test_the_exact_spectrum_refuses_what_it_cannot_compute(paths):
    """Without --scheme the spectrum is exact: a period whose frequency squared is not finite names
    --periods, a record too large for doubles names the record, --accuracy is refused as meaningless."""
    last = assert_bad_input(nvib_subprocess("spectrum", "rec.txt", "--dt", "0.01", "--periods", "1e-300",
                                            cwd=paths["dir"]), "spectrum", "--periods")
    assert "not finite" in last
    last = assert_bad_input(nvib_subprocess("spectrum", "rec.txt", "--dt", "0.01", "--scale", "1e308",
                                            "--periods", "0.5,1", cwd=paths["dir"]), "spectrum", "record")
    assert "too large for doubles" in last
    last = assert_bad_input(nvib_subprocess("spectrum", "rec.txt", "--dt", "0.01", "--accuracy", "1e-3",
                                            cwd=paths["dir"]), "spectrum", "--accuracy")
    assert "exact" in last


def test_spectrum_failing_run_exits_1_naming_its_period(paths):
    p = nvib_subprocess("spectrum", "rec.txt", "--dt", "0.01", "--scale", "1e308", "--periods", "0.5,1",
                        "--scheme", "newmark", cwd=paths["dir"])
    last = assert_failed_run(p, "spectrum")
    assert "the run at T = 0.5 s" in last and "diverged" in last and "Newmark" in last


@pytest.mark.skipif(not os.path.exists("/dev/full"), reason="needs /dev/full")
def test_spectrum_output_that_cannot_be_written_exits_1(paths, tmp_path):
    out = tmp_path / "sa.csv"
    out.symlink_to("/dev/full")  # every write fails: no space left on the device
    p = nvib_subprocess("spectrum", "rec.txt", "--dt", "0.01", "--periods", "0.5", "--out", out, cwd=paths["dir"])
    assert "--out: cannot write" in assert_failed_run(p, "spectrum")


@pytest.mark.parametrize("argv, flag, needle", [
    (["--dt", "1e-300", "--no-scipy"], "--dt", "too many steps"),
    (["--t-end", "1e300", "--no-scipy"], "--t-end", "too many steps"),
    (["--rtol", "1e-300"], "--rtol", "must be >= 2.3e-14"),
])
def test_cost_step_counts_and_tolerances_name_the_option(paths, argv, flag, needle):
    """A step count beyond 64 bits was 'nvib cost: error: dt: ...' without the option; an rtol below
    solve_ivp's floor ran at that floor, for as long as it took."""
    p = nvib_subprocess("cost", "hardening", "--schemes", "newmark", *argv, cwd=paths["dir"], timeout=60)
    assert needle in assert_bad_input(p, "cost", flag)
    assert not list(paths["dir"].glob("cost_*"))


def test_more_options_named(paths):
    """--points beyond what a plot takes asked for terabytes (a MemoryError traceback); a library error about
    collapse_deformation lacked its option; a record's repeated time printed numpy's np.float64(0.0)."""
    d = paths["dir"]
    p = nvib_subprocess("stability", "--points", "1000000000000", "--plot", d / "rho.png", cwd=d)
    assert "must be <= 100000" in assert_bad_input(p, "stability", "--points")
    p = nvib_subprocess("run", "hardening", "--collapse-deformation", "1e-3", cwd=d)
    assert "effects with memory" in assert_bad_input(p, "run", "--collapse-deformation")
    (d / "repeated.txt").write_text("0 1\n0 2\n")
    p = nvib_subprocess("spectrum", "repeated.txt", cwd=d)
    assert "(sample 2: t = 0.0 after 0.0)" in assert_bad_input(p, "spectrum", "record")
