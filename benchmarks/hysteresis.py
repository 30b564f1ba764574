"""Speed of the laws with memory: the inelastic building against hand-written C++ loops, bilinear
against elastic storeys, and 10^5 bilinear springs in a chain.

The scene building_inelastic (nvib.load_scene("building_inelastic"): six floors of 1e5 kg, a
bilinear storey (k = 1e8 N/m, fy per storey, b = 0.03, kinematic hardening) and a p_delta on each
drift, Rayleigh damping 5 % on modes 1 and 3, the record SGM-1 times 9.80665 as ground
acceleration) at its dt = 0.002 s to t_end = 30 s (15,000 steps), saving every 10th state.

Targets (issue "Hysteresis", item 8):
  (a) CentralDifference on the inelastic building: nvib.solve() from Python within 1.5x of a
      hand-written C++ central-difference loop with bilinear storeys;
  (b) the per-step cost of the bilinear building within 1.5x of the same building with elastic
      storeys (the bilinear effects replaced by springs of the same k), for CentralDifference and
      for Newmark + Newton;
  (c) 10^5 bilinear springs in a chain: ns per step per DOF beside the elastic chain.
(OpenSees on the same building is benchmarks/opensees_hysteresis.py.)

Contenders, all measured in this run:
  * hand-written C++ (benchmarks/cpp/building_inelastic_loop.cpp): plain arrays, no nvib; the
    model's numbers (masses, storeys, the bands of K and C, the record) read from a file this
    script writes from the nvib model; the bilinear return mapping of nvib's bilinear.hpp written
    out, the plastic deformation updated where it is evaluated (central difference) or committed
    when Newton converges; the record's segment carried from step to step. Its central difference
    reproduces nvib's trajectory bit for bit (checked below); its Newmark loops make nvib's Newton
    iterations with nvib's convergence test (dense LU as nvib at this size, or Thomas on the three
    diagonals), and for the elastic storeys also the linear path nvib takes for a linear model
    (S factorised once per run, one solve per step);
  * nvib through its C++ headers (benchmarks/cpp/building_inelastic_nvib.cpp, compiled against
    nvib.include_dir()): the scene's effects built with make_effect / make_effect_model;
  * nvib.solve() from Python: the whole call, and Stats.wall_time inside it.
Elastic building: the bilinear effects replaced by springs of the same k; nvib assembles them into
K with the P-delta, so the model is linear (Newmark: one factorisation per run, one solve per
step). Control *noyield*: bilinear effects with fy = 1e300 (a law with memory that never leaves its
elastic branch). Both C++ programs are built with nvib's Release flags (-O3 -DNDEBUG); each time is
the best over ROUNDS interleaved rounds of REPEATS runs.

Chain (c): n = 10^5 storeys of 1e5 kg, each a spring (k = 1e8 N/m) or a bilinear spring (k = 1e8,
fy = 1e5 N, b = 0.03) and a damper (2 % of critical at k) on its drift, declared as effect arrays
(nvib.Model(effects=[{"type": "spring"/"bilinear", "i": ..., "j": ...}, ...]) as
nvib.scenes.chain builds them), a_g = 10 sin(pi t), dt = 0.2 sqrt(m / k), 200 steps of
CentralDifference from u0 = 0 with v0 = 0 (*from rest*: almost no storey yields) and with v0
normal of standard deviation 0.1 m/s (*yielding*: about a tenth of the storey evaluations on the
yield branch). Time: Stats.wall_time (the C++ loop), best of CHAIN_ROUNDS x CHAIN_REPEATS, against
the hand-written loop's chain mode (the same force pass fused into one loop over the storeys).

    python benchmarks/hysteresis.py [--rounds 5] [--repeats 20] [--out benchmarks/results/hysteresis.md]
"""

from __future__ import annotations

import filecmp
import json
import math
import os
import subprocess
import sys
import tempfile
import time
import tomllib

import numpy as np

import nvib
from building import CXXFLAGS, HERE, ROOT, bench_parser, checked_bench_args, eigen_include, machine_info, rel_diff

TARGET = 1.5
SCENE = "building_inelastic"
NOYIELD_FY = 1e300
STOREYS = ("bilinear", "elastic", "noyield")
SCHEME_LABEL = {"cd": "CentralDifference", "newmark": "Newmark + Newton"}
SCHEMES = {"cd": nvib.CentralDifference, "newmark": nvib.Newmark}
# The chain of table (c).
CHAIN_MASS, CHAIN_K, CHAIN_FY, CHAIN_B, CHAIN_ZETA = 1e5, 1e8, 1e5, 0.03, 0.02
CHAIN_AG, CHAIN_OMEGA = 10.0, math.pi
KEEP_MARKER = "<!-- kept by hysteresis.py: hand-written analysis below -->"


# ---- the model -------------------------------------------------------------------------------
def scene_record(scene) -> nvib.GroundMotion:
    """The scene's ground motion, read as the scene reads it (its file and scale from the TOML)."""
    path = scene.scene["path"]
    with open(path, "rb") as fh:
        spec = next(e for e in tomllib.load(fh)["effect"] if e["type"] == "ground_acceleration")["signal"]
    return nvib.GroundMotion.from_at2(os.path.join(os.path.dirname(path), spec["file"]), scale=spec.get("scale", 1.0))


def effect_specs(scene, record, storeys: str) -> list[dict]:
    """The scene's effects as dicts, with the bilinear storeys kept, made springs or made never to yield."""
    out = []
    for e in scene.effects:
        measure = {scene.dofs[i]: float(c) for i, c in zip(e.index, e.coef)}
        spec = {"type": e.type, "name": e.name, **({} if e.type == "ground_acceleration" else {"measure": measure}),
                **{k: float(v) for k, v in e.parameters.items()}}
        if e.type == "ground_acceleration":
            spec["signal"] = record
        elif e.type == "bilinear" and storeys == "elastic":
            spec = {"type": "spring", "name": e.name, "measure": measure, "k": spec["k"]}
        elif e.type == "bilinear" and storeys == "noyield":
            spec["fy"] = NOYIELD_FY
        out.append(spec)
    return out


def building_model(scene, record, storeys: str) -> nvib.Model:
    """The scene's model with its mass, its Rayleigh C (kept as computed for the scene) and the effects."""
    return nvib.Model(scene.mass_matrix.diagonal().copy(), C=scene.C, effects=effect_specs(scene, record, storeys),
                      dofs=list(scene.dofs), name=f"{SCENE} ({storeys})")


def tridiagonal(A: np.ndarray, name: str) -> tuple[np.ndarray, np.ndarray]:
    if not (np.array_equal(A, A.T) and not np.any(np.triu(A, 2))):
        raise SystemExit(f"{name} is not symmetric tridiagonal: the hand-written loop assumes it")
    return np.diag(A).copy(), np.diag(A, 1).copy()


def write_model_file(path: str, scene, record) -> None:
    """The numbers both C++ programs read: 'key v1 v2 ...' per line, every double with all its digits."""
    bil = [e for e in scene.effects if e.type == "bilinear"]
    pd = [e for e in scene.effects if e.type == "p_delta"]
    n = scene.n
    storey = [[0]] + [[s, s - 1] for s in range(1, n)]
    for group in (bil, pd):  # storey s acts on its drift, in order: what the loop assumes
        coefs = [list(e.coef) for e in group]
        if [list(e.index) for e in group] != storey or coefs != [[1.0]] + [[1.0, -1.0]] * (n - 1):
            raise SystemExit("the scene's storeys are not the drifts x1, x2 - x1, ...: the hand-written loop "
                             "assumes them")
    row = lambda key, xs: key + " " + " ".join(repr(float(x)) for x in xs)  # noqa: E731
    lines = [f"# {SCENE}: written by benchmarks/hysteresis.py for the hand-written loops and building_inelastic_nvib",
             f"n {n}", row("dt", [scene.scene["dt"]]), row("t_end", [scene.scene["t_end"]]),
             row("mass", scene.mass_matrix.diagonal())]
    for key in ("k", "fy", "b"):
        lines.append(row(key, [e.parameters[key] for e in bil]))
    lines.append(row("P", [e.parameters["P"] for e in pd]))
    lines.append(row("storey_h", [e.parameters["h"] for e in pd]))
    for name, A in (("K", scene.K.toarray()), ("C", scene.C.toarray())):
        d, o = tridiagonal(A, name)
        lines += [row(f"{name}_diag", d), row(f"{name}_off", o)]
    lines += [row("record_t", record.t), row("record_a", record.a)]
    with open(path, "w", encoding="utf-8") as fh:
        fh.write("\n".join(lines) + "\n")


def chain_model(n: int, law: str) -> nvib.Model:
    idx = np.arange(n, dtype=np.int32)
    c = 2.0 * CHAIN_ZETA * math.sqrt(CHAIN_K * CHAIN_MASS)
    storeys = {"type": "spring" if law == "elastic" else "bilinear", "name": "storeys", "i": idx, "j": idx - 1,
               "k": CHAIN_K}
    if law == "bilinear":
        storeys.update(fy=CHAIN_FY, b=CHAIN_B)
    effects = [storeys, {"type": "damper", "name": "dampers", "i": idx, "j": idx - 1, "c": c},
               {"type": "ground_acceleration", "name": "ground",
                "signal": {"kind": "sine", "amplitude": CHAIN_AG, "omega": CHAIN_OMEGA}}]
    return nvib.Model(np.full(n, CHAIN_MASS), effects=effects, name=f"chain({n}, {law})")


# ---- running ---------------------------------------------------------------------------------
def compile_programs(tmp: str, cxx: str) -> tuple[dict, str]:
    include = nvib.include_dir()
    out = {}
    for name, extra in (("building_inelastic_loop", []),
                        ("building_inelastic_nvib", ["-I", include, "-I", eigen_include()])):
        exe = os.path.join(tmp, name)
        subprocess.run([cxx, *CXXFLAGS, *extra, os.path.join(HERE, "cpp", name + ".cpp"), "-o", exe], check=True)
        out[name] = exe
    return out, include


def run_json(args: list[str]) -> list[dict]:
    p = subprocess.run(args, check=True, capture_output=True, text=True)
    return [json.loads(line) for line in p.stdout.splitlines() if line.strip().startswith("{")]


def loop_key(r: dict) -> tuple:
    return (r["scheme"], r["storeys"], r["solver"])


def time_python(model, scheme_key: str, dt: float, t_end: float, save_every: int, repeats: int) -> dict:
    """The best whole nvib.solve() call of `repeats` (the previous result freed outside the timing)."""
    best, inner, res = math.inf, math.inf, None
    for _ in range(repeats):
        t0 = time.perf_counter()
        new = nvib.solve(model, SCHEMES[scheme_key](), dt=dt, t_end=t_end, save_every=save_every)
        elapsed = time.perf_counter() - t0
        res = new
        best = min(best, elapsed)
        inner = min(inner, res.stats.wall_time)
    s = res.stats
    return {"best": best, "best_wall_time": inner, "steps": s.num_steps, "newton_iters": s.num_newton_iters,
            "force_evals": s.num_force_evals, "factorizations": s.num_factorizations, "u": res.u[-1].tolist(),
            "v": res.v[-1].tolist(), "a": res.a[-1].tolist()}


def keep_best(store: dict, key, row: dict) -> None:
    if key not in store or row["best"] < store[key]["best"]:
        store[key] = dict(row)


def check_agreement(exes: dict, model_file: str, tmp: str, models: dict, dt: float, t_end: float,
                    save_every: int) -> dict:
    """The saved displacements of every hand-written case against nvib.solve() (max over the saved states
    of |u_loop - u_nvib|, relative to max |u_nvib|)."""
    prefix = os.path.join(tmp, "dump")
    rows = run_json([exes["building_inelastic_loop"], model_file, "1", str(save_every), f"--dump={prefix}"])
    ref = {}
    for storeys in ("bilinear", "elastic"):
        for key in SCHEMES:
            ref[(key, storeys)] = nvib.solve(models[storeys], SCHEMES[key](), dt=dt, t_end=t_end,
                                             save_every=save_every).u
    out = {}
    for r in rows:
        scheme = "cd" if r["scheme"] == "cd" else "newmark"
        u = np.fromfile(f"{prefix}.{r['scheme']}.{r['storeys']}.{r['solver']}.bin").reshape(-1, 6)
        uref = ref[(scheme, r["storeys"])]
        out[loop_key(r)] = float(np.max(np.abs(u - uref)) / np.max(np.abs(uref))) if u.shape == uref.shape else math.inf
    return out


def hand_chain(exe: str, n: int, steps: int, repeats: int, dt: float, v0_file: str | None, dump: str) -> dict:
    c = 2.0 * CHAIN_ZETA * math.sqrt(CHAIN_K * CHAIN_MASS)
    args = [exe, "--chain", str(n), str(steps), str(repeats), repr(dt), repr(CHAIN_MASS), repr(CHAIN_K),
            repr(CHAIN_FY), repr(CHAIN_B), repr(c), repr(CHAIN_AG), repr(CHAIN_OMEGA)]
    if v0_file:
        args.append(v0_file)
    return {r["law"]: r for r in run_json(args + [f"--dump={dump}"])}


def nvib_chain(model, steps: int, dt: float, v0, repeats: int) -> dict:
    best, whole, res = math.inf, math.inf, None
    for _ in range(repeats):
        t0 = time.perf_counter()
        res = nvib.solve(model, nvib.CentralDifference(), dt=dt, t_end=steps * dt, save_every=steps, v0=v0)
        whole = min(whole, time.perf_counter() - t0)
        best = min(best, res.stats.wall_time)
    return {"best": best, "whole": whole, "steps": res.stats.num_steps, "u": res.u[-1]}


# ---- report ----------------------------------------------------------------------------------
def main() -> int:
    ap = bench_parser(__doc__, rounds=5, repeats=20)
    ap.add_argument("--save-every", type=int, default=10)
    ap.add_argument("--chain-n", type=int, default=100_000)
    ap.add_argument("--chain-steps", type=int, default=200)
    ap.add_argument("--chain-rounds", type=int, default=3)
    ap.add_argument("--chain-repeats", type=int, default=3)
    ap.add_argument("--chain-sigma", type=float, default=0.1, help="std of v0 [m/s] of the yielding chain (0.1)")
    ap.add_argument("--no-chain", action="store_true", help="skip table (c)")
    ap.add_argument("--out", default=os.path.join(HERE, "results", "hysteresis.md"))
    args = checked_bench_args(ap)
    started = time.perf_counter()
    load_at_start = os.getloadavg()[0]

    scene = nvib.load_scene(SCENE)
    dt, t_end, k = scene.scene["dt"], scene.scene["t_end"], args.save_every
    record = scene_record(scene)
    models = {s: building_model(scene, record, s) for s in STOREYS}
    # The rebuilt bilinear model is the scene (bit for bit), so the scene stands for it below.
    a = nvib.solve(scene, nvib.CentralDifference(), dt=dt, t_end=t_end, save_every=k)
    b = nvib.solve(models["bilinear"], nvib.CentralDifference(), dt=dt, t_end=t_end, save_every=k)
    if not np.array_equal(a.u, b.u):
        raise SystemExit("the model rebuilt from the scene's effects does not reproduce the scene")
    models["bilinear"] = scene
    print(f"scene {SCENE}: {scene}", file=sys.stderr)

    best_loop, best_core, best_py = {}, {}, {}
    ratios: dict = {}
    with tempfile.TemporaryDirectory(prefix="nvib-hysteresis-") as tmp:
        exes, include = compile_programs(tmp, args.cxx)
        model_file = os.path.join(tmp, "building_inelastic.txt")
        write_model_file(model_file, scene, record)
        agreement = check_agreement(exes, model_file, tmp, models, dt, t_end, k)
        print("agreement (hand-written loops against nvib.solve, saved u): " +
              ", ".join(f"{'/'.join(key)} {v:.1e}" for key, v in agreement.items()), file=sys.stderr)
        bad = {key: v for key, v in agreement.items() if not v <= (1e-12 if key[0] == "cd" else 1e-9)}
        if bad:
            raise SystemExit(f"the hand-written loops do not reproduce nvib's trajectories: {bad}")
        for _ in range(2):  # warm-up: page in libraries, settle the clock
            for s in STOREYS:
                for key in SCHEMES:
                    nvib.solve(models[s], SCHEMES[key](), dt=dt, t_end=t_end, save_every=k)
        for rnd in range(args.rounds):
            this = {}
            for r in run_json([exes["building_inelastic_loop"], model_file, str(args.repeats), str(k)]):
                keep_best(best_loop, loop_key(r), r)
                this[loop_key(r)] = r
            for r in run_json([exes["building_inelastic_nvib"], model_file, str(args.repeats), str(k)]):
                keep_best(best_core, (r["scheme"], r["storeys"]), r)
            for s in STOREYS:
                for key in SCHEMES:
                    row = time_python(models[s], key, dt, t_end, k, args.repeats)
                    keep_best(best_py, (key, s), row)
                    this[(key, s)] = row
            ratio = this[("cd", "bilinear")]["best"] / this[("cd", "bilinear", "-")]["best"]
            ratios.setdefault("cd", []).append(ratio)
            print(f"round {rnd + 1}/{args.rounds}: CD bilinear, nvib from Python / hand-written {ratio:.2f}x",
                  file=sys.stderr)

        chain = {}
        if not args.no_chain:
            n, steps = args.chain_n, args.chain_steps
            cdt = 0.2 * math.sqrt(CHAIN_MASS / CHAIN_K)
            v0_file = os.path.join(tmp, "chain_v0.bin")
            v0 = np.random.default_rng(20260101).normal(0.0, args.chain_sigma, n)
            v0.tofile(v0_file)
            cmodels = {law: chain_model(n, law) for law in ("elastic", "bilinear")}
            cases = {"from rest": (None, None), "yielding": (v0_file, v0)}
            for case, (vfile, vv) in cases.items():
                best_h, best_n = {}, {}
                dump = os.path.join(tmp, "chain")
                for rnd in range(args.chain_rounds):
                    h = hand_chain(exes["building_inelastic_loop"], n, steps, args.chain_repeats, cdt, vfile, dump)
                    for law, r in h.items():
                        keep_best(best_h, law, r)
                    for law, m in cmodels.items():
                        keep_best(best_n, law, nvib_chain(m, steps, cdt, vv, args.chain_repeats))
                agree = {}
                for law in cmodels:
                    u_hand = np.fromfile(f"{dump}.chain.{law}.bin")
                    u_nvib = best_n[law]["u"]
                    agree[law] = float(np.max(np.abs(u_hand - u_nvib)) / np.max(np.abs(u_nvib)))
                chain[case] = {"hand": best_h, "nvib": best_n, "agree": agree}
                print(f"chain {case}: " + ", ".join(
                    f"{law} nvib {best_n[law]['best'] / steps / n * 1e9:.2f} / hand "
                    f"{best_h[law]['best'] / steps / n * 1e9:.2f} ns/step/DOF" for law in cmodels), file=sys.stderr)

    load_at_end = os.getloadavg()[0]
    elapsed = time.perf_counter() - started
    lines = report(args, scene, include, best_loop, best_core, best_py, ratios, agreement, chain, load_at_start,
                   load_at_end, elapsed)
    text = "\n".join(lines) + "\n"
    print(text)
    kept = ""
    if os.path.isfile(args.out):
        with open(args.out, encoding="utf-8") as fh:
            old = fh.read()
        if KEEP_MARKER in old:
            kept = "\n" + old[old.index(KEEP_MARKER):]
    os.makedirs(os.path.dirname(args.out), exist_ok=True)
    with open(args.out, "w", encoding="utf-8") as fh:
        fh.write(text + kept)
    return 0


def same_headers(include: str) -> bool:
    """Whether the headers compiled (nvib.include_dir()) are those of this checkout's cpp/include."""
    ours = os.path.join(ROOT, "cpp", "include")
    for base, _, files in os.walk(os.path.join(ours, "nvib")):
        for f in files:
            mine = os.path.join(base, f)
            theirs = os.path.join(include, os.path.relpath(mine, ours))
            if not os.path.isfile(theirs) or not filecmp.cmp(mine, theirs, shallow=False):
                return False
    return True


def report(args, scene, include, loop, core, py, ratios, agreement, chain, load0, load1, elapsed) -> list[str]:
    steps = loop[("cd", "bilinear", "-")]["steps"]
    ns = lambda s, m=steps: s / m * 1e9  # noqa: E731
    met = lambda ok: "yes" if ok else "**no**"  # noqa: E731
    lines = ["# Laws with memory: the inelastic building against hand-written C++, bilinear against elastic, "
             "10^5 bilinear springs", ""]
    lines += machine_info(args.cxx, load0)
    lines += [f"- 1-minute load average at the end {load1:.2f}; the whole run took {elapsed:.0f} s",
              f"- nvib C++ compiled against `nvib.include_dir()` = {include} "
              f"({'identical to' if same_headers(include) else '**differs from**'} this checkout's cpp/include)", ""]

    # ---- (a)
    hand, hand_el = loop[("cd", "bilinear", "-")], loop[("cd", "elastic", "-")]
    lines += [
        "## (a) Inelastic building, CentralDifference: nvib against a hand-written loop",
        "",
        f"Scene `{SCENE}` (6 DOFs: bilinear storeys, P-delta in K, Rayleigh C, record SGM-1), dt = "
        f"{scene.scene['dt']:g} s, t_end = {scene.scene['t_end']:g} s = {steps:,} steps, from rest, save_every = "
        f"{args.save_every}. Best of {args.rounds} interleaved rounds x {args.repeats} runs. *hand-written C++*: "
        "`cpp/building_inelastic_loop.cpp`; *nvib C++*: `cpp/building_inelastic_nvib.cpp` (`nvib::solve` through "
        "the headers); *nvib from Python*: the whole `nvib.solve(...)` call (its Stats.wall_time in brackets). "
        f"Ratio = nvib / hand-written (target for the bilinear building from Python: <= {TARGET}).",
        "",
        "| storeys | hand-written C++ [ms] | nvib C++ [ms] | nvib from Python [ms] | per step: hand [ns] | "
        "nvib C++ [ns] | nvib Python [ns] | ratio nvib C++ | ratio nvib Python | target met |",
        "|---|---:|---:|---:|---:|---:|---:|---:|---:|---|",
    ]
    for s in ("bilinear", "elastic"):
        h, c, p = loop[("cd", s, "-")], core[("cd", s)], py[("cd", s)]
        rc, rp = c["best"] / h["best"], p["best"] / h["best"]
        lines.append(f"| {s} | {h['best'] * 1e3:.3f} | {c['best'] * 1e3:.3f} | {p['best'] * 1e3:.3f} "
                     f"({p['best_wall_time'] * 1e3:.3f}) | {ns(h['best']):.1f} | {ns(c['best']):.1f} | "
                     f"{ns(p['best']):.1f} | {rc:.2f} | **{rp:.2f}** | "
                     f"{met(rp <= TARGET) if s == 'bilinear' else '(context)'} |")
    agree_cd = max(agreement[("cd", "bilinear", "-")], agreement[("cd", "elastic", "-")])
    newton_agree = max(v for key, v in agreement.items() if key[0] != "cd")
    final = max(rel_diff(core[key][x], py[key][x]) for key in core for x in ("u", "v", "a"))
    lines += [
        "",
        f"The hand-written central difference reproduces nvib's trajectory: the saved displacements differ from "
        f"`nvib.solve()`'s by {agree_cd:.1e} relative to max |u| (bilinear and elastic storeys; required: 1e-12); "
        f"the hand-written Newmark loops by {newton_agree:.1e} (Newton's tolerance; required: 1e-9). nvib C++ and "
        f"nvib from Python end in the same state to {final:.1e}. On the yield branch: "
        f"{hand['yield_fraction'] * 100:.1f} % of the storey evaluations (CentralDifference). Ratio in each round "
        f"(nvib from Python / hand-written, that round's bests): "
        + ", ".join(f"{r:.2f}" for r in ratios["cd"]) + ".",
        "",
    ]

    # ---- (b)
    lines += [
        "## (b) Per-step cost: bilinear storeys against elastic ones",
        "",
        "The same building with the bilinear effects replaced by springs of the same k (*elastic*: nvib assembles "
        "them into K, the model is linear, and Newmark factorises once per run and makes one solve per step), and "
        "with bilinear effects that never yield (*noyield*, fy = 1e300: a law with memory on its elastic branch). "
        f"Per step = best total / {steps:,} steps. Ratio = bilinear / elastic (target <= {TARGET} for nvib).",
        "",
        "| scheme | contender | bilinear [ns/step] | elastic [ns/step] | ratio bilinear / elastic | target met | "
        "noyield [ns/step] | noyield / elastic | Newton it. per step (bilinear) | factorisations per step (bilinear) |",
        "|---|---|---:|---:|---:|---|---:|---:|---:|---:|",
    ]
    for key in SCHEMES:
        for who, src in (("nvib C++", core), ("nvib from Python", py)):
            b, e, q = src[(key, "bilinear")], src[(key, "elastic")], src[(key, "noyield")]
            r = b["best"] / e["best"]
            lines.append(f"| {SCHEME_LABEL[key]} | {who} | {ns(b['best']):.1f} | {ns(e['best']):.1f} | **{r:.2f}** | "
                         f"{met(r <= TARGET)} | {ns(q['best']):.1f} | {q['best'] / e['best']:.2f} | "
                         f"{b['newton_iters'] / steps:.3f} | {b['factorizations'] / steps:.3f} |")
        if key == "cd":
            r = hand["best"] / hand_el["best"]
            lines.append(f"| {SCHEME_LABEL[key]} | hand-written C++ | {ns(hand['best']):.1f} | "
                         f"{ns(hand_el['best']):.1f} | {r:.2f} | | | | | |")
        else:
            for solver, label in (("dense", "dense LU"), ("tridiag", "tridiagonal")):
                b = loop[("newmark", "bilinear", solver)]
                e = loop[("newmark_linear", "elastic", solver)]
                r = b["best"] / e["best"]
                lines.append(f"| {SCHEME_LABEL[key]} | hand-written C++, {label} (elastic: factorised once) | "
                             f"{ns(b['best']):.1f} | {ns(e['best']):.1f} | {r:.2f} | | | | "
                             f"{b['newton_iters'] / steps:.3f} | {b['factorizations'] / steps:.3f} |")
            b, e = loop[("newmark", "bilinear", "dense")], loop[("newmark", "elastic", "dense")]
            lines.append(f"| {SCHEME_LABEL[key]} | hand-written C++, dense LU, elastic through full Newton | "
                         f"{ns(b['best']):.1f} | {ns(e['best']):.1f} | {b['best'] / e['best']:.2f} | | | | "
                         f"{b['newton_iters'] / steps:.3f} | {b['factorizations'] / steps:.3f} |")
    nb, nh = core[("newmark", "bilinear")], loop[("newmark", "bilinear", "dense")]
    lines += [
        "",
        f"Newmark + Newton, bilinear building: nvib C++ {ns(nb['best']):.0f} ns per step, "
        f"{nb['best'] / nb['newton_iters'] * 1e9:.0f} ns per Newton iteration; the hand-written dense loop "
        f"{ns(nh['best']):.0f} and {nh['best'] / nh['newton_iters'] * 1e9:.0f} (nvib / hand-written: "
        f"{nb['best'] / nh['best']:.2f}x; nvib from Python {py[('newmark', 'bilinear')]['best'] / nh['best']:.2f}x). "
        f"Force evaluations per step: nvib {nb['force_evals'] / steps:.2f}, hand-written "
        f"{nh['force_evals'] / steps:.2f}.",
        "",
    ]

    # ---- (c)
    if chain:
        n, cs = args.chain_n, args.chain_steps
        per = lambda s: s / cs / n * 1e9  # noqa: E731
        lines += [
            f"## (c) {n:,} bilinear springs in a chain: ns per step per DOF",
            "",
            f"Chain of {n:,} storeys (spring or bilinear spring k = {CHAIN_K:g} N/m, fy = {CHAIN_FY:g} N, b = "
            f"{CHAIN_B:g}, and a damper of {CHAIN_ZETA:.0%} on each drift, effect arrays; a_g = {CHAIN_AG:g} "
            f"sin(pi t)), CentralDifference, dt = 0.2 sqrt(m/k), {cs} steps, first and last states saved. "
            "*from rest*: u0 = v0 = 0; "
            f"*yielding*: v0 normal with standard deviation {args.chain_sigma:g} m/s (seeded). nvib: Stats.wall_time, "
            f"best of {args.chain_rounds} rounds x {args.chain_repeats} runs; hand-written: the chain mode of "
            "`cpp/building_inelastic_loop.cpp` (one fused pass over the storeys), best of the same. *yield branch*: "
            "share of the storey evaluations that slip (counted by the hand-written loop).",
            "",
            "| case | law | nvib [ns/step/DOF] | hand-written [ns/step/DOF] | nvib / hand-written | yield branch | "
            "nvib: bilinear / elastic | hand-written: bilinear / elastic | final u, nvib vs hand-written |",
            "|---|---|---:|---:|---:|---:|---:|---:|---:|",
        ]
        for case, d in chain.items():
            for law in ("elastic", "bilinear"):
                nv, hd = d["nvib"][law], d["hand"][law]
                extra = ("| | " if law == "elastic" else
                         f"| **{nv['best'] / d['nvib']['elastic']['best']:.2f}** | "
                         f"{hd['best'] / d['hand']['elastic']['best']:.2f} ")
                lines.append(f"| {case} | {law} | {per(nv['best']):.2f} | {per(hd['best']):.2f} | "
                             f"{nv['best'] / hd['best']:.2f} | {hd['yield_fraction'] * 100:.2f} % "
                             f"{extra}| {d['agree'][law]:.1e} |")
        lines.append("")

    # ---- targets
    rp = py[("cd", "bilinear")]["best"] / hand["best"]
    rb_cd = core[("cd", "bilinear")]["best"] / core[("cd", "elastic")]["best"]
    rb_nm = core[("newmark", "bilinear")]["best"] / core[("newmark", "elastic")]["best"]
    rb_nm_py = py[("newmark", "bilinear")]["best"] / py[("newmark", "elastic")]["best"]
    rb_cd_py = py[("cd", "bilinear")]["best"] / py[("cd", "elastic")]["best"]
    hand_nm = nh["best"] / loop[("newmark_linear", "elastic", "dense")]["best"]
    lines += ["## Targets", "",
              f"- (a) nvib.solve() from Python on the inelastic building with CentralDifference: {rp:.2f}x the "
              f"hand-written loop (nvib C++ {core[('cd', 'bilinear')]['best'] / hand['best']:.2f}x); "
              f"target <= {TARGET}: "
              f"{'met' if rp <= TARGET else f'**not met**, by a factor {rp / TARGET:.2f}'}.",
              f"- (b) bilinear / elastic per step, CentralDifference: nvib C++ {rb_cd:.2f}, from Python {rb_cd_py:.2f} "
              f"(hand-written {hand['best'] / hand_el['best']:.2f}); target <= {TARGET}: "
              f"{'met' if max(rb_cd, rb_cd_py) <= TARGET else '**not met**'}.",
              f"- (b) bilinear / elastic per step, Newmark + Newton: nvib C++ {rb_nm:.2f}, from Python {rb_nm_py:.2f} "
              f"(hand-written, dense: {hand_nm:.2f}); target <= {TARGET}: "
              f"{'met' if max(rb_nm, rb_nm_py) <= TARGET else '**not met**'}."]
    if chain:
        for case, d in chain.items():
            r = d["nvib"]["bilinear"]["best"] / d["nvib"]["elastic"]["best"]
            lines.append(f"- (c) chain of {args.chain_n:,}, {case}: bilinear {per(d['nvib']['bilinear']['best']):.2f} "
                         f"ns per step per DOF against elastic {per(d['nvib']['elastic']['best']):.2f} ({r:.2f}x; "
                         f"hand-written {d['hand']['bilinear']['best'] / d['hand']['elastic']['best']:.2f}x).")
    return lines


if __name__ == "__main__":
    sys.exit(main())
