"""How far a run's own error estimate (Result.error_estimate) is from its true error, and what it costs.

For each scene, scheme and step: the true error max_t |u_i - u_ref,i| / max_t |u_ref,i| of the worst DOF
(a DOF whose peak is under 1e-3 of the largest is measured against 1e-3 of the largest, as the estimate
is), the estimate's largest DOF, their ratio, and whether the run warned (warn_error = 1 %). The
references: the closed form or DOP853 (nvib.reference) for the paper's scenes; for building_inelastic
(laws with memory, which DOP853 cannot carry), Newmark with full Newton at 1/64 of the scene's step,
checked against 1/128 (the difference is printed). Then the estimate's overhead: the building and a
10^5-DOF chain, best of several runs with error_estimate=True and False.

    python benchmarks/error_estimate.py [--quick] [--out benchmarks/results/error_estimate.md]
"""

from __future__ import annotations

import argparse
import math
import os
import platform
import sys
import time

import numpy as np

import nvib
from nvib.analysis.reference import reference

SCENES = ["hardening", "pendulum", "pendulum_ic2", "building", "vehicle", "building_inelastic"]
FACTORS = (1.0, 0.5, 0.25)


def schemes():
    return [nvib.CentralDifference(), nvib.CEMDTS(), nvib.Zhai(), nvib.Newmark(), nvib.GeneralizedAlpha(),
            nvib.PreciseIntegration()]


class FineStep:
    """Newmark (full Newton) at dt/64, checked at dt/128; u between steps by cubic Hermite interpolation."""

    def __init__(self, model, t_end, dt):
        from scipy.interpolate import CubicHermiteSpline

        a = nvib.solve(model, nvib.Newmark(), dt=dt / 64, t_end=t_end)
        b = nvib.solve(model, nvib.Newmark(), dt=dt / 128, t_end=t_end)
        self._u = CubicHermiteSpline(b.t, b.u, b.v, axis=0)
        peak = np.max(np.abs(b.u), axis=0)
        peak = np.maximum(peak, 1e-3 * peak.max())
        self.check = float(np.max(np.max(np.abs(a.u - b.u[::2]), axis=0) / peak))
        self.t_end = float(b.t[-1])
        self.description = f"Newmark at dt/128 (differs from dt/64 by {self.check:.1e})"

    def u(self, t):
        return self._u(t)


def true_error(res, ref) -> float:
    keep = res.t <= ref.t_end * (1 + 1e-12)
    u_ref = ref.u(res.t[keep])
    peak = np.max(np.abs(u_ref), axis=0)
    peak = np.maximum(peak, 1e-3 * peak.max())
    with np.errstate(all="ignore"):
        err = np.max(np.abs(res.u[keep] - u_ref), axis=0) / peak
    return float(np.max(err)) if np.all(np.isfinite(err)) else math.inf


def table(quick: bool) -> tuple[list[dict], dict]:
    rows, refs = [], {}
    for name in SCENES:
        model = nvib.load_scene(name)
        t_end, dt0 = model.scene["t_end"], model.scene["dt"]
        ref = FineStep(model, t_end, dt0) if name == "building_inelastic" else reference(model, t_end)
        refs[name] = ref.description
        for scheme in schemes():
            if scheme.key == "pim" and model.n > nvib._core.PIM_MAX_DOFS:
                continue
            for f in FACTORS[:1] if quick else FACTORS:
                dt = dt0 * f
                res = nvib.solve(model, scheme, dt=dt, t_end=t_end, throw=False)
                est = res.error_estimate
                true = true_error(res, ref) if res.status == nvib.Status.success else math.inf
                warned = any("estimated error" in w for w in res.warnings)
                rows.append(dict(scene=name, scheme=scheme.label, dt=dt, status=res.status.name, true=true,
                                 estimate=est.max, dof=est.dof, warned=warned))
                print(f"{name:18s} {scheme.label:24s} dt {dt:<9.3g} true {true:9.2e} estimate {est.max:9.2e}",
                      file=sys.stderr)
    return rows, refs


def verdict(r: dict) -> str:
    if not math.isfinite(r["estimate"]):
        return "no estimate" + (" (true > 10 %, not warned)" if r["true"] > 0.1 else "")
    ratio = r["estimate"] / r["true"] if r["true"] > 0 else math.inf
    if r["true"] >= 0.3:
        return "true >= 0.3" + ("" if r["warned"] else ", NOT WARNED")
    return "yes" if 1 / 3 <= ratio <= 3 else "no"


def overhead(repeats: int) -> list[dict]:
    cases = [("building", nvib.load_scene("building"), [nvib.CentralDifference(), nvib.Newmark(), nvib.PreciseIntegration()],
              7e-4, 10.0)]
    from scipy import sparse

    n = 100_000
    main = np.full(n, 2.0e4)
    main[-1] = 1.0e4
    K = sparse.diags([main, -1.0e4 * np.ones(n - 1), -1.0e4 * np.ones(n - 1)], [0, -1, 1], format="csc")
    u0 = np.zeros(n)
    u0[0] = 1e-3
    chain = nvib.Model(np.ones(n), K=K, u0=u0)
    cases.append(("chain, 10^5 DOFs (linear)", chain, [nvib.CentralDifference()], 5e-3, 2.0))
    out = []
    for name, model, ss, dt, t_end in cases:
        for s in ss:
            times = {}
            for flag in (False, True):
                best = math.inf
                for _ in range(repeats):
                    t0 = time.perf_counter()
                    nvib.solve(model, s, dt=dt, t_end=t_end, save_every=10**9, error_estimate=flag)
                    best = min(best, time.perf_counter() - t0)
                times[flag] = best
            out.append(dict(model=name, scheme=s.label, off=times[False], on=times[True]))
            print(f"{name:28s} {s.label:20s} off {times[False]:.4f} s on {times[True]:.4f} s", file=sys.stderr)
    return out


def machine() -> list[str]:
    from building import cpu_name, git_revision

    return [f"- CPU: {cpu_name()}, {os.cpu_count()} logical CPUs; {platform.system()} {platform.release()}; "
            f"1-minute load average at the end {os.getloadavg()[0]:.2f}",
            f"- nvib {nvib.__version__} (git {git_revision()}), Python {platform.python_version()}, "
            f"NumPy {np.__version__}"]


def markdown(rows, refs, costs) -> str:
    lines = ["# Error estimate against the true error", "", "`python benchmarks/error_estimate.py`", "",
             *machine(), "",
             "true: max over DOFs of max_t |u - u_ref| / max_t |u_ref| (peaks under 1e-3 of the largest floored "
             "there); estimate: `Result.error_estimate.max`; within 3: the estimate within a factor 3 of the true "
             "error (asked where the true error is below 0.3); warned: a `warnings` entry (warn_error = 1 %).", "",
             "References: " + "; ".join(f"{k}: {v}" for k, v in refs.items()), "",
             "| scene | scheme | dt [s] | true error | estimate | estimate / true | within 3 | warned |",
             "|---|---|---:|---:|---:|---:|---|---|"]
    for r in rows:
        ratio = r["estimate"] / r["true"] if r["true"] > 0 and math.isfinite(r["estimate"]) else math.nan
        lines.append(f"| {r['scene']} | {r['scheme']} | {r['dt']:.3g} | {r['true']:.2e} | {r['estimate']:.2e} | "
                     f"{ratio:.2f} | {verdict(r)} | {'yes' if r['warned'] else 'no'} |")
    judged = [r for r in rows if math.isfinite(r["estimate"]) and r["true"] < 0.3]
    within = [r for r in judged if verdict(r) == "yes"]
    ratios = [r["estimate"] / r["true"] for r in judged if r["true"] > 0]
    silent = [r for r in rows if r["true"] > 0.1 and not r["warned"]]
    lines += ["", f"Within a factor 3: {len(within)} of {len(judged)} runs with an estimate and a true error below "
                  f"0.3 (estimate / true from {min(ratios):.2f} to {max(ratios):.2f}). Runs with a true error above "
                  f"10 % and no warning: {len(silent)}"
              + (" (" + ", ".join(f"{r['scene']} {r['scheme']} dt {r['dt']:.3g}" for r in silent) + ")" if silent else "")
              + ".", ""]
    lines += ["## Overhead", "", "| model | scheme | without [s] | with [s] | overhead |", "|---|---|---:|---:|---:|"]
    for c in costs:
        lines.append(f"| {c['model']} | {c['scheme']} | {c['off']:.4f} | {c['on']:.4f} | "
                     f"{100 * (c['on'] / c['off'] - 1):+.1f} % |")
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--quick", action="store_true", help="one step per scene and scheme, fewer timing repeats")
    p.add_argument("--out", help="write the markdown table here")
    a = p.parse_args(argv)
    rows, refs = table(a.quick)
    costs = overhead(2 if a.quick else 7)
    text = markdown(rows, refs, costs)
    print(text)
    if a.out:
        with open(a.out, "w") as f:
            f.write(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
