"""Build tools the packaging tests run: cmake from PATH or from the test extras."""

from __future__ import annotations

import os
import shutil
import sys

import pytest


def cmake() -> str:
    """The cmake executable: on PATH, else the PyPI cmake package's beside the interpreter."""
    exe = shutil.which("cmake")
    if exe is None:
        cand = os.path.join(os.path.dirname(sys.executable), "cmake")
        exe = cand if os.path.exists(cand) else None
    if exe is None:
        pytest.fail("cmake not found: install the test extras (pip install .[test])")
    return exe
