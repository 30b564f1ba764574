"""The Python Model: a mass plus declared effects (built-in or Python laws) and an optional force callable."""

from __future__ import annotations

import numbers

import numpy as np

from . import _checks, _compiled, _core
from ._core import ArgumentError
from ._names import GeneratedNames, NumberedNames
from ._records import GroundMotion

def _effect_parameters() -> dict[str, tuple[tuple[str, ...], dict[str, object]]]:
    """(required, optional-with-default) parameters of each built-in effect type, from the C++ laws
    (an optional parameter without a default, such as bouc_wen's ``dy`` beside ``fy``, has None);
    a law's signal (``irregularity``, ``signal``) is a parameter too (a table, see ``_signal``)."""
    out = {}
    for kind, law in _core.laws().items():
        required = tuple(name for name, default, _, may_be_unset, _ in law["parameters"]
                         if default is None and not may_be_unset)
        optional = {name: (choices.split("|")[0] if choices else default)
                    for name, default, _, may_be_unset, choices in law["parameters"]
                    if default is not None or may_be_unset}
        if law["signal"]:
            if law["signal_required"]:
                required += (law["signal"],)
            else:
                optional[law["signal"]] = None
        out[kind] = (required, optional)
    return out


EFFECT_PARAMETERS = _effect_parameters()
"""Parameters of each built-in effect type: (required, optional with their defaults). Every effect may
also carry a ``name`` and a free-text ``note``."""
_CHOICES = {kind: {name: choices.split("|") for name, _, _, _, choices in law["parameters"] if choices}
            for kind, law in _core.laws().items()}
_COMMON_KEYS = ("type", "measure", "name", "note")
_SIGNAL_KEYS = {"sine": (("amplitude", "omega"), {"phase": 0.0}), "table": (("t", "values"), {})}


def _signal(where: str, spec) -> dict:
    """A signal: {kind = "sine", amplitude, omega, phase = 0}, {kind = "table", t = [...], values = [...]},
    a GroundMotion, or {kind = "record", file = ..., scale = 1, dt = ...} (a record file, see GroundMotion)."""
    if isinstance(spec, GroundMotion):
        spec = spec.signal()
    elif isinstance(spec, dict) and spec.get("kind") == "record":
        spec = GroundMotion.from_spec(where, spec).signal()
    if not isinstance(spec, dict):
        raise _checks.type_error(where, f"expected a table with 'kind' = 'sine', 'table' or 'record', or a "
                                        f"GroundMotion, got {type(spec).__name__}")
    kind = spec.get("kind")
    if kind not in _SIGNAL_KEYS:
        raise _checks.value_error(f"{where}.kind", f"expected 'sine', 'table' or 'record', got {kind!r}")
    required, optional = _SIGNAL_KEYS[kind]
    _checks.unknown_keys(where, spec, ("kind",) + required + tuple(optional), f"a {kind} signal")
    for key in required:
        if key not in spec:
            raise _checks.value_error(f"{where}.{key}", "missing")
    out = {"signal": kind}
    if kind == "sine":
        out["amplitude"] = _checks.real(f"{where}.amplitude", spec["amplitude"])
        out["omega"] = _checks.real(f"{where}.omega", spec["omega"])
        out["phase"] = _checks.real(f"{where}.phase", spec.get("phase", 0.0))
    else:
        t, y = _checks.samples(f"{where}.t", f"{where}.values", spec["t"], spec["values"], nonfinite=where)
        out["t"], out["values"] = t.tolist(), y.tolist()
    return out


def _law_parameters(where: str, kind: str, spec: dict, convert) -> tuple[dict, dict]:
    """The parameters of law `kind` given in `spec`, each as convert("effects[i].<key>", value),
    and its signal's keyword arguments (empty without one)."""
    required, optional = EFFECT_PARAMETERS[kind]
    signal_key = _core.laws()[kind]["signal"]
    params, signal = {}, {}
    for key in list(required) + list(optional):
        if key not in spec:
            continue
        if key == signal_key:
            signal = _signal(f"{where}.{key}", spec[key])
        elif key in _CHOICES[kind]:  # a word, passed to the law as its place in the list
            words = _CHOICES[kind][key]
            if spec[key] not in words:
                raise _checks.value_error(f"{where}.{key}", f"expected one of {', '.join(map(repr, words))}, "
                                                            f"got {spec[key]!r}")
            params[key] = float(words.index(spec[key]))
        else:
            params[key] = convert(f"{where}.{key}", spec[key])
    return params, signal


def _python_law_flags(where: str, spec: dict) -> list:
    """A Python law's declared uses_velocity and uses_time (True unless said otherwise), checked."""
    flags = []
    for key in ("uses_velocity", "uses_time"):
        value = spec.get(key, True)
        if not isinstance(value, bool):
            raise _checks.type_error(f"{where}.{key}", f"expected True or False, got {value!r}")
        flags.append(value)
    return flags


def _effect_name(where: str, spec: dict) -> str:
    name = spec.get("name", "")
    if not isinstance(name, str):
        raise _checks.type_error(f"{where}.name", "expected a string")
    return name


def _units(where: str, units, n: int):
    """One unit string for every DOF, or a list of n (kept as one string when they are all the same)."""
    if isinstance(units, str):
        if not units.strip():
            raise _checks.value_error(where, "expected a unit such as 'm' or 'rad', got an empty string")
        return units
    if not hasattr(units, "__iter__"):
        raise _checks.type_error(where, f"expected a string or a list of {n} strings, got {type(units).__name__}")
    units = list(units)
    if len(units) != n:
        raise _checks.value_error(where, f"expected {n} units (one per DOF), got {len(units)}")
    for k, u in enumerate(units):
        if not isinstance(u, str) or not u.strip():
            raise _checks.type_error(f"{where}[{k}]", f"expected a unit such as 'm' or 'rad', got {u!r}")
    return units[0] if len(set(units)) == 1 else units


def unit_list(units, n: int) -> list[str]:
    """The unit of each of n DOFs from what ``_units`` keeps: one string for all, or a list."""
    return [units] * n if isinstance(units, str) else list(units)


def rate_unit(unit: str, power: int) -> str:
    """The unit of the displacement (power 0), velocity (1) or acceleration (2) of a DOF in ``unit``."""
    return unit if power == 0 else f"{unit}/s" if power == 1 else f"{unit}/s^2"


def _rebuild_model(init, state) -> "Model":
    mass, kwargs = init
    model = Model(mass, **kwargs)
    model.__dict__.update(state)
    return model


def _rebuild_cloudpickled(payload: bytes) -> "Model":
    """A model whose arguments were pickled by cloudpickle (its Python callables: lambdas and closures
    travel by value); the standard unpickler reads cloudpickle's output."""
    import pickle

    return _rebuild_model(*pickle.loads(payload))


class Model:
    """M a + K u + C v + F(u, v, t) = 0 with F the declared effects and an optional force callable.

    Parameters
    ----------
    mass : 1-D array (lumped/diagonal mass), a scipy.sparse symmetric positive definite matrix (a
        consistent mass: factorised once by a sparse Cholesky), or a dense one (up to 2000 DOFs).
    K, C : optional constant stiffness and damping matrices, dense arrays or scipy.sparse matrices;
        they are kept sparse, with the linear springs and dampers among the effects added in.
    force : optional callable ``force(u, v, t) -> array (n,)``: the nonlinear
        force on the left-hand side, loads included with a minus sign.
    tangent : optional callable ``tangent(u, v, t) -> (K_t, C_t)`` (C_t may be
        None); without it, central finite differences are used and counted in
        ``stats.num_fd_force_evals``.
    effects : optional list of effects, each a dict such as
        ``{"type": "hardening_spring", "measure": {"x": 1.0}, "k0": 100, "a": 30}``.
        Built-in effects are evaluated in C++ with no Python in the loop. A
        Python law is an effect too: ``{"type": "callable", "measure": {...},
        "law": f(d, dd, t) -> float, "tangent": optional (d, dd, t) -> (df/dd, df/ddd),
        "uses_velocity": True, "uses_time": True, "name": ...}`` acts as g^T f on
        its measure d = g . u. ``force`` may be given with ``effects``: both act.
    dofs : optional DOF names (used by effect measures and by ``solve(dofs=...)``).
    u0, v0 : initial state (zeros by default).
    uses_velocity, uses_time : declare that ``force`` does not depend on v or t,
        so the schemes can skip what is not needed (a callable effect declares its own).
    units : the unit of each DOF's displacement, one string for all or one per DOF (default "m").
        nvib is unit-agnostic (any consistent set of units works); units only label plots and tables.
        Velocities are in units/s, accelerations in units/s^2, times in s.
    """

    def __init__(self, mass, *, K=None, C=None, force=None, tangent=None, effects=None, dofs=None,
                 u0=None, v0=None, uses_velocity: bool = True, uses_time: bool = True, without=(), name: str = "",
                 units="m", _mass_of=None):
        # _mass_of: the core of a model with this very mass (_rebuilt()), whose factorised mass is shared
        if effects is not None and not isinstance(effects, list):
            effects = list(effects)  # once: a generator is read here
        # The arguments, for pickling and copying (the core model is rebuilt from them).
        self._init = (mass, dict(K=K, C=C, force=force, tangent=tangent, effects=effects, dofs=dofs, u0=u0, v0=v0,
                                 uses_velocity=uses_velocity, uses_time=uses_time, without=without, name=name,
                                 units=units))
        if _checks.is_sparse(mass):
            m = _checks.sparse_matrix("mass", mass)
        else:
            m = np.ascontiguousarray(_checks.real_array("mass", [mass] if isinstance(mass, numbers.Real) else mass))
            if m.ndim not in (1, 2):
                raise _checks.value_error("mass", f"expected a 1-D array (diagonal), a 2-D matrix or a scipy.sparse "
                                                  f"matrix, got {m.ndim} dimensions")
        n = m.shape[0]
        if n == 0:
            raise _checks.value_error("mass", "the model needs at least one degree of freedom")
        self.n = n
        if dofs is None:
            dofs = NumberedNames("u", n)  # u0, u1, ... made on demand
        if isinstance(dofs, (str, bytes)) or not hasattr(dofs, "__iter__"):
            raise _checks.type_error("dofs", f"expected a list of {n} names, got {type(dofs).__name__}")
        if not isinstance(dofs, GeneratedNames):  # generated names are unique strings by construction
            dofs = list(dofs)
            for k, d in enumerate(dofs):
                if not isinstance(d, str):  # an integer in a measure means a DOF index, never a name
                    raise _checks.type_error(f"dofs[{k}]", f"expected a name (a string), got {d!r}; integers in "
                                                           "measures and dofs= already mean DOF indices")
            if len(set(dofs)) != len(dofs):
                raise _checks.value_error("dofs", "names must be unique")
        if len(dofs) != n:
            raise _checks.value_error("dofs", f"expected {n} names, got {len(dofs)}")
        self.dofs = dofs
        self._lookup: dict | None = None
        self._units = _units("units", units, n)
        Km = _checks.linear_part("K", K, n)
        Cm = _checks.linear_part("C", C, n)
        self.u0 = _checks.vector("u0", np.zeros(n) if u0 is None else u0, n)
        self.v0 = _checks.vector("v0", np.zeros(n) if v0 is None else v0, n)
        if force is not None and not callable(force):
            raise _checks.type_error("force", f"expected a callable force(u, v, t), got {type(force).__name__}")
        if tangent is not None and not callable(tangent):
            raise _checks.type_error("tangent", f"expected a callable tangent(u, v, t) -> (K, C), got {type(tangent).__name__}")
        if tangent is not None and force is None:
            raise _checks.value_error("tangent", "given without a force")
        self.force = force
        self.tangent = tangent
        self.name = str(name)
        self._declared = effects is not None
        self.python_laws: list[str] = []  # where each Python law sits ("effects[3]")
        self.without = (without,) if isinstance(without, str) else tuple(without)
        builtin, laws, arrays, vector_laws = [], [], [], []
        if effects is not None:
            effects = list(effects)
            known = {e.get("name") for e in effects if isinstance(e, dict)} | {
                e.get("type") for e in effects if isinstance(e, dict)}
            for w in self.without:
                if w not in known:
                    names = sorted({str(e.get("name")) for e in effects if isinstance(e, dict) and e.get("name")})
                    types = sorted({str(e.get("type")) for e in effects if isinstance(e, dict) and e.get("type")})
                    raise _checks.value_error("without", f"no effect named or typed {w!r} in this model "
                                              f"(names: {', '.join(names) or 'none'}; types: {', '.join(types)})")
            for i, e in enumerate(effects):
                if isinstance(e, dict) and (e.get("name") in self.without or e.get("type") in self.without):
                    continue
                if isinstance(e, dict) and e.get("type") == "compiled" and "law" in e:
                    e = _compiled.lower(f"effects[{i}]", e)  # the built-in law that calls it
                if isinstance(e, dict) and e.get("type") == "callable" and "i" in e:
                    vector_laws.append(self._python_array_law(i, e))
                elif isinstance(e, dict) and e.get("type") == "callable":
                    laws.append(self._python_law(i, e))
                elif isinstance(e, dict) and "i" in e:
                    arrays.append(self._effect_array(i, e))
                else:
                    builtin.append(self._effect(i, e))
            self.python_laws = sorted((law[4] for law in laws + vector_laws), key=lambda w: int(w[8:-1]))
        elif self.without:
            raise _checks.value_error("without", "only a model of declared effects can leave effects out")
        # With Python in the loop (force or callable laws) the GIL is kept during runs.
        self._core = _core.Model(m, builtin, Km, Cm, dofs, force, tangent, _checks.boolean("uses_velocity", uses_velocity),
                                 _checks.boolean("uses_time", uses_time), laws, arrays, vector_laws, _mass_of)

    def __repr__(self) -> str:
        """Size, DOFs, mass, linear parts, effects by type, Python callables and flags, in one line."""
        from collections import Counter

        head = f"Model({self.name!r}, " if self.name else "Model("
        dofs = list(self.dofs[:4]) + (["..."] if self.n > 5 else []) + ([self.dofs[self.n - 1]] if self.n > 4 else [])
        parts = [f"{self.n} DOF{'s' if self.n != 1 else ''} [{', '.join(map(str, dofs))}]",
                 f"mass {self._core.mass_kind}"]
        units = sorted(set(self.units))
        parts.append(f"units {'/'.join(units)}")
        for name, mat in (("K", self.K), ("C", self.C)):
            if mat.nnz:
                parts.append(f"{name} with {mat.nnz} nonzeros")
        counts = Counter(e.type for e in (self.effects or []))
        for arr in self.effect_arrays:
            counts[arr.type] += len(arr)
        if counts:
            parts.append("effects: " + ", ".join(k if c == 1 else f"{k} x{c}" for k, c in counts.items()))
        if self.python_laws:
            parts.append(f"{len(self.python_laws)} Python law{'s' if len(self.python_laws) != 1 else ''}")
        if self.force is not None:
            parts.append("force callable" + (" with tangent" if self.tangent is not None else ""))
        if self.without:
            parts.append(f"without {', '.join(self.without)}")
        flags = [f for f, on in (("linear", self.is_linear), ("uses_velocity", self.uses_velocity),
                                 ("uses_time", self.uses_time)) if on]
        if flags:
            parts.append(", ".join(flags))
        return head + "; ".join(parts) + ")"

    def __reduce__(self):
        """Pickled as its arguments and its attributes (u0, v0, scene, ...): the core is rebuilt on loading, so
        a model goes to another process (a process pool, Dask). A model that calls Python has its arguments
        pickled by cloudpickle, so that lambdas and closures (the code and what it refers to) travel too; a
        compiled law made by Numba travels as its Python function and is compiled again on loading."""
        mass, kwargs = self._init
        init = (mass, {**kwargs, "effects": _compiled.travelling(kwargs["effects"])}) if kwargs.get("effects") else self._init
        if self._core.has_python:
            import cloudpickle

            return (_rebuild_cloudpickled, (cloudpickle.dumps((init, self._state())),))
        return (_rebuild_model, (init, self._state()))

    def _state(self) -> dict:
        """Its attributes besides the core and what is made from the arguments (u0, v0, scene, ...)."""
        return {k: v for k, v in self.__dict__.items() if k not in ("_core", "_lookup", "_init")}

    def _rebuilt(self, **changes) -> "Model":
        """The model built again from its arguments with ``changes`` (effects=, C=, ...), its attributes kept.
        The mass is not among the changes: the new model shares this one's, factorised (a batch builds one model
        per run, and a large model's consistent mass takes a tenth of a second or more to factorise)."""
        if "mass" in changes:
            raise ValueError("_rebuilt() keeps the mass")
        mass, kwargs = self._init
        model = Model(mass, **{**kwargs, **changes}, _mass_of=self._core)
        state = self._state()
        # What was computed from the linear part (the modes of the stability check) holds for the new model
        # only if its K and C are this one's: other C (rayleigh()) or other linear springs change them.
        if "_linear_modes" in state and not model._core.same_linear_parts(self._core):
            del state["_linear_modes"]
        model.__dict__.update(state)
        return model

    def _python_law(self, i: int, spec: dict):
        """A scalar law given as Python callables on a measure: {"type": "callable", "measure": {...},
        "law": f(d, d', t) -> float, "tangent": optional (d, d', t) -> (df/dd, df/dd'),
        "uses_velocity": True, "uses_time": True, "name": ""}; with memory, "state": its initial internal
        variables (a list of floats), and then law(d, d', t, state) -> (f, trial state) and
        tangent(d, d', t, state) -> (df/dd, df/dd'), ``state`` the committed one (a tuple)."""
        where = f"effects[{i}]"
        allowed = {"type", "measure", "law", "tangent", "uses_velocity", "uses_time", "name", "note", "state"}
        for key in spec:
            if key not in allowed:
                raise _checks.value_error(f"{where}.{key}", f"unknown key of a callable effect (expected "
                                 f"{', '.join(sorted(allowed - {'type'}))})")
        law = spec.get("law")
        stateful = spec.get("state") is not None
        signature = "law(d, dd, t, state) -> (force, state)" if stateful else "law(d, dd, t) -> float"
        if not callable(law):
            raise _checks.type_error(f"{where}.law", f"expected a callable {signature}, got {type(law).__name__}")
        tangent = spec.get("tangent")
        if tangent is not None and not callable(tangent):
            raise _checks.type_error(f"{where}.tangent", f"expected a callable tangent(d, dd, t{', state' if stateful else ''}) "
                            f"-> (df/dd, df/ddd), got {type(tangent).__name__}")
        initial = []
        if stateful:
            state = spec["state"]
            if isinstance(state, (str, bytes)) or not hasattr(state, "__iter__"):
                raise _checks.type_error(f"{where}.state", f"expected the initial internal variables, a list of floats, "
                                                            f"got {type(state).__name__}")
            initial = [_checks.real(f"{where}.state[{k}]", x) for k, x in enumerate(state)]
            if not initial:
                raise _checks.value_error(f"{where}.state", "a law with memory needs at least one internal variable")
        measure = spec.get("measure")
        if not isinstance(measure, dict) or not measure:
            raise _checks.value_error(f"{where}.measure", "expected a non-empty mapping DOF -> coefficient")
        index = [self._dof_index(f"{where}.measure", k) for k in measure]
        coef = [_checks.real(f"{where}.measure[{k!r}]", c) for k, c in measure.items()]
        flags = _python_law_flags(where, spec)
        _effect_name(where, spec)
        return (index, coef, law, tangent, where, *flags, initial)

    def _python_array_law(self, i: int, spec: dict):
        """A vectorised Python law on many effects: {"type": "callable", "i": [...], "j": [...] (optional; -1:
        the ground), "law": f(d, d', t) -> forces, "tangent": optional (d, d', t) -> (df/dd, df/dd'), arrays of
        every effect at once; with memory "state": the initial internal variables (one row for every effect,
        or one row per effect), then law(d, d', t, state) -> (forces, states) and tangent(d, d', t, state),
        ``state`` the committed states, an array (effects, variables)}."""
        where = f"effects[{i}]"
        allowed = {"type", "i", "j", "law", "tangent", "uses_velocity", "uses_time", "name", "note", "state"}
        for key in spec:
            if key not in allowed:
                raise _checks.value_error(f"{where}.{key}", f"unknown key of a vectorised callable effect (expected "
                                                            f"{', '.join(sorted(allowed - {'type'}))})")
        law, tangent = spec.get("law"), spec.get("tangent")
        if not callable(law):
            raise _checks.type_error(f"{where}.law", f"expected a callable law(d, dd, t) -> forces (arrays of every "
                                                     f"effect), got {type(law).__name__}")
        if tangent is not None and not callable(tangent):
            raise _checks.type_error(f"{where}.tangent", f"expected a callable tangent(d, dd, t) -> (df/dd, df/ddd), "
                                                         f"got {type(tangent).__name__}")
        idx, jdx = self._array_ends(where, spec)
        if jdx is None:
            jdx = np.full(idx.size, -1, dtype=np.int32)  # every effect to the ground
        initial, width = [], 0
        if spec.get("state") is not None:
            state = _checks.real_array(f"{where}.state", spec["state"])
            if state.ndim == 1:
                state = np.tile(state, (idx.size, 1))
            if state.ndim != 2 or state.shape[0] != idx.size or state.shape[1] == 0:
                raise _checks.value_error(f"{where}.state", f"expected the initial internal variables: one row for "
                                                            f"every effect, or {idx.size} rows (one per effect)")
            initial, width = np.ascontiguousarray(state).reshape(-1).tolist(), state.shape[1]
        flags = _python_law_flags(where, spec)
        _effect_name(where, spec)
        return (idx.tolist(), jdx.tolist(), law, tangent, where, *flags, initial, width)

    def _effect_array(self, i: int, spec: dict) -> "_core.EffectArray":
        """Many effects of one law: {"type": ..., "i": [...], "j": [...] (optional; -1: the ground; one
        index or name: the same for every effect), each
        parameter one value or one per effect, "name": ...}; d_k = u[i_k] - u[j_k]."""
        where = f"effects[{i}]"
        kind = spec.get("type")
        if kind not in EFFECT_PARAMETERS:
            raise _checks.value_error(f"{where}.type", f"unknown effect type {kind!r} (known: {', '.join(EFFECT_PARAMETERS)})")
        required, optional = EFFECT_PARAMETERS[kind]
        for key in spec:
            if key not in ("type", "i", "j", "name", "note") and key not in required and key not in optional:
                raise _checks.value_error(f"{where}.{key}", f"unknown parameter of {kind} "
                                                            f"(expected i, j, {', '.join(required + tuple(optional))})")
        idx, jdx = self._array_ends(where, spec)

        def per_effect(arg: str, value) -> np.ndarray:
            arr = _checks.real_array(arg, value)
            if arr.ndim > 1 or (arr.ndim == 1 and arr.size not in (1, idx.size)):
                raise _checks.value_error(arg, f"expected one value or {idx.size} (one per effect), got shape {arr.shape}")
            return np.ascontiguousarray(arr.reshape(-1))

        params, signal = _law_parameters(where, kind, spec, per_effect)
        name = _effect_name(where, spec)
        try:
            return _core.EffectArray(kind, idx, jdx if jdx is not None else np.empty(0, dtype=np.int32), params,
                                     self.n, name=name, **signal)
        except ArgumentError as exc:  # names the parameter or entry: make it effects[i].<it>
            raise _checks.value_error(f"{where}.{exc.argument}", exc.reason) from None

    def _array_ends(self, where: str, spec: dict):
        """The DOFs an array's effects join, i and j (None when not given; one DOF or -1, the ground, for
        every effect), checked."""
        idx = self._dof_array(f"{where}.i", spec["i"], ground=False)
        jspec = spec.get("j")
        if isinstance(jspec, (str, numbers.Integral)) and not isinstance(jspec, bool):
            jspec = [jspec] * idx.size
        jdx = self._dof_array(f"{where}.j", jspec, ground=True) if jspec is not None else None
        if jdx is not None and jdx.shape != idx.shape:
            raise _checks.value_error(f"{where}.j", f"expected {idx.size} entries (as many as i), got {jdx.size}")
        return idx, jdx

    def _dof_array(self, where: str, values, *, ground: bool) -> np.ndarray:
        """DOF indices (int32) from integers or DOF names; -1 (the ground) where ``ground``."""
        if isinstance(values, (str, bytes)) or np.ndim(values) != 1:
            raise _checks.type_error(where, "expected a 1-D list or array of DOF indices or names")
        arr = np.asarray(values)
        if arr.dtype.kind in "USO":  # names (and maybe -1 for the ground): map the given items, not their strings
            items = values.tolist() if isinstance(values, np.ndarray) else list(values)
            arr = np.asarray([self._dof_index(where, v) if isinstance(v, str) else v for v in items])
        if arr.size == 0 or arr.dtype.kind not in "iu":
            raise _checks.type_error(where, "expected a non-empty list of DOF indices or names")
        lo = -1 if ground else 0
        bad = np.flatnonzero((arr < lo) | (arr >= self.n))
        if bad.size:
            raise _checks.value_error(f"{where}[{bad[0]}]", f"DOF index {arr[bad[0]]} is out of range for {self.n} "
                                                            "degrees of freedom" + (" (-1: the ground)" if ground else ""))
        return arr.astype(np.int32)

    def _dof_index(self, where: str, key) -> int:
        if isinstance(key, numbers.Integral) and not isinstance(key, bool):
            if not 0 <= int(key) < self.n:
                raise _checks.value_error(where, f"DOF index {key} is out of range for {self.n} degrees of freedom")
            return int(key)
        if isinstance(self.dofs, GeneratedNames):
            k = self.dofs.number(key) if isinstance(key, str) else None
            if k is not None:
                return k
        else:
            if self._lookup is None:  # built once: a list's index() is O(n) per call
                self._lookup = {d: k for k, d in enumerate(self.dofs)}
            if isinstance(key, str) and key in self._lookup:
                return self._lookup[key]
        known = ", ".join(self.dofs[:20]) + (f", ... ({self.n} in all)" if self.n > 20 else "")
        raise _checks.value_error(where, f"unknown DOF {key!r} (known: {known})")

    def _effect(self, i: int, spec) -> "_core.Effect":
        where = f"effects[{i}]"
        if not isinstance(spec, dict):
            raise _checks.type_error(where, f"expected a dict with 'type' and 'measure', got {type(spec).__name__}")
        kind = spec.get("type")
        if kind not in EFFECT_PARAMETERS:
            raise _checks.value_error(f"{where}.type", f"unknown effect type {kind!r} "
                                      f"(known: {', '.join(EFFECT_PARAMETERS)}, callable)")
        if "measure" in spec:
            measure = spec["measure"]
            if not isinstance(measure, dict) or not measure:
                raise _checks.value_error(f"{where}.measure", "expected a non-empty mapping DOF -> coefficient")
            index = [self._dof_index(f"{where}.measure", k) for k in measure]
            coef = [_checks.real(f"{where}.measure[{k!r}]", c) for k, c in measure.items()]
        elif kind == "ground_acceleration":  # every DOF moves with the ground
            index, coef = np.arange(self.n), np.ones(self.n)
        else:
            raise _checks.value_error(f"{where}.measure", "missing")
        required, optional = EFFECT_PARAMETERS[kind]
        for key in spec:
            if key not in _COMMON_KEYS and key not in required and key not in optional:
                raise _checks.value_error(f"{where}.{key}", f"unknown parameter of {kind} (expected {', '.join(required + tuple(optional))})")
        for key in required:
            if key not in spec:
                raise _checks.value_error(f"{where}.{key}", f"missing parameter of {kind}")
        params, signal = _law_parameters(where, kind, spec, _checks.real)
        name = _effect_name(where, spec)
        try:
            return _core.Effect(kind, index, coef, params, name=name, **signal)
        except ArgumentError as exc:  # names the parameter: make it effects[i].<parameter>
            raise _checks.value_error(f"{where}.{exc.argument}", exc.reason) from None

    @property
    def effects(self) -> list | None:
        """The built-in effects declared one by one (``_core.Effect``; None for a model declared
        without ``effects``). Held by the core; this list is made on each access."""
        return self._core.effects if self._declared else None

    @property
    def effect_arrays(self) -> list:
        """The effect arrays (``_core.EffectArray``), held by the core; made on each access."""
        return self._core.effect_arrays

    @property
    def units(self) -> list[str]:
        """The unit of each DOF's displacement (velocities in units/s, accelerations in units/s^2)."""
        return unit_list(self._units, self.n)

    def unit(self, dof) -> str:
        """The unit of one DOF (a name or an index)."""
        return self._units if isinstance(self._units, str) else self._units[self._dof_index("dof", dof)]

    @property
    def uses_velocity(self) -> bool:
        return self._core.uses_velocity

    @property
    def uses_time(self) -> bool:
        return self._core.uses_time

    @property
    def is_linear(self) -> bool:
        return self._core.is_linear

    @property
    def warnings(self) -> list[str]:
        """What the accepted model still wants said, each starting with the argument it is about: a nearly
        singular mass (its DOF named), a K or C symmetric only up to round-off. Every run's
        ``Result.warnings`` repeats them."""
        return list(self._core.warnings)

    @property
    def mass_matrix(self) -> np.ndarray:
        """The mass as a dense array (models of up to 2000 DOFs; see ``mass_sparse``)."""
        if self.n > 2000:
            raise _checks.value_error("mass_matrix", f"a dense {self.n} x {self.n} array would take "
                                                     f"{8e-6 * self.n ** 2:.0f} MB; use mass_sparse")
        return self._core.mass_matrix

    @property
    def mass_sparse(self):
        """The mass as a scipy.sparse matrix (compressed columns)."""
        return self._core.mass_sparse

    @property
    def K(self):
        """The linear stiffness (the K given plus every linear spring), a scipy.sparse matrix."""
        return self._core.K

    @property
    def C(self):
        """The linear damping (the C given plus every linear damper), a scipy.sparse matrix."""
        return self._core.C

    @property
    def linear_product(self) -> str:
        """How K u + C v is taken every step: ``"band"`` (K and C complete bands of half-width <= 2),
        ``"rayleigh"`` (a lumped mass m and C = alpha m + beta K to round-off: K (u + beta v) + alpha m v,
        half the memory traffic), ``"shared"`` (C stored on K's pattern: the indices read once),
        ``"rows"`` (any pattern; K and C of fewer than 4096 stored entries together keep it, their
        sums in a fixed order) or ``"none"`` (no K and no C)."""
        return self._core.linear_product

    @property
    def linear_product_block(self) -> int:
        """3 or 2 where the ``"rayleigh"`` or ``"shared"`` product holds K (and C) by node blocks (nodes of
        that many consecutive DOFs whose blocks K stores nearly full: a 3-D solid mesh), 0 otherwise. The
        same values as by rows, with about half the loads per entry."""
        return self._core.linear_product_block

    def evaluate_force(self, u, v, t: float = 0.0) -> np.ndarray:
        """K u + C v + F(u, v, t): everything on the left of M a + ... = 0."""
        return self._core.force(_checks.vector("u", u, self.n), _checks.vector("v", v, self.n), _checks.real("t", t))

    def tangent_matrices(self, u, v, t: float = 0.0, *, sparse: bool = False):
        """(K_t, C_t): derivatives of K u + C v + F(u, v, t) with respect to u and v; dense arrays (models of
        up to 2000 DOFs), or scipy.sparse matrices with ``sparse=True`` (models of declared effects)."""
        args = (_checks.vector("u", u, self.n), _checks.vector("v", v, self.n), _checks.real("t", t))
        if sparse:
            return self._core.tangent_sparse(*args)
        if self.n > 2000:
            raise _checks.value_error("sparse", f"dense {self.n} x {self.n} tangents would take "
                                                f"{16e-6 * self.n ** 2:.0f} MB; use sparse=True")
        return self._core.tangent(*args)

    def linearized_frequencies(self, u=None) -> np.ndarray:
        """Circular frequencies [rad/s] of the undamped model linearised at u (default: zero), ascending."""
        from scipy import linalg

        u = np.zeros(self.n) if u is None else _checks.vector("u", u, self.n)
        if self.n > 2000:  # not tangent_matrices' own error: it names a sparse=True this method does not take
            raise _checks.value_error("model", f"linearized_frequencies gives every frequency, from dense matrices, "
                                               f"of models of up to 2000 DOFs (this one has {self.n}: "
                                               f"{8e-6 * self.n ** 2:.0f} MB a matrix); for the lowest k of a larger "
                                               "one: K, _ = model.tangent_matrices(u, v, sparse=True), then "
                                               "scipy.sparse.linalg.eigsh(K, k, M=model.mass_sparse, sigma=0)")
        K, _ = self.tangent_matrices(u, np.zeros(self.n), 0.0)
        w2 = linalg.eigh(0.5 * (K + K.T), self.mass_matrix, eigvals_only=True)
        return np.sqrt(np.clip(w2, 0.0, None))

    def static_equilibrium(self, t: float = 0.0, u_guess=None, *, rtol: float = 1e-12, max_iter: int = 200) -> np.ndarray:
        """Displacement where K u + F(u, 0, t) = 0 (the constant loads balanced), by the Newton component:
        converged when the residual is below rtol times the loads seen from the guess.

        Where the tangent stiffness is singular (a body held only by a contact
        that is not yet closed, a free-floating vehicle), the iteration matrix
        gets a mass-proportional term, like an implicit dynamic step, until the
        tangent is regular again. A body that nothing holds raises an
        ArgumentError naming ``initial``.
        """
        t = _checks.real("t", t)
        rtol = _checks.real("rtol", rtol, positive=True)
        max_iter = _checks.integer("max_iter", max_iter, minimum=1)
        u = np.zeros(self.n) if u_guess is None else _checks.vector("u_guess", u_guess, self.n)
        return self._core.static_equilibrium(t, u, rtol, max_iter)


class LawResponse:
    """A law driven along a path (``drive``): ``force``, ``slope_d`` (df/dd, the consistent tangent of
    a law with memory) and ``slope_v`` (df/dd') at each point, and ``state``, its internal variables
    after each point by name (empty for a law without memory)."""

    def __init__(self, force, slope_d, slope_v, state):
        self.force, self.slope_d, self.slope_v, self.state = force, slope_d, slope_v, state

    def __repr__(self) -> str:
        return f"LawResponse({len(self.force)} points; state: {', '.join(self.state) or 'none'})"


def drive(effect: dict, d, *, rate=None, t=None) -> LawResponse:
    """Drive one law along a path of deformations ``d`` (with rates ``rate`` and times ``t``, zero by
    default), each point a trial from the committed state and then a commit, as OpenSees'
    testUniaxialMaterial does: the law alone, without a model or a scheme. ``effect`` is an effect's
    dict without its measure, e.g. ``{"type": "bilinear", "k": 1e3, "fy": 10.0, "b": 0.05}``.
    """
    if not isinstance(effect, dict):
        raise _checks.type_error("effect", f"expected a dict such as {{'type': 'bilinear', 'k': 1e3, 'fy': 10}}, "
                                           f"got {type(effect).__name__}")
    d = np.ascontiguousarray(_checks.real_array("d", d), dtype=float).reshape(-1)
    n = d.size
    rate = np.zeros(n) if rate is None else _checks.vector("rate", rate, n)
    t = np.zeros(n) if t is None else _checks.vector("t", t, n)
    if "measure" in effect:
        raise _checks.value_error("effect.measure", "drive takes the law alone: d is its measure")
    model = Model([1.0], effects=[dict(effect, measure={0: 1.0})])
    f, kd, kv, state = _core.drive(model.effects[0], d.tolist(), np.asarray(rate).tolist(), np.asarray(t).tolist())
    return LawResponse(f, kd, kv, state)
