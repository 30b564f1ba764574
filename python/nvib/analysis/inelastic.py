"""Inelastic response spectra of a ground-motion record: constant strength and constant ductility.

For each period T the SDOF of unit mass m = 1

    u'' + 2 zeta w u' + f_s(u) = -a_g(t),      w = 2 pi / T,

with viscous damping on the initial stiffness k = w^2 and f_s a hysteretic law (default bilinear,
elastic-perfectly plastic: b = 0) whose stiffness is k and whose yield force is the strength f_y being
tried. The quantities are those of Chopra, Dynamics of Structures (4th ed., Pearson 2012), sections
7.2 to 7.5:

- u_o, f_o = k u_o: the peak deformation and force of the elastic system (its exact Sd, from the
  closed-form kernel: GroundMotion.exact_response, as ``nvib.spectrum``);
- f_y / f_o = fbar_y, the normalized yield strength, and R_y = f_o / f_y = 1 / fbar_y, the
  yield-strength reduction factor (section 7.2);
- u_y = f_y / k, the yield deformation; u_m = max |u(t)|, the peak deformation; mu = u_m / u_y, the
  ductility demand (section 7.2);
- A_y = w^2 u_y = f_y / m, the pseudo-acceleration of yield, and C_y = f_y / (m g) = A_y / g, the
  yield-strength ratio (strength coefficient; section 7.5).

Constant strength (sections 7.3, 7.4): for given R_y (f_y = f_o / R_y) or C_y (f_y = C_y m g), the ductility
demand mu of each period. Constant ductility (section 7.5): for a target mu, the strength giving it.
As in Chopra's procedure, mu is computed for a set of fbar_y values from 1 down (the scan), the first
interval where mu(fbar_y) reaches the target brackets it, and the strength is refined there (regula
falsi, Illinois variant, on log mu against log fbar_y, falling back to bisection) until fbar_y and mu
both meet a tolerance of SEARCH_TOLERANCE times the accuracy. mu(fbar_y) need not be monotonic;
scanning down from the elastic strength finds the largest fbar_y that gives the target, the one
Chopra takes when several do (crossings closer together than the scan's spacing are not told apart:
give a denser ``fy_ratios`` to resolve them). fbar_y = 1 is the elastic system, mu = 1 there by
definition, so mu = 1 gives fbar_y = 1 exactly.

Runs: every SDOF is integrated through ``solve_many`` with keep="peaks" (the peak |u| tracked at every
step), by default with Newmark's average acceleration and full Newton iterations. The SDOFs that share
a step are run together as the independent DOFs of one model (a diagonal mass, the law and the
damper as effect arrays, every DOF under the ground acceleration): the same equations, each DOF's
Newton update its own (the tangent is diagonal), at a fraction of the cost of one model per SDOF.
solve_many takes one step per call, so the calls of different steps run on the worker threads at once.
Each run lasts the record and FREE_VIBRATION_PERIODS periods of free vibration after it (of the
longest period among the SDOFs run together): the peak inelastic response comes during the strong
motion in practice, and the free vibration catches a peak that the record's end cuts short.

Accuracy: the step is min(record dt, T sqrt(12 accuracy) / (2 pi)) rounded down to a whole number of
steps per record interval (as ``nvib.spectrum`` does: the period error of a second-order scheme is
about (w dt)^2 / 12). Every result is obtained again at half the step: the relative change of mu
(constant strength) or of fbar_y (constant ductility) is that result's ``error``. Results that miss
the accuracy are obtained again at half the step, and checked at a quarter, up to ``max_halvings``
times; the values reported are those at ``dt``, with the error measured for them.
"""

from __future__ import annotations

import dataclasses
import math
import os
import time

import numpy as np

from .. import _checks
from .._batch import RunError, solve_many
from .._core import StopToken
from .._errors import ArgumentError, ArgumentTypeError, NvibError
from .._model import EFFECT_PARAMETERS, Model
from .._records import STANDARD_GRAVITY, GroundMotion
from .._solve import Status
from .spectrum import MIN_ACCURACY, unit_factor, unit_labels

__all__ = ["InelasticSpectrum", "inelastic_spectrum"]

FREE_VIBRATION_PERIODS = 2.0  # free vibration after the record, in periods of the longest SDOF of a run
SCAN_PER_DECADE = 20  # trial strengths fbar_y per decade of the default scan (spacing 12 %)
SCAN_SMALLEST = 1e-3  # the smallest fbar_y of the default scan
SCAN_ROUND = 8  # trial strengths of the scan run at a time for each period
SEARCH_TOLERANCE = 0.1  # the search's tolerance on fbar_y and mu, as a fraction of the accuracy
MAX_SEARCH_ITERATIONS = 100
SDOFS_PER_MODEL = 256  # SDOFs run together in one model; PIM's dense exponential makes it slower above 8
SDOFS_PER_MODEL_BY_SCHEME = {"pim": 8}
MAX_STEPS = 1e8  # steps of one run; a period that needs more is refused


@dataclasses.dataclass
class InelasticSpectrum:
    """An inelastic response spectrum (see the module's text for the definitions, after Chopra,
    Dynamics of Structures, sections 7.2 to 7.5).

    ``kind``: "constant ductility" (``targets`` are ductility demands mu, ``target`` = "mu") or
    "constant strength" (``targets`` are reduction factors R_y, ``target`` = "R_y", or strength
    coefficients C_y, ``target`` = "Cy"). Arrays [target, period]:

    - ``fy_ratio``: fbar_y = f_y / f_o [-]; ``R_y`` = f_o / f_y [-];
    - ``Cy`` = f_y / (m g) [-] (None when the record's unit is not known); ``Ay`` = f_y / m, in the
      record's acceleration unit (g for a record in g);
    - ``uy`` = f_y / k and ``um`` = max |u| (in the record's unit times s^2: g s^2 for a record in g,
      m for m/s^2; ``in_units("m/s^2")`` gives metres);
    - ``mu`` = u_m / u_y [-], the ductility demand of the runs at the reported strength (for constant
      ductility, the target to the search's tolerance; inf where the law collapsed);
    - ``error``: the relative change of mu (constant strength) or fbar_y (constant ductility) when the
      step is halved; 0 for a target mu = 1, whose fbar_y = 1 is exact (its ``mu``, the elastic run's
      u_m / u_o, differs from 1 by the step's error of the elastic peak), and where the law collapsed at
      both steps; NaN where no value was found;
    - ``dt``: the step of the runs reported [s];
    - ``estimate``: the estimate the run reported makes of its own error (``Result.error_estimate`` of its
      SDOF, relative to the peak of u; NaN where the law collapsed or the scheme makes none): the error of
      the whole history, phase included, beside ``error``, the change of the result at half the step. The
      SDOFs run together in one model share its memory (the dissipation rate over which an error is
      carried), so an SDOF's estimate differs from that of its run alone: measured 0.496 to 1.8 times it.

    ``Sd`` and ``PSa`` [period]: the exact elastic spectrum (u_o and f_o / m) the strengths are
    normalised by. ``warnings``: what was not found or not met, by target and period (also NaN in the
    arrays). ``runs``: SDOF runs made; ``steps``: their steps in all; ``wall_time`` [s]: the call's."""

    periods: np.ndarray
    damping: float
    law: dict
    kind: str
    target: str
    targets: np.ndarray
    fy_ratio: np.ndarray
    R_y: np.ndarray
    Cy: np.ndarray | None
    Ay: np.ndarray
    uy: np.ndarray
    um: np.ndarray
    mu: np.ndarray
    error: np.ndarray
    dt: np.ndarray
    Sd: np.ndarray
    PSa: np.ndarray
    accuracy: float
    units: str
    wall_time: float
    record: str = ""
    scheme: str = ""
    warnings: list = dataclasses.field(default_factory=list)
    runs: int = 0
    steps: int = 0
    estimate: np.ndarray | None = None

    def label(self, k: int) -> str:
        """The legend of target k: "μ = 2", "R_y = 4" or "C_y = 0.2"."""
        return f"{_SYMBOLS[self.target]} = {self.targets[k]:g}"

    def in_units(self, units: str) -> InelasticSpectrum:
        """The same spectrum with A_y, PSa in ``units`` ("g" or "m/s^2"; u_y, u_m, Sd follow: g s^2 or m).
        Refused, naming ``units``, when the record's unit is not known."""
        f = unit_factor(self.units, units)
        return dataclasses.replace(self, Ay=self.Ay * f, uy=self.uy * f, um=self.um * f, Sd=self.Sd * f,
                                   PSa=self.PSa * f, units=units)

    def reduction_factors(self) -> dict:
        """R_y(mu, T) of a constant-ductility spectrum: {mu: R_y at each period}, the R_y-mu-T relation of
        this record (from which design relations such as Chopra's, chapter 7, are drawn)."""
        if self.kind != "constant ductility":
            raise _checks.value_error("kind", "R_y(mu, T) comes from a constant-ductility spectrum (ductility=)")
        return {float(m): self.R_y[k].copy() for k, m in enumerate(self.targets)}

    def columns(self) -> list:
        """The table's columns: [(header with its unit, values [target, period])], displacements in m when
        the record's unit is known (C_y left out when it is not)."""
        si = self.in_units("m/s^2") if self.units in ("g", "m/s^2") else self
        acc = unit_labels(self.units)["PSa"]
        disp = unit_labels(si.units)["Sd"]
        cols = [("f_y/f_o [-]", self.fy_ratio), ("R_y [-]", self.R_y), ("C_y [-]", self.Cy),
                (f"A_y [{acc}]", self.Ay), (f"u_y [{disp}]", si.uy), (f"u_m [{disp}]", si.um),
                ("μ = u_m/u_y [-]", self.mu), ("error", self.error), ("dt [s]", self.dt),
                ("estimate", self.estimate)]
        return [(h, v) for h, v in cols if v is not None]

    def markdown(self) -> str:
        """The table: one row per target and period, each column with its unit."""
        cols = self.columns()
        head = f"| target {_SYMBOLS[self.target]} | T [s] | " + " | ".join(h for h, _ in cols) + " |"
        rows = [head, "|" + "---:|" * (len(cols) + 2)]
        for k in range(self.targets.size):
            for j, T in enumerate(self.periods):
                cells = [_cell(v[k, j], h) for h, v in cols]
                rows.append(f"| {self.targets[k]:g} | {T:.4g} | " + " | ".join(cells) + " |")
        return "\n".join(rows) + "\n"

    def to_csv(self, path) -> None:
        """Write the table to ``path``: one row per target and period, each column's unit in its header,
        the elastic Sd and PSa of the period beside them, numbers to their shortest round-trip decimals."""
        cols = self.columns()
        si = self.in_units("m/s^2") if self.units in ("g", "m/s^2") else self
        disp = unit_labels(si.units)["Sd"]
        acc = unit_labels(self.units)["PSa"]
        head = ([f"target {_SYMBOLS[self.target]} [-]", "period [s]"] + [h for h, _ in cols]
                + [f"elastic Sd [{disp}]", f"elastic PSa [{acc}]"])
        with open(path, "w", encoding="utf-8") as fh:
            fh.write(",".join(head) + "\n")
            for k in range(self.targets.size):
                for j in range(self.periods.size):
                    values = [self.targets[k], self.periods[j]] + [v[k, j] for _, v in cols] + [si.Sd[j], self.PSa[j]]
                    fh.write(",".join(repr(float(x)) for x in values) + "\n")

    def plot(self, path=None, *, ax=None, quantity: str | None = None):
        """One curve per target against the period (log axis), labelled "μ = 2" (or "R_y = 4"), with the
        elastic system (μ = 1, exact) for reference, dashed (the curve of a target μ = 1 is that system).
        ``quantity``: "Cy" (the default of a constant-ductility spectrum of a record whose unit is known),
        "Ay" (its default otherwise), "R_y", "fy_ratio", "mu" (the default of a constant-strength
        spectrum), "um" or "uy". Saves to ``path`` (PNG, SVG, PDF) if given; returns the axes."""
        if quantity is None:
            quantity = "mu" if self.kind == "constant strength" else ("Cy" if self.Cy is not None else "Ay")
        if quantity not in _PLOTTED:
            raise _checks.value_error("quantity", f"expected one of {', '.join(_PLOTTED)}, got {quantity!r}")
        if quantity == "Cy" and self.Cy is None:
            raise _checks.value_error("quantity", "C_y needs the record's unit (g or m/s^2); plot 'Ay'")
        if quantity == "R_y" and self.kind != "constant ductility":
            raise _checks.value_error("quantity", "R_y against T per μ comes from a constant-ductility spectrum")
        from matplotlib.ticker import FuncFormatter

        fig = None
        if ax is None:
            from matplotlib.backends.backend_agg import FigureCanvasAgg
            from matplotlib.figure import Figure

            fig = Figure(figsize=(7.0, 4.8), layout="constrained")
            FigureCanvasAgg(fig)
            ax = fig.add_subplot()
        shown = self.in_units("m/s^2") if quantity in ("um", "uy") and self.units in ("g", "m/s^2") else self
        values = getattr(shown, quantity)
        elastic = {"Cy": None if self.Cy is None else self.PSa / _gravity(self.units), "Ay": self.PSa,
                   "R_y": np.ones(self.periods.size), "fy_ratio": np.ones(self.periods.size),
                   "mu": np.ones(self.periods.size), "um": shown.Sd, "uy": shown.Sd}[quantity]
        elastic_target = self.target == "mu" and 1.0 in self.targets  # fbar_y = 1: the elastic curve itself
        if not elastic_target:
            reference = "elastic, exact (μ = 1)" if quantity != "mu" else "elastic limit (μ = 1)"
            ax.plot(self.periods, elastic, "k--", lw=1.2, label=reference)
        for k in range(self.targets.size):
            label = f"{_TEX[self.target]} = {self.targets[k]:g}"
            elastic_curve = self.target == "mu" and self.targets[k] == 1.0
            ax.plot(self.periods, values[k], "k--" if elastic_curve else "-o", ms=2.5, lw=1.2 if elastic_curve else 1.4,
                    label=label + " (elastic, exact)" if elastic_curve else label)
        plain = FuncFormatter(lambda x, _: f"{x:g}")  # 0.2, 1, 5 rather than 2 x 10^-1
        ax.set_xscale("log")
        axes = [ax.xaxis]
        if quantity in ("mu", "um", "uy"):
            ax.set_yscale("log")
            axes.append(ax.yaxis)
        else:
            ax.set_ylim(bottom=0.0)
        for axis in axes:
            axis.set_major_formatter(plain)
            axis.set_minor_formatter(FuncFormatter(lambda x, _: f"{x:g}" if f"{x:.0e}"[0] in "25" else ""))
        unit = {"Ay": unit_labels(self.units)["PSa"], "um": unit_labels(shown.units)["Sd"],
                "uy": unit_labels(shown.units)["Sd"]}.get(quantity, "-")
        ax.set_xlabel("period T [s]")
        ax.set_ylabel(f"{_PLOTTED[quantity]} [{unit}]")
        worst = np.nanmax(self.error) if np.any(np.isfinite(self.error)) else math.nan
        ax.set_title(f"{self.record}: {self.kind}, {_law_label(self.law)}, ζ = {self.damping:g}\n"
                     f"{self.scheme}, largest error {worst:.1e} (asked {self.accuracy:g})", fontsize=9)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
        if fig is not None and path is not None:
            fig.savefig(path, dpi=120)
        return ax


_SYMBOLS = {"mu": "μ", "R_y": "R_y", "Cy": "C_y"}
_TEX = {"mu": "μ", "R_y": "$R_y$", "Cy": "$C_y$"}
_PLOTTED = {"Cy": "yield-strength ratio $C_y = f_y / (m g)$", "Ay": "pseudo-acceleration $A_y = f_y / m$",
            "R_y": "yield-strength reduction factor $R_y = f_o / f_y$",
            "fy_ratio": "normalized yield strength $f_y / f_o$", "mu": "ductility demand $μ = u_m / u_y$",
            "um": "peak deformation $u_m$", "uy": "yield deformation $u_y$"}


def _cell(x: float, header: str) -> str:
    if np.isnan(x):
        return "n/a"
    if header in ("error", "estimate"):
        return f"{x:.1e}"
    return f"{x:.4g}"


def _gravity(units: str) -> float:
    """g in the record's acceleration unit."""
    return {"g": 1.0, "m/s^2": STANDARD_GRAVITY}[units]


def _law_label(law: dict) -> str:
    extra = ", ".join(f"{k} = {v:g}" if isinstance(v, (int, float)) else f"{k} = {v}"
                      for k, v in law.items() if k != "type")
    return f"{law['type']}" + (f" ({extra})" if extra else "")


# ---- arguments -------------------------------------------------------------------------------------

_SET_BY_THE_SPECTRUM = {"k": "the stiffness follows from the period (k = m w^2)",
                        "fy": "the yield force is the strength being tried",
                        "dy": "the yield deformation follows from fy and k",
                        "fy_neg": "the negative side's yield force follows fy (a symmetric law)"}


def _hysteretic_laws() -> list[str]:
    return [kind for kind, (req, opt) in EFFECT_PARAMETERS.items() if {"k", "fy"} <= set(req) | set(opt)]


def _check_law(law) -> dict:
    """The law as a dict of its parameters but k and fy (set per run), checked by the core once."""
    if law is None:
        return {"type": "bilinear", "b": 0.0}
    laws = ", ".join(_hysteretic_laws())
    if not isinstance(law, dict) or "type" not in law:
        raise _checks.type_error("law", "expected a hysteretic law as a dict such as {'type': 'bilinear', 'b': 0.05} "
                                        f"(its k and fy are set by the spectrum; laws with both: {laws})")
    kind = law["type"]
    if kind not in EFFECT_PARAMETERS or kind not in _hysteretic_laws():
        what = "an unknown law" if kind not in EFFECT_PARAMETERS else "a law without a stiffness k and a yield force fy"
        raise _checks.value_error("law", f"{kind!r} is {what}; expected one of {laws}")
    required, optional = EFFECT_PARAMETERS[kind]
    for key in law:
        if key in _SET_BY_THE_SPECTRUM:
            raise _checks.value_error(f"law.{key}", f"set by the spectrum ({_SET_BY_THE_SPECTRUM[key]}); leave it out")
        if key != "type" and key not in required and key not in optional:
            allowed = [k for k in required + tuple(optional) if k not in _SET_BY_THE_SPECTRUM]
            raise _checks.value_error(f"law.{key}", f"unknown parameter of {kind}{_checks.suggestion(key, allowed)} "
                                                    f"(expected {', '.join(allowed)})")
    missing = [k for k in required if k not in law and k not in _SET_BY_THE_SPECTRUM]
    if missing:
        raise _checks.value_error(f"law.{missing[0]}", f"missing parameter of {kind}")
    try:  # the core checks the values (b in [0, 1), ...): an effect of unit stiffness and strength
        Model([1.0], effects=[{**law, "measure": {0: 1.0}, "k": 1.0, "fy": 1.0}])
    except (ArgumentError, ArgumentTypeError) as exc:
        name = getattr(exc, "argument", "") or ""
        where = "law." + name.split(".", 1)[1] if name.startswith("effects[0].") else "law"
        raise (_checks.value_error if isinstance(exc, ArgumentError) else _checks.type_error)(
            where, getattr(exc, "reason", str(exc))) from None
    return dict(law)


def _check_targets(name: str, values, *, at_least: float | None) -> np.ndarray:
    x = _checks.real_array(name, values)
    if x.ndim > 1 or x.size == 0:
        raise _checks.value_error(name, "expected one value or a list of them")
    x = np.atleast_1d(x)
    if not np.all(np.isfinite(x)):
        raise _checks.value_error(name, f"expected finite values, got {x.tolist()}")
    if at_least is not None and np.any(x < at_least):
        raise _checks.value_error(name, f"a ductility demand mu = u_m / u_y is >= 1 (mu = 1: the elastic strength), "
                                        f"got {x[x < at_least][0]:g}")
    if at_least is None and np.any(x <= 0):
        raise _checks.value_error(name, f"expected values > 0, got {x[x <= 0][0]:g}")
    return x


def _check_fy_ratios(fy_ratios) -> np.ndarray:
    if fy_ratios is None:
        count = int(round(SCAN_PER_DECADE * math.log10(1.0 / SCAN_SMALLEST)))
        return np.geomspace(1.0, SCAN_SMALLEST, count + 1)
    x = np.atleast_1d(_checks.real_array("fy_ratios", fy_ratios))
    if x.ndim != 1 or x.size == 0 or not np.all((x > 0) & (x <= 1)):
        raise _checks.value_error("fy_ratios", "expected normalized yield strengths f_y / f_o in (0, 1]")
    return np.unique(np.concatenate([x, [1.0]]))[::-1]  # from the elastic strength down


# ---- the runs ---------------------------------------------------------------------------------------

class _Runs:
    """Peak |u| of SDOFs (period index, steps per record interval, yield force), made in batches through
    solve_many and kept, so that a strength asked for again (at the other step of a halving, by another
    target's search) is not run again."""

    def __init__(self, record, periods, law, damping, scheme, threads, rdt):
        self.record, self.periods, self.law, self.damping = record, periods, law, damping
        self.scheme, self.threads, self.rdt = scheme, threads, rdt
        self.record_end = float(record.t[-1])
        self.k = (2.0 * np.pi / periods) ** 2  # the initial stiffness, m = 1
        self.collapsible = "failed" in _laws()[law["type"]]["state"]  # a law that can lose its strength
        self.per_model = 1 if self.collapsible else SDOFS_PER_MODEL_BY_SCHEME.get(scheme.key, SDOFS_PER_MODEL)
        self.workers = threads if threads is not None else max(1, os.cpu_count() or 1)
        self.peak: dict = {}  # (p, substeps, fy) -> peak |u| (inf: the law collapsed)
        self.estimate: dict = {}  # (p, substeps, fy) -> the run's estimated error (NaN: none)
        self.runs = 0
        self.steps = 0

    def t_end(self, T: float) -> float:
        return self.record_end + FREE_VIBRATION_PERIODS * T

    def __call__(self, jobs: list) -> list:
        """The peak |u| of each job (p, substeps, fy), running those not run yet: one solve_many call per step,
        the calls of different steps on ``workers`` threads at once (solve_many takes one step per call)."""
        todo = [j for j in dict.fromkeys(jobs) if j not in self.peak]
        groups = [(n, sorted((j for j in todo if j[1] == n), key=lambda j: (self.periods[j[0]], j[2])))
                  for n in sorted({j[1] for j in todo})]
        if self.workers == 1 or len(groups) == 1:
            done = [self._run(n, group, self.threads) for n, group in groups]
        else:
            done = self._concurrently(sorted(groups, key=lambda g: -g[0] * len(g[1])))  # the longest first
        for runs, steps in done:
            self.runs += runs
            self.steps += steps
        return [self.peak[j] for j in jobs]

    def _concurrently(self, groups: list) -> list:
        """The groups of SDOFs of different steps, each through solve_many on one thread, ``workers`` at once.
        Ctrl-C (KeyboardInterrupt in this thread) stops the runs under way at their next poll, as solve_many's
        own threads are stopped, and the groups not started are not run."""
        import concurrent.futures as cf

        stop = StopToken()

        def group(n, jobs):
            with stop:
                return self._run(n, jobs, 1)

        with cf.ThreadPoolExecutor(self.workers) as pool:
            futures = [pool.submit(group, n, jobs) for n, jobs in groups]
            try:
                return [f.result() for f in futures]
            except BaseException:
                stop.set()
                for f in futures:
                    f.cancel()
                raise

    def _model(self, T: np.ndarray, fy: np.ndarray) -> Model:
        w = 2.0 * np.pi / T
        i = np.arange(T.size)
        effects = [{**self.law, "i": i, "k": w * w, "fy": fy},
                   {"type": "ground_acceleration", "signal": self.record}]  # every DOF moves with the ground
        if self.damping > 0.0:
            effects.append({"type": "damper", "i": i, "c": 2.0 * self.damping * w})
        return Model(np.ones(T.size), effects=effects)

    def _run(self, n: int, group: list, threads, per_model: int | None = None) -> tuple:
        """Run ``group`` (jobs of one step, rdt / n) through one solve_many call on ``threads`` threads, in models
        of at most ``per_model`` SDOFs (and as many models as threads); keep their peaks. Returns (SDOF runs,
        SDOF steps)."""
        per_model = self.per_model if per_model is None else per_model
        dt = self.rdt / n
        T = np.array([self.periods[j[0]] for j in group])
        fy = np.array([j[2] for j in group])
        count = max(math.ceil(len(group) / per_model), min(threads or self.workers, len(group)))
        parts = np.array_split(np.arange(len(group)), count)
        t_end = self.t_end(float(T.max()))
        batch = solve_many([self._model(T[k], fy[k]) for k in parts], self.scheme, dt=dt, t_end=t_end, keep="peaks",
                           threads=threads, progress=False, max_displacement=math.inf)
        runs, steps = len(group), len(group) * round(t_end / dt)
        for k, res in zip(parts, batch):
            jobs = [group[i] for i in k]
            if res is not None and res.success:
                est = res.error_estimates if res.error_estimates is not None else np.full(len(jobs), np.nan)
                for j, u, e in zip(jobs, res.peak_u, est):
                    self.peak[j] = float(u)
                    self.estimate[j] = float(e)
            elif len(jobs) > 1:  # which SDOF failed: each on its own
                more = self._run(n, jobs, threads, per_model=1)
                runs, steps = runs + more[0], steps + more[1]
            elif res is not None and res.status == Status.collapsed:
                self.peak[jobs[0]] = math.inf
            else:
                T0, f0 = self.periods[jobs[0][0]], jobs[0][2]
                why = res.message if res is not None else "it was not run"
                raise NvibError(f"inelastic_spectrum: the run at T = {T0:g} s with f_y = {f0:.6g} (dt = {dt:g} s) "
                                f"{'could not be made' if isinstance(res, RunError) else 'failed'}: {why}")
        return runs, steps


def _laws() -> dict:
    from .. import _core

    return _core.laws()


# ---- constant strength ------------------------------------------------------------------------------

def _constant_strength(runs: _Runs, fy: np.ndarray, n0: np.ndarray, accuracy: float, max_halvings: int):
    """(u_m, error, substeps, u_y) [target, period] for the strengths fy [target, period]: each checked by
    halving the step, the misses halved again."""
    nt, npd = fy.shape
    n = np.tile(n0, (nt, 1))
    um = np.full((nt, npd), np.nan)
    err = np.full((nt, npd), np.nan)
    uy = fy / runs.k
    todo = [(t, p) for t in range(nt) for p in range(npd)]
    for attempt in range(max_halvings + 1):
        jobs = [(p, n[t, p], fy[t, p]) for t, p in todo] + [(p, 2 * n[t, p], fy[t, p]) for t, p in todo]
        peaks = runs(jobs)
        for c, (t, p) in enumerate(todo):
            coarse, fine = peaks[c], peaks[c + len(todo)]
            um[t, p] = coarse
            err[t, p] = 0.0 if math.isinf(coarse) and math.isinf(fine) else abs(coarse - fine) / max(fine, 1e-300)
        todo = [(t, p) for t, p in todo if not err[t, p] <= accuracy]
        if attempt == max_halvings:
            break
        todo = _halve(todo, runs, n)
        if not todo:
            break
    return um, err, n, uy


def _halve(todo: list, runs: _Runs, n: np.ndarray) -> list:
    """The (target, period) pairs of ``todo`` whose step can be halved again (their check at half of it stays
    within MAX_STEPS), their step counts ``n`` doubled."""
    todo = [(t, p) for t, p in todo if _steps(runs, p, 4 * n[t, p]) <= MAX_STEPS]
    for t, p in todo:
        n[t, p] *= 2
    return todo


def _steps(runs: _Runs, p: int, n: int) -> float:
    return runs.t_end(runs.periods[p]) * n / runs.rdt


# ---- constant ductility -----------------------------------------------------------------------------

class _Search:
    """At one period and one step, the largest fbar_y in (0, 1] whose ductility demand is each target mu
    (Chopra section 7.5): a scan of ``grid`` from 1 down, SCAN_ROUND strengths at a time, until mu reaches
    the target; then regula falsi (Illinois) on x = ln fbar_y, g = ln(mu / target) in the first bracket."""

    def __init__(self, grid: np.ndarray, tol: float):
        self.grid = grid
        self.tol = math.log1p(tol)
        self.scanned: list = []  # (fbar_y, mu) in the grid's order
        self.asked = 0  # grid strengths of the last requests
        self.targets: dict = {}  # target -> its state

    def add(self, target: float) -> None:
        if target in self.targets:
            return
        self.targets[target] = {"state": "scan"}
        self._bracket(target, 0)

    @property
    def done(self) -> bool:
        return all(s["state"] in ("found", "none") for s in self.targets.values())

    def requests(self) -> list:
        """The strengths fbar_y this search needs next."""
        scanning = [t for t, s in self.targets.items() if s["state"] == "scan"]
        self.asked = 0 if not scanning else 1 if scanning == [1.0] else SCAN_ROUND  # mu = 1: the elastic run only
        start = len(self.scanned)
        out = list(self.grid[start:start + self.asked])
        for s in self.targets.values():
            if s["state"] == "refine":
                s["trial"] = self._next(s)
                out.append(math.exp(s["trial"]))
        return out

    def feed(self, mu: dict) -> None:
        """The ductility demands of the strengths requested (fbar_y -> mu)."""
        start = len(self.scanned)
        self.scanned += [(f, mu[f]) for f in self.grid[start:start + self.asked]]
        for target, s in self.targets.items():
            if s["state"] == "scan":
                self._bracket(target, start)
                if s["state"] == "scan" and len(self.scanned) == self.grid.size:
                    s["state"] = "none"
            elif s["state"] == "refine":
                self._update(target, s, mu[math.exp(s["trial"])])

    def _bracket(self, target: float, start: int) -> None:
        """Look for the first scanned strength from ``start`` on whose mu reaches the target."""
        s = self.targets[target]
        if target == 1.0 and self.scanned:  # the elastic strength, by definition; its run gives the mu reached
            s.update(state="found", fy=1.0, mu=self.scanned[0][1])
            return
        for k in range(max(start, 1), len(self.scanned)):
            f, m = self.scanned[k]
            if m >= target:
                fb, mb = self.scanned[k - 1]
                mb = 1.0 if k == 1 else mb  # mu = 1 at fbar_y = 1 by definition (the elastic system)
                s.update(state="refine", xa=math.log(f), ga=_g(m, target), xb=math.log(fb), gb=_g(mb, target),
                         side=None, iterations=0, target=target)
                s["Ga"], s["Gb"] = s["ga"], s["gb"]  # the values regula falsi uses (Illinois halves them)
                self._converged(s)
                return

    def _next(self, s: dict) -> float:
        xa, xb, Ga, Gb = s["xa"], s["xb"], s["Ga"], s["Gb"]
        mid = 0.5 * (xa + xb)
        if not (math.isfinite(Ga) and math.isfinite(Gb)) or s["iterations"] >= MAX_SEARCH_ITERATIONS // 2:
            return mid
        x = xb - Gb * (xb - xa) / (Gb - Ga)
        lo, hi = min(xa, xb), max(xa, xb)
        margin = 1e-3 * (hi - lo)  # keep strictly inside, so that the bracket shrinks
        return min(max(x, lo + margin), hi - margin)

    def _update(self, target: float, s: dict, m: float) -> None:
        x, g = s["trial"], _g(m, target)
        s["iterations"] += 1
        if g >= 0:  # mu reached: the new smaller-strength end
            s["xa"], s["ga"], s["Ga"] = x, g, g
            if s["side"] == "a":
                s["Gb"] *= 0.5
            s["side"] = "a"
        else:
            s["xb"], s["gb"], s["Gb"] = x, g, g
            if s["side"] == "b":
                s["Ga"] *= 0.5
            s["side"] = "b"
        self._converged(s)

    def _converged(self, s: dict) -> None:
        width = abs(s["xb"] - s["xa"])
        best = "a" if abs(s["ga"]) <= abs(s["gb"]) else "b"
        g = s["g" + best]
        if (width <= self.tol and abs(g) <= self.tol) or width <= 1e-13 or s["iterations"] >= MAX_SEARCH_ITERATIONS:
            s.update(state="found", fy=math.exp(s["x" + best]), mu=s["target"] * math.exp(g),
                     unmet=abs(g) > self.tol)

    def result(self, target: float) -> dict:
        return self.targets[target]


def _g(mu: float, target: float) -> float:
    return math.log(mu / target) if mu > 0 else -math.inf


def _constant_ductility(runs: _Runs, targets: np.ndarray, fo: np.ndarray, n0: np.ndarray, accuracy: float,
                        max_halvings: int, grid: np.ndarray):
    """(fbar_y, mu reached, error, substeps, notes) [target, period]: the search at each period's step and
    at half of it, run together; the misses searched again at half and a quarter of the step."""
    nt, npd = targets.size, fo.size
    uo = fo / runs.k
    searches: dict = {}  # (p, substeps) -> _Search
    tol = SEARCH_TOLERANCE * accuracy

    def search(p, n, target):
        s = searches.setdefault((p, n), _Search(grid, tol))
        s.add(target)
        return s

    def run_all():
        while True:
            active = [(key, s) for key, s in searches.items() if not s.done]
            if not active:
                return
            asked = [(key, s, s.requests()) for key, s in active]
            jobs = [(p, n, f * fo[p]) for (p, n), _, fs in asked for f in fs]
            peaks = iter(runs(jobs))
            for (p, n), s, fs in asked:
                s.feed({f: next(peaks) / (f * uo[p]) for f in fs})

    n = np.tile(n0, (nt, 1))
    fbar = np.full((nt, npd), np.nan)
    mu = np.full((nt, npd), np.nan)
    err = np.full((nt, npd), np.nan)
    notes = {}
    todo = [(t, p) for t in range(nt) for p in range(npd)]
    for attempt in range(max_halvings + 1):
        for t, p in todo:
            search(p, n[t, p], float(targets[t]))
            search(p, 2 * n[t, p], float(targets[t]))
        run_all()
        for t, p in todo:
            coarse = searches[(p, n[t, p])].result(float(targets[t]))
            fine = searches[(p, 2 * n[t, p])].result(float(targets[t]))
            notes.pop((t, p), None)
            if coarse["state"] != "found":
                fbar[t, p] = mu[t, p] = err[t, p] = math.nan
                f_min, m_min = searches[(p, n[t, p])].scanned[-1]
                notes[(t, p)] = ("none", f_min, m_min)
                continue
            fbar[t, p], mu[t, p] = coarse["fy"], coarse["mu"]
            if coarse.get("unmet"):
                notes[(t, p)] = ("unmet", coarse["mu"])
            err[t, p] = abs(coarse["fy"] - fine["fy"]) / fine["fy"] if fine["state"] == "found" else math.nan
        # where no scanned strength reaches the target, a finer step is not tried
        todo = [(t, p) for t, p in todo if not err[t, p] <= accuracy and not np.isnan(fbar[t, p])]
        if attempt == max_halvings:
            break
        todo = _halve(todo, runs, n)
        if not todo:
            break
    return fbar, mu, err, n, notes


# ---- the entry point --------------------------------------------------------------------------------

def inelastic_spectrum(record: GroundMotion, periods, *, ductility=None, R=None, Cy=None, damping: float = 0.05,
                       law: dict | None = None, scheme=None, accuracy: float | None = None,
                       max_halvings: int | None = None, threads: int | None = None,
                       fy_ratios=None) -> InelasticSpectrum:
    """The inelastic response spectrum of ``record`` at ``periods`` [s] (Chopra, Dynamics of Structures,
    sections 7.2 to 7.5; see the module's text and ``InelasticSpectrum``).

    Give one of:

    - ``ductility``: target ductility demands mu >= 1 (one or several, e.g. [2, 4, 6]): the constant-
      ductility spectrum, the largest strength f_y <= f_o giving each mu at each period;
    - ``R``: yield-strength reduction factors R_y = f_o / f_y > 0: the constant-strength spectrum (the
      ductility demand at f_y = f_o / R_y);
    - ``Cy``: strength coefficients C_y = f_y / (m g) > 0: constant strength at f_y = C_y m g (needs
      the record's unit: g or m/s^2).

    ``damping``: the viscous damping ratio zeta on the initial stiffness, 0 <= zeta < 1. ``law``: the
    hysteretic law as an effect without its stiffness and strength, which the spectrum sets (k = m w^2,
    fy the strength tried): {"type": "bilinear", "b": 0.05} (default b = 0, elastic-perfectly plastic),
    {"type": "bouc_wen", "alpha": 0.05, "n": 2}, {"type": "imk_peak_oriented", "up": ..., ...} (its
    deformations up, upc, uu are absolute, not relative to u_y; a run where it collapses has mu = inf).
    ``scheme``: any nvib scheme (default Newmark's average acceleration, full Newton). ``accuracy``
    (default 1e-3): the relative change of mu or fbar_y to reach when the step is halved; ``max_halvings``
    (default 4) halvings at most; ``threads`` as in ``solve_many``. ``fy_ratios``: the trial fbar_y of the
    constant-ductility scan (default 20 per decade from 1 down to 1e-3).

    Where no fbar_y of the scan reaches a target, or a result misses the accuracy after ``max_halvings``,
    the spectrum says so in ``warnings`` (and the values are NaN where nothing was found). A run that fails
    (Newton, divergence) raises an NvibError naming its period and strength.
    """
    import nvib  # the schemes

    start = time.perf_counter()
    if not isinstance(record, GroundMotion):
        raise _checks.type_error("record", f"expected a GroundMotion, got {type(record).__name__}")
    periods = _checks.real_array("periods", periods)
    if periods.ndim == 0:
        periods = periods.reshape(1)
    if periods.ndim != 1 or periods.size == 0 or np.any(~(periods > 0)) or not np.all(np.isfinite(periods)):
        raise _checks.value_error("periods", "expected a non-empty list of positive periods [s]")
    given = [name for name, v in (("ductility", ductility), ("R", R), ("Cy", Cy)) if v is not None]
    if len(given) != 1:
        raise _checks.value_error("ductility, R, Cy" if not given else ", ".join(given),
                                  "give one of ductility (constant ductility), R or Cy (constant strength)"
                                  + (f", not {' and '.join(given)}" if given else ""))
    if ductility is not None:
        targets, target, kind = _check_targets("ductility", ductility, at_least=1.0), "mu", "constant ductility"
    elif R is not None:
        targets, target, kind = _check_targets("R", R, at_least=None), "R_y", "constant strength"
    else:
        targets, target, kind = _check_targets("Cy", Cy, at_least=None), "Cy", "constant strength"
        if record.units not in ("g", "m/s^2"):
            raise _checks.value_error("Cy", "f_y = C_y m g needs the record's unit (g or m/s^2), which is not known; "
                                            "give R, or a record with its unit")
    if fy_ratios is not None and ductility is None:
        raise _checks.value_error("fy_ratios", "the scan of trial strengths applies to a constant-ductility spectrum")
    grid = _check_fy_ratios(fy_ratios)
    damping = _checks.real("damping", damping)
    if not 0.0 <= damping < 1.0:
        raise _checks.value_error("damping", f"expected 0 <= damping < 1 (a fraction of critical), got {damping:g}")
    law = _check_law(law)
    if scheme is None:
        scheme = nvib.Newmark()
    elif not isinstance(scheme, tuple(nvib.schemes().values())):
        raise _checks.type_error("scheme", f"expected a scheme such as nvib.Newmark(), got {type(scheme).__name__}")
    accuracy = _checks.real("accuracy", 1e-3 if accuracy is None else accuracy, positive=True)
    if accuracy < MIN_ACCURACY:
        raise _checks.value_error("accuracy", f"must be >= {MIN_ACCURACY:g} (below it the round-off of the steps is "
                                              f"as large as the error asked for), got {accuracy:g}")
    max_halvings = _checks.integer("max_halvings", 4 if max_halvings is None else max_halvings, minimum=0,
                                   maximum=30)
    if threads is not None:
        threads = _checks.integer("threads", threads, minimum=1, maximum=None)

    el = record.exact_response(periods, damping)
    Sd, PSa = np.asarray(el["Sd"], dtype=float), np.asarray(el["PSa"], dtype=float)
    bad = ~(np.isfinite(Sd) & np.isfinite(PSa) & (Sd > 0))
    if np.any(bad):
        T = periods[bad][0]
        raise _checks.value_error("record", f"its elastic response at T = {T:g} s is {Sd[bad][0]:g}: the strengths "
                                            "are fractions of the elastic one, which must be finite and > 0")
    rdt = record.dt if record.dt is not None else float(np.min(np.diff(record.t)))
    with np.errstate(over="ignore", divide="ignore"):
        n0 = np.ceil(rdt / np.minimum(rdt, periods * math.sqrt(12.0 * accuracy) / (2.0 * math.pi)))
    runs = _Runs(record, periods, law, damping, scheme, threads, rdt)
    too_long = [p for p in range(periods.size) if not _steps(runs, p, 2.0 * n0[p]) <= MAX_STEPS]
    if too_long:
        p = too_long[0]
        raise _checks.value_error("periods", f"T = {periods[p]:g} s takes {_steps(runs, p, 2.0 * n0[p]):.3g} steps of "
                                             f"{rdt / (2.0 * n0[p]):.3g} s (its halving check), more than "
                                             f"{MAX_STEPS:.0e}: give longer periods (or a coarser accuracy than "
                                             f"{accuracy:g})")
    n0 = n0.astype(np.int64)
    fo = PSa.copy()  # f_o = k u_o = m PSa, m = 1
    warnings: list = []
    if kind == "constant strength":
        fy = fo / targets[:, None] if target == "R_y" else np.tile(targets[:, None] * _gravity(record.units),
                                                                   (1, periods.size))
        um, err, n, uy = _constant_strength(runs, fy, n0, accuracy, max_halvings)
        mu = um / uy
        fbar = fy / fo
        for k in range(targets.size):
            collapsed = np.flatnonzero(np.isinf(um[k]))
            if collapsed.size:
                warnings.append(f"{_SYMBOLS[target]} = {targets[k]:g}: the law collapsed (lost its strength) at "
                                f"{_periods_text(periods[collapsed])}: μ = inf there")
    else:
        fbar, mu, err, n, notes = _constant_ductility(runs, targets, fo, n0, accuracy, max_halvings, grid)
        for k in range(targets.size):
            none = [p for (t, p), note in sorted(notes.items()) if t == k and note[0] == "none"]
            if none:
                reached = ", ".join(f"{notes[(k, p)][2]:.3g}" for p in none[:5]) + (", ..." if len(none) > 5 else "")
                warnings.append(f"μ = {targets[k]:g}: no f_y/f_o down to {grid[-1]:g} reaches it at "
                                f"{_periods_text(periods[none])} (μ there: {reached}); the values are NaN")
            unmet = [p for (t, p), note in sorted(notes.items()) if t == k and note[0] == "unmet"]
            if unmet:
                warnings.append(f"μ = {targets[k]:g}: the search ended with μ off the target by more than its "
                                f"tolerance at {_periods_text(periods[unmet])} (μ(f_y) jumps there); μ reached is "
                                "reported")
        fy = fbar * fo
        uy = fy / runs.k
    for k in range(targets.size):
        missed = np.flatnonzero(err[k] > accuracy)
        if missed.size:
            warnings.append(f"{_SYMBOLS[target]} = {targets[k]:g}: error above the accuracy {accuracy:g} after "
                            f"{max_halvings} halvings at {_periods_text(periods[missed])} (largest "
                            f"{np.max(err[k][missed]):.2g}); the error reached is reported")
    # the estimate of each run reported: its job is (period, substeps, f_y), as it was run
    estimate = np.array([[runs.estimate.get((p, n[t, p], fy[t, p]), math.nan) for p in range(periods.size)]
                         for t in range(targets.size)])
    g = _gravity(record.units) if record.units in ("g", "m/s^2") else None
    with np.errstate(divide="ignore", invalid="ignore"):
        return InelasticSpectrum(
            periods=periods, damping=damping, law=law, kind=kind, target=target, targets=targets, fy_ratio=fbar,
            R_y=1.0 / fbar, Cy=None if g is None else fy / g, Ay=fy, uy=uy, um=mu * uy, mu=mu, error=err, dt=rdt / n,
            Sd=Sd, PSa=PSa, accuracy=accuracy, units=record.units, wall_time=time.perf_counter() - start,
            record=record.name, scheme=nvib.scheme_label(scheme), warnings=warnings, runs=runs.runs, steps=runs.steps,
            estimate=estimate)


def _periods_text(T: np.ndarray) -> str:
    shown = ", ".join(f"{x:.3g}" for x in T[:6])
    return f"T = {shown}{', ...' if T.size > 6 else ''} s ({T.size} period{'s' if T.size != 1 else ''})"
