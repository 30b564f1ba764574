"""Scale: time per step and memory against the number of DOFs, from 10 to 10^6.

Models (nvib.scenes, built from effect arrays):
  * chain(n): a shear chain of n storeys (hardening storey springs, dampers, a
    ground acceleration); tridiagonal iteration matrix;
  * lattice(nx, nx): an nx x nx mass-spring lattice (linear and cubic ties,
    dampers, ground springs, a ground acceleration); its iteration matrix has
    bandwidth nx, so a sparse factorisation fills in.
Schemes: CentralDifference, CEMDTS(0.45) (explicit), Newmark and
GeneralizedAlpha with full Newton (implicit; sparse LDLT chosen automatically
above 64 DOFs), the implicit ones up to the size where one step takes a second.

Each case runs in a fresh process (`scale.py --case MODEL N SCHEME`): it
builds the model, picks a number of steps worth about half a second of work
(a short probe first), runs solve() saving only the first and last states,
and reports Stats.wall_time per step (the C++ loop), the build time, and the
peak resident memory above the process's own before the build, less the saved
history: bytes per DOF of the model, the stepper and the run.

Against: a hand-written C++ central-difference loop of the same chain
(benchmarks/cpp/chain_loop.cpp, plain arrays, -O3), run at every n. Targets
(issue "Scale"): explicit exponent <= 1.05 from 10^3 to 10^6 with a constant
within 2x of the hand-written loop at n = 10^5; Newmark + Newton on the chain
exponent <= 1.2 from 10^3 to 10^5; at most 400 bytes per DOF for the chain
beyond the saved history. Exponents are least-squares slopes of log(time per
step) against log(n).

    python benchmarks/scale.py [--quick] [--out benchmarks/results/scale.md] [--replot]
"""

from __future__ import annotations

import argparse
import json
import math
import os
import resource
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
SCHEMES = {"cd": "CentralDifference", "cemdts": "CEMDTS(0.45)", "newmark": "Newmark (newton)",
           "galpha": "GαM(0.5,0.5) (newton)"}
EXPLICIT = ("cd", "cemdts")
CHAIN_N = (10, 100, 1_000, 10_000, 100_000, 1_000_000)
LATTICE_NX = (3, 10, 32, 100, 316, 1000)
TARGET_WORK = 0.5  # seconds of stepping per case
SLOW_STEP = 1.0    # implicit cases stop at the size where a step takes this long
MEMORY_FROM = 10_000  # below, the process's own pages (Python, NumPy, SciPy, the module) dominate the difference


def rss_bytes() -> int:
    with open("/proc/self/status") as fh:
        for line in fh:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) * 1024
    return 0


def run_case(model_kind: str, size: int, key: str) -> dict:
    """One case, in this (fresh) process."""
    import numpy as np

    import nvib

    schemes = {"cd": nvib.CentralDifference(), "cemdts": nvib.CEMDTS(0.45), "newmark": nvib.Newmark(),
               "galpha": nvib.GeneralizedAlpha()}
    # warm up on a tiny model first: the modules imported on first use (scipy.sparse, ...) and the code
    # pages touched are the process's, not the model's
    small = nvib.scenes.chain(10) if model_kind == "chain" else nvib.scenes.lattice(3, 3)
    nvib.solve(small, schemes[key], dt=small.scene["dt"], t_end=4 * small.scene["dt"], u0=np.full(small.n, 1e-4))
    del small
    base = rss_bytes()
    t0 = time.perf_counter()
    model = nvib.scenes.chain(size) if model_kind == "chain" else nvib.scenes.lattice(size, size)
    build = time.perf_counter() - t0
    n = model.n
    dt = model.scene["dt"]
    scheme = schemes[key]
    # a start away from rest, so that every implicit step iterates
    u0 = np.linspace(1e-4, 2e-4, n) if model_kind == "chain" else np.full(n, 1e-4)
    # A run's time is its start (copying the model into the stepper, the divergence bound's set-up,
    # the history) plus its steps: per step is the difference between runs of `steps` and of 2 steps
    # over the steps between (at 10^6 DOFs the start is worth 15 to 30 explicit steps, and a few
    # steps divided into a whole run's time reported it as step time).
    # (a result is dropped before the next run starts: two histories alive at once would be counted
    # in the peak memory as the model's)
    def best_of(k, rounds, keep=False):
        t, r = math.inf, None
        for _ in range(rounds):
            r = None
            nvib._core.ordering_cache(clear=True)  # every run orders its matrices, as the first (no run reuses another's)
            r = nvib.solve(model, scheme, dt=dt, t_end=k * dt, save_every=k, u0=u0)
            t = min(t, r.stats.wall_time)
        return t, (r if keep else None)
    short_t, _ = best_of(2, 1)
    if key not in EXPLICIT and short_t / 2 > SLOW_STEP:  # a few slow steps: 2 and 4 of them, once
        steps, rounds = 4, 1
    else:
        longer_t, _ = best_of(6, 1)
        # (an implicit run's first steps iterate more than its later ones: the difference of two short
        # runs may be small or noisy, so it is not taken below a tenth of the short run's mean step)
        per = max((longer_t - short_t) / 4, 0.05 * short_t, 1e-9)
        steps = int(min(100_000, max(8, TARGET_WORK / per)))
        rounds = 1 if steps <= 8 else 3  # the best of three runs (one where a run is a few slow steps)
        short_t, _ = best_of(2, rounds)
    best, res = best_of(steps, rounds, keep=True)
    # (a difference at or below zero is not resolved: a few slow steps hidden by the variation of a start
    # of tens of seconds; it is reported as such, not as a step of no time)
    resolved = best > short_t
    per_step = (best - short_t) / (steps - 2) if resolved else math.nan
    start = max(short_t - 2 * per_step, 0.0) if resolved else short_t
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
    history = res.t.nbytes + res.u.nbytes + res.v.nbytes + res.a.nbytes
    s = res.stats
    return {"model": model_kind, "size": size, "n": n, "scheme": key, "steps": s.num_steps,
            "per_step": per_step, "start": start, "build": build, "bytes_per_dof": (peak - base - history) / n,
            "peak_mb": peak / 1e6, "linear_solver": s.linear_solver,
            "newton_per_step": s.num_newton_iters / s.num_steps, "success": res.success,
            "u_top": float(res.u[-1, -1])}


def case_in_subprocess(model_kind: str, size: int, key: str) -> dict:
    p = subprocess.run([sys.executable, os.path.abspath(__file__), "--case", model_kind, str(size), key],
                       capture_output=True, text=True, timeout=3600)
    if p.returncode != 0:
        raise SystemExit(f"case {model_kind} {size} {key} failed:\n{p.stderr[-3000:]}")
    return json.loads(p.stdout.strip().splitlines()[-1])


def hand_loop(exe: str, n: int) -> dict:
    steps = int(min(200_000, max(20, TARGET_WORK / (4e-9 * n))))  # about TARGET_WORK seconds at 4 ns per DOF
    p = subprocess.run([exe, str(n), str(steps), "3"], capture_output=True, text=True, check=True)
    r = json.loads(p.stdout)
    r["per_step"] = r["best"] / steps
    return r


def slope(ns, ts) -> float:
    import numpy as np

    return float(np.polyfit(np.log(ns), np.log(ts), 1)[0])


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--case", nargs=3, metavar=("MODEL", "SIZE", "SCHEME"), help=argparse.SUPPRESS)
    ap.add_argument("--quick", action="store_true", help="up to 10^5 DOFs (a check of the script)")
    ap.add_argument("--cxx", default=os.environ.get("CXX", "g++"))
    ap.add_argument("--out", default=os.path.join(HERE, "results", "scale.md"))
    ap.add_argument("--replot", action="store_true",
                    help="rewrite the table and the PNG from the measurements of the last run (the .json beside --out)")
    args = ap.parse_args()
    if args.case:
        print(json.dumps(run_case(args.case[0], int(args.case[1]), args.case[2])))
        return 0

    import numpy as np

    from building import CXXFLAGS, machine_info, write_report

    raw = os.path.splitext(args.out)[0] + ".json"
    if args.replot:
        with open(raw, encoding="utf-8") as fh:
            data = json.load(fh)
        rows, chain_n, header = data["rows"], data["chain_n"], data["header"]
        hand = {int(n): v for n, v in data["hand"].items()}
    else:
        chain_n = [n for n in CHAIN_N if not args.quick or n <= 100_000]
        lattice_nx = [nx for nx in LATTICE_NX if not args.quick or nx <= 316]
        load = os.getloadavg()[0]
        rows = []
        for kind, sizes in (("chain", chain_n), ("lattice", lattice_nx)):
            for key in SCHEMES:
                for size in sizes:
                    r = case_in_subprocess(kind, size, key)
                    rows.append(r)
                    print(f"{kind} {r['n']:>9,} {key:8s} {r['per_step'] * 1e6:12.2f} us/step "
                          f"{r['per_step'] / r['n'] * 1e9:8.2f} ns/step/DOF {r['bytes_per_dof']:8.0f} B/DOF "
                          f"{r['linear_solver']}", file=sys.stderr)
                    if key not in EXPLICIT and r["per_step"] > SLOW_STEP:
                        break
        with tempfile.TemporaryDirectory() as tmp:
            exe = os.path.join(tmp, "chain_loop")
            subprocess.run([args.cxx, *CXXFLAGS, os.path.join(HERE, "cpp", "chain_loop.cpp"), "-o", exe], check=True)
            hand = {n: hand_loop(exe, n) for n in chain_n}
        header = machine_info(args.cxx, load)
        with open(raw, "w", encoding="utf-8") as fh:  # the measurements, for --replot
            json.dump({"rows": rows, "hand": hand, "chain_n": chain_n, "header": header}, fh, indent=1)
    by = {(r["model"], r["scheme"]): [] for r in rows}
    for r in rows:
        by[(r["model"], r["scheme"])].append(r)

    def fit(model, key, lo, hi):
        pts = [(r["n"], r["per_step"]) for r in by[(model, key)] if lo <= r["n"] <= hi and r["per_step"] > 0]
        return slope(*zip(*pts)) if len(pts) >= 2 else float("nan")

    exps = {(m, k): (fit(m, k, 1_000, 1_000_000) if k in EXPLICIT else fit(m, k, 1_000, 100_000))
            for m in ("chain", "lattice") for k in SCHEMES}
    hand_exp = slope([n for n in chain_n if n >= 1000], [hand[n]["per_step"] for n in chain_n if n >= 1000])
    n5 = 100_000 if 100_000 in hand else max(hand)
    cd5 = next(r for r in by[("chain", "cd")] if r["n"] == n5)
    ratio5 = cd5["per_step"] / hand[n5]["per_step"]
    chain_bytes = max(r["bytes_per_dof"] for r in rows if r["model"] == "chain" and r["scheme"] in EXPLICIT
                      and r["n"] >= 100_000)

    # ---- plot
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 3, figsize=(16, 5))
    styles = {"cd": ("C0", "o"), "cemdts": ("C1", "s"), "newmark": ("C2", "^"), "galpha": ("C3", "v")}
    for ax, model in zip(axes[:2], ("chain", "lattice")):
        for key, label in SCHEMES.items():
            pts = by[(model, key)]
            ax.loglog([r["n"] for r in pts], [r["per_step"] for r in pts], marker=styles[key][1],
                      color=styles[key][0], label=f"nvib {label} (slope {exps[(model, key)]:.2f})")
        if model == "chain":
            ax.loglog(chain_n, [hand[n]["per_step"] for n in chain_n], "k--", marker="x",
                      label=f"hand-written C++ CD (slope {hand_exp:.2f})")
        ns = np.array([10, 1e6])
        ax.loglog(ns, 1e-8 * ns, ":", color="0.6", label="slope 1 (10 ns per DOF)")
        ax.set_xlabel("degrees of freedom n")
        ax.set_ylabel("wall time per step [s]")
        ax.set_title(f"{model}: time per step (Stats.wall_time)")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
    ax = axes[2]
    for model, marker in (("chain", "o"), ("lattice", "s")):
        for key in SCHEMES:
            pts = [r for r in by[(model, key)] if r["n"] >= MEMORY_FROM]
            ax.semilogx([r["n"] for r in pts], [r["bytes_per_dof"] for r in pts], marker=marker,
                        color=styles[key][0], ls="-" if model == "chain" else "--",
                        label=f"{model}, {SCHEMES[key]}")
    ax.axhline(400, color="k", lw=0.8, ls=":")
    ax.text(1.2e4, 420, "target for the chain: 400 B/DOF", fontsize=8)
    ax.set_xlabel("degrees of freedom n")
    ax.set_ylabel("peak memory beyond the saved history [bytes per DOF]")
    ax.set_title("memory (peak RSS of a fresh process)")
    ax.set_ylim(0, None)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=6, ncol=2, loc="center", bbox_to_anchor=(0.5, 0.6))  # between the two groups of lines
    fig.tight_layout()
    png = os.path.splitext(args.out)[0] + ".png"
    fig.savefig(png, dpi=110)

    # ---- table
    lines = ["# Scale: time per step and memory from 10 to 10^6 DOFs", ""]
    lines += header
    lines += ["", f"![time per step and memory]({os.path.basename(png)})", "",
              "Per step: the time of a run of `steps` steps less that of a run of 2, over the steps between "
              "(Stats.wall_time, best of 3); *start*: the rest of a run's time (the model copied into the "
              "stepper, the divergence bound's set-up, the history). *Not resolved*: the longer run took no "
              "longer than the shorter (a few slow steps after a start of tens of seconds, whose own variation "
              "hides them); its start column is then the short run's whole time.", "",
              "| model | n | scheme | steps | per step [us] | per step per DOF [ns] | start [ms] | Newton it. per step | "
              "linear solver | build [s] | bytes per DOF | peak RSS [MB] |",
              "|---|---:|---|---:|---:|---:|---:|---:|---|---:|---:|---:|"]
    for r in rows:
        per_dof = f"{r['bytes_per_dof']:.0f}" if r["n"] >= MEMORY_FROM else "-"
        resolved = r["per_step"] > 0  # (NaN: the difference of the two runs did not resolve a step)
        step_us = f"{r['per_step'] * 1e6:.3g}" if resolved else "not resolved"
        step_ns = f"{r['per_step'] / r['n'] * 1e9:.3g}" if resolved else "-"
        lines.append(f"| {r['model']} | {r['n']:,} | {SCHEMES[r['scheme']]} | {r['steps']:,} | "
                     f"{step_us} | {step_ns} | {r.get('start', math.nan) * 1e3:.3g} | "
                     f"{r['newton_per_step']:.2f} | {r['linear_solver'] or '-'} | {r['build']:.3g} | "
                     f"{per_dof} | {r['peak_mb']:.0f} |")
    lines += ["", "Hand-written C++ central difference on the chain (benchmarks/cpp/chain_loop.cpp, best of 3):", "",
              "| n | steps | per step [us] | per step per DOF [ns] | nvib CentralDifference / hand-written |",
              "|---:|---:|---:|---:|---:|"]
    for n in chain_n:
        cd = next(r for r in by[("chain", "cd")] if r["n"] == n)
        lines.append(f"| {n:,} | {hand[n]['steps']:,} | {hand[n]['per_step'] * 1e6:.3g} | "
                     f"{hand[n]['per_step'] / n * 1e9:.3g} | {cd['per_step'] / hand[n]['per_step']:.2f} |")
    met = lambda ok: "met" if ok else "**not met**"  # noqa: E731
    ecd, ecem, enm = exps[("chain", "cd")], exps[("chain", "cemdts")], exps[("chain", "newmark")]
    lines += ["", "## Targets", "",
              f"- Explicit exponent from 10^3 to 10^6 DOFs (chain): CentralDifference {ecd:.3f}, CEMDTS {ecem:.3f} "
              f"(target <= 1.05: {met(max(ecd, ecem) <= 1.05)}); the hand-written loop's own: {hand_exp:.3f}. "
              f"Lattice: CentralDifference {exps[('lattice', 'cd')]:.3f}, CEMDTS {exps[('lattice', 'cemdts')]:.3f}.",
              f"- Constant at n = {n5:,}: nvib CentralDifference {cd5['per_step'] / n5 * 1e9:.2f} ns per step per DOF, "
              f"{ratio5:.2f}x the hand-written loop (target <= 2: {met(ratio5 <= 2)}).",
              f"- Newmark + Newton on the chain, exponent from 10^3 to 10^5: {enm:.3f} (target <= 1.2: "
              f"{met(enm <= 1.2)}); GeneralizedAlpha {exps[('chain', 'galpha')]:.3f}; on the lattice (fill-in) "
              f"Newmark {exps[('lattice', 'newmark')]:.3f}.",
              f"- Memory: at most {chain_bytes:.0f} bytes per DOF for the chain at 10^5 DOFs and more with the "
              f"explicit schemes (target <= 400: {met(chain_bytes <= 400)}); the implicit schemes add their "
              "factorisation (see the table)."]
    nmax = max(chain_n)
    cdmax = next(r for r in by[("chain", "cd")] if r["n"] == nmax)
    ratio_max = cdmax["per_step"] / hand[nmax]["per_step"]
    lines.insert(lines.index("## Targets") + 4,
                 f"- At n = {nmax:,}: nvib CentralDifference {ratio_max:.2f}x the hand-written loop (target <= 1.3, "
                 f"issue \"At the limit\": {met(ratio_max <= 1.3)}).")
    lines += ["", "## Reading", "",
              f"The explicit exponent is not a property of the algorithm (each step is O(n + nnz) with no "
              f"allocation) but of the memory hierarchy: from 10^5 to 10^6 DOFs the working set leaves the caches, "
              f"and the hand-written loop's own exponent is {hand_exp:.3f}. On a lumped-mass model whose effects reach "
              f"a bounded distance along the DOFs (the chain) nvib's explicit step runs block by block in one pass "
              f"over memory (the update of u, the loads, each kind of effect a block behind the one before, the "
              f"mass and the update of v: Model::stream_acceleration). Its storeys and dampers (an array of one "
              f"law each) read no array of their own: the chain kernel computes each effect's DOFs and one "
              f"parameter set serves them all (dampers declared one by one are assembled into C, a band, whose "
              f"rows with constant diagonals multiply by values held in registers). Beyond the hand-written "
              f"loop it takes the divergence "
              f"test (the largest |u_i| and a test of finiteness, on each block as it is updated) and the error "
              f"estimate (every 8th step a pass over u, a_n, a_{{n-1}} and its arrays of the jerk and the peak, "
              f"read and written: about 8 % of a step at 10^6 DOFs, the difference of runs with and without "
              f"it): the ratio is {ratio5:.2f}x "
              f"at 10^5 and {ratio_max:.2f}x at {nmax:,}. The lattice's effects "
              f"reach nx DOFs along the numbering: it streams up to nx = 512 (a block of 2048 DOFs holds four "
              f"rows), and above takes the stage-by-stage step. "
              f"The implicit schemes on the chain stay near-linear (a tridiagonal LDLT has no fill-in); on the "
              f"lattice (bandwidth nx) the factorisation fills in and the exponent is "
              f"{exps[('lattice', 'newmark')]:.2f}, near the n^1.5 of factorising a 2-D grid with a fill-reducing "
              f"ordering (nested dissection), with about "
              f"{max(r['bytes_per_dof'] for r in rows if r['model'] == 'lattice' and r['scheme'] == 'newmark' and r['n'] >= MEMORY_FROM):.0f} "
              "bytes per DOF for the factor."]
    write_report(args.out, lines)
    return 0


if __name__ == "__main__":
    sys.exit(main())
