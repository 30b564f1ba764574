"""The schemes, as the C++ registry (cpp/include/nvib/schemes/all.hpp) declares
them: one class per scheme, bound by one generic template, with its
parameters, key, label and orders. Here they only get a Python signature and
a parameter list in their docstring, both generated from the declaration."""

from __future__ import annotations

import inspect

from . import _core
from ._core import Newton

__all__ = ["Newton", "scheme_classes", "schemes"]


def schemes() -> dict[str, type]:
    """The registry: command-line key -> scheme class, in registry order
    (``{"lcdm": CentralDifference, "cemdts": CEMDTS, ...}``)."""
    return {key: cls for key, cls in _core.SCHEMES}


def scheme_classes() -> list[type]:
    return [cls for _, cls in _core.SCHEMES]


def _describe(cls) -> tuple[inspect.Signature, str]:
    params, lines = [], []
    kinds = {True: inspect.Parameter.POSITIONAL_OR_KEYWORD, False: inspect.Parameter.KEYWORD_ONLY}
    for p in cls.parameters():
        params.append(inspect.Parameter(p["name"], kinds[p["positional"]], default=p["default"]))
        bounds = f", {p['bounds']}" if p["bounds"] else ""
        lines.append(f"    {p['name']} ({p['kind']}{bounds}; default {p['default']!r}): {p['doc']}")
    if any(p["kind"] == "newton" for p in cls.parameters()):
        params.append(inspect.Parameter("iteration", inspect.Parameter.KEYWORD_ONLY, default=None))
        lines.append("    iteration (choice): shortcut for newton=Newton(iteration=...)")
    return inspect.Signature(params), "\n".join(lines)


for _cls in [Newton] + scheme_classes():
    _cls.__module__ = "nvib"
    _cls.__signature__, _params = _describe(_cls)
    _cls.__doc__ = f"{_cls.__doc__}\n\nParameters\n----------\n{_params}\n"
del _cls, _params


def check_scheme(name: str, scheme) -> None:
    """Raises ArgumentTypeError naming ``name`` unless ``scheme`` is a scheme of the registry."""
    from ._checks import type_error

    classes = tuple(scheme_classes())
    if not isinstance(scheme, classes):
        raise type_error(name, f"expected a scheme ({', '.join(c.__name__ for c in classes)}), "
                               f"got {type(scheme).__name__}")
