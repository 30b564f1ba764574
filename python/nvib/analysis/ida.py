"""Incremental dynamic analysis: a model under every record at every scale factor, through
``solve_many``, reduced to one damage measure per run (a peak storey drift by default). A run that
diverges is a collapse: its measure is infinite, it stays in the table, and the curve of its record
ends there with a mark at the top."""

from __future__ import annotations

import dataclasses

import numpy as np

from .. import _checks
from .._batch import RunError, solve_many
from .._labels import scheme_label
from .._model import Model
from .._records import GroundMotion

__all__ = ["IDA", "ida", "intensity"]


@dataclasses.dataclass
class IDA:
    """``measure`` [record, scale] (inf where the run collapsed), ``collapsed`` (bool, same shape),
    ``records`` (names), ``scales`` (the intensity levels: the records' scale factors, or with an intensity
    measure its values), the name of the measure, and per level the ``median``, ``p16`` and ``p84`` of the
    measure over the records (collapses count as infinite). ``messages``: why a run failed. With an
    intensity measure, ``im_name`` names it (e.g. "Sa(T1 = 0.8 s, 5 %)") with its ``im_unit``, and
    ``factors`` [record, level] are the scale factors that brought each record to each level."""

    records: list
    scales: np.ndarray
    measure_name: str
    measure: np.ndarray
    collapsed: np.ndarray
    messages: dict
    scheme: str
    im_name: str = "scale factor"
    im_unit: str = "-"
    factors: np.ndarray | None = None

    def fractile(self, q: float) -> np.ndarray:
        """The q-th percentile (0-100) of the measure over the records at each scale, interpolated
        linearly between records; infinite where it reaches into the collapses."""
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

    def markdown(self) -> str:
        """The table: one row per scale, one column per record, then the fractiles."""
        level = "scale" if self.factors is None else f"{self.im_name} [{self.im_unit or 'record units'}]"
        head = f"| {level} | " + " | ".join(self.records) + " | median | 16 % | 84 % |"
        rows = [head, "|---:|" + "---:|" * (len(self.records) + 3)]
        fmt = lambda x: "collapse" if not np.isfinite(x) else f"{x:.4g}"  # noqa: E731
        for j, s in enumerate(self.scales):
            cells = [fmt(self.measure[i, j]) for i in range(len(self.records))]
            rows.append(f"| {s:g} | " + " | ".join(cells) + f" | {fmt(self.median[j])} | {fmt(self.p16[j])} | "
                        f"{fmt(self.p84[j])} |")
        return "\n".join(rows) + "\n"

    def plot(self, path=None, *, ax=None, units: str = ""):
        """IDA curves: the scale factor against the measure, one curve per record, the median and the
        16/84 % fractiles; a collapse is an x at the top of its record's curve. Saves to ``path`` if given."""
        import matplotlib

        if ax is None and path is not None:
            matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig = None
        if ax is None:
            fig, ax = plt.subplots(figsize=(7, 5))
        finite = self.measure[np.isfinite(self.measure)]
        top = 1.15 * finite.max() if finite.size else 1.0
        for i, name in enumerate(self.records):
            ok = ~self.collapsed[i]
            line, = ax.plot(self.measure[i, ok], self.scales[ok], "-o", ms=3, lw=1, alpha=0.8, label=name)
            if self.collapsed[i].any():
                j = int(np.argmax(self.collapsed[i]))  # the first scale that collapsed
                ax.plot([top], [self.scales[j]], "x", color=line.get_color(), ms=8, mew=2)
        for values, style, label in ((self.median, "k-", "median"), (self.p16, "k--", "16 % / 84 %"),
                                     (self.p84, "k--", None)):
            ok = np.isfinite(values)
            ax.plot(values[ok], self.scales[ok], style, lw=2, label=label)
        unit = f" [{units}]" if units else ""
        ax.set_xlabel(f"{self.measure_name}{unit}  (x at right: collapse)")
        ax.set_ylabel("scale factor of the record [-]" if self.factors is None else
                      f"{self.im_name} [{self.im_unit or 'record units'}]")
        ax.set_title(f"IDA, {self.scheme}")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7, loc="lower right")
        if fig is not None and path is not None:
            fig.tight_layout()
            fig.savefig(path, dpi=120)
            plt.close(fig)
        return ax


def _measure(summary, measure: str) -> float:
    if measure == "peak_drift":
        values = [np.max(v) for v in summary.peak_measures.values()]
        if not values:
            raise _checks.value_error("measure", "peak_drift needs named effects (storeys) with a measure")
        return float(max(values))
    if measure == "peak_u":
        return float(np.max(summary.peak_u))
    if measure in summary.peak_measures:
        return float(np.max(summary.peak_measures[measure]))
    raise _checks.value_error("measure", f"expected 'peak_drift', 'peak_u' or the name of an effect "
                                         f"({', '.join(summary.peak_measures) or 'none named'}), got {measure!r}")


def _check_measure(model, measure) -> None:
    """The measure, before any run (a run that collapses has none to look it up in): "peak_drift" (which
    needs a named effect with a measure), "peak_u" or the name of an effect with a measure."""
    if not isinstance(model, Model):
        raise _checks.type_error("model", f"expected a Model, got {type(model).__name__}")
    if not isinstance(measure, str):
        raise _checks.type_error("measure", f"expected 'peak_drift', 'peak_u' or an effect's name, got {measure!r}")
    named = [e.name for e in model.effects or [] if e.name and not e.is_load]
    named += [a.name for a in model.effect_arrays if a.name and not a.is_load]
    if measure == "peak_u" or measure in named:
        return
    if measure == "peak_drift":
        if not named:
            raise _checks.value_error("measure", "peak_drift needs named effects (storeys) with a measure")
        return
    raise _checks.value_error("measure", f"expected 'peak_drift', 'peak_u' or the name of an effect "
                                         f"({', '.join(dict.fromkeys(named)) or 'none named'})"
                                         f"{_checks.suggestion(measure, ['peak_drift', 'peak_u', *named])}, "
                                         f"got {measure!r}")


def intensity(record: GroundMotion, im="sa", *, period: float | None = None, damping: float = 0.05) -> float:
    """The intensity measure of ``record``: "sa" (the exact pseudo-spectral acceleration Sa(T1, damping)
    at ``period``, nvib._core.elastic_spectrum), "pga" (the peak |a_g|), or a callable f(record) -> float."""
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
    if im != "sa":
        raise _checks.value_error("im", f"expected 'sa', 'pga' or a callable f(record) -> float, got {im!r}"
                                        f"{_checks.suggestion(str(im), ['sa', 'pga'])}")
    if period is None:
        raise _checks.value_error("period", "im='sa' needs the period T1 of Sa(T1) [s]")
    return float(record.psa([period], damping)[0])


def _im_label(im, period, damping) -> str:
    if callable(im):
        return getattr(im, "__name__", "intensity")
    return "PGA" if im == "pga" else f"Sa(T1 = {period:g} s, {100 * damping:g} %)"


def ida(model, records, scales, *, scheme=None, dt: float, t_end: float | None = None, measure: str = "peak_drift",
        im=None, period: float | None = None, damping: float = 0.05, threads: int | None = None,
        progress: bool = True) -> IDA:
    """Run ``model`` under every record of ``records`` (GroundMotions) at every level of ``scales``
    and reduce each run to ``measure``: "peak_drift" (the largest peak of the named effects'
    measures: storey drifts), "peak_u" (the largest peak |u|) or the name of one effect.

    Without ``im`` the levels are scale factors of the records. With ``im`` they are values of an
    intensity measure, and each record is scaled to each of them (Vamvatsikos & Cornell 2002): "sa",
    the exact pseudo-spectral acceleration Sa(``period``, ``damping``) of the record (``period``: the
    structure's T1 [s]), "pga", or a callable f(record) -> float. ``t_end``: default the end of the
    longest record (a shorter one is followed by free vibration). A diverging run is a collapse
    (infinite measure); ``IDA.messages`` keeps why."""
    import nvib

    records = list(records)
    for k, r in enumerate(records):
        if not isinstance(r, GroundMotion):
            raise _checks.type_error(f"records[{k}]", f"expected a GroundMotion, got {type(r).__name__}")
    scales = np.sort(_checks.real_array("scales", scales))
    if scales.ndim != 1 or scales.size == 0:
        raise _checks.value_error("scales", "expected a list of scale factors")
    _check_measure(model, measure)
    scheme = nvib.CEMDTS() if scheme is None else scheme
    t_end = max(float(r.t[-1]) for r in records) if t_end is None else _checks.real("t_end", t_end, positive=True)
    damping = _checks.real("damping", damping)
    period = None if period is None else _checks.real("period", period, positive=True)
    factors = None
    if im is not None:  # each record scaled to each level of the intensity measure
        own = np.array([intensity(r, im, period=period, damping=damping) for r in records])
        factors = scales[None, :] / own[:, None]
        motions = [r.scaled(float(f)) for r, row in zip(records, factors) for f in row]
        batch = solve_many(model, scheme, dt=dt, t_end=t_end, ground_motions=motions, keep="peaks",
                           threads=threads, progress=progress)
    else:
        batch = solve_many(model, scheme, dt=dt, t_end=t_end, ground_motions=records, scales=list(scales),
                           keep="peaks", threads=threads, progress=progress)
    values = np.full((len(records), scales.size), np.inf)
    collapsed = np.zeros_like(values, dtype=bool)
    messages = {}
    for k, run in enumerate(batch):
        i, j = divmod(k, scales.size)
        if isinstance(run, RunError):
            raise run.error
        if run.success:
            values[i, j] = _measure(run, measure)
        else:
            collapsed[i, j] = True
            messages[(i, j)] = run.message
    names = [r.name or f"record {k}" for k, r in enumerate(records)]
    if factors is None:
        return IDA(names, scales, measure, values, collapsed, messages, scheme_label(scheme))
    units = {r.units for r in records}
    unit = units.pop() if len(units) == 1 else ""
    return IDA(names, scales, measure, values, collapsed, messages, scheme_label(scheme),
               _im_label(im, period, damping), unit, factors)
