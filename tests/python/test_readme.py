"""The README tells the truth: what it lists, prints and runs is checked against nvib itself.

Skips when the tests run from elsewhere than a source checkout (no README.md beside them)."""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

import nvib
from nvib.analysis import cost as cost_module

ROOT = Path(__file__).resolve().parent.parent.parent
README = ROOT / "README.md"
STATUSES = [s.name for s in nvib.Status]


def readme() -> str:
    if not README.is_file():
        pytest.skip(f"no README.md in {ROOT}: not a source checkout")
    return README.read_text(encoding="utf-8")


# ---- statuses: every list of them has all of them ------------------------------------------------

def test_the_status_enum_is_listed_whole():
    m = re.search(r"`Status` \(an enum: (.*?)\) and `Failure`", readme(), re.S)
    assert m, "README.md no longer lists the members of Status where it names the bound types"
    listed = set(re.findall(r"`(\w+)`", m.group(1)))
    assert set(STATUSES) <= listed, sorted(set(STATUSES) - listed)


def test_cost_rows_name_every_failing_status():
    m = re.search(r"^- A run that fails is a row: (.*?)(?=^- )", readme(), re.S | re.M)
    assert m, "README.md's description of cost rows moved"
    listed = set(re.findall(r"`(\w+)`", m.group(1)))
    failing = set(STATUSES) - {"success"}
    assert failing <= listed, sorted(failing - listed)
    assert all(f"'{s}'" in cost_module.__doc__ for s in STATUSES)


def test_the_type_stub_lists_every_status():
    stub = Path(nvib.__file__).with_name("_core.pyi")
    if not stub.is_file():
        pytest.skip("no _core.pyi beside the package")
    tree = ast.parse(stub.read_text(encoding="utf-8"))
    (cls,) = [n for n in tree.body if isinstance(n, ast.ClassDef) and n.name == "Status"]
    members = {t.id: node.value.value for node in cls.body if isinstance(node, ast.Assign)
               for t in node.targets}
    assert members == {s.name: s.value for s in nvib.Status}
