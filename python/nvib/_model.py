"""The Python Model: a mass plus either declared effects or a force callable."""

from __future__ import annotations

import numbers

import numpy as np

from . import _checks, _core

# Parameters of each built-in effect type: (required, optional-with-default).
EFFECT_PARAMETERS: dict[str, tuple[tuple[str, ...], dict[str, float]]] = {
    "spring": (("k",), {}),
    "damper": (("c",), {}),
    "hardening_spring": (("k0", "a"), {}),
    "cubic_spring": (("k3",), {}),
    "pendulum_gravity": (("m", "g", "l"), {}),
    "constant_force": (("value",), {}),
    "harmonic_force": (("amplitude", "omega"), {"phase": 0.0}),
}


def _effect_params(kind: str, p: dict) -> tuple[float, float, float]:
    if kind == "hardening_spring":
        return p["k0"], p["a"], 0.0
    if kind == "pendulum_gravity":
        return p["m"] * p["g"] * p["l"], 0.0, 0.0
    if kind == "harmonic_force":
        return p["amplitude"], p["omega"], p["phase"]
    (only,) = EFFECT_PARAMETERS[kind][0]
    return p[only], 0.0, 0.0


class Model:
    """M a + K u + C v + F(u, v, t) = 0 with F either declared effects or a callable.

    Parameters
    ----------
    mass : 1-D array (lumped/diagonal mass) or 2-D symmetric positive definite matrix.
    K, C : optional constant stiffness and damping matrices.
    force : optional callable ``force(u, v, t) -> array (n,)``: the nonlinear
        force on the left-hand side, loads included with a minus sign.
    tangent : optional callable ``tangent(u, v, t) -> (K_t, C_t)`` (C_t may be
        None); without it, central finite differences are used and counted in
        ``stats.num_fd_force_evals``.
    effects : optional list of built-in effects, each a dict such as
        ``{"type": "hardening_spring", "measure": {"x": 1.0}, "k0": 100, "a": 30}``;
        they are evaluated in C++ with no Python in the loop.
    dofs : optional DOF names (used by effect measures and by ``solve(dofs=...)``).
    u0, v0 : initial state (zeros by default).
    uses_velocity, uses_time : declare that ``force`` does not depend on v or t,
        so the schemes can skip what is not needed.
    """

    def __init__(self, mass, *, K=None, C=None, force=None, tangent=None, effects=None, dofs=None,
                 u0=None, v0=None, uses_velocity: bool = True, uses_time: bool = True):
        m = np.asarray(mass, dtype=float) if not isinstance(mass, numbers.Real) else np.asarray([mass], dtype=float)
        if m.ndim not in (1, 2):
            raise ValueError(f"mass: expected a 1-D array (diagonal) or a 2-D matrix, got {m.ndim} dimensions")
        n = m.shape[0]
        if n == 0:
            raise ValueError("mass: the model needs at least one degree of freedom")
        self.n = n
        if dofs is None:
            dofs = [f"u{i}" for i in range(n)]
        dofs = [str(d) for d in dofs]
        if len(dofs) != n:
            raise ValueError(f"dofs: expected {n} names, got {len(dofs)}")
        if len(set(dofs)) != n:
            raise ValueError("dofs: names must be unique")
        self.dofs = dofs
        Km = _checks.matrix("K", K, n) if K is not None else np.zeros((0, 0))
        Cm = _checks.matrix("C", C, n) if C is not None else np.zeros((0, 0))
        self.u0 = _checks.vector("u0", np.zeros(n) if u0 is None else u0, n)
        self.v0 = _checks.vector("v0", np.zeros(n) if v0 is None else v0, n)
        if force is not None and not callable(force):
            raise TypeError(f"force: expected a callable force(u, v, t), got {type(force).__name__}")
        if tangent is not None and not callable(tangent):
            raise TypeError(f"tangent: expected a callable tangent(u, v, t) -> (K, C), got {type(tangent).__name__}")
        if tangent is not None and force is None:
            raise ValueError("tangent: given without a force")
        if effects is not None and force is not None:
            raise ValueError("effects, force: give either built-in effects or a force callable, not both")
        self.force = force
        self.tangent = tangent
        self.effects = None
        if effects is not None:
            self.effects = [self._effect(i, e) for i, e in enumerate(effects)]
            self._core = _core.EffectModel(m, self.effects, Km, Cm)
        else:
            self._core = _core.CallableModel(m, Km, Cm, force, tangent, bool(uses_velocity), bool(uses_time))

    def _dof_index(self, where: str, key) -> int:
        if isinstance(key, numbers.Integral) and not isinstance(key, bool):
            if not 0 <= int(key) < self.n:
                raise ValueError(f"{where}: DOF index {key} is out of range for {self.n} degrees of freedom")
            return int(key)
        if key in self.dofs:
            return self.dofs.index(key)
        raise ValueError(f"{where}: unknown DOF {key!r} (known: {', '.join(self.dofs)})")

    def _effect(self, i: int, spec) -> "_core.Effect":
        where = f"effects[{i}]"
        if not isinstance(spec, dict):
            raise TypeError(f"{where}: expected a dict with 'type' and 'measure', got {type(spec).__name__}")
        kind = spec.get("type")
        if kind not in EFFECT_PARAMETERS:
            raise ValueError(f"{where}.type: unknown effect type {kind!r} (known: {', '.join(EFFECT_PARAMETERS)})")
        if "measure" not in spec:
            raise ValueError(f"{where}.measure: missing")
        measure = spec["measure"]
        if not isinstance(measure, dict) or not measure:
            raise ValueError(f"{where}.measure: expected a non-empty mapping DOF -> coefficient")
        index = [self._dof_index(f"{where}.measure", k) for k in measure]
        coef = [_checks.real(f"{where}.measure[{k!r}]", c) for k, c in measure.items()]
        required, optional = EFFECT_PARAMETERS[kind]
        for key in spec:
            if key not in ("type", "measure", "name") and key not in required and key not in optional:
                raise ValueError(f"{where}.{key}: unknown parameter for {kind} (expected {', '.join(required + tuple(optional))})")
        params = dict(optional)
        for key in required:
            if key not in spec:
                raise ValueError(f"{where}.{key}: missing parameter of {kind}")
        for key in list(required) + list(optional):
            if key in spec:
                params[key] = _checks.real(f"{where}.{key}", spec[key])
        return _core.Effect(kind, index, coef, *_effect_params(kind, params))

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
    def mass_matrix(self) -> np.ndarray:
        return self._core.mass_matrix

    def evaluate_force(self, u, v, t: float = 0.0) -> np.ndarray:
        """K u + C v + F(u, v, t): everything on the left of M a + ... = 0."""
        return self._core.force(_checks.vector("u", u, self.n), _checks.vector("v", v, self.n), float(t))

    def __repr__(self) -> str:
        kind = f"{len(self.effects)} effects" if self.effects is not None else ("force callable" if self.force else "linear")
        return f"Model(n={self.n}, {kind}, uses_velocity={self.uses_velocity}, uses_time={self.uses_time}, is_linear={self.is_linear})"
