"""Response spectra of a ground-motion record.

For each period T the SDOF u'' + 2 zeta w u' + w^2 u = -a_g(t) (w = 2 pi / T, unit mass; or with a
declared nonlinear law in place of the linear spring): Sd = max |u|, Sv = max |u'|, pseudo-Sv = w Sd,
pseudo-Sa = w^2 Sd, and the absolute Sa = max |u'' + a_g|.

The elastic spectrum is exact: the closed-form response to the record, which is linear between its
samples (Nigam & Jennings 1969; Chopra, Dynamics of Structures, section 5.2), for every period at once
in C++ (nvib._core.elastic_spectrum), each interval's peak located between its samples, and the free
vibration after the record followed until its peak can no longer grow.

With a scheme, or a nonlinear law in place of the spring, each period's SDOF is integrated through
``solve_many``, the step following from the period and the requested accuracy; the scheme's elastic
spectrum is checked against the exact peaks (Sd and Sa, between samples), an inelastic one against the
same run at half the step, and the periods that miss the accuracy are run again at half the step, so
the spectrum reports the accuracy it reached and what it cost.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from .. import _checks, _core
from .._batch import RunError, solve_many
from .._errors import NvibError, error_for
from .._model import Model
from .._records import STANDARD_GRAVITY, GroundMotion

__all__ = ["Spectrum", "spectrum", "exact_sdof_peaks", "rotd_spectrum"]

# below this the round-off of the steps is as large as the error asked for (measured: 1e-9 itself is met at
# T = 0.1 and 1 s of a 4 s record, missed at 3 s, 3.7e-6 after four halvings; the error reached is reported)
MIN_ACCURACY = 1e-9
CHUNK = 32  # histories made at a time by one solve_many call
_WORK_ARRAYS = 16  # arrays of one double per saved state besides the histories: the exact check, absolute_a


@dataclasses.dataclass
class Spectrum:
    """Spectral values per period: ``periods`` [s], ``damping``, ``Sd`` (peak relative displacement),
    ``Sv`` (peak relative velocity), ``PSv`` = w Sd, ``PSa`` = w^2 Sd and ``Sa`` (peak absolute
    acceleration). ``units``: the record's ("g", "m/s^2" or "" when not known): PSa and Sa are in it,
    Sd in it times s^2 (m for m/s^2), Sv and PSv in it times s; ``in_units("g")`` converts.

    ``check`` says how they were obtained and what ``error`` means:
    - "exact": the closed-form response to the record, linear between its samples (Nigam & Jennings
      1969), each peak located between samples and the free vibration after the record followed until
      its peak can no longer grow; exact to round-off (about 1e-12 relative, measured against the same
      record interpolated to 1/64 of its step), so ``error`` is None and ``dt`` the record's step;
    - "exact check": runs of ``scheme``; ``error`` is the larger of the relative errors of Sd and Sa
      against the exact peaks of the same span (between samples too), ``dt`` each period's step;
    - "half step": runs of a nonlinear ``law``; ``error`` is the relative change of Sd when the step is
      halved.
    ``estimate`` (runs only; None when exact): each period's run's estimate of its own error
    (``Result.error_estimate``, relative to the peak of u), NaN where the scheme makes none. It estimates
    the error of the whole history, phase included, which bounds the error of its peak: measured 1.4 to 350
    times ``error`` on a 4-s record at accuracy 1e-3 and 1e-4 (Newmark, central difference).
    With several damping ratios the spectral values are arrays (dampings x periods)."""

    periods: np.ndarray
    damping: float | np.ndarray
    Sd: np.ndarray
    PSv: np.ndarray
    PSa: np.ndarray
    Sa: np.ndarray
    dt: np.ndarray
    error: np.ndarray | None
    wall_time: float
    check: str
    record: str = ""
    scheme: str = ""
    Sv: np.ndarray | None = None
    units: str = ""
    estimate: np.ndarray | None = None

    def by_damping(self) -> list:
        """One Spectrum per damping ratio (a spectrum of several damping ratios split into its rows)."""
        if np.ndim(self.damping) == 0:
            return [self]
        rows = []
        for k, z in enumerate(np.asarray(self.damping)):
            pick = {f: getattr(self, f)[k] for f in ("Sd", "PSv", "PSa", "Sa", "dt")}
            rows.append(dataclasses.replace(self, damping=float(z), **pick,
                                            error=None if self.error is None else self.error[k],
                                            Sv=None if self.Sv is None else self.Sv[k],
                                            estimate=None if self.estimate is None else self.estimate[k]))
        return rows

    def in_units(self, units: str) -> Spectrum:
        """The same spectrum with its accelerations in ``units`` ("g" or "m/s^2"; Sd, PSv follow: g s^2 or m).
        Refused, naming ``units``, when the spectrum's own unit is not known."""
        factor = unit_factor(self.units, units)
        return dataclasses.replace(self, Sd=self.Sd * factor, PSv=self.PSv * factor, PSa=self.PSa * factor,
                                   Sa=self.Sa * factor, Sv=None if self.Sv is None else self.Sv * factor,
                                   units=units)


ACCELERATION_UNITS = {"g": STANDARD_GRAVITY, "m/s^2": 1.0}  # in m/s^2


def unit_factor(have: str, want: str) -> float:
    """The factor turning accelerations in ``have`` into ``want`` (both "g" or "m/s^2")."""
    if want not in ACCELERATION_UNITS:
        raise _checks.value_error("units", f"expected one of {', '.join(ACCELERATION_UNITS)}, got {want!r}")
    if have not in ACCELERATION_UNITS:
        raise _checks.value_error("units", f"the record's unit is not known{f' ({have!r})' if have else ''}, so its "
                                           f"values cannot be given in {want}")
    return ACCELERATION_UNITS[have] / ACCELERATION_UNITS[want]


def unit_labels(units: str) -> dict:
    """The units of Sd, PSv and PSa for accelerations in ``units``: m and m/s for m/s^2."""
    if units == "m/s^2":
        return {"Sd": "m", "PSv": "m/s", "PSa": "m/s^2"}
    if units:
        return {"Sd": f"{units} s^2", "PSv": f"{units} s", "PSa": units}
    return {"Sd": "record units s^2", "PSv": "record units s", "PSa": "record units"}


def _exact_step(u, v, a0, a1, w, z, h):
    """The exact state after one interval h of u'' + 2 z w u' + w^2 u = -a_g, a_g linear from a0 to a1."""
    wd = w * math.sqrt(1.0 - z * z)
    s = (a1 - a0) / h
    c1 = -s / (w * w)  # particular solution c0 + c1 tau
    c0 = (-a0 - 2.0 * z * w * c1) / (w * w)
    A = u - c0
    B = (v - c1 + z * w * A) / wd
    e = np.exp(-z * w * h)
    cs, sn = np.cos(wd * h), np.sin(wd * h)
    return (e * (A * cs + B * sn) + c0 + c1 * h,
            e * ((wd * B - z * w * A) * cs - (z * w * B + wd * A) * sn) + c1)


def exact_sdof_peaks(t, ag, periods, damping: float):
    """Sd and absolute Sa (peaks at the times ``t``) of the linear SDOF u'' + 2 zeta w u' + w^2 u = -a_g
    (unit mass, from rest at t[0]) under the ground acceleration that is linear between the samples
    (t, ag), exactly: the closed-form solution over each interval (Nigam & Jennings 1969). On evenly
    spaced samples that one-step map is a fixed linear recurrence, run as a digital filter
    (scipy.signal.lfilter); otherwise interval by interval. Returns (Sd, Sa)."""
    from scipy import signal as sig

    t = np.asarray(t, dtype=float)
    ag = np.asarray(ag, dtype=float)
    periods = np.atleast_1d(np.asarray(periods, dtype=float))
    z = float(damping)
    if not 0.0 <= z < 1.0:
        raise _checks.value_error("damping", f"the exact solution needs 0 <= damping < 1, got {z}")
    sd, sa = np.zeros(periods.size), np.zeros(periods.size)
    d = np.diff(t)
    h = float(d.mean())
    uniform = bool(np.all(np.abs(d - h) <= 1e-9 * h))
    for k, T in enumerate(periods):
        w = 2.0 * math.pi / T
        if uniform:
            # x_{k+1} = M x_k + r_k with r_k = N0 g_k + N1 g_{k+1} and x_0 = 0: a zero-state linear filter
            cols = [_exact_step(*basis, w, z, h) for basis in ((1, 0, 0, 0), (0, 1, 0, 0), (0, 0, 1, 0), (0, 0, 0, 1))]
            M = np.array([cols[0], cols[1]]).T
            N0, N1 = np.array(cols[2]), np.array(cols[3])
            r = np.zeros((2, t.size))
            r[:, :-1] = np.outer(N0, ag[:-1]) + np.outer(N1, ag[1:])
            u, v = np.zeros(t.size), np.zeros(t.size)
            for j in range(2):  # input channel j, outputs u and v
                num, den = sig.ss2tf(M, np.eye(2), np.eye(2), np.zeros((2, 2)), input=j)
                u += sig.lfilter(num[0], den, r[j])
                v += sig.lfilter(num[1], den, r[j])
        else:
            u, v = np.zeros(t.size), np.zeros(t.size)
            for i in range(t.size - 1):
                u[i + 1], v[i + 1] = _exact_step(u[i], v[i], ag[i], ag[i + 1], w, z, t[i + 1] - t[i])
        sd[k] = np.max(np.abs(u))
        sa[k] = np.max(np.abs(2.0 * z * w * v + w * w * u))  # |u'' + a_g|
    return sd, sa


def _sdof(period: float, damping: float, record: GroundMotion, law: dict | None) -> Model:
    w = 2.0 * math.pi / period
    if law is None:
        spring = {"type": "spring", "name": "spring", "measure": {0: 1.0}, "k": w * w}
    else:
        if not isinstance(law, dict) or "type" not in law:
            raise _checks.type_error("law", "expected an effect without its measure, such as "
                                            "{'type': 'hardening_spring', 'a': 10.0} (its stiffness is set from the period)")
        spring = {**law, "name": "spring", "measure": {0: 1.0}}
        stiffness = {"spring": "k", "hardening_spring": "k0"}.get(law["type"])
        if stiffness is not None:
            spring[stiffness] = w * w  # the initial stiffness gives the period
    effects = [spring, {"type": "ground_acceleration", "name": "ground", "signal": record}]
    if damping > 0.0:
        effects.append({"type": "damper", "name": "damper", "measure": {0: 1.0}, "c": 2.0 * damping * w})
    return Model([1.0], effects=effects, dofs=["u"])


def spectrum(record: GroundMotion, periods, *, damping=0.05, scheme=None, law: dict | None = None,
             accuracy: float | None = None, t_end: float | None = None, threads: int | None = None,
             max_halvings: int | None = None) -> Spectrum:
    """The response spectrum of ``record`` at ``periods`` [s] (see the module's text and ``Spectrum``).

    Elastic (no ``law``, no ``scheme``): exact, in closed form, for one damping ratio or several
    (``damping=[0.02, 0.05]``: arrays of dampings x periods); ``accuracy`` and ``t_end`` do not apply.

    With ``scheme`` (any nvib scheme) or a nonlinear ``law`` (an effect in place of the linear spring,
    its stiffness from the period) the SDOF of each period is integrated: ``accuracy`` (default 1e-3) is
    the relative error to reach, checked against the exact peaks (a scheme on the linear SDOF: Sd and
    absolute Sa, between samples) or by halving the step (a law, with Newmark unless ``scheme`` is
    given); the first step is min(record dt, T sqrt(12 accuracy) / (2 pi)) (the period error of a
    second-order scheme is about (w dt)^2 / 12), halved for the periods that miss it, up to
    ``max_halvings`` times (default 4); ``threads`` as in ``solve_many``. ``t_end``: default the record's end plus two of the longest periods (the peak
    may come in the free vibration after it). Periods whose runs would not fit in memory (half the memory
    available, as for ``solve``) are refused before any run, naming ``periods``; a halving that would not
    fit is not made (that period's ``error`` says what was reached). A run that fails raises an NvibError
    naming its period.
    """
    import time

    import nvib  # the schemes

    if not isinstance(record, GroundMotion):
        raise _checks.type_error("record", f"expected a GroundMotion, got {type(record).__name__}")
    periods = _checks.real_array("periods", periods)
    if periods.ndim != 1 or periods.size == 0 or np.any(~(periods > 0)) or not np.all(np.isfinite(periods)):
        raise _checks.value_error("periods", "expected a non-empty list of positive periods")
    dampings = _checks.real_array("damping", damping)
    if dampings.ndim > 1 or dampings.size == 0:
        raise _checks.value_error("damping", "expected one damping ratio or a list of them")
    if scheme is None and law is None:
        for name, value in (("accuracy", accuracy), ("t_end", t_end), ("max_halvings", max_halvings),
                            ("threads", threads)):
            if value is not None:
                raise _checks.value_error(name, "the elastic spectrum is exact (closed form, the free vibration after "
                                                "the record followed as long as its peak can grow): "
                                                f"{name} applies to runs with a scheme= or a law=")
        start = time.perf_counter()
        out = record.exact_response(periods, dampings if dampings.ndim else float(dampings))
        wall = time.perf_counter() - start
        bad = ~np.isfinite(out["Sa"]) | ~np.isfinite(out["Sd"])
        if np.any(bad):
            T = np.broadcast_to(periods, bad.shape)[bad][0]
            raise _checks.value_error("record", f"its response at T = {T:g} s is not finite: its values, up to "
                                                f"{np.max(np.abs(record.a)):.3g}, are too large for doubles")
        rdt = record.dt if record.dt is not None else float(np.min(np.diff(record.t)))
        return Spectrum(periods, dampings if dampings.ndim else float(dampings), out["Sd"], out["PSv"], out["PSa"],
                        out["Sa"], np.full(periods.size, rdt), None, wall, "exact", record.name, "", Sv=out["Sv"],
                        units=record.units)
    if dampings.ndim:  # runs: one spectrum per damping ratio, stacked
        parts = [spectrum(record, periods, damping=float(z), scheme=scheme, law=law, accuracy=accuracy, t_end=t_end,
                          threads=threads, max_halvings=max_halvings) for z in dampings]
        stack = {k: np.vstack([getattr(p, k) for p in parts])
                 for k in ("Sd", "PSv", "PSa", "Sa", "dt", "error", "estimate")}
        return Spectrum(periods, dampings, stack["Sd"], stack["PSv"], stack["PSa"], stack["Sa"], stack["dt"],
                        stack["error"], sum(p.wall_time for p in parts), parts[0].check, record.name, parts[0].scheme,
                        units=record.units, estimate=stack["estimate"])
    damping = float(dampings)
    if not 0.0 <= damping < 1.0:
        raise _checks.value_error("damping", f"expected 0 <= damping < 1 for runs, got {damping}")
    accuracy = _checks.real("accuracy", 1e-3 if accuracy is None else accuracy, positive=True)
    if accuracy < MIN_ACCURACY:
        raise _checks.value_error("accuracy", f"must be >= {MIN_ACCURACY:g} (below it the round-off of the millions "
                                              f"of steps it takes is as large as the error asked for), got {accuracy:g}")
    max_halvings = _checks.integer("max_halvings", 4 if max_halvings is None else max_halvings, minimum=0)
    scheme = nvib.Newmark() if scheme is None else scheme
    given_t_end = t_end is not None
    t_end = float(record.t[-1] + 2.0 * periods.max()) if t_end is None else _checks.real("t_end", t_end, positive=True)
    rdt = record.dt if record.dt is not None else float(np.min(np.diff(record.t)))
    dts = np.minimum(rdt, periods * math.sqrt(12.0 * accuracy) / (2.0 * math.pi))
    with np.errstate(over="ignore", divide="ignore"):  # a period far too short: its step count is refused below
        dts = rdt / np.ceil(rdt / dts)  # a whole number of steps per record interval
    exact = law is None
    limit = 0.5 * _core.available_memory()  # what solve() allows one run's history
    _check_memory(periods, dts, t_end, exact, limit, rdt=rdt, record_end=float(record.t[-1]), accuracy=accuracy,
                  given_t_end=given_t_end)
    Sd, Sa, err = np.zeros(periods.size), np.zeros(periods.size), np.full(periods.size, np.inf)
    est = np.full(periods.size, np.nan)
    wall = 0.0
    todo = np.arange(periods.size)
    for attempt in range(max_halvings + 1):
        for dt in np.unique(dts[todo]):
            idx = todo[dts[todo] == dt]
            runs, times = _run(record, periods[idx], float(dt), damping, law, scheme, t_end, threads)
            wall += sum(r[2] for r in runs)
            Sd[idx] = [r[0] for r in runs]
            Sa[idx] = [r[1] for r in runs]
            est[idx] = [r[3] for r in runs]
            if exact:  # the exact peaks over the same span, between samples too, under the record as the runs saw it
                ref = _core.elastic_spectrum_at(times, record(times), periods[idx], damping, free_vibration=False)
                err[idx] = np.maximum(np.abs(Sd[idx] - ref["Sd"]) / np.maximum(ref["Sd"], 1e-300),
                                      np.abs(Sa[idx] - ref["Sa"]) / np.maximum(ref["Sa"], 1e-300))
            else:
                half, _ = _run(record, periods[idx], float(dt) / 2.0, damping, law, scheme, t_end, threads)
                wall += sum(r[2] for r in half)
                ref = np.array([r[0] for r in half])
                err[idx] = np.abs(Sd[idx] - ref) / np.maximum(ref, 1e-300)
            del times
        todo = todo[~(err[todo] <= accuracy)]  # a NaN error (an inf or NaN peak) misses the accuracy too
        if attempt == max_halvings:  # dt stays the step of the last runs, whose error err holds
            break
        if todo.size:  # a period whose halved step would not fit in memory keeps the error it reached
            steps, inverse, counts = np.unique(dts[todo], return_inverse=True, return_counts=True)
            fits = np.array([_memory_needed(n, 2.0 * t_end / dt, exact) <= limit for dt, n in zip(steps, counts)])
            todo = todo[fits[inverse.reshape(-1)]]
        if todo.size == 0:
            break
        dts[todo] /= 2.0
    w = 2.0 * math.pi / periods
    return Spectrum(periods, damping, Sd, w * Sd, w * w * Sd, Sa, dts, err, wall,
                    "exact check" if exact else "half step", record.name, nvib.scheme_label(scheme), units=record.units,
                    estimate=est)


def _memory_needed(group: int, steps: float, exact: bool) -> float:
    """Bytes the runs of ``group`` periods of ``steps`` steps each take at once (an estimate): CHUNK histories
    at a time and the work arrays of the check; without the exact check, the same runs at half the step."""
    per_state = _core.history_bytes(1, 1, False)  # t, u, v, a of the SDOF
    if exact:
        return (min(group, CHUNK) * per_state + _WORK_ARRAYS * 8.0) * (steps + 1.0)
    return (min(group, CHUNK) * per_state + _WORK_ARRAYS * 8.0) * (2.0 * steps + 1.0)


def _steps(t_end: float, dt: float) -> float:
    return t_end / dt if dt > 0 else math.inf  # a step that underflowed to 0 (T = 1e-320 s)


def _check_memory(periods, dts, t_end, exact, limit, *, rdt, record_end, accuracy, given_t_end) -> None:
    """Refuse, before anything is allocated, periods whose runs would not fit in memory: a period so short
    that its step (from the accuracy) is tiny, or one so long that t_end (the record's end plus two of the
    longest periods) is huge. Names ``periods``, or ``t_end`` when the caller's t_end is at fault."""
    worst = None
    for dt in np.unique(dts):
        group = periods[dts == dt]
        need = _memory_needed(group.size, _steps(t_end, dt), exact)
        if need > limit and (worst is None or need > worst[0]):
            worst = (need, dt, group)
    if worst is None:
        return
    need, dt, group = worst
    which = f"T = {group[0]:g} s" if group.size == 1 else f"T = {group.min():g} to {group.max():g} s"
    cost = (f"{_steps(t_end, dt):.3g} steps of {dt:.3g} s (the record's samples are {rdt:g} s apart) over "
            f"t_end = {t_end:g} s, whose runs would need about "
            f"{need / 1e9:.3g} GB, more than the {limit / 1e9:.3g} GB they may take (half the memory available)")
    own_t_end = record_end + 2.0 * group.max()  # the run these periods need
    fits_own = _memory_needed(group.size, _steps(min(t_end, own_t_end), dt), exact) <= limit
    if given_t_end and fits_own:
        raise _checks.value_error("t_end", f"{which} takes {cost}; give a shorter t_end")
    if not given_t_end and fits_own:  # the longest period makes every run long
        raise _checks.value_error("periods", f"the longest period, {periods.max():g} s, makes t_end the record's "
                                             f"end plus two of it, and {which} then takes {cost}; give shorter "
                                             f"periods, or t_end")
    if dt < rdt:  # the step comes from the period and the accuracy
        raise _checks.value_error("periods", f"{which} takes {cost}; give longer periods (or a coarser accuracy "
                                             f"than {accuracy:g})")
    raise _checks.value_error("t_end" if given_t_end else "periods",
                              f"{which} takes {cost}; give " + ("a shorter t_end" if given_t_end else "shorter periods"))


def _run(record, periods, dt, damping, law, scheme, t_end, threads):
    """([(Sd, absolute Sa, wall time, estimated error)] per period, the runs' times), through solve_many (one SDOF
    each)."""
    out, times = [], None
    for k in range(0, len(periods), CHUNK):  # CHUNK histories at a time: memory stays bounded
        rows, t = _run_chunk(record, periods[k:k + CHUNK], dt, damping, law, scheme, t_end, threads)
        out += rows
        times = t if times is None else times
    return out, times


def _run_chunk(record, periods, dt, damping, law, scheme, t_end, threads):
    models = [_sdof(T, damping, record, law) for T in periods]
    batch = solve_many(models, scheme, dt=dt, t_end=t_end, keep="history", threads=threads, progress=False,
                       max_displacement=math.inf)
    out = []
    for T, res in zip(periods, batch):
        if isinstance(res, RunError):
            raise NvibError(f"spectrum: the run at T = {T:g} s (dt = {dt:g} s) could not be made: {res.message}")
        if not res.success:
            exc = error_for(res.failure, res)
            raise type(exc)(f"spectrum: the run at T = {T:g} s (dt = {dt:g} s) failed: {res.failure.message}",
                            res.failure, res)
        e = res.error_estimate
        out.append((float(np.max(np.abs(res.u[:, 0]))), float(np.max(np.abs(res.absolute_a[:, 0]))),
                    res.stats.wall_time, e.max if e is not None else math.nan))
    # the times alone (a copy: a view would keep the whole history alive); every period has the same
    return out, np.array(batch[0].t)


def rotd_spectrum(a1, a2, dt: float, periods, damping: float = 0.05, *, angles: int = 180,
                  percentiles=(50.0, 100.0)) -> dict:
    """RotDnn of two horizontal components sampled dt apart (Boore 2010): for each angle theta of ``angles``
    evenly spaced in [0, 180) degrees, the exact peak Sd of the oscillator under a1 cos(theta) + a2 sin(theta)
    (nvib._core.rotated_sd: the responses to a1 and a2 combined, peaks between samples, free vibration after
    the record), then per period the given percentiles over the angles (50: RotD50, 100: RotD100, the
    largest). Returns {"periods", "angles" (degrees), "Sd" (angles x periods), and per percentile p:
    "RotD<p>" of Sd and "RotD<p>_PSa"}."""
    if not isinstance(angles, (int, np.integer)) or angles < 1:
        raise _checks.value_error("angles", f"expected a whole number >= 1, got {angles!r}")
    periods = np.atleast_1d(np.asarray(periods, dtype=float))
    theta = np.arange(angles) * (180.0 / angles)
    sd = _core.rotated_sd(np.asarray(a1, dtype=float), np.asarray(a2, dtype=float), dt, periods, damping, theta)
    w2 = (2.0 * math.pi / periods) ** 2
    out = {"periods": periods, "angles": theta, "Sd": sd}
    for p in percentiles:
        name = f"RotD{p:g}"
        out[name] = np.percentile(sd, p, axis=0)
        out[name + "_PSa"] = w2 * out[name]
    return out
