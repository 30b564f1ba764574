"""nvib demo: the hardening oscillator (Yang et al. 2017, section 4.2) with
every scheme of the registry, compared with its closed-form solution."""

from __future__ import annotations

import argparse
import math
import sys
import time

import numpy as np

from .._labels import status_text
from .._model import Model
from .._schemes import scheme_classes
from .._solve import solve
from ..analysis import exact

M, K0, A, X0, T_END = 1.0, 100.0, 30.0, 1.5, 0.3
MAX_STEPS = 1_000_000  # --dt must leave at most this many steps over T_END (the paper's dt: 300)
BLOWUP = 2.0  # a run whose energy grows beyond BLOWUP x E0 has blown up (the oscillator conserves E0)

EPILOG = f"""\
A scheme whose run diverges, or whose energy grows beyond {BLOWUP:g} times the initial energy E0
(which the oscillator conserves), has its row say where it blew up instead of its errors. Exit
status: 0 every scheme ran to t_end, 1 some scheme blew up (try a smaller --dt), 2 bad input.
"""


def hardening_model() -> Model:
    return Model([M], effects=[{"type": "hardening_spring", "measure": {"x": 1.0}, "k0": K0, "a": A}],
                 dofs=["x"], u0=[X0])


def demo_schemes():
    """(label, scheme) for every scheme of the registry, with its defaults."""
    return [(cls().label, cls()) for cls in scheme_classes()]


def check_dt(dt: float) -> None:
    """dt must be finite, > 0, at most T_END (a longer step would carry the run past it) and leave at most
    MAX_STEPS steps over T_END."""
    from . import _common as c

    if not (math.isfinite(dt) and dt > 0):
        raise c.Usage("--dt", f"must be a finite number > 0, got {dt!r}")
    if dt > T_END:
        raise c.Usage("--dt", f"must be <= t_end = {T_END:g} s (a longer step would end the run past it), got {dt:g}")
    if T_END / dt > MAX_STEPS:
        raise c.Usage("--dt", f"must be >= {T_END / MAX_STEPS:g} s (at most {MAX_STEPS} steps over t_end = "
                              f"{T_END:g} s), got {dt:g}")


def blowup(res, e: np.ndarray, e0: float) -> str | None:
    """Where the run blew up ('diverged at t = 0.15 (step 3)', 'blew up by t = 0.3: energy 2.48e+17 x E0'),
    or None when it ran to t_end with its energy e within BLOWUP x e0. Energy lost is numerical damping,
    not a blow-up."""
    if res.failure is not None:
        return f"{status_text(res.status)} at t = {res.failure.t:g} (step {res.failure.step})"
    with np.errstate(all="ignore"):
        bad = ~(e <= BLOWUP * e0)  # NaN counts
    if np.any(bad):
        i = int(np.argmax(bad))
        return f"blew up by t = {res.t[i]:g}: energy {e[i] / e0:.3g} x E0"
    return None


def run(dt: float = 1e-3, repeats: int = 5) -> list[dict]:
    """One row per scheme: energy error, error against the closed form, counters, wall time, and
    ``failure``: where the run blew up (None when it did not; its errors are then meaningless)."""
    check_dt(dt)
    model = hardening_model()
    rows = []
    for label, scheme in demo_schemes():
        best = float("inf")
        for _ in range(repeats):
            t0 = time.perf_counter()
            res = solve(model, scheme, dt=dt, t_end=T_END, throw=False)
            best = min(best, time.perf_counter() - t0)
        x, v = res.u[:, 0], res.v[:, 0]
        xe, _ = exact.hardening(res.t, m=M, k0=K0, a=A, x0=X0)
        e = exact.hardening_energy(x, v, m=M, k0=K0, a=A)
        e0 = exact.hardening_energy(X0, 0.0, m=M, k0=K0, a=A)
        with np.errstate(all="ignore"):
            rows.append({
                "scheme": label,
                "max_rel_energy_error": float(np.max(np.abs(e - e0)) / e0),
                "max_abs_error": float(np.max(np.abs(x - xe))),
                "force_evals": int(res.stats.num_force_evals),
                "newton_iters": int(res.stats.num_newton_iters),
                "wall_time_s": best,
                "failure": blowup(res, e, e0),
            })
    return rows


def table(rows: list[dict]) -> str:
    w = max(len("scheme"), *(len(r["scheme"]) for r in rows))
    head = (f"{'scheme':<{w}} {'max rel. energy err':>19} {'max |x - x_exact|':>17} {'force evals':>11} "
            f"{'Newton it.':>10} {'wall time':>10}")
    lines = [head, "-" * len(head)]
    for r in rows:
        if r.get("failure"):
            errors = f"{r['failure']:<37}"  # over both error columns: the numbers would mean nothing
        else:
            errors = f"{r['max_rel_energy_error']:>19.3e} {r['max_abs_error']:>17.3e}"
        lines.append(f"{r['scheme']:<{w}} {errors} {r['force_evals']:>11d} {r['newton_iters']:>10d} "
                     f"{r['wall_time_s'] * 1e6:>8.0f}us")
    return "\n".join(lines)


def plot(path: str, dt: float = 1e-3) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    model = hardening_model()
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 4.5))
    t = np.linspace(0.0, T_END, 2001)
    xe, ve = exact.hardening(t, m=M, k0=K0, a=A, x0=X0)
    ax2.plot(xe, ve, "k-", lw=2.5, alpha=0.35, label="exact")
    for label, scheme in demo_schemes():
        res = solve(model, scheme, dt=dt, t_end=T_END, throw=False)  # a diverged run: its history so far
        xe_r, _ = exact.hardening(res.t, m=M, k0=K0, a=A, x0=X0)
        ax1.plot(res.t, res.u[:, 0] - xe_r, label=label)
        ax2.plot(res.u[:, 0], res.v[:, 0], lw=0.8, label=label)
    ax1.set_xlabel("t [s]")
    ax1.set_ylabel("x - x_exact [m]")
    ax1.set_title(f"Displacement error, dt = {dt:g} s")
    ax1.legend(fontsize=8)
    ax2.set_xlabel("x [m]")
    ax2.set_ylabel("v [m/s]")
    ax2.set_title("Phase locus")
    ax2.legend(fontsize=8)
    fig.suptitle("Hardening oscillator m x'' + k0 (1 + a x^2) x = 0, m = 1, k0 = 100, a = 30, x0 = 1.5")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def add_parser(sub) -> None:
    from . import _common as c

    p = sub.add_parser("demo", help="hardening oscillator with every scheme against its closed form",
                       description="The hardening oscillator with every scheme, against its closed form.",
                       epilog=EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--dt", type=c.positive_real, default=1e-3,
                   help=f"time step [s] (default 1e-3, the paper's; at least {T_END / MAX_STEPS:g})")
    p.add_argument("--repeats", type=c.positive_int, default=5, help="timing repeats, >= 1 (the best is shown)")
    p.add_argument("--plot", metavar="PNG", help="write error histories and phase loci to this PNG")
    p.set_defaults(func=lambda args, parser: c.run_checked(command, args, parser), subparser=p)


def command(args) -> int:
    from . import _common as c

    if args.plot is not None:
        c.check_output("--plot", args.plot, c.PLOT_FORMATS)
    check_dt(args.dt)
    print("Hardening oscillator m x'' + k0 (1 + a x^2) x = 0 (Yang et al. 2017, section 4.2)")
    print(f"m = {M:g}, k0 = {K0:g}, a = {A:g}, x0 = {X0:g}, dt = {args.dt:g} s, "
          f"t_end = {T_END:g} s; reference: closed form x0 cn(w t | m) (Jacobi elliptic)")
    print()
    rows = run(dt=args.dt, repeats=args.repeats)
    print(table(rows))
    code = 0
    if args.plot:
        try:
            plot(args.plot, dt=args.dt)
            print(f"\nplot written to {args.plot}")
        except OSError as exc:
            print(f"nvib demo: error: --plot: cannot write {args.plot!r}: {exc.strerror or exc}", file=sys.stderr)
            code = 1
    failed = [r["scheme"] for r in rows if r["failure"]]
    if failed:
        rows_text = "its row" if len(failed) == 1 else "their rows"
        print(f"nvib demo: error: {', '.join(failed)} blew up with dt = {args.dt:g} s (see {rows_text}); "
              "try a smaller --dt", file=sys.stderr)
        return 1
    return code
