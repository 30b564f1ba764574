"""The ``nvib`` command line (also ``python -m nvib``).

    nvib scenes                      the built-in scenes
    nvib run SCENE [options]         integrate a scene, print a summary, optionally --out / --plot
    nvib demo                        hardening oscillator with every scheme against its closed form
    nvib stability [options]         spectral radius and stability limit of schemes on a linear SDOF
    nvib paper OUTDIR                the figures and tables of Yang et al. (2017), and CEMDTS's eta study

Exit status: 0 success, 1 the run failed (diverged, Newton failed) or an
output could not be written, 2 bad input (the message names the argument).
"""

from __future__ import annotations

import argparse
import math
import os
import re
import sys
import time
from collections import Counter
from fractions import Fraction

SCHEME_CHOICES = ("lcdm", "cd", "cemdts", "zhai", "newmark", "galpha", "pim")
OUT_FORMATS = (".npz", ".csv")
PLOT_FORMATS = (".png", ".svg", ".pdf")
MAX_SAVED = 200_000  # default cap on saved states; --save-every overrides

# Scheme options: flag -> (constructor keyword, schemes it applies to)
_SCHEME_OPTIONS = {
    "velocity": ("velocity", ("lcdm", "cd")),
    "eta": ("eta", ("cemdts",)),
    "psi": ("psi", ("zhai",)),
    "phi": ("phi", ("zhai",)),
    "beta": ("beta", ("newmark", "galpha")),
    "gamma": ("gamma", ("newmark", "galpha")),
    "alpha_m": ("alpha_m", ("galpha",)),
    "alpha_f": ("alpha_f", ("galpha",)),
    "rho_inf": ("rho_inf", ("galpha",)),
    "iteration": ("iteration", ("newmark", "galpha")),
    "squarings": ("squarings", ("pim",)),
    "order": ("order", ("pim",)),
    "corrections": ("corrections", ("pim",)),
}


class _Usage(Exception):
    """Bad input discovered after parsing: becomes ``nvib run: error: argument X: ...`` and exit 2."""

    def __init__(self, argument: str | None, message: str):
        super().__init__(message)
        self.argument = argument
        self.message = message


def _flag(name: str) -> str:
    return "--" + name.replace("_", "-")


def _named(message: str, known: dict[str, str]) -> tuple[str | None, str]:
    """Split a library message 'eta: needs ...' into (the CLI argument, the rest) when the name is known."""
    m = re.match(r"^([A-Za-z_][\w, ]*?): (.*)$", message, re.S)
    if m:
        names = [n.strip() for n in m.group(1).split(",")]
        if all(n in known for n in names):
            return "/".join(known[n] for n in names), m.group(2)
    return None, message


# ---------------------------------------------------------------- argument types

def _real(text: str) -> float:
    """A finite real number; fractions such as 1/4 or 1/12 are accepted."""
    try:
        x = float(text)
    except ValueError:
        try:
            x = float(Fraction(text.strip()))
        except (ValueError, ZeroDivisionError):
            raise argparse.ArgumentTypeError(f"expected a number (such as 0.25 or 1/4), got {text!r}") from None
    if not math.isfinite(x):
        raise argparse.ArgumentTypeError(f"must be finite, got {text!r}")
    return x


def _positive_real(text: str) -> float:
    x = _real(text)
    if x <= 0:
        raise argparse.ArgumentTypeError(f"must be > 0, got {text!r}")
    return x


def _bound(text: str) -> float:
    """A positive real number or 'inf'."""
    if text.strip().lower() in ("inf", "infinity"):
        return math.inf
    return _positive_real(text)


def _positive_int(text: str) -> int:
    try:
        k = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None
    if k < 1:
        raise argparse.ArgumentTypeError(f"must be >= 1, got {text!r}")
    return k


def _int(text: str) -> int:
    try:
        return int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None


# ---------------------------------------------------------------- formatting helpers

def _seconds(x: float) -> str:
    if x < 1e-3:
        return f"{x * 1e6:.0f} us"
    if x < 1.0:
        return f"{x * 1e3:.3g} ms"
    return f"{x:.3g} s"


def _effect_summary(model) -> str:
    if not model.effects:
        return "(none)"
    counts = Counter(e.type for e in model.effects)
    return ", ".join(k if c == 1 else f"{k} x{c}" for k, c in counts.items())


def _table(rows: list[list[str]], right: set[int] = frozenset()) -> list[str]:
    widths = [max(len(r[i]) for r in rows) for i in range(len(rows[0]))]
    out = []
    for r in rows:
        cells = [c.rjust(w) if i in right else c.ljust(w) for i, (c, w) in enumerate(zip(r, widths))]
        out.append("  ".join(cells).rstrip())
    return out


# ---------------------------------------------------------------- nvib scenes

def _scenes(args) -> int:
    from . import load_scene, scene_names

    rows = [["name", "DOFs", "dt [s]", "t_end [s]", "effects", "title"]]
    sources = []
    for name in scene_names():
        try:
            m = load_scene(name)
        except (ValueError, OSError) as exc:  # a broken built-in scene should not hide the others
            rows.append([name, "?", "?", "?", "?", f"cannot load: {exc}"])
            continue
        s = m.scene
        rows.append([name, str(m.n), "-" if s["dt"] is None else f"{s['dt']:g}",
                     "-" if s["t_end"] is None else f"{s['t_end']:g}", _effect_summary(m), s["title"]])
        sources.append((name, s["source"]))
    lines = _table(rows, right={1, 2, 3})
    lines.insert(1, "-" * max(len(line) for line in lines))
    print("\n".join(lines))
    if sources:
        print("\nsources:")
        w = max(len(n) for n, _ in sources)
        for n, src in sources:
            print(f"  {n:<{w}}  {src or '-'}")
    print("\nrun one with: nvib run NAME  (--without takes an effect name or type; see nvib run --help)")
    return 0


# ---------------------------------------------------------------- nvib demo

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


# ---------------------------------------------------------------- nvib cost

COST_SCHEMES = ("lcdm", "cemdts", "newmark:none", "newmark", "galpha:none", "galpha", "pim")
COST_ITERATIONS = ("newton", "modified", "none")


def _cost_scheme(text: str):
    """NAME or NAME:ITERATION (newmark, galpha) -> a scheme with its default parameters."""
    from . import CEMDTS, CentralDifference, GeneralizedAlpha, Newmark, PreciseIntegration, Zhai

    name, _, iteration = text.partition(":")
    makers = {"lcdm": CentralDifference, "cd": CentralDifference, "cemdts": CEMDTS, "zhai": Zhai,
              "newmark": Newmark, "galpha": GeneralizedAlpha, "pim": PreciseIntegration}
    if name not in makers:
        raise _Usage("--schemes", f"unknown scheme {name!r} (expected {', '.join(SCHEME_CHOICES)}, "
                     "newmark and galpha optionally as NAME:newton|modified|none)")
    if iteration:
        if name not in ("newmark", "galpha"):
            raise _Usage("--schemes", f"{text!r}: only newmark and galpha take an iteration")
        if iteration not in COST_ITERATIONS:
            raise _Usage("--schemes", f"{text!r}: iteration must be one of {', '.join(COST_ITERATIONS)}")
        return makers[name](iteration=iteration)
    return makers[name]()


def _cost(args, parser) -> int:
    try:
        return _cost_checked(args)
    except _Usage as exc:
        parser.error(f"argument {exc.argument}: {exc.message}" if exc.argument else exc.message)
    return 2  # not reached: parser.error exits


def _cost_checked(args) -> int:
    from . import cost as run_cost, cost_scipy, reference
    from .cost import SCIPY_METHODS, SCIPY_RTOLS, cheapest, markdown_table, plot_work_precision

    model, notes = _load_model(args)
    name = model.scene["name"]
    plot = args.plot or f"cost_{name}.png"
    table = args.table or f"cost_{name}.md"
    _check_output("--plot", plot, PLOT_FORMATS)
    _check_output("--table", table, (".md",))
    schemes = [_cost_scheme(x) for x in (args.schemes or COST_SCHEMES)]
    dofs = args.dof or [model.scene["plot_dof"]]
    for d in dofs:
        if d not in model.dofs:
            raise _Usage("--dof", f"unknown DOF {d!r} in scene {name!r} (DOFs: {', '.join(model.dofs)})")
    t_end = args.t_end if args.t_end is not None else model.scene["t_end"]
    if t_end is None:
        raise _Usage("--t-end", f"the scene {name!r} sets no t_end; give --t-end")
    if args.dt:
        dts = args.dt
    elif model.scene["dt"] is not None:
        dts = [model.scene["dt"] * 2.0 ** k for k in range(2, -6, -1)]
    else:
        raise _Usage("--dt", f"the scene {name!r} sets no dt; give --dt")
    methods = [] if args.no_scipy else (args.scipy or list(SCIPY_METHODS))
    rtols = args.rtol or list(SCIPY_RTOLS)
    for note in notes:
        print(f"note: {note}", file=sys.stderr)

    show = args.progress if args.progress is not None else _isatty(sys.stderr)

    def progress(done, total, row):
        if show:
            what = f"{row['label']} dt = {row['dt']:g}" if row["contender"] == "nvib" else \
                f"{row['label']} rtol = {row['rtol']:g}"
            print(f"\r  {row['contender']} {done}/{total}: {what:<48}", end="", file=sys.stderr, flush=True)

    t0 = time.perf_counter()
    try:
        ref = reference(model, t_end)
        rows = run_cost(model, schemes, dts, t_end=t_end, dofs=dofs, reference=ref, repeats=args.repeats,
                        progress=progress)
        if methods:
            rows += cost_scipy(model, methods, rtols, t_end=t_end, dofs=dofs, reference=ref, repeats=args.repeats,
                               max_time=args.max_time, progress=progress)
    except KeyboardInterrupt:
        print("\nnvib cost: interrupted", file=sys.stderr)
        return 130
    except (ValueError, TypeError) as exc:
        arg, msg = _named(str(exc), {"dts": "--dt", "t_end": "--t-end", "rtols": "--rtol", "repeats": "--repeats",
                                     "max_time": "--max-time", "methods": "--scipy"})
        raise _Usage(arg, msg) from None
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
            setting = "" if r is None else (f"dt = {r['dt']:g}" if who == "nvib" else f"rtol = {r['rtol']:g}")
            lines.append(f"- {who}: " + ("none reaches it" if r is None else
                                         f"{r['label']}, {setting}: error {r['max_error']:.2e}, "
                                         f"{r['wall_time'] * 1e3:.3g} ms"))
        lines.append("")
    lines.append(markdown_table(rows))
    text = "\n".join(lines) + "\n"
    print(text)
    code = 0
    try:
        with open(table, "w") as fh:
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


# ---------------------------------------------------------------- nvib run

def _make_scheme(args):
    from . import CEMDTS, CentralDifference, GeneralizedAlpha, Newmark, PreciseIntegration, Zhai

    given = {opt: getattr(args, opt) for opt in _SCHEME_OPTIONS if getattr(args, opt) is not None}
    for opt in given:
        _, applies = _SCHEME_OPTIONS[opt]
        if args.scheme not in applies:
            raise _Usage(_flag(opt), f"does not apply to --scheme {args.scheme} (only to {', '.join(applies)})")
    kw = {_SCHEME_OPTIONS[opt][0]: val for opt, val in given.items()}
    if "rho_inf" in kw:
        clash = [o for o in ("alpha_m", "alpha_f", "beta", "gamma") if o in kw]
        if clash:
            raise _Usage("--rho-inf", f"sets alpha_m, alpha_f, beta and gamma itself; drop "
                         f"{', '.join(_flag(c) for c in clash)}")
    known = {_SCHEME_OPTIONS[o][0]: _flag(o) for o in _SCHEME_OPTIONS}
    try:
        if args.scheme in ("lcdm", "cd"):
            return CentralDifference(**kw)
        if args.scheme == "cemdts":
            return CEMDTS(**kw)
        if args.scheme == "zhai":
            return Zhai(**kw)
        if args.scheme == "newmark":
            return Newmark(**kw)
        if args.scheme == "galpha":
            if "rho_inf" in kw:
                return GeneralizedAlpha.from_rho_inf(kw.pop("rho_inf"), **kw)
            return GeneralizedAlpha(**kw)
        return PreciseIntegration(**kw)
    except (ValueError, TypeError) as exc:
        arg, msg = _named(str(exc), known)
        raise _Usage(arg or "--scheme", msg) from None


def _load_model(args):
    """The scene's model without the --without effects, and notes for the user."""
    from . import SceneError, load_scene
    from ._scenes import scene_from_dict, tomllib

    notes = []
    try:
        full = load_scene(args.scene)
    except (OSError, ValueError) as exc:  # unknown name, missing file, malformed scene (SceneError)
        raise _Usage("SCENE", str(exc).removeprefix("scene: ")) from None
    if not args.without:
        return full, notes
    names = sorted({e.name for e in full.effects if e.name})
    types = sorted({e.type for e in full.effects})
    for w in args.without:
        if w not in names and w not in types:
            raise _Usage("--without", f"no effect named or typed {w!r} in scene {full.scene['name']!r} "
                         f"(names: {', '.join(names) or '-'}; types: {', '.join(types) or '-'})")
    try:
        model = load_scene(args.scene, without=args.without)
    except SceneError as exc:
        if full.scene.get("initial_u") != "static_equilibrium" or "static_equilibrium" not in str(exc):
            raise _Usage("--without", str(exc)) from None
        # Without e.g. the wheel-rail contact a vehicle has no equilibrium to rest in:
        # start from the full scene's equilibrium instead (same initial state, fewer forces).
        with open(full.scene["path"], "rb") as fh:
            data = tomllib.load(fh)
        data.setdefault("initial", {})["u"] = [float(x) for x in full.u0]
        try:
            model = scene_from_dict(data, path=full.scene["path"], without=args.without)
        except SceneError as exc2:
            raise _Usage("--without", str(exc2)) from None
        model.scene["initial_u"] = "static equilibrium of the full scene"
        notes.append(f"without {', '.join(args.without)} the model has no static equilibrium; "
                     f"starting from that of the full scene")
    if not model.effects:
        notes.append("no effects left: the model is a free mass (u = u0 + v0 t)")
    return model, notes


def _check_output(arg: str, path: str, formats: tuple[str, ...]) -> None:
    ext = os.path.splitext(path)[1].lower()
    if ext not in formats:
        raise _Usage(arg, f"expected a file ending in {' or '.join(formats)}, got {path!r}")
    folder = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(folder):
        raise _Usage(arg, f"folder {folder!r} does not exist")
    if not os.access(folder, os.W_OK):
        raise _Usage(arg, f"folder {folder!r} is not writable")


def write_npz(path: str, result, extra: dict | None = None) -> None:
    """t, u, v, a, dofs, the stats counters, energy_* columns (if recorded) and run metadata."""
    import numpy as np

    data = {"t": result.t, "u": result.u, "v": result.v, "a": result.a, "dofs": np.array(result.dofs, dtype=str),
            "status": np.array(result.status), "scheme": np.array(repr(result.scheme)), "dt": np.array(result.dt)}
    for k, val in result.stats.as_dict().items():
        data[k] = np.array(val)
    if result.energy is not None:
        for k, val in result.energy.as_dict().items():
            data[f"energy_{k}"] = val
    if result.failure:
        data["failure"] = np.array(str(result.failure.get("message", result.status)))
    for k, val in (extra or {}).items():
        data[k] = np.array(val)
    with open(path, "wb") as fh:
        np.savez_compressed(fh, **data)


def write_csv(path: str, result) -> None:
    """Header t,u:<dof>,...,v:<dof>,...,a:<dof>,...[,energy:<term>,...]; full double precision."""
    import numpy as np

    cols = [result.t[:, None], result.u, result.v, result.a]
    head = ["t"] + [f"{q}:{d}" for q in ("u", "v", "a") for d in result.dofs]
    if result.energy is not None:
        for k, val in result.energy.as_dict().items():
            cols.append(np.asarray(val)[:, None])
            head.append(f"energy:{k}")
    table = np.hstack(cols) if len(result.t) else np.zeros((0, len(head)))
    np.savetxt(path, table, fmt="%.17g", delimiter=",", header=",".join(head), comments="")


def _failure_line(result, scheme, dt: float) -> str:
    f = result.failure or {}
    t, step = f.get("t"), f.get("step")
    msg = str(f.get("message", result.status))
    where = f" at t = {t:g} s (step {step})" if t is not None else ""
    # the library's message repeats the time; keep its detail only
    detail = re.sub(r"^diverged at t = [^:]*: ?", "", msg)
    detail = re.sub(r" at t = [-+0-9.eE]+", "", detail)
    if result.status == "diverged":
        head, hint = f"diverged{where}", "try a smaller --dt" + (" or an implicit scheme" if scheme.is_explicit else "")
    elif result.status == "newton_failed":
        full_newton = getattr(scheme, "iteration", "newton") == "newton"
        head, hint = f"Newton iteration failed{where}", "try a smaller --dt" + ("" if full_newton else
                                                                                " or --iteration newton")
    elif result.status == "singular_matrix":
        head, hint = f"singular iteration matrix{where}", "try a smaller --dt"
    else:
        head, hint = f"run failed ({result.status}){where}", ""
    line = f"{head} with {scheme.name}, dt = {dt:g} s"
    if detail:
        line += f": {detail}"
    return line + (f" ({hint})" if hint else "")


def _run(args, parser) -> int:
    try:
        return _run_checked(args)
    except _Usage as exc:
        parser.error(f"argument {exc.argument}: {exc.message}" if exc.argument else exc.message)
    return 2  # not reached: parser.error exits


def _run_checked(args) -> int:
    import numpy as np

    from . import _core, solve
    from ._progress import ProgressBar

    if args.out:
        _check_output("--out", args.out, OUT_FORMATS)
    if args.plot:
        _check_output("--plot", args.plot, PLOT_FORMATS)
        import importlib.util

        if importlib.util.find_spec("matplotlib") is None:
            raise _Usage("--plot", "needs matplotlib (pip install matplotlib)")
    scheme = _make_scheme(args)
    model, notes = _load_model(args)
    dof = args.dof if args.dof is not None else model.scene["plot_dof"]
    if dof not in model.dofs:
        raise _Usage("--dof", f"unknown DOF {dof!r} in scene {model.scene['name']!r} (DOFs: {', '.join(model.dofs)})")
    dt = args.dt if args.dt is not None else model.scene["dt"]
    t_end = args.t_end if args.t_end is not None else model.scene["t_end"]
    if dt is None:
        raise _Usage("--dt", f"the scene {model.scene['name']!r} sets no dt; give --dt")
    if t_end is None:
        raise _Usage("--t-end", f"the scene {model.scene['name']!r} sets no t_end; give --t-end")
    known = {"dt": "--dt", "t_end": "--t-end", "save_every": "--save-every", "max_displacement": "--max-displacement",
             "max_energy_error": "--max-energy-error"}
    try:
        n_steps = _core.steps_to_reach(0.0, t_end, dt)
    except (ValueError, OverflowError) as exc:
        arg, msg = _named(str(exc), known)
        raise _Usage(arg or "--dt", msg) from None
    save_every = args.save_every if args.save_every is not None else max(1, math.ceil(n_steps / MAX_SAVED))

    for note in notes:
        print(f"note: {note}", file=sys.stderr)
    show = args.progress if args.progress is not None else _isatty(sys.stderr)
    bar = ProgressBar(sys.stderr, enabled=show)
    t0 = time.perf_counter()
    try:
        res = solve(model, scheme, dt=dt, t_end=t_end, save_every=save_every, throw=False,
                    max_displacement=args.max_displacement, progress=bar if show else None, energy=args.energy,
                    max_energy_error=args.max_energy_error)
    except KeyboardInterrupt:
        bar.close(done=False)
        print("nvib run: interrupted", file=sys.stderr)
        return 130
    except (ValueError, TypeError) as exc:
        bar.close(done=False)
        arg, msg = _named(str(exc), known)
        raise _Usage(arg, msg) from None
    elapsed = time.perf_counter() - t0
    bar.close(done=res.status == "success")

    _print_summary(res, model, scheme, dof, dt, t_end, save_every, elapsed, args)
    code = 0
    if args.out:
        try:
            extra = {"scene": model.scene["name"], "t_end": t_end, "save_every": save_every,
                     "without": np.array(list(args.without or []), dtype=str)}
            if args.out.lower().endswith(".npz"):
                write_npz(args.out, res, extra)
            else:
                write_csv(args.out, res)
            print(f"wrote {args.out}")
        except OSError as exc:
            print(f"nvib run: error: --out: cannot write {args.out!r}: {exc.strerror or exc}", file=sys.stderr)
            code = 1
    if args.plot:
        from .plot import plot_run

        try:
            plot_run(res, model, dof, args.plot)
            print(f"wrote {args.plot}")
        except OSError as exc:
            print(f"nvib run: error: --plot: cannot write {args.plot!r}: {exc.strerror or exc}", file=sys.stderr)
            code = 1
    if res.status != "success":
        print(f"nvib run: error: {_failure_line(res, scheme, dt)}", file=sys.stderr)
        return 1
    return code


def _relative_balance_error(res) -> float:
    import numpy as np

    with np.errstate(all="ignore"):  # a run that blew up has inf energies: inf / inf
        return res.energy.relative_balance_error()


def _isatty(stream) -> bool:
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError):
        return False


def _print_summary(res, model, scheme, dof, dt, t_end, save_every, elapsed, args) -> None:
    s = model.scene
    stats = res.stats.as_dict()
    title = f"{s['name']}: {s['title']}" if s.get("title") else s["name"]
    lines = [("scene", title)]
    if args.without:
        lines.append(("without", ", ".join(args.without)))
    lines.append(("scheme", repr(scheme)))
    saved = f"{len(res.t)} state{'s' if len(res.t) != 1 else ''} saved"
    if save_every > 1:
        saved += f" (every {save_every} steps)"
    lines.append(("steps", f"{stats['num_steps']} of {res.num_steps_requested}, dt = {dt:g} s, "
                           f"t_end = {t_end:g} s; {saved}"))
    lines.append(("status", res.status))
    lines.append(("wall time", f"{_seconds(elapsed)} (integrator loop {_seconds(stats['wall_time'])})"))
    counters = [(k.removeprefix("num_"), v) for k, v in stats.items() if k not in ("wall_time", "num_steps")]
    lines.append(("counters", ", ".join(f"{k} {v}" for k, v in counters)))
    if len(res.t):
        j = res.dofs.index(dof)
        u, v, a = (float(x[-1, j]) + 0.0 for x in (res.u, res.v, res.a))  # + 0.0: no "-0"
        lines.append((f"final {dof}", f"t = {res.t[-1]:.6g} s: u = {u:.9g}, v = {v:.9g}, a = {a:.9g}"))
    if res.energy is not None:
        rel = _relative_balance_error(res)
        lines.append(("energy", f"relative balance error {rel:.3e} (max |K + P + D - W - E0| / max energy)"
                      if math.isfinite(rel) else "relative balance error: n/a (the energies overflowed)"))
    w = max(len(k) for k, _ in lines)
    print("\n".join(f"{k:<{w}}  {v}" for k, v in lines))


# ---------------------------------------------------------------- nvib stability

STABILITY_SCHEMES = ("cd", "cemdts", "zhai", "newmark", "galpha", "pim")
STABILITY_OMEGAS = (0.1, 1.0, 2.0, 10.0, 100.0)  # where the table shows the spectral radius


def _stability(args, parser) -> int:
    try:
        return _stability_checked(args)
    except _Usage as exc:
        parser.error(f"argument {exc.argument}: {exc.message}" if exc.argument else exc.message)
    return 2  # not reached: parser.error exits


def _stability_schemes(args) -> list:
    """(label, scheme) for each of --schemes, each given only the options that apply to it."""
    from .stability import scheme_label

    names = list(dict.fromkeys(args.schemes))
    for opt, (_, applies) in _SCHEME_OPTIONS.items():
        if getattr(args, opt, None) is not None and not set(applies) & set(names):
            raise _Usage(_flag(opt), f"applies to none of --schemes {' '.join(names)} (only to {', '.join(applies)})")
    out = []
    for name in names:
        kw = {opt: (getattr(args, opt, None) if name in applies else None)
              for opt, (_, applies) in _SCHEME_OPTIONS.items()}
        scheme = _make_scheme(argparse.Namespace(scheme=name, **kw))
        label = scheme_label(scheme)
        if label not in [lab for lab, _ in out]:  # lcdm and cd are one scheme
            out.append((label, scheme))
    return out


def _stability_checked(args) -> int:
    import numpy as np

    from . import stability

    if not 0.0 <= args.xi < 1.0:
        raise _Usage("--xi", f"the damping ratio needs 0 <= xi < 1, got {args.xi:g}")
    lo, hi = stability.OMEGA_RANGE
    if args.omega_max > hi:
        raise _Usage("--omega-max", f"must be <= {hi:g}, got {args.omega_max:g}")
    if not lo <= args.omega_min < args.omega_max:
        raise _Usage("--omega-min", f"must lie in [{lo:g}, --omega-max {args.omega_max:g}), got {args.omega_min:g}")
    if args.plot:
        _check_output("--plot", args.plot, PLOT_FORMATS)
        import importlib.util

        if importlib.util.find_spec("matplotlib") is None:
            raise _Usage("--plot", "needs matplotlib (pip install matplotlib)")
    schemes = _stability_schemes(args)
    limit = max(stability.OMEGA_LIMIT, args.omega_max)

    print(f"Linear SDOF u'' + 2 xi w u' + w^2 u = 0, xi = {args.xi:g}: amplification matrix of one step "
          f"of each scheme's stepper, Omega = w dt")
    print(f"Omega_crit: smallest Omega with spectral radius rho > 1 + {stability.RHO_TOL:g} "
          f"(scan and bisection up to {limit:g}; 'none' = stable up to there)")
    print()
    rows = [["scheme", "Omega_crit"] + [f"rho({om:g})" for om in STABILITY_OMEGAS]]
    crits = []
    for label, scheme in schemes:
        oc = stability.critical_omega_h(scheme, args.xi, omega_max=limit)
        crits.append(oc)
        rho = stability.spectral_radius(scheme, np.array(STABILITY_OMEGAS), args.xi)
        rows.append([label, "none" if math.isinf(oc) else f"{oc:.6g}"] + [f"{r:.6g}" for r in rho])
    lines = _table(rows, right=set(range(1, len(rows[0]))))
    lines.insert(1, "-" * max(len(line) for line in lines))
    print("\n".join(lines))
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


# ---------------------------------------------------------------- nvib paper

def _paper(args, parser) -> int:
    try:
        return _paper_checked(args)
    except _Usage as exc:
        parser.error(f"argument {exc.argument}: {exc.message}" if exc.argument else exc.message)
    return 2  # not reached: parser.error exits


def _paper_checked(args) -> int:
    from . import paper

    out = os.path.abspath(args.outdir)
    if os.path.exists(out) and not os.path.isdir(out):
        raise _Usage("OUTDIR", f"{args.outdir!r} exists and is not a folder")
    show = args.progress if args.progress is not None else _isatty(sys.stderr)
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


# ---------------------------------------------------------------- parser

_RUN_EPILOG = """\
schemes: lcdm/cd = central difference (leapfrog), cemdts = CEMDTS (default, eta = 0.45),
zhai = Zhai (psi = phi = 1/2), newmark = Newmark (beta = 1/4, gamma = 1/2, Newton),
galpha = generalized-alpha (alpha_m = alpha_f = 1/2, beta = 1/4, gamma = 1/2, or --rho-inf),
pim = precise integration (squarings 20, order 2, 1 correction). Parameters accept
fractions (--eta 1/12). Exit status: 0 success, 1 the run failed (diverged, Newton
failed; partial --out/--plot still written), 2 bad input.

examples:
  nvib run hardening --scheme newmark --plot hardening.png
  nvib run vehicle --without contact --dof z_w1 --energy --out vehicle.npz
  nvib run building --scheme galpha --rho-inf 0.8 --dt 1e-3 --save-every 10 --out building.csv
"""


def _add_scheme_parameters(g, *, iteration: bool = True) -> None:
    """The scheme parameters as options (the keys of _SCHEME_OPTIONS); each applies to the schemes that have it."""
    g.add_argument("--velocity", choices=("synchronized", "half_step"),
                   help="lcdm/cd: velocity carried and reported (default synchronized)")
    g.add_argument("--eta", type=_real, help="cemdts: eta (default 0.45)")
    g.add_argument("--psi", type=_real, help="zhai: psi (default 1/2)")
    g.add_argument("--phi", type=_real, help="zhai: phi (default 1/2)")
    g.add_argument("--beta", type=_real, help="newmark/galpha: beta (default 1/4)")
    g.add_argument("--gamma", type=_real, help="newmark/galpha: gamma (default 1/2)")
    g.add_argument("--alpha-m", type=_real, help="galpha: alpha_m (default 1/2)")
    g.add_argument("--alpha-f", type=_real, help="galpha: alpha_f (default 1/2)")
    g.add_argument("--rho-inf", type=_real, metavar="R",
                   help="galpha: spectral radius at infinity; sets alpha_m, alpha_f, beta, gamma")
    if iteration:
        g.add_argument("--iteration", choices=("newton", "modified", "none"),
                       help="newmark/galpha: equilibrium iteration (default newton)")
    g.add_argument("--squarings", type=_int, help="pim: 2^N squarings of the exponential (default 20)")
    g.add_argument("--order", type=_int, help="pim: interpolation order of the load term (default 2)")
    g.add_argument("--corrections", type=_int, help="pim: corrector passes (default 1)")


def build_parser() -> argparse.ArgumentParser:
    from . import __version__

    parser = argparse.ArgumentParser(prog="nvib", description="Time integration of nonlinear vibration systems.")
    parser.add_argument("--version", action="version", version=f"nvib {__version__}")
    parser.add_argument("--cmake-dir", action="store_true", help="print the folder of nvibConfig.cmake and exit")
    parser.add_argument("--include-dir", action="store_true", help="print the folder of the C++ headers and exit")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")

    p = sub.add_parser("scenes", help="list the built-in scenes", description="List the built-in scenes.")
    p.set_defaults(func=lambda args, parser: _scenes(args), subparser=p)

    p = sub.add_parser("run", help="integrate a scene and summarise, save or plot the run",
                       usage="%(prog)s SCENE [--scheme NAME] [scheme parameters] [--dt DT] [--t-end T] "
                             "[--without NAME ...] [--dof NAME] [--energy] [--out FILE] [--plot PNG] [...]",
                       description="Integrate a scene (a built-in name or a .toml file) with one scheme.",
                       epilog=_RUN_EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("scene", metavar="SCENE", help="built-in scene name (see nvib scenes) or path to a .toml scene")
    g = p.add_argument_group("scheme")
    g.add_argument("--scheme", choices=SCHEME_CHOICES, default="cemdts", help="time-stepping scheme (default cemdts)")
    _add_scheme_parameters(g)
    g = p.add_argument_group("run")
    g.add_argument("--dt", type=_positive_real, help="time step [s] (default: the scene's)")
    g.add_argument("--t-end", type=_positive_real, metavar="T", help="end time [s] (default: the scene's)")
    g.add_argument("--save-every", type=_positive_int, metavar="K",
                   help=f"save every K-th step (default 1, or more to keep at most {MAX_SAVED} states)")
    g.add_argument("--without", nargs="+", action="extend", metavar="NAME",
                   help="leave out effects by name or type (repeatable)")
    g.add_argument("--max-displacement", type=_bound, metavar="U",
                   help="stop as diverged once some |u_i| exceeds U (default: 1e10 x max(1, max|u0|, "
                        "max|v0| x duration); 'inf': only non-finite states)")
    g.add_argument("--dof", metavar="NAME", help="DOF to report and plot (default: the scene's plot_dof)")
    g.add_argument("--energy", action="store_true",
                   help="record the energy balance; a run whose balance error exceeds --max-energy-error times "
                        "the energy scale stops as diverged")
    g.add_argument("--max-energy-error", type=_bound, metavar="F",
                   help="with --energy: stop as diverged once the energy balance error exceeds F times the energy "
                        "scale (default 0.5; 'inf': no check)")
    g = p.add_argument_group("output")
    g.add_argument("--out", metavar="FILE", help="write the history to FILE.npz or FILE.csv")
    g.add_argument("--plot", metavar="PNG", help="write histories, phase locus (and energy) to this PNG")
    g.add_argument("--progress", action=argparse.BooleanOptionalAction, default=None,
                   help="progress bar on stderr for runs over a second (default: when stderr is a terminal)")
    p.set_defaults(func=_run, subparser=p)

    p = sub.add_parser("cost", help="work-precision diagram: error against wall time for schemes and SciPy",
                       description="Run each scheme at each step (and SciPy solve_ivp at each tolerance) on a "
                                   "scene, measure the error against the reference (closed form or DOP853) and "
                                   "the wall time, write a work-precision PNG and a markdown table.")
    p.add_argument("scene", metavar="SCENE", help="built-in scene name (see nvib scenes) or path to a .toml scene")
    p.add_argument("--schemes", nargs="+", metavar="NAME",
                   help="schemes, newmark/galpha optionally as NAME:newton|modified|none "
                        f"(default: {' '.join(COST_SCHEMES)})")
    p.add_argument("--dt", type=_positive_real, nargs="+", help="steps (default: the scene's dt x 4, 2, 1, ... 1/32)")
    p.add_argument("--t-end", type=_positive_real, metavar="T", help="end time [s] (default: the scene's)")
    p.add_argument("--dof", nargs="+", metavar="NAME", help="DOFs the error is measured on (default: plot_dof)")
    p.add_argument("--scipy", nargs="+", metavar="METHOD", choices=("RK23", "RK45", "DOP853", "Radau", "BDF", "LSODA"),
                   help="solve_ivp methods (default: RK45 DOP853 Radau LSODA)")
    p.add_argument("--no-scipy", action="store_true", help="leave SciPy out")
    p.add_argument("--rtol", type=_positive_real, nargs="+", help="SciPy tolerances (default 1e-3 ... 1e-10)")
    p.add_argument("--repeats", type=_positive_int, default=3, help="timed runs per row, the best is kept (default 3)")
    p.add_argument("--max-time", type=_positive_real, default=30.0, metavar="S",
                   help="skip a SciPy method's tighter tolerances once a run takes longer (default 30 s)")
    p.add_argument("--target", type=_positive_real, metavar="ERR",
                   help="draw this error level and name the cheapest run of each contender reaching it")
    p.add_argument("--plot", metavar="PNG", help="work-precision diagram (default cost_SCENE.png)")
    p.add_argument("--table", metavar="MD", help="markdown table (default cost_SCENE.md)")
    p.add_argument("--progress", action=argparse.BooleanOptionalAction, default=None,
                   help="progress on stderr (default: when stderr is a terminal)")
    p.set_defaults(func=_cost, subparser=p, without=None)

    p = sub.add_parser("paper", help="regenerate the figures and tables of Yang et al. (2017) into a folder",
                       description="Run the cases of Yang et al. (2017) with its schemes (Newmark and GaM both in "
                                   "the paper's incremental format and with Newton iteration, LCDM with synchronized "
                                   "and half-step velocity) against closed forms or DOP853 references, and write "
                                   "Figs. 2-4, 6, 7, 9-11, Table 1, the CPU-time table, CEMDTS's eta study "
                                   "(PNG and CSV) and summary.md into OUTDIR.")
    p.add_argument("outdir", metavar="OUTDIR", help="folder for the figures and tables (created if missing)")
    p.add_argument("--repeats", type=_positive_int, default=3,
                   help="timed runs per figure run, the best is kept (default 3)")
    p.add_argument("--cpu-repeats", type=_positive_int, default=5,
                   help="timed runs per scheme in the CPU-time table (default 5)")
    p.add_argument("--progress", action=argparse.BooleanOptionalAction, default=None,
                   help="report each finished part on stderr (default: when stderr is a terminal)")
    p.set_defaults(func=_paper, subparser=p)

    p = sub.add_parser("demo", help="hardening oscillator with every scheme against its closed form")
    p.add_argument("--dt", type=float, default=1e-3, help="time step [s] (default 1e-3, the paper's)")
    p.add_argument("--repeats", type=int, default=5, help="timing repeats (the best is shown)")
    p.add_argument("--plot", metavar="PNG", help="write error histories and phase loci to this PNG")
    p.set_defaults(func=lambda args, parser: _demo(args), subparser=p)

    p = sub.add_parser("stability", help="spectral radius and stability limit of schemes on a linear SDOF",
                       description="Spectral radius of each scheme's amplification matrix for the linear SDOF "
                                   "u'' + 2 xi w u' + w^2 u = 0 against Omega = w dt (taken from the steppers "
                                   "themselves), and the stability limit Omega_crit.",
                       epilog="example:\n  nvib stability --schemes cd cemdts zhai newmark galpha pim --xi 0.05 "
                              "--plot rho.png",
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--schemes", nargs="+", choices=SCHEME_CHOICES, default=list(STABILITY_SCHEMES), metavar="NAME",
                   help=f"schemes to compare, from {', '.join(SCHEME_CHOICES)} (default: {' '.join(STABILITY_SCHEMES)})")
    p.add_argument("--xi", type=_real, default=0.0, help="damping ratio, 0 <= xi < 1 (default 0)")
    g = p.add_argument_group("scheme parameters (each applies to the schemes that have it)")
    _add_scheme_parameters(g, iteration=False)  # a linear SDOF: the iteration changes nothing
    g = p.add_argument_group("plot")
    g.add_argument("--plot", metavar="PNG", help="write spectral radius against Omega (log axis) to this PNG")
    g.add_argument("--omega-min", type=_positive_real, default=1e-2, metavar="W", help="plot from Omega = W (default 0.01)")
    g.add_argument("--omega-max", type=_positive_real, default=100.0, metavar="W",
                   help="plot up to Omega = W (default 100; Omega_crit is searched up to max(W, 1e4))")
    g.add_argument("--points", type=_positive_int, default=300, help="Omega values on the plot (default 300)")
    p.set_defaults(func=_stability, subparser=p)
    return parser


def main(argv: list[str] | None = None) -> int:
    from . import cmake_dir, include_dir

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
    if args.command == "demo" and not (args.dt > 0):
        parser.error("--dt must be > 0")
    return args.func(args, args.subparser)  # usage errors then read "nvib run: error: ..."


if __name__ == "__main__":
    sys.exit(main())
