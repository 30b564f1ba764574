"""A batch on a finite-element model with a consistent mass: what each run pays before its first step.

solve_many builds one model per run (the given one with its ground motion scaled); a consistent mass is
factorised when a model is built, and each implicit run factorises its iteration matrix. Two things
spare a batch's runs most of that: their models share the factorised mass of the model they come from,
and the fill-reducing orderings of a sparse factorisation (most of its analysis) are kept by pattern for
the next matrix of the same pattern. This script runs the same batch three ways, one thread each (the
per-run cost, not the parallel speed-up: benchmarks/batch.py measures that):

* solve_many as it is;
* solve_many as before: each run's model built from its arguments alone (its mass factorised) and the
  kept orderings forgotten before each run (reproduced by replacing Model._rebuilt for that measurement);
* a loop of Model() + solve(), as a script without solve_many would do (the orderings are kept for it too).

Models: benchmarks/fe_models.py's walls and blocks, with their hardening springs; Newmark + full Newton
(the springs on a large linear part: the low-rank update), a few steps; scales 0.5, 1, 1.5, 2. Best of
--rounds interleaved rounds. Every way gives the same results, bit for bit (checked).

    python benchmarks/batch_fe.py [--out benchmarks/results/batch_fe.md]
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)

import nvib  # noqa: E402
from nvib._model import Model  # noqa: E402

import fe_models as fm  # noqa: E402
from building import cpu_name, git_revision  # noqa: E402
from fe_newton import nvib_model  # noqa: E402

SCALES = [0.5, 1.0, 1.5, 2.0]


def unshared_rebuilt(self, **changes):
    """Model._rebuilt without the shared mass and without kept orderings: each model factorises its own
    mass, and its run orders its iteration matrix, from scratch."""
    nvib._core.ordering_cache(clear=True)
    mass, kwargs = self._init
    model = Model(mass, **{**kwargs, **changes})
    model.__dict__.update(self._state())
    return model


def scaled(case: fm.Case, s: float) -> Model:
    return nvib_model(dataclasses.replace(case, ground_amplitude=case.ground_amplitude * s))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--models", nargs="*", default=["wall 40x60", "wall 60x120", "block 12x12x12", "block 16x16x16"])
    ap.add_argument("--steps", type=int, default=20)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--out", default=os.path.join(HERE, "results", "batch_fe.md"))
    args = ap.parse_args()

    rows = []
    for name in args.models:
        case = fm.make(name)
        dt = case.T1 / 50  # benchmarks/fe_newton.py's Newmark step
        base = nvib_model(case)
        run = dict(dt=dt, t_end=args.steps * dt, threads=1, progress=False, save_every=args.steps)
        best = {"shared": np.inf, "unshared": np.inf, "loop": np.inf, "model": np.inf}
        results = {}
        original = Model._rebuilt
        for _ in range(args.rounds):
            nvib._core.ordering_cache(clear=True)  # (each way starts with no pattern kept)
            t0 = time.perf_counter()
            results["shared"] = nvib.solve_many(base, nvib.Newmark(), scales=SCALES, **run)
            best["shared"] = min(best["shared"], time.perf_counter() - t0)
            Model._rebuilt = unshared_rebuilt
            try:
                t0 = time.perf_counter()
                results["unshared"] = nvib.solve_many(base, nvib.Newmark(), scales=SCALES, **run)
                best["unshared"] = min(best["unshared"], time.perf_counter() - t0)
            finally:
                Model._rebuilt = original
            nvib._core.ordering_cache(clear=True)
            t0 = time.perf_counter()
            loop = []
            for s in SCALES:
                t1 = time.perf_counter()
                m = scaled(case, s)
                if s == SCALES[0]:  # the first of the round, built with no ordering kept: Model() from scratch
                    best["model"] = min(best["model"], time.perf_counter() - t1)
                loop.append(nvib.solve(m, nvib.Newmark(), dt=dt, t_end=args.steps * dt, save_every=args.steps))
            best["loop"] = min(best["loop"], time.perf_counter() - t0)
            results["loop"] = loop
        for way in ("unshared", "loop"):
            for a, b in zip(results["shared"], results[way]):
                if not (np.array_equal(a.u, b.u) and np.array_equal(a.v, b.v)):
                    raise SystemExit(f"{name}: solve_many and the {way} runs differ")
        solver = results["shared"][0].stats.linear_solver
        rows.append((name, case.M.shape[0], dt, solver, best["model"], best["shared"], best["unshared"], best["loop"]))
        print(rows[-1], flush=True)

    load = os.getloadavg()[0]
    lines = [
        "# A batch on a finite-element model: the factorised mass shared, the orderings kept",
        "",
        f"Written by `benchmarks/batch_fe.py`. {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}; {cpu_name()}; "
        f"git {git_revision()}; 1-minute load average {load:.2f} at the end.",
        "",
        f"{len(SCALES)} runs per model (its ground motion scaled by {', '.join(map(str, SCALES))}), Newmark + full "
        f"Newton, {args.steps} steps, one thread; best of {args.rounds} interleaved rounds, each way starting with "
        "no ordering kept. *Model()*: building one model from its arrays (its consistent mass factorised, from "
        "scratch). *solve_many*: as it is (the runs' models share the factorised mass; orderings kept by pattern); "
        "*as before*: `solve_many` with each run's model factorising its own mass and each run ordering its "
        "matrices from scratch; *loop*: `Model()` + `solve()` per run (orderings kept). All three give the same "
        "results, bit for bit.",
        "",
        "| model | DOFs | dt [s] | linear solver | Model() [s] | solve_many [s] | solve_many as before [s] | "
        "loop of Model() + solve() [s] | per run saved [s] | now / before |",
        "|---|---:|---:|---|---:|---:|---:|---:|---:|---:|",
    ]
    for name, n, dt, solver, tm, sh, un, lp in rows:
        lines.append(f"| {name} | {n} | {dt:.3g} | {solver} | {tm:.3f} | {sh:.3f} | {un:.3f} | {lp:.3f} | "
                     f"{(un - sh) / len(SCALES):.3f} | {sh / un:.2f} |")
    with open(args.out, "w", encoding="utf-8") as f:
        f.write("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
