"""Saving a Result: .npz (everything, compressed) or .csv (the histories as columns)."""

from __future__ import annotations

import os

import numpy as np

from . import _checks

FORMATS = (".npz", ".csv")


def save_result(path: str, result, extra: dict | None = None) -> None:
    """Writes ``result`` to ``path`` by its extension.

    .npz: t, u, v, a, dofs, status, scheme, dt, the stats counters, energy_* columns
    (if recorded), the failure message (if any) and the ``extra`` entries.
    .csv: a header ``t,u:<dof>,...,v:<dof>,...,a:<dof>,...[,energy:<term>,...]``
    and the values as the shortest decimals that read back exactly (0.3, not 0.29999999999999999)."""
    ext = os.path.splitext(str(path))[1].lower()
    if ext == ".npz":
        _write_npz(path, result, extra)
    elif ext == ".csv":
        _write_csv(path, result)
    else:
        raise _checks.value_error("path", f"expected a file ending in {' or '.join(FORMATS)}, got {path!r}")


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
    if result.failure is not None:
        data["failure"] = np.array(result.failure.message)
    data["units"] = np.array(result.units, dtype=str)
    data["relative_to_ground"] = np.array(int(result.relative_to_ground))
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
    table = np.hstack(cols) if len(result.t) else np.zeros((0, len(head)))
    with open(path, "w", encoding="utf-8", newline="") as fh:  # shortest decimals that read back exactly
        fh.write(",".join(head) + "\n")
        for row in table.tolist():
            fh.write(",".join(map(repr, row)) + "\n")
