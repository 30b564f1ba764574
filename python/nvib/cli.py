"""The ``nvib`` command line (also ``python -m nvib``)."""

from __future__ import annotations

import argparse
import sys


def _demo(args) -> int:
    from . import demo

    print("Hardening oscillator m x'' + k0 (1 + a x^2) x = 0 (Yang et al. 2017, section 4.2)")
    print(f"m = {demo.M:g}, k0 = {demo.K0:g}, a = {demo.A:g}, x0 = {demo.X0:g}, dt = {args.dt:g} s, "
          f"t_end = {demo.T_END:g} s; reference: closed form x0 cn(w t | m) (Jacobi elliptic)")
    print()
    print(demo.table(demo.run(dt=args.dt, repeats=args.repeats)))
    if args.plot:
        demo.plot(args.plot, dt=args.dt)
        print(f"\nplot written to {args.plot}")
    return 0


def main(argv: list[str] | None = None) -> int:
    from . import __version__, cmake_dir, include_dir

    parser = argparse.ArgumentParser(prog="nvib", description="Time integration of nonlinear vibration systems.")
    parser.add_argument("--version", action="version", version=f"nvib {__version__}")
    parser.add_argument("--cmake-dir", action="store_true", help="print the folder of nvibConfig.cmake and exit")
    parser.add_argument("--include-dir", action="store_true", help="print the folder of the C++ headers and exit")
    sub = parser.add_subparsers(dest="command")
    p = sub.add_parser("demo", help="hardening oscillator with every scheme against its closed form")
    p.add_argument("--dt", type=float, default=1e-3, help="time step [s] (default 1e-3, the paper's)")
    p.add_argument("--repeats", type=int, default=5, help="timing repeats (the best is shown)")
    p.add_argument("--plot", metavar="PNG", help="write error histories and phase loci to this PNG")
    p.set_defaults(func=_demo)
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
    if args.command == "demo" and not (args.dt > 0):
        parser.error("--dt must be > 0")
    return args.func(args)


if __name__ == "__main__":
    sys.exit(main())
