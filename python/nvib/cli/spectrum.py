"""nvib spectrum: the response spectrum of a ground-motion record file: elastic (exact, the default, or
integrated by a scheme) or inelastic (constant ductility with --ductility, constant strength with
--strength-ratio: nvib.inelastic_spectrum)."""

from __future__ import annotations

import argparse
import math
import sys

from . import _common as c


MAX_PERIODS = 1_000_000  # COUNT of FIRST:LAST:COUNT: each period is a run


def periods(text: str):
    """FIRST:LAST:COUNT (log-spaced) or a comma-separated list of periods in seconds, each finite and > 0."""
    import numpy as np

    try:
        if ":" in text:
            first, last, count = text.split(":")
            lo, hi, n = float(first), float(last), int(count)
            if not (0 < lo < hi < math.inf and 2 <= n <= MAX_PERIODS):
                raise ValueError
            return np.geomspace(lo, hi, n)
        values = np.array([float(x) for x in text.split(",")])
        if values.size == 0 or not np.all((values > 0) & (values < math.inf)):
            raise ValueError
        return values
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected FIRST:LAST:COUNT (0 < FIRST < LAST, 2 <= COUNT <= {MAX_PERIODS}, "
                                         f"log-spaced) or a list T1,T2,... of finite positive periods in s, "
                                         f"got {text!r}") from None


FLAGS = {"periods": "--periods", "accuracy": "--accuracy", "damping": "--damping", "scheme": "--scheme",
         "record": "record"}
INELASTIC_FLAGS = {**FLAGS, "ductility": "--ductility", "R": "--strength-ratio", "law": "--law",
                   "law.b": "--hardening", "law.alpha": "--hardening"}
HARDENING = {"bilinear": "b", "bouc_wen": "alpha"}  # --hardening: the law's post-yield stiffness ratio


def add_parser(sub) -> None:
    from .. import schemes

    keys = list(schemes())
    p = sub.add_parser("spectrum", help="response spectrum of a ground-motion record",
                       description="Response spectrum of a record (a PEER .AT2 file, or a text file of one column "
                                   "with --dt or two columns t, a): Sd, Sv, pseudo-Sv, pseudo-Sa and the absolute Sa "
                                   "for each period, exact (closed form, peaks between samples); with --scheme, "
                                   "integrated by that scheme, with the accuracy reached against the exact peaks. "
                                   "With --ductility or --strength-ratio, the inelastic spectrum of a hysteretic "
                                   "SDOF (Chopra, Dynamics of Structures, 7.2-7.5): the strength giving each "
                                   "ductility demand, or the ductility demand of each strength, checked by halving "
                                   "the step.",
                       epilog="examples:\n  nvib spectrum elcentro.AT2 --scale 9.80665 --damping 0.05 "
                              "--periods 0.05:5:200 --plot sa.png\n"
                              "  nvib spectrum elcentro.AT2 --ductility 1 2 4 6 --periods 0.05:3:50 --plot cy.png",
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("record", help="the record file")
    p.add_argument("--dt", type=c.positive_real, help="the sample step of a one-column file [s]")
    p.add_argument("--scale", type=c.real, default=1.0,
                   help="factor on the values (default 1; a record in g stays in g, 9.80665 turns g into m/s^2)")
    p.add_argument("--record-units", choices=("g", "m/s^2"),
                   help="what a plain file's values are in (an AT2 file is in g)")
    p.add_argument("--units", choices=("g", "m/s^2"),
                   help="spectral accelerations printed, written and plotted in g or m/s^2 (Sd then in m; "
                        "default: the record's unit)")
    p.add_argument("--damping", type=c.real, nargs="+", default=[0.05], help="damping ratios (default 0.05)")
    p.add_argument("--periods", type=periods, default=periods("0.05:5:100"),
                   help="FIRST:LAST:COUNT log-spaced, or T1,T2,... (default 0.05:5:100) [s]")
    p.add_argument("--scheme", choices=keys, help="integrate each period with this scheme instead of the exact "
                                                  "solution (to see what a scheme's spectrum costs and how accurate "
                                                  "it is)")
    p.add_argument("--accuracy", type=c.positive_real,
                   help="with --scheme: relative accuracy of Sd and Sa to reach; with --ductility or "
                        "--strength-ratio: of the strength or the ductility demand, measured by halving the step "
                        "(default 1e-3)")
    p.add_argument("--ductility", type=c.real, nargs="+", metavar="MU",
                   help="constant-ductility spectrum: for each ductility demand mu >= 1, the largest yield "
                        "strength giving it at each period (C_y, A_y, R_y = f_o / f_y)")
    p.add_argument("--strength-ratio", type=c.real, nargs="+", metavar="R",
                   help="constant-strength spectrum: the ductility demand at each period of the yield strength "
                        "f_y = f_o / R (R = R_y > 0, the yield-strength reduction factor)")
    p.add_argument("--law", choices=tuple(HARDENING),
                   help="with --ductility or --strength-ratio: the hysteretic law (default bilinear)")
    p.add_argument("--hardening", type=c.real, metavar="B",
                   help="with --ductility or --strength-ratio: the post-yield stiffness ratio (bilinear b, "
                        "bouc_wen alpha; default 0, elastic-perfectly plastic)")
    p.add_argument("--out", "--csv", metavar="CSV", help="write the spectrum to this CSV file")
    p.add_argument("--plot", metavar="PNG", help="write the spectra to this PNG")
    p.set_defaults(func=lambda args, parser: c.run_checked(run, args, parser), subparser=p)


def run(args) -> int:
    import numpy as np

    from .. import GroundMotion, NvibError, RecordError, scheme_label, spectrum

    for z in args.damping:  # the exact spectrum takes any damping >= 0; runs of a scheme, an underdamped one
        if not (0.0 <= z < 1.0 if args.scheme is not None else z >= 0.0):
            raise c.Usage("--damping", f"expected 0 <= damping{' < 1 with --scheme' if args.scheme else ''}, got {z:g}")
    if args.plot is not None:
        c.check_output("--plot", args.plot, c.PLOT_FORMATS)
    if args.out is not None:
        c.check_output("--out", args.out, (".csv",))
    try:
        record = GroundMotion.from_file(args.record, dt=args.dt, scale=args.scale, units=args.record_units or "")
    except RecordError as exc:
        raise c.Usage("record", str(exc)) from None
    except ValueError as exc:
        raise c.usage_from(exc, {"dt": "--dt", "scale": "--scale", "units": "--record-units"},
                           default="record") from None
    if args.units is not None and record.units not in ("g", "m/s^2"):
        raise c.Usage("--units", f"the unit of {args.record}'s values is not known; give --record-units")
    units = args.units or record.units
    if args.ductility is not None or args.strength_ratio is not None:
        return run_inelastic(args, record, units)
    for flag, value in (("--law", args.law), ("--hardening", args.hardening)):
        if value is not None:
            raise c.Usage(flag, "applies to an inelastic spectrum (--ductility or --strength-ratio)")
    if args.accuracy is not None and args.scheme is None:
        raise c.Usage("--accuracy", "applies to runs with --scheme: the spectrum without one is exact")
    scheme = c.make_scheme(args.scheme, args) if args.scheme is not None else None
    from ..analysis.spectrum import unit_labels

    sd_units = unit_labels("m/s^2" if units else "")
    heads = {"Sd": sd_units["Sd"], "PSv": sd_units["PSv"], "PSa": unit_labels(units)["PSa"],
             "Sa": unit_labels(units)["PSa"]}
    print(f"{record}")
    results = []
    for z in args.damping:
        try:
            sp = spectrum(record, args.periods, damping=z, scheme=scheme, accuracy=args.accuracy)
        except NvibError as exc:  # a run failed (diverged, Newton failed): its period and why
            how = f"with {scheme_label(scheme)}, " if scheme is not None else ""
            print(f"nvib spectrum: error: {str(exc).removeprefix('spectrum: ')} ({how}damping {z:g})",
                  file=sys.stderr)
            return 1
        except (ValueError, TypeError) as exc:  # periods too short or too long for the memory, an accuracy too fine
            raise c.usage_from(exc, FLAGS) from None
        results.append(sp)
        shown = sp.in_units(units) if units else sp
        si = sp.in_units("m/s^2") if units else sp  # Sd, PSv in m and m/s when the unit is known
        if sp.error is None:
            print(f"damping {z:g}: {sp.periods.size} periods, exact (closed form, peaks between samples), "
                  f"{c.seconds(sp.wall_time)}")
        else:
            print(f"damping {z:g}: {sp.periods.size} periods, {sp.scheme}, runs {c.seconds(sp.wall_time)}, "
                  f"max error of Sd and Sa {np.max(sp.error):.1e} ({sp.check}); the runs' own estimates: "
                  f"{_worst(sp.estimate)}")
        runs = sp.error is not None
        rows = [["T [s]"] + [f"{k} [{v}]" for k, v in heads.items()] + (["error", "estimate"] if runs else [])]
        step = max(1, sp.periods.size // 10)
        for k in range(0, sp.periods.size, step):
            rows.append([f"{sp.periods[k]:.4g}", f"{si.Sd[k]:.4g}", f"{si.PSv[k]:.4g}", f"{shown.PSa[k]:.4g}",
                         f"{shown.Sa[k]:.4g}"] + ([f"{sp.error[k]:.1e}", f"{sp.estimate[k]:.1e}"] if runs else []))
        print("\n".join("  " + line for line in c.table(rows, right=set(range(len(rows[0]))))))
    code = 0
    if args.out:
        try:
            with open(args.out, "w", encoding="utf-8") as fh:
                # each column's unit in its header: "PSa [g]" stays "PSa [g]" at any --scale
                fh.write(",".join(["damping", "period [s]"] + [f"{k} [{v}]" for k, v in heads.items()]
                                  + ["error", "dt [s]", "estimate"]) + "\n")
                for sp in results:
                    shown = sp.in_units(units) if units else sp
                    si = sp.in_units("m/s^2") if units else sp
                    for k in range(sp.periods.size):  # shortest round-trip decimals
                        # exact: no error to report, nor an estimate
                        error = sp.error[k] if sp.error is not None else math.nan
                        estimate = sp.estimate[k] if sp.estimate is not None else math.nan
                        values = (sp.damping, sp.periods[k], si.Sd[k], si.PSv[k], shown.PSa[k], shown.Sa[k],
                                  error, sp.dt[k], estimate)
                        fh.write(",".join(repr(float(x)) for x in values) + "\n")
            print(f"wrote {args.out}")
        except OSError as exc:
            print(f"nvib spectrum: error: --out: cannot write {args.out!r}: {exc.strerror or exc}", file=sys.stderr)
            code = 1
    if args.plot:
        from ..plot import spectrum_figure

        how = "exact" if scheme is None else f"{results[0].scheme}, accuracy {np.max(results[0].error):.1e} reached"
        fig = spectrum_figure(results, units=units or None, title=f"{record.label}: {how}")
        try:
            fig.savefig(args.plot, dpi=120)
            print(f"wrote {args.plot}")
        except OSError as exc:
            print(f"nvib spectrum: error: --plot: cannot write {args.plot!r}: {exc.strerror or exc}", file=sys.stderr)
            code = 1
    return code


def run_inelastic(args, record, units: str) -> int:
    """The constant-ductility (--ductility) or constant-strength (--strength-ratio) spectrum: a table of every
    tenth period per target, the warnings, and the CSV and plot asked for."""
    import numpy as np

    from .. import NvibError, inelastic_spectrum
    from ..analysis.inelastic import _cell

    if args.ductility is not None and args.strength_ratio is not None:
        raise c.Usage("--ductility", "gives a constant-ductility spectrum, --strength-ratio a constant-strength "
                                     "one: give one of them")
    if len(args.damping) != 1:
        raise c.Usage("--damping", "an inelastic spectrum takes one damping ratio")
    law = {"type": args.law or "bilinear"}
    law[HARDENING[law["type"]]] = args.hardening if args.hardening is not None else 0.0
    scheme = c.make_scheme(args.scheme, args) if args.scheme is not None else None
    try:
        sp = inelastic_spectrum(record, args.periods, ductility=args.ductility, R=args.strength_ratio,
                                damping=args.damping[0], law=law, scheme=scheme, accuracy=args.accuracy)
    except NvibError as exc:  # a run failed (diverged, Newton failed): its period and strength
        print(f"nvib spectrum: error: {str(exc).removeprefix('inelastic_spectrum: ')}", file=sys.stderr)
        return 1
    except (ValueError, TypeError) as exc:
        raise c.usage_from(exc, INELASTIC_FLAGS) from None
    if units and units != sp.units:
        sp = sp.in_units(units)
    print(f"{record}")
    worst = np.nanmax(sp.error) if np.any(np.isfinite(sp.error)) else math.nan
    how = ", ".join(f"{k} = {v:g}" for k, v in law.items() if k != "type")
    print(f"{sp.kind}, {law['type']}{f' ({how})' if how else ''}, damping {sp.damping:g}: {sp.periods.size} "
          f"periods x {sp.targets.size} targets, {sp.scheme}, {sp.runs} SDOF runs in {c.seconds(sp.wall_time)}, "
          f"largest error {worst:.1e} (accuracy {sp.accuracy:g}, measured by halving the step); the runs' own "
          f"estimates: {_worst(sp.estimate)}")
    columns = [(h, v) for h, v in sp.columns() if not h.startswith(("u_y", "dt"))]
    step = max(1, sp.periods.size // 10)
    for k in range(sp.targets.size):
        rows = [["T [s]"] + [h for h, _ in columns]]
        for j in range(0, sp.periods.size, step):
            rows.append([f"{sp.periods[j]:.4g}"] + [_cell(v[k, j], h) for h, v in columns])
        print(f"{sp.label(k)}:")
        print("\n".join("  " + line for line in c.table(rows, right=set(range(len(rows[0]))))))
    for w in sp.warnings:
        print(f"nvib spectrum: warning: {w}", file=sys.stderr)
    return max(c.write_output("spectrum", "--out", args.out, sp.to_csv),
               c.write_output("spectrum", "--plot", args.plot, sp.plot))


def _worst(estimate) -> str:
    """The largest of the runs' estimates, or that there are none (a scheme without one)."""
    import numpy as np

    return f"largest {np.nanmax(estimate):.1e}" if np.any(~np.isnan(estimate)) else "none"

