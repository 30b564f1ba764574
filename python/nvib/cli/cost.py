"""nvib cost SCENE: work-precision diagram (error against wall time) of schemes and SciPy on a scene."""

from __future__ import annotations

import argparse
import sys
import time

from . import _common as c

COST_FLAGS = {"dts": "--dt", "tols": "--tol", "t_end": "--t-end", "rtols": "--rtol", "repeats": "--repeats",
              "max_time": "--max-time", "methods": "--scipy", "dofs": "--dof"}


def default_schemes() -> list[str]:
    """Every scheme of the registry with its defaults; the implicit ones also with one Newton iteration per step."""
    from .. import schemes

    out = []
    for key, cls in schemes().items():
        out.append(key)
        if not cls.is_explicit:
            out.append(f"{key}:one_iteration")
    return out


def add_parser(sub) -> None:
    from ..analysis.cost import SCIPY_METHODS

    p = sub.add_parser("cost", help="work-precision diagram: error against wall time for schemes and SciPy",
                       description="Run each scheme at each step (and SciPy solve_ivp at each tolerance) on a "
                                   "scene, measure the error against the reference (closed form or DOP853) and "
                                   "the wall time, write a work-precision PNG and a markdown table.")
    p.add_argument("scene", metavar="SCENE", help="built-in scene name (see nvib scenes) or path to a .toml scene")
    p.add_argument("--schemes", nargs="+", metavar="NAME",
                   help="schemes, the implicit ones optionally as NAME:MODE (a Newton mode) "
                        f"(default: {' '.join(default_schemes())})")
    p.add_argument("--dt", type=c.positive_real, nargs="+", help="steps (default: the scene's dt x 4, 2, 1, ... 1/32)")
    p.add_argument("--tol", type=c.positive_real, nargs="+", metavar="TOL",
                   help="also adaptive runs (solve(..., tol=)) of each scheme that takes a tol, at these tolerances "
                        "(the largest --dt their first step), a curve '<scheme>, tol' each")
    p.add_argument("--t-end", type=c.positive_real, metavar="T", help="end time [s] (default: the scene's)")
    p.add_argument("--dof", nargs="+", metavar="NAME", help="DOFs the error is measured on (default: plot_dof)")
    p.add_argument("--scipy", nargs="+", metavar="METHOD", choices=("RK23", "RK45", "DOP853", "Radau", "BDF", "LSODA"),
                   help=f"solve_ivp methods (default: {' '.join(SCIPY_METHODS)})")
    p.add_argument("--no-scipy", action="store_true", help="leave SciPy out")
    p.add_argument("--rtol", type=c.positive_real, nargs="+", help="SciPy tolerances (default 1e-3 ... 1e-10)")
    p.add_argument("--repeats", type=c.positive_int, default=3, help="timed runs per row, the best is kept (default 3)")
    p.add_argument("--max-time", type=c.positive_real, default=30.0, metavar="S",
                   help="skip a SciPy method's tighter tolerances once a run takes longer (default 30 s)")
    p.add_argument("--target", type=c.positive_real, metavar="ERR", default=1e-3,
                   help="draw this error level and name (and star on the diagram) the cheapest run of each contender "
                        "reaching it (default 1e-3)")
    p.add_argument("--plot", metavar="PNG", help="work-precision diagram (default cost_SCENE.png)")
    p.add_argument("--table", metavar="MD", help="markdown table (default cost_SCENE.md)")
    p.add_argument("--progress", action=argparse.BooleanOptionalAction, default=None,
                   help="progress on stderr (default: when stderr is a terminal)")
    p.set_defaults(func=lambda args, parser: c.run_checked(run, args, parser), subparser=p, without=None)


def cost_scheme(text: str):
    """NAME or NAME:MODE -> the scheme with its defaults (and that Newton mode)."""
    from .. import Newton, schemes

    name, _, mode = text.partition(":")
    registry = schemes()
    if name not in registry:
        raise c.Usage("--schemes", f"unknown scheme {name!r} (expected {', '.join(registry)}, the implicit ones "
                                   "optionally as NAME:MODE)")
    cls = registry[name]
    if not mode:
        return cls()
    if cls.is_explicit:
        raise c.Usage("--schemes", f"{text!r}: only the implicit schemes take a Newton mode")
    try:
        return cls(newton=Newton(iteration=mode))
    except ValueError as exc:
        raise c.Usage("--schemes", f"{text!r}: {exc}") from None


def run(args) -> int:
    from .. import cost as run_cost, cost_scipy, reference
    from ..analysis.cost import SCIPY_METHODS, SCIPY_RTOLS, cheapest, markdown_table, plot_work_precision, setting_text
    from .. import _core
    from .run import load_model, step_error

    model = load_model(args)
    name = model.scene["name"]
    plot = args.plot if args.plot is not None else f"cost_{name}.png"  # '' is refused, not the default
    table = args.table if args.table is not None else f"cost_{name}.md"
    c.check_output("--plot", plot, c.PLOT_FORMATS)
    c.check_output("--table", table, (".md",))
    schemes = [cost_scheme(x) for x in (args.schemes or default_schemes())]
    dofs = args.dof or [model.scene["plot_dof"]]
    for d in dofs:
        if d not in model.dofs:
            raise c.Usage("--dof", f"unknown DOF {d!r} in scene {name!r} (DOFs: {', '.join(model.dofs)})")
    t_end = args.t_end if args.t_end is not None else model.scene["t_end"]
    if t_end is None:
        raise c.Usage("--t-end", f"the scene {name!r} sets no t_end; give --t-end")
    if args.dt:
        dts = args.dt
    elif model.scene["dt"] is not None:
        dts = [model.scene["dt"] * 2.0 ** k for k in range(2, -6, -1)]
    else:
        raise c.Usage("--dt", f"the scene {name!r} sets no dt; give --dt")
    for dt in dts:  # a step count beyond 64 bits names the flag given (or the scene's key), not the library's dt
        try:
            _core.run_steps(0.0, t_end, dt)
        except (ValueError, OverflowError) as exc:
            raise step_error(exc, args, model) from None
    methods = [] if args.no_scipy else (args.scipy or list(SCIPY_METHODS))
    rtols = args.rtol or list(SCIPY_RTOLS)
    for note in model.scene["notes"]:
        print(f"note: {note}", file=sys.stderr)

    show = args.progress if args.progress is not None else c.isatty(sys.stderr)

    def progress(done, total, row):
        if show:
            what = f"{row['label']} {setting_text(row)}"
            print(f"\r  {row['contender']} {done}/{total}: {what:<48}", end="", file=sys.stderr, flush=True)

    t0 = time.perf_counter()
    try:
        ref = reference(model, t_end)
        rows = run_cost(model, schemes, dts, tols=args.tol or (), t_end=t_end, dofs=dofs, reference=ref, repeats=args.repeats,
                        progress=progress)
        if methods:
            rows += cost_scipy(model, methods, rtols, t_end=t_end, dofs=dofs, reference=ref, repeats=args.repeats,
                               max_time=args.max_time, progress=progress)
    except KeyboardInterrupt:
        print("\nnvib cost: interrupted", file=sys.stderr)
        return 130
    except (ValueError, TypeError) as exc:
        raise c.usage_from(exc, COST_FLAGS) from None
    if show:
        print("\r" + " " * 70 + "\r", end="", file=sys.stderr)
    s = model.scene
    head = f"{name}: {s['title']}" if s.get("title") else name
    lines = [f"# Work-precision: {head}", "",
             f"t_end = {t_end:g} s; error on {', '.join(dofs)}: max over the saved times of |u - u_ref|, "
             f"relative to max |u_ref|; reference: {ref.description}. Wall time: best of up to {args.repeats} "
             f"runs (whole call). SciPy solve_ivp on the same model (first-order form, the model's force), "
             f"atol = rtol x per-component scale, error at its own steps.", ""]
    if args.target is not None:
        lines.append(f"Cheapest run with error <= {args.target:g}:")
        lines.append("")
        for who in sorted({r["contender"] for r in rows}):
            r = cheapest(rows, args.target, contender=who)
            setting = "" if r is None else setting_text(r)
            lines.append(f"- {who}: " + ("none reaches it" if r is None else
                                         f"{r['label']}, {setting}: error {r['max_error']:.2e}, "
                                         f"{r['wall_time'] * 1e3:.3g} ms"))
        lines.append("")
    lines.append(markdown_table(rows))
    text = "\n".join(lines) + "\n"
    print(text)
    code = 0
    try:
        with open(table, "w", encoding="utf-8") as fh:
            fh.write(text)
        print(f"wrote {table}")
    except OSError as exc:
        print(f"nvib cost: error: --table: cannot write {table!r}: {exc.strerror or exc}", file=sys.stderr)
        code = 1
    try:
        plot_work_precision(rows, plot, title=f"{head}  (error on {', '.join(dofs)})", target=args.target)
        print(f"wrote {plot}")
    except OSError as exc:
        print(f"nvib cost: error: --plot: cannot write {plot!r}: {exc.strerror or exc}", file=sys.stderr)
        code = 1
    print(f"({time.perf_counter() - t0:.3g} s)", file=sys.stderr)
    return code
