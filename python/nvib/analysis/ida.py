"""Incremental dynamic analysis (Vamvatsikos & Cornell 2002, "Incremental dynamic analysis", Earthquake
Engng Struct. Dyn. 31:491-514): a model under each record scaled to rising levels of an intensity measure
(IM; by default the exact 5 %-damped pseudo-spectral acceleration Sa(T1) of the record at the structure's
first period), each run reduced to a damage measure (DM; by default the maximum interstorey drift ratio,
from the storeys' drifts and heights), until the structure collapses.

Each record's curve is traced by hunt and fill: levels rise by a growing step until a run collapses (the
hunt), the bracket between the last level survived and the first that collapsed is halved until it is
narrower than ``tolerance`` (relative; the fill of the bracket), and runs left over fill the gaps of the
curve below it wider than a fifth of its capacity, widest first. With ``levels`` given, every record is run at every level instead (stripes).

A run collapses, and the IDA says by which cause:
- "strength lost": a law with memory reached its ultimate deformation or lost its strength (the run stops
  with Status.collapsed, naming the effect);
- "drift limit": the demand reached ``drift_limit`` (a drift ratio, 0.10 by default);
- "non-convergence": the run failed numerically (Newton did not converge, the iteration matrix was
  singular, or the response grew without bound);
- "dynamic instability": the curve flattened, its slope (IM per DM) from the level below falling under
  ``slope_limit`` (0.2) times its elastic slope, the secant of its first level (FEMA 350; Vamvatsikos &
  Cornell 2002, section 6).
Each run goes to its own record's end plus ``tail`` seconds of free vibration. Each run's accuracy is
checked by making it again at half the step (``check=True``): ``error`` is the relative change of the
demand, or inf where the verdict (collapse or not) changes with the step. Each run also reports its own
estimate of its error (``estimate``: ``Result.error_estimate``, the largest over the DOFs, relative to each
DOF's peak), with or without the check; a surviving run whose estimate exceeds ``warn_error`` (1e-2 unless
given) is named in the warnings.
"""

from __future__ import annotations

import dataclasses
import math
import time

import numpy as np

from .. import _checks
from .._batch import RunError, solve_many
from .._labels import scheme_label
from .._model import Model
from .._records import STANDARD_GRAVITY, GroundMotion
from .._solve import ERROR_WARNING, Status
from .._storeys import declared, max_drift_ratio, storey_heights

__all__ = ["IDA", "Curve", "ida", "intensity", "read_ida", "CAUSES"]

CAUSES = ("strength lost", "drift limit", "non-convergence", "dynamic instability")
FILL_GAP = 0.2  # runs left after the bracket fill the gaps of a curve wider than this fraction of its capacity
_FAILED = {Status.newton_failed: "non-convergence", Status.singular_matrix: "non-convergence",
           Status.diverged: "non-convergence", Status.collapsed: "strength lost"}


@dataclasses.dataclass
class Curve:
    """One record's IDA curve, sorted by intensity: ``im`` (the levels run), ``demand`` (the damage measure;
    inf where the run collapsed), ``collapsed``, ``cause`` ("" or one of CAUSES), ``factor`` (the scale factor
    that brought the record to each level), ``error`` (the relative change of the demand when the step is
    halved; 0 for a collapse found at both steps, inf where the verdict changes, NaN when not checked),
    ``message`` (why a run failed), ``peak_storey`` (where the demand is, for a drift ratio),
    ``run_demand`` (the demand each run reached, finite also where a flattening curve counts it as a collapse;
    NaN where the run failed) and ``estimate`` (each run's estimate of its own error, relative to the peaks;
    NaN where the run has none)."""

    record: str
    im: np.ndarray
    demand: np.ndarray
    collapsed: np.ndarray
    cause: list
    factor: np.ndarray
    error: np.ndarray
    message: list
    peak_storey: list
    run_demand: np.ndarray
    estimate: np.ndarray

    @property
    def capacity(self) -> float:
        """The collapse capacity: the highest level survived below the first collapse (inf when the record
        never collapsed; 0 when it collapsed at its first level)."""
        if not self.collapsed.any():
            return math.inf
        first = int(np.argmax(self.collapsed))
        return float(self.im[first - 1]) if first else 0.0

    @property
    def collapse_im(self) -> float:
        """The lowest level at which the record collapsed (inf when it never did)."""
        return float(self.im[np.argmax(self.collapsed)]) if self.collapsed.any() else math.inf

    @property
    def collapse_cause(self) -> str:
        return self.cause[int(np.argmax(self.collapsed))] if self.collapsed.any() else ""

    def demand_at(self, levels) -> np.ndarray:
        """The demand at ``levels``, linear between the levels run, inf at and above the first collapse
        (NaN below the first level run)."""
        levels = np.asarray(levels, dtype=float)
        first = int(np.argmax(self.collapsed)) if self.collapsed.any() else self.im.size
        x, y = np.r_[0.0, self.im[:first]], np.r_[0.0, self.demand[:first]]
        out = np.interp(levels, x, y)
        out[levels > x[-1]] = np.inf if first < self.im.size else np.nan
        return out

    def im_at(self, demand: float) -> float:
        """The lowest level at which the demand reaches ``demand`` (linear between levels run; a collapse
        reaches every demand); inf when it never does."""
        x, y = np.r_[0.0, self.im], np.r_[0.0, self.demand]
        for k in range(1, x.size):
            if y[k] >= demand:
                if not np.isfinite(y[k]):
                    return float(x[k])
                return float(x[k - 1] + (x[k] - x[k - 1]) * (demand - y[k - 1]) / (y[k] - y[k - 1]))
        return math.inf


@dataclasses.dataclass
class IDA:
    """The curves of an incremental dynamic analysis (one ``Curve`` per record) and their summary on common
    ``levels`` of the intensity measure: ``measure`` [record, level] (each curve's demand there; inf above
    its collapse) and ``collapsed`` [record, level], whose fractiles (``median``, ``p16``, ``p84``) count a
    collapse as an infinite demand. ``im_name``/``im_unit`` name the intensity measure, ``measure_name``/
    ``measure_unit`` the demand; ``tolerance``: the relative width each collapse was bracketed to (None for
    stripes); ``warnings``: runs whose accuracy or tracing fell short. ``runs``: runs made (with the checks)."""

    records: list
    curves: list
    levels: np.ndarray
    measure: np.ndarray
    collapsed: np.ndarray
    measure_name: str
    measure_unit: str
    im_name: str
    im_unit: str
    scheme: str
    dt: float
    tolerance: float | None
    warnings: list
    runs: int
    wall_time: float

    @property
    def messages(self) -> dict:
        """{(record, level): why the run failed} for the runs at ``levels`` that failed."""
        out = {}
        for i, c in enumerate(self.curves):
            for j, x in enumerate(self.levels):
                k = np.flatnonzero(c.im == x)
                if k.size and c.message[k[0]]:
                    out[(i, j)] = c.message[k[0]]
        return out

    @property
    def capacities(self) -> np.ndarray:
        """Each record's collapse capacity (``Curve.capacity``; inf when it never collapsed)."""
        return np.array([c.capacity for c in self.curves])

    def fractile(self, q: float) -> np.ndarray:
        """The q-th percentile (0-100) of the demand over the records at each level (linear between records),
        a collapse counting as an infinite demand: inf where the percentile reaches into the collapses."""
        big = np.finfo(float).max
        x = np.percentile(np.where(np.isinf(self.measure), big, self.measure), q, axis=0)
        return np.where(x > 1e300, np.inf, x)

    @property
    def median(self) -> np.ndarray:
        return self.fractile(50)

    @property
    def p16(self) -> np.ndarray:
        return self.fractile(16)

    @property
    def p84(self) -> np.ndarray:
        return self.fractile(84)

    def capacity_fractile(self, q: float) -> float:
        """The q-th percentile of the collapse capacities (records that never collapsed count as infinite)."""
        big = np.finfo(float).max
        x = float(np.percentile(np.where(np.isinf(self.capacities), big, self.capacities), q))
        return math.inf if x > 1e300 else x

    @property
    def estimates(self) -> np.ndarray:
        """Every run's estimate of its own error (the curves' ``estimate``, one after the other)."""
        return np.concatenate([c.estimate for c in self.curves]) if self.curves else np.zeros(0)

    def estimate_summary(self) -> str:
        """One line: the runs' estimated errors (median and worst, with the record and level of the worst)."""
        est = self.estimates
        if not np.any(np.isfinite(est)):
            return "estimated error of the runs: none reported"
        worst, where = -math.inf, ""
        for c in self.curves:
            if np.any(np.isfinite(c.estimate)):
                k = int(np.nanargmax(c.estimate))
                if c.estimate[k] > worst:
                    worst, where = float(c.estimate[k]), f"{c.record} at {c.im[k]:.4g}"
        return (f"estimated error of the runs (relative to the peaks): median {np.nanmedian(est):.2g}, "
                f"worst {worst:.2g} ({where}), {int(np.sum(np.isfinite(est)))} of {est.size} runs estimated")

    def _im_label(self) -> str:
        return f"{self.im_name} [{self.im_unit}]" if self.im_unit else self.im_name

    def _dm_label(self) -> str:
        return f"{self.measure_name} [{self.measure_unit}]" if self.measure_unit else self.measure_name

    def markdown(self) -> str:
        """Two tables: each record's collapse (capacity, cause, runs, worst checked error, worst estimated
        error), then the demand at each level with its fractiles."""
        fmt = lambda x: "collapse" if np.isinf(x) else ("-" if np.isnan(x) else f"{x:.4g}")  # noqa: E731
        worst = lambda x: np.nanmax(x) if np.any(~np.isnan(x)) else math.nan  # noqa: E731
        rows = [f"| record | capacity {self._im_label()} | first collapse | cause | runs | worst error | "
                "worst estimate |", "|---|---:|---:|---|---:|---:|---:|"]
        for c in self.curves:
            cap = "none found" if np.isinf(c.capacity) else f"{c.capacity:.4g}"
            err, est = worst(c.error), worst(c.estimate)
            rows.append(f"| {c.record} | {cap} | {'-' if np.isinf(c.collapse_im) else f'{c.collapse_im:.4g}'} | "
                        f"{c.collapse_cause or '-'} | {c.im.size} | {'-' if np.isnan(err) else f'{err:.2g}'} | "
                        f"{'-' if np.isnan(est) else f'{est:.2g}'} |")
        rows += ["", f"| {self._im_label()} | " + " | ".join(self.records) + " | median | 16 % | 84 % |",
                 "|---:|" + "---:|" * (len(self.records) + 3)]
        for j, x in enumerate(self.levels):
            cells = [fmt(self.measure[i, j]) for i in range(len(self.records))]
            rows.append(f"| {x:.4g} | " + " | ".join(cells) + f" | {fmt(self.median[j])} | {fmt(self.p16[j])} | "
                        f"{fmt(self.p84[j])} |")
        return "\n".join(rows) + "\n"

    def to_csv(self, path) -> None:
        """Every run, one row each (record, intensity, demand, collapsed, cause, scale factor, checked error,
        storey, message, the run's demand, its estimated error), under comment lines that say what the IDA measured; ``read_ida`` reads it back."""
        import csv

        with open(path, "w", newline="", encoding="utf-8") as fh:
            for key in ("im_name", "im_unit", "measure_name", "measure_unit", "scheme", "dt"):
                fh.write(f"# {key}: {getattr(self, key)}\n")
            fh.write(f"# tolerance: {'stripes' if self.tolerance is None else self.tolerance}\n")
            out = csv.writer(fh, quoting=csv.QUOTE_MINIMAL)
            out.writerow(["record", f"im [{self.im_unit}]", f"demand [{self.measure_unit}]", "collapsed", "cause",
                          "scale factor", "error", "storey", "message", f"run demand [{self.measure_unit}]",
                          "estimate"])
            for c in self.curves:
                for k in range(c.im.size):
                    out.writerow([c.record, repr(float(c.im[k])), repr(float(c.demand[k])), int(c.collapsed[k]),
                                  c.cause[k], repr(float(c.factor[k])), repr(float(c.error[k])), c.peak_storey[k],
                                  c.message[k], repr(float(c.run_demand[k])), repr(float(c.estimate[k]))])

    def plot(self, path=None, *, ax=None):
        """IDA curves: the intensity against the demand, one curve per record with its runs as dots, each
        collapse an x at the right (labelled with its cause), and the 16/50/84 % fractiles. Saves to ``path``."""
        import matplotlib

        if ax is None and path is not None:
            matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig = None
        if ax is None:
            fig, ax = plt.subplots(figsize=(7.5, 5.5))
        finite = np.concatenate([c.demand[np.isfinite(c.demand)] for c in self.curves] + [np.zeros(1)])
        top = 1.12 * finite.max() if finite.max() > 0 else 1.0
        marks = {"strength lost": "X", "drift limit": ">", "non-convergence": "s", "dynamic instability": "v"}
        seen = set()
        for c in self.curves:
            first = int(np.argmax(c.collapsed)) if c.collapsed.any() else c.im.size
            x, y = np.r_[0.0, c.demand[:first]], np.r_[0.0, c.im[:first]]
            line, = ax.plot(x, y, "-o", ms=2.5, lw=1, alpha=0.85, label=c.record)
            if first < c.im.size:
                cause = c.cause[first]
                ax.plot([x[-1], top], [y[-1], c.im[first]], ":", color=line.get_color(), lw=1)
                ax.plot([top], [c.im[first]], marks.get(cause, "x"), color=line.get_color(), ms=8,
                        label=None if cause in seen else f"collapse: {cause}", mec="k")
                seen.add(cause)
        for values, style, label in ((self.median, "k-", "median"), (self.p16, "k--", "16 % / 84 %"),
                                     (self.p84, "k--", None)):
            ok = np.isfinite(values)
            ax.plot(np.r_[0.0, values[ok]], np.r_[0.0, self.levels[ok]], style, lw=2, label=label)
        ax.set_xlim(0, top * 1.04)
        ax.set_ylim(bottom=0)
        ax.set_xlabel(self._dm_label() + "  (markers at right: collapse)")
        ax.set_ylabel(self._im_label())
        ax.set_title(f"IDA of {len(self.curves)} records, {self.scheme}, dt = {self.dt:g} s")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7, loc="upper left")
        if fig is not None and path is not None:
            fig.tight_layout()
            fig.savefig(path, dpi=120)
            plt.close(fig)
        return ax


# ---- the intensity measure --------------------------------------------------------------------------

def intensity(record: GroundMotion, im="sa", *, period: float | None = None, damping: float = 0.05) -> float:
    """The intensity measure of ``record``: "sa" (the exact pseudo-spectral acceleration Sa(T1, damping)
    at ``period``, nvib._core.elastic_spectrum), "pga" (the peak |a_g|), "scale" (1: the levels are the
    records' scale factors), or a callable f(record) -> float. In the record's units."""
    if not isinstance(record, GroundMotion):
        raise _checks.type_error("record", f"expected a GroundMotion, got {type(record).__name__}")
    if callable(im):
        value = im(record)
        if not isinstance(value, (int, float, np.floating)) or not np.isfinite(value) or value <= 0:
            raise _checks.value_error("im", f"the intensity measure gave {value!r} for {record.name or 'a record'}: "
                                            "expected a finite positive number")
        return float(value)
    if im == "pga":
        return float(np.max(np.abs(record.a)))
    if im == "scale":
        return 1.0
    if im != "sa":
        raise _checks.value_error("im", f"expected 'sa', 'pga', 'scale' or a callable f(record) -> float, got {im!r}"
                                        f"{_checks.suggestion(str(im), ['sa', 'pga', 'scale'])}")
    if period is None:
        raise _checks.value_error("period", "im='sa' needs the period T1 of Sa(T1) [s]")
    return float(record.psa([period], damping)[0])


def _im_label(im, period, damping) -> str:
    if callable(im):
        return getattr(im, "__name__", "intensity")
    if im in ("pga", "scale"):
        return "PGA" if im == "pga" else "scale factor of the records"
    return f"Sa(T1 = {period:.3g} s, {100 * damping:g} %)"


def first_period(model: Model) -> float:
    """T1 [s]: the longest period of ``model`` linearised at its initial state (P-delta included)."""
    w = model.linearized_frequencies(model.u0)
    w = w[w > 0]
    if w.size == 0:
        raise _checks.value_error("period", "the model has no positive frequency at its initial state: give the "
                                            "period T1 of Sa(T1)")
    return 2.0 * math.pi / float(w[0])


# ---- the demand -----------------------------------------------------------------------------------

def _check_measure(model, measure) -> tuple[str, str]:
    """(name, unit) of the measure, checked before any run (a run that collapses has none to look it up in):
    "drift_ratio" (needs storeys), "peak_drift" (named effects with a measure), "peak_u" or an effect's name."""
    if not isinstance(model, Model):
        raise _checks.type_error("model", f"expected a Model, got {type(model).__name__}")
    if not isinstance(measure, str):
        raise _checks.type_error("measure", f"expected 'drift_ratio', 'peak_drift', 'peak_u' or an effect's name, "
                                            f"got {measure!r}")
    named = [e.name for e in model.effects or [] if e.name and not e.is_load]
    named += [a.name for a in model.effect_arrays if a.name and not a.is_load]
    unit = model.unit(0) if model.n else ""
    if measure == "drift_ratio":
        return "max interstorey drift ratio", "%"
    if measure == "peak_u":
        return "peak |u|", unit
    if measure in named:
        return f"peak |{measure}|", unit
    if measure == "peak_drift":
        if not named:
            raise _checks.value_error("measure", "peak_drift needs named effects (storeys) with a measure")
        return "peak storey drift", unit
    raise _checks.value_error("measure", f"expected 'drift_ratio', 'peak_drift', 'peak_u' or the name of an effect "
                                         f"({', '.join(dict.fromkeys(named)) or 'none named'})"
                                         f"{_checks.suggestion(measure, ['drift_ratio', 'peak_drift', 'peak_u', *named])}"
                                         f", got {measure!r}")


def _demand(summary, measure: str, heights) -> tuple[float, str]:
    if measure == "drift_ratio":
        return max_drift_ratio(summary.peak_measures, heights)
    if measure == "peak_drift":
        name, value = max(((k, float(np.max(v))) for k, v in summary.peak_measures.items()), key=lambda kv: kv[1])
        return value, name
    if measure == "peak_u":
        return float(np.max(summary.peak_u)), ""
    return float(np.max(summary.peak_measures[measure])), measure


# ---- the tracer --------------------------------------------------------------------------------------

def _verdicts(points: dict, slope_limit: float) -> list:
    """[(level, demand, cause, message, storey, run demand)] of ``points`` {level: (demand, failed cause,
    message, storey)}, sorted, each run's cause decided: a failed run's own, and "dynamic instability" where
    the slope from the highest surviving level below falls under ``slope_limit`` times the elastic slope."""
    out, below, elastic = [], None, None
    for x in sorted(points):
        d, cause, msg, storey = points[x]
        if not cause and below is not None and elastic is not None and d > below[1]:
            if (x - below[0]) / (d - below[1]) < slope_limit * elastic:
                cause, msg = "dynamic instability", (f"the curve's slope from {below[0]:.4g} fell under "
                                                     f"{slope_limit:g} of its elastic slope")
        out.append((x, d if not cause else math.inf, cause, msg, storey, d))
        if not cause and below is None and d > 0:
            elastic = x / d  # the secant of the first level: the curve's elastic slope
        if not cause and (below is None or x > below[0]):
            below = (x, d)
    return out


class _Record:
    """The runs of one record so far, and what to run next (hunt, then fill)."""

    def __init__(self, start, step, growth, tolerance, max_runs, ceiling, slope_limit):
        self.points = {}  # level -> (demand, failed cause, message, storey)
        self.start, self.step, self.growth = start, step, growth
        self.tolerance, self.max_runs, self.ceiling, self.slope_limit = tolerance, max_runs, ceiling, slope_limit
        self.hunting = True
        self.note = ""

    def verdicts(self):
        return _verdicts(self.points, self.slope_limit)

    def bracket(self):
        """(highest level survived below the first collapse, first collapsing level) or None."""
        lo = 0.0
        for x, _, cause, *_ in self.verdicts():
            if cause:
                return lo, x
            lo = x
        return None

    def next_level(self):
        """The next level to run, or None when the record is traced."""
        n = len(self.points)
        if n >= self.max_runs:
            if self.hunting or self._wide():
                self.note = f"stopped at its {self.max_runs} runs (max_runs) before its collapse was bracketed"
            return None
        levels = sorted(self.points)
        if self.hunting:
            b = self.bracket()
            if b is None:
                x = self.start if not levels else levels[-1] + self.step + self.growth * (n - 1)
                if x > self.ceiling:
                    self.note = f"no collapse up to {levels[-1]:.4g} (the ceiling {self.ceiling:.4g})"
                    return None
                return x
            self.hunting = False
        if self._wide():
            lo, hi = self.bracket()
            return 0.5 * (lo + hi) if lo > 0 else 0.5 * hi
        # fill: the widest gap in intensity below the collapse, while runs are left and it is wider than a
        # fifth of the capacity
        lo, _ = self.bracket()
        below = [0.0] + [x for x in levels if x <= lo]
        gaps = np.diff(below)
        if below[-1] <= 0 or gaps.max() <= FILL_GAP * lo:
            return None
        k = int(np.argmax(gaps))
        return 0.5 * (below[k] + below[k + 1])

    def _wide(self):
        b = self.bracket()
        return b is not None and (b[1] - b[0]) > self.tolerance * b[0]


def _validate(model, records, levels, im, period, damping, measure, storeys, drift_limit, slope_limit, tolerance,
              max_runs, tail):
    records = list(records) if not isinstance(records, GroundMotion) else [records]
    if not records:
        raise _checks.value_error("records", "expected at least one GroundMotion")
    for k, r in enumerate(records):
        if not isinstance(r, GroundMotion):
            raise _checks.type_error(f"records[{k}]", f"expected a GroundMotion, got {type(r).__name__}")
    if measure is None:
        measure = "drift_ratio" if (storeys is not None or declared(model)) else None
        if measure is None and isinstance(model, Model):
            raise _checks.value_error("storeys", "the demand is the maximum interstorey drift ratio: give "
                                                 "storeys={'storey1': 3.5, ...} (the effects whose measure is a storey "
                                                 "drift, and their heights in m; a scene's [storeys] table), or "
                                                 "measure='peak_drift', 'peak_u' or an effect's name")
    heights = storey_heights(model, storeys) if measure == "drift_ratio" else None
    measure_name, measure_unit = _check_measure(model, measure)
    if levels is not None:
        levels = np.sort(_checks.real_array("levels", levels))
        if levels.ndim != 1 or levels.size == 0 or np.any(levels <= 0):
            raise _checks.value_error("levels", "expected a list of positive intensity levels")
    damping = _checks.real("damping", damping)
    if not 0.0 <= damping < 1.0:
        raise _checks.value_error("damping", f"expected 0 <= damping < 1, got {damping}")
    if im == "sa" and period is None:
        period = first_period(model)
    period = None if period is None else _checks.real("period", period, positive=True)
    checked = dict(drift_limit=_checks.real("drift_limit", drift_limit, positive=True),
                   slope_limit=_checks.real("slope_limit", slope_limit, positive=True),
                   tolerance=_checks.real("tolerance", tolerance, positive=True),
                   max_runs=_checks.integer("max_runs", max_runs, minimum=2),
                   tail=(None if tail is None else _checks.real("tail", tail)))
    if checked["tail"] is not None and checked["tail"] < 0:
        raise _checks.value_error("tail", f"expected a free-vibration time >= 0 [s], got {tail}")
    if checked["slope_limit"] >= 1.0:
        raise _checks.value_error("slope_limit", f"expected a fraction of the elastic slope below 1, got {slope_limit}")
    return records, levels, measure, measure_name, measure_unit, heights, damping, period, checked


def ida(model, records, levels=None, *, im="sa", period: float | None = None, damping: float = 0.05,
        measure: str | None = None, storeys: dict | None = None, scheme=None, dt: float, tail: float | None = None,
        drift_limit: float = 0.10, slope_limit: float = 0.2, tolerance: float = 0.05, start: float | None = None,
        step: float | None = None, max_runs: int = 16, ceiling: float | None = None, check: bool = True,
        threads: int | None = None, progress: bool = True, **options) -> IDA:
    """Incremental dynamic analysis of ``model`` under ``records`` (GroundMotions; see the module's text).

    Intensity ``im``: "sa" (the exact Sa(``period``, ``damping``) of each record; ``period`` defaults to the
    model's T1 linearised at its initial state), "pga", "scale" (the records' own scale factors) or a callable
    f(record) -> float; in the records' units. Records in g are run in m/s^2 (the models' SI unit).

    Demand ``measure``: "drift_ratio" (default when the model has storeys: the maximum over storeys and time
    of |drift| / height, from ``storeys`` {effect name: height [m]} or the scene's [storeys]), "peak_drift"
    (the largest peak of the named effects' measures), "peak_u" or the name of one effect.

    Without ``levels`` each record is traced by hunt and fill: the first level ``start`` (default a tenth of the
    records' median intensity), then steps of ``step`` (default ``start``) growing by half of it each run, up to
    ``ceiling`` (default 20 times the median intensity); the collapse bracketed to ``tolerance`` (relative);
    at most ``max_runs`` runs per record. With ``levels``: every record at every level (stripes).

    ``tail``: free vibration after each record [s] (default 2 T1, or 2 s without a period). ``drift_limit``: the
    drift ratio that counts as collapse (measure "drift_ratio"). ``slope_limit``: the flattening that counts as
    dynamic instability. ``check``: make every run again at dt/2 and report the change as its ``error``.
    Other keywords go to ``solve_many`` (``save_every``, ``energy``, ...)."""
    import nvib

    t_start = time.perf_counter()
    if "t_end" in options:
        raise _checks.value_error("t_end", "each run goes to its own record's end plus the free vibration of tail= "
                                           "seconds")
    records, levels, measure, measure_name, measure_unit, heights, damping, period, lim = _validate(
        model, records, levels, im, period, damping, measure, storeys, drift_limit, slope_limit, tolerance,
        max_runs, tail)
    scheme = nvib.CEMDTS() if scheme is None else scheme
    dt = _checks.real("dt", dt, positive=True)
    own = np.array([intensity(r, im, period=period, damping=damping) for r in records])
    median = float(np.median(own))
    start = 0.1 * median if start is None else _checks.real("start", start, positive=True)
    step = start if step is None else _checks.real("step", step, positive=True)
    ceiling = 20.0 * median if ceiling is None else _checks.real("ceiling", ceiling, positive=True)
    tail = lim["tail"] if lim["tail"] is not None else (2.0 * period if period is not None else 2.0)
    ends = [float(r.t[-1]) + tail for r in records]
    limit = lim["drift_limit"] if measure == "drift_ratio" else math.inf

    def run(pairs, step_dt):
        """[(demand, cause, message, storey)] of the runs (record index, level) at step_dt, in one batch, and
        [their estimated errors]."""
        if not pairs:
            return [], []
        motions = []
        for i, x in pairs:
            r = records[i]
            base = r.scaled(STANDARD_GRAVITY) if r.units == "g" else r
            motions.append(base.scaled(x / own[i]) if x != own[i] else base)
        batch = solve_many(model, scheme, dt=step_dt, t_end=[ends[i] for i, _ in pairs],
                           ground_motions=motions, keep="peaks", threads=threads, progress=progress, **options)
        out = []
        for run_ in batch:
            if isinstance(run_, RunError):
                raise run_.error
            if run_.success:
                d, where = _demand(run_, measure, heights)
                if measure == "drift_ratio":
                    d = 100.0 * d  # in %
                if d >= 100.0 * limit:
                    out.append((d, "drift limit", f"the drift ratio reached {d:.3g} % in {where} (drift_limit "
                                                  f"{100 * limit:g} %)", where))
                else:
                    out.append((d, "", "", where))
            else:
                out.append((math.nan, _FAILED.get(run_.status, "non-convergence"), run_.message, ""))
        return out, [math.nan if r.error_estimate is None else r.error_estimate for r in batch]

    tracers = [_Record(start, step, 0.5 * step, lim["tolerance"], lim["max_runs"], ceiling, lim["slope_limit"])
               for _ in records]
    runs = 0
    estimates = {}  # (record index, level) -> the run's estimated error

    def trace(pairs):
        values, errors = run(pairs, dt)
        for (i, x), value, e in zip(pairs, values, errors):
            tracers[i].points[x] = value
            estimates[(i, x)] = e
        return len(pairs)

    if levels is not None:
        runs += trace([(i, float(x)) for i in range(len(records)) for x in levels])
    else:
        while True:
            pairs = [(i, x) for i, t in enumerate(tracers) for x in [t.next_level()] if x is not None]
            if not pairs:
                break
            runs += trace(pairs)
    warnings = [f"{records[i].name or f'record {i}'}: {t.note}" for i, t in enumerate(tracers) if t.note]
    checks = {}
    if check:  # every run again at half the step
        pairs = [(i, x) for i, t in enumerate(tracers) for x in sorted(t.points)]
        for pair, value in zip(pairs, run(pairs, 0.5 * dt)[0]):
            checks[pair] = value
        runs += len(pairs)
    curves = []
    names = [r.name or f"record {k}" for k, r in enumerate(records)]
    warn_error = options.get("warn_error", ERROR_WARNING)
    for i, t in enumerate(tracers):
        v = t.verdicts()
        est = np.array([estimates[(i, p[0])] for p in v])
        above = [k for k, p in enumerate(v) if not p[2] and est[k] > warn_error]
        if above:
            k = max(above, key=lambda k: est[k])
            warnings.append(f"{names[i]}: {len(above)} of {len(v)} runs estimate their error above warn_error = "
                            f"{warn_error:g} (worst {est[k]:.2g} at {v[k][0]:.4g}): a smaller dt would make them "
                            f"more accurate")
        err = np.full(len(v), np.nan)
        if check:
            half = _verdicts({x: checks[(i, x)] for x, *_ in v}, lim["slope_limit"])
            for k, ((x, d, cause, *_), (_, dh, cause_h, *_)) in enumerate(zip(v, half)):
                if bool(cause) != bool(cause_h):
                    err[k] = math.inf
                    warnings.append(f"{names[i]} at {x:.4g}: the verdict changes when the step is halved ("
                                    f"{cause or 'survives'} at dt = {dt:g} s, {cause_h or 'survives'} at {dt / 2:g} s)")
                else:
                    err[k] = 0.0 if cause else abs(d - dh) / max(abs(dh), 1e-300)
        curves.append(Curve(names[i], np.array([p[0] for p in v]), np.array([p[1] for p in v]),
                            np.array([bool(p[2]) for p in v]), [p[2] for p in v],
                            np.array([p[0] / own[i] for p in v]), err, [p[3] for p in v], [p[4] for p in v],
                            np.array([p[5] for p in v]), est))
    grid = levels if levels is not None else _summary_levels(curves)
    measure_arr = np.vstack([c.demand_at(grid) for c in curves])
    units = {r.units for r in records}
    im_unit = "-" if im == "scale" else (units.pop() if len(units) == 1 and not callable(im) else "")
    return IDA(names, curves, grid, measure_arr, np.isinf(measure_arr), measure_name, measure_unit,
               _im_label(im, period, damping), im_unit, scheme_label(scheme), dt,
               lim["tolerance"] if levels is None else None, warnings, runs, time.perf_counter() - t_start)


def _summary_levels(curves) -> np.ndarray:
    """Common levels for the fractiles of traced curves: 25 from the lowest level run to the highest collapse."""
    lows = [c.im[0] for c in curves if c.im.size]
    highs = [c.collapse_im if np.isfinite(c.collapse_im) else c.im[-1] for c in curves if c.im.size]
    return np.linspace(min(lows), max(highs), 25)


def read_ida(path) -> IDA:
    """The IDA an ``IDA.to_csv`` file holds (the file named in every error)."""
    import csv

    meta, rows = {}, []
    try:
        with open(path, newline="", encoding="utf-8") as fh:
            lines = fh.read().splitlines()
    except (OSError, UnicodeDecodeError) as exc:
        raise _checks.value_error("path", f"{path!r}: cannot read it: {getattr(exc, 'strerror', None) or exc}") from None
    body = []
    for line in lines:
        if line.startswith("# ") and ": " in line and not body:
            key, _, value = line[2:].partition(": ")
            meta[key] = value
        else:
            body.append(line)
    need = {"im_name", "im_unit", "measure_name", "measure_unit", "scheme", "dt", "tolerance"}
    if not need <= set(meta) or not body or not body[0].startswith("record,"):
        raise _checks.value_error("path", f"{path!r}: not an IDA file written by nvib (IDA.to_csv, nvib ida --out)")
    curves = {}
    try:
        for k, row in enumerate(csv.reader(body[1:]), start=2):
            if not row:
                continue
            if len(row) not in (10, 11):  # files written before the estimate column have 10
                raise ValueError(f"row {k} has {len(row)} fields, expected 11")
            rows.append(row)
            name = row[0]
            c = curves.setdefault(name, [])
            c.append((float(row[1]), float(row[2]), row[3] == "1", row[4], float(row[5]), float(row[6]), row[8],
                      row[7], float(row[9]), float(row[10]) if len(row) == 11 else math.nan))
    except ValueError as exc:
        raise _checks.value_error("path", f"{path!r}: {exc}") from None
    if not curves:
        raise _checks.value_error("path", f"{path!r}: holds no runs")
    out = []
    for name, pts in curves.items():
        pts.sort(key=lambda p: p[0])
        cols = list(zip(*pts))
        out.append(Curve(name, np.array(cols[0]), np.array(cols[1]), np.array(cols[2], dtype=bool), list(cols[3]),
                         np.array(cols[4]), np.array(cols[5]), list(cols[6]), list(cols[7]), np.array(cols[8]),
                         np.array(cols[9])))
    stripes = meta["tolerance"] == "stripes"
    grid = np.unique(np.concatenate([c.im for c in out])) if stripes else _summary_levels(out)
    measure = np.vstack([c.demand_at(grid) for c in out])
    return IDA([c.record for c in out], out, grid, measure, np.isinf(measure), meta["measure_name"],
               meta["measure_unit"], meta["im_name"], meta["im_unit"], meta["scheme"], float(meta["dt"]),
               None if stripes else float(meta["tolerance"]), [], len(rows), 0.0)
