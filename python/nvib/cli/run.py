"""nvib run SCENE: integrate a scene with one scheme, print a summary, optionally save and plot the run."""

from __future__ import annotations

import argparse
import importlib.util
import math
import sys
import time
from collections import Counter

from . import _common as c
from .._io import FORMATS

OUT_FORMATS = FORMATS
MAX_SAVED = 200_000  # default cap on saved states; --save-every overrides
STOREY_RECORD_BYTES = 256e6  # the most that recording the storeys for --plot may add to a run's memory
RUN_FLAGS = {"dt": "--dt", "tol": "--tol", "t_end": "--t-end", "save_every": "--save-every", "max_displacement": "--max-displacement",
             "max_energy_error": "--max-energy-error", "without": "--without", "scene": "SCENE", "dofs": "--dof",
             "collapse_deformation": "--collapse-deformation", "record": "--record-effect", "energy": "--energy",
             "ground_motion": "--record"}

EPILOG = """\
Scheme parameters accept fractions (--eta 1/12). Exit status: 0 success (also a structure that
collapsed: the summary says which effect), 1 the run failed (diverged, Newton failed; partial
--out/--plot still written), 2 bad input, 130 interrupted (Ctrl-C; --out holds the partial history
when the core hands it over, and stderr says which).

examples:
  nvib run hardening --scheme newmark --plot hardening.png
  nvib run vehicle --without contact --dof z_w1 --energy --out vehicle.npz
  nvib run building --scheme galpha --rho-inf 0.8 --dt 1e-3 --save-every 10 --out building.csv
  nvib run building_inelastic --scheme newmark --measure storey1 --plot storey1.png
  nvib run building_inelastic --record RSN953_NORTHR_MUL009.AT2 --sa 0.9 0.5   # Sa(0.9 s, 5 %) = 0.5 g
"""


def add_parser(sub) -> None:
    from .. import schemes
    p = sub.add_parser("run", help="integrate a scene and summarise, save or plot the run",
                       usage="%(prog)s SCENE [--scheme NAME] [scheme parameters] [--dt DT] [--t-end T] "
                             "[--without NAME ...] [--dof NAME] [--energy] [--out FILE] [--plot PNG] [...]",
                       description="Integrate a scene (a built-in name or a .toml file) with one scheme.",
                       epilog=EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("scene", metavar="SCENE", help="built-in scene name (see nvib scenes) or path to a .toml scene")
    g = p.add_argument_group("scheme")
    keys = list(schemes())
    g.add_argument("--scheme", choices=keys, default="cemdts",
                   help="time-stepping scheme: " + ", ".join(f"{k} ({cls.__name__})" for k, cls in schemes().items())
                        + " (default cemdts)")
    c.add_scheme_options(g)
    g = p.add_argument_group("run")
    g.add_argument("--dt", type=c.positive_real, help="time step [s] (default: the scene's)")
    g.add_argument("--tol", type=c.positive_real, metavar="TOL",
                   help="adaptive steps: choose each step so that the estimated error stays within TOL of each "
                        "DOF's peak; --dt is then the first step (and an explicit scheme's longest)")
    g.add_argument("--t-end", type=c.positive_real, metavar="T", help="end time [s] (default: the scene's)")
    g.add_argument("--save-every", type=c.positive_int, metavar="K",
                   help=f"save every K-th step (default 1, or more to keep at most {MAX_SAVED} states)")
    g.add_argument("--without", nargs="+", action="extend", metavar="NAME",
                   help="leave out effects by name or type (repeatable)")
    g.add_argument("--max-displacement", type=c.bound, metavar="U",
                   help="stop as diverged once some |u_i| exceeds U (default: 1e10 x max(1, max|u0|, "
                        "max|v0| x duration, the static displacement of the loads); 'inf': only non-finite "
                        "states)")
    g.add_argument("--dof", metavar="NAME", help="DOF to report and plot (default: the scene's plot_dof)")
    g.add_argument("--measure", metavar="EFFECT",
                   help="plot the measure d = g . u of the effect of this name (a storey drift: --measure storey2) "
                        "instead of the DOF's displacement, and its force-deformation loop (the effect is recorded)")
    g.add_argument("--record-effect", nargs="+", action="extend", metavar="NAME", dest="record",
                   help="record these effects (measure, rate, force, internal variables) into --out and the "
                        "summary (default: the scene's record list)")
    g.add_argument("--collapse-deformation", type=c.positive_real, metavar="D",
                   help="collapse (status collapsed, the run stops) once an effect with memory deforms beyond D "
                        "(default: the scene's; a law that loses its strength always collapses)")
    g.add_argument("--energy", action="store_true",
                   help="record the energy balance; a run whose balance error exceeds --max-energy-error times "
                        "the energy scale stops as diverged")
    g.add_argument("--max-energy-error", type=c.bound, metavar="F",
                   help="with --energy: stop as diverged once the energy balance error exceeds F times the energy "
                        "scale (default 0.5; 'inf': no check)")
    g = p.add_argument_group("ground motion")
    g.add_argument("--record", metavar="FILE", dest="ground_record",
                   help="run the scene under this record (a PEER .AT2 file in g, or a text file of one column with "
                        "--record-dt or two columns t, a) in place of its own ground motion")
    g.add_argument("--record-dt", type=c.positive_real, metavar="DT", help="the sample step of a one-column --record [s]")
    g.add_argument("--record-units", choices=("g", "m/s^2"),
                   help="what a plain --record file's values are in (an AT2 file is in g)")
    how = g.add_mutually_exclusive_group()
    how.add_argument("--scale", type=c.real, metavar="S", help="multiply the --record by S")
    how.add_argument("--sa", type=c.positive_real, nargs=2, metavar=("T1", "VALUE"),
                     help="scale the --record so that its exact pseudo-spectral acceleration at the period T1 [s] "
                          "is VALUE (in the record's unit: g for an AT2 file)")
    g.add_argument("--sa-damping", type=c.real, default=0.05, metavar="Z",
                   help="the damping ratio of --sa (default 0.05)")
    g = p.add_argument_group("output")
    g.add_argument("--out", metavar="FILE", help=f"write the history to FILE{' or FILE'.join(OUT_FORMATS)} "
                                                 "(.nc: netCDF, needs xarray)")
    g.add_argument("--plot", metavar="PNG",
                   help="write histories, phase locus (and energy) to this PNG; under a ground motion, a_g(t) below "
                        "the response; for a scene with [storeys], the peak drift ratio over the height and the loop "
                        "of the critical storey (every storey is then recorded, and --out holds them too)")
    g.add_argument("--progress", action=argparse.BooleanOptionalAction, default=None,
                   help="progress bar on stderr for runs over a second (default: when stderr is a terminal)")
    p.set_defaults(func=lambda args, parser: c.run_checked(run, args, parser), subparser=p)


def effect_summary(model) -> str:
    if not model.effects:
        return "(none)"
    counts = Counter(e.type for e in model.effects)
    return ", ".join(k if n == 1 else f"{k} x{n}" for k, n in counts.items())


def ground_motion(args):
    """(the --record as given, scaled by --scale or to --sa, a line for the summary, its name and scaling for
    the figure's title), or (None, None, None)."""
    from .. import GroundMotion, RecordError

    record = args.ground_record
    given = [f for f, v in (("--record-dt", args.record_dt), ("--record-units", args.record_units),
                            ("--scale", args.scale), ("--sa", args.sa)) if v is not None]
    if record is None:
        if given:
            raise c.Usage(given[0], "it applies to a --record; give --record FILE too")
        return None, None, None
    if not 0.0 <= args.sa_damping < 1.0:
        raise c.Usage("--sa-damping", f"expected 0 <= damping < 1, got {args.sa_damping:g}")
    try:
        gm = GroundMotion.from_file(record, dt=args.record_dt, units=args.record_units or "")
    except RecordError as exc:
        raise c.Usage("--record", str(exc)) from None
    except ValueError as exc:
        raise c.usage_from(exc, {"dt": "--record-dt", "units": "--record-units"}, default="--record") from None
    if gm.units not in ("g", "m/s^2"):
        raise c.Usage("--record-units", f"the unit of {record}'s values is not known (the scenes are in m/s^2): "
                                        "give --record-units g or m/s^2")
    text = f"{gm.label} ({gm.name}): {len(gm)} samples, " + (f"dt = {gm.dt:g} s, " if gm.dt else "") + \
        f"{gm.duration:g} s, PGA {gm.pga:.4g} {gm.units}"
    figure = gm.name
    if args.scale is not None:
        gm = gm.scaled(args.scale)
        text += f"; scaled by {args.scale:g}: PGA {gm.pga:.4g} {gm.units}"
        figure += f" x {args.scale:g}"
    elif args.sa is not None:
        period, value = args.sa
        before = float(gm.psa([period], args.sa_damping)[0])
        try:
            gm, factor = gm.scaled_to_sa(period, value, damping=args.sa_damping)
        except ValueError as exc:
            raise c.Usage("--sa", str(exc).removeprefix("period: ")) from None
        text += (f"; scaled by {factor:.6g} to Sa(T1 = {period:g} s, {100 * args.sa_damping:g} %) = {value:g} "
                 f"{gm.units} (was {before:.4g} {gm.units}): PGA {gm.pga:.4g} {gm.units}")
        figure += f" x {factor:.4g}: Sa(T1 = {period:g} s, {100 * args.sa_damping:g} %) = {value:g} {gm.units}"
    return gm, text, figure


def load_model(args, ground=None):
    from .. import load_scene

    try:
        return load_scene(args.scene, without=args.without or (), ground_motion=ground)
    except OSError as exc:  # a missing file
        raise c.Usage("SCENE", str(exc).removeprefix("scene: ")) from None
    except ValueError as exc:  # unknown name, malformed scene, unknown --without
        raise c.usage_from(exc, RUN_FLAGS, default="SCENE") from None


def run(args) -> int:
    from .. import Status, _core, solve
    from .._progress import ProgressBar

    if args.out is not None:
        c.check_output("--out", args.out, OUT_FORMATS)
        if args.out.lower().endswith(".nc") and importlib.util.find_spec("xarray") is None:
            raise c.Usage("--out", 'a .nc file needs xarray, which is not installed: pip install "nvib[xarray]"')
    if args.plot is not None:
        c.check_output("--plot", args.plot, c.PLOT_FORMATS)
    scheme = c.make_scheme(args.scheme, args)
    ground, ground_text, ground_title = ground_motion(args)
    model = load_model(args, ground)
    args.ground_text = ground_text
    dof = args.dof if args.dof is not None else model.scene["plot_dof"]
    if dof not in model.dofs:
        raise c.Usage("--dof", f"unknown DOF {dof!r} in scene {model.scene['name']!r} (DOFs: {', '.join(model.dofs)})")
    named = sorted({e.name for e in (model.effects or []) if e.name} | {a.name for a in model.effect_arrays if a.name})
    if args.measure is not None:
        if args.measure not in named:
            raise c.Usage("--measure", f"no effect named {args.measure!r} in scene {model.scene['name']!r} "
                                       f"(named effects: {', '.join(named) or 'none'})")
        if not args.plot:
            raise c.Usage("--measure", "it chooses what --plot draws; give --plot too")
    record = list(args.record) if args.record else list(model.scene.get("record") or [])
    for name in record:
        if name not in named:
            raise c.Usage("--record-effect", f"no effect named {name!r} in scene {model.scene['name']!r} "
                                             f"(named effects: {', '.join(named) or 'none'})")
    if args.measure is not None and args.measure not in record:
        record.append(args.measure)
    collapse = (args.collapse_deformation if args.collapse_deformation is not None
                else model.scene.get("collapse_deformation"))
    dt = args.dt if args.dt is not None else model.scene["dt"]
    t_end = args.t_end if args.t_end is not None else model.scene["t_end"]
    if dt is None:
        raise c.Usage("--dt", f"the scene {model.scene['name']!r} sets no dt; give --dt")
    if t_end is None:
        raise c.Usage("--t-end", f"the scene {model.scene['name']!r} sets no t_end; give --t-end")
    if ground is not None and ground.t[-1] > t_end:
        model.scene["notes"].append(f"the --record lasts until t = {ground.t[-1]:g} s, the run ends at "
                                    f"{t_end:g} s (--t-end)")
    try:
        n_steps = _core.run_steps(0.0, t_end, dt)
    except (ValueError, OverflowError) as exc:
        raise step_error(exc, args, model) from None
    save_every = args.save_every if args.save_every is not None else max(1, math.ceil(n_steps / MAX_SAVED))
    args.summary_records = list(record)
    if args.plot and model.scene.get("storeys"):
        record += storeys_to_record(model, record, n_steps // save_every + 1 + (n_steps % save_every != 0))

    for note in model.scene["notes"]:
        print(f"note: {note}", file=sys.stderr)
    show = args.progress if args.progress is not None else c.isatty(sys.stderr)
    bar = ProgressBar(sys.stderr, enabled=show)
    t0 = time.perf_counter()
    try:
        res = solve(model, scheme, dt=dt, t_end=t_end, save_every=save_every, throw=False,
                    max_displacement=args.max_displacement, progress=bar if show else None, energy=args.energy,
                    max_energy_error=args.max_energy_error, record=record, collapse_deformation=collapse,
                    tol=args.tol)
    except KeyboardInterrupt as exc:
        bar.close(done=False)
        res = getattr(exc, "result", None)  # the history saved before the interrupt (none before the loop)
        if not args.out:
            note = ""
        elif res is None:
            note = f"; it stopped before the first step, {args.out} not written"
        elif write_out(res, model, t_end, save_every, args):
            note = f"; the partial history{reached(res, ' up to')} is in {args.out}"
        else:
            note = ""  # write_out said why
        print(f"nvib run: interrupted{note}", file=sys.stderr)
        return 130
    except (ValueError, TypeError) as exc:
        bar.close(done=False)
        raise c.usage_from(exc, RUN_FLAGS) from None
    elapsed = time.perf_counter() - t0
    bar.close(done=res.success)

    print_summary(res, model, scheme, dof, dt, t_end, save_every, elapsed, args)
    code = 0
    if args.out and not write_out(res, model, t_end, save_every, args):
        code = 1
    if args.plot:
        from ..plot import default_title, plot_run

        title = None if ground is None else default_title(res, model, ground=ground_title)
        try:
            plot_run(res, model, dof, args.plot, title, measure=args.measure, collapse_deformation=collapse,
                     ground_units=None if ground is None else ground.units)
            print(f"wrote {args.plot}")
        except OSError as exc:
            print(f"nvib run: error: --plot: cannot write {args.plot!r}: {exc.strerror or exc}", file=sys.stderr)
            code = 1
    if not res.success and res.status != Status.collapsed:
        kept = f"; the partial history{reached(res, ' up to')} is in {args.out}" if args.out and code == 0 else ""
        print(f"nvib run: error: {failure_line(res, scheme, dt)}{kept}", file=sys.stderr)
        return 1
    return code


def storeys_to_record(model, record: list, n_saved: int) -> list[str]:
    """The storeys --plot records beside ``record``: every one, so that the loop of the critical storey (known
    only after the run) can be drawn, unless they would add more than STOREY_RECORD_BYTES (or a quarter of
    the memory available) to the run: then none, with a note on stderr."""
    from .. import _core

    laws = _core.laws()
    storeys = set(model.scene["storeys"])
    extra = [e for e in model.effects or [] if e.name in storeys and e.name not in record and e.type in laws]
    names = list(dict.fromkeys(e.name for e in extra))
    per_state = sum(8.0 * (3 + len(laws[e.type]["state"])) for e in extra)  # measure, rate, force, state
    need = per_state * n_saved
    available = _core.available_memory()
    if need <= STOREY_RECORD_BYTES and (available <= 0 or need <= 0.25 * available):
        return names
    print(f"note: --plot does not record the storeys ({need / 1e6:.3g} MB for {n_saved} saved states): the "
          "figure draws the loop of the critical storey only if it is recorded (--record-effect NAME, or a larger "
          "--save-every)", file=sys.stderr)
    return []


def write_out(res, model, t_end: float, save_every: int, args) -> bool:
    """Writes --out (the whole or the partial history); False, with the error on stderr, if it cannot."""
    import numpy as np

    extra = {"scene": model.scene["name"], "t_end": t_end, "save_every": save_every,
             "without": np.array(list(args.without or []), dtype=str)}
    try:  # netCDF goes through xarray (checked to be there before the run) and holds no extra entries
        res.save(args.out, None if args.out.lower().endswith(".nc") else extra)
    except OSError as exc:
        print(f"nvib run: error: --out: cannot write {args.out!r}: {exc.strerror or exc}", file=sys.stderr)
        return False
    print(f"wrote {args.out}")
    return True


def reached(res, prefix: str = " at") -> str:
    """' at t = 1.25 s', the time of the last saved state ('' when none was saved)."""
    return f"{prefix} t = {res.t[-1]:g} s" if len(res.t) else ""


def step_error(exc: Exception, args, model) -> c.Usage:
    """An error of the step count (dt, t_end): it names the flag when the user gave --dt or --t-end, else the
    scene file and its key, since the value came from the scene."""
    argument = getattr(exc, "argument", None) or "dt"
    given = [n for n in ("dt", "t_end") if getattr(args, n) is not None]
    if given:  # the ratio t_end/dt is at fault: the value the user changed is the one to look at
        blamed = [n for n in argument.split(", ") if n in given] or given
        return c.Usage("/".join(RUN_FLAGS[n] for n in blamed), str(exc).removeprefix(argument + ": "))
    return c.Usage("SCENE", f"{model.scene['path']}: [scene] {exc}")


def failure_line(result, scheme, dt: float) -> str:
    """What failed, with which scheme and step, and what to try."""
    from .. import Status

    f = result.failure
    hints = {
        Status.diverged: "try a smaller --dt" + (" or an implicit scheme" if scheme.is_explicit else ""),
        Status.newton_failed: "try a smaller --dt" + ("" if getattr(scheme, "iteration", "newton") == "newton"
                                                     else " or --iteration newton"),
        Status.singular_matrix: "try a smaller --dt",
    }
    hint = hints.get(result.status, "")
    return f"{f.message} (with {scheme.name}, dt = {dt:g} s)" + (f"; {hint}" if hint else "")


def effect_line(rec, res, model) -> str:
    """A recorded effect in one line: its peak and final deformation and force, what it dissipated."""
    import numpy as np

    from ..plot import _energy_unit, _force_unit, _unit_of

    e = next((x for x in (model.effects or []) if x.name == rec.name), None)
    unit = _unit_of([model.units[int(i)] for i in e.index]) if e is not None else "units"
    d, f = np.asarray(rec.measure), np.asarray(rec.force)
    if not d.size:
        return f"{rec.type}: nothing saved"
    text = (f"{rec.type}: peak |d| {np.abs(d).max():.4g} {unit}, final d {float(d.reshape(len(d), -1)[-1, 0]):.4g} {unit}, "
            f"peak |f| {np.abs(f).max():.4g} {_force_unit(unit)}")
    if "dissipated" in rec.state:
        text += f", dissipated {float(np.asarray(rec.state['dissipated']).sum(axis=-1)[-1] if rec.count > 1 else rec.state['dissipated'][-1]):.4g} {_energy_unit(res.units)}"
    return text + (f" ({rec.count} effects)" if rec.count > 1 else "")


def print_summary(res, model, scheme, dof, dt, t_end, save_every, elapsed, args) -> None:
    import numpy as np

    from .._model import rate_unit

    s = model.scene
    stats = res.stats.as_dict()
    title = f"{s['name']}: {s['title']}" if s.get("title") else s["name"]
    lines = [("scene", title)]
    if args.without:
        lines.append(("without", ", ".join(args.without)))
    if getattr(args, "ground_text", None):
        lines.append(("record", args.ground_text))
    lines.append(("scheme", repr(scheme)))
    saved = f"{len(res.t)} state{'s' if len(res.t) != 1 else ''} saved"
    if save_every > 1:
        saved += f" (every {save_every} steps)"
    if args.tol:
        h = np.diff(res.t) if save_every == 1 and len(res.t) > 1 else None
        span = f", from {h.min():.3g} to {h.max():.3g} s" if h is not None else ""
        lines.append(("steps", f"{stats['num_steps']} adaptive (first {dt:g} s{span}), t_end = {t_end:g} s; {saved}"))
    else:
        lines.append(("steps", f"{stats['num_steps']} of {res.num_steps_requested}, dt = {dt:g} s, "
                               f"t_end = {t_end:g} s; {saved}"))
    lines.append(("status", res.status.name))
    lines.append(("wall time", f"{c.seconds(elapsed)} (integrator loop {c.seconds(stats['wall_time'])})"))
    counters = [(k.removeprefix("num_"), v) for k, v in stats.items()
                if k not in ("wall_time", "num_steps", "linear_solver")]
    lines.append(("counters", ", ".join(f"{k} {v}" for k, v in counters)))
    if stats["linear_solver"]:
        lines.append(("linear solver", f"{stats['linear_solver']} ({model.n} DOFs)"))
    if len(res.t):
        j = res.dofs.index(dof)
        u, v, a = (float(x[-1, j]) + 0.0 for x in (res.u, res.v, res.a))  # + 0.0: no "-0"
        unit = res.units[j]
        lines.append((f"final {dof}", f"t = {res.t[-1]:.6g} s: u = {u:.9g} {unit}, v = {v:.9g} {rate_unit(unit, 1)}, "
                                      f"a = {a:.9g} {rate_unit(unit, 2)}"
                                      + (" (relative to the ground)" if res.relative_to_ground else "")))
    est = res.error_estimate
    if est is not None:
        how = (f"measured against a companion run on double steps; adaptive, tol {args.tol:g}: "
               f"{stats['num_check_steps']} companion steps, {stats['num_rejected_steps']} retaken, "
               f"{stats['num_events']} landed on events, {stats['num_restarts']} restarts") if args.tol else \
            "estimated from the steps"
        lines.append(("error estimate", f"{est.max:.2g} of the peak of {est.dof} (max |u - u_exact| / max |u|, "
                                        f"{how})" if est.available else
                      "not available for this scheme (nvib cost measures its error)"))
    if res.energy is not None:
        rel = res.energy.relative_balance_error()
        lines.append(("energy", f"relative balance error {rel:.3e} (max |K + P + D + H - W - E0| / max energy)"
                      if math.isfinite(rel) else "relative balance error: n/a (the energies overflowed)"))
    asked = getattr(args, "summary_records", None)
    for name, rec in res.effects.items():
        if asked is None or name in asked:  # not the storeys recorded only for --plot
            lines.append((name, effect_line(rec, res, model)))
    lines += [("warning", w) for w in res.warnings]
    w = max(len(k) for k, _ in lines)
    print("\n".join(f"{k:<{w}}  {v}" for k, v in lines))
