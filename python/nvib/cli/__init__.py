"""The ``nvib`` command line (also ``python -m nvib``), one module per command:

    nvib scenes                      the built-in scenes
    nvib run SCENE [options]         integrate a scene, print a summary, optionally --out / --plot
    nvib cost SCENE [options]        work-precision diagram of the schemes and SciPy
    nvib demo                        hardening oscillator with every scheme against its closed form
    nvib stability [options]         spectral radius and stability limit of schemes on a linear SDOF
    nvib paper OUTDIR                the figures and tables of Yang et al. (2017), and CEMDTS's eta study
    nvib spectrum RECORD [options]   response spectrum of a ground-motion record

The schemes, their options and their labels come from the registry. Exit
status: 0 success, 1 the run failed (diverged, Newton failed) or an output
could not be written, 2 bad input (the message names the argument).
"""

from __future__ import annotations

import argparse
import sys

from . import cost, demo, paper, run, scenes, spectrum, stability

__all__ = ["build_parser", "main"]


def build_parser() -> argparse.ArgumentParser:
    from .. import __version__

    parser = argparse.ArgumentParser(prog="nvib", description="Time integration of nonlinear vibration systems.")
    parser.add_argument("--version", action="version", version=f"nvib {__version__}")
    parser.add_argument("--cmake-dir", action="store_true", help="print the folder of nvibConfig.cmake and exit")
    parser.add_argument("--include-dir", action="store_true", help="print the folder of the C++ headers and exit")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for command in (scenes, run, cost, paper, demo, stability, spectrum):
        command.add_parser(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    from .. import cmake_dir, include_dir

    parser = build_parser()
    args = parser.parse_args(argv)
    if args.cmake_dir:
        print(cmake_dir())
        return 0
    if args.include_dir:
        print(include_dir())
        return 0
    if not args.command:
        parser.print_help()
        return 2
    return args.func(args, args.subparser)  # usage errors then read "nvib run: error: ..."


if __name__ == "__main__":
    sys.exit(main())
