"""nvib ida: incremental dynamic analysis of a scene under records, traced to collapse."""

from __future__ import annotations

import argparse
import sys

from . import _common as c

FLAGS = {"records": "RECORDS", "levels": "--levels", "im": "--im", "period": "--period", "damping": "--damping",
         "dt": "--dt", "tail": "--tail", "drift_limit": "--drift-limit", "slope_limit": "--slope-limit",
         "tolerance": "--tolerance", "max_runs": "--max-runs", "start": "--start", "step": "--step",
         "ceiling": "--ceiling", "measure": "--measure", "storeys": "SCENE", "scene": "SCENE"}


def _levels(text: str):
    try:
        values = [float(x) for x in text.split(",")]
        if not values or not all(0 < x < float("inf") for x in values):
            raise ValueError
        return values
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected L1,L2,... positive intensity levels, got {text!r}") from None


def add_parser(sub) -> None:
    from .. import schemes

    p = sub.add_parser("ida", help="incremental dynamic analysis of a scene under records, to collapse",
                       description="Incremental dynamic analysis (Vamvatsikos & Cornell 2002): the scene under each "
                                   "record scaled to rising levels of Sa(T1) (or PGA), each record traced by hunt and "
                                   "fill to its collapse; the demand is the maximum interstorey drift ratio (the "
                                   "scene's [storeys]). Prints each record's collapse capacity and cause and the "
                                   "fractiles; --out writes every run (read by nvib fragility).",
                       epilog="example:\n  nvib ida building_collapse rec1.AT2 rec2.AT2 rec3.AT2 --im sa --period 0.83 "
                              "--out ida.csv --plot ida.png",
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("scene", metavar="SCENE", help="built-in scene name or path to a .toml scene with ground motion")
    p.add_argument("records", metavar="RECORDS", nargs="+", help="record files (PEER .AT2 in g, or text files)")
    p.add_argument("--record-dt", type=c.positive_real, metavar="DT", help="the sample step of one-column records [s]")
    p.add_argument("--record-units", choices=("g", "m/s^2"), help="what plain record files' values are in")
    g = p.add_argument_group("intensity")
    g.add_argument("--im", choices=("sa", "pga", "scale"), default="sa",
                   help="intensity measure: Sa(T1) (exact, default), PGA or the records' scale factor")
    g.add_argument("--period", "--periods", type=c.positive_real, metavar="T1", dest="period",
                   help="T1 of Sa(T1) [s] (default: the scene's first period, linearised at rest)")
    g.add_argument("--damping", type=c.real, default=0.05, help="damping ratio of Sa(T1) (default 0.05)")
    g.add_argument("--levels", type=_levels, help="L1,L2,...: run every record at these levels (stripes) instead "
                                                  "of tracing each to collapse")
    g.add_argument("--start", type=c.positive_real, help="first level of the hunt (default a tenth of the records' "
                                                         "median intensity)")
    g.add_argument("--step", type=c.positive_real, help="first step of the hunt (default --start)")
    g.add_argument("--ceiling", type=c.positive_real, help="highest level tried (default 20 times the median)")
    g.add_argument("--tolerance", type=c.positive_real, default=0.05,
                   help="relative width each collapse is bracketed to (default 0.05)")
    g.add_argument("--max-runs", type=c.positive_int, default=16, help="runs per record at most (default 16)")
    g = p.add_argument_group("collapse and runs")
    g.add_argument("--drift-limit", type=c.positive_real, default=10.0, metavar="PERCENT",
                   help="drift ratio that counts as collapse [%%] (default 10)")
    g.add_argument("--slope-limit", type=c.positive_real, default=0.2,
                   help="dynamic instability: the curve's slope below this fraction of its elastic slope (0.2)")
    g.add_argument("--tail", type=c.real, metavar="SECONDS", help="free vibration after each record (default 2 T1)")
    g.add_argument("--scheme", choices=list(schemes()), default="cemdts", help="the scheme (default cemdts)")
    g.add_argument("--dt", type=c.positive_real, help="time step [s] (default: the scene's)")
    g.add_argument("--no-check", action="store_true", help="do not check each run at half the step")
    g.add_argument("--measure", help="demand instead of the drift ratio: peak_drift, peak_u or an effect's name")
    g = p.add_argument_group("output")
    g.add_argument("--out", metavar="CSV", help="write every run to this CSV (nvib fragility reads it)")
    g.add_argument("--plot", metavar="PNG", help="write the IDA curves to this PNG")
    g.add_argument("--fragility", metavar="PNG", help="write the collapse fragility fitted to the capacities")
    g.add_argument("--progress", action=argparse.BooleanOptionalAction, default=None,
                   help="progress bar (default: when the standard error is a terminal)")
    p.set_defaults(func=lambda args, parser: c.run_checked(run, args, parser), subparser=p)


def run(args) -> int:
    from .. import GroundMotion, RecordError, fragility, ida, load_scene, schemes

    for arg, path in (("--out", args.out), ("--plot", args.plot), ("--fragility", args.fragility)):
        if path is not None:
            c.check_output(arg, path, (".csv",) if arg == "--out" else c.PLOT_FORMATS)
    try:
        model = load_scene(args.scene)
    except (ValueError, TypeError, FileNotFoundError) as exc:
        raise c.Usage("SCENE", str(exc)) from None
    records = []
    for path in args.records:
        try:
            records.append(GroundMotion.from_file(path, dt=args.record_dt, units=args.record_units or ""))
        except RecordError as exc:
            raise c.Usage("RECORDS", str(exc)) from None
        except ValueError as exc:
            raise c.usage_from(exc, {"dt": "--record-dt", "units": "--record-units"}, default="RECORDS") from None
        if records[-1].units not in ("g", "m/s^2"):
            raise c.Usage("--record-units", f"the unit of {path}'s values is not known (the scenes are in m/s^2): "
                                            "give --record-units g or m/s^2")
    dt = args.dt if args.dt is not None else model.scene.get("dt")
    if dt is None:
        raise c.Usage("--dt", f"the scene {model.scene['name']!r} sets no dt; give --dt")
    scheme = schemes()[args.scheme]()
    progress = c.isatty(sys.stderr) if args.progress is None else args.progress
    try:
        res = ida(model, records, args.levels, im=args.im, period=args.period, damping=args.damping, dt=dt,
                  measure=args.measure, scheme=scheme, tail=args.tail, drift_limit=args.drift_limit / 100.0,
                  slope_limit=args.slope_limit, tolerance=args.tolerance, start=args.start, step=args.step,
                  max_runs=args.max_runs, ceiling=args.ceiling, check=not args.no_check, progress=progress)
    except (ValueError, TypeError) as exc:
        raise c.usage_from(exc, FLAGS) from None
    print(f"IDA of {model.scene['name']} under {len(records)} records: {res.im_name} [{res.im_unit}] against "
          f"{res.measure_name} [{res.measure_unit}], {res.scheme}, dt = {res.dt:g} s; {res.runs} runs "
          f"(with the half-step checks) in {c.seconds(res.wall_time)}")
    print(res.markdown())
    print(res.estimate_summary())
    caps = res.capacities
    if caps.size:
        print(f"collapse capacity: median {res.capacity_fractile(50):.4g}, 16 % {res.capacity_fractile(16):.4g}, "
              f"84 % {res.capacity_fractile(84):.4g} {res.im_unit} (records that never collapsed count as above)")
    for w in res.warnings:
        print(f"warning: {w}")
    code = max(c.write_output("ida", "--out", args.out, res.to_csv), c.write_output("ida", "--plot", args.plot, res.plot))
    if args.fragility is not None:
        try:
            f = fragility.from_ida(res)
        except ValueError as exc:  # no record collapsed: no collapse fragility
            print(f"nvib ida: error: --fragility: {exc}", file=sys.stderr)
            return 1
        print(fragility.markdown_table([f]))
        code = max(code, c.write_output("ida", "--fragility", args.fragility, f.plot))
    return code
