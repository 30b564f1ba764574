"""Rough edges a new user meets: empty output names, huge save_every, truth values given as strings."""

import subprocess
import sys

import pytest

import nvib


@pytest.mark.parametrize("argv, flag", [(["run", "hardening", "--out", ""], "--out"),
                                        (["run", "hardening", "--plot", ""], "--plot"),
                                        (["stability", "--plot", ""], "--plot")])
def test_empty_output_names_are_refused(argv, flag, tmp_path):
    p = subprocess.run([sys.executable, "-m", "nvib", *argv], capture_output=True, text=True, cwd=tmp_path)
    assert p.returncode == 2 and f"argument {flag}: expected a file name" in p.stderr
    assert list(tmp_path.iterdir()) == []  # nothing written


def test_save_every_beyond_64_bits_is_named():
    with pytest.raises(nvib.ArgumentError) as exc:
        nvib.solve(nvib.load_scene("hardening"), nvib.CEMDTS(), dt=1e-3, t_end=0.01, save_every=10**30)
    assert exc.value.argument == "save_every" and "must be <=" in str(exc.value)


@pytest.mark.parametrize("key", ["uses_velocity", "uses_time"])
def test_flags_must_be_booleans(key):
    with pytest.raises(nvib.ArgumentTypeError) as exc:
        nvib.Model([1.0], force=lambda u, v, t: u, **{key: "False"})
    assert exc.value.argument == key
    assert nvib.Model([1.0], force=lambda u, v, t: u, **{key: False}) is not None


def test_builtin_scene_names_win_over_files_in_the_working_directory(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "building").mkdir()          # a folder named like a built-in scene
    (tmp_path / "hardening").write_text("garbage", encoding="utf-8")
    assert nvib.load_scene("building").scene["name"] == "building"
    assert nvib.load_scene("hardening").scene["name"] == "hardening"
    with pytest.raises(FileNotFoundError, match="is a folder, not a scene file"):
        nvib.load_scene("./building")
    (tmp_path / "mine.toml").write_text('[dofs]\nnames = ["x"]\nmass = [1.0]\n', encoding="utf-8")
    assert nvib.load_scene("mine.toml").n == 1
    with pytest.raises(nvib.ArgumentError, match="a scene file is named by a path"):
        nvib.load_scene("nosuchscene")


def test_dof_names_must_be_strings():
    with pytest.raises(nvib.ArgumentTypeError) as exc:
        nvib.Model([1.0, 1.0], dofs=[1, 2], effects=[{"type": "spring", "measure": {1: 1.0}, "k": 1.0}])
    assert exc.value.argument == "dofs[0]" and "DOF indices" in str(exc.value)
