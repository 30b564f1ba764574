"""Peak memory of a long run: memory holds only what is saved.

Runs the hardening oscillator (m = 1, k0 = 100, a = 30, x0 = 1.5; built-in
effect, so the loop is C++ only) for many steps in a fresh subprocess per
case and reads the peak resident set size (ru_maxrss) of that process. The
baseline row is the same process importing nvib and building the model
without integrating.

    python benchmarks/memory.py [--steps 10000000] [--out benchmarks/results/memory.md]
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import textwrap

CHILD = textwrap.dedent("""
    import json, resource, sys, time
    import nvib
    steps, save_every = int(sys.argv[1]), int(sys.argv[2])
    model = nvib.Model([1.0], effects=[{"type": "hardening_spring", "measure": {"x": 1.0}, "k0": 100.0, "a": 30.0}],
                       dofs=["x"], u0=[1.5])
    dt = 1e-5
    out = {"steps": steps, "save_every": save_every}
    if steps > 0:
        t0 = time.perf_counter()
        res = nvib.solve(model, nvib.CEMDTS(0.45), dt=dt, t_end=steps * dt, save_every=save_every)
        out["wall_time"] = time.perf_counter() - t0
        out["saved"] = len(res.t)
        out["steps_done"] = res.stats.num_steps
        out["saved_bytes"] = res.u.nbytes + res.v.nbytes + res.a.nbytes + res.t.nbytes
    out["peak_rss_mb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    print(json.dumps(out))
""")


def measure(steps: int, save_every: int) -> dict:
    p = subprocess.run([sys.executable, "-c", CHILD, str(steps), str(save_every)], capture_output=True, text=True,
                       check=True)
    return json.loads(p.stdout.strip().splitlines()[-1])


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--steps", type=int, default=10_000_000)
    ap.add_argument("--out", default=os.path.join(os.path.dirname(__file__), "results", "memory.md"))
    args = ap.parse_args()
    cases = [(0, 1), (args.steps, 1000), (args.steps, 100_000), (args.steps // 10, 1)]
    rows = [measure(s, k) for s, k in cases]
    lines = [
        "# Peak memory of long runs",
        "",
        "Hardening oscillator (built-in effect, C++ loop), CEMDTS(0.45), dt = 1e-5 s; each case in a fresh",
        "process; peak RSS from `ru_maxrss`. Baseline: interpreter + `import nvib` + model, no run.",
        "",
        "| steps | save_every | saved states | saved arrays [MB] | peak RSS [MB] | above baseline [MB] | wall time [s] | per step [ns] |",
        "|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    base = rows[0]["peak_rss_mb"]
    for r in rows:
        if r["steps"] == 0:
            lines.append(f"| 0 (baseline) | - | - | - | {base:.1f} | 0 | - | - |")
            continue
        lines.append(f"| {r['steps']:,} | {r['save_every']:,} | {r['saved']:,} | {r['saved_bytes'] / 2**20:.2f} | "
                     f"{r['peak_rss_mb']:.1f} | {r['peak_rss_mb'] - base:.1f} | {r['wall_time']:.2f} | "
                     f"{r['wall_time'] / r['steps'] * 1e9:.0f} |")
    text = "\n".join(lines) + "\n"
    print(text)
    os.makedirs(os.path.dirname(args.out), exist_ok=True)
    with open(args.out, "w") as fh:
        fh.write(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
