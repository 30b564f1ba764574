"""nvib paper OUTDIR: the figures and tables of Yang et al. (2017), and CEMDTS's eta study."""

from __future__ import annotations

import argparse
import os
import sys
import time

from .. import _checks
from . import _common as c


def add_parser(sub) -> None:
    p = sub.add_parser("paper", help="regenerate the figures and tables of Yang et al. (2017) into a folder",
                       description="Run the cases of Yang et al. (2017) with its schemes (Newmark and GaM both in "
                                   "one Newton iteration per step and with full Newton iteration, LCDM with "
                                   "synchronized and half-step velocity) against closed forms or DOP853 references, "
                                   "and write Figs. 2-4, 6, 7, 9-11, Table 1, the CPU-time table, CEMDTS's eta study "
                                   "(PNG and CSV) and summary.md into OUTDIR.")
    p.add_argument("outdir", metavar="OUTDIR", help="folder for the figures and tables (created if missing)")
    p.add_argument("--repeats", type=c.positive_int, default=3,
                   help="timed runs per figure run, the best is kept (default 3)")
    p.add_argument("--cpu-repeats", type=c.positive_int, default=5,
                   help="timed runs per scheme in the CPU-time table (default 5)")
    p.add_argument("--progress", action=argparse.BooleanOptionalAction, default=None,
                   help="report each finished part on stderr (default: when stderr is a terminal)")
    p.set_defaults(func=lambda args, parser: c.run_checked(run, args, parser), subparser=p)


def run(args) -> int:
    from .. import paper

    out = os.path.abspath(args.outdir)
    if os.path.exists(out) and not os.path.isdir(out):
        raise c.Usage("OUTDIR", f"{args.outdir!r} exists and is not a folder")
    if os.path.lexists(out) and not os.path.exists(out):  # a link to nothing, or a loop of links
        raise c.Usage("OUTDIR", f"{args.outdir!r}: {_checks.input_file_problem(out, 'folder')}")
    above = os.path.dirname(out)
    while not os.path.exists(above):  # the folders to be made must not sit in a file ("notes.txt/figures")
        above = os.path.dirname(above)
    if not os.path.isdir(above):
        raise c.Usage("OUTDIR", f"{above!r} is a file, not a folder")
    show = args.progress if args.progress is not None else c.isatty(sys.stderr)
    t0 = time.perf_counter()

    def progress(what):
        if show:
            print(f"  {what} ({time.perf_counter() - t0:.1f} s)", file=sys.stderr, flush=True)

    try:
        files = paper.write_paper(out, repeats=args.repeats, cpu_repeats=args.cpu_repeats, progress=progress)
    except KeyboardInterrupt:
        print("nvib paper: interrupted", file=sys.stderr)
        return 130
    except OSError as exc:
        print(f"nvib paper: error: OUTDIR: cannot write into {args.outdir!r}: {exc.strerror or exc}",
              file=sys.stderr)
        return 1
    for path in files.values():
        print(f"wrote {path}")
    print(f"{len(files)} files in {time.perf_counter() - t0:.1f} s; read {files['summary.md']}")
    return 0
