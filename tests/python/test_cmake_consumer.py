"""The installed package is usable from C++: find_package(nvib) in a separate
CMake project, built against the headers and config installed by pip."""

import os
import subprocess
import sys


import nvib

import _build_tools

HERE = os.path.dirname(os.path.abspath(__file__))
CONSUMER = os.path.join(os.path.dirname(HERE), "cmake_consumer")


def test_installed_tree_has_headers_and_config():
    assert os.path.isfile(os.path.join(nvib.include_dir(), "nvib", "nvib.hpp"))
    assert os.path.isfile(os.path.join(nvib.cmake_dir(), "nvibConfig.cmake"))
    assert os.path.isfile(os.path.join(nvib.cmake_dir(), "nvibConfigVersion.cmake"))


def test_cli_prints_cmake_dir():
    out = subprocess.run([sys.executable, "-m", "nvib", "--cmake-dir"], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == nvib.cmake_dir()


def test_find_package_consumer_builds_and_runs(tmp_path):
    cmake = _build_tools.cmake()
    build = tmp_path / "build"
    cfg = subprocess.run([cmake, "-S", CONSUMER, "-B", str(build), f"-Dnvib_DIR={nvib.cmake_dir()}",
                          "-DCMAKE_BUILD_TYPE=Release"], capture_output=True, text=True)
    assert cfg.returncode == 0, cfg.stdout + cfg.stderr
    bld = subprocess.run([cmake, "--build", str(build)], capture_output=True, text=True)
    assert bld.returncode == 0, bld.stdout + bld.stderr
    exe = build / "consumer"
    run = subprocess.run([str(exe)], capture_output=True, text=True)
    assert run.returncode == 0, run.stdout + run.stderr
    assert "nvib consumer: steps 1000" in run.stdout
