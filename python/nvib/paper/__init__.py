"""The evidence of Yang et al. (2017): its figures, Table 1, its CPU-time table, and an η study of CEMDTS.

``write_paper(outdir)`` (the command ``nvib paper OUTDIR``) runs every case of
the paper with the paper's schemes and writes into ``outdir``:

    fig02_pendulum_ic1.png ... fig11_pendulum_ic1_dt0.8.png   the figures (PNG)
    table1_energy_error.png   Table 1 as a plot (energy error against Δt)
    eta_study.png             CEMDTS against η
    runs.csv                  one row per (case, scheme): the measures below
    table1.csv                hardening oscillator, one row per (scheme, Δt)
    cpu_time.csv              building at Δt = 1e-4 s, one row per scheme
    eta_study.csv             one row per (problem, η), and half-step LCDM
    summary.md                every table in markdown, with the figures

Schemes, with the paper's settings (Yang et al. 2017, section 4): LCDM with
synchronized and with half-step velocity (same displacements, different
velocities); CEMDTS(0.45); Newmark(1/4, 1/2) and GαM = GeneralizedAlpha(1/2,
1/2, 1/4, 1/2), each in the paper's incremental format (iteration
'incremental': Chopra section 5.7, the paper's section 6), in the one-iteration
format (iteration 'one_iteration': one Newton iteration on the full residual
per step, accepted as is) and with full Newton iteration; PIM (20 squarings,
interpolation degree 2, 1 correction).

Measures (one row per run):

    max_error      nvib.cost: max |u - u_ref| over the run on the case's DOF / max |u_ref|
    error_estimate the run's own estimate of its error (Result.error_estimate.max: the worst DOF,
                   relative to its peak; NaN for PIM, which has none), so an inaccurate run shows
                   without a reference
    energy_error   conservative models: max_n |E_n - E_0| / E_0, E = kinetic + potential from
                   nvib's energy accounting (potential 0 at rest); other models: nvib's relative
                   energy balance error (Energy.relative_balance_error)
    locus_error    one-DOF conservative models: the largest distance from a computed (u, v) to the
                   exact phase locus (the closed orbit of the closed form), both axes scaled by the
                   orbit's extent (max |u|, max |v|). This is the paper's 'phase locus' comparison:
                   blind to timing, it sees amplitude and shape
    state_error    the same scaled distance to the exact state at the same time (timing included)
    max_abs_u, t_over_the_top   the pendulum: largest |θ| and the first time |θ| > π (the locus
                   leaves the libration: 'snake-like')
    wall_time      nvib.cost: best of ``repeats`` runs of the whole solve() call

References come from ``nvib.reference``: closed forms for the pendulum and the
hardening oscillator, DOP853 at rtol 1e-12 for the building and the vehicle.
"""

from __future__ import annotations

import csv
import math
import os
import platform
import time

from .cases import (CASES, HARDENING_TMIN, PAPER_ETA, RUN_FIELDS, _fmt, building_facts, cpu_time, eta_study,
                    measure, paper_schemes, recommend_eta, setting, table1)
from .figures import plot_eta, plot_history, plot_long, plot_phase, plot_table1

def run_cases(cases=CASES, *, repeats: int = 3, outdir: str | None = None, progress=None) -> list[dict]:
    """Every case with its schemes; writes each figure to outdir (when given). One row per run."""
    rows = []
    for case in cases:
        s = setting(case.scene, case.dt, case.t_end, case.dof)
        case_rows, runs = [], []
        for scheme in paper_schemes(case.half_step):
            row, res = measure(s, scheme, repeats=repeats, case=case.key, claim=case.claim)
            case_rows.append(row)
            runs.append(res)
        if outdir is not None:
            draw = {"phase": plot_phase, "history": plot_history, "long": plot_long}[case.kind]
            draw(case, s, case_rows, runs, os.path.join(outdir, case.key + ".png"))
        rows += case_rows
        if progress is not None:
            progress(case.key)
    return rows



def _write_csv(path: str, rows: list[dict], fields) -> None:
    with open(path, "w", encoding="utf-8", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(fields), extrasaction="ignore")
        w.writeheader()
        for r in rows:
            w.writerow({k: ("" if isinstance(r.get(k), float) and math.isnan(r[k]) else r.get(k, ""))
                        for k in fields})


def _md(header: list[str], body: list[list[str]], right_from: int = 1) -> str:
    lines = ["| " + " | ".join(header) + " |",
             "|" + "|".join("---" if i < right_from else "---:" for i in range(len(header))) + "|"]
    lines += ["| " + " | ".join(r) + " |" for r in body]
    return "\n".join(lines)


def _runs_md(rows: list[dict]) -> str:
    head = ["scheme", "status", "max error", "estimated error", "energy error", "locus error", "state error", "max abs u",
            "over the top [s]", "E end / E0", "Newton it./step", "max residual", "wall [ms]"]
    body = [[r["scheme"], r["status"], _fmt(r["max_error"]), _fmt(r["error_estimate"]), _fmt(r["energy_error"]), _fmt(r["locus_error"]),
             _fmt(r["state_error"]), _fmt(r["max_abs_u"]), _fmt(r["t_over_the_top"]),
             _fmt(r["energy_end_over_start"]), _fmt(r["newton_iters_per_step"]), _fmt(r["max_residual"]),
             _fmt(r["wall_time"] * 1e3)] for r in rows]
    return _md(head, body)


def _table1_md(rows: list[dict]) -> str:
    dts = sorted({r["dt"] for r in rows})
    labels = list(dict.fromkeys(r["scheme"] for r in rows))
    cell = {(r["scheme"], r["dt"]): r for r in rows}
    head = ["scheme"] + [f"Δt = {dt * 1e3:.3g} ms (Tmin/{HARDENING_TMIN / dt:.3g})" for dt in dts]
    body = [[lab] + [_fmt(cell[(lab, dt)]["energy_error"]) if cell[(lab, dt)]["status"] == "success"
                     else cell[(lab, dt)]["status"] for dt in dts] for lab in labels]
    order = []
    for dt in dts:
        ranked = sorted((r for r in rows if r["dt"] == dt), key=lambda r: r["energy_error"])
        order.append(f"- Δt = {dt * 1e3:.3g} ms: " + " < ".join(f"{r['scheme']}" for r in ranked))
    return _md(head, body) + "\n\nOrder, smallest energy error first:\n\n" + "\n".join(order)


def _cpu_md(rows: list[dict]) -> str:
    head = ["scheme", "nvib [ms]", "nvib / CEMDTS", "2017 [s]", "2017 / CEMDTS", "error on x6", "force evals",
            "Newton it.", "factorisations", "timed runs"]
    body = [[r["label"], _fmt(r["wall_time"] * 1e3), _fmt(r["over_cemdts"]), _fmt(r["paper_2017_s"]),
             _fmt(r["paper_over_cemdts"]), _fmt(r["max_error"]), _fmt(int(r["force_evals"])),
             _fmt(int(r["newton_iters"])), _fmt(int(r["factorizations"])), str(r["repeats"])] for r in rows]
    return _md(head, body)


def _eta_md(rows: list[dict]) -> str:
    problems = list(dict.fromkeys(r["problem"] for r in rows))
    variants = list(dict.fromkeys(r["variant"] for r in rows))
    cell = {(r["problem"], r["variant"]): r for r in rows}
    out = []
    for key, name in (("energy_error", "max relative energy error"), ("locus_error", "phase-locus error"),
                      ("state_error", "state error")):
        head = ["variant"] + problems
        body = [[v] + [_fmt(cell[(p, v)][key]) for p in problems] for v in variants]
        out.append(f"**{name}**\n\n" + _md(head, body))
    return "\n\n".join(out)


def _overview_md(runs: list[dict]) -> str:
    """Error and wall time of every scheme in every case, side by side (one run on one machine)."""
    keys = [c.key for c in CASES]
    labels = list(dict.fromkeys(r["scheme"] for r in runs))
    cell = {(r["case"], r["scheme"]): r for r in runs}
    head = ["scheme"] + [k.split("_", 1)[0] for k in keys]

    def body(get):
        return [[lab] + [get(cell[(k, lab)]) if (k, lab) in cell else "" for k in keys] for lab in labels]

    return ("**max error** (displacement of the figure's DOF, relative)\n\n" +
            _md(head, body(lambda r: _fmt(r["max_error"]))) +
            "\n\n**estimated error** (the run's own Result.error_estimate, worst DOF)\n\n" +
            _md(head, body(lambda r: _fmt(r["error_estimate"]))) +
            "\n\n**energy error** (max |E - E0| / E0; building and vehicle: energy balance error)\n\n" +
            _md(head, body(lambda r: _fmt(r["energy_error"]))) +
            "\n\n**wall time [ms]** (best of the timed runs of the whole solve() call)\n\n" +
            _md(head, body(lambda r: _fmt(r["wall_time"] * 1e3))))


def _summary(path: str, meta: dict, runs: list[dict], t1: list[dict], cpu: list[dict], eta: list[dict],
             facts: dict) -> None:
    eta_best, worst = recommend_eta(eta)
    parts = [
        "# Yang et al. (2017) regenerated by nvib",
        "",
        f"Written by `nvib paper` on {meta['date']} ({meta['machine']}; Python {meta['python']}, nvib "
        f"{meta['version']}) in {meta['elapsed']:.1f} s. Measures are defined in `nvib.paper` (module docstring): "
        "max error = max |u - u_ref| / max |u_ref| on the figure's DOF; energy error = max |E - E0| / E0 "
        "(conservative models) or nvib's energy balance error (building, vehicle); locus error = largest scaled "
        "distance to the exact phase locus; state error = scaled distance to the exact state at the same time. "
        "Wall time: best of several runs of the whole solve() call.",
        "",
    ]
    parts += ["## Overview: every case, every scheme", "", _overview_md(runs), ""]
    for case in CASES:
        rows = [r for r in runs if r["case"] == case.key]
        parts += [f"## {case.title} ({case.claim})", "", f"![{case.key}]({case.key}.png)", "",
                  f"Reference: {rows[0]['reference']}.", "", _runs_md(rows), ""]
        if case.key == "fig06_building_floor1":
            parts += [f"Building as modelled: linearised circular frequencies at rest {facts['omega_min']:.4g} ... "
                      f"{facts['omega_max']:.4g} rad/s (Tmin = {facts['tmin']:.4g} s); largest inter-storey drift "
                      f"of the reference over 10 s {facts['max_drift']:.4g} m (storey {facts['storey']}), so the "
                      f"largest secant stiffness over the stiffness at rest (the paper's degree of nonlinearity) is "
                      f"{facts['nonlinearity']:.4g}.", ""]
    parts += ["## Table 1: hardening oscillator, maximum relative energy error (C4)", "",
              "![table1](table1_energy_error.png)", "",
              f"t_end = 0.3 s; Tmin = 2π / 82.76 rad/s = {HARDENING_TMIN * 1e3:.2f} ms (the paper's secant frequency).",
              "", _table1_md(t1), "",
              "## CPU time, building, Δt = 1e-4 s, t_end = 10 s (C6)", "",
              "nvib: best of the timed runs of the whole `solve()` call, every state saved; 2017: the paper's "
              "figures (its hardware, end time not stated).", "", _cpu_md(cpu), "",
              "## CEMDTS: η study", "", "![eta](eta_study.png)", "", _eta_md(eta), "",
              f"Recommended η (smallest worst-case ratio of its energy error to the best η of each problem): "
              f"**{eta_best:.4g}** (worst ratio {worst[eta_best]:.3g}); η = 1/12: {worst[1.0 / 12.0]:.3g}; "
              f"η = 0.45: {worst[PAPER_ETA]:.3g}; η = 0 (LCDM): {worst[0.0]:.3g}.", "",
              "Best η of each problem (on the grid above):", ""]
    cem = [r for r in eta if r["eta"] != ""]
    for p in dict.fromkeys(r["problem"] for r in cem):
        pr = [r for r in cem if r["problem"] == p]
        parts.append(f"- {p}: " + "; ".join(
            f"{name} {min(pr, key=lambda r: r[key])['eta']:.4g}" for key, name in
            (("energy_error", "energy error"), ("locus_error", "locus error"), ("state_error", "state error"))))
    parts.append("")
    with open(path, "w", encoding="utf-8") as fh:
        fh.write("\n".join(parts))


def write_paper(outdir: str, *, repeats: int = 3, cpu_repeats: int = 5, progress=None) -> dict:
    """Run everything and write the figures, CSV tables and summary.md into ``outdir`` (created if missing).
    Returns {name: path} of the files written."""
    import datetime

    t0 = time.perf_counter()
    os.makedirs(outdir, exist_ok=True)
    say = progress or (lambda what: None)
    runs = run_cases(repeats=repeats, outdir=outdir, progress=say)
    t1 = table1(repeats=repeats)
    plot_table1(t1, os.path.join(outdir, "table1_energy_error.png"))
    say("table1")
    cpu = cpu_time(repeats=cpu_repeats)
    say("cpu_time")
    eta = eta_study()
    plot_eta(eta, os.path.join(outdir, "eta_study.png"))
    say("eta_study")
    facts = building_facts()
    files = {c.key: os.path.join(outdir, c.key + ".png") for c in CASES}
    files.update({n: os.path.join(outdir, n + ".png") for n in ("table1_energy_error", "eta_study")})
    for name, rows, fields in (("runs", runs, RUN_FIELDS), ("table1", t1, RUN_FIELDS + ("dt_over_tmin",)),
                               ("cpu_time", cpu, ("label", "scheme", "dt", "t_end", "wall_time", "repeats",
                                                  "over_cemdts", "paper_2017_s", "paper_over_cemdts", "max_error",
                                                  "energy_error", "num_steps", "force_evals", "newton_iters",
                                                  "factorizations", "status", "reference")),
                               ("eta_study", eta, ("problem", "variant", "eta") + RUN_FIELDS)):
        files[name + ".csv"] = os.path.join(outdir, name + ".csv")
        _write_csv(files[name + ".csv"], rows, fields)
    from .. import __version__

    meta = {"date": datetime.date.today().isoformat(), "machine": f"{platform.machine()}, {platform.system()}",
            "python": platform.python_version(), "version": __version__, "elapsed": time.perf_counter() - t0}
    files["summary.md"] = os.path.join(outdir, "summary.md")
    _summary(files["summary.md"], meta, runs, t1, cpu, eta, facts)
    return files
