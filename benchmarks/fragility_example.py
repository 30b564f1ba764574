"""Fragility functions fitted by maximum likelihood, as a figure and a table for the README.

    python benchmarks/fragility_example.py [--out benchmarks/results/fragility.png]

Left: synthetic multiple-stripe data (8 levels of Sa, 20 runs each, drawn from a lognormal fragility
with theta = 0.6 g and beta = 0.45, seed 20) and the fit, which should hold the true values within about
two standard errors. Middle and right: an IDA of the scene building_collapse (deteriorating storeys and
P-delta) under eight 12-s windows of its record SGM-1 at 14 scale factors (112 runs, CEMDTS,
dt = 0.002 s): the collapse fragility from each window's first collapsing scale (windows that never
collapse are censored at the highest scale), and the fragility of a peak storey drift above 35 mm (1 %
of the 3.5 m storey), collapses counted as exceedances. The IM of the IDA is the scale factor of the
record (1 = SGM-1's 0.40 g). Writes the figure and a markdown table beside it (results/fragility.md).
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
STARTS = (0, 2, 4, 6, 8, 10, 12, 14)  # s: the windows of SGM-1
SCALES = (0.2, 0.4, 0.6, 0.7, 0.8, 0.9, 1.0, 1.1, 1.2, 1.4, 1.7, 2.0, 2.5, 3.0)
DRIFT_LIMIT = 0.035  # m


def synthetic():
    import nvib
    from scipy import stats

    rng = np.random.default_rng(SEED)
    z = rng.binomial(RUNS, stats.norm.cdf(np.log(LEVELS / THETA) / BETA))
    return nvib.fragility.fit_stripes(LEVELS, RUNS, z, im_name="Sa(T1 = 0.8 s, 5 %)", im_unit="g",
                                      event="drift ratio > 2 %")


def building_ida():
    import nvib

    model = nvib.load_scene("building_collapse")
    at2 = os.path.join(os.path.dirname(nvib.__file__), "scenes", "records", "sgm1.AT2")
    gm = nvib.GroundMotion.from_at2(at2, scale=nvib.STANDARD_GRAVITY)
    records = []
    for start in STARTS:
        i = int(round(start / gm.dt))
        records.append(nvib.GroundMotion.from_array(gm.a[i:i + int(round(12.0 / gm.dt))], dt=gm.dt,
                                                    name=f"SGM-1 from {start} s"))
    t0 = time.perf_counter()
    ida = nvib.ida(model, records, SCALES, scheme=nvib.CEMDTS(), dt=0.002, t_end=12.0, progress=False)
    return ida, time.perf_counter() - t0


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=os.path.join(HERE, "results", "fragility.png"))
    args = ap.parse_args(argv)
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    import nvib

    stripes = synthetic()
    ida, seconds = building_ida()
    collapse = nvib.fragility.from_ida(ida)
    drift = nvib.fragility.from_ida(ida, demand_limit=DRIFT_LIMIT)
    drift.event = f"peak storey drift > {DRIFT_LIMIT * 1e3:g} mm"
    for f in (stripes, collapse, drift):
        print(f)

    fig, axes = plt.subplots(1, 3, figsize=(16, 4.8), constrained_layout=True)
    stripes.plot(ax=axes[0])
    from scipy import stats

    axes[0].plot(LEVELS, stats.norm.cdf(np.log(LEVELS / THETA) / BETA), "x", color="0.5",
                 label=f"true: θ = {THETA} g, β = {BETA}")
    axes[0].legend(fontsize=7, loc="lower right")
    axes[0].set_title(f"Synthetic stripes: {LEVELS.size} levels x {RUNS} runs", fontsize=10)
    collapse.plot(ax=axes[1])
    axes[1].set_title(f"building_collapse, IDA of {len(ida.records)} windows of SGM-1: collapse", fontsize=10)
    drift.plot(ax=axes[2])
    axes[2].set_title(f"the same IDA: peak storey drift > {DRIFT_LIMIT * 1e3:g} mm", fontsize=10)
    fig.savefig(args.out, dpi=100)
    print(f"wrote {args.out}")

    md = os.path.splitext(args.out)[0] + ".md"
    with open(md, "w", encoding="utf-8") as fh:
        fh.write("# Fragility functions (benchmarks/fragility_example.py)\n\n")
        fh.write("θ and β by maximum likelihood (Baker 2015); standard errors from the observed information "
                 "(SE(θ) = θ SE(ln θ), the delta method).\n\n")
        fh.write(nvib.fragility.markdown_table([stripes, collapse, drift]))
        fh.write(f"\nSynthetic stripes: drawn from θ = {THETA} g, β = {BETA} (seed {SEED}); the fit is "
                 f"{abs(stripes.theta - THETA) / stripes.se_theta:.2f} SE(θ) and "
                 f"{abs(stripes.beta - BETA) / stripes.se_beta:.2f} SE(β) from them.\n\n")
        fh.write(stripes.data_table())
        fh.write(f"\nIDA of building_collapse: {len(ida.records)} windows x {len(SCALES)} scales, CEMDTS, "
                 f"dt = 0.002 s, 12 s each, {seconds:.2f} s of computing; the IM is the scale factor of "
                 f"the record (1 = 0.40 g). Collapse:\n\n")
        fh.write(collapse.data_table())
        fh.write(f"\nPeak storey drift > {DRIFT_LIMIT * 1e3:g} mm (collapses count as exceedances):\n\n")
        fh.write(drift.data_table())
        fh.write("\nThe IDA's peak storey drift [m]:\n\n")
        fh.write(ida.markdown())
    print(f"wrote {md}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
