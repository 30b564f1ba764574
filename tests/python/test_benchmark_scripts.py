"""Every benchmark script still starts: it imports what it uses from nvib and parses its options
(`--help`), so a renamed module or parameter breaks a test rather than the next measurement. Every
script is described in benchmarks/README.md and names no folder of one machine."""

from __future__ import annotations

import os
import re
import subprocess
import sys

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
BENCHMARKS = os.path.join(ROOT, "benchmarks")
SCRIPTS = sorted(f for f in os.listdir(BENCHMARKS) if f.endswith(".py")) if os.path.isdir(BENCHMARKS) else []


@pytest.mark.skipif(not SCRIPTS, reason="not a source checkout (no benchmarks/ folder)")
@pytest.mark.parametrize("script", SCRIPTS)
def test_benchmark_script_starts(script):
    p = subprocess.run([sys.executable, os.path.join(BENCHMARKS, script), "--help"], capture_output=True,
                       text=True, timeout=300, cwd=BENCHMARKS)
    assert p.returncode == 0, p.stderr[-2000:]
    assert "usage:" in p.stdout and "Traceback" not in p.stderr


@pytest.mark.skipif(not SCRIPTS, reason="not a source checkout (no benchmarks/ folder)")
def test_every_script_is_described_in_the_benchmarks_readme():
    # A row of its own, or named in the row of the script it serves (opensees_building.py: opensees.py's)
    with open(os.path.join(BENCHMARKS, "README.md"), encoding="utf-8") as fh:
        table = "".join(line for line in fh if line.startswith("| `"))
    assert not [s for s in SCRIPTS if f"`{s}`" not in table]


@pytest.mark.skipif(not SCRIPTS, reason="not a source checkout (no benchmarks/ folder)")
@pytest.mark.parametrize("script", SCRIPTS)
def test_script_names_no_path_of_one_machine(script):
    # Paths are relative to the script (or the repository root it finds from it), never a folder of
    # the machine it was written on; the results' machine lines record where nvib was loaded from.
    with open(os.path.join(BENCHMARKS, script), encoding="utf-8") as fh:
        text = fh.read()
    assert not re.findall(r"(?<![\w.~])/(?:work|home|Users|root|opt|srv)/[\w./-]*", text)
