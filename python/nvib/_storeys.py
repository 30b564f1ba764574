"""Storeys of a building model: named effects whose measure is an interstorey drift, each with its height,
so that a drift in metres becomes a drift ratio (drift / height), the demand engineers compare with limits.

A scene declares them in its ``[storeys]`` table (effect name = height in metres); a model built in
Python passes ``storeys={"storey1": 3.5, ...}`` to the tools that need them."""

from __future__ import annotations

import math

import numpy as np

from . import _checks


def declared(model) -> dict | None:
    """The storeys a scene declared for ``model`` ({name: height}), or None."""
    scene = getattr(model, "scene", None)
    return scene.get("storeys") if isinstance(scene, dict) else None


def storey_heights(model, storeys=None, *, argument: str = "storeys") -> dict[str, float]:
    """{effect name: height [m]}: ``storeys`` when given, else the model's scene's ``[storeys]``. Each name must
    be a named effect of ``model`` that is not a load, each height finite and > 0; refused naming ``argument``."""
    if storeys is None:
        storeys = declared(model)
        if storeys is None:
            raise _checks.value_error(argument, "the model declares no storeys: give storeys={'storey1': 3.5, ...} "
                                                "(the effects whose measure is a storey drift, and their heights in m), "
                                                "or a [storeys] table in its scene")
    if not isinstance(storeys, dict) or not storeys:
        raise _checks.type_error(argument, f"expected a dict {{effect name: storey height [m]}}, got {storeys!r}")
    named = [e.name for e in model.effects or [] if e.name and not e.is_load]
    out = {}
    for name, h in storeys.items():
        if name not in named:
            raise _checks.value_error(f"{argument}[{name!r}]", f"no effect of that name with a measure (named: "
                                                               f"{', '.join(named) or 'none'})"
                                                               f"{_checks.suggestion(str(name), named)}")
        out[name] = _checks.real(f"{argument}[{name!r}]", h, positive=True)
    return out


def max_drift_ratio(peaks: dict, heights: dict) -> tuple[float, str]:
    """The largest peak drift ratio over the storeys and the storey it is in, from the peak |drift| of each
    named effect (``RunSummary.peak_measures``). NaN peaks give NaN."""
    best, where = -math.inf, ""
    for name, h in heights.items():
        r = float(np.max(peaks[name])) / h
        if not r <= best:  # NaN wins, so it is never hidden
            best, where = r, name
            if math.isnan(r):
                break
    return best, where


def drift_ratio_histories(model, result, heights: dict) -> dict[str, np.ndarray]:
    """{storey: drift ratio (drift / height, dimensionless) at each saved state} of a Result (the drift is the
    storey effect's measure, from the saved DOFs). Refused, naming ``result``, when the result did not save a
    DOF that a storey's drift needs."""
    effects = {e.name: e for e in model.effects or [] if e.name}
    column = {int(k): j for j, k in enumerate(result.dof_indices)}
    u = np.asarray(result.u)
    out = {}
    for name, h in heights.items():
        e = effects[name]
        missing = [model.dofs[int(i)] for i in e.index if int(i) not in column]
        if missing:
            raise _checks.value_error("result", f"the drift of {name!r} needs {missing[0]!r}, which this result did "
                                                "not save")
        out[name] = (u[:, [column[int(i)] for i in e.index]] @ np.asarray(e.coef, dtype=float)) / h
    return out


def peak_drift_ratios(model, result, heights: dict) -> dict[str, float]:
    """{storey: peak |drift ratio| over the saved states} of a Result, in the order of ``heights`` (storey 1 at
    the bottom): the drift ratio envelope. A history holding NaN gives NaN (never hidden); refused, naming
    ``result``, as ``drift_ratio_histories``."""
    out = {}
    for name, r in drift_ratio_histories(model, result, heights).items():
        r = np.abs(r)
        out[name] = float(np.max(r)) if r.size else math.nan
    return out
