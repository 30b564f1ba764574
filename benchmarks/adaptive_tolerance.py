"""Whether an adaptive run (solve(..., tol=)) meets its tolerance: the true error against tol.

For each of the paper's scenes and each scheme with a local control (PIM has none and refuses a tol), at
tol = 1e-3 and 1e-4: the true error max_t |u_i - u_ref,i| / max_t |u_ref,i| of the worst DOF (a DOF whose
peak is under 1e-3 of the largest is measured against 1e-3 of the largest) at every accepted step (all
are saved), against the closed form or DOP853 with contact events (nvib.reference), its ratio to tol,
the run's own estimate (the answer against its companion run on double steps) and its ratio to the
truth, the answer's steps, the companion's, the retaken ones, the events landed, the restarts and the
wall time of the whole run (every attempt). The scene's dt is the first step (and an explicit scheme's
longest companion step).

    python benchmarks/adaptive_tolerance.py [--out benchmarks/results/adaptive_tolerance.md]
"""

from __future__ import annotations

import argparse
import os
import sys
import time

import nvib
from nvib.analysis.reference import reference

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from building import cpu_name, git_revision  # noqa: E402
from error_estimate import true_error  # noqa: E402  (the same measure as the estimate's table)

SCENES = ["building", "hardening", "pendulum", "pendulum_ic2", "vehicle"]
TOLS = (1e-3, 1e-4)


def schemes():
    return [nvib.CentralDifference(), nvib.CEMDTS(), nvib.Zhai(), nvib.Newmark(), nvib.GeneralizedAlpha()]


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--out", help="write the table (Markdown) here too")
    args = p.parse_args()
    lines = ["# Adaptive runs against their tolerance", "",
             f"nvib {nvib.__version__}, revision {git_revision()}, {cpu_name()}, "
             f"load average {os.getloadavg()[0]:.2f}, {time.strftime('%Y-%m-%d')}", "",
             "| scene | scheme | tol | true error | true / tol | estimate | estimate / true | steps | companion steps "
             "| retaken | events | restarts | time (s) |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    print("\n".join(lines))
    for scene in SCENES:
        model = nvib.load_scene(scene)
        t_end, dt = model.scene["t_end"], model.scene["dt"]
        ref = reference(model, t_end)
        for scheme in schemes():
            for tol in TOLS:
                res = nvib.solve(model, scheme, dt=dt, t_end=t_end, tol=tol, throw=False)
                err = true_error(res, ref)
                s = res.stats
                row = (f"| {scene} | {scheme.label} | {tol:g} | {err:.3g} | {err / tol:.3g} | "
                       f"{res.error_estimate.max:.3g} | {res.error_estimate.max / err:.2g} | {s.num_steps} | "
                       f"{s.num_check_steps} | {s.num_rejected_steps} | {s.num_events} | {s.num_restarts} | "
                       f"{s.wall_time:.3g} |")
                lines.append(row)
                print(row, flush=True)
    if args.out:
        with open(args.out, "w") as f:
            f.write("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
