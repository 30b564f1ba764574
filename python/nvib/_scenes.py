"""Scenes: TOML files that declare a model (DOFs, mass, effects, initial state)
and its run settings. Built-in ones live in nvib/scenes/."""

from __future__ import annotations

import os
import sys

import numpy as np

from . import _checks
from ._model import Model

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

SCENE_DIR = os.path.join(os.path.dirname(__file__), "scenes")
_SCENE_KEYS = {"name", "title", "source", "t_end", "dt", "plot_dof"}
_TOP_KEYS = {"scene", "dofs", "initial", "effect"}


class SceneError(ValueError):
    """A scene file is malformed: the message names the file and the key."""


def scene_names() -> list[str]:
    """Names of the built-in scenes."""
    return sorted(f[:-5] for f in os.listdir(SCENE_DIR) if f.endswith(".toml"))


def scene_path(name_or_path: str) -> str:
    if os.path.sep in name_or_path or name_or_path.endswith(".toml") or os.path.exists(name_or_path):
        if not os.path.isfile(name_or_path):
            raise FileNotFoundError(f"scene: no such file {name_or_path!r}")
        return name_or_path
    path = os.path.join(SCENE_DIR, name_or_path + ".toml")
    if not os.path.isfile(path):
        raise _checks.value_error("scene", f"unknown scene {name_or_path!r} (built-in: {', '.join(scene_names())})")
    return path


def load_scene(name_or_path: str, *, without=()) -> Model:
    """Build the Model a scene declares; ``without`` leaves out effects by name or type.

    The returned model carries the scene's settings in ``model.scene``
    (name, title, source, dt, t_end, plot_dof, path).
    """
    path = scene_path(str(name_or_path))
    try:
        with open(path, "rb") as fh:
            data = tomllib.load(fh)
    except tomllib.TOMLDecodeError as exc:
        raise SceneError(f"{path}: malformed TOML: {exc}") from None
    return scene_from_dict(data, path=path, without=without)


def _require(path: str, table: dict, key: str, where: str):
    if key not in table:
        raise SceneError(f"{path}: [{where}] {key}: missing")
    return table[key]


def scene_from_dict(data: dict, *, path: str = "<scene>", without=()) -> Model:
    for key in data:
        if key not in _TOP_KEYS:
            raise SceneError(f"{path}: {key}: unknown table (expected {', '.join(sorted(_TOP_KEYS))})")
    meta = data.get("scene", {})
    for key in meta:
        if key not in _SCENE_KEYS:
            raise SceneError(f"{path}: [scene] {key}: unknown key (expected {', '.join(sorted(_SCENE_KEYS))})")
    dofs = _require(path, data, "dofs", "dofs")
    names = _require(path, dofs, "names", "dofs")
    mass = _require(path, dofs, "mass", "dofs")
    for key in dofs:
        if key not in ("names", "mass"):
            raise SceneError(f"{path}: [dofs] {key}: unknown key (expected names, mass)")
    if not isinstance(names, list) or not all(isinstance(n, str) for n in names):
        raise SceneError(f"{path}: [dofs] names: expected a list of strings")
    n = len(names)
    try:
        m = _checks.real_array("mass", mass)
    except (TypeError, ValueError) as exc:
        raise SceneError(f"{path}: [dofs] {exc}") from None
    if m.shape not in ((n,), (n, n)):
        raise SceneError(f"{path}: [dofs] mass: expected {n} entries (one per DOF) or a {n}x{n} matrix, "
                         f"got shape {m.shape}")
    if m.ndim == 1 and np.any(~(m > 0)):
        i = int(np.argmax(~(m > 0)))
        raise SceneError(f"{path}: [dofs] mass: entry {i} ({names[i]}) is {m[i]:g}; every mass must be > 0")
    effects = data.get("effect", [])
    if not isinstance(effects, list):
        raise SceneError(f"{path}: effect: expected [[effect]] tables")

    initial = data.get("initial", {})
    for key in initial:
        if key not in ("u", "v"):
            raise SceneError(f"{path}: [initial] {key}: unknown key (expected u, v)")

    def state(key):
        val = initial.get(key, [0.0] * n)
        if isinstance(val, dict):
            arr = np.zeros(n)
            for dof, x in val.items():
                if dof not in names:
                    raise SceneError(f"{path}: [initial] {key}: unknown DOF {dof!r}")
                try:
                    arr[names.index(dof)] = _checks.real(f"{key}.{dof}", x)
                except (TypeError, ValueError) as exc:
                    raise SceneError(f"{path}: [initial] {exc}") from None
            return arr
        try:
            arr = _checks.real_array(key, val)
        except (TypeError, ValueError) as exc:
            raise SceneError(f"{path}: [initial] {exc}") from None
        if arr.shape != (n,):
            raise SceneError(f"{path}: [initial] {key}: expected {n} entries, got {arr.size}")
        return arr

    u_spec = initial.get("u")
    static = isinstance(u_spec, str)
    if static and u_spec != "static_equilibrium":
        raise SceneError(f"{path}: [initial] u: expected a list, a table DOF = value or \"static_equilibrium\", "
                         f"got {u_spec!r}")
    try:
        model = Model(m, effects=effects, dofs=names, u0=None if static else state("u"), v0=state("v"),
                      without=without, name=meta.get("name", os.path.basename(path)[:-5]))
        if static:
            model.u0 = model.static_equilibrium()
    except (ValueError, TypeError) as exc:
        raise SceneError(f"{path}: {exc}") from None
    settings = {}
    for key in ("dt", "t_end"):
        if key in meta:
            try:
                settings[key] = _checks.real(key, meta[key], positive=key == "dt")
            except (TypeError, ValueError) as exc:
                raise SceneError(f"{path}: [scene] {exc}") from None
    model.scene = {
        "name": meta.get("name", os.path.basename(path)[:-5]),
        "title": meta.get("title", ""),
        "source": meta.get("source", ""),
        "dt": settings.get("dt"),
        "t_end": settings.get("t_end"),
        "plot_dof": meta.get("plot_dof", names[0]),
        "path": path,
        "initial_u": "static_equilibrium" if static else "given",
    }
    if model.scene["plot_dof"] not in names:
        raise SceneError(f"{path}: [scene] plot_dof: unknown DOF {model.scene['plot_dof']!r}")
    return model
