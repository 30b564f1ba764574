"""The ``nvib`` command line (also ``python -m nvib``), one module per command:

    nvib scenes                      the built-in scenes
    nvib run SCENE [options]         integrate a scene, print a summary, optionally --out / --plot
    nvib cost SCENE [options]        work-precision diagram of the schemes and SciPy
    nvib demo                        hardening oscillator with every scheme against its closed form
    nvib stability [options]         spectral radius and stability limit of schemes on a linear SDOF
    nvib paper OUTDIR                the figures and tables of Yang et al. (2017), and CEMDTS's eta study
    nvib spectrum RECORD [options]   response spectrum of a ground-motion record
    nvib ida SCENE RECORDS [options] incremental dynamic analysis to collapse
    nvib fragility FILE [options]    lognormal fragility curves from an IDA or from stripes
    nvib --cmake-dir                 the folder of nvibConfig.cmake (nvib_DIR for find_package(nvib))
    nvib --include-dir               the folder of nvib's C++ headers
    nvib --cflags                    -I<nvib headers> -I<Eigen headers>, for a compiler command line

The schemes, their options and their labels come from the registry. Exit
status: 0 success, 1 the run failed (diverged, Newton failed) or an output
could not be written, 2 bad input (the message names the argument), 130
interrupted (Ctrl-C), 141 the standard output was closed early (a pipe into
``head``): the command stops quietly, as a C tool killed by SIGPIPE does, so
``set -o pipefail`` still sees that the output was cut short.
"""

from __future__ import annotations

import argparse
import os
import sys

from . import cost, demo, fragility, ida, paper, run, scenes, spectrum, stability

__all__ = ["build_parser", "main"]

EXIT_INTERRUPTED = 130  # 128 + SIGINT
EXIT_BROKEN_PIPE = 141  # 128 + SIGPIPE

EPILOG = """\
exit status: 0 success, 1 the run failed (diverged, Newton failed) or an output could not be written,
2 bad input (the message names the argument), 130 interrupted, 141 the output pipe was closed early
(nvib ... | head)
"""


def build_parser() -> argparse.ArgumentParser:
    from .. import __version__

    parser = argparse.ArgumentParser(prog="nvib", description="Time integration of nonlinear vibration systems.",
                                     epilog=EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--version", action="version", version=f"nvib {__version__}")
    parser.add_argument("--cmake-dir", action="store_true", help="print the folder of nvibConfig.cmake and exit")
    parser.add_argument("--include-dir", action="store_true", help="print the folder of nvib's C++ headers and exit")
    parser.add_argument("--cflags", action="store_true",
                        help="print the compiler flags for nvib's and Eigen's headers (-I<nvib> -I<eigen>) and exit")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for command in (scenes, run, cost, paper, demo, stability, spectrum, ida, fragility):
        command.add_parser(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run one command; returns its exit status. A closed standard output (``nvib scenes | head -3``) and
    Ctrl-C end the command quietly with status 141 and 130 instead of a traceback."""
    try:
        try:
            return _main(argv)
        finally:
            sys.stdout.flush()  # a closed pipe shows here rather than in the interpreter's final flush
    except BrokenPipeError:
        _discard_stdout()
        return EXIT_BROKEN_PIPE
    except KeyboardInterrupt:  # the commands that run long say what they stop themselves
        print("nvib: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED


def _discard_stdout() -> None:
    """Point the standard output at the null device, so that what is still buffered goes nowhere at exit
    instead of raising BrokenPipeError again (and printing "Exception ignored ...")."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        try:
            os.dup2(devnull, sys.stdout.fileno())
        finally:
            os.close(devnull)
    except (OSError, ValueError, AttributeError):  # no file descriptor (a test's captured stream)
        pass


def _main(argv: list[str] | None) -> int:
    from .. import cmake_dir, include_dir

    parser = build_parser()
    args = parser.parse_args(argv)
    if args.cmake_dir:
        print(cmake_dir())
        return 0
    if args.include_dir:
        print(include_dir())
        return 0
    if args.cflags:
        return _print_cflags(include_dir())
    if not args.command:
        parser.print_help()
        return 2
    return args.func(args, args.subparser)  # usage errors then read "nvib run: error: ..."


def _eigen_include_dir() -> str | None:
    """Folder holding Eigen/Dense: the cmeel-eigen wheel's (a dependency of nvib,
    normally in the same site-packages), else a system Eigen."""
    site = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    candidates = [os.path.join(site, "cmeel.prefix", "include", "eigen3")]
    try:
        import cmeel

        candidates.append(os.path.join(os.path.dirname(cmeel.__path__[0]), "cmeel.prefix", "include", "eigen3"))
    except ImportError:
        pass
    candidates += [os.path.join(prefix, "include", "eigen3") for prefix in (sys.prefix, "/usr/local", "/usr")]
    for cand in candidates:
        if os.path.isfile(os.path.join(cand, "Eigen", "Dense")):
            return cand
    return None


def _print_cflags(nvib_include: str) -> int:
    if not os.path.isfile(os.path.join(nvib_include, "nvib", "nvib.hpp")):
        print(f"nvib: error: --cflags: no C++ headers in {nvib_include} (this nvib is not an installed package; "
              "pip install . installs them)", file=sys.stderr)
        return 1
    eigen = _eigen_include_dir()
    if eigen is None:
        print("nvib: error: --cflags: Eigen headers not found (pip install cmeel-eigen, or the system's libeigen3-dev)",
              file=sys.stderr)
        return 1
    print(f"-I{nvib_include} -I{eigen}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
