"""An incremental dynamic analysis to collapse and the fragility curves fitted to it, for the README.

    python benchmarks/ida_example.py [--out benchmarks/results]

The scene building_collapse (six storeys that deteriorate as the modified Ibarra-Medina-Krawinkler model
does, with P-delta) under a suite of ten synthetic records made as SGM-1 is (tools/make_ground_motion.py:
Kanai-Tajimi and Clough-Penzien filtered noise in the Jennings envelope, 30 s, PGA 0.40 g; seeds 1 to 10),
each traced by hunt and fill on Sa(T1, 5 %) to its collapse (CEMDTS, dt = 0.002 s, every run checked at
half the step). Writes ida.png and ida.md (the curves, capacities, causes and fractiles), and
fragility.png and fragility.md: left, synthetic multiple-stripe data (8 levels of Sa, 20 runs each, drawn
from a lognormal fragility with theta = 0.6 g and beta = 0.45, seed 20) and the fit, which should hold the
true values within about two standard errors; middle, the collapse fragility of the IDA; right, the
fragility of a maximum interstorey drift ratio above 1 % from the same curves.
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
THETA, BETA, SEED = 0.6, 0.45, 20
LEVELS = np.array([0.15, 0.3, 0.45, 0.6, 0.75, 0.9, 1.1, 1.4])
RUNS = 20
SEEDS = range(1, 11)  # the synthetic records
DRIFT_LIMIT = 1.0  # % drift ratio


def synthetic():
    import nvib
    from scipy import stats

    rng = np.random.default_rng(SEED)
    z = rng.binomial(RUNS, stats.norm.cdf(np.log(LEVELS / THETA) / BETA))
    return nvib.fragility.fit_stripes(LEVELS, RUNS, z, im_name="Sa(T1 = 0.8 s, 5 %)", im_unit="g",
                                      event="drift ratio > 2 %")


def records():
    """The suite: SGM-1's recipe with seeds 1 to 10, in g."""
    import sys

    import nvib

    sys.path.insert(0, os.path.join(HERE, "..", "tools"))
    import make_ground_motion as mk

    out = []
    for seed in SEEDS:
        t, a, _ = mk.generate(seed)
        out.append(nvib.GroundMotion.from_array(a, dt=mk.DT, units="g", name=f"SGM seed {seed}"))
    return out


def building_ida():
    import nvib

    model = nvib.load_scene("building_collapse")
    return nvib.ida(model, records(), scheme=nvib.CEMDTS(), dt=0.002, progress=False)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=os.path.join(HERE, "results"), help="folder of the figures and tables")
    args = ap.parse_args(argv)
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    import nvib

    stripes = synthetic()
    ida = building_ida()
    ida.plot(os.path.join(args.out, "ida.png"))
    collapse = nvib.fragility.from_ida(ida)
    drift = nvib.fragility.from_ida(ida, demand_limit=DRIFT_LIMIT)
    for f in (stripes, collapse, drift):
        print(f)
    with open(os.path.join(args.out, "ida.md"), "w", encoding="utf-8") as fh:
        fh.write("# IDA of building_collapse (benchmarks/ida_example.py)\n\n")
        fh.write(f"{len(ida.records)} synthetic records (SGM-1's recipe, seeds {SEEDS[0]} to {SEEDS[-1]}), each traced "
                 f"by hunt and fill on {ida.im_name} to its collapse, bracketed to {ida.tolerance:g} relative; "
                 f"{ida.scheme}, dt = {ida.dt:g} s, every run made again at dt/2 (worst change of a demand: "
                 f"{max(np.max(c.error[np.isfinite(c.error)], initial=0) for c in ida.curves):.2g}); "
                 f"{ida.runs} runs in {ida.wall_time:.2f} s on 2 cores.\n\n")
        fh.write(f"Collapse capacity: median {ida.capacity_fractile(50):.3g} g, 16 % {ida.capacity_fractile(16):.3g} g, "
                 f"84 % {ida.capacity_fractile(84):.3g} g.\n\n")
        fh.write(ida.markdown())
        if ida.warnings:
            fh.write("\nWarnings:\n\n" + "".join(f"- {w}\n" for w in ida.warnings))

    fig, axes = plt.subplots(1, 3, figsize=(16, 4.8), constrained_layout=True)
    stripes.plot(ax=axes[0])
    from scipy import stats

    axes[0].plot(LEVELS, stats.norm.cdf(np.log(LEVELS / THETA) / BETA), "x", color="0.5",
                 label=f"true: θ = {THETA} g, β = {BETA}")
    axes[0].legend(fontsize=7, loc="lower right")
    axes[0].set_title(f"Synthetic stripes: {LEVELS.size} levels x {RUNS} runs", fontsize=10)
    collapse.plot(ax=axes[1])
    axes[1].set_title(f"building_collapse, IDA of {len(ida.records)} records: collapse", fontsize=10)
    drift.plot(ax=axes[2])
    axes[2].set_title(f"the same IDA: max drift ratio > {DRIFT_LIMIT:g} %", fontsize=10)
    png = os.path.join(args.out, "fragility.png")
    fig.savefig(png, dpi=100)
    print(f"wrote {png}")

    md = os.path.join(args.out, "fragility.md")
    with open(md, "w", encoding="utf-8") as fh:
        fh.write("# Fragility functions (benchmarks/ida_example.py)\n\n")
        fh.write("θ and β by maximum likelihood (Baker 2015); standard errors from the observed information "
                 "(SE(θ) = θ SE(ln θ), the delta method).\n\n")
        fh.write(nvib.fragility.markdown_table([stripes, collapse, drift]))
        fh.write(f"\nSynthetic stripes: drawn from θ = {THETA} g, β = {BETA} (seed {SEED}); the fit is "
                 f"{abs(stripes.theta - THETA) / stripes.se_theta:.2f} SE(θ) and "
                 f"{abs(stripes.beta - BETA) / stripes.se_beta:.2f} SE(β) from them.\n\n")
        fh.write(stripes.data_table())
        fh.write("\nCollapse (each record's first collapsing Sa(T1), see ida.md):\n\n")
        fh.write(collapse.data_table())
        fh.write(f"\nMaximum interstorey drift ratio > {DRIFT_LIMIT:g} % (each curve's Sa(T1) where it reaches the "
                 "limit, interpolated between its runs; a collapse reaches it):\n\n")
        fh.write(drift.data_table())
    print(f"wrote {md}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
