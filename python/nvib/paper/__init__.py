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

Schemes, with the paper's settings (PAPER.md): LCDM with synchronized and
with half-step velocity (same displacements, different velocities); CEMDTS(0.45);
Newmark(1/4, 1/2) and GαM = GeneralizedAlpha(1/2, 1/2, 1/4, 1/2), each in the
paper's incremental format (iteration 'none': one linearised solve per step)
and with full Newton iteration; PIM (20 squarings, order 2, 1 correction).

Measures (one row per run):

    max_error      nvib.cost: max |u - u_ref| over the run on the case's DOF / max |u_ref|
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
from dataclasses import dataclass

import numpy as np

from .. import _checks, _core
from .._core import CEMDTS, CentralDifference, GeneralizedAlpha, Newmark, PreciseIntegration
from .._labels import scheme_label
from .._scenes import load_scene
from .._solve import solve
from ..analysis.cost import _conservative, cost
from ..analysis.reference import reference

# The hardening oscillator's smallest period by the paper's secant frequency sqrt(k0 (1 + a x0^2) / m)
# = 82.76 rad/s (section 4.2: "the time step is 1/76 of the minimum natural period").
HARDENING_TMIN = 2.0 * math.pi / math.sqrt(100.0 * (1.0 + 30.0 * 1.5 ** 2) / 1.0)
TABLE1_DTS = (5e-4, 1e-3, 2e-3, HARDENING_TMIN / 20.0, HARDENING_TMIN / 10.0)
CPU_DT, CPU_T_END = 1e-4, 10.0  # the paper's end time is not stated; 10 s assumed (PAPER.md)
CPU_2017 = {"CEMDTS": 1.89, "Newmark": 2.01, "GαM": 2.23, "PIM": 11.12}  # seconds, 2017 hardware
PAPER_ETA = 0.45
ETA_GRID = tuple(sorted(set(np.round(np.linspace(0.0, 0.5, 21), 6).tolist()) | {1.0 / 12.0, PAPER_ETA}))
ORBIT_SAMPLES = 400_000  # points on the exact orbit: spacing ~1e-5 of its extent, far below the errors measured


def _color(label: str) -> str:
    """One colour per scheme in every figure (grey is left to the reference)."""
    order = ("LCDM", "LCDM (half-step v)", "CEMDTS", "Newmark (none)", "Newmark (newton)", "GαM(0.5,0.5) (none)",
             "GαM(0.5,0.5) (newton)", "PIM")
    colors = ("C0", "C1", "C2", "C3", "C4", "C5", "C6", "C9")
    for name, c in zip(order, colors):
        if label == name or (name == "CEMDTS" and label.startswith("CEMDTS")):
            return c
    return "C8"


def paper_schemes(half_step: bool = True) -> list:
    """The paper's five schemes, LCDM in both velocity variants, Newmark and GαM in both formats."""
    out = [CentralDifference()]
    if half_step:
        out.append(CentralDifference(velocity="half_step"))
    out += [CEMDTS(PAPER_ETA),
            Newmark(0.25, 0.5, iteration="none"), Newmark(0.25, 0.5, iteration="newton"),
            GeneralizedAlpha(0.5, 0.5, 0.25, 0.5, iteration="none"),
            GeneralizedAlpha(0.5, 0.5, 0.25, 0.5, iteration="newton"),
            PreciseIntegration(squarings=20, order=2, corrections=1)]
    return out


@dataclass(frozen=True)
class Case:
    """One figure of the paper: a scene, a step, an end time, the DOF shown and how it is drawn."""
    key: str
    title: str
    scene: str
    dt: float
    t_end: float
    dof: str
    kind: str  # 'phase' (phase loci), 'history' (displacement against time), 'long' (largest angle and energy)
    claim: str
    half_step: bool = True  # history figures leave out half-step LCDM: its displacements are LCDM's


CASES = (
    Case("fig02_pendulum_ic1", "Fig. 2: pendulum IC1, θ(0) = -0.95π, Δt = 0.3 s, t_end = 15 s",
         "pendulum", 0.3, 15.0, "theta", "phase", "C1"),
    Case("fig03_pendulum_ic2", "Fig. 3: pendulum IC2, θ'(0) = 1 rad/s, Δt = 0.3 s, t_end = 10 s",
         "pendulum_ic2", 0.3, 10.0, "theta", "phase", "C2"),
    Case("fig03b_pendulum_ic2_2000s", "Pendulum IC2 over 2000 s, Δt = 0.3 s (section 6: Newmark 'snake-like' "
         "once θ passes π)", "pendulum_ic2", 0.3, 2000.0, "theta", "long", "C2, C8"),
    Case("fig04_hardening", "Fig. 4: hardening oscillator, x(0) = 1.5 m, Δt = 1e-3 s, t_end = 0.3 s",
         "hardening", 1e-3, 0.3, "x", "phase", "C3"),
    Case("fig06_building_floor1", "Fig. 6: building, floor 1, Δt = 7e-4 s", "building", 7e-4, 10.0, "x1",
         "history", "C5", half_step=False),
    Case("fig07_building_floor6", "Fig. 7: building, floor 6, Δt = 0.03 s = 0.3 Tmin", "building", 0.03, 10.0,
         "x6", "history", "C5", half_step=False),
    Case("fig09_vehicle_wheelset1", "Fig. 9: vehicle impact, wheelset 1, Δt = 1e-3 s", "vehicle", 1e-3, 1.0,
         "z_w1", "history", "C7", half_step=False),
    Case("fig10_pendulum_ic1_1800s", "Fig. 10: pendulum IC1, Δt = 0.3 s, t_end = 1800 s", "pendulum", 0.3,
         1800.0, "theta", "phase", "C8"),
    Case("fig11_pendulum_ic1_dt0.8", "Fig. 11: pendulum IC1, Δt = 0.8 s, t_end = 15 s", "pendulum", 0.8, 15.0,
         "theta", "phase", "C8"),
)

# CEMDTS's η study: the paper's steps, and Table 1's recommended largest step on the hardening oscillator
ETA_PROBLEMS = (
    ("hardening, Δt = 1e-3 s", "hardening", 1e-3, 0.3),
    ("hardening, Δt = Tmin/20", "hardening", HARDENING_TMIN / 20.0, 0.3),
    ("pendulum IC1, Δt = 0.3 s", "pendulum", 0.3, 15.0),
    ("pendulum IC2, Δt = 0.3 s", "pendulum_ic2", 0.3, 10.0),
)

RUN_FIELDS = ("case", "claim", "scene", "scheme", "dt", "t_end", "dof", "status", "max_error", "energy_error",
              "locus_error", "state_error", "max_abs_u", "t_over_the_top", "energy_end_over_start",
              "newton_iters_per_step", "max_residual", "force_evals", "wall_time", "reference")


# ---------------------------------------------------------------- measuring

def _is_pendulum(model) -> bool:
    return any(e.type == "pendulum_gravity" for e in model.effects)


class Orbit:
    """The exact phase locus of a one-DOF conservative model, sampled from its closed form over a period."""

    NEAR = 0.05

    def __init__(self, model):
        span = 1.0
        for _ in range(40):  # at least one period: the velocity has changed sign twice
            t = np.linspace(0.0, span, 4001)[1:]
            v = reference(model, span).v(t)[:, 0]
            s = np.sign(v[v != 0.0])
            if np.count_nonzero(np.diff(s)) >= 2:
                break
            span *= 2.0
        else:
            raise _checks.value_error("model", "no closed orbit found (the motion is not periodic)")
        u, v = reference(model, span)(np.linspace(0.0, span, ORBIT_SAMPLES))
        self.scale = np.array([np.max(np.abs(u)), np.max(np.abs(v))])
        from scipy.spatial import cKDTree

        self.u, self.v = u[::20, 0], v[::20, 0]  # for drawing
        points = np.column_stack((u[:, 0], v[:, 0])) / self.scale
        self.tree = cKDTree(points)
        self.coarse = cKDTree(points[::20])
        # a point's distance to the coarse samples exceeds its distance to the orbit by at most this
        self.coarse_resolution = 0.5 * float(np.max(np.hypot(*np.diff(points[::20], axis=0).T)))

    def distance(self, u: np.ndarray, v: np.ndarray) -> np.ndarray:
        """Distance of each (u, v) to the sampled orbit, in the scaled plane."""
        x = np.column_stack((u, v)) / self.scale
        # a k-d tree query is slow far from a dense curve: points beyond NEAR (a run gone over the top) keep
        # their coarse distance, within coarse_resolution of the true one
        d, _ = self.coarse.query(x)
        near = d < self.NEAR
        if np.any(near):
            d[near], _ = self.tree.query(x[near])
        return d


@dataclass
class Setting:
    """A model at one step and end time, with its reference (and exact orbit when there is one)."""
    model: object
    dt: float
    t_end: float
    dof: str
    ref: object
    orbit: Orbit | None = None
    col: int = 0
    conservative: bool = False


def setting(scene: str, dt: float, t_end: float, dof: str | None = None) -> Setting:
    model = load_scene(scene)
    dof = dof or model.scene["plot_dof"]
    # the last step may end past t_end (t_end/dt not whole): the reference covers the whole run
    span = _core.steps_to_reach(0.0, t_end, dt) * dt
    ref = reference(model, max(span, t_end))
    conservative = _conservative(model)
    orbit = Orbit(model) if conservative and model.n == 1 and ref.kind == "closed_form" else None
    return Setting(model, dt, t_end, dof, ref, orbit, model.dofs.index(dof), conservative)


def measure(s: Setting, scheme, *, repeats: int = 3, case: str = "", claim: str = "") -> tuple[dict, object]:
    """One row of RUN_FIELDS and the run itself (all DOFs saved, energy recorded)."""
    row = cost(s.model, [scheme], [s.dt], t_end=s.t_end, dofs=[s.dof], reference=s.ref, repeats=repeats,
               energy=False)[0]
    # energy recorded as a measurement: the figures show each run to its end, however far it goes astray
    res = solve(s.model, scheme, dt=s.dt, t_end=s.t_end, energy=True, max_energy_error=math.inf, throw=False)
    u, v = res.u[:, s.col], res.v[:, s.col]
    out = {k: math.nan for k in RUN_FIELDS}
    out.update(case=case, claim=claim, scene=s.model.scene["name"], scheme=scheme_label(scheme), dt=s.dt,
               t_end=s.t_end, dof=s.dof, status=res.status, max_error=row["max_error"], wall_time=row["wall_time"],
               force_evals=res.stats.num_force_evals, reference=s.ref.description, t_over_the_top="")
    with np.errstate(all="ignore"):
        if s.conservative:
            e = res.energy.total
            out["energy_error"] = float(np.max(np.abs(e - e[0])) / abs(e[0]))
            out["energy_end_over_start"] = float(e[-1] / e[0])
        else:
            out["energy_error"] = float(res.energy.relative_balance_error())
    if s.orbit is not None and res.status == "success":
        out["locus_error"] = float(np.max(s.orbit.distance(u, v)))
        ur, vr = s.ref(res.t)
        out["state_error"] = float(np.max(np.hypot((u - ur[:, s.col]) / s.orbit.scale[0],
                                                   (v - vr[:, s.col]) / s.orbit.scale[1])))
    out["max_abs_u"] = float(np.max(np.abs(u)))
    if _is_pendulum(s.model):
        over = np.flatnonzero(np.abs(u) > math.pi)
        out["t_over_the_top"] = float(res.t[over[0]]) if over.size else ""
    steps = res.stats.num_steps
    out["newton_iters_per_step"] = res.stats.num_newton_iters / steps if steps else 0.0
    out["max_residual"] = "" if res.max_residual is None else res.max_residual
    return out, res


# ---------------------------------------------------------------- figures

def _figure(width: float, height: float):
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width, height), layout="constrained")
    FigureCanvasAgg(fig)
    return fig


def _fmt(x) -> str:
    if x == "" or x is None or (isinstance(x, float) and math.isnan(x)):
        return "–"
    if isinstance(x, str):
        return x
    if isinstance(x, (int, np.integer)):
        return f"{int(x):,}"
    if math.isinf(x):
        return "inf"
    return f"{x:.3g}" if 1e-3 <= abs(x) < 1e4 or x == 0 else f"{x:.2e}"


def _axis_labels(s: Setting) -> tuple[str, str, float]:
    """Labels of the phase plane and the factor that scales the displacement axis."""
    if _is_pendulum(s.model):
        return "θ / π", "θ' [rad/s]", 1.0 / math.pi
    return f"{s.dof} [m]", f"{s.dof}' [m/s]", 1.0


def _grid(n: int, ncol: int = 4, width: float = 4.2, height: float = 3.6):
    nrow = math.ceil(n / ncol)
    fig = _figure(width * ncol, height * nrow + 0.7)
    return fig, [fig.add_subplot(nrow, ncol, k + 1) for k in range(n)]


def plot_phase(case: Case, s: Setting, rows: list[dict], runs: list, path: str) -> None:
    """One panel per scheme: the exact phase locus and the computed one, with the run's measures."""
    xlab, ylab, fx = _axis_labels(s)
    fig, axes = _grid(len(runs))
    for ax, row, res in zip(axes, rows, runs):
        ax.plot(s.orbit.u * fx, s.orbit.v, color="k", lw=3.0, alpha=0.25, label="exact")
        u, v = res.u[:, s.col], res.v[:, s.col]
        ax.plot(u * fx, v, color=_color(row["scheme"]), lw=0.9, marker="." if len(u) < 400 else None, ms=3)
        ax.plot([u[-1] * fx], [v[-1]], "s", color="k", ms=4)
        note = f"energy error {_fmt(row['energy_error'])}, locus error {_fmt(row['locus_error'])}"
        if row["t_over_the_top"] != "":
            note += f"\n|θ| > π at t = {row['t_over_the_top']:.4g} s; max |θ| = {row['max_abs_u'] / math.pi:.3g}π"
        ax.set_title(f"{row['scheme']}\n{note}", fontsize=8.5)
        ax.set_xlabel(xlab)
        ax.set_ylabel(ylab)
        ax.grid(True, alpha=0.3)
    fig.suptitle(f"{case.title}\nthick grey: exact phase locus ({s.ref.description}); black square: the state at "
                 f"the end", fontsize=11)
    fig.savefig(path, dpi=90)


def plot_history(case: Case, s: Setting, rows: list[dict], runs: list, path: str) -> None:
    """One panel per scheme (reference and computed displacement of one DOF), and |u - u_ref| of all on a log
    axis in the last panel."""
    fig, axes = _grid(len(runs) + 1, height=3.4)
    offset = float(s.model.u0[s.col])
    unit, factor = ("mm", 1e3) if s.model.scene["name"] == "vehicle" else ("m", 1.0)
    ylab = f"{s.dof}{' - static equilibrium' if offset != 0.0 else ''} [{unit}]"
    tt = np.linspace(0.0, s.t_end, 20001)
    u_ref = (s.ref.u(tt)[:, s.col] - offset) * factor
    peak = 0.0
    for ax, row, res in zip(axes, rows, runs):
        t, u = res.t, res.u[:, s.col]
        ax.plot(tt, u_ref, color="k", lw=2.5, alpha=0.3)
        ax.plot(t, (u - offset) * factor, color=_color(row["scheme"]), lw=0.8)
        ax.set_title(f"{row['scheme']}: error {_fmt(row['max_error'])}", fontsize=9)
        ax.set_xlabel("t [s]")
        ax.set_ylabel(ylab, fontsize=8)
        ax.grid(True, alpha=0.3)
        keep = t <= s.ref.t_end
        err = np.abs(u[keep] - s.ref.u(t[keep])[:, s.col]) * factor
        peak = max(peak, float(np.max(err)))
        axes[-1].semilogy(t[keep][1:], err[1:], color=_color(row["scheme"]), lw=0.7, label=row["scheme"])
    ax = axes[-1]
    ax.set_ylim(peak * 1e-7, peak * 3.0)
    ax.set_title("|u - reference|, colours as in the other panels", fontsize=9)
    ax.set_xlabel("t [s]")
    ax.set_ylabel(f"[{unit}]", fontsize=8)
    ax.grid(True, which="both", alpha=0.3)
    fig.suptitle(f"{case.title}\nthick grey: reference ({s.ref.description}); error: max |u - u_ref| / max |u_ref| "
                 f"over the run", fontsize=11)
    fig.savefig(path, dpi=90)


def plot_long(case: Case, s: Setting, rows: list[dict], runs: list, path: str) -> None:
    """Largest angle so far and the energy over a long run: where each scheme leaves the libration and how its
    energy drifts."""
    fig = _figure(12.0, 8.0)
    top, bottom = fig.subplots(2, 1, sharex=True)
    for k, (row, res) in enumerate(zip(rows, runs)):
        style = ("-", "--", "-.", ":")[k % 4]
        cross = "" if row["t_over_the_top"] == "" else f": |θ| > π at t = {row['t_over_the_top']:.4g} s"
        color = _color(row["scheme"])
        top.plot(res.t, np.maximum.accumulate(np.abs(res.u[:, s.col])) / math.pi, style, color=color, lw=1.2,
                 label=row["scheme"] + cross)
        e = res.energy.total
        bottom.plot(res.t, e / e[0], style, color=color, lw=0.8)
    top.axhline(1.0, color="k", lw=0.8)
    top.text(0.0, 1.0, " |θ| = π: over the top", fontsize=8, va="bottom")
    top.set_yscale("log")
    top.set_ylabel("largest |θ| so far / π")
    top.legend(fontsize=8, loc="upper left")
    top.grid(True, which="both", alpha=0.3)
    bottom.set_yscale("log")
    bottom.set_ylabel("E(t) / E(0)")
    bottom.set_xlabel("t [s]")
    bottom.grid(True, which="both", alpha=0.3)
    fig.suptitle(f"{case.title}\nexact: largest |θ| = π/3 and E(t) = E(0)", fontsize=11)
    fig.savefig(path, dpi=90)


# ---------------------------------------------------------------- the parts

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


def table1(*, dts=TABLE1_DTS, repeats: int = 3) -> list[dict]:
    """Table 1: the maximum relative energy error of each scheme on the hardening oscillator for several Δt."""
    rows = []
    for dt in dts:
        s = setting("hardening", dt, 0.3)
        for scheme in paper_schemes():
            row, _ = measure(s, scheme, repeats=repeats, case="table1", claim="C4")
            row["dt_over_tmin"] = dt / HARDENING_TMIN
            rows.append(row)
    return rows


def cpu_time(*, repeats: int = 5) -> list[dict]:
    """The paper's CPU-time comparison: the building at Δt = 1e-4 s (t_end 10 s), wall time of each scheme."""
    model = load_scene("building")
    schemes = paper_schemes(half_step=False)
    rows = cost(model, schemes, [CPU_DT], t_end=CPU_T_END, dofs=["x6"], repeats=repeats)
    base = next(r["wall_time"] for r in rows if r["label"].startswith("CEMDTS"))
    for r in rows:
        family = r["label"].split("(")[0].split(" ")[0]
        r["paper_2017_s"] = CPU_2017.get(family, math.nan)
        r["over_cemdts"] = r["wall_time"] / base
        r["paper_over_cemdts"] = r["paper_2017_s"] / CPU_2017["CEMDTS"]
    return rows


def eta_study(*, etas=ETA_GRID, problems=ETA_PROBLEMS) -> list[dict]:
    """CEMDTS against η (and LCDM with both velocities) on the conservative problems: energy, locus and
    state errors at the given steps."""
    rows = []
    for name, scene, dt, t_end in problems:
        s = setting(scene, dt, t_end)
        variants = [(eta, CEMDTS(eta)) for eta in etas]
        variants += [("LCDM", CentralDifference()), ("LCDM (half-step v)", CentralDifference(velocity="half_step"))]
        for eta, scheme in variants:
            row, _ = measure(s, scheme, repeats=1, case="eta_study")
            row.update(problem=name, eta=eta if not isinstance(eta, str) else "", variant=row["scheme"])
            rows.append(row)
    return rows


def recommend_eta(rows: list[dict]) -> tuple[float, dict]:
    """The η whose worst energy error relative to the best η of each problem is smallest (minimax regret),
    and that worst ratio for every η."""
    problems = sorted({r["problem"] for r in rows})
    cem = [r for r in rows if r["eta"] != ""]
    best = {p: min(r["energy_error"] for r in cem if r["problem"] == p) for p in problems}
    worst = {}
    for r in cem:
        ratio = r["energy_error"] / best[r["problem"]]
        worst[r["eta"]] = max(worst.get(r["eta"], 0.0), ratio)
    eta = min(worst, key=lambda e: (worst[e], e))
    return eta, worst


def plot_eta(rows: list[dict], path: str) -> None:
    problems = list(dict.fromkeys(r["problem"] for r in rows))
    fig = _figure(15.0, 5.2)
    axes = fig.subplots(1, 3)
    measures = (("energy_error", "max relative energy error"), ("locus_error", "phase-locus error"),
                ("state_error", "state error (timing included)"))
    for ax, (key, name) in zip(axes, measures):
        for k, p in enumerate(problems):
            pr = [r for r in rows if r["problem"] == p]
            cem = sorted((r for r in pr if r["eta"] != ""), key=lambda r: r["eta"])
            ax.semilogy([r["eta"] for r in cem], [r[key] for r in cem], "o-", color=f"C{k}", ms=3, lw=1.2,
                        label=p)
            half = next(r for r in pr if r["variant"] == "LCDM (half-step v)")
            ax.axhline(half[key], color=f"C{k}", ls=":", lw=1.2)
        for eta, lab in ((1.0 / 12.0, "1/12"), (PAPER_ETA, "0.45 (paper)")):
            ax.axvline(eta, color="0.4", lw=0.8, ls="--")
            ax.text(eta, 1.0, f" η = {lab}", transform=ax.get_xaxis_transform(), fontsize=8, va="top")
        ax.set_xlabel("η")
        ax.set_title(name, fontsize=10)
        ax.grid(True, which="both", alpha=0.3)
    axes[0].legend(fontsize=8, loc="lower right")
    fig.suptitle("CEMDTS against η (η = 0 is LCDM with synchronized velocity; dotted: LCDM with half-step "
                 "velocity); references: closed forms", fontsize=11)
    fig.savefig(path, dpi=90)


def plot_table1(rows: list[dict], path: str) -> None:
    fig = _figure(9.0, 6.0)
    ax = fig.add_subplot()
    labels = list(dict.fromkeys(r["scheme"] for r in rows))
    for k, lab in enumerate(labels):
        rr = sorted((r for r in rows if r["scheme"] == lab), key=lambda r: r["dt"])
        ax.loglog([r["dt_over_tmin"] for r in rr], [r["energy_error"] for r in rr], ("o-", "s--", "^-.", "v:")[k % 4],
                  color=_color(lab), lw=1.2, ms=4, label=lab)
    ax.axvline(1.0 / 20.0, color="0.4", lw=0.8, ls="--")
    ax.text(1.0 / 20.0, 1.0, " Δt = Tmin/20", transform=ax.get_xaxis_transform(), fontsize=8, va="top")
    ax.set_xlabel("Δt / Tmin  (Tmin = 2π / 82.76 rad/s = 75.9 ms)")
    ax.set_ylabel("max relative energy error over 0.3 s")
    ax.set_title("Table 1: hardening oscillator, maximum relative energy error against the step")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.savefig(path, dpi=100)


def building_facts() -> dict:
    """What section 5.1 states about the building, measured: linearised frequencies at rest, Tmin, the largest
    inter-storey drift of the reference over 10 s and the largest secant stiffness ratio 1 + a d^2 it gives."""
    model = load_scene("building")
    w = model.linearized_frequencies(model.u0)
    t = np.linspace(0.0, 10.0, 200_001)
    u = reference(model, 10.0).u(t)
    drift = np.abs(np.diff(np.column_stack((np.zeros(len(t)), u)), axis=1))
    d = float(np.max(drift))
    storey = int(np.argmax(np.max(drift, axis=0)))
    spring = [e for e in model.effects if e.type == "hardening_spring"][storey]
    # secant stiffness at the largest drift over the stiffness at rest: the paper's degree of nonlinearity
    ratio = (spring.value(d, 0.0, 0.0) / d) / (spring.value(1e-9, 0.0, 0.0) / 1e-9)
    return {"omega_min": float(np.min(w)), "omega_max": float(np.max(w)), "tmin": 2 * math.pi / float(np.max(w)),
            "max_drift": d, "storey": storey + 1, "nonlinearity": ratio}


# ---------------------------------------------------------------- output

def _write_csv(path: str, rows: list[dict], fields) -> None:
    with open(path, "w", newline="") as fh:
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
    head = ["scheme", "status", "max error", "energy error", "locus error", "state error", "max abs u",
            "over the top [s]", "E end / E0", "Newton it./step", "max residual", "wall [ms]"]
    body = [[r["scheme"], r["status"], _fmt(r["max_error"]), _fmt(r["energy_error"]), _fmt(r["locus_error"]),
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
    with open(path, "w") as fh:
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
