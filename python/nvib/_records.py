"""Ground-motion records: PEER NGA ``.AT2`` files, one-column files with a given dt, two-column
(t, a) files and arrays. A record acts as a signal of the effects (``ground_acceleration``): linear
between samples, zero before its first and after its last sample, so a run may go on past it (free
vibration). nvib is unit-agnostic: a record keeps the values of its file (an AT2 file's are in g)
times ``scale`` (``scale=9.80665`` turns g into m/s²)."""

from __future__ import annotations

import math
import os
import re

import numpy as np

from . import _checks

__all__ = ["GroundMotion", "RecordError", "STANDARD_GRAVITY"]

STANDARD_GRAVITY = 9.80665  # [m/s^2]: scale = STANDARD_GRAVITY turns an AT2 file's g into m/s^2

_NPTS_DT = (re.compile(r"NPTS\s*=\s*(\d+)\s*,?\s*DT\s*=\s*([-+0-9.EeDd]+)", re.IGNORECASE),  # NGA-West2
            re.compile(r"^\s*(\d+)\s+([-+0-9.EeDd]+)\s+NPTS\s*,\s*DT", re.IGNORECASE))      # older NGA
_HEADER_LINES = 4  # an AT2 file's header: title, event, units, NPTS/DT
MAX_RECORD_BYTES = 64 * 2**20  # a record file larger than this is refused before it is read


class RecordError(ValueError):
    """A record file that cannot be read: ``path`` and ``line`` (1-based; None for the whole file) say where."""

    def __init__(self, path: str, line: int | None, message: str):
        super().__init__(f"{path}{f', line {line}' if line else ''}: {message}")
        self.path = path
        self.line = line
        self.reason = message

    def __reduce__(self):
        return (RecordError, (self.path, self.line, self.reason))


def _number(path: str, line: int, text: str) -> float:
    try:
        x = float(text.replace("D", "E").replace("d", "e"))  # Fortran's double exponent
    except ValueError:
        raise RecordError(path, line, f"{text!r} is not a number") from None
    if not math.isfinite(x):
        raise RecordError(path, line, f"{text!r} is not finite")
    return x


def _read_lines(path: str) -> list[str]:
    """The lines of a record file. What cannot be read (a folder, a loop of symbolic links, a device such
    as /dev/zero, a file over MAX_RECORD_BYTES) is a RecordError naming the file, refused before reading."""
    path = os.fspath(path)
    problem = _checks.input_file_problem(path, "record file", streams=True)
    if problem:
        raise RecordError(path, None, problem)
    try:
        with open(path, "rb") as fh:
            size = os.fstat(fh.fileno()).st_size
            if size > MAX_RECORD_BYTES:
                raise RecordError(path, None, _too_large(size))
            raw = fh.read(MAX_RECORD_BYTES + 1)  # a pipe has no size to check beforehand
    except OSError as exc:  # no permission to read it
        raise RecordError(path, None, f"cannot be read: {exc.strerror or exc}") from None
    if len(raw) > MAX_RECORD_BYTES:
        raise RecordError(path, None, _too_large(len(raw)))
    return raw.decode("utf-8", errors="replace").splitlines()


def _too_large(size: int) -> str:
    return (f"{size / 2**20:.1f} MB, more than the {MAX_RECORD_BYTES // 2**20} MB a record file may have "
            "(some 4 million samples; a longer record can be given as an array: GroundMotion.from_array)")


class GroundMotion:
    """A ground acceleration record a(t): ``t``, ``a`` (arrays), ``dt`` (None if the samples are not
    evenly spaced), ``pga`` (max |a|), ``duration`` (last time - first time), ``name`` and ``units``
    (what the values are in, as far as known: "g" for an unscaled AT2 file).

    Build one with ``GroundMotion.from_at2(path)``, ``.from_file(path, dt=, scale=)`` or
    ``.from_array(a, dt)``; ``scaled(f)`` multiplies it. Give it as the ``signal`` of a
    ``ground_acceleration`` effect; in a scene, ``signal = { kind = "record", file = "x.AT2",
    scale = 9.80665 }`` with the path relative to the scene file."""

    def __init__(self, t, a, *, name: str = "", units: str = ""):
        t, a = _checks.samples("t", "a", t, a, nonfinite="a")
        self.t = np.ascontiguousarray(t, dtype=float)
        self.a = np.ascontiguousarray(a, dtype=float)
        self.name = str(name)
        self.units = str(units)

    # ---- construction
    @classmethod
    def from_array(cls, a, dt, *, scale: float = 1.0, t0: float = 0.0, name: str = "", units: str = "") -> GroundMotion:
        """Samples a[k] at t0 + k dt, times ``scale``."""
        dt = _checks.real("dt", dt, positive=True)
        scale = _checks.real("scale", scale)
        t0 = _checks.real("t0", t0)
        a = _checks.real_array("a", a)
        if a.ndim != 1:
            raise _checks.value_error("a", f"expected a 1-D array of samples, got shape {a.shape}")
        return cls(t0 + dt * np.arange(a.size), a * scale, name=name, units=units)

    @classmethod
    def from_at2(cls, path, *, scale: float = 1.0, name: str | None = None) -> GroundMotion:
        """A PEER NGA ``.AT2`` file: four header lines (the fourth giving NPTS and DT, as ``NPTS=
        4000, DT= .0100 SEC`` or ``4000 .0100 NPTS, DT``), then NPTS values in g, any number a line."""
        path = os.fspath(path)
        scale = _checks.real("scale", scale)
        lines = _read_lines(path)
        header = None
        for k, line in enumerate(lines[:_HEADER_LINES]):
            for rx in _NPTS_DT:
                m = rx.search(line)
                if m:
                    header = (k + 1, m)
                    break
            if header:
                break
        if header is None:
            raise RecordError(path, min(len(lines), _HEADER_LINES) or None,
                              "no NPTS and DT in the header (expected a line such as 'NPTS=  4000, DT= .0100 SEC' "
                              "within the first four lines)")
        hline, m = header
        npts = int(m.group(1))
        dt = _number(path, hline, m.group(2))
        if npts < 2:
            raise RecordError(path, hline, f"NPTS = {npts}: a record needs at least two samples")
        if not dt > 0:
            raise RecordError(path, hline, f"DT = {m.group(2)} must be > 0")
        values = []
        for k in range(hline, len(lines)):
            for field in lines[k].replace(",", " ").split():
                values.append(_number(path, k + 1, field))
        if len(values) != npts:
            raise RecordError(path, hline, f"NPTS = {npts}, but {len(values)} values follow the header "
                                           f"(lines {hline + 1} to {len(lines)})")
        units = "g" if any("UNITS OF G" in ln.upper() for ln in lines[:hline]) else ""
        if scale != 1.0:
            units = ""  # scaled: the caller knows what the values are in now
        return cls.from_array(np.array(values), dt, scale=scale,
                              name=name if name is not None else os.path.basename(path), units=units)

    @classmethod
    def from_file(cls, path, *, dt: float | None = None, scale: float = 1.0, name: str | None = None) -> GroundMotion:
        """A plain text file: one column of samples (``dt`` required) or two columns (t, a) (``dt``
        not given). Blank lines and lines starting with ``#`` are skipped; a ``.AT2`` file is read by
        ``from_at2``."""
        path = os.fspath(path)
        if path.upper().endswith(".AT2"):
            if dt is not None:
                raise _checks.value_error("dt", "an AT2 file gives its own DT; do not pass dt")
            return cls.from_at2(path, scale=scale, name=name)
        scale = _checks.real("scale", scale)
        rows, first = [], None
        for k, line in enumerate(_read_lines(path)):
            text = line.strip()
            if not text or text.startswith("#"):
                continue
            fields = text.replace(",", " ").split()
            if first is None:
                first = (k + 1, len(fields))
                if len(fields) not in (1, 2):
                    raise RecordError(path, k + 1, f"expected one column (a) or two (t, a), got {len(fields)}")
            elif len(fields) != first[1]:
                raise RecordError(path, k + 1, f"expected {first[1]} column{'s' if first[1] > 1 else ''} "
                                               f"as on line {first[0]}, got {len(fields)}")
            rows.append([_number(path, k + 1, f) for f in fields])
        if first is None or len(rows) < 2:
            raise RecordError(path, None, "fewer than two samples")
        data = np.array(rows)
        label = name if name is not None else os.path.basename(path)
        if first[1] == 1:
            if dt is None:
                raise _checks.value_error("dt", f"{path} has one column of samples: give their time step dt")
            return cls.from_array(data[:, 0], dt, scale=scale, name=label)
        if dt is not None:
            raise _checks.value_error("dt", f"{path} has two columns (t, a): its times are given, do not pass dt")
        bad = np.flatnonzero(np.diff(data[:, 0]) <= 0)
        if bad.size:
            raise RecordError(path, None, f"times must increase strictly (sample {bad[0] + 2}: "
                                          f"t = {float(data[bad[0] + 1, 0])!r} after {float(data[bad[0], 0])!r})")
        return cls(data[:, 0], data[:, 1] * scale, name=label)

    @classmethod
    def from_spec(cls, where: str, spec: dict, *, base_dir: str | None = None) -> GroundMotion:
        """A scene's ``{kind = "record", file = ..., scale = 1, dt = ...}``: ``file`` relative to base_dir. Any
        other key is refused naming it (a misspelt ``scale`` would leave the record unscaled)."""
        _checks.unknown_keys(where, spec, ("kind", "file", "scale", "dt"), "a record signal")
        file = spec.get("file")
        if not isinstance(file, str) or not file:
            raise _checks.value_error(f"{where}.file", "expected the path of a record file")
        path = file if os.path.isabs(file) or base_dir is None else os.path.join(base_dir, file)
        scale = _checks.real(f"{where}.scale", spec.get("scale", 1.0))
        dt = spec.get("dt")
        if dt is not None:
            dt = _checks.real(f"{where}.dt", dt, positive=True)
        return cls.from_file(path, dt=dt, scale=scale)

    # ---- properties
    @property
    def dt(self) -> float | None:
        """The sampling step, or None when the samples are not evenly spaced (to 1e-9 relative)."""
        d = np.diff(self.t)
        return float(d[0]) if np.all(np.abs(d - d[0]) <= 1e-9 * d[0]) else None

    @property
    def pga(self) -> float:
        """Peak ground acceleration max |a| (in the record's units)."""
        return float(np.max(np.abs(self.a)))

    @property
    def duration(self) -> float:
        return float(self.t[-1] - self.t[0])

    def __len__(self) -> int:
        return self.t.size

    def scaled(self, factor: float) -> GroundMotion:
        """The same record with every value times ``factor`` (an intensity level, or g to m/s²)."""
        factor = _checks.real("factor", factor)
        return GroundMotion(self.t, self.a * factor, name=self.name, units="" if factor != 1.0 else self.units)

    def __call__(self, t):
        """a(t): linear between samples, 0 outside the record (as the solver sees it)."""
        return np.interp(t, self.t, self.a, left=0.0, right=0.0)

    def signal(self) -> dict:
        """The record as a table signal of the effects."""
        return {"kind": "table", "t": self.t.tolist(), "values": self.a.tolist()}

    def __eq__(self, other) -> bool:
        return (isinstance(other, GroundMotion) and np.array_equal(self.t, other.t) and np.array_equal(self.a, other.a)
                and self.name == other.name and self.units == other.units)

    __hash__ = None

    def __repr__(self) -> str:
        dt = self.dt
        step = f"dt={dt:g} s" if dt is not None else "uneven steps"
        units = f" {self.units}" if self.units else ""
        name = f"{self.name!r}, " if self.name else ""
        return f"GroundMotion({name}{len(self)} samples, {step}, duration={self.duration:g} s, pga={self.pga:.4g}{units})"
