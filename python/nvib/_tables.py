"""Results as tables and files: ``Result.to_pandas()``, ``Result.to_xarray()``, ``Result.save(path)``
(.npz, .csv, .nc) and ``load_result(path)`` (.npz, .nc). pandas and xarray are optional extras."""

from __future__ import annotations

import importlib
import math
import os

import numpy as np

from . import _checks
from ._core import Failure, Result, Stats, Status
from ._io import effect_arrays, effect_columns, failure_fields, save_result
from ._model import rate_unit
from ._solve import ground_a

__all__ = ["load_result"]

_ENERGY = ("kinetic", "potential", "work_in", "dissipated", "hysteretic", "balance_error")
_COUNTERS = tuple(k for k in Stats().as_dict() if k.startswith("num_"))  # in the core's order


def _need(module: str, extra: str, what: str):
    try:
        return importlib.import_module(module)
    except ImportError:
        raise ImportError(f"{what} needs {module}, which is not installed: pip install \"nvib[{extra}]\"") from None


def _attrs(res) -> dict:
    """Scalars and strings describing the run (netCDF attributes take nothing else)."""
    out = {"scheme": repr(res.scheme), "dt": float(res.dt), "status": res.status.name,
           "num_steps_requested": int(res.num_steps_requested),
           "max_residual": float("nan") if res.max_residual is None else float(res.max_residual),
           "failure": "", "relative_to_ground": int(res.relative_to_ground), "warnings": "\n".join(res.warnings)}
    out.update(failure_fields(res.failure))
    for k, v in res.stats.as_dict().items():
        out[f"stats_{k}"] = v
    return out


def to_pandas(self):
    """A DataFrame indexed by time ``t``, columns ``u:<dof>``, ``v:<dof>``, ``a:<dof>`` (and
    ``energy:<term>`` and ``effect:<name>:<field>`` where recorded); ``attrs`` holds the scheme, dt,
    status, failure and counters."""
    pd = _need("pandas", "pandas", "Result.to_pandas()")
    cols = {}
    for q, arr in (("u", self.u), ("v", self.v), ("a", self.a)):
        for j, d in enumerate(self.dofs):
            cols[f"{q}:{d}"] = np.asarray(arr)[:, j]
    if self.energy is not None:
        for k, v in self.energy.as_dict().items():
            cols[f"energy:{k}"] = np.asarray(v)
    cols.update(effect_columns(self))
    df = pd.DataFrame(cols, index=pd.Index(np.asarray(self.t), name="t"))
    df.attrs.update(_attrs(self))
    df.attrs["units"] = {"t": "s", **{f"{q}:{d}": rate_unit(u, p) for q, p in (("u", 0), ("v", 1), ("a", 2))
                                      for d, u in zip(self.dofs, self.units)}}
    return df


def to_xarray(self):
    """A Dataset with u, v, a over (time, dof) (and ground_a, the ground's acceleration, under a ground
    motion; the energy terms over time), the run in ``attrs``."""
    xr = _need("xarray", "xarray", "Result.to_xarray()")
    data = {q: (("time", "dof"), np.asarray(getattr(self, q))) for q in ("u", "v", "a")}
    ground = ground_a(self)
    if ground is not None:  # what absolute_a adds to a
        data["ground_a"] = (("time", "dof"), ground)
    if self.energy is not None:
        for k, v in self.energy.as_dict().items():
            data[f"energy_{k}"] = (("time",), np.asarray(v))
    for key, arr in effect_arrays(self).items():  # by position; effects_names and the types as attributes
        if key.endswith(("_measure", "_rate", "_force", "_state")):
            data[key] = (("time", f"{key}_column"), arr)
    ds = xr.Dataset(data, coords={"time": np.asarray(self.t), "dof": [str(d) for d in self.dofs],
                                  "unit": ("dof", [str(u) for u in self.units])})
    ds["time"].attrs["units"] = "s"
    for q, p in (("u", 0), ("v", 1), ("a", 2)):  # per DOF in the unit coordinate; here the rate
        ds[q].attrs["units"] = rate_unit("unit", p)
    ds.attrs.update(_attrs(self))
    if "failure_residuals" in ds.attrs:  # netCDF takes an array; an empty one is left out
        residuals = np.asarray(ds.attrs.pop("failure_residuals"), float)
        if residuals.size:
            ds.attrs["failure_residuals"] = residuals
    for key, arr in effect_arrays(self).items():
        if not key.endswith(("_measure", "_rate", "_force", "_state")):
            ds.attrs[key] = "\n".join(np.atleast_1d(arr).astype(str).tolist())
    return ds


def save(self, path) -> None:
    """Write the result by the extension of ``path``: .npz (everything), .csv (the histories as columns, in
    shortest round-trip decimals) or .nc (netCDF, through xarray)."""
    path = os.fspath(path)
    if path.lower().endswith(".nc"):
        to_xarray(self).to_netcdf(path, engine=_netcdf_engine())
    else:
        save_result(path, self)


def _netcdf_engine() -> str:
    try:
        importlib.import_module("netCDF4")
        return "netcdf4"
    except ImportError:
        return "scipy"  # netCDF 3, from SciPy


def _rebuild(path, t, u, v, a, energy, dofs, attrs, units, effects=None, ground=None) -> Result:
    stats = Stats.__new__(Stats)
    stats.__setstate__(tuple(int(attrs.get(f"stats_{k}", 0)) for k in _COUNTERS) +
                       (float(attrs.get("stats_wall_time", 0.0)), str(attrs.get("stats_linear_solver", ""))))
    status = Status[str(attrs.get("status", "success"))]
    failure = Failure.__new__(Failure)
    failure.__setstate__((status, int(attrs.get("failure_step", 0)), float(attrs.get("failure_t", math.nan)),
                          int(attrs.get("failure_dof", -1)),
                          [float(x) for x in np.atleast_1d(np.asarray(attrs.get("failure_residuals", []), float))],
                          str(attrs.get("failure", ""))))
    res = Result.__new__(Result)
    m = len(dofs)
    res.__setstate__((np.asarray(t, float), np.asarray(u, float).reshape(-1, m), np.asarray(v, float).reshape(-1, m),
                      np.asarray(a, float).reshape(-1, m), energy, list(range(m)), stats, status, failure,
                      int(attrs.get("num_steps_requested", 0)), float(attrs.get("max_residual", math.nan)),
                      str(attrs.get("scheme", "")), float(attrs.get("dt", 0.0)), [str(d) for d in dofs], None,
                      effects or []))
    warnings = str(attrs.get("warnings", ""))
    res._extras = {"ground": None, "ground_a": None if ground is None else np.asarray(ground, float).reshape(-1, m),
                   "file": path, "relative_to_ground": bool(int(attrs.get("relative_to_ground", 0))),
                   "units": [str(u) for u in units] if units is not None else "m",
                   "warnings": warnings.split("\n") if warnings else []}
    return res


def _records(get, names) -> list:
    """The recorded effects (as the pickled Result holds them) from named arrays (effect_arrays)."""
    out = []
    for q, name in enumerate(names):
        measure = np.atleast_2d(np.asarray(get(f"effect{q}_measure"), float))
        count = measure.shape[1]
        state_names = [str(x) for x in np.atleast_1d(get(f"effect{q}_state_names")) if str(x)]
        out.append((str(name), str(get(f"effect{q}_type")), state_names, count, measure,
                    np.asarray(get(f"effect{q}_rate"), float).reshape(-1, count),
                    np.asarray(get(f"effect{q}_force"), float).reshape(-1, count),
                    np.asarray(get(f"effect{q}_state"), float).reshape(len(measure), -1) if state_names
                    else np.zeros((len(measure), 0))))
    return out


def load_result(path) -> Result:
    """A Result read back from .npz or .nc (as ``Result.save`` writes them). Its ``scheme`` is the scheme's
    repr; histories, DOF names, energy, status, failure (message, time, step, DOF, residuals) and counters are
    as saved, and so is the ground's acceleration ``absolute_a`` adds (a file written before it was saved has
    none: absolute_a then raises ArgumentError unless a is not relative to the ground)."""
    path = os.fspath(path)
    ext = os.path.splitext(path)[1].lower()
    if ext == ".npz":
        with np.load(path, allow_pickle=False) as z:
            keys = set(z.files)
            energy = (np.column_stack([z[f"energy_{k}"] if f"energy_{k}" in keys else np.zeros(len(z["t"]))
                                       for k in _ENERGY]) if "energy_kinetic" in keys else np.zeros((0, 0)))
            attrs = {k: z[k].item() for k in keys if z[k].ndim == 0}
            if "failure_residuals" in keys:
                attrs["failure_residuals"] = z["failure_residuals"]
            attrs.update({f"stats_{k}": z[k].item() for k in (*_COUNTERS, "wall_time", "linear_solver") if k in keys})
            names = list(z["effects_names"]) if "effects_names" in keys else []
            effects = _records(lambda k: z[k], names)
            return _rebuild(path, z["t"], z["u"], z["v"], z["a"], energy, list(z["dofs"]), attrs,
                            list(z["units"]) if "units" in keys else None, effects,
                            z["ground_a"] if "ground_a" in keys else None)
    if ext == ".nc":
        xr = _need("xarray", "xarray", "load_result() of a .nc file")
        with xr.open_dataset(path, engine=_netcdf_engine()) as ds:
            energy = (np.column_stack([ds[f"energy_{k}"].values if f"energy_{k}" in ds else np.zeros(ds.sizes["time"])
                                       for k in _ENERGY]) if "energy_kinetic" in ds else np.zeros((0, 0)))
            attrs = dict(ds.attrs)
            names = attrs["effects_names"].split("\n") if attrs.get("effects_names") else []

            def get(key):
                if key in ds:
                    return ds[key].values
                return np.array(attrs[key].split("\n") if key.endswith("_state_names") else attrs[key])

            effects = _records(get, names)
            return _rebuild(path, ds["time"].values, ds["u"].values, ds["v"].values, ds["a"].values, energy,
                            list(ds["dof"].values), attrs, list(ds["unit"].values) if "unit" in ds.coords else None,
                            effects, ds["ground_a"].values if "ground_a" in ds else None)
    raise _checks.value_error("path", f"expected a file ending in .npz or .nc, got {path!r}")


Result.to_pandas = to_pandas
Result.to_xarray = to_xarray
Result.save = save
