"""Edges of the command line, each run through ``python -m nvib`` in a subprocess: a closed output pipe,
Ctrl-C during a run, the demo's options and blown-up schemes, scene files that cannot be read, empty
output names."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import threading
import time

import numpy as np
import pytest

import nvib

TIMEOUT = 120


def _env(**extra) -> dict:
    """PYTHONPATH that finds this nvib both in the source layout and when installed."""
    env = dict(os.environ)
    root = os.path.dirname(os.path.dirname(os.path.abspath(nvib.__file__)))
    env["PYTHONPATH"] = os.pathsep.join([root] + ([env["PYTHONPATH"]] if env.get("PYTHONPATH") else []))
    env.update(extra)
    return env


def nvib_cli(*argv, cwd=None) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "nvib", *map(str, argv)], capture_output=True, text=True,
                          env=_env(), cwd=cwd, timeout=TIMEOUT)


def assert_usage_error(p: subprocess.CompletedProcess, command: str, *needles: str) -> str:
    """Exit status 2, no traceback, the last line 'nvib COMMAND: error: ...' holding every needle."""
    assert p.returncode == 2, p.stderr
    assert "Traceback" not in p.stderr
    last = p.stderr.strip().splitlines()[-1]
    assert last.startswith(f"nvib {command}: error: "), last
    for needle in needles:
        assert needle in last, (needle, last)
    return last


# ---------------------------------------------------------------- a closed output pipe

def run_with_stdout_closed(argv) -> tuple[int, str]:
    with subprocess.Popen([sys.executable, "-m", "nvib", *argv], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                          env=_env()) as p:
        p.stdout.close()  # long before the child has imported nvib
        err = p.stderr.read().decode()
        code = p.wait(timeout=TIMEOUT)
    return code, err


@pytest.mark.parametrize("argv", [["scenes"], ["run", "hardening", "--scheme", "pim"], ["demo", "--repeats", "1"],
                                  ["--cmake-dir"]])
def test_closed_stdout_ends_quietly_with_status_141(argv):
    """The reader is gone before the command writes (as `nvib scenes | head -3` once head has exited):
    no traceback, no "Exception ignored" from the final flush, exit status 141 (128 + SIGPIPE)."""
    code, err = run_with_stdout_closed(argv)
    assert code == 141, err
    assert err == ""


@pytest.mark.parametrize("argv", [["--help"], ["run", "--help"]])
def test_closed_stdout_and_help_stay_quiet(argv):
    code, err = run_with_stdout_closed(argv)
    assert err == ""
    assert code in (0, 141)  # argparse drops the write error of its own help text and exits 0


def test_pipe_closed_after_a_few_bytes():
    """The reader takes a few bytes and closes the pipe, as head does."""
    with subprocess.Popen([sys.executable, "-m", "nvib", "scenes"], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                          env=_env(PYTHONUNBUFFERED="1")) as p:
        head = p.stdout.read(12)
        p.stdout.close()
        err = p.stderr.read().decode()
        code = p.wait(timeout=TIMEOUT)
    assert head.startswith(b"name")
    assert "Traceback" not in err and "Exception ignored" not in err
    assert code in (0, 141)  # 0 when it had written everything before the pipe closed


# ---------------------------------------------------------------- Ctrl-C during nvib run --out

T_END = 1e6  # 1e9 steps of the hardening oscillator: only Ctrl-C ends this run in time


@pytest.fixture(scope="module")
def interrupted_run(tmp_path_factory):
    """`nvib run hardening --t-end 1e6 --progress --out run.npz`, sent SIGINT once its progress bar shows."""
    if not hasattr(signal, "SIGINT") or os.name != "posix":
        pytest.skip("needs POSIX signals")
    out = tmp_path_factory.mktemp("interrupt") / "run.npz"
    # SIGINT at its default disposition in the child, as in a terminal: a test runner started in the background
    # by a shell ignores it, the child would inherit that, and Python then leaves Ctrl-C ignored
    p = subprocess.Popen([sys.executable, "-m", "nvib", "run", "hardening", "--t-end", str(T_END), "--progress",
                          "--out", str(out)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=_env(),
                         preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    err = bytearray()
    started = threading.Event()

    def read_stderr():
        while chunk := os.read(p.stderr.fileno(), 4096):
            err.extend(chunk)
            if b"%" in err:  # the progress bar: the run is in the integrator loop
                started.set()
        started.set()

    reader = threading.Thread(target=read_stderr, daemon=True)
    reader.start()
    started.wait(timeout=60)
    time.sleep(0.3)  # a few saved states more
    p.send_signal(signal.SIGINT)
    stdout = p.stdout.read().decode()
    code = p.wait(timeout=60)
    reader.join(timeout=10)
    p.stdout.close()
    p.stderr.close()
    return {"code": code, "stdout": stdout, "stderr": err.decode(), "out": out}


def test_ctrl_c_exits_130_and_says_what_became_of_out(interrupted_run):
    r = interrupted_run
    assert r["code"] == 130, r["stderr"]
    assert "Traceback" not in r["stderr"]
    last = r["stderr"].strip().splitlines()[-1]
    assert last.startswith("nvib run: interrupted") and str(r["out"]) in last, last


def test_ctrl_c_writes_the_partial_history(interrupted_run):
    r = interrupted_run
    assert r["out"].exists(), r["stderr"]
    res = nvib.load_result(r["out"])
    assert 0.0 < res.t[-1] < T_END
    assert f"up to t = {res.t[-1]:g} s is in {r['out']}" in r["stderr"]


def test_diverged_run_says_where_its_partial_history_is(tmp_path):
    out = tmp_path / "div.npz"
    p = nvib_cli("run", "hardening", "--scheme", "lcdm", "--dt", "0.05", "--out", out)
    assert p.returncode == 1 and "Traceback" not in p.stderr
    res = nvib.load_result(out)
    assert 0.0 < res.t[-1] < 0.3
    assert p.stderr.strip().endswith(f"the partial history up to t = {res.t[-1]:g} s is in {out}")


# ---------------------------------------------------------------- nvib demo

@pytest.mark.parametrize("argv, flag", [
    (["--dt", "inf"], "argument --dt: must be finite"),
    (["--dt", "nan"], "argument --dt: must be finite"),
    (["--dt", "0"], "argument --dt: must be > 0"),
    (["--dt=-1e-3"], "argument --dt: must be > 0"),
    (["--dt", "1e-12"], "argument --dt: must be >= 3e-07 s (at most 1000000 steps"),
    (["--dt", "1e-300"], "argument --dt: must be >= 3e-07 s"),
    (["--repeats", "0"], "argument --repeats: must be >= 1"),
    (["--repeats=-3"], "argument --repeats: must be >= 1"),
    (["--repeats", "1.5"], "argument --repeats: expected a whole number"),
    (["--plot", "demo.txt"], "argument --plot: expected a file ending in"),
])
def test_demo_bad_options_exit_2_naming_the_flag(argv, flag, tmp_path):
    assert_usage_error(nvib_cli("demo", *argv, cwd=tmp_path), "demo", flag)
    assert list(tmp_path.iterdir()) == []


def demo_rows(stdout: str) -> dict:
    """{scheme label: rest of its row} of the demo's table."""
    labels = [cls().label for cls in nvib._schemes.scheme_classes()]
    rows = {}
    for line in stdout.splitlines():
        for label in labels:
            if line.startswith(label + " "):
                rows[label] = line[len(label):].strip()
    assert len(rows) == len(labels), stdout
    return rows


def test_demo_rows_say_where_a_scheme_diverged():
    p = nvib_cli("demo", "--dt", "0.05", "--repeats", "1")
    assert p.returncode == 1 and "Traceback" not in p.stderr
    rows = demo_rows(p.stdout)
    assert rows["LCDM"].startswith("diverged at t = 0.15 (step 3) ")
    assert rows["PIM"].startswith("diverged at t = 0.1 (step 2) ")
    assert "e+1" not in p.stdout and "e+2" not in p.stdout  # no energy error of 1e22
    last = p.stderr.strip().splitlines()[-1]
    assert last.startswith("nvib demo: error: LCDM, ") and last.endswith("try a smaller --dt")


def test_demo_rows_say_where_a_scheme_blew_up():
    """One step of the whole run, past the oscillator's period: no divergence by the displacement bound, but
    energies of 1e17 to 1e32 x E0; the rows say so rather than print the numbers. A longer step than the run
    (--dt 1) is refused: it would end the run past t_end."""
    p = nvib_cli("demo", "--dt", "1", "--repeats", "1")
    assert p.returncode == 2 and "Traceback" not in p.stderr
    assert p.stderr.strip().splitlines()[-1] == "nvib demo: error: argument --dt: must be <= t_end = 0.3 s (a longer " \
                                                 "step would end the run past it), got 1"
    p = nvib_cli("demo", "--dt", "0.3", "--repeats", "1")
    assert p.returncode == 1 and "Traceback" not in p.stderr
    rows = demo_rows(p.stdout)
    for label in ("LCDM", "PIM"):
        assert rows[label].startswith("blew up by t = 0.3: energy "), rows[label]
    assert not rows["Newmark (newton)"].startswith("blew up")  # Newmark stays bounded
    assert "e+32 " not in p.stdout.replace("e+32 x E0", "")  # only as the blow-up factor
    assert "PIM" in p.stderr.strip().splitlines()[-1]


def test_demo_default_runs_clean():
    p = nvib_cli("demo", "--repeats", "1")
    assert p.returncode == 0 and p.stderr == ""
    assert "blew up" not in p.stdout and "diverged" not in p.stdout


# ---------------------------------------------------------------- scene files that cannot be read

SCENE = '[scene]\nt_end = 1.0\ndt = 0.01\n\n[dofs]\nnames = ["x"]\nmass = [1.0]\n'


def scene_error(path, *argv, command="run") -> str:
    """The usage error of loading the scene at path: exit 2, no traceback, the file named."""
    last = assert_usage_error(nvib_cli(command, path, *argv), command, "argument SCENE: ", str(path))
    return last


def test_scene_not_utf8_names_the_file_and_line(tmp_path):
    path = tmp_path / "latin1.toml"
    path.write_bytes(SCENE.encode() + b"# r\xe9sum\xe9\n")
    last = scene_error(path)
    assert f"{path}: not UTF-8 text: byte 0xe9 on line 8" in last


def test_scene_nested_too_deeply_names_the_file(tmp_path):
    path = tmp_path / "deep.toml"
    path.write_text(SCENE + "a = " + "[" * 100_000 + "\n", encoding="utf-8")
    last = scene_error(path)
    assert f"{path}: malformed TOML: arrays or inline tables nested too deeply" in last


def test_scene_too_large_is_refused_before_reading(tmp_path):
    path = tmp_path / "huge.toml"
    with open(path, "wb") as fh:  # sparse: 65 MiB on paper, a few bytes on disk
        fh.write(SCENE.encode())
        fh.truncate(65 * 2**20)
    last = scene_error(path)
    assert f"{path}: 65.0 MB, more than the 64 MB a scene file may have" in last


def test_scene_out_of_memory_names_the_file(tmp_path):
    """A MemoryError while parsing (simulated: the parser raises it) is an error naming the file."""
    path = tmp_path / "mem.toml"
    path.write_text(SCENE, encoding="utf-8")
    code = ("import sys\n"
            "from nvib import _scenes\n"
            "def boom(text): raise MemoryError\n"
            "_scenes.tomllib.loads = boom\n"  # tomllib, or tomli before Python 3.11
            "from nvib.cli import main\n"
            f"sys.exit(main(['run', {str(path)!r}]))\n")
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=_env(), timeout=TIMEOUT)
    last = assert_usage_error(p, "run", "argument SCENE: ", f"{path}: too large to read into memory")
    assert "Traceback" not in p.stderr and last


def test_scene_t_end_not_positive_names_the_file_and_key(tmp_path):
    path = tmp_path / "neg.toml"
    path.write_text(SCENE.replace("t_end = 1.0", "t_end = -5"), encoding="utf-8")
    last = scene_error(path)
    assert f"{path}: [scene] t_end: must be > 0, got -5" in last
    assert "--t-end" not in last
    scene_error(path, command="cost")  # nvib cost loads scenes the same way
    # a --t-end the user gave is blamed as the flag
    assert_usage_error(nvib_cli("run", "hardening", "--t-end", "-5"), "run", "argument --t-end: must be > 0")


def test_step_count_errors_name_the_scene_key_or_the_flag_given(tmp_path):
    path = tmp_path / "tiny.toml"
    path.write_text(SCENE.replace("dt = 0.01", "dt = 1e-300"), encoding="utf-8")
    last = scene_error(path)
    assert f"{path}: [scene] dt: too many steps" in last and "--dt" not in last
    assert_usage_error(nvib_cli("run", path, "--dt", "1e-299"), "run", "argument --dt: too many steps")
    assert_usage_error(nvib_cli("run", "hardening", "--t-end", "1e300"), "run", "argument --t-end: too many steps")


# ---------------------------------------------------------------- empty output names

@pytest.mark.parametrize("argv, flag", [
    (["run", "hardening", "--out", ""], "--out"),
    (["run", "hardening", "--plot", ""], "--plot"),
    (["demo", "--plot", ""], "--plot"),
    (["cost", "hardening", "--plot", ""], "--plot"),
    (["cost", "hardening", "--table", ""], "--table"),
    (["stability", "--plot", ""], "--plot"),
])
def test_empty_output_names_are_refused_naming_the_flag(argv, flag, tmp_path):
    p = nvib_cli(*argv, cwd=tmp_path)
    assert_usage_error(p, argv[0], f"argument {flag}: expected a file name")
    assert list(tmp_path.iterdir()) == []  # nothing written, not even a default-named file


def test_help_documents_the_exit_statuses():
    p = nvib_cli("--help")
    assert p.returncode == 0 and "141" in p.stdout and "130" in p.stdout
    p = nvib_cli("demo", "--help")
    assert p.returncode == 0 and "blew up" in p.stdout and "Exit" in p.stdout
