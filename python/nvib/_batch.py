"""Many runs in one call: ``solve_many``.

The runs are a list of models, or one model under several ground motions and/or scale factors, or
one model with parameter variations of named effects, with one scheme or one per run. Models of
built-in effects run on threads (the solver releases the GIL, so they use every core); models that
call Python run in processes (they pickle: their lambdas and closures by value, through cloudpickle).
Results come back in input order; a run that fails keeps its status and message in its own result and
the others go on. ``keep="peaks"`` keeps a summary per
run instead of its history, so memory stays bounded however many runs there are.
"""

from __future__ import annotations

import concurrent.futures as cf
import dataclasses
import itertools
import math
import os
import signal
import sys
import time
from concurrent.futures.process import BrokenProcessPool

import numpy as np

from . import _checks, _compiled
from ._labels import scheme_label
from ._model import Model
from ._progress import ProgressBar
from ._records import GroundMotion
from . import _core
from ._core import ArgumentError, ArgumentTypeError, StopToken
from ._solve import Status, _solve, check_option_names, check_settings, solve

__all__ = ["solve_many", "RunSummary", "RunError", "Batch"]


@dataclasses.dataclass
class RunSummary:
    """What ``keep="peaks"`` keeps of a run: its status and message, the peak |u| of every DOF, the peak
    |d| of every named effect's measure (a storey's drift), the final state, the largest relative energy
    balance error (with ``energy=True``), the counters and the wall time. ``label`` says what the run was.
    The peaks and the energy error are over every step of the run, whatever ``save_every``.
    ``error_estimate``: the run's estimated error, the largest over its DOFs (``Result.error_estimate``;
    None when switched off or not available for the scheme), and ``error_estimates`` each DOF's (relative
    to that DOF's peak; None likewise); ``warnings``: the run's ``Result.warnings``."""

    label: dict
    status: Status | None
    message: str
    peak_u: np.ndarray
    peak_measures: dict
    t_final: float
    u_final: np.ndarray
    v_final: np.ndarray
    energy_error: float | None
    stats: object
    wall_time: float
    error_estimate: float | None = None
    warnings: list = dataclasses.field(default_factory=list)
    error_estimates: np.ndarray | None = None

    @property
    def success(self) -> bool:
        return self.status == Status.success


@dataclasses.dataclass
class RunError:
    """A run that could not be made (a bad parameter value, a model that does not build): the error."""

    label: dict
    error: BaseException

    status = None
    success = False

    @property
    def message(self) -> str:
        return f"{type(self.error).__name__}: {self.error}"


class Batch(list):
    """The results of ``solve_many`` in input order (a Result or RunSummary per run, or a RunError),
    with ``labels`` (what each run was: its index, ground motion, scale, varied parameters, scheme) and
    ``error_estimates`` (each run's estimated error); its repr names the run with the largest."""

    def __init__(self, results, labels):
        super().__init__(results)
        self.labels = list(labels)

    @property
    def failed(self) -> list[int]:
        """Indices of the runs that did not succeed (None: a run an interrupt kept from starting)."""
        return [k for k, r in enumerate(self) if r is None or not r.success]

    @property
    def error_estimates(self) -> np.ndarray:
        """Each run's estimated error (the largest over its DOFs, ``Result.error_estimate``); NaN for a run
        without one (not made, switched off, a scheme it does not cover)."""
        out = np.full(len(self), np.nan)
        for k, r in enumerate(self):
            e = getattr(r, "error_estimate", None)
            if isinstance(r, RunSummary):
                out[k] = np.nan if e is None else e
            elif e is not None and e.available:
                out[k] = e.max
        return out

    def __repr__(self) -> str:
        est = self.error_estimates
        line = f"Batch of {len(self)} run{'s' if len(self) != 1 else ''}, {len(self.failed)} not succeeded"
        if np.any(~np.isnan(est)):
            k = int(np.nanargmax(est))
            line += f"; largest error estimate {est[k]:.2g} (run {k}: {self.labels[k]})"
        return line

    def __reduce__(self):
        return (Batch, (list(self), self.labels))


# ---- the runs ---------------------------------------------------------------------------------------

def _scaled_signal(signal, factor: float):
    if factor == 1.0:
        return signal
    if isinstance(signal, GroundMotion):
        return signal.scaled(factor)
    if isinstance(signal, dict) and signal.get("kind") == "sine":
        return {**signal, "amplitude": _checks.real("signal.amplitude", signal["amplitude"]) * factor}
    if isinstance(signal, dict) and signal.get("kind") == "table":
        return {**signal, "values": (np.asarray(signal["values"], dtype=float) * factor).tolist()}
    if isinstance(signal, dict) and signal.get("kind") == "record":
        return GroundMotion.from_spec("signal", signal).scaled(factor)
    raise _checks.value_error("scales", f"cannot scale the signal {signal!r}")


def _derived(model: Model, motion, scale: float, changes: dict) -> Model:
    """The model with its ground accelerations' signal replaced by `motion` (if given) times `scale`,
    and the named effects' parameters changed (`changes`: {"storey1.k0": value})."""
    effects = model._init[1].get("effects")
    if effects is None:
        raise _checks.value_error("model", "ground motions, scales and variations need a model of declared effects")
    effects = [dict(e) if isinstance(e, dict) else e for e in effects]
    ground = [e for e in effects if isinstance(e, dict) and e.get("type") == "ground_acceleration"]
    if (motion is not None or scale != 1.0) and not ground:
        raise _checks.value_error("ground_motions" if motion is not None else "scales",
                                  "the model has no ground_acceleration effect")
    for e in ground:
        e["signal"] = _scaled_signal(motion if motion is not None else e.get("signal"), scale)
    for key, value in changes.items():
        hits, param = _named(effects, key)
        for e in hits:
            e[param] = value
    out = model._rebuilt(effects=effects)
    scene = getattr(model, "scene", None)
    if isinstance(scene, dict) and scene.get("initial_u") == "static_equilibrium":
        out.u0 = out.static_equilibrium()  # the changed model has its own equilibrium
    return out


def _named(effects: list, key) -> tuple[list, str]:
    """The declared effects (dicts) a variation key "effect_name.parameter" names, and the parameter."""
    name, _, param = str(key).rpartition(".")
    hits = [e for e in effects if isinstance(e, dict) and e.get("name") == name] if name else []
    if not hits:
        named = sorted(str(e.get("name")) for e in effects if isinstance(e, dict) and e.get("name"))
        raise _checks.value_error(f"variations[{key!r}]", "expected 'effect_name.parameter' naming an effect of the "
                                                          f"model (named: {', '.join(named) or 'none'})")
    if any(param not in e for e in hits):
        raise _checks.value_error(f"variations[{key!r}]", f"effect {name!r} has no parameter {param!r}")
    return hits, param


def _expand(models, ground_motions, scales, variations):
    """[(model or None, motion, scale, changes, label)] in input order."""
    if isinstance(models, Model):
        motions = [None] if ground_motions is None else list(ground_motions)
        for k, g in enumerate(motions):
            if g is not None and not isinstance(g, GroundMotion):
                raise _checks.type_error(f"ground_motions[{k}]", f"expected a GroundMotion, got {type(g).__name__}")
        factors = [1.0] if scales is None else [_checks.real(f"scales[{k}]", s) for k, s in enumerate(scales)]
        if not motions or not factors:
            raise _checks.value_error("ground_motions" if not motions else "scales", "empty")
        variations = dict(variations or {})
        declared = models._init[1].get("effects") or []
        for key in variations:
            _named(declared, key)
            if isinstance(variations[key], (str, bytes)) or not hasattr(variations[key], "__len__"):
                raise _checks.type_error(f"variations[{key!r}]", "expected a list of values, one per run")
        lengths = {key: len(v) for key, v in variations.items()}
        for key, count in lengths.items():
            if count == 0:
                raise _checks.value_error(f"variations[{key!r}]", "empty: expected a list of values, one per run")
        if len(set(lengths.values())) > 1:
            raise _checks.value_error("variations", f"every parameter needs as many values (got {lengths})")
        nvar = next(iter(lengths.values()), 1)
        runs = []
        for (gi, g), s, k in itertools.product(enumerate(motions), factors, range(nvar)):
            changes = {key: values[k] for key, values in variations.items()}
            label = {}
            if ground_motions is not None:
                label["ground_motion"] = g.name or gi
            if scales is not None:
                label["scale"] = s
            label.update(changes)
            runs.append((models, g, s, changes, label))
        return runs
    models = list(models)
    for k, m in enumerate(models):
        if not isinstance(m, Model):
            raise _checks.type_error(f"models[{k}]", f"expected a Model, got {type(m).__name__}")
    for arg, value in (("ground_motions", ground_motions), ("scales", scales), ("variations", variations)):
        if value is not None:
            raise _checks.value_error(arg, "applies to one model; with a list of models, make each model as wanted")
    return [(m, None, 1.0, {}, {"model": m.name or k}) for k, m in enumerate(models)]


MAX_SUMMARY_STATES = 1000  # keep="peaks" without save_every: states a run saves at most


def _peak_rows(model: Model):
    """The measures whose peaks a summary keeps, as the rows of a sparse matrix D (d = D u): one row per named
    effect that is not a load, one per effect of a named array (d_k = u[i_k] - u[j_k]); and [(name, rows,
    one)] saying which rows are whose (one: a single effect, a float; else an array of peaks)."""
    from scipy import sparse

    rows, cols, vals, layout = [], [], [], []
    m = 0
    for e in model.effects or []:
        if e.name and not e.is_load:
            rows += [m] * len(e.index)
            cols += list(e.index)
            vals += [float(c) for c in e.coef]
            layout.append((e.name, slice(m, m + 1), True))
            m += 1
    for arr in model.effect_arrays:
        if arr.name and not arr.is_load:
            i, j = np.asarray(arr.i, dtype=int), np.asarray(arr.j, dtype=int)
            k = np.arange(m, m + i.size)
            rows += k.tolist() + k[j >= 0].tolist()
            cols += i.tolist() + j[j >= 0].tolist()
            vals += [1.0] * i.size + [-1.0] * int(np.count_nonzero(j >= 0))
            layout.append((arr.name, slice(m, m + i.size), False))
            m += i.size
    D = sparse.csc_matrix((vals, (rows, cols)), shape=(m, model.n), dtype=float)
    return D, layout


def _summary(model: Model, res, label: dict, layout=None) -> RunSummary:
    """A run's summary: the peaks the run tracked over every step (a run made with peaks), else those of its
    saved history (a partial result of an interrupted run made without)."""
    u = res.u
    tracked = res._peaks if layout is not None else None
    if tracked is not None:
        peak_u, peak_d, tracked_err = tracked
        measures = {name: (float(peak_d[rows][0]) if one else np.array(peak_d[rows])) for name, rows, one in layout}
    else:
        peak_u = np.max(np.abs(u), axis=0) if len(u) else np.zeros(model.n)
        measures = {}
        for e in model.effects or []:
            if e.name and not e.is_load:
                d = u[:, list(e.index)] @ np.asarray(e.coef)
                measures[e.name] = float(np.max(np.abs(d))) if d.size else 0.0
        for arr in model.effect_arrays:
            if arr.name and not arr.is_load:  # one peak per effect of the array: d_k = u[i_k] - u[j_k]
                i, j = np.asarray(arr.i), np.asarray(arr.j)
                uj = np.where(j >= 0, u[:, np.maximum(j, 0)], 0.0) if j.size else 0.0
                measures[arr.name] = np.max(np.abs(u[:, i] - uj), axis=0) if len(u) else np.zeros(i.size)
    if tracked is not None and tracked_err is not None:
        err = float(tracked_err)
    else:
        err = float(res.energy.relative_balance_error()) if res.energy is not None else None
    msg = res.failure.message if res.failure is not None else ""
    est = res.error_estimate
    return RunSummary(label, res.status, msg, peak_u, measures, float(res.t[-1]), u[-1].copy(), res.v[-1].copy(),
                      err, res.stats, res.stats.wall_time, est.max if est is not None and est.available else None,
                      list(res.warnings), est.per_dof.copy() if est is not None and est.available else None)


def _run_one(model, motion, scale, changes, label, scheme, own, keep, options):
    """One run (``own``: the options of this run alone, such as its t_end); never raises for the run's own
    failure (bad input gives a RunError)."""
    options = {**options, **own} if own else options
    try:
        m = _derived(model, motion, scale, changes) if (motion is not None or scale != 1.0 or changes) else model
        if keep == "peaks":
            # the peaks (and with energy the balance error) are tracked over every step by the run itself; the
            # history it saves (the caller's save_every, else at most MAX_SUMMARY_STATES states) is dropped once
            # the final state is read from it
            D, layout = _peak_rows(m)
            opts = dict(options)
            if "save_every" not in opts:
                steps = _core.steps_to_reach(float(opts.get("t0", 0.0)), opts["t_end"], opts["dt"])
                opts["save_every"] = max(1, math.ceil(steps / MAX_SUMMARY_STATES))
            res = _solve(m, scheme, D, throw=False, **opts)
            return _summary(m, res, label, layout)
        return solve(m, scheme, throw=False, **options)
    except (ValueError, TypeError, ArithmeticError, RuntimeError) as exc:
        return RunError(label, exc)


def _partial(item, keep, options, exc: BaseException):
    """What an interrupted run hands back: its partial Result (Status.interrupted), summarised for
    keep="peaks"; None when it stopped before its first step."""
    res = getattr(exc, "result", None)
    if res is None or keep != "peaks":
        return res
    return _summary(item[0], res, item[4], _peak_rows(item[0])[1] if res._peaks is not None else None)


def _run_chunk(items, keep, options, stop=None):
    """The runs of one chunk in turn, each under ``stop`` (a StopToken) when given. Once the token is
    set, or a run is interrupted, the rest are not started (None); an interrupted run's partial result
    takes its place, so the chunk always returns one entry per run."""
    token = stop if stop is not None else _PROCESS_STOP
    out = []
    for item in items:
        if token is not None and token.is_set:
            out.append(None)
            continue
        try:
            if token is not None:
                with token:
                    out.append(_run_one(*item, keep, options))
            else:
                out.append(_run_one(*item, keep, options))
        except KeyboardInterrupt as exc:
            out.append(_partial(item, keep, options, exc))
            if token is not None:
                token.set()
            else:
                raise
    return out


# ---- worker processes -------------------------------------------------------------------------------

_PROCESS_STOP = None  # a worker process's StopToken, set by its SIGINT handler


def _on_sigint_in_worker(signum, frame):
    # the running solve sees the token at its next poll and stops with its partial result; no run starts
    # after it. Raising here instead could land outside a run and kill the worker between tasks.
    if _PROCESS_STOP is not None:
        _PROCESS_STOP.set()


def _init_worker():
    """A batch's worker process: dies with its parent (Linux), and turns SIGINT into a stop request."""
    global _PROCESS_STOP
    if sys.platform.startswith("linux"):
        try:
            import ctypes

            libc = ctypes.CDLL(None, use_errno=True)
            libc.prctl(1, signal.SIGKILL, 0, 0, 0)  # PR_SET_PDEATHSIG: killed when the parent dies
        except (OSError, AttributeError):  # pragma: no cover - no prctl
            pass
        if os.getppid() == 1:  # the parent died before the request took effect
            os._exit(1)
    _PROCESS_STOP = StopToken()
    signal.signal(signal.SIGINT, _on_sigint_in_worker)


def _stop_workers(pool) -> None:
    """Ask each worker process of ``pool`` to stop its run (their SIGINT handler)."""
    for proc in list((getattr(pool, "_processes", None) or {}).values()):
        try:
            os.kill(proc.pid, signal.SIGINT)
        except (ProcessLookupError, PermissionError):
            pass


def _kill_workers(pool) -> None:
    for proc in list((getattr(pool, "_processes", None) or {}).values()):
        try:
            proc.kill()
        except (ProcessLookupError, PermissionError, AttributeError):
            pass


def _interrupted(results, labels, exc: BaseException) -> KeyboardInterrupt:
    """The KeyboardInterrupt solve_many raises: ``.result`` is the Batch of what was done (finished runs,
    the partial ones with Status.interrupted, None for the runs never started)."""
    batch = Batch(results, labels)
    finished = sum(1 for r in batch if r is not None and getattr(r, "status", None) != Status.interrupted)
    partial = sum(1 for r in batch if r is not None and getattr(r, "status", None) == Status.interrupted)
    err = KeyboardInterrupt(f"solve_many interrupted: {finished} of {len(batch)} runs finished, {partial} "
                            f"stopped part-way, {len(batch) - finished - partial} not run (exc.result holds them)")
    err.result = batch
    return err


def _python_callables(model: Model):
    """(where, callable) for each Python callable of a model: its force and tangent, its callable laws."""
    for key in ("force", "tangent"):
        if getattr(model, key, None) is not None:
            yield key, getattr(model, key)
    for i, e in enumerate(model._init[1].get("effects") or []):
        if isinstance(e, dict) and e.get("type") == "callable":
            for key in ("law", "tangent"):
                if e.get(key) is not None:
                    yield f"effects[{i}].{key}", e[key]


def _check_picklable(items, *, single: bool) -> None:
    """Models that call Python run in worker processes, which get them pickled (by cloudpickle, so lambdas
    and closures go by value): their callables are tried here, before any pool starts, so that one that
    refers to what cannot travel (a lock, an open file, a C++ object) is an error naming it and what to do
    instead of a PicklingError out of the pool."""
    import cloudpickle

    seen = set()
    for k, item in enumerate(items):
        model = item[0]
        if id(model) in seen:
            continue
        seen.add(id(model))
        try:  # compiled laws: those given by an address cannot travel
            _compiled.travelling(model._init[1].get("effects"))
        except ArgumentTypeError as exc:
            name = f"{'models' if single else f'models[{k}]'}.{exc.argument}"
            raise _checks.type_error(name, exc.reason) from None
        if not model._core.has_python:
            continue
        for where, fn in _python_callables(model):
            try:
                cloudpickle.dumps(fn)
            except Exception as exc:  # PicklingError, TypeError ("cannot pickle '_thread.lock' object"), ...
                name = f"{'models' if single else f'models[{k}]'}.{where}"
                raise _checks.type_error(name, f"{getattr(fn, '__qualname__', type(fn).__name__)} cannot be pickled "
                                               f"({type(exc).__name__}: {exc}): a model that calls Python runs in "
                                               "worker processes, which get it with what it refers to; let it "
                                               "refer only to what pickles (numbers, arrays, functions), or run "
                                               "the models in threads (threads=1, or processes=False)") from None


def _run_alone(conn, item, keep, options) -> None:
    """In a process of its own: one run, sent back through ``conn`` as (True, result) or (False, exception).
    The process is a batch worker like the pool's: it dies with its parent and stops its run on SIGINT."""
    _init_worker()
    try:
        out = (True, _run_chunk([item], keep, options)[0])
    except Exception as exc:
        out = (False, exc)
    conn.send(out)
    conn.close()


def _death(exitcode) -> str:
    if exitcode is not None and exitcode < 0:
        try:
            return f"killed by {signal.Signals(-exitcode).name}"
        except ValueError:
            return f"killed by signal {-exitcode}"
    return f"exited with status {exitcode}"


def _rerun_apart(lost, items, keep, options, results, workers) -> None:
    """The runs of the chunks whose worker process died (a pool loses every chunk not yet finished), each
    made again in a process of its own, ``workers`` at a time: the run that ends its process again gets a
    RunError saying so, the others their results."""
    import multiprocessing as mp
    from multiprocessing.connection import wait

    ctx = mp.get_context()
    pending = list(lost)
    running = {}  # connection -> (run index, process)
    try:
        while pending or running:
            while pending and len(running) < workers:
                k = pending.pop(0)
                receive, send = ctx.Pipe(duplex=False)
                proc = ctx.Process(target=_run_alone, args=(send, items[k], keep, options), daemon=True)
                proc.start()
                send.close()
                running[receive] = (k, proc)
            for conn in wait(list(running)):  # a result, or the end of a process that died before sending one
                k, proc = running.pop(conn)
                try:
                    ok, out = conn.recv()
                except (EOFError, OSError):
                    proc.join()
                    results[k] = RunError(items[k][4], BrokenProcessPool(
                        f"its worker process died ({_death(proc.exitcode)}), also when the run was made again on "
                        "its own: a force that ends the process (os._exit), a crash in Python code it calls, or "
                        "the memory running out"))
                    continue
                finally:
                    conn.close()
                proc.join()
                if not ok:
                    raise out
                results[k] = out
    finally:
        for _, proc in running.values():
            proc.kill()


# ---- the call ----------------------------------------------------------------------------------------

def solve_many(models, scheme, *, dt: float, t_end: float, ground_motions=None, scales=None, variations=None,
               keep: str = "history", threads: int | None = None, processes: bool | None = None, client=None,
               progress: bool = True, **options) -> Batch:
    """Run many analyses and return their results in input order (a ``Batch``, a list).

    ``models``: a list of Models, or one Model with ``ground_motions`` (GroundMotion records that replace
    its ground accelerations' signal) and/or ``scales`` (factors on that signal: an IDA's intensity
    levels; every motion at every scale) and/or ``variations`` ({"storey1.k0": [values...], ...}: run k
    sets every listed parameter of the named effect to its k-th value; with motions and scales, every
    combination). ``scheme``: one scheme, or a list of one per run; ``t_end`` likewise (one end time, or a
    list of one per run: each record to its own end). ``keep``: "history" (each run's
    Result) or "peaks" (a RunSummary: memory stays bounded for 10^5 runs; the peaks are tracked over every
    step while the run saves only every ``save_every``-th state, by default at most 1000 states, and drops them). ``threads``: worker threads
    (default: every core); models that call Python go to as many processes instead (``processes=True``
    forces processes). ``client``: a ``dask.distributed.Client`` to send chunks of runs to (the same
    results as a local run). Other keywords go to ``solve()`` (``save_every``, ``dofs``, ``energy``, ...).
    A failed run keeps its status and message in its own result (``Batch.failed`` lists them). When a worker
    process dies (a force calling os._exit, a crash, the memory running out), the runs the pool lost are made
    again each in a process of its own: one that dies again gets a RunError saying so, the others their results.
    """
    if keep not in ("history", "peaks"):
        raise _checks.value_error("keep", f"expected 'history' or 'peaks', got {keep!r}")
    _check_options(options, keep)
    dt = _checks.number("dt", dt)
    t0 = _checks.number("t0", options.get("t0", 0.0))
    own_ends = None
    if isinstance(t_end, (list, tuple, np.ndarray)):  # one per run
        own_ends = [_checks.number(f"t_end[{k}]", x) for k, x in enumerate(t_end)]
        for k, x in enumerate(own_ends):
            try:
                _core.run_steps(t0, x, dt)
            except ArgumentError as exc:
                raise _checks.value_error(f"t_end[{k}]", exc.reason) from None
        t_end = max(own_ends) if own_ends else 0.0
    else:
        t_end = _checks.number("t_end", t_end)
        _core.run_steps(t0, t_end, dt)  # the core's checks, once for all
    if threads is not None:
        threads = _checks.integer("threads", threads, minimum=1, maximum=None)
    if processes is not None:
        processes = _checks.boolean("processes", processes)
    runs = _expand(models, ground_motions, scales, variations)
    schemes = list(scheme) if isinstance(scheme, (list, tuple)) else [scheme] * len(runs)
    if len(schemes) != len(runs):
        raise _checks.value_error("scheme", f"expected one scheme or {len(runs)} (one per run), got {len(schemes)}")
    if own_ends is not None and len(own_ends) != len(runs):
        raise _checks.value_error("t_end", f"expected one end time or {len(runs)} (one per run), got {len(own_ends)}")
    options = {**options, "dt": dt, "t_end": t_end}
    labels = []
    items = []
    for k, ((m, g, s, changes, label), sc) in enumerate(zip(runs, schemes)):
        label = {**label, "scheme": scheme_label(sc)}
        labels.append(label)
        items.append((m, g, s, changes, label, sc, {"t_end": own_ends[k]} if own_ends is not None else {}))
    workers = threads if threads is not None else max(1, os.cpu_count() or 1)
    uses_python = any(item[0]._core.has_python for item in items)
    to_processes = (workers > 1 or processes) and (processes if processes is not None else uses_python)
    if client is not None or to_processes:
        _check_picklable(items, single=isinstance(models, Model))
    bar = ProgressBar(enabled=bool(progress))
    results = [None] * len(items)
    try:
        if client is not None:
            _on_dask(client, items, keep, options, bar, results, labels)
        elif workers == 1 and not processes:
            _serially(items, keep, options, bar, results, labels)
        else:
            use_processes = processes if processes is not None else uses_python
            _on_pool(use_processes, workers, items, keep, options, bar, results, labels)
    except BrokenProcessPool:  # a worker process died: the pool lost every run it had not handed back
        try:
            _rerun_apart([k for k, r in enumerate(results) if r is None], items, keep, options, results, workers)
        except KeyboardInterrupt as exc:
            raise _interrupted(results, labels, exc) from None
        bar(len(items), len(items))
    finally:
        bar.close()
    return Batch(results, labels)


def _check_options(options: dict, keep: str) -> None:
    """The keywords solve_many hands to solve(): each a keyword of solve() (a misspelt one is refused naming it,
    not handed to every run to fail in), the settings that do not depend on the model checked once here."""
    check_option_names(options, also=("t0", "u0", "v0"))
    if "throw" in options:
        raise _checks.value_error("throw", "solve_many never raises for a run's failure: each result keeps its status "
                                           "(Batch.failed lists the runs that failed)")
    if keep == "peaks" and options.get("dofs") is not None:
        raise _checks.value_error("dofs", 'keep="peaks" keeps the peak and the final state of every DOF; dofs '
                                          'chooses the DOFs of keep="history"')
    check_settings({k: v for k, v in options.items() if k not in ("t0", "u0", "v0")})


def _serially(items, keep, options, bar, results, labels):
    for k, item in enumerate(items):
        try:
            results[k] = _run_one(*item, keep, options)
        except KeyboardInterrupt as exc:
            results[k] = _partial(item, keep, options, exc)
            raise _interrupted(results, labels, exc) from None
        bar(k + 1, len(items))


def _on_pool(use_processes, workers, items, keep, options, bar, results, labels):
    """Chunks of runs on a pool of threads or processes. On Ctrl-C (KeyboardInterrupt in this thread) the
    running runs are told to stop (a StopToken for threads; SIGINT, which the workers turn into their
    token, for processes), the chunks not started are cancelled, and what was done is handed back."""
    # chunks: a few per worker, so that the pool's per-task cost is spread and the load balances
    size = max(1, math.ceil(len(items) / (4 * workers)))
    chunks = [list(range(k, min(k + size, len(items)))) for k in range(0, len(items), size)]
    stop = None if use_processes else StopToken()
    if use_processes:
        pool = cf.ProcessPoolExecutor(max_workers=workers, initializer=_init_worker)
    else:
        pool = cf.ThreadPoolExecutor(max_workers=workers)
    futures = {}
    done = 0

    def take(fut):
        nonlocal done
        for k, r in zip(futures[fut], fut.result()):
            results[k] = r
        done += len(futures[fut])

    try:
        for chunk in chunks:
            futures[pool.submit(_run_chunk, [items[k] for k in chunk], keep, options, stop)] = chunk
        for fut in cf.as_completed(futures):
            take(fut)
            bar(done, len(items))
    except KeyboardInterrupt as exc:
        if stop is not None:
            stop.set()
        for fut in futures:
            fut.cancel()
        if use_processes:
            _stop_workers(pool)
        finished, _ = cf.wait([f for f in futures if not f.cancelled()], timeout=_STOP_WAIT)
        for fut in finished:
            if fut.exception() is None:
                take(fut)
        raise _interrupted(results, labels, exc) from None
    except BrokenProcessPool:  # keep what finished before the worker died; the caller makes the rest again
        for fut in futures:
            if fut.done() and not fut.cancelled() and fut.exception() is None:
                take(fut)
        _kill_workers(pool)
        pool.shutdown(wait=False, cancel_futures=True)
        raise
    except BaseException:
        if use_processes:  # no worker survives the call: one that did not stop in _STOP_WAIT is killed
            pool.shutdown(wait=False, cancel_futures=True)
            _kill_workers(pool)
        raise
    finally:
        pool.shutdown(wait=True, cancel_futures=True)


_STOP_WAIT = 5.0  # s: how long the runs told to stop have to hand back their partial results


def _run_chunk_dask(items, keep, options, event_name):
    """A chunk on a Dask worker: its runs under a StopToken that a watcher thread sets when the client
    sets the Dask Event ``event_name`` (the client's Ctrl-C: Dask does not stop a running task)."""
    import threading

    from distributed import Event

    event = Event(event_name)  # here, in the task's thread, where the worker's client is found
    if event.is_set():
        return [None] * len(items)
    stop = StopToken()
    ended = threading.Event()

    def watch():
        while not ended.is_set():
            try:
                if event.wait(timeout=0.2):
                    stop.set()
                    return
            except Exception:  # the scheduler went away: nobody is left to ask for a stop
                return

    watcher = threading.Thread(target=watch, daemon=True)
    watcher.start()
    try:
        return _run_chunk(items, keep, options, stop)
    finally:
        ended.set()
        watcher.join()


def _on_dask(client, items, keep, options, bar, results, labels):
    """Chunks of runs as Dask tasks (their models pickled), gathered in input order."""
    import uuid

    from distributed import Event

    workers = max(1, len(client.scheduler_info().get("workers", {})) or 1)
    size = max(1, math.ceil(len(items) / (4 * workers)))
    starts = list(range(0, len(items), size))
    event_name = f"nvib-stop-{uuid.uuid4().hex}"
    futures = client.map(_run_chunk_dask, [items[k:k + size] for k in starts], keep=keep, options=options,
                         event_name=event_name, pure=False)
    pending = dict(zip(futures, starts))
    try:
        for fut in futures:
            part = fut.result()
            for j, r in enumerate(part):
                results[pending[fut] + j] = r
            bar(pending.pop(fut) + len(part), len(items))
    except KeyboardInterrupt as exc:
        # every chunk returns soon once the event is set: the runs under way stop at their next poll and
        # hand back their partial results, the chunks not started return at once
        Event(event_name, client=client).set()
        deadline = time.monotonic() + _STOP_WAIT
        for fut, start in list(pending.items()):
            try:
                part = fut.result(timeout=max(0.01, deadline - time.monotonic()))
            except Exception:  # not back in time, or failed: those runs are not handed back
                fut.cancel()
                continue
            for j, r in enumerate(part):
                results[start + j] = r
        raise _interrupted(results, labels, exc) from None
