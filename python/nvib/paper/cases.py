"""The cases of Yang et al. (2017) and their measurements: the paper's schemes,
one Case per figure, the measures of one run (``measure``), Table 1, the
CPU-time table and CEMDTS's eta study."""

from __future__ import annotations

import math
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
CPU_DT, CPU_T_END = 1e-4, 10.0  # the paper's end time is not stated (section 5.1); 10 s assumed
CPU_2017 = {"CEMDTS": 1.89, "Newmark": 2.01, "GαM": 2.23, "PIM": 11.12}  # seconds, 2017 hardware
PAPER_ETA = 0.45
ETA_GRID = tuple(sorted(set(np.round(np.linspace(0.0, 0.5, 21), 6).tolist()) | {1.0 / 12.0, PAPER_ETA}))
ORBIT_SAMPLES = 400_000  # points on the exact orbit: spacing ~1e-5 of its extent, far below the errors measured



NON_ITERATED = ("incremental", "one_iteration")
"""The two ways of not iterating an implicit step: "incremental" is the textbook incremental format the paper
applies to Newmark and GαM (Chopra section 5.7: the tangent at the start of the step, force and acceleration
carried in increments, what is left unbalanced never corrected); "one_iteration" is one Newton iteration on
the full residual, accepted as it is."""


def paper_schemes(half_step: bool = True) -> list:
    """The paper's five schemes: LCDM in both velocity variants, CEMDTS, PIM, and Newmark and GαM each in
    the paper's incremental format, with one Newton iteration per step and with full Newton iteration."""
    out = [CentralDifference()]
    if half_step:
        out.append(CentralDifference(velocity="half_step"))
    out.append(CEMDTS(PAPER_ETA))
    for mode in (*NON_ITERATED, "newton"):
        out.append(Newmark(0.25, 0.5, iteration=mode))
    for mode in (*NON_ITERATED, "newton"):
        out.append(GeneralizedAlpha(0.5, 0.5, 0.25, 0.5, iteration=mode))
    out.append(PreciseIntegration(squarings=20, interpolation=2, corrections=1))
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

RUN_FIELDS = ("case", "claim", "scene", "scheme", "dt", "t_end", "dof", "status", "max_error", "error_estimate",
              "energy_error",
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
               t_end=s.t_end, dof=s.dof, status=res.status.name, max_error=row["max_error"], wall_time=row["wall_time"],
               force_evals=res.stats.num_force_evals, reference=s.ref.description, t_over_the_top="")
    with np.errstate(all="ignore"):
        if s.conservative:
            e = res.energy.total
            out["energy_error"] = float(np.max(np.abs(e - e[0])) / abs(e[0]))
            out["energy_end_over_start"] = float(e[-1] / e[0])
        else:
            out["energy_error"] = float(res.energy.relative_balance_error())
    if s.orbit is not None and res.success:
        out["locus_error"] = float(np.max(s.orbit.distance(u, v)))
        ur, vr = s.ref(res.t)
        out["state_error"] = float(np.max(np.hypot((u - ur[:, s.col]) / s.orbit.scale[0],
                                                   (v - vr[:, s.col]) / s.orbit.scale[1])))
    est = res.error_estimate  # the run's own estimate (all DOFs), beside the measured error
    out["error_estimate"] = est.max if est is not None else math.nan
    out["max_abs_u"] = float(np.max(np.abs(u)))
    if _is_pendulum(s.model):
        over = np.flatnonzero(np.abs(u) > math.pi)
        out["t_over_the_top"] = float(res.t[over[0]]) if over.size else ""
    steps = res.stats.num_steps
    out["newton_iters_per_step"] = res.stats.num_newton_iters / steps if steps else 0.0
    out["max_residual"] = "" if res.max_residual is None else res.max_residual
    return out, res


# ---------------------------------------------------------------- figures

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

