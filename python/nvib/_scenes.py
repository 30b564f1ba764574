"""Scenes: TOML files that declare a model (DOFs, mass, effects, initial state)
and its run settings. Built-in ones live in nvib/scenes/."""

from __future__ import annotations

import os
import sys

import numpy as np

from . import _checks
from ._core import ArgumentError
from ._model import Model, _units
from ._records import STANDARD_GRAVITY, GroundMotion

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

SCENE_DIR = os.path.join(os.path.dirname(__file__), "scenes")
_SCENE_KEYS = {"name", "title", "source", "t_end", "dt", "plot_dof", "record", "collapse_deformation"}
_TOP_KEYS = {"scene", "dofs", "initial", "effect", "damping", "storeys"}
MAX_SCENE_BYTES = 64 * 2**20  # a scene file larger than this is refused before it is read


class SceneError(ArgumentError):
    """A scene file is malformed or missing: the message names the file and the key; ``.argument`` is "scene"."""

    def __init__(self, message: str, key: str | None = None):
        super().__init__(message)
        self.argument = "scene"
        self.key = key  # the scene's table or key at fault, when known ("initial")


def scene_names() -> list[str]:
    """Names of the built-in scenes."""
    return sorted(f[:-5] for f in os.listdir(SCENE_DIR) if f.endswith(".toml"))


def scene_path(name_or_path: str) -> str:
    """The file of a scene: a built-in name wins unless the argument looks like a path (contains a
    folder separator or ends in .toml), so a file or folder named "building" in the working directory
    does not shadow the built-in scene."""
    looks_like_path = "/" in name_or_path or os.path.sep in name_or_path or name_or_path.endswith(".toml")
    builtin = os.path.join(SCENE_DIR, name_or_path + ".toml")
    if not looks_like_path and os.path.isfile(builtin):
        return builtin
    if looks_like_path or os.path.lexists(name_or_path):  # lexists: a broken link or a loop of them is named
        problem = _checks.input_file_problem(name_or_path, "scene file")
        if problem:
            raise FileNotFoundError(f"scene: {name_or_path!r}: {problem}")
        return name_or_path
    raise _checks.value_error("scene", f"unknown scene {name_or_path!r} (built-in: {', '.join(scene_names())}; a "
                                       "scene file is named by a path such as ./my_scene.toml)")


def load_scene(name_or_path: str, *, without=(), ground_motion: GroundMotion | None = None) -> Model:
    """Build the Model a scene declares; ``without`` leaves out effects by name or type; ``ground_motion``
    (a GroundMotion) replaces the signal of the scene's ground_acceleration effects (a record in g is
    turned into m/s^2, the built-in scenes' unit; refused, naming ``ground_motion``, for a scene
    without ground motion).

    The returned model carries the scene's settings in ``model.scene`` (name,
    title, source, dt, t_end, plot_dof, path, initial_u, notes). A scene that
    starts from its static equilibrium may have none once effects are left
    out (a vehicle without its wheel-rail contact): it then starts from the
    full scene's equilibrium, and ``model.scene["notes"]`` says so.
    """
    path = scene_path(str(name_or_path))
    data = _read_toml(path)
    without = (without,) if isinstance(without, str) else tuple(without)
    if ground_motion is not None:
        if not isinstance(ground_motion, GroundMotion):
            raise _checks.type_error("ground_motion", f"expected a GroundMotion, got {type(ground_motion).__name__}")
        if ground_motion.units == "g":
            ground_motion = ground_motion.scaled(STANDARD_GRAVITY)
    if not without:
        return scene_from_dict(data, path=path, ground_motion=ground_motion)
    full = scene_from_dict(data, path=path)
    names = sorted({e.name for e in full.effects if e.name})
    types = sorted({e.type for e in full.effects})
    for w in without:
        if w not in names and w not in types:
            raise _checks.value_error("without", f"no effect named or typed {w!r} in scene {full.scene['name']!r} "
                                                 f"(names: {', '.join(names) or '-'}; types: {', '.join(types) or '-'})")
    notes = []
    try:
        model = scene_from_dict(data, path=path, without=without, ground_motion=ground_motion)
    except SceneError as exc:
        if exc.key != "initial":
            raise
        # Without e.g. the wheel-rail contact a vehicle has no equilibrium to rest in:
        # start from the full scene's equilibrium instead (same initial state, fewer forces).
        data = dict(data, initial=dict(data.get("initial", {}), u=[float(x) for x in full.u0]))
        model = scene_from_dict(data, path=path, without=without, ground_motion=ground_motion)
        model.scene["initial_u"] = "static equilibrium of the full scene"
        notes.append(f"without {', '.join(without)} the model has no static equilibrium; "
                     f"starting from that of the full scene")
    if not model.effects:
        notes.append("no effects left: the model is a free mass (u = u0 + v0 t)")
    model.scene["notes"] = notes
    return model


def _read_toml(path: str) -> dict:
    """The TOML table of a scene file; every error names the file. Files over MAX_SCENE_BYTES are refused
    before they are read."""
    size = None
    try:
        with open(path, "rb") as fh:
            size = os.fstat(fh.fileno()).st_size
            if size > MAX_SCENE_BYTES:
                raise SceneError(_too_large(path, size))
            raw = fh.read(MAX_SCENE_BYTES + 1)  # the file may have grown since
        if len(raw) > MAX_SCENE_BYTES:
            raise SceneError(_too_large(path, len(raw)))
        try:
            text = raw.decode("utf-8")
        except UnicodeDecodeError as exc:
            line = raw.count(b"\n", 0, exc.start) + 1
            raise SceneError(f"{path}: not UTF-8 text: byte 0x{raw[exc.start]:02x} on line {line} (offset "
                             f"{exc.start}); a TOML file is UTF-8") from None
        del raw
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise SceneError(f"{path}: malformed TOML: {exc}") from None
    except RecursionError:
        raise SceneError(f"{path}: malformed TOML: arrays or inline tables nested too deeply to read") from None
    except MemoryError:
        raise SceneError(f"{path}: too large to read into memory"
                         + (f" ({_size_text(size)})" if size is not None else "")) from None


def _size_text(size: int) -> str:
    return f"{size / 2**20:.1f} MB" if size >= 2**20 else f"{size} bytes"


def _too_large(path: str, size: int) -> str:
    return (f"{path}: {_size_text(size)}, more than the {MAX_SCENE_BYTES // 2**20} MB a scene file may have "
            "(a scene declares its model; large data such as a ground-motion record goes in a file of its own)")


def _with_records(path: str, i: int, effect):
    """The effect with a record signal ({kind = "record", file = ...}) read, its file relative to the scene's."""
    signal = effect.get("signal") if isinstance(effect, dict) else None
    if not (isinstance(signal, dict) and signal.get("kind") == "record"):
        return effect
    try:
        record = GroundMotion.from_spec(f"effects[{i}].signal", signal, base_dir=os.path.dirname(os.path.abspath(path)))
    except (ValueError, TypeError) as exc:
        raise SceneError(f"{path}: {exc}", key="effect") from None
    return {**effect, "signal": record}


def _with_damping(path: str, model: Model, damping) -> Model:
    """[damping] rayleigh = { zeta = 0.05, omegas = [w1, w2] } (or modes = [1, 3], or alpha/beta)."""
    from ._damping import rayleigh

    if not isinstance(damping, dict) or set(damping) != {"rayleigh"} or not isinstance(damping["rayleigh"], dict):
        raise SceneError(f"{path}: [damping]: expected rayleigh = {{ zeta = ..., omegas = [...] }} (or modes = "
                         "[i, j], or alpha = ..., beta = ...)", key="damping")
    spec = damping["rayleigh"]
    unknown = set(spec) - {"zeta", "omegas", "modes", "alpha", "beta"}
    if unknown:
        raise SceneError(f"{path}: [damping] rayleigh.{sorted(unknown)[0]}: unknown key (expected zeta, omegas, "
                         "modes, alpha, beta)", key="damping")
    try:
        return rayleigh(model, **spec)
    except (ValueError, TypeError) as exc:
        raise SceneError(f"{path}: [damping] rayleigh.{exc}", key="damping") from None


def _scene_record(path: str, model: Model, record) -> list[str]:
    """[scene] record = ["storey1", ...]: effects a run of the scene records, each a name of its effects."""
    if isinstance(record, str):
        record = [record]
    if not isinstance(record, list) or not all(isinstance(r, str) for r in record):
        raise SceneError(f"{path}: [scene] record: expected a list of effect names")
    named = {e.name for e in model.effects or []} | {a.name for a in model.effect_arrays}
    for r in record:
        if r not in named and not any(w == r for w in model.without):
            raise SceneError(f"{path}: [scene] record: no effect named {r!r} (named: "
                             f"{', '.join(sorted(x for x in named if x)) or 'none'})")
    return [r for r in record if r in named]


def _require(path: str, table: dict, key: str, where: str):
    if key not in table:
        raise SceneError(f"{path}: [{where}] {key}: missing")
    return table[key]


def _with_ground_motion(path: str, effects: list, ground_motion: GroundMotion, without, scene: str) -> list:
    """The effects with every ground_acceleration that is not left out driven by ``ground_motion``."""
    def driven(e):
        return (isinstance(e, dict) and e.get("type") == "ground_acceleration"
                and e.get("name") not in without and e.get("type") not in without)

    if not any(driven(e) for e in effects):
        left_out = any(isinstance(e, dict) and e.get("type") == "ground_acceleration" for e in effects)
        raise _checks.value_error("ground_motion", f"scene {scene!r} has no ground motion to replace (no "
                                                   "ground_acceleration effect" + (" left: it is left out by "
                                                   "without)" if left_out else ")"))
    return [{**e, "signal": ground_motion} if driven(e) else e for e in effects]


def scene_from_dict(data: dict, *, path: str = "<scene>", without=(), ground_motion: GroundMotion | None = None) -> Model:
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
        if key not in ("names", "mass", "units"):
            raise SceneError(f"{path}: [dofs] {key}: unknown key (expected names, mass, units)")
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
    if ground_motion is not None:  # before the records are read: the scene's own is not needed then
        effects = _with_ground_motion(path, effects, ground_motion, tuple(without),
                                      meta.get("name", os.path.basename(path)[:-5]))
    effects = [_with_records(path, i, e) for i, e in enumerate(effects)]

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
        units = _units("[dofs] units", dofs.get("units", "m"), n)
        model = Model(m, effects=effects, dofs=names, u0=None if static else state("u"), v0=state("v"),
                      without=without, name=meta.get("name", os.path.basename(path)[:-5]), units=units)
    except (ValueError, TypeError) as exc:
        raise SceneError(f"{path}: {exc}") from None
    if static:
        try:
            model.u0 = model.static_equilibrium()
        except ArgumentError as exc:
            raise SceneError(f"{path}: {exc}", key="initial") from None
    damping = data.get("damping")
    if damping is not None:
        model = _with_damping(path, model, damping)
    settings = {}
    for key in ("dt", "t_end", "collapse_deformation"):
        if key in meta:
            try:
                settings[key] = _checks.real(key, meta[key], positive=True)  # scenes start at t = 0
            except (TypeError, ValueError) as exc:
                raise SceneError(f"{path}: [scene] {exc}") from None
    model.scene = {
        "name": meta.get("name", os.path.basename(path)[:-5]),
        "title": meta.get("title", ""),
        "source": meta.get("source", ""),
        "dt": settings.get("dt"),
        "t_end": settings.get("t_end"),
        "plot_dof": meta.get("plot_dof", names[0]),
        "record": _scene_record(path, model, meta.get("record", [])),
        "collapse_deformation": settings.get("collapse_deformation"),
        "path": path,
        "initial_u": "static_equilibrium" if static else "given",
        "notes": [],
    }
    if model.scene["plot_dof"] not in names:
        raise SceneError(f"{path}: [scene] plot_dof: unknown DOF {model.scene['plot_dof']!r}")
    model.scene["storeys"] = _scene_storeys(path, model, data.get("storeys"))
    return model


def _scene_storeys(path: str, model: Model, storeys) -> dict | None:
    """[storeys] storey1 = 3.5, ...: the effects whose measure is a storey drift, with their heights [m]
    (for drift ratios). Storeys left out with ``without`` are dropped."""
    if storeys is None:
        return None
    from ._storeys import storey_heights

    kept = {e.name for e in model.effects or [] if e.name}
    if not isinstance(storeys, dict):
        raise SceneError(f"{path}: [storeys]: expected a table of effect name = storey height [m]", key="storeys")
    storeys = {k: v for k, v in storeys.items() if k in kept or not model.without}
    if not storeys:  # every storey left out
        return None
    try:
        return storey_heights(model, storeys, argument="[storeys]")
    except (ValueError, TypeError) as exc:
        raise SceneError(f"{path}: {exc}", key="storeys") from None
