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

# The line of an AT2 header that gives the number of samples and their step, in the forms PEER has used:
#   NGA-West2:   "NPTS=  5590, DT=   .0050 SEC,"    (any spacing, case and commas)
#   older PEER:  "NPTS=  4000, DT= .0100 SEC"  or  "4000  0.0100  NPTS, DT"
#   reversed:    "DT= .0100 SEC, NPTS= 4000"
_NUM = r"([-+]?(?:\d+\.?\d*|\.\d+)(?:[EeDd][-+]?\d+)?)"
_NPTS_DT = ((re.compile(r"NPTS\s*[=:]?\s*(\d+)\s*,?\s*(?:SEC\s*,?\s*)?DT\s*[=:]?\s*" + _NUM, re.IGNORECASE), 1, 2),
            (re.compile(r"^\s*(\d+)\s*,?\s+" + _NUM + r"\s*,?\s*NPTS\s*,?\s*DT", re.IGNORECASE), 1, 2),
            (re.compile(r"DT\s*[=:]?\s*" + _NUM + r"\s*(?:SEC)?\s*,?\s*NPTS\s*[=:]?\s*(\d+)", re.IGNORECASE), 2, 1))
_HEADER_LINES = 4  # an AT2 file's header: title, event, units, NPTS/DT
# Fixed-width Fortran columns (E15.7) may leave no blank between two values when one fills its field:
# "-0.1234567E-02-0.5678901E-03". A sign right after a digit or a point starts a new value.
_RUN_TOGETHER = re.compile(r"(?<=[0-9.])(?=[-+])")
_DATE = re.compile(r"\b\d{1,2}/\d{1,2}/\d{2,4}\b")
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
    # Line ends as files in the wild have them: LF, CR LF, CR alone (old Mac) and CR CR LF (a CR LF file
    # copied again through a text-mode transfer, as some PEER/OpenSees examples are): one line break each,
    # so the line numbers in errors are those an editor shows.
    text = raw.decode("utf-8", errors="replace")
    return text.replace("\r\r\n", "\n").replace("\r\n", "\n").replace("\r", "\n").split("\n")


def _fields(path: str, line: int, text: str) -> list[float]:
    """The numbers of one data line: separated by blanks or commas, or run together in fixed columns."""
    out = []
    for field in text.replace(",", " ").split():
        try:
            out.append(_number(path, line, field))
        except RecordError:
            parts = _RUN_TOGETHER.split(field)
            if len(parts) == 1:
                raise
            out.extend(_number(path, line, part) for part in parts)
    return out


def _header_metadata(line: str) -> dict:
    """Event, date, time, station and component from an AT2 file's second line, in PEER's two forms:
    "Northridge-01, 1/17/1994, Sylmar - Olive View Med FF, 360" (NGA-West2: event, date, station, component)
    and "NORTHRIDGE EQ 01/17/94, 1231, SYLMAR COUNTY HOSP PARKING LOT, 360" (older: event and date, time,
    station, component). What cannot be told apart is left empty; the whole line is kept as ``header``."""
    fields = [f.strip() for f in line.split(",")]
    fields = [f for f in fields if f]
    out = {"event": "", "date": "", "time": "", "station": "", "component": ""}
    if len(fields) < 2:
        out["event"] = fields[0] if fields else ""
        return out
    out["component"] = fields.pop()
    dated = next((k for k, f in enumerate(fields) if _DATE.fullmatch(f)), None)
    if dated is not None:  # NGA-West2: the event's name (which may hold a comma: "Kobe, Japan") before the date
        out["event"], out["date"] = ", ".join(fields[:dated]), fields[dated]
        fields = fields[dated + 1:]
    else:
        first = fields.pop(0)
        m = _DATE.search(first)
        if m:  # the older form: the date ends the event's name
            out["event"], out["date"] = first[:m.start()].strip(" ,"), m.group(0)
        else:
            out["event"] = first
    if fields and re.fullmatch(r"\d{3,4}", fields[0]) and len(fields) > 1:  # hhmm of the older form
        out["time"] = fields.pop(0)
    out["station"] = ", ".join(fields)
    return out


def _too_large(size: int) -> str:
    return (f"{size / 2**20:.1f} MB, more than the {MAX_RECORD_BYTES // 2**20} MB a record file may have "
            "(some 4 million samples; a longer record can be given as an array: GroundMotion.from_array)")


_META = ("event", "date", "station", "component", "rsn")  # what a record keeps of its file's header


def _units_after(units: str, factor: float) -> str:
    """The unit of a record's values after multiplying them by ``factor``: the same at any scale (an
    intensity level), except the one conversion a factor can mean, g times STANDARD_GRAVITY (m/s^2) and back."""
    if units == "g" and factor == STANDARD_GRAVITY:
        return "m/s^2"
    if units == "m/s^2" and factor == 1.0 / STANDARD_GRAVITY:
        return "g"
    return units


class GroundMotion:
    """A ground acceleration record a(t): ``t``, ``a`` (arrays), ``dt`` (None if the samples are not
    evenly spaced), ``pga`` (max |a|), ``duration`` (last time - first time), ``name`` and ``units``
    (what the values are in, as far as known: "g" for an AT2 file, "m/s^2" once multiplied by
    STANDARD_GRAVITY; "" when not known). From an AT2 header it keeps ``event``, ``date``, ``station``,
    ``component`` and ``rsn`` (PEER's record sequence number, from a file named RSN<n>_...; None if
    not known); ``label`` joins them for titles and legends.

    Build one with ``GroundMotion.from_at2(path)``, ``.from_file(path, dt=, scale=)`` or
    ``.from_array(a, dt)``; ``scaled(f)`` multiplies it, ``scaled_to_sa(T, value)`` scales it to a
    pseudo-spectral acceleration at one period. Give it as the ``signal`` of a
    ``ground_acceleration`` effect; in a scene, ``signal = { kind = "record", file = "x.AT2",
    scale = 9.80665 }`` with the path relative to the scene file."""

    def __init__(self, t, a, *, name: str = "", units: str = "", event: str = "", date: str = "", station: str = "",
                 component: str = "", rsn: int | None = None):
        t, a = _checks.samples("t", "a", t, a, nonfinite="a")
        self.t = np.ascontiguousarray(t, dtype=float)
        self.a = np.ascontiguousarray(a, dtype=float)
        self.name = str(name)
        self.units = str(units)
        self.event, self.date, self.station, self.component = str(event), str(date), str(station), str(component)
        self.rsn = None if rsn is None else _checks.integer("rsn", rsn, minimum=0)

    def _meta(self) -> dict:
        return {k: getattr(self, k, "" if k != "rsn" else None) for k in _META}

    @property
    def label(self) -> str:
        """"RSN953, Northridge-01, Beverly Hills - 14145 Mulhol, 009": what the header said of the record
        (its name when the header said nothing)."""
        meta = self._meta()
        parts = ([f"RSN{meta['rsn']}"] if meta["rsn"] is not None else []) + [
            meta[k] for k in ("event", "station", "component") if meta[k]]
        return ", ".join(parts) if len(parts) > (meta["rsn"] is not None) else self.name

    # ---- construction
    @classmethod
    def from_array(cls, a, dt, *, scale: float = 1.0, t0: float = 0.0, name: str = "", units: str = "") -> GroundMotion:
        """Samples a[k] at t0 + k dt, times ``scale``; ``units``: what the samples are in (before the scale)."""
        dt = _checks.real("dt", dt, positive=True)
        scale = _checks.real("scale", scale)
        t0 = _checks.real("t0", t0)
        a = _checks.real_array("a", a)
        if a.ndim != 1:
            raise _checks.value_error("a", f"expected a 1-D array of samples, got shape {a.shape}")
        return cls(t0 + dt * np.arange(a.size), a * scale, name=name, units=_units_after(str(units), scale))

    @classmethod
    def from_at2(cls, path, *, scale: float = 1.0, name: str | None = None) -> GroundMotion:
        """A PEER ``.AT2`` file: a header of four lines (title; event, date, station, component; units;
        NPTS and DT, as ``NPTS=  4000, DT= .0100 SEC`` or ``4000 .0100 NPTS, DT``), then NPTS values in g,
        any number a line (blank-separated, or run together in fixed Fortran columns; exponents E or D).
        Any line ends (LF, CR LF, CR, CR CR LF). The values stay in g at any ``scale`` except
        STANDARD_GRAVITY, which turns them into m/s^2."""
        path = os.fspath(path)
        scale = _checks.real("scale", scale)
        lines = _read_lines(path)
        header = None
        for k, line in enumerate(lines[:_HEADER_LINES]):
            for rx, i_npts, i_dt in _NPTS_DT:
                m = rx.search(line)
                if m:
                    header = (k + 1, m.group(i_npts), m.group(i_dt))
                    break
            if header:
                break
        if header is None:
            raise RecordError(path, min(len(lines), _HEADER_LINES) or None,
                              "no NPTS and DT in the header (expected a line such as 'NPTS=  4000, DT= .0100 SEC' "
                              "or '4000  .0100  NPTS, DT' within the first four lines)")
        hline, npts_text, dt_text = header
        npts = int(npts_text)
        dt = _number(path, hline, dt_text)
        if npts < 2:
            raise RecordError(path, hline, f"NPTS = {npts}: a record needs at least two samples")
        if not dt > 0:
            raise RecordError(path, hline, f"DT = {dt_text} must be > 0")
        values, last = [], hline
        for k in range(hline, len(lines)):  # the samples start on the line after NPTS and DT
            found = _fields(path, k + 1, lines[k])
            if found:
                values.extend(found)
                last = k + 1
        if len(values) != npts:
            where = f"lines {hline + 1} to {last}" if last > hline else "none after it"
            raise RecordError(path, hline, f"the header says NPTS = {npts}, but {len(values)} values follow it "
                                           f"({where})")
        units = "g" if any("UNITS OF G" in ln.upper() for ln in lines[:hline]) else ""
        meta = _header_metadata(lines[1]) if hline > 2 else {}
        meta.pop("time", None)
        rsn = re.match(r"RSN(\d+)_", os.path.basename(path), re.IGNORECASE)
        gm = cls.from_array(np.array(values), dt, scale=scale, units=units,
                            name=name if name is not None else os.path.basename(path))
        for k, v in meta.items():
            setattr(gm, k, v)
        gm.rsn = int(rsn.group(1)) if rsn else None
        return gm

    @classmethod
    def from_file(cls, path, *, dt: float | None = None, scale: float = 1.0, name: str | None = None,
                  units: str = "") -> GroundMotion:
        """A plain text file: one column of samples (``dt`` required) or two columns (t, a) (``dt``
        not given), its values in ``units`` ("g", "m/s^2"; "" when not known). Blank lines and lines
        starting with ``#`` are skipped; a ``.AT2`` file is read by ``from_at2`` (its values are in g)."""
        path = os.fspath(path)
        units = str(units)
        if path.upper().endswith(".AT2"):
            if dt is not None:
                raise _checks.value_error("dt", "an AT2 file gives its own DT; do not pass dt")
            if units not in ("", "g"):
                raise _checks.value_error("units", f"an AT2 file is in g, got units={units!r}")
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
            return cls.from_array(data[:, 0], dt, scale=scale, name=label, units=units)
        if dt is not None:
            raise _checks.value_error("dt", f"{path} has two columns (t, a): its times are given, do not pass dt")
        bad = np.flatnonzero(np.diff(data[:, 0]) <= 0)
        if bad.size:
            raise RecordError(path, None, f"times must increase strictly (sample {bad[0] + 2}: "
                                          f"t = {float(data[bad[0] + 1, 0])!r} after {float(data[bad[0], 0])!r})")
        return cls(data[:, 0], data[:, 1] * scale, name=label, units=_units_after(units, scale))

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
        """The same record with every value times ``factor``: an intensity level keeps the unit (a record
        in g stays in g), STANDARD_GRAVITY turns g into m/s^2 (and its inverse m/s^2 into g)."""
        factor = _checks.real("factor", factor)
        return GroundMotion(self.t, self.a * factor, name=self.name, units=_units_after(self.units, factor),
                            **self._meta())

    def psa(self, periods, damping: float = 0.05):
        """The exact pseudo-spectral acceleration w^2 Sd at ``periods`` [s] (an array like them), in the
        record's units, with the free vibration after the record (nvib._core.elastic_spectrum)."""
        periods = _checks.real_array("periods", periods)  # their values and damping's: the kernel's checks
        out = self.exact_response(np.atleast_1d(periods).ravel(), _checks.number("damping", damping))
        return np.asarray(out["PSa"], dtype=float).reshape(periods.shape)

    def exact_response(self, periods, damping) -> dict:
        """The kernel's exact elastic spectrum of this record (a dict of Sd, Sv, PSv, PSa, Sa, ...: see
        nvib._core.elastic_spectrum) at ``periods`` for one damping ratio or several; the evenly sampled
        form when the samples are evenly spaced."""
        from . import _core

        if self.dt is not None:
            return _core.elastic_spectrum(self.a, self.dt, periods, damping, t0=float(self.t[0]))
        return _core.elastic_spectrum_at(self.t, self.a, periods, damping)

    def scaled_to_sa(self, period: float, value: float, damping: float = 0.05) -> tuple[GroundMotion, float]:
        """(the record scaled so that its pseudo-spectral acceleration at ``period`` [s] is ``value`` (in
        the record's units: g for a record in g), the factor): the usual scaling of a record to a target
        Sa(T1). Refused, naming ``period``, when the record gives no response at that period."""
        period = _checks.real("period", period, positive=True)
        value = _checks.real("value", value)
        if value < 0:
            raise _checks.value_error("value", f"a spectral acceleration is >= 0, got {value:g}")
        before = float(self.psa([period], damping)[0])
        if not before > 0:
            raise _checks.value_error("period", f"the record's PSa at T = {period:g} s is {before:g}: no factor "
                                                "scales it to a given value")
        factor = value / before
        return self.scaled(factor), factor

    def __call__(self, t):
        """a(t): linear between samples, 0 outside the record (as the solver sees it)."""
        return np.interp(t, self.t, self.a, left=0.0, right=0.0)

    def signal(self) -> dict:
        """The record as a table signal of the effects."""
        return {"kind": "table", "t": self.t.tolist(), "values": self.a.tolist()}

    def __eq__(self, other) -> bool:
        return (isinstance(other, GroundMotion) and np.array_equal(self.t, other.t) and np.array_equal(self.a, other.a)
                and self.name == other.name and self.units == other.units and self._meta() == other._meta())

    __hash__ = None

    def __repr__(self) -> str:
        dt = self.dt
        step = f"dt={dt:g} s" if dt is not None else "uneven steps"
        units = f" {self.units}" if self.units else ""
        name = f"{self.name!r}, " if self.name else ""
        if self.label != self.name:
            name += f"{self.label!r}, "
        return f"GroundMotion({name}{len(self)} samples, {step}, duration={self.duration:g} s, pga={self.pga:.4g}{units})"
