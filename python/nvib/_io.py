"""Writing a Result (through ``Result.save``): .npz (everything, compressed) or .csv (the histories as columns)."""

from __future__ import annotations

import csv
import os

import numpy as np

from . import _checks
from ._solve import ground_a

FORMATS = (".npz", ".csv", ".nc")  # what Result.save writes (.nc through xarray, in _tables)


def write(path: str, result, extra: dict | None = None) -> None:
    """Writes ``result`` to ``path`` by its extension (``Result.save``, which also writes .nc).

    .npz: t, u, v, a, dofs, status, scheme, dt, the stats counters, energy_* columns
    (if recorded), ground_a (under a ground motion: the ground's acceleration at each saved DOF, what
    ``absolute_a`` adds to a), the recorded effects (``effect_arrays``), the failure (if any:
    ``failure_fields``) and the ``extra`` entries.
    .csv: a header ``t,u:<dof>,...,v:<dof>,...,a:<dof>,...[,energy:<term>,...][,effect:<name>:<field>,...]``
    and the values as the shortest decimals that read back exactly (0.3, not 0.29999999999999999); a name
    holding a comma, double quote or line break is quoted as RFC 4180 says (Python's csv module reads it)."""
    ext = os.path.splitext(str(path))[1].lower()
    if ext == ".npz":
        _write_npz(path, result, extra)
    elif ext == ".csv":
        _write_csv(path, result)
    else:
        endings = f"{', '.join(FORMATS[:-1])} or {FORMATS[-1]}"
        raise _checks.value_error("path", f"expected a file ending in {endings}, got {path!r}")


def failure_fields(failure) -> dict:
    """What a Failure holds beside its status (which the result's status repeats): failure (the message),
    failure_step, failure_t, failure_dof (-1 if none) and failure_residuals (Newton's, possibly none);
    nothing when the run did not fail."""
    if failure is None:
        return {}
    return {"failure": failure.message, "failure_step": int(failure.step), "failure_t": float(failure.t),
            "failure_dof": int(failure.dof), "failure_residuals": [float(x) for x in failure.residuals]}


def effect_columns(result):
    """(column name, 1-D array) for every recorded effect: measure, rate, force and internal variables,
    ``effect:<name>:<field>`` (``effect:<name>[k]:<field>`` for the k-th of several of one name)."""
    for name, rec in result.effects.items():
        fields = [("measure", rec.measure), ("rate", rec.rate), ("force", rec.force)] + list(rec.state.items())
        for field, values in fields:
            values = np.asarray(values)
            if rec.count == 1:
                yield f"effect:{name}:{field}", values
            else:
                for k in range(rec.count):
                    yield f"effect:{name}[{k}]:{field}", values[:, k]


def effect_arrays(result) -> dict:
    """The recorded effects as named arrays, by position: effects_names, effect<q>_type, _state_names,
    _measure, _rate, _force, _state (states x effects and internal variables; what load_result reads)."""
    out = {}
    names = list(result.effects)
    if names:
        out["effects_names"] = np.array(names, dtype=str)
    for q, name in enumerate(names):
        rec = result.effects[name]
        out[f"effect{q}_type"] = np.array(rec.type)
        out[f"effect{q}_state_names"] = np.array(rec.state_names, dtype=str)
        for field in ("measure", "rate", "force"):
            out[f"effect{q}_{field}"] = np.asarray(getattr(rec, field)).reshape(len(result.t), rec.count)
        w = len(rec.state_names)
        if w:  # (a law without memory has no internal variables to store)
            state = np.zeros((len(result.t), rec.count * w))
            for j, var in enumerate(rec.state_names):
                state[:, j::w] = np.asarray(rec.state[var]).reshape(len(result.t), rec.count)
            out[f"effect{q}_state"] = state
    return out


def _write_npz(path: str, result, extra: dict | None) -> None:
    data = {"t": result.t, "u": result.u, "v": result.v, "a": result.a, "dofs": np.array(result.dofs, dtype=str),
            "status": np.array(result.status.name), "scheme": np.array(repr(result.scheme)),
            "dt": np.array(result.dt), "num_steps_requested": np.array(result.num_steps_requested),
            "max_residual": np.array(np.nan if result.max_residual is None else result.max_residual)}
    for k, val in result.stats.as_dict().items():
        data[k] = np.array(val)
    if result.energy is not None:
        for k, val in result.energy.as_dict().items():
            data[f"energy_{k}"] = val
    data.update(effect_arrays(result))
    for k, val in failure_fields(result.failure).items():
        data[k] = np.array(val, dtype=float) if k == "failure_residuals" else np.array(val)
    data["units"] = np.array(result.units, dtype=str)
    data["relative_to_ground"] = np.array(int(result.relative_to_ground))
    ground = ground_a(result)
    if ground is not None:
        data["ground_a"] = ground
    if result.warnings:
        data["warnings"] = np.array("\n".join(result.warnings))
    for k, val in (extra or {}).items():
        data[k] = np.array(val)
    with open(path, "wb") as fh:
        np.savez_compressed(fh, **data)


def _write_csv(path: str, result) -> None:
    cols = [result.t[:, None], result.u, result.v, result.a]
    head = ["t"] + [f"{q}:{d}" for q in ("u", "v", "a") for d in result.dofs]
    if result.energy is not None:
        for k, val in result.energy.as_dict().items():
            cols.append(np.asarray(val)[:, None])
            head.append(f"energy:{k}")
    for name, val in effect_columns(result):
        cols.append(val[:, None])
        head.append(name)
    table = np.hstack(cols) if len(result.t) else np.zeros((0, len(head)))
    with open(path, "w", encoding="utf-8", newline="") as fh:  # shortest decimals that read back exactly
        out = csv.writer(fh, lineterminator="\n")  # a name with a comma, quote or line break is quoted (RFC 4180)
        # csv quotes a field holding the line terminator, "\n", but not a lone "\r", which readers take for a
        # line break too: a header with one is quoted throughout
        (csv.writer(fh, lineterminator="\n", quoting=csv.QUOTE_ALL) if any("\r" in h for h in head) else out
         ).writerow(head)
        out.writerows([repr(x) for x in row] for row in table.tolist())
