"""What a user's own law costs: the paper's building (six storeys of hardening springs, Yang et al. 2017,
section 5.1; dt = 1e-4 s to t_end = 10 s, every state saved) with its storey law given four ways, each
run from Python with nvib.solve():

  * built-in: the scene's `hardening_spring` effects;
  * compiled (Numba): the same arithmetic in a numba.cfunc of nvib.LAW_SIGNATURE, as "compiled" effects
    (no Python in the loop; trajectories bit for bit the built-in's, checked here);
  * compiled array: the same cfunc as one effect array of six storeys;
  * Python: the same law as a "callable" effect with its tangent (the GIL kept, one Python call per
    storey per evaluation).

For each, the best of ROUNDS interleaved runs, under the central difference (one force evaluation per
step) and Newmark with full Newton (force and tangent evaluations); the ratio to the built-in run, and
the extra cost per law call over the built-in law's: (time - built-in time) / (calls), the calls being
six per force evaluation plus six per tangent evaluation. Target (issue "Your own laws", item 1): the
compiled law within 1.5x of the built-in, explicit and Newton.

A vectorised Python law (one call per evaluation for every effect of an array) on nvib.scenes.chain(n),
n = 10^2, 10^3, 10^4 hardening storeys, the central difference for 500 steps: the time per effect and
evaluation, beside the built-in array's and the compiled array's. Target (item 2): <= 0.5 us per effect
per evaluation at 10^4 effects.

    python benchmarks/law_cost.py            # writes benchmarks/results/law_cost.md
"""

from __future__ import annotations

import os
import sys
import time

import numpy as np

import nvib

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from building import cpu_name, git_revision  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
OUT = os.path.join(HERE, "results", "law_cost.md")
ROUNDS = 7
DT, T_END = 1e-4, 10.0


def hardening_c(p, s, d, dd, t, out, trial):
    k0, a = p[0], p[1]
    out[0] = k0 * (1.0 + a * d * d) * d
    out[1] = k0 * (1.0 + 3.0 * a * d * d)
    out[2] = 0.0
    return 0


def variants():
    import numba

    law = numba.cfunc(nvib.LAW_SIGNATURE)(hardening_c)
    base = nvib.load_scene("building")
    mass, kw = base._init
    storeys = [e for e in kw["effects"] if e["type"] == "hardening_spring"]
    others = [e for e in kw["effects"] if e["type"] != "hardening_spring"]

    def model(effects):
        m = nvib.Model(mass, **{**kw, "effects": others + effects})
        m.u0, m.v0 = base.u0, base.v0
        return m

    compiled = model([{"type": "compiled", "name": e["name"], "measure": e["measure"], "law": law,
                       "params": [e["k0"], e["a"]], "uses_time": False} for e in storeys])
    n = len(storeys)
    array = model([{"type": "compiled", "i": list(range(n)), "j": [-1] + list(range(n - 1)), "law": law,
                    "params": [[e["k0"] for e in storeys], [e["a"] for e in storeys]], "uses_time": False}])

    def python_law(k0, a):
        return {"law": lambda d, dd, t: k0 * (1.0 + a * d * d) * d,
                "tangent": lambda d, dd, t: (k0 * (1.0 + 3.0 * a * d * d), 0.0)}

    python = model([{"type": "callable", "name": e["name"], "measure": e["measure"], "uses_velocity": False,
                     "uses_time": False, **python_law(e["k0"], e["a"])} for e in storeys])
    return {"built-in": model(storeys), "compiled (Numba)": compiled, "compiled array": array, "Python": python}, n


def chain_variants(n: int, law):
    """nvib.scenes.chain(n) with its hardening storeys built in, as a vectorised Python law, compiled."""
    base = nvib.scenes.chain(n)
    mass, kw = base._init
    storeys = next(e for e in kw["effects"] if e["type"] == "hardening_spring")
    others = [e for e in kw["effects"] if e is not storeys]
    k0, a = storeys["k0"], storeys["a"]
    vector = {"type": "callable", "i": storeys["i"], "j": storeys["j"], "uses_velocity": False, "uses_time": False,
              "law": lambda d, dd, t: k0 * (1.0 + a * d * d) * d,
              "tangent": lambda d, dd, t: (k0 * (1.0 + 3.0 * a * d * d), None)}
    compiled = {"type": "compiled", "i": storeys["i"], "j": storeys["j"], "law": law, "params": [k0, a],
                "uses_time": False}
    out = {}
    for name, spec in (("built-in array", storeys), ("vectorised Python", vector), ("compiled array", compiled)):
        m = nvib.Model(mass, **{**kw, "effects": [spec] + others})
        m.u0, m.v0 = base.u0, base.v0
        out[name] = m
    return out


def chain_table(rounds: int) -> list[str]:
    import numba

    law = numba.cfunc(nvib.LAW_SIGNATURE)(hardening_c)
    lines = ["", "## A vectorised Python law on a chain", "",
             "nvib.scenes.chain(n): n hardening storeys as one array, dampers, a ground motion; the central "
             "difference, 500 steps; time per effect and force evaluation (best of the rounds).", "",
             "| effects | law | run [ms] | ns per effect and evaluation | / built-in |", "|---:|---|---:|---:|---:|"]
    for n in (100, 1000, 10000):
        models = chain_variants(n, law)
        sch = nvib.CentralDifference()
        dt = 0.2 * np.sqrt(1e5 / 1e8)
        best = {k: np.inf for k in models}
        evals = {}
        for _ in range(rounds):
            for name, m in models.items():
                res = nvib.solve(m, sch, dt=dt, t_end=500 * dt, save_every=50)
                best[name] = min(best[name], res.stats.wall_time)
                evals[name] = res.stats.num_force_evals
        for name in models:
            per = best[name] / evals[name] / n * 1e9
            lines.append(f"| {n:,} | {name} | {best[name] * 1e3:.2f} | {per:.1f} | "
                         f"{best[name] / best['built-in array']:.2f}x |")
    return lines


def main() -> None:
    import argparse

    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rounds", type=int, default=ROUNDS, help=f"interleaved rounds (default {ROUNDS})")
    rounds = parser.parse_args().rounds
    models, n = variants()
    schemes = {"central difference": nvib.CentralDifference(), "Newmark, Newton": nvib.Newmark()}
    rows = []
    load = os.getloadavg()[0]
    start = time.time()
    for sname, sch in schemes.items():
        best = {k: np.inf for k in models}
        stats = {}
        for _ in range(rounds):
            for name, m in models.items():
                if name == "Python" and best[name] < np.inf and best[name] > 2.0:
                    continue  # one run of a slow contender is enough
                res = nvib.solve(m, sch, dt=DT, t_end=T_END)
                best[name] = min(best[name], res.stats.wall_time)
                stats[name] = res.stats
                if name == "built-in":
                    ref = res.u
                elif name != "Python":
                    assert np.array_equal(res.u, ref), f"{name} differs from the built-in law under {sname}"
        for name in models:
            s = stats[name]
            calls = n * (s.num_force_evals + s.num_tangent_evals)
            extra = (best[name] - best["built-in"]) / calls * 1e9
            rows.append((sname, name, best[name] * 1e3, best[name] / best["built-in"], calls, extra))
    lines = ["# A user's own law: what it costs", "",
             f"- date: {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}; nvib {nvib.__version__} "
             f"(git {git_revision()}); CPU: {cpu_name()}, {os.cpu_count()} logical CPUs; 1-minute load average "
             f"at start {load:.2f}",
             f"- the building (6 storeys), dt = {DT:g} s, t_end = {T_END:g} s, every state saved; best of {rounds} "
             "interleaved runs (`Stats.wall_time`); the compiled runs' displacements equal the built-in's bit for "
             "bit (checked in this run)",
             f"- whole run: {time.time() - start:.0f} s", "",
             "| scheme | law | run [ms] | / built-in | law calls | extra ns per call |",
             "|---|---|---:|---:|---:|---:|"]
    for sname, name, ms, ratio, calls, extra in rows:
        lines.append(f"| {sname} | {name} | {ms:.2f} | {ratio:.2f}x | {calls:,} | "
                     f"{'-' if name == 'built-in' else f'{extra:.1f}'} |")
    lines += chain_table(rounds)
    text = "\n".join(lines) + "\n"
    print(text)
    with open(OUT, "w", encoding="utf-8") as fh:
        fh.write(text)


if __name__ == "__main__":
    main()
