"""nvib stability: spectral radius and stability limit of the schemes on a linear SDOF."""

from __future__ import annotations

import argparse
import math
import sys

from . import _common as c

OMEGAS = (0.1, 1.0, 2.0, 10.0, 100.0)  # where the table shows the spectral radius
MAX_POINTS = 100_000  # --points: far more than a plot shows (1e12 asked for terabytes)


def add_parser(sub) -> None:
    from .. import schemes

    keys = list(schemes())
    p = sub.add_parser("stability", help="spectral radius and stability limit of schemes on a linear SDOF",
                       description="Spectral radius of each scheme's amplification matrix for the linear SDOF "
                                   "u'' + 2 xi w u' + w^2 u = 0 against Omega = w dt (taken from the steppers "
                                   "themselves), and the stability limit Omega_crit.",
                       epilog=f"example:\n  nvib stability --schemes {' '.join(keys)} --xi 0.05 --plot rho.png",
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--schemes", nargs="+", choices=keys, default=keys, metavar="NAME",
                   help=f"schemes to compare, from {', '.join(keys)} (default: all)")
    p.add_argument("--xi", type=c.real, default=0.0, help="damping ratio, 0 <= xi < 1 (default 0)")
    g = p.add_argument_group("scheme parameters (each applies to the schemes that have it)")
    c.add_scheme_options(g, iteration=False)  # a linear SDOF: the Newton iteration changes nothing
    g = p.add_argument_group("plot")
    g.add_argument("--plot", metavar="PNG", help="write spectral radius against Omega (log axis) to this PNG")
    g.add_argument("--omega-min", type=c.positive_real, default=1e-2, metavar="W", help="plot from Omega = W (default 0.01)")
    g.add_argument("--omega-max", type=c.positive_real, default=100.0, metavar="W",
                   help="plot up to Omega = W (default 100; Omega_crit is searched up to max(W, 1e4))")
    g.add_argument("--points", type=c.positive_int, default=300, help="Omega values on the plot (default 300)")
    p.set_defaults(func=lambda args, parser: c.run_checked(run, args, parser), subparser=p)


def chosen_schemes(args) -> list:
    """(label, scheme) for each of --schemes, each given only the options that apply to it."""
    from .._labels import scheme_label

    names = list(dict.fromkeys(args.schemes))
    for name, opt in c.scheme_options().items():
        if getattr(args, f"scheme_{name}", None) is not None and not set(opt["schemes"]) & set(names):
            raise c.Usage(c.flag(name), f"applies to none of --schemes {' '.join(names)} "
                                        f"(only to {', '.join(opt['schemes'])})")
    out = []
    for name in names:
        scheme = c.make_scheme(name, args, only_applicable=True)
        out.append((scheme_label(scheme, iteration=False), scheme))
    return out


def run(args) -> int:
    import numpy as np

    from ..analysis import stability

    if not 0.0 <= args.xi < 1.0:
        raise c.Usage("--xi", f"the damping ratio needs 0 <= xi < 1, got {args.xi:g}")
    lo, hi = stability.OMEGA_RANGE
    if args.omega_max > hi:
        raise c.Usage("--omega-max", f"must be <= {hi:g}, got {args.omega_max:g}")
    if not lo <= args.omega_min < args.omega_max:
        raise c.Usage("--omega-min", f"must lie in [{lo:g}, --omega-max {args.omega_max:g}), got {args.omega_min:g}")
    if args.points > MAX_POINTS:
        raise c.Usage("--points", f"must be <= {MAX_POINTS} (Omega values on the plot), got {args.points}")
    if args.plot is not None:
        c.check_output("--plot", args.plot, c.PLOT_FORMATS)
    schemes = chosen_schemes(args)
    limit = max(stability.OMEGA_LIMIT, args.omega_max)

    print(f"Linear SDOF u'' + 2 xi w u' + w^2 u = 0, xi = {args.xi:g}: amplification matrix of one step "
          f"of each scheme's stepper, Omega = w dt")
    print(f"Omega_crit: smallest Omega with spectral radius rho > 1 + {stability.RHO_TOL:g} "
          f"(scan and bisection up to {limit:g}; 'none' = stable up to there)")
    print()
    rows = [["scheme", "Omega_crit"] + [f"rho({om:g})" for om in OMEGAS]]
    crits = []
    for label, scheme in schemes:
        oc = stability.critical_omega_h(scheme, args.xi, omega_max=limit)
        crits.append(oc)
        rho = stability.spectral_radius(scheme, np.array(OMEGAS), args.xi)
        rows.append([label, "none" if math.isinf(oc) else f"{oc:.6g}"] + [f"{r:.6g}" for r in rho])
    print("\n".join(c.table(rows, right=set(range(1, len(rows[0]))))))
    if args.plot:
        oms = np.geomspace(args.omega_min, args.omega_max, args.points)
        try:
            stability.plot_spectral_radius([s for _, s in schemes], args.plot, xi=args.xi, omega_h=oms,
                                           labels=[lab for lab, _ in schemes], critical=crits)
        except OSError as exc:
            print(f"nvib stability: error: --plot: cannot write {args.plot!r}: {exc.strerror or exc}",
                  file=sys.stderr)
            return 1
        print(f"\nwrote {args.plot}")
    return 0
