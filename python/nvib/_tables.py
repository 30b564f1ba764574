"""Results as tables and files: ``Result.to_pandas()``, ``Result.to_xarray()``, ``Result.save(path)``
(.npz, .csv, .nc) and ``load_result(path)`` (.npz, .nc). pandas and xarray are optional extras."""

from __future__ import annotations

import importlib
import math
import os

import numpy as np

from . import _checks
from ._core import ArgumentError, Failure, Result, Stats, Status
from ._io import effect_arrays, effect_columns, failure_fields, write
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


def save(self, path, extra: dict | None = None) -> None:
    """Write the result by the extension of ``path``: .npz (everything, and the ``extra`` entries: a
    scene's name, the run's settings), .csv (the histories as columns, in shortest round-trip decimals) or
    .nc (netCDF, through xarray). The one way a result is written (the command line's --out too)."""
    path = os.fspath(path)
    if path.lower().endswith(".nc"):
        if extra:
            raise _checks.value_error("extra", "only an .npz file holds extra entries")
        to_xarray(self).to_netcdf(path, engine=_netcdf_engine())
    else:
        write(path, self, extra)


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
    n = len(t)
    res.__setstate__((np.asarray(t, float), np.asarray(u, float).reshape(n, m), np.asarray(v, float).reshape(n, m),
                      np.asarray(a, float).reshape(n, m), energy, list(range(m)), stats, status, failure,
                      int(attrs.get("num_steps_requested", 0)), float(attrs.get("max_residual", math.nan)),
                      str(attrs.get("scheme", "")), float(attrs.get("dt", 0.0)), [str(d) for d in dofs], None,
                      effects or []))
    warnings = str(attrs.get("warnings", ""))
    res._extras = {"ground": None, "ground_a": None if ground is None else np.asarray(ground, float).reshape(n, m),
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


_NEEDS = ("t", "u", "v", "a", "dofs")  # what a file must hold to be read as a result
_ZIP = (b"PK\x03\x04", b"PK\x05\x06")  # a .npz is a zip archive (the second: one with no members)
_NETCDF3 = (b"CDF\x01", b"CDF\x02", b"CDF\x05")  # classic, 64-bit offsets, 64-bit data
_HDF5 = b"\x89HDF\r\n\x1a\n"  # netCDF-4 files are HDF5 files


def _not_result(path: str, what: str) -> ArgumentError:
    """ArgumentError (a ValueError) naming the file and what is wrong with it; ``.argument`` is "path"."""
    return _checks.value_error("path", f"{path!r} {what}")


def _head(path: str) -> bytes:
    """The first bytes of the file, which say what kind it is; an empty file is refused here."""
    with open(path, "rb") as fh:
        head = fh.read(8)
    if not head:
        raise _not_result(path, "is empty (0 bytes), not a saved result")
    return head


_KINDS = (  # (first bytes, what the file is, the ending load_result would read it by)
    (_ZIP, "a zip archive", ".npz"),
    (_NETCDF3, "a netCDF-3 file", ".nc"),
    ((_HDF5,), "an HDF5 (netCDF-4) file", ".nc"),
    ((b"\x93NUMPY",), "a NumPy .npy array", None),
    ((b"\x80\x02", b"\x80\x03", b"\x80\x04", b"\x80\x05"), "a Python pickle, which nvib does not load", None),
)


def _wrong_kind(path: str, head: bytes, expected: str) -> ArgumentError:
    """The file's first bytes are not those of ``expected``: say what they are, if they say it."""
    for signatures, kind, ext in _KINDS:
        if head.startswith(signatures):
            if ext:  # perhaps a result, under the other name
                return _not_result(path, f"is not {expected} but {kind}: load_result reads a file by the ending of "
                                         f"its name, and one of this kind would end in {ext}")
            return _not_result(path, f"is not {expected} but {kind}: not a result nvib saved")
    text = all(32 <= b < 127 or b in b"\t\r\n" for b in head)
    return _not_result(path, f"is not {expected}{' but text' if text else ''}: not a result nvib saved")


def _is_hdf5(path: str) -> bool:
    """HDF5's signature at the start of the file or after a user block (512, 1024, 2048, ... bytes)."""
    with open(path, "rb") as fh:
        size = os.fstat(fh.fileno()).st_size
        offset = 0
        while offset + len(_HDF5) <= size:
            fh.seek(offset)
            if fh.read(len(_HDF5)) == _HDF5:
                return True
            offset = 512 if offset == 0 else 2 * offset
    return False


def _listing(names) -> str:
    names = sorted(str(k) for k in names)
    return ", ".join(names[:12]) + (f" and {len(names) - 12} more" if len(names) > 12 else "") if names else "nothing"


def _numbers(path: str, name: str, x, shape: tuple, expected: str) -> np.ndarray:
    """x as floats if it is a numeric array of the given shape (None: any length), else ArgumentError."""
    x = np.asarray(x)
    if (x.dtype.kind not in "iuf" or x.ndim != len(shape)
            or any(want is not None and got != want for got, want in zip(x.shape, shape))):
        raise _not_result(path, f"is not a result nvib saved: its {name} is an array of shape {x.shape} and dtype "
                                f"{x.dtype}, not {expected}")
    return x.astype(float)


def _from_fields(path: str, arrays: dict, attrs: dict, names: list, get) -> Result:
    """The Result a file's named arrays and scalars describe, checked to be what ``Result.save`` writes:
    ArgumentError naming the file and the field at fault otherwise. ``get(key)`` reads the recorded effects."""
    missing = [k for k in _NEEDS if k not in arrays]
    if missing:
        raise _not_result(path, f"is not a result nvib saved: it has no {', '.join(missing)} "
                                f"(it holds {_listing(arrays)})")
    t = _numbers(path, "t", arrays["t"], (None,), "the saved times (1-D numbers)")
    dofs = np.asarray(arrays["dofs"])
    if dofs.ndim != 1:
        raise _not_result(path, f"is not a result nvib saved: its dofs has shape {dofs.shape}, not a list of names")
    n, m = len(t), len(dofs)
    grid = f"{n} x {m} numbers (saved times x DOFs)"
    u, v, a = (_numbers(path, q, arrays[q], (n, m), grid) for q in ("u", "v", "a"))
    ground = (_numbers(path, "ground_a", arrays["ground_a"], (n, m), grid) if "ground_a" in arrays else None)
    terms = [_numbers(path, f"energy_{k}", arrays[f"energy_{k}"], (n,), f"{n} numbers (one per saved time)")
             if f"energy_{k}" in arrays else np.zeros(n) for k in _ENERGY]
    energy = np.column_stack(terms) if "energy_kinetic" in arrays else np.zeros((0, 0))
    if "failure_residuals" in arrays:
        attrs["failure_residuals"] = _numbers(path, "failure_residuals", np.atleast_1d(arrays["failure_residuals"]),
                                              (None,), "a list of numbers")
    status = str(attrs.get("status", "success"))
    if status not in Status.__members__:
        raise _not_result(path, f"is not a result nvib saved: its status {status!r} is none of "
                                f"{', '.join(Status.__members__)}")
    units = arrays.get("units")
    try:
        return _rebuild(path, t, u, v, a, energy, list(dofs), attrs, None if units is None else list(units),
                        _records(get, names), ground)
    except ArgumentError:
        raise
    except (KeyError, IndexError, TypeError, ValueError) as exc:  # the recorded effects, a scalar of the run
        raise _not_result(path, f"is not a result nvib saved, or a damaged one: {type(exc).__name__}: {exc}") from exc


def _load_npz(path: str) -> Result:
    head = _head(path)
    if not head.startswith(_ZIP):
        raise _wrong_kind(path, head, "a .npz archive (a zip file)")
    try:
        # the file opened here, not by np.load, which leaves it open when the archive is unreadable
        with open(path, "rb") as fh, np.load(fh, allow_pickle=False) as z:  # all read now: a damaged member fails here
            arrays = {}
            for k in z.files:
                try:
                    arrays[k] = np.asarray(z[k])
                except ValueError as exc:
                    if "allow_pickle" not in str(exc):
                        raise
                    raise _not_result(path, f"holds Python objects in {k}, which nvib never saves and does not "
                                            "read, so it is not a result nvib saved") from None
    except ArgumentError:
        raise
    except Exception as exc:  # a truncated or damaged archive: zipfile, zlib and NumPy each say it their way
        raise _not_result(path, "is damaged or truncated: its .npz archive cannot be read") from exc
    attrs = {k: x.item() for k, x in arrays.items() if x.ndim == 0}
    attrs.update({f"stats_{k}": attrs[k] for k in (*_COUNTERS, "wall_time", "linear_solver") if k in attrs})
    names = [str(x) for x in np.atleast_1d(arrays["effects_names"])] if "effects_names" in arrays else []
    return _from_fields(path, arrays, attrs, names, lambda k: arrays[k])


def _load_nc(path: str) -> Result:
    head = _head(path)
    hdf5 = _is_hdf5(path)
    if not (head.startswith(_NETCDF3) or hdf5):
        raise _wrong_kind(path, head, "a netCDF file")
    xr = _need("xarray", "xarray", "load_result() of a .nc file")
    engine = _netcdf_engine()
    if hdf5 and engine == "scipy":
        raise ImportError(f"load_result() of {path!r}, a netCDF-4 (HDF5) file, needs netCDF4, which is not "
                          "installed: pip install netCDF4")
    try:
        if engine == "scipy":  # from a file opened here: SciPy leaves its own open when the file is truncated
            with open(path, "rb") as fh, xr.open_dataset(fh, engine=engine) as ds:
                ds = ds.load()  # read it all now: a truncated file fails here
        else:
            with xr.open_dataset(path, engine=engine) as ds:
                ds = ds.load()
    except ImportError:
        raise
    except Exception as exc:  # the netCDF readers say it their way
        raise _not_result(path, f"cannot be read as netCDF: it is damaged or truncated, or holds what xarray "
                                f"cannot decode ({exc})") from exc
    arrays = {str(k): ds[k].values for k in ds.data_vars}
    for coord, key in (("time", "t"), ("dof", "dofs"), ("unit", "units")):
        if coord in ds.coords:
            arrays[key] = ds[coord].values
    missing = [k for k in ("u", "v", "a") if k not in ds.data_vars] + [k for k in ("time", "dof") if k not in ds.coords]
    if missing:
        raise _not_result(path, f"is not a result nvib saved: it has no {', '.join(missing)} (it holds "
                                f"{_listing([*ds.data_vars, *ds.coords])})")
    bad = [q for q in ("u", "v", "a", "ground_a") if q in ds.data_vars and ds[q].dims != ("time", "dof")]
    if bad:
        raise _not_result(path, f"is not a result nvib saved: its {bad[0]} is over {ds[bad[0]].dims}, not "
                                "(time, dof)")
    attrs = dict(ds.attrs)
    names = str(attrs["effects_names"]).split("\n") if attrs.get("effects_names") else []

    def get(key):
        if key in arrays:
            return arrays[key]
        return np.array(str(attrs[key]).split("\n") if key.endswith("_state_names") else attrs[key])

    return _from_fields(path, arrays, attrs, names, get)


def load_result(path) -> Result:
    """A Result read back from .npz or .nc (as ``Result.save`` writes them). Its ``scheme`` is the scheme's
    repr; histories, DOF names, energy, status, failure (message, time, step, DOF, residuals) and counters are
    as saved, and so is the ground's acceleration ``absolute_a`` adds (a file written before it was saved has
    none: absolute_a then raises ArgumentError unless a is not relative to the ground).

    A file that is not a result nvib saved (empty, truncated or damaged, of another kind, or holding other
    arrays) raises ArgumentError (a ValueError) naming the file and what is wrong; pickled objects are never
    loaded."""
    path = os.fspath(path)
    ext = os.path.splitext(path)[1].lower()
    if ext == ".npz":
        return _load_npz(path)
    if ext == ".nc":
        return _load_nc(path)
    raise _checks.value_error("path", f"expected a file ending in .npz or .nc, got {path!r}")

