"""Accuracy against cost on the five scenes: nvib's schemes, SciPy solve_ivp and hand-written C++ loops.

For each scene (pendulum, pendulum_ic2, hardening, building, vehicle) this runs
nvib.cost() over a grid of steps and nvib.cost_scipy() over a grid of
tolerances (RK45, DOP853, Radau with the analytic Jacobian, LSODA), and for the
building and the vehicle the hand-written C++ loops (LCDM and CEMDTS(0.45) on
plain arrays: cpp/building_loop.cpp, cpp/vehicle_loop.cpp) at the same steps,
their own saved displacements measured against the same reference. It writes

    results/cost.md             the tables below and how everything was measured
    results/cost_<scene>.png    one work-precision diagram per scene
    results/cost_rows.csv       every row (all fields of nvib.cost)

Adaptive runs (solve(..., tol=), tol 1e-2 ... 1e-6) of every scheme that takes a tol are a curve of
their own, compared at equal error with the best fixed step and the best SciPy run on every scene
(issue 21: vehicle >= 30x SciPy, building >= 50x).

Targets (issue 4), ratios measured in this one run:
  * equal error: 1e-6 relative on floor 6 (x6) of the building, 1e-5 on
    wheelset 1 (z_w1) of the vehicle: the cheapest nvib run reaching it is
    >= 30x faster than the cheapest SciPy run reaching it;
  * CPU time on the building at dt = 1e-4 s over 10 s: every nvib scheme
    (CEMDTS(0.45), Newmark and GαM(0.5, 0.5, 0.25, 0.5) with iteration "none"
    and "newton", PIM) >= 100x faster than Yang et al. 2017 (CEMDTS 1.89 s,
    Newmark 2.01 s, GαM 2.23 s, PIM 11.12 s), with its ratio to the
    hand-written loop.

    PYTHONPATH=python python benchmarks/cost.py [--scenes building vehicle] [--quick]
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import os
import shutil
import subprocess
import sys
import tempfile
import time

import numpy as np

import nvib
from nvib.analysis.cost import FIELDS, cheapest, markdown_table, plot_work_precision, setting_text, time_at_error

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from building import machine_info  # noqa: E402  (the same machine description as building.md)

CXXFLAGS = ["-std=c++17", "-O3", "-DNDEBUG"]
ETA = 0.45
MAX_SAVED = 100_000  # as nvib.cost: save every k-th step beyond this many states
PAPER_2017 = {"CEMDTS": 1.89, "Newmark": 2.01, "GαM": 2.23, "PIM": 11.12}  # s, dt = 1e-4, building


def schemes():
    return [nvib.CentralDifference(), nvib.CEMDTS(ETA),
            nvib.Newmark(iteration="one_iteration"), nvib.Newmark(iteration="newton"),
            nvib.GeneralizedAlpha(0.5, 0.5, 0.25, 0.5, iteration="one_iteration"),
            nvib.GeneralizedAlpha(0.5, 0.5, 0.25, 0.5, iteration="newton"),
            nvib.PreciseIntegration(), nvib.PreciseIntegration(interpolation=3)]


def geometric(start: float, factor: float, count: int) -> list[float]:
    return [start * factor ** -k for k in range(count)]


# dts: the step grid; max_steps: (explicit, others) caps on the number of steps of one run
SCENES = {
    "pendulum": dict(dofs=["theta"], dts=geometric(1.2, 2 ** 0.5, 17), rtols=geometric(1e-3, 10 ** 0.5, 17)),
    "pendulum_ic2": dict(dofs=["theta"], dts=geometric(1.2, 2 ** 0.5, 17), rtols=geometric(1e-3, 10 ** 0.5, 17)),
    "hardening": dict(dofs=["x"], dts=geometric(4e-3, 2 ** 0.5, 17), rtols=geometric(1e-3, 10 ** 0.5, 17)),
    "building": dict(dofs=["x6"], dts=geometric(1e-2, 2 ** 0.25, 29), rtols=geometric(1e-3, 10 ** 0.25, 33),
                     target=1e-6, loop="building"),
    "vehicle": dict(dofs=["z_w1"], dts=geometric(1e-3, 2 ** 0.25, 37), rtols=geometric(1e-3, 10 ** 0.25, 33),
                    target=1e-5, loop="vehicle"),
}
MAX_STEPS = (1_000_000, 300_000)
TOLS = geometric(1e-2, 10 ** 0.5, 9)  # adaptive runs (solve(..., tol=)): 1e-2 ... 1e-6
# The error at which the adaptive runs are compared with the best fixed step and the best SciPy run
ADAPTIVE_TARGETS = {"pendulum": 1e-4, "pendulum_ic2": 1e-4, "hardening": 1e-4, "building": 1e-6, "vehicle": 1e-5}


# ---------------------------------------------------------------- hand-written loops

def compile_loops(tmp: str, cxx: str) -> dict:
    out = {}
    for name in ("building_loop", "vehicle_loop"):
        exe = os.path.join(tmp, name)
        subprocess.run([cxx, *CXXFLAGS, os.path.join(HERE, "cpp", name + ".cpp"), "-o", exe], check=True)
        out[name] = exe
    return out


def loop_rows(kind: str, exe: str, model, ref, dts, dofs, t_end: float, repeats: int, tmp: str) -> list[dict]:
    """Rows of the hand-written loop (LCDM and CEMDTS) at each dt, error from its own saved displacements."""
    cols = [model.dofs.index(d) for d in dofs]
    rows = []
    for dt in dts:
        nsteps = round(t_end / dt)
        if nsteps > MAX_STEPS[0]:
            continue
        k = max(1, math.ceil(nsteps / (MAX_SAVED - 1)))
        prefix = os.path.join(tmp, f"{kind}_dump")
        args = [exe, repr(dt), repr(t_end), str(repeats), repr(ETA), str(k)]
        if kind == "vehicle":
            args += [repr(float(x)) for x in model.u0] + [repr(float(x)) for x in model.v0]
        p = subprocess.run(args + [f"--dump={prefix}"], check=True, capture_output=True, text=True)
        for line in p.stdout.splitlines():
            r = json.loads(line)
            scheme = r["scheme"]
            u = np.fromfile(f"{prefix}.{scheme}.bin" if kind == "vehicle" else f"{prefix}.{scheme}.{k}.bin")
            u = u.reshape(-1, model.n)[:, cols]
            steps = np.append(np.arange(0, nsteps + 1, k), nsteps) if nsteps % k else np.arange(0, nsteps + 1, k)
            t = steps * dt
            keep = t <= t_end * (1 + 1e-12)
            u_ref = ref.u(t[keep])[:, cols]
            with np.errstate(all="ignore"):
                err = float(np.max(np.abs(u[keep] - u_ref)) / np.max(np.abs(u_ref)))
            ok = math.isfinite(err)
            label = {"cd": "LCDM", "cemdts": f"CEMDTS({ETA:g})", "zhai": "Zhai(0.5,0.5)"}[scheme]
            rows.append({**{f: float("nan") for f in FIELDS}, "contender": "C++ loop", "scheme": label,
                         "label": f"hand-written {label}", "dt": dt, "t_end": t_end, "dofs": ",".join(dofs),
                         "max_error": err if ok else math.inf, "energy_error": float("nan"),
                         "wall_time": r["best"], "repeats": r["repeats"], "num_steps": r["steps"],
                         "force_evals": r["steps"] + 1, "newton_iters": 0, "factorizations": 0,
                         "status": "success" if ok else "diverged", "message": "", "reference": ref.description})
    return rows


# ---------------------------------------------------------------- the scenes

def run_scene(name: str, cfg: dict, exes: dict | None, args, tmp: str) -> dict:
    model = nvib.load_scene(name)
    t_end = model.scene["t_end"]
    t0 = time.perf_counter()
    ref = nvib.reference(model, t_end, check=True)
    ref_time = time.perf_counter() - t0
    dts = cfg["dts"][:: 2 if args.quick else 1]
    rtols = cfg["rtols"][:: 2 if args.quick else 1]
    rows = []
    adaptive_done: set = set()
    for scheme in schemes():
        cap = MAX_STEPS[0] if scheme.is_explicit else MAX_STEPS[1]
        mine = [dt for dt in dts if t_end / dt <= cap]
        rows += nvib.cost(model, [scheme], mine, dofs=cfg["dofs"], reference=ref, repeats=args.repeats)
        if scheme.adaptive and scheme.label not in adaptive_done:  # one adaptive curve per scheme and Newton mode
            adaptive_done.add(scheme.label)
            rows += [r for r in nvib.cost(model, [scheme], [model.scene["dt"]], tols=TOLS[:: 2 if args.quick else 1],
                                          dofs=cfg["dofs"], reference=ref, repeats=args.repeats)
                     if r["tol"] == r["tol"]]
        print(f"  {name}: {nvib.scheme_label(scheme)} done", file=sys.stderr)
    rows += nvib.cost_scipy(model, rtols=rtols, dofs=cfg["dofs"], reference=ref, repeats=args.repeats,
                            max_time=args.max_time)
    print(f"  {name}: SciPy done", file=sys.stderr)
    if exes and cfg.get("loop"):
        kind = cfg["loop"]
        rows += loop_rows(kind, exes[kind + "_loop"], model, ref, dts, cfg["dofs"], t_end, args.repeats, tmp)
    return {"model": model, "ref": ref, "ref_time": ref_time, "rows": rows}


def summary_table(rows: list[dict], levels=(1e-2, 1e-4, 1e-6, 1e-8)) -> list[str]:
    """Per curve: the cheapest run reaching each error level (wall time, and its dt or rtol)."""
    groups: dict = {}
    for r in rows:
        groups.setdefault((r["contender"], r["label"]), []).append(r)
    head = ["contender", "scheme", *[f"error <= {e:g}" for e in levels], "failed runs"]
    lines = ["| " + " | ".join(head) + " |", "|---|---|" + "---:|" * len(levels) + "---:|"]
    for (who, label), rs in groups.items():
        cells = [who, label]
        for e in levels:
            r = cheapest(rs, e)
            if r is None:
                cells.append("-")
            else:
                cells.append(f"{r['wall_time'] * 1e3:.3g} ms ({setting_text(r)})")
        cells.append(str(sum(r["status"] not in ("success", "skipped") for r in rs)))
        lines.append("| " + " | ".join(cells) + " |")
    return lines


def _adaptive(row: dict) -> bool:
    return row["contender"] == "nvib" and row["tol"] == row["tol"]


def adaptive_rows(results: dict) -> list[str]:
    """Per scene: the cheapest adaptive nvib run, fixed-step nvib run and SciPy run reaching the target error."""
    lines = ["| scene | error on | target | cheapest adaptive run | its error | [ms] | cheapest fixed step | its error "
             "| [ms] | cheapest SciPy run | its error | [ms] | fixed / adaptive | SciPy / adaptive |",
             "|---|---|---:|---|---:|---:|---|---:|---:|---|---:|---:|---:|---:|"]
    for name, res in results.items():
        target = ADAPTIVE_TARGETS[name]
        rows = res["rows"]
        ad = cheapest([r for r in rows if _adaptive(r)], target)
        fx = cheapest([r for r in rows if r["contender"] == "nvib" and not _adaptive(r)], target)
        sp = cheapest(rows, target, contender="scipy")

        def cells(r):
            return ["none reaches it", "", ""] if r is None else \
                [f"{r['label'].removesuffix(', tol')}, {setting_text(r)}", f"{r['max_error']:.2e}", f"{r['wall_time'] * 1e3:.3g}"]

        def ratio(r):
            return f"**{r['wall_time'] / ad['wall_time']:.2g}x**" if r is not None and ad is not None else "-"
        lines.append("| " + " | ".join([name, SCENES[name]["dofs"][0], f"{target:g}", *cells(ad), *cells(fx),
                                        *cells(sp), ratio(fx), ratio(sp)]) + " |")
    return lines


def equal_error_rows(results: dict) -> list[str]:
    lines = ["| scene | error on | target | cheapest nvib run | its error | nvib [ms] | cheapest SciPy run | "
             "its error | SciPy [ms] | speed-up | speed-up, interpolated | hand-written loop [ms] | target met |",
             "|---|---|---:|---|---:|---:|---|---:|---:|---:|---:|---:|---|"]
    for name in ("building", "vehicle"):
        if name not in results:
            continue
        res = results[name]
        target = SCENES[name]["target"]
        rows = res["rows"]
        nv = cheapest(rows, target, contender="nvib")
        sp = cheapest(rows, target, contender="scipy")
        lp = cheapest(rows, target, contender="C++ loop")
        at = time_at_error(rows, target)
        best_at = {who: min((t for (c, _), t in at.items() if c == who and math.isfinite(t)), default=math.nan)
                   for who in ("nvib", "scipy")}
        interp = best_at["scipy"] / best_at["nvib"]
        if nv and sp:
            ratio = sp["wall_time"] / nv["wall_time"]
            lines.append(
                f"| {name} | {SCENES[name]['dofs'][0]} | {target:g} | {nv['label']}, {setting_text(nv)} | "
                f"{nv['max_error']:.2e} | {nv['wall_time'] * 1e3:.3g} | {sp['label']}, rtol = {sp['rtol']:.2e} | "
                f"{sp['max_error']:.2e} | {sp['wall_time'] * 1e3:.3g} | **{ratio:.1f}x** | {interp:.1f}x | "
                + (f"{lp['wall_time'] * 1e3:.3g} ({lp['label'].removeprefix('hand-written ')}, dt = {lp['dt']:.3g})"
                   if lp else "-") + f" | {'yes' if ratio >= 30 else 'no'} |")
        else:
            lines.append(f"| {name} | {SCENES[name]['dofs'][0]} | {target:g} | "
                         f"{'none reaches it' if nv is None else nv['label']} | | | "
                         f"{'none reaches it' if sp is None else sp['label']} | | | - | - | - | no |")
    return lines


# ---------------------------------------------------------------- CPU time at dt = 1e-4 (the paper's table)

def cpu_time_table(exes: dict | None, rounds: int, repeats: int) -> list[str]:
    model = nvib.load_scene("building")
    dt, t_end = 1e-4, 10.0
    cases = [("CEMDTS", "CEMDTS(0.45)", nvib.CEMDTS(ETA)),
             ("Newmark", "Newmark, incremental (the paper's format)", nvib.Newmark(iteration="incremental")),
             ("Newmark", "Newmark, one Newton iteration per step", nvib.Newmark(iteration="one_iteration")),
             ("Newmark", "Newmark, Newton", nvib.Newmark(iteration="newton")),
             ("GαM", "GαM(0.5, 0.5, 0.25, 0.5), incremental (the paper's format)",
              nvib.GeneralizedAlpha(0.5, 0.5, 0.25, 0.5, iteration="incremental")),
             ("GαM", "GαM(0.5, 0.5, 0.25, 0.5), one Newton iteration per step",
              nvib.GeneralizedAlpha(0.5, 0.5, 0.25, 0.5, iteration="one_iteration")),
             ("GαM", "GαM(0.5, 0.5, 0.25, 0.5), Newton",
              nvib.GeneralizedAlpha(0.5, 0.5, 0.25, 0.5, iteration="newton")),
             ("PIM", "PIM (interpolation 2, 1 correction)", nvib.PreciseIntegration()),
             (None, "LCDM (context)", nvib.CentralDifference())]
    best = {label: math.inf for _, label, _ in cases}
    loop_best = math.inf
    stats = {}
    ref = nvib.reference(model, t_end)
    errors = {}
    for _ in range(rounds):
        if exes:
            p = subprocess.run([exes["building_loop"], repr(dt), repr(t_end), str(repeats), repr(ETA), "1"],
                               check=True, capture_output=True, text=True)
            loop = {json.loads(x)["scheme"]: json.loads(x) for x in p.stdout.splitlines()}
            loop_best = min(loop_best, loop["cemdts"]["best"])
        for _, label, scheme in cases:
            for _ in range(repeats):
                t0 = time.perf_counter()
                res = nvib.solve(model, scheme, dt=dt, t_end=t_end)  # every state of every DOF saved
                best[label] = min(best[label], time.perf_counter() - t0)
            stats[label] = res.stats
            if label not in errors:
                u_ref = ref.u(res.t)[:, 5]
                errors[label] = float(np.max(np.abs(res.u[:, 5] - u_ref)) / np.max(np.abs(u_ref)))
    lines = ["| scheme | nvib [ms] | 2017 [s] | 2017 / nvib (target >= 100) | target met | nvib / hand-written loop "
             "| force evals | Newton it. | factorisations | error on x6 |",
             "|---|---:|---:|---:|---|---:|---:|---:|---:|---:|"]
    for key, label, _ in cases:
        t = best[label]
        paper = PAPER_2017.get(key) if key else None
        s = stats[label]
        lines.append(f"| {label} | {t * 1e3:.3g} | {paper if paper else '-'} | "
                     + (f"**{paper / t:.0f}x**" if paper else "-") + " | "
                     + (("yes" if paper / t >= 100 else "no") if paper else "-") + " | "
                     + (f"{t / loop_best:.1f}x" if exes else "-") + f" | {s.num_force_evals:,} | "
                     f"{s.num_newton_iters:,} | {s.num_factorizations:,} | {errors[label]:.1e} |")
    lines += ["", "Hand-written loop (cpp/building_loop.cpp, CEMDTS(0.45), same dt, every state saved): "
                  + (f"{loop_best * 1e3:.3g} ms." if exes else "not run (no C++ compiler).")]
    return lines


# ---------------------------------------------------------------- main

def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scenes", nargs="+", default=list(SCENES), choices=list(SCENES))
    ap.add_argument("--quick", action="store_true", help="every other step and tolerance (a rough run)")
    ap.add_argument("--repeats", type=int, default=3, help="timed runs per row, the best is kept (default 3)")
    ap.add_argument("--max-time", type=float, default=5.0,
                    help="skip a SciPy method's tighter tolerances once one run takes longer (default 5 s)")
    ap.add_argument("--cpu-rounds", type=int, default=5, help="interleaved rounds of the CPU-time table")
    ap.add_argument("--no-cpu-table", action="store_true")
    ap.add_argument("--cxx", default=os.environ.get("CXX", "g++"))
    ap.add_argument("--out", default=os.path.join(HERE, "results"))
    args = ap.parse_args()
    load = os.getloadavg()[0]
    os.makedirs(args.out, exist_ok=True)
    started = time.perf_counter()
    results = {}
    with tempfile.TemporaryDirectory(prefix="nvib-cost-") as tmp:
        exes = compile_loops(tmp, args.cxx) if shutil.which(args.cxx) else None
        for name in args.scenes:
            print(f"{name} ...", file=sys.stderr)
            results[name] = run_scene(name, SCENES[name], exes, args, tmp)
        cpu = None if args.no_cpu_table else cpu_time_table(exes, args.cpu_rounds, args.repeats)
    lines = ["# Accuracy against cost", ""] + machine_info(args.cxx, load) + [
        f"- whole run: {time.perf_counter() - started:.0f} s" + (" (--quick)" if args.quick else ""), ""]
    lines += [
        "## How it is measured", "",
        "- **Error**: max over the saved times of |u − u_ref| on the named DOF, divided by max |u_ref| over the "
        "same times (`nvib.cost`). nvib saves every step (every k-th beyond 100,000 states); SciPy is measured "
        "at its own accepted steps (no dense output: its cheapest way to run, and fewer points to be wrong at); "
        "the hand-written loops save every step (every k-th, as nvib) and their own displacements are measured.",
        "- **Reference** (`nvib.reference`): the closed form for the pendulum scenes (Jacobi elliptic) and the "
        "hardening oscillator (x0 cn); DOP853 at rtol = 1e-12 with atol = rtol × per-component scale for the "
        "building and the vehicle (restarted where a wheel–rail contact opens or closes). Its check against a "
        "solve at rtol = 1e-13 is in each scene's section.",
        "- **SciPy**: `solve_ivp` on y = [u; v], y' = [v; −M⁻¹ f(u, v, t)] with the model's own C++ force "
        "(`Model.evaluate_force`), from the same initial state (the vehicle's static equilibrium); Radau and "
        "LSODA get the analytic Jacobian; atol = rtol × the per-component peaks of the reference (a favour to "
        "SciPy). A method's tighter tolerances are skipped once one of its runs takes longer than "
        f"{args.max_time:g} s.",
        "- **Wall time**: best of up to 3 runs of the whole call (`nvib.solve`, `solve_ivp`) from Python; a run "
        "over 1 s is timed once. The hand-written loops (`cpp/building_loop.cpp`, `cpp/vehicle_loop.cpp`, "
        f"`g++ {' '.join(CXXFLAGS)}`) are timed inside the C++ program (best of 3, output preallocated).",
        "- **Energy error**: nvib's energy balance (`Result.energy.relative_balance_error()`), in "
        "`cost_rows.csv`; the SciPy rows have it only for the conservative scenes (pendulum, hardening).",
        "- nvib runs with more than 1,000,000 steps (explicit schemes) or 300,000 steps (the others) are not made; "
        "the adaptive runs (`tol` from 1e-2 to 1e-6, the scene's dt their first step) are all made.",
        "- OpenSees: not in this comparison; the building side by side with OpenSees 3.7.1 is "
        "`benchmarks/opensees.py` (`opensees.md`).", ""]
    if cpu is not None or any(n in results for n in ("building", "vehicle")):
        lines += ["## Targets", ""]
    if any(n in results for n in ("building", "vehicle")):
        lines += ["### Equal error: nvib against SciPy (target: nvib >= 30x faster)", "",
                  "The cheapest measured run of each side that reaches the error (any scheme and step; any "
                  "method and tolerance). *Interpolated*: the same with each curve's time at exactly the "
                  "target error, interpolated in log–log between its two runs around it.", ""]
        lines += equal_error_rows(results) + [""]
    if results:
        lines += ["### Adaptive runs at equal error (issue 21: against SciPy, vehicle >= 30x, building >= 50x; "
                  "against the best fixed step)", "",
                  "The cheapest adaptive run (`solve(..., tol=)`, tol from 1e-2 to 1e-6, every scheme that takes "
                  "a tol; its time includes the companion run on double steps and any restart), the cheapest "
                  "fixed-step nvib run and the cheapest SciPy run reaching the error on the named DOF.", ""]
        lines += adaptive_rows(results) + [""]
    if cpu is not None:
        lines += ["### CPU time on the building at dt = 1e-4 s, t_end = 10 s (Yang et al. 2017, section 5.1)", "",
                  "Best of " f"{args.cpu_rounds} rounds x {args.repeats} runs of the whole `nvib.solve()` call, "
                  "every state of every DOF saved. The paper's figures are from 2017 hardware (its end time is not "
                  "stated; 10 s assumed). The hand-written loop implements CEMDTS only (the cheapest scheme); the "
                  "ratios of the implicit schemes and PIM to it include their extra algorithmic work.", ""]
        lines += cpu + [""]
    for name, res in results.items():
        ref = res["ref"]
        png = f"cost_{name}.png"
        target = SCENES[name].get("target")
        plot_work_precision(res["rows"], os.path.join(args.out, png),
                            title=f"{name}: {res['model'].scene['title']}", target=target)
        lines += [f"## {name}", "", f"![{name}]({png})", "",
                  f"Error on {', '.join(SCENES[name]['dofs'])}; reference: {ref.description}"
                  + (f" ({res['ref_time']:.2f} s to compute, {ref.num_force_evals:,} force evaluations; "
                     f"largest difference to rtol = {ref.check_rtol:g} on the measured DOF: "
                     f"{ref.check_difference[res['model'].dofs.index(SCENES[name]['dofs'][0])]:.1e})"
                     if ref.kind == "dop853" else "") + ".", "",
                  "Cheapest run reaching each error level:", ""]
        lines += summary_table(res["rows"]) + [""]
    text = "\n".join(lines) + "\n"
    kept = ""
    path = os.path.join(args.out, "cost.md")
    marker = "<!-- kept by cost.py: hand-written analysis below -->"
    if os.path.isfile(path):
        with open(path) as fh:
            old = fh.read()
        if marker in old:
            kept = "\n" + old[old.index(marker):]
    with open(path, "w") as fh:
        fh.write(text + kept)
    with open(os.path.join(args.out, "cost_rows.csv"), "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=["scene", *FIELDS])
        w.writeheader()
        for name, res in results.items():
            for r in res["rows"]:
                w.writerow({"scene": name, **r})
    print(text)
    for name, res in results.items():
        print(f"\n### {name}: all rows\n\n{markdown_table(res['rows'])}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
