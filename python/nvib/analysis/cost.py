"""Accuracy against cost: ``cost(model, schemes, dts)`` and its SciPy peers.

Every run becomes one row (a dict; a list of them is what ``pandas.DataFrame``
takes), with the same keys for nvib, SciPy and any other contender:

    contender   'nvib', 'scipy' (or what a benchmark adds, e.g. 'C++ loop')
    scheme      the scheme's full name (scheme.name) or the SciPy method
    label       a short name for plots and tables
    dt, rtol    the fixed step (nvib) or the relative tolerance (SciPy); NaN where it does not apply
    tol         an adaptive nvib run's tolerance (solve(..., tol=)), its dt then the first step; NaN otherwise
    t_end, dofs the span and the DOFs the error is measured on (comma-separated names)
    max_error   max over the saved times and the chosen DOFs of |u - u_ref|,
                divided by max |u_ref| over the same times and DOFs
    energy_error  max relative energy balance error (nvib's accounting,
                Result.energy.relative_balance_error()); for SciPy on a conservative
                model (no loads, no velocity or time dependence) the drift of
                kinetic + potential energy over the same scale; NaN where the model
                does not account for energy
    wall_time   seconds, the best of `repeats` runs of the whole call (solve() or solve_ivp())
    repeats     how many runs were timed (fewer than asked when one run is long)
    num_steps, force_evals, tangent_evals, newton_iters, factorizations
                counters of the run (NaN where a contender does not report one:
                SciPy reports no Newton iterations, and no step count when it
                outputs at given times)
    status      'success'; 'diverged', 'newton_failed', 'singular_matrix', 'collapsed' (nvib; a run
                stopped as 'interrupted', by Ctrl-C or an exception in a Python callback, raises);
                'failed' (SciPy gave up); 'skipped' (not run: a looser tolerance of the
                same method already took longer than max_time)
    message     why a run failed or was skipped ('' on success)
    reference   what the error is measured against (Reference.description)

A run that fails is a row too: its max_error and energy_error are inf (never
a small number), its wall_time the time it ran before failing.

The reference (``nvib.reference``) is evaluated at each run's own saved
times: the closed form exactly, DOP853 through its dense output. nvib runs
save every step of the chosen DOFs (every k-th step when a run would save
more than ``max_saved`` states). SciPy is measured at its own accepted steps
by default (no dense output: the cheapest way to run it, and its error is
then looked at on fewer points); ``n_eval`` = N asks for N + 1 equally spaced
output times instead (t_eval, which costs DOP853 three extra force
evaluations per step).

SciPy solves the first-order form y = [u; v], y' = [v; -M^-1 f(u, v, t)]
with the model's own force f (the C++ effects through ``Model.evaluate_force``,
M^-1 applied exactly), from the same initial state as nvib (the model's u0,
v0: for the vehicle its static equilibrium). atol = rtol x per-component
scale (the peaks of the reference, see ``nvib.reference``), which favours
SciPy. Radau, BDF and LSODA get the model's analytic Jacobian
[[0, I], [-M^-1 K_t, -M^-1 C_t]].

The energy accounting costs time, so an nvib run with ``energy=True`` is done
once for the errors and then timed without it (the states are the same).
"""

from __future__ import annotations

import math
import time

import numpy as np

from .. import _checks, _core
from .._errors import ArgumentError
from .._labels import scheme_label
from .._model import Model
from .._schemes import check_scheme
from .._solve import solve
from .reference import FirstOrder, Reference, scale_from_peaks, reference as _reference

SCIPY_METHODS = ("RK45", "DOP853", "Radau", "LSODA")
SCIPY_RTOLS = (1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10)
SCIPY_MIN_RTOL = 2.3e-14  # solve_ivp's floor, 100 machine epsilons (as reference's DOP853 rtol)
_JACOBIAN_METHODS = ("Radau", "BDF", "LSODA")
FIELDS = ("contender", "scheme", "label", "dt", "rtol", "tol", "t_end", "dofs", "max_error", "energy_error", "wall_time",
          "repeats", "num_steps", "force_evals", "tangent_evals", "newton_iters", "factorizations", "status",
          "message", "reference")
NAN = float("nan")
INF = float("inf")


def _row(**kw) -> dict:
    row = {k: NAN for k in FIELDS}
    row.update(status="success", message="", repeats=0)
    row.update(kw)
    return row


def _dof_columns(model: Model, dofs) -> list[int]:
    if dofs is None:
        return list(range(model.n))
    if isinstance(dofs, (str, int)):
        dofs = [dofs]
    cols = [model._dof_index("dofs", d) for d in dofs]
    if not cols:
        raise _checks.value_error("dofs", "give at least one DOF (or None for all)")
    return cols


def _t_end(model: Model, t_end) -> float:
    if t_end is None:
        t_end = (getattr(model, "scene", None) or {}).get("t_end")
        if t_end is None:
            raise _checks.value_error("t_end", "the model has no scene t_end; give t_end")
    t_end = _checks.real("t_end", t_end, positive=True)
    return t_end


def _get_reference(model: Model, t_end: float, ref) -> Reference:
    if ref is None:
        return _reference(model, t_end)
    if not isinstance(ref, Reference):
        raise _checks.type_error("reference", f"expected an nvib Reference (from nvib.reference), got {type(ref).__name__}")
    if ref.n != model.n or ref.t0 != 0.0 or ref.t_end < t_end * (1 - 1e-12):
        raise _checks.value_error("reference", f"covers [{ref.t0:g}, {ref.t_end:g}] for {ref.n} DOFs; the runs need "
                         f"[0, {t_end:g}] for {model.n}")
    return ref


def _error(t: np.ndarray, u: np.ndarray, ref: Reference, cols: list[int]) -> float:
    """max |u - u_ref| / max |u_ref| over the saved times within the reference's span."""
    keep = t <= ref.t_end * (1 + 1e-12)
    if not np.any(keep):
        return NAN
    u_ref = ref.u(t[keep])[:, cols]
    scale = float(np.max(np.abs(u_ref)))
    with np.errstate(all="ignore"):
        err = float(np.max(np.abs(u[keep] - u_ref)))
    if not math.isfinite(err):
        return INF
    return err / scale if scale > 0 else err


def _repeat(run, first_time: float, repeats: int, long_run: float) -> tuple[float, int]:
    """Best wall time over `repeats` runs, the first already done; a run longer than long_run is not repeated."""
    best, done = first_time, 1
    while done < repeats and best < long_run:
        t0 = time.perf_counter()
        run()
        best = min(best, time.perf_counter() - t0)
        done += 1
    return best, done


def _check_common(repeats, long_run):
    repeats = _checks.integer("repeats", repeats, minimum=1)
    long_run = _checks.real("long_run", long_run, positive=True)
    return repeats, long_run


def cost(model: Model, schemes, dts, *, tols=(), t_end: float | None = None, dofs=None,
         reference: Reference | None = None, repeats: int = 3, energy: bool = True, max_saved: int = 100_000,
         long_run: float = 1.0, max_displacement: float | None = None, progress=None) -> list[dict]:
    """One row per (scheme, dt) and per (scheme, tol): error against the reference, energy error, best wall
    time, counters, status.

    model : an nvib.Model (t_end defaults to its scene's). schemes : nvib scheme
    objects. dts : steps. tols : tolerances of adaptive runs (``solve(..., tol=)``, the largest of dts
    their first step; labelled "<scheme>, tol"; a scheme without a local control, PIM, is left out of
    them). dofs : DOF names or indices the error is measured on
    (default: all). reference : a precomputed ``nvib.reference(model, t_end)``
    (computed, and cached per model, when not given). repeats : timed runs per
    row, the best is kept (a run longer than ``long_run`` seconds is timed
    once). energy : record the energy balance error where the model accounts
    for energy. progress : optional callable progress(done, total, row).
    See the module docstring for how each field is measured."""
    if not isinstance(model, Model):
        raise _checks.type_error("model", f"expected nvib.Model, got {type(model).__name__}")
    schemes = list(schemes) if isinstance(schemes, (list, tuple)) else [schemes]
    if not schemes:
        raise _checks.value_error("schemes", "give at least one scheme")
    for s in schemes:
        check_scheme("schemes", s)
    dts = [_checks.number("dts", dt) for dt in np.atleast_1d(np.asarray(dts, dtype=float)).tolist()]
    if not dts:
        raise _checks.value_error("dts", "give at least one step")
    tols = [_checks.real("tols", tol, positive=True) for tol in np.atleast_1d(np.asarray(tols, dtype=float)).tolist()]
    for tol in tols:
        if not tol < 1.0:
            raise _checks.value_error("tols", f"each must lie in (0, 1) (an error relative to a peak), got {tol:g}")
    t_end = _t_end(model, t_end)
    for dt in dts:  # the core's checks of a run's step, naming the list the step came from
        try:
            _core.run_steps(0.0, t_end, dt)
        except ArgumentError as exc:
            raise _checks.value_error("dts" if exc.argument == "dt" else exc.argument, exc.reason) from None
    cols = _dof_columns(model, dofs)
    repeats, long_run = _check_common(repeats, long_run)
    max_saved = _checks.integer("max_saved", max_saved, minimum=2)
    if progress is not None and not callable(progress):
        raise _checks.type_error("progress", "expected a callable progress(done, total, row)")
    ref = _get_reference(model, t_end, reference)
    with_energy = bool(energy) and bool(model._core.accounts_energy)
    names = ",".join(model.dofs[c] for c in cols)
    rows = []
    adaptive = [s for s in schemes if s.adaptive] if tols else []
    total = len(schemes) * len(dts) + len(adaptive) * len(tols)
    runs = [(scheme, dt, math.nan) for scheme in schemes for dt in dts] + \
        [(scheme, max(dts), tol) for scheme in adaptive for tol in tols]
    for scheme, dt, tol in runs:
        rows.append(_nvib_row(model, scheme, dt, tol, t_end, cols, names, ref, repeats, long_run, with_energy,
                              max_saved, max_displacement))
        if progress is not None:
            progress(len(rows), total, rows[-1])
    return rows


def _nvib_row(model, scheme, dt, tol, t_end, cols, names, ref, repeats, long_run, with_energy, max_saved,
              max_displacement) -> dict:
    adaptive = not math.isnan(tol)
    n_steps = _core.steps_to_reach(0.0, t_end, dt)
    save_every = 1 if adaptive else max(1, math.ceil(n_steps / (max_saved - 1)))
    kw = dict(dt=dt, t_end=t_end, save_every=save_every, dofs=cols, throw=False, max_displacement=max_displacement)
    if adaptive:
        kw["tol"] = tol
    label = scheme_label(scheme) + (", tol" if adaptive else "")
    base = dict(contender="nvib", scheme=scheme.name, label=label, dt=dt, tol=tol, t_end=t_end, dofs=names,
                reference=ref.description)
    t0 = time.perf_counter()
    # The energy is a measurement here, not a stopping rule: the row's status is what solve() does without it.
    res = solve(model, scheme, energy=with_energy, max_energy_error=math.inf if with_energy else None, **kw)
    first = time.perf_counter() - t0
    stats = res.stats
    counters = dict(num_steps=stats.num_steps, force_evals=stats.num_force_evals,
                    tangent_evals=stats.num_tangent_evals, newton_iters=stats.num_newton_iters,
                    factorizations=stats.num_factorizations)
    if not res.success:
        msg = res.failure.message if res.failure is not None else res.status.name
        return _row(**base, **counters, max_error=INF, energy_error=INF if with_energy else NAN, wall_time=first,
                    repeats=1, status=res.status.name, message=msg)
    err = _error(res.t, res.u, ref, cols)
    e_err = NAN
    if with_energy:
        with np.errstate(all="ignore"):
            e_err = float(res.energy.relative_balance_error())
    if not math.isfinite(err):  # cannot happen after a successful solve(); never report it as small
        return _row(**base, **counters, max_error=INF, energy_error=INF if with_energy else NAN, wall_time=first,
                    repeats=1, status="diverged", message="non-finite displacement")

    def run():
        solve(model, scheme, **kw)

    if with_energy:  # the timed runs leave the energy accounting out
        t0 = time.perf_counter()
        run()
        first = time.perf_counter() - t0
    best, done = _repeat(run, first, repeats, long_run)
    return _row(**base, **counters, max_error=err, energy_error=e_err, wall_time=best, repeats=done)


# ---------------------------------------------------------------- SciPy peers

def _conservative(model: Model) -> bool:
    """Energy is kinetic + potential and stays constant: declared effects only, no loads, no dampers."""
    return (bool(model._core.accounts_energy) and not model.uses_velocity and not model.uses_time
            and not any(e.is_load for e in (model.effects or [])))


def _scales_from_reference(model: Model, ref: Reference, t_end: float) -> np.ndarray:
    grid = np.linspace(0.0, t_end, 4001)
    u, v = ref(grid)
    return scale_from_peaks(np.concatenate((np.max(np.abs(u), axis=0), np.max(np.abs(v), axis=0))), model.n)


def cost_scipy(model: Model, methods=SCIPY_METHODS, rtols=SCIPY_RTOLS, *, t_end: float | None = None, dofs=None,
               reference: Reference | None = None, repeats: int = 3, n_eval: int | None = None,
               jacobian: bool = True, long_run: float = 1.0, max_time: float = 30.0, progress=None) -> list[dict]:
    """One row per (method, rtol) of ``scipy.integrate.solve_ivp`` on the same model, in the same format
    as ``cost``. Tolerances run from loose to tight; once a run of a method takes longer than
    ``max_time`` seconds, its tighter tolerances are 'skipped' rows. n_eval : None (default) to
    measure the error at the solver's own steps, or N for N + 1 equally spaced output times
    (dense output). jacobian : give Radau, BDF and LSODA the model's analytic Jacobian."""
    from scipy.integrate import solve_ivp

    if not isinstance(model, Model):
        raise _checks.type_error("model", f"expected nvib.Model, got {type(model).__name__}")
    methods = [methods] if isinstance(methods, str) else list(methods)
    known = ("RK23", "RK45", "DOP853", "Radau", "BDF", "LSODA")
    for m in methods:
        if m not in known:
            raise _checks.value_error("methods", f"unknown solve_ivp method {m!r} (known: {', '.join(known)})")
    rtols = sorted((_checks.real("rtols", r, positive=True) for r in np.atleast_1d(np.asarray(rtols, dtype=float))),
                   reverse=True)
    if not methods or not rtols:
        raise _checks.value_error("methods, rtols", "give at least one of each")
    if rtols[-1] < SCIPY_MIN_RTOL:  # solve_ivp would raise it to that with a warning, and take as long
        raise _checks.value_error("rtols", f"must be >= {SCIPY_MIN_RTOL:g} (solve_ivp raises a smaller one to 100 "
                                           f"machine epsilons), got {rtols[-1]:g}")
    t_end = _t_end(model, t_end)
    cols = _dof_columns(model, dofs)
    repeats, long_run = _check_common(repeats, long_run)
    max_time = _checks.real("max_time", max_time, positive=True)
    if n_eval is not None:
        n_eval = _checks.integer("n_eval", n_eval, minimum=1)
    ref = _get_reference(model, t_end, reference)
    scale = _scales_from_reference(model, ref, t_end)
    y0 = np.concatenate((model.u0, model.v0))
    t_eval = None if n_eval is None else np.linspace(0.0, t_end, n_eval + 1)
    n = model.n
    conservative = _conservative(model)
    names = ",".join(model.dofs[c] for c in cols)
    rows = []
    total = len(methods) * len(rtols)
    for method in methods:
        too_long = None
        for rtol in rtols:
            base = dict(contender="scipy", scheme=method, label=f"SciPy {method}", rtol=rtol, t_end=t_end,
                        dofs=names, reference=ref.description)
            if too_long is not None:
                rows.append(_row(**base, status="skipped", repeats=0,
                                 message=f"rtol {too_long[0]:g} already took {too_long[1]:.3g} s > max_time"))
            else:
                rows.append(_scipy_row(solve_ivp, model, method, rtol, scale, y0, t_eval, t_end, cols, ref, base,
                                       repeats, long_run, jacobian, conservative, n))
                if rows[-1]["wall_time"] > max_time:
                    too_long = (rtol, rows[-1]["wall_time"])
            if progress is not None:
                progress(len(rows), total, rows[-1])
    return rows


def _scipy_row(solve_ivp, model, method, rtol, scale, y0, t_eval, t_end, cols, ref, base, repeats, long_run,
               jacobian, conservative, n) -> dict:
    sys = FirstOrder(model)
    kw = dict(method=method, t_eval=t_eval, rtol=rtol, atol=rtol * scale)
    if jacobian and method in _JACOBIAN_METHODS:
        kw["jac"] = sys.jac

    def run():
        with np.errstate(all="ignore"):
            return solve_ivp(sys.rhs, (0.0, t_end), y0, **kw)

    t0 = time.perf_counter()
    try:
        sol = run()
    except (ValueError, ArithmeticError, np.linalg.LinAlgError) as exc:
        return _row(**base, max_error=INF, energy_error=INF if conservative else NAN,
                    wall_time=time.perf_counter() - t0, repeats=1, status="failed", message=str(exc))
    first = time.perf_counter() - t0
    counters = dict(force_evals=sol.nfev, tangent_evals=sol.njev, factorizations=sol.nlu)
    if sol.status != 0 or not np.all(np.isfinite(sol.y)) or (t_eval is not None and sol.y.shape[1] != t_eval.size):
        return _row(**base, **counters, max_error=INF, energy_error=INF if conservative else NAN, wall_time=first,
                    repeats=1, status="failed", message=str(sol.message))
    err = _error(sol.t, sol.y[:n].T[:, cols], ref, cols)
    e_err = NAN
    if conservative:
        core = model._core
        ek = np.array([core.kinetic(np.ascontiguousarray(sol.y[n:, j])) for j in range(sol.t.size)])
        ep = np.array([core.potential(np.ascontiguousarray(sol.y[:n, j]), 0.0) for j in range(sol.t.size)])
        top = float(np.max(np.abs(ek) + np.abs(ep)))
        drift = float(np.max(np.abs(ek + ep - ek[0] - ep[0])))
        e_err = drift / top if top > 0 else drift
    if t_eval is None:
        counters["num_steps"] = sol.t.size - 1
    best, done = _repeat(run, first, repeats, long_run)
    return _row(**base, **counters, max_error=err, energy_error=e_err, wall_time=best, repeats=done)


# ---------------------------------------------------------------- reading the rows

def cheapest(rows: list[dict], target: float, *, contender: str | None = None) -> dict | None:
    """The successful row with max_error <= target and the least wall time (of one contender if given)."""
    target = _checks.real("target", target, positive=True)
    ok = [r for r in rows if r["status"] == "success" and r["max_error"] <= target
          and (contender is None or r["contender"] == contender)]
    return min(ok, key=lambda r: r["wall_time"]) if ok else None


def time_at_error(rows: list[dict], target: float) -> dict:
    """For each (contender, label) curve: the wall time at max_error = target, interpolated linearly in
    log(time) against log(error) between the two runs (in order of dt or rtol) where the error first
    falls to the target; NaN when the curve never reaches it. Less tied to the grid of dt or rtol
    than ``cheapest``."""
    target = _checks.real("target", target, positive=True)
    out = {}
    groups: dict = {}
    for r in rows:
        groups.setdefault((r["contender"], r["label"]), []).append(r)
    for key, rs in groups.items():
        ok = [r for r in rs if r["status"] == "success" and r["max_error"] > 0]
        ok.sort(key=_setting)
        out[key] = NAN
        for i, r in enumerate(ok):
            if r["max_error"] <= target:
                if i == 0:
                    out[key] = r["wall_time"]
                else:
                    a, b = ok[i - 1], r
                    x = (math.log(target) - math.log(a["max_error"])) / (math.log(b["max_error"]) -
                                                                         math.log(a["max_error"]))
                    out[key] = math.exp(math.log(a["wall_time"]) + x * (math.log(b["wall_time"]) -
                                                                        math.log(a["wall_time"])))
                break
    return out


def _setting(row: dict) -> float:
    """The order of a curve's runs, the loosest first: SciPy's rtol, an adaptive run's tol, else dt."""
    if row["contender"] == "scipy":
        return -row["rtol"]
    tol = row.get("tol", NAN)
    return -(tol if isinstance(tol, float) and not math.isnan(tol) else row["dt"])


def setting_text(row: dict) -> str:
    """'dt = .. s', 'tol = ..' (an adaptive nvib run) or 'rtol = ..' (SciPy): what a row's run was given."""
    if row["contender"] == "scipy":
        return f"rtol = {row['rtol']:g}"
    tol = row.get("tol", NAN)
    return f"tol = {tol:g}" if isinstance(tol, float) and not math.isnan(tol) else f"dt = {row['dt']:g} s"


def _fmt(x, spec: str = ".3g") -> str:
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "-"
    if isinstance(x, float) and math.isinf(x):
        return "inf"
    if isinstance(x, (int, np.integer)):
        return f"{int(x):,}"
    if isinstance(x, float) and x.is_integer() and spec == "int":
        return f"{int(x):,}"
    return format(x, spec if spec != "int" else ".0f")


def markdown_table(rows: list[dict]) -> str:
    """The rows as a markdown table (times in ms)."""
    head = ["contender", "scheme", "dt [s]", "rtol or tol", "max error", "energy error", "wall time [ms]", "runs", "steps",
            "force evals", "Newton it.", "factorisations", "status"]
    lines = ["| " + " | ".join(head) + " |", "|" + "|".join(["---", "---"] + ["---:"] * 10 + ["---"]) + "|"]
    for r in rows:
        msg = r["message"]
        status = r["status"] if not msg else (msg if msg.startswith(r["status"]) else f"{r['status']}: {msg}")
        wall = r["wall_time"] * 1e3 if isinstance(r["wall_time"], float) and math.isfinite(r["wall_time"]) else NAN
        tol = r.get("tol", NAN)
        setting = r["rtol"] if isinstance(tol, float) and math.isnan(tol) else tol
        cells = [r["contender"], r["label"], _fmt(r["dt"]), _fmt(setting, ".0e"), _fmt(r["max_error"], ".2e"),
                 _fmt(r["energy_error"], ".2e"), _fmt(wall, ".3g"), _fmt(r["repeats"]), _fmt(r["num_steps"], "int"),
                 _fmt(r["force_evals"], "int"), _fmt(r["newton_iters"], "int"), _fmt(r["factorizations"], "int"),
                 status.replace("|", "/")]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def plot_work_precision(rows: list[dict], path: str, *, title: str | None = None, target: float | None = None,
                        dpi: int = 110) -> None:
    """Write ``work_precision_figure(rows, title=title, target=target)`` to ``path``."""
    work_precision_figure(rows, title=title, target=target).savefig(path, dpi=dpi)


def work_precision_figure(rows: list[dict], *, title: str | None = None, target: float | None = None):
    """Work-precision diagram: log max_error against log wall time, one line per (contender, label), points
    in order of dt or rtol. Failed runs are counted in the legend, not drawn. ``target`` draws a dashed
    line at that error and marks the cheapest run of each contender (nvib, SciPy) that reaches it with a star."""
    if target is not None:
        target = _checks.real("target", target, positive=True)
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(8.5, 6.0), layout="constrained")
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    groups: dict = {}
    for r in rows:
        groups.setdefault((r["contender"], r["label"]), []).append(r)
    styles = {"nvib": ("-", "o"), "scipy": ("--", "s")}
    import matplotlib

    palette = matplotlib.colormaps["tab20"]
    drawn = 0
    for i, ((who, label), rs) in enumerate(groups.items()):
        color = palette(((2 * i) % 20 + (2 * i // 20) % 2) / 19.999)  # the dark shades first, then the light
        ok = [r for r in rs if r["status"] == "success" and r["max_error"] > 0]
        ok.sort(key=_setting)
        failed = sum(r["status"] not in ("success", "skipped") for r in rs)
        ls, marker = styles.get(who, (":", "^"))
        name = label if label.startswith(("SciPy", who)) or who == "nvib" else f"{who}: {label}"
        if failed:
            name += f" ({failed} failed)"
        if ok:
            ax.loglog([r["wall_time"] for r in ok], [r["max_error"] for r in ok], ls=ls, marker=marker, ms=4,
                      lw=1.3, color=color, label=name)
            drawn += 1
        else:
            ax.plot([], [], ls=ls, marker=marker, color=color, label=name + " (nothing to draw)")
    if target is not None:
        ax.axhline(target, color="k", ls=":", lw=1.0, label=f"error {target:g}")
        for who in dict.fromkeys(r["contender"] for r in rows):  # the cheapest run of each contender at the target
            best = cheapest(rows, target, contender=who)
            if best is None or not best["max_error"] > 0:
                continue
            setting = setting_text(best)
            ax.plot(best["wall_time"], best["max_error"], marker="*", ms=16, mfc="gold", mec="k", mew=1.0,
                    ls="none", zorder=5, label=f"cheapest {who} at error <= {target:g}")
            ax.annotate(f"{best['label']}\n{setting}, {best['wall_time']:.3g} s", (best["wall_time"], best["max_error"]),
                        xytext=(8, -14), textcoords="offset points", fontsize=7,
                        bbox=dict(boxstyle="round,pad=0.2", fc="white", ec="0.6", alpha=0.85))
    if drawn:
        ax.set_xscale("log")
        ax.set_yscale("log")
    ax.set_xlabel("wall time [s] (best of repeats)")
    ref = next((r["reference"] for r in rows if isinstance(r["reference"], str)), "")
    dofs = next((r["dofs"] for r in rows if isinstance(r["dofs"], str)), "")
    ax.set_ylabel(f"relative error max |u - u_ref| / max |u_ref| [-]  ({dofs})")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, loc="best", ncol=2 if len(groups) > 8 else 1)
    head = title or "Work-precision"
    fig.suptitle(f"{head}\nreference: {ref}", fontsize=10)
    return fig
