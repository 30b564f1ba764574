"""solve() and the step-by-step Stepper: argument checks that name the
argument, then the C++ loop (nvib._core.solve / Stepper.integrate), which
owns the stepping, saving, divergence and energy checks, counters and defaults."""

from __future__ import annotations

import contextlib
import difflib
import inspect
import math
import typing

import numpy as np

from . import _checks, _core
from ._core import Energy, Failure, Result, Stats, Status
from ._errors import error_for
from ._model import Model, unit_list
from ._records import GroundMotion

__all__ = ["ENERGY_WARNING", "Energy", "Failure", "Result", "Stats", "Status", "Stepper", "default_max_displacement",
           "solve"]

Result.__module__ = Energy.__module__ = Failure.__module__ = Stats.__module__ = "nvib"


def _signal_values(signal, t: np.ndarray) -> np.ndarray:
    """A signal of the effects (a GroundMotion or a sine/table dict) at the times t, as the solver sees it."""
    if isinstance(signal, GroundMotion):
        return signal(t)
    if signal.get("kind") == "sine":
        return float(signal["amplitude"]) * np.sin(float(signal["omega"]) * t + float(signal.get("phase", 0.0)))
    if signal.get("kind") == "table":
        return np.interp(t, np.asarray(signal["t"], float), np.asarray(signal["values"], float), left=0.0, right=0.0)
    return GroundMotion.from_spec("signal", signal)(t)


def ground_motions(model: Model) -> list[tuple[str, np.ndarray, object]]:
    """[(name, r over the model's DOFs, signal)] of the model's ground accelerations (single effects, not left
    out): P = -M r a_g(t) with a_g the signal (a GroundMotion or a sine/table/record dict) as the run sees it."""
    effects = model._init[1].get("effects") or []
    out = []
    for e in effects:
        if not isinstance(e, dict) or e.get("type") != "ground_acceleration" or "i" in e:
            continue
        if e.get("name") in model.without or "ground_acceleration" in model.without:
            continue
        r = np.ones(model.n)
        if "measure" in e:
            r = np.zeros(model.n)
            for key, c in e["measure"].items():
                r[model._dof_index("measure", key)] += float(c)
        out.append((str(e.get("name") or ""), r, e.get("signal")))
    return out


def _ground_of(model: Model, dofs) -> list | None:
    """[(r on the saved DOFs, signal)] of the model's ground accelerations (single effects), or None."""
    cols = np.asarray(dofs, dtype=int)
    return [(r[cols], signal) for _, r, signal in ground_motions(model)] or None


ENERGY_WARNING = 0.05
"""A run that records its energy and ends with a relative energy balance error above this (5 %) gets an
entry in ``Result.warnings``: its history is not to be trusted even though it did not diverge."""

ERROR_WARNING = 0.01
"""A run whose estimated error (``Result.error_estimate``) exceeds this (1 % of a DOF's peak) gets an entry
in ``Result.warnings`` naming the DOF and the step that would meet it."""


class _Warn(typing.NamedTuple):
    """The levels at which a run's result warns: energy balance error, estimated error; and the run's
    tol (NaN at a fixed step), which the warning of an inaccurate adaptive run names instead of a step."""
    energy: float
    error: float
    tol: float = math.nan


class ErrorEstimate:
    """The error a run estimates for itself, from its accepted steps (``Result.error_estimate``).

    per_dof : every DOF's estimated max |u_i - u_i,exact| / max |u_i| (NaN where a scheme has no
    estimate). max, dof : the largest and
    the DOF's name. dt, order : the run's step and the scheme's global order, so that ``dt_for(target)``
    = dt (target / max)^(1/order) is the step that would meet target.

    The estimate is the leading phase error of the scheme on each mode, c h^2 tau |da/dt|, with c the
    scheme's error constant (its principal eigenvalue against exp(i w h)) and tau the age of the motion
    (its damping, viscous and hysteretic, forgets); for PreciseIntegration, exact on linear modes, each
    step's interpolation error of the nonlinear remainder propagated by its exponential: see
    ``cpp/include/nvib/solve/error_estimate.hpp``.
    Measured against closed forms and DOP853 in ``benchmarks/results/error_estimate.md``.

    An adaptive run's (``tol`` set) is measured instead: the difference between the run and a companion
    run on double steps, divided by 2^order - 1 (``cpp/include/nvib/solve/adaptive.hpp``; measured in
    ``benchmarks/results/adaptive_tolerance.md``)."""

    def __init__(self, per_dof: np.ndarray, names: list[str], dt: float, order: int, tol: float = math.nan):
        self.per_dof = np.asarray(per_dof, dtype=float)
        self.names = names  # indexable (a model's generated names are made on demand)
        self.dt = float(dt)
        self.order = int(order)
        self.tol = float(tol)
        seen = ~np.isnan(self.per_dof)
        if np.any(seen):
            k = int(np.argmax(np.where(seen, self.per_dof, -np.inf)))
            self.max, self.dof = float(self.per_dof[k]), self.names[k]
        else:
            self.max, self.dof = math.nan, None

    @property
    def available(self) -> bool:
        return not math.isnan(self.max)

    def dt_for(self, target: float) -> float:
        """The step at which the estimate would be ``target`` (its leading term scales as dt^order)."""
        target = _checks.real("target", target, positive=True)
        if not self.available or self.max <= 0.0:
            return math.inf if self.available else math.nan
        return self.dt * (target / self.max) ** (1.0 / self.order)

    def as_dict(self) -> dict:
        return {self.names[k]: float(e) for k, e in enumerate(self.per_dof)}

    def __repr__(self) -> str:
        if not self.available:
            return "ErrorEstimate(not available for this scheme)"
        if not math.isnan(self.tol):
            return f"ErrorEstimate(max {self.max:.3g} at {self.dof}, adaptive, tol {self.tol:g})"
        return f"ErrorEstimate(max {self.max:.3g} at {self.dof}, dt {self.dt:g} s, order {self.order})"


def error_estimate(self) -> ErrorEstimate | None:
    """The run's estimate of its own error relative to each DOF's peak (``ErrorEstimate``), or None for a
    run made with ``error_estimate=False``."""
    per_dof = self._error_estimate
    if per_dof is None:
        return None
    extras = _extras(self)
    names = extras.get("all_dofs")
    if names is None:
        names = [f"dof{k}" for k in range(len(per_dof))]
    return ErrorEstimate(per_dof, names, self.dt, extras.get("order", 2), extras.get("tol", math.nan))


def _error_note(res: Result, limit: float) -> str | None:
    """The warning of a completed run whose estimated error exceeds limit (a failed run says why it failed)."""
    est = error_estimate(res)
    if res.status != Status.success or est is None or not est.available or not est.max > limit:
        return None
    if not math.isnan(est.tol):
        return (f"the estimated error reached {est.max:.2g} of the peak of {est.dof} (above warn_error = {limit:g}) "
                f"in a run with tol = {est.tol:g}: a smaller tol (or max_dt) would meet it")
    return (f"the estimated error reached {est.max:.2g} of the peak of {est.dof} (above warn_error = {limit:g}): "
            f"a step of about {est.dt_for(limit):.3g} s would meet it (the run's is {est.dt:g} s); "
            f"nvib.cost measures the true error against a reference")


def _tol_note(res: Result) -> str | None:
    """The warning of an adaptive run that ended above its tol (its restarts used up)."""
    est = error_estimate(res)
    if res.status != Status.success or est is None or math.isnan(est.tol) or not est.max > est.tol:
        return None
    return (f"the estimated error {est.max:.2g} of the peak of {est.dof} exceeds tol = {est.tol:g} after "
            f"{res.stats.num_restarts} restarts with a tighter control: a smaller max_dt, or another scheme, "
            f"would meet it")


def _extras(self) -> dict:
    return self._extras if isinstance(self._extras, dict) else {}


def _step_note(model: Model, scheme, dt: float) -> str | None:
    """The warning of an explicit run whose dt is above the scheme's (damped) stability limit on the
    model's linear part (``nvib.stability.step_warning``); None for every other run."""
    if getattr(scheme, "is_explicit", False) is not True or not isinstance(getattr(scheme, "key", None), str):
        return None
    from .analysis import stability

    return stability.step_warning(model, scheme, dt)


def _failure_error(res: Result, note: str | None):
    """The exception of a failed run; a divergence says why dt was expected to diverge when it was."""
    exc = error_for(res.failure, res)
    if note and res.status == Status.diverged:
        exc.args = (f"{exc.args[0]}; {note}",) + tuple(exc.args[1:])
    return exc


def _annotate(res: Result, model: Model, warn: _Warn, note: str | None = None) -> Result:
    """What the Python layer knows about a run beside its history: the ground motions under the model
    (relative displacements, absolute accelerations), the units of the saved DOFs, and warnings (the
    model's own, a dt above the stability limit, an energy balance error, an estimated error)."""
    idx = np.asarray(res.dof_indices, dtype=int)
    units = model._units if isinstance(model._units, str) else [model._units[k] for k in idx]
    warnings = list(model.warnings)
    if note:
        warnings.append(note)
    if res.energy is not None and len(res.t) > 1:
        with np.errstate(all="ignore"):
            rel = res.energy.relative_balance_error()
        if np.isfinite(rel) and rel > warn.energy:
            warnings.append(f"the energy balance error reached {rel:.1%} of the energy scale (above "
                            f"{warn.energy:.0%}): this history is inaccurate; try a smaller dt")
    if res.status == Status.collapsed:
        warnings.append(res.failure.message)
    ground = _ground_of(model, idx)
    order = getattr(res.scheme, "order_u", 2)
    res._extras = {"ground": ground, "relative_to_ground": ground is not None, "units": units, "warnings": warnings,
                   "all_dofs": model.dofs, "order": order if isinstance(order, int) else 2, "tol": warn.tol}
    for note in (_error_note(res, warn.error), _tol_note(res)):
        if note:
            warnings.append(note)
    return res


def ground_a(res: Result) -> np.ndarray | None:
    """The ground's acceleration at the saved DOFs and times, (n_saved, n_saved_dofs): what ``absolute_a``
    adds to ``a``. None when the model has no ground motion, and when it is not known: a result read from a
    file written before files held it (``relative_to_ground`` then says whether ``a`` is relative)."""
    extras = _extras(res)
    if extras.get("ground_a") is not None:  # read from a file
        return np.asarray(extras["ground_a"])
    ground = extras.get("ground")
    if ground is None:
        return None
    t = np.asarray(res.t)
    out = np.zeros((len(t), len(res.dofs)))
    for r, signal in ground:
        out += np.outer(_signal_values(signal, t), r)
    return out


def absolute_a(self) -> np.ndarray:
    """Absolute accelerations of the saved DOFs, a + r a_g(t) for each ground acceleration of the model
    (its displacements, velocities and accelerations are relative to the ground); ``a`` itself when the
    model has no ground motion. A result read from a file that holds a relative to the ground but not the
    ground's acceleration (written before files held it) raises ArgumentError naming the file."""
    g = ground_a(self)
    if g is not None:
        return self.a + g
    if self.relative_to_ground:
        file = _extras(self).get("file")
        where = f"the file {file!r}" if file else "this result"
        raise _checks.value_error("absolute_a", f"{where} holds a relative to the ground but not the ground's "
                                                "acceleration (no ground_a: written before nvib saved it), so the "
                                                "absolute accelerations cannot be rebuilt; solve again to have them")
    return self.a


def _energy_repr(self) -> str:
    n = len(self.kinetic)
    if n == 0:
        return "Energy(0 states)"
    with np.errstate(all="ignore"):
        rel = self.relative_balance_error()
    end = ", ".join(f"{k.replace('_', ' ')} {float(v[-1]):.6g}"
                    for k, v in self.as_dict().items() if k != "balance_error")
    return f"Energy({n} state{'s' if n != 1 else ''}; at the end: {end}; relative balance error {rel:.3g})"


Energy.__repr__ = _energy_repr


@contextlib.contextmanager
def _partial_annotated(model: Model, warn: _Warn, note: str | None = None):
    """A run stopped by an exception (Ctrl-C, an error in a Python callback) carries the history saved
    before it as ``exc.result``: annotated like any result (units, ground, warnings)."""
    try:
        yield
    except BaseException as exc:
        partial = getattr(exc, "result", None)
        if isinstance(partial, Result):
            _annotate(partial, model, warn, note)
        raise


def _warning_level(name: str, value) -> float:
    return _checks.real(name, value, positive=True) if value != math.inf else math.inf


def _check_model(model):
    if not isinstance(model, Model):
        raise _checks.type_error("model", f"expected nvib.Model, got {type(model).__name__}")


def _dof_indices(model: Model, dofs) -> list[int]:
    if dofs is None:
        return []
    if isinstance(dofs, (str, int)):
        dofs = [dofs]
    return [model._dof_index("dofs", d) for d in dofs]


def _limit(name: str, value) -> float:
    """A run limit: None for the default (NaN to the core), math.inf for none, else a positive real."""
    if value is None:
        return math.nan
    if isinstance(value, (int, float)) and value == math.inf:
        return math.inf
    return _checks.real(name, value, positive=True)


def _record(model: Model, record) -> list[str]:
    """The names of the effects to record: a name, or a list of names of the model's effects."""
    if record is None:
        return []
    names = [record] if isinstance(record, str) else record
    if not hasattr(names, "__iter__"):
        raise _checks.type_error("record", f"expected an effect's name or a list of names, got {type(record).__name__}")
    names = list(names)
    for k, name in enumerate(names):
        if not isinstance(name, str):
            raise _checks.type_error(f"record[{k}]", f"expected an effect's name, got {name!r}")
    return names


# The options of a run, as solve(), Stepper.integrate() and solve_many() take them by keyword: name ->
# default. The loop's own defaults come from the C++ SolveOptions (RUN_DEFAULTS: None where the loop
# derives the value from the run, such as the divergence bound); the others exist only in Python.
RUN_OPTIONS = {
    "save_every": _core.RUN_DEFAULTS["save_every"],
    "dofs": None,
    "throw": True,
    "max_displacement": _core.RUN_DEFAULTS["max_displacement"],
    "progress": None,
    "energy": _core.RUN_DEFAULTS["energy"],
    "max_energy_error": _core.RUN_DEFAULTS["max_energy_error"],
    "warn_energy_error": ENERGY_WARNING,
    "record": None,
    "collapse_deformation": _core.RUN_DEFAULTS["collapse_deformation"],
    "stop_at_collapse": _core.RUN_DEFAULTS["stop_at_collapse"],
    "error_estimate": _core.RUN_DEFAULTS["error_estimate"],
    "warn_error": ERROR_WARNING,
    "tol": None,
    "max_dt": None,
    "min_dt": None,
}


def check_option_names(options: dict, *, also=()) -> None:
    """Refuse a keyword that is not an option of a run (nor one of ``also``), naming it and the closest."""
    for key in options:
        if key not in RUN_OPTIONS and key not in also:
            close = difflib.get_close_matches(key, [*RUN_OPTIONS, *also], n=1)
            hint = f"; did you mean {close[0]!r}?" if close else f" (the options are {', '.join(RUN_OPTIONS)})"
            raise _checks.type_error(key, f"not an option of a run{hint}")


def check_settings(given: dict) -> tuple[dict, object, bool, _Warn]:
    """The options of a run that do not depend on the model, from the caller's keywords: (the C++ loop's
    options among them, progress, throw, warn_energy_error). Types are converted and Python's own options
    checked (the loop checks the rest); solve_many checks a batch's options with it once, before any run."""
    check_option_names(given)
    o = {**RUN_OPTIONS, **given}
    progress = o["progress"]
    if progress is not None and not callable(progress):
        raise _checks.type_error("progress", "expected a callable progress(step, n_steps)")
    if not isinstance(o["energy"], bool):
        raise _checks.type_error("energy", f"expected True or False, got {type(o['energy']).__name__}")
    core = dict(save_every=_checks.integer("save_every", o["save_every"], minimum=1),
                max_displacement=_limit("max_displacement", o["max_displacement"]), energy=o["energy"],
                max_energy_error=_limit("max_energy_error", o["max_energy_error"]),
                collapse_deformation=math.nan if o["collapse_deformation"] is None else
                _checks.real("collapse_deformation", o["collapse_deformation"], positive=True),
                stop_at_collapse=_checks.boolean("stop_at_collapse", o["stop_at_collapse"]),
                error_estimate=_checks.boolean("error_estimate", o["error_estimate"]),
                **{k: math.nan if o[k] is None else _checks.real(k, o[k], positive=True)
                   for k in ("tol", "max_dt", "min_dt")})
    warn = _Warn(_warning_level("warn_energy_error", o["warn_energy_error"]),
                 _warning_level("warn_error", o["warn_error"]), core["tol"])
    return core, progress, _checks.boolean("throw", o["throw"]), warn


def _run_options(model: Model, given: dict) -> tuple[dict, object, bool, _Warn]:
    """check_settings, and the options that name the model's DOFs and effects."""
    core, progress, throw, warn = check_settings(given)
    core.update(dofs=_dof_indices(model, given.get("dofs", RUN_OPTIONS["dofs"])),
                record=_record(model, given.get("record", RUN_OPTIONS["record"])))
    return core, progress, throw, warn


def _with_options(*fixed: inspect.Parameter):
    """The signature a function taking ``**options`` shows (help, inspect): its own parameters, then
    every option of a run with its default."""
    options = [inspect.Parameter(k, inspect.Parameter.KEYWORD_ONLY, default=v) for k, v in RUN_OPTIONS.items()]

    def decorate(f):
        f.__signature__ = inspect.Signature([*fixed, *options], return_annotation="Result")
        return f
    return decorate


_P = inspect.Parameter


class Stepper:
    """Step-by-step integration: ``st = Stepper(model, scheme, dt); st.step(); st.u``.
    One thread at a time: a Stepper used from two threads at once raises RuntimeError."""

    def __init__(self, model: Model, scheme, dt: float, *, t0: float = 0.0, u0=None, v0=None):
        _check_model(model)
        self.model = model
        self.scheme = scheme
        self.dt = _checks.number("dt", dt)  # dt and t0 are checked by the C++ stepper
        t0 = _checks.number("t0", t0)
        u0 = model.u0 if u0 is None else _checks.vector("u0", u0, model.n)
        v0 = model.v0 if v0 is None else _checks.vector("v0", v0, model.n)
        self._st = _core.Stepper(model._core, scheme, self.dt)
        self._st.initialize(t0, u0, v0)

    def __repr__(self) -> str:
        model = f"{self.model.name!r}, " if self.model.name else ""
        return (f"Stepper({self.scheme!r}, dt={self.dt:g} s, t={self.t:g} s, step {self.step_index}; "
                f"model {model}{self.model.n} DOF{'s' if self.model.n != 1 else ''})")

    t = property(lambda self: self._st.t, doc="current time")
    u = property(lambda self: self._st.u, doc="current displacement")
    v = property(lambda self: self._st.v, doc="current velocity")
    a = property(lambda self: self._st.a, doc="current acceleration")
    stats = property(lambda self: self._st.stats, doc="counters since construction")
    step_index = property(lambda self: self._st.step_index)
    last_residuals = property(lambda self: list(self._st.last_residuals),
                              doc="Newton residual norms of the last step (implicit schemes); for the "
                                  "incremental and one_iteration modes the one before the step and the one it leaves")
    accepted_residual = property(lambda self: self._st.accepted_residual,
                                 doc="equilibrium residual of the last accepted step relative to its force scale "
                                     "(implicit schemes; None where it is not evaluated)")

    def state(self) -> np.ndarray:
        """The carried state as one vector: [u; v; a] followed by the scheme's history
        (a_{n-1} for CEMDTS and Zhai; the order + 1 interpolated remainders, newest first,
        for PreciseIntegration; with CentralDifference(velocity="half_step") v is v_{n-1/2})."""
        return self._st.state()

    def set_state(self, x, t: float | None = None) -> None:
        """Continue from the carried state x (as ``state()`` returns it) at time t (default: now)."""
        t = self.t if t is None else _checks.real("t", t)
        x = _checks.real_array("x", x)
        if x.ndim != 1:
            raise _checks.value_error("x", f"expected a 1-D state vector, got shape {x.shape}")
        self._st.set_state(t, x)

    def step(self, n: int = 1) -> None:
        """Advance n steps; raises DivergenceError / ConvergenceError on failure."""
        n = _checks.integer("n", n, minimum=1)
        for _ in range(n):
            status, failure = self._st.step()
            if failure is not None:
                raise error_for(failure)

    @_with_options(_P("self", _P.POSITIONAL_OR_KEYWORD), _P("t_end", _P.POSITIONAL_OR_KEYWORD))
    def integrate(self, t_end: float, **options) -> Result:
        """Continue to t_end and return the saved history of this stretch (options as in ``solve``)."""
        t_end = _checks.number("t_end", t_end)  # checked by the C++ loop
        opts, progress, throw, warn = _run_options(self.model, options)
        if not hasattr(self, "_note"):
            self._note = _step_note(self.model, self.scheme, self.dt)
        with _partial_annotated(self.model, warn, self._note):
            res = _annotate(self._st.integrate(t_end, opts, progress), self.model, warn, self._note)
        if throw and not res.success and res.status != Status.collapsed:
            raise _failure_error(res, self._note)
        return res


def default_max_displacement(u, v, duration: float) -> float:
    """The default divergence bound on |u_i|: 1e10 x max(1, max|u|, max|v| x duration), for a model
    without declared loads (solve() adds their static displacement to the scale: see there).

    Far beyond any physical response of the model started from (u, v), yet
    reached long before a diverging state overflows, so such a run stops with
    a message naming the DOF instead of running on with inf or NaN. It is the
    bound the C++ loop applies when none is given."""
    u = np.atleast_1d(_checks.real_array("u", u)).ravel()
    v = np.atleast_1d(_checks.real_array("v", v)).ravel()
    return _core.default_max_displacement(u, v, _checks.real("duration", duration))


@_with_options(_P("model", _P.POSITIONAL_OR_KEYWORD), _P("scheme", _P.POSITIONAL_OR_KEYWORD),
               _P("dt", _P.KEYWORD_ONLY), _P("t_end", _P.KEYWORD_ONLY), _P("t0", _P.KEYWORD_ONLY, default=0.0),
               _P("u0", _P.KEYWORD_ONLY, default=None), _P("v0", _P.KEYWORD_ONLY, default=None))
def solve(model: Model, scheme, *, dt: float, t_end: float, t0: float = 0.0, u0=None, v0=None, **options) -> Result:
    """Integrate ``model`` with ``scheme`` from t0 to t_end in steps of dt.

    Saves steps 0, save_every, 2 save_every, ... and always the last one. A
    run whose state becomes non-finite or whose |u_i| exceeds
    ``max_displacement`` (default: 1e10 times the run's displacement scale,
    the largest of 1, max|u0|, max|v0| (t_end - t0) and the static
    displacement of the declared loads over the run, so that a model in mm
    or um, or loaded hard in its own units, is not called diverged where
    the same model in m is not; ``math.inf`` for none) stops within one
    step with status ``Status.diverged``. An explicit scheme whose dt is
    above its stability limit on the model's linear part (damping included:
    a heavily damped top mode shrinks it) is run, but ``Result.warnings``
    and the DivergenceError say so (``nvib.stability.step_warning``). An
    implicit step whose equilibrium iteration does not converge stops the
    run with ``Status.newton_failed``
    (the residual history in the failure); the ``incremental`` and
    ``one_iteration`` modes never iterate and report what they leave
    unbalanced in ``Result.max_residual``. If (t_end - t0)/dt is not an
    integer the run ends at the first multiple of dt past t_end. With
    ``throw=False`` a failed run returns its partial history with ``status``
    set instead of raising. ``energy=True`` records the energy accounting
    (``Result.energy``) for models of declared effects, and then also checks
    it every step: a run whose energy balance error exceeds
    ``max_energy_error`` (default ``DEFAULT_MAX_ENERGY_ERROR`` = 0.5) times
    the energy scale (the largest |kinetic| + |potential| + |work in| +
    |dissipated| so far) stops as diverged. That catches an instability that
    stays finite, such as a vehicle launched off its rails, which no
    displacement bound sees; a sound run's balance error is orders of
    magnitude smaller. ``math.inf`` turns it off. A run that completes with a
    relative balance error above ``warn_energy_error`` (default 5 %) is
    not stopped, but ``Result.warnings`` says so.

    nvib is unit-agnostic: any consistent set of units works. The built-in
    scenes use SI (m, kg, s, N, rad); ``Model.units`` only labels plots and
    tables. Under a ground acceleration u, v and a are relative to the ground
    (``Result.relative_to_ground``; ``Result.absolute_a`` adds it back).

    Effects with memory (bilinear, bouc_wen, friction, imk_peak_oriented, Python laws with a
    ``state``) are committed once per accepted step. ``record=["storey1", ...]`` records the named
    effects at every saved state: ``Result.effects["storey1"]`` has their measure, rate, force and
    internal variables. A structure collapses when a law loses its strength for good (an IMK law's
    energy or ultimate deformation used up) or, with ``collapse_deformation``, when an effect with
    memory deforms beyond it: the run then stops with status ``collapsed`` (returned, never raised;
    ``Result.warnings`` names the effect), unless ``stop_at_collapse=False``.
    """
    return _solve(model, scheme, None, dt=dt, t_end=t_end, t0=t0, u0=u0, v0=v0, **options)


def _solve(model: Model, scheme, peaks, *, dt, t_end, t0=0.0, u0=None, v0=None, **options) -> Result:
    """solve(), and with ``peaks`` (an (m, n) scipy.sparse matrix D) the peaks max |u_i| and max |D u| over every
    step, saved or not, in ``Result._peaks`` (what solve_many(keep="peaks") keeps of a run)."""
    _check_model(model)
    dt, t0, t_end = _checks.number("dt", dt), _checks.number("t0", t0), _checks.number("t_end", t_end)  # C++ checks
    u0 = model.u0 if u0 is None else _checks.vector("u0", u0, model.n)
    v0 = model.v0 if v0 is None else _checks.vector("v0", v0, model.n)
    opts, progress, throw, warn = _run_options(model, options)
    if peaks is not None:
        opts["peaks"] = peaks
    _core.run_steps(t0, t_end, dt)  # the core's checks of the run's times, before the stability note uses dt
    note = _step_note(model, scheme, dt)
    with _partial_annotated(model, warn, note):
        res = _annotate(_core.solve(model._core, scheme, dt, t_end, t0, u0, v0, opts, progress), model, warn, note)
    if throw and not res.success and res.status != Status.collapsed:
        raise _failure_error(res, note)
    return res
