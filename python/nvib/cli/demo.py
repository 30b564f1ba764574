"""nvib demo: the hardening oscillator (Yang et al. 2017, section 4.2) with
every scheme of the registry, compared with its closed-form solution."""

from __future__ import annotations

import time

import numpy as np

from .._model import Model
from .._schemes import scheme_classes
from .._solve import solve
from ..analysis import exact

M, K0, A, X0, T_END = 1.0, 100.0, 30.0, 1.5, 0.3


def hardening_model() -> Model:
    return Model([M], effects=[{"type": "hardening_spring", "measure": {"x": 1.0}, "k0": K0, "a": A}],
                 dofs=["x"], u0=[X0])


def demo_schemes():
    """(label, scheme) for every scheme of the registry, with its defaults."""
    return [(cls().label, cls()) for cls in scheme_classes()]


def run(dt: float = 1e-3, repeats: int = 5) -> list[dict]:
    """One row per scheme: energy error, error against the closed form, counters, wall time."""
    model = hardening_model()
    rows = []
    for label, scheme in demo_schemes():
        best = float("inf")
        for _ in range(repeats):
            t0 = time.perf_counter()
            res = solve(model, scheme, dt=dt, t_end=T_END)
            best = min(best, time.perf_counter() - t0)
        x, v = res.u[:, 0], res.v[:, 0]
        xe, _ = exact.hardening(res.t, m=M, k0=K0, a=A, x0=X0)
        e = exact.hardening_energy(x, v, m=M, k0=K0, a=A)
        e0 = exact.hardening_energy(X0, 0.0, m=M, k0=K0, a=A)
        rows.append({
            "scheme": label,
            "max_rel_energy_error": float(np.max(np.abs(e - e0)) / e0),
            "max_abs_error": float(np.max(np.abs(x - xe))),
            "force_evals": int(res.stats.num_force_evals),
            "newton_iters": int(res.stats.num_newton_iters),
            "wall_time_s": best,
        })
    return rows


def table(rows: list[dict]) -> str:
    w = max(len("scheme"), *(len(r["scheme"]) for r in rows))
    head = (f"{'scheme':<{w}} {'max rel. energy err':>19} {'max |x - x_exact|':>17} {'force evals':>11} "
            f"{'Newton it.':>10} {'wall time':>10}")
    lines = [head, "-" * len(head)]
    for r in rows:
        lines.append(f"{r['scheme']:<{w}} {r['max_rel_energy_error']:>19.3e} {r['max_abs_error']:>17.3e} "
                     f"{r['force_evals']:>11d} {r['newton_iters']:>10d} {r['wall_time_s'] * 1e6:>8.0f}us")
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
        res = solve(model, scheme, dt=dt, t_end=T_END)
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

    p = sub.add_parser("demo", help="hardening oscillator with every scheme against its closed form")
    p.add_argument("--dt", type=c.positive_real, default=1e-3, help="time step [s] (default 1e-3, the paper's)")
    p.add_argument("--repeats", type=c.positive_int, default=5, help="timing repeats (the best is shown)")
    p.add_argument("--plot", metavar="PNG", help="write error histories and phase loci to this PNG")
    p.set_defaults(func=lambda args, parser: c.run_checked(command, args, parser), subparser=p)


def command(args) -> int:
    from . import _common as c

    if args.plot is not None:
        c.check_output("--plot", args.plot, c.PLOT_FORMATS)
    print("Hardening oscillator m x'' + k0 (1 + a x^2) x = 0 (Yang et al. 2017, section 4.2)")
    print(f"m = {M:g}, k0 = {K0:g}, a = {A:g}, x0 = {X0:g}, dt = {args.dt:g} s, "
          f"t_end = {T_END:g} s; reference: closed form x0 cn(w t | m) (Jacobi elliptic)")
    print()
    print(table(run(dt=args.dt, repeats=args.repeats)))
    if args.plot:
        plot(args.plot, dt=args.dt)
        print(f"\nplot written to {args.plot}")
    return 0
