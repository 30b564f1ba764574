"""The registry contract: every scheme of cpp/include/nvib/schemes/all.hpp is a
Python class, a command-line key with its options, a label, and is run by the
order, stability and fuzz tests, with no scheme list kept by hand anywhere."""

from __future__ import annotations

import importlib
import inspect
import os
import pickle
import re

import pytest

import nvib
from nvib import _core
from nvib.cli import build_parser
from nvib.cli import cost as cli_cost
from nvib.cli import demo as cli_demo
from nvib.cli._common import scheme_options

from _registry import VARIANTS, scheme_variants, with_newton

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))


def registry_line() -> list[str]:
    """The struct names of the one AllSchemes line of all.hpp, in order."""
    with open(os.path.join(ROOT, "cpp", "include", "nvib", "schemes", "all.hpp"), encoding="utf-8") as fh:
        text = fh.read()
    (line,) = re.findall(r"^using AllSchemes = SchemeList<(.*)>;$", text, re.M)
    return [name.strip() for name in line.split(",")]


def subparser(name):
    parser = build_parser()
    action = next(a for a in parser._actions if a.dest == "command")
    return action.choices[name]


def test_the_binding_follows_the_registry_line():
    assert [cls.__name__ for _, cls in _core.SCHEMES] == registry_line()
    assert list(nvib.schemes()) == [cls.key for _, cls in _core.SCHEMES]


def test_every_scheme_is_a_python_class(scheme_key, scheme_class):
    assert getattr(nvib, scheme_class.__name__) is scheme_class and scheme_class.__name__ in nvib.__all__
    s = scheme_class()
    assert scheme_class.key == scheme_key and isinstance(scheme_class.is_explicit, bool)
    assert s.label and s.short_label and s.label.startswith(s.short_label)
    assert s.order_u in (1, 2, 3, 4) and s.order_v in (1, 2, 3, 4)
    assert eval(repr(s), vars(nvib)) == s and pickle.loads(pickle.dumps(s)) == s
    assert str(inspect.signature(scheme_class)).startswith("(")
    assert "Parameters" in scheme_class.__doc__
    for p in scheme_class.parameters():
        assert getattr(s, p["name"]) == p["default"] or p["kind"] == "newton"


def test_every_scheme_is_on_the_command_line(scheme_key, scheme_class):
    assert scheme_key in subparser("run")._option_string_actions["--scheme"].choices
    assert scheme_key in subparser("stability")._option_string_actions["--schemes"].choices
    assert scheme_key in cli_cost.default_schemes()
    assert any(type(s) is scheme_class for _, s in cli_demo.demo_schemes())
    options = scheme_options()
    for p in scheme_class.parameters():
        names = ["iteration"] if p["kind"] == "newton" else [p["name"]]
        for name in names:
            assert scheme_key in options[name]["schemes"], (scheme_key, name)
            assert "--" + name.replace("_", "-") in subparser("run")._option_string_actions


def test_every_scheme_has_its_own_test_file(scheme_key):
    assert os.path.isfile(os.path.join(HERE, f"test_scheme_{scheme_key}.py"))


@pytest.mark.parametrize("module, fixture", [("test_orders", "scheme_class"), ("test_stability", "scheme_class"),
                                             ("test_fuzz", "scheme_class")])
def test_the_generic_tests_run_every_scheme(module, fixture):
    """The order, stability and fuzz tests take the registry fixture (conftest.py), so they run each
    scheme of the registry; none of them keeps a list of schemes of its own."""
    mod = importlib.import_module(module)
    tests = [f for name, f in vars(mod).items() if name.startswith("test_") and callable(f)]
    assert any(fixture in inspect.signature(f).parameters for f in tests), module
    assert not hand_kept_lists(mod), f"{module} keeps a hand-made list of schemes: {hand_kept_lists(mod)}"


def hand_kept_lists(mod) -> list[str]:
    """Module-level lists, tuples or dicts whose entries are schemes of three or more registry classes:
    a list of schemes kept by hand (a family of one or two classes, or settings by key, is not one)."""
    classes = tuple(cls for _, cls in _core.SCHEMES)
    found = []
    for name, value in vars(mod).items():
        entries = list(value.values()) if isinstance(value, dict) else value if isinstance(value, (list, tuple)) else []
        kinds = {type(e) for e in entries if isinstance(e, classes)}
        if len(kinds) >= 3:
            found.append(name)
    return found


def test_the_hand_kept_list_check_can_fail():
    class Module:
        SCHEMES = [nvib.CentralDifference(), nvib.Newmark(), nvib.PreciseIntegration()]
        FAMILY = (nvib.CEMDTS(0.0), nvib.CEMDTS(0.5), nvib.CentralDifference())
    assert hand_kept_lists(Module) == ["SCHEMES"]


def test_the_cpp_tests_are_typed_over_the_registry():
    with open(os.path.join(ROOT, "tests", "cpp", "test_registry.cpp"), encoding="utf-8") as fh:
        assert "nvib::AllSchemes::for_each" in fh.read()
    with open(os.path.join(ROOT, "tests", "cpp", "CMakeLists.txt"), encoding="utf-8") as fh:
        assert "test_registry" in fh.read()


def test_the_helpers_follow_the_registry():
    ids = scheme_variants()
    for key, cls in nvib.schemes().items():
        assert type(ids[cls.__name__]) is cls and ids[cls.__name__] == cls()
    assert set(scheme_variants(explicit=True)) | set(scheme_variants(explicit=False)) == set(ids)
    assert all(key in nvib.schemes() for key in VARIANTS)
    nm = with_newton(nvib.Newmark(0.3, 0.6, iteration="modified"), jacobian="finite_difference")
    assert nm == nvib.Newmark(0.3, 0.6, newton=nvib.Newton(iteration="modified", jacobian="finite_difference"))
    assert with_newton(nvib.CEMDTS(0.2), max_iter=3) == nvib.CEMDTS(0.2)
