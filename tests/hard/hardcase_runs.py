"""The hard cases: how each is run and what is measured. Shared by the test
table (tests/hard/test_hard_cases.py) and the script that prints the
measurements (benchmarks/hard_cases.py), so the expected outcomes in the
table and the reported numbers come from the same runs.

Energies (closed forms, per unit of the conserved quantity):
  pendulum   e = v^2/2 + (g/l)(1 - cos u)            (g/l = 1 rad^2/s^2)
  hardening  e = m v^2/2 + k0 (u^2/2 + a u^4/4)      (nvib.exact.hardening_energy)
  building, vehicle: nvib's energy accounting, relative balance error
  (kinetic + potential + dissipated - work of the loads, over the largest term).
References for the displacement error:
  building   CentralDifference at dt = 1e-5 s (10^6 steps), which agrees with
             CEMDTS at 2e-5 s to 2e-8 relative on every floor;
  vehicle    CentralDifference at dt = 1e-6 s (10^6 steps), which agrees with
             CEMDTS at 5e-7 s to 7e-7 relative on the wheelsets.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
import sys
import time

import numpy as np

import nvib

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

# The paper's settings (Yang et al. 2017, section 4): Newmark beta = 1/4, gamma = 1/2; GaM
# alpha_m = alpha_f = 1/2, beta = 1/4, gamma = 1/2; CEMDTS eta = 0.45; PIM predictor-corrector.
# "one_iteration": one Newton iteration on the full residual per step, accepted (not the paper's
# incremental format, iteration="incremental", which nvib paper runs);
# "newton": full Newton-Raphson; "modified": one tangent per step.
SCHEMES = {
    "LCDM": lambda: nvib.CentralDifference(),
    "CEMDTS": lambda: nvib.CEMDTS(0.45),
    "Zhai": lambda: nvib.Zhai(0.5, 0.5),
    "Newmark-one_iteration": lambda: nvib.Newmark(0.25, 0.5, iteration="one_iteration"),
    "Newmark-newton": lambda: nvib.Newmark(0.25, 0.5, iteration="newton"),
    "GaM-one_iteration": lambda: nvib.GeneralizedAlpha(0.5, 0.5, 0.25, 0.5, iteration="one_iteration"),
    "GaM-newton": lambda: nvib.GeneralizedAlpha(0.5, 0.5, 0.25, 0.5, iteration="newton"),
    "PIM": lambda: nvib.PreciseIntegration(squarings=20, interpolation=2, corrections=1),
    # modified Newton: one tangent per step (Newton's defaults otherwise)
    "Newmark-modified": lambda: nvib.Newmark(0.25, 0.5, iteration="modified"),
    "GaM-modified": lambda: nvib.GeneralizedAlpha(0.5, 0.5, 0.25, 0.5, iteration="modified"),
}

HARDENING = dict(m=1.0, k0=100.0, a=30.0, x0=1.5)
# Largest tangent frequency of the hardening oscillator, at the turning point x0:
# sqrt(k0 (1 + 3 a x0^2) / m) = 142.65 rad/s.
OMEGA_TANGENT_MAX = math.sqrt(HARDENING["k0"] * (1.0 + 3.0 * HARDENING["a"] * HARDENING["x0"] ** 2) / HARDENING["m"])


@functools.lru_cache(maxsize=None)
def scene(name: str):
    return nvib.load_scene(name)


def _base(res, run: dict) -> dict:
    steps = res.stats.num_steps
    out = {
        "status": res.status.name,
        "t_end_reached": float(res.t[-1]),
        "steps": steps,
        "newton_iters_per_step": res.stats.num_newton_iters / steps if steps else 0.0,
        "max_residual": res.max_residual,
        "wall_time": run["wall"],
    }
    if res.status != nvib.Status.success:
        out["fail_t"] = res.failure.t
        out["fail_step"] = res.failure.step
        out["fail_dof"] = res.failure.dof
        out["raised"] = run["raised"]
    return out


def _solve(model, scheme_key: str, **kw):
    """The run with throw=False, and {"wall": its wall time, "raised": what the same run with
    throw=True raised (None if it succeeded)}."""
    start = time.perf_counter()
    res = nvib.solve(model, SCHEMES[scheme_key](), throw=False, **kw)
    run = {"wall": time.perf_counter() - start, "raised": None}
    if res.status != nvib.Status.success:  # the same run with throw=True: what the caller gets
        try:
            nvib.solve(model, SCHEMES[scheme_key](), **kw)
        except nvib.NvibError as exc:
            run["raised"] = {"type": type(exc).__name__, "t": exc.t, "step": exc.step, "dof": exc.dof,
                             "residuals": len(exc.residuals), "message": str(exc)}
    return res, run


def pendulum(scheme_key: str, dt: float, t_end: float) -> dict:
    """Pendulum IC1 (theta0 = -0.95 pi, at rest): libration or over the top, energy error."""
    res, run = _solve(scene("pendulum"), scheme_key, dt=dt, t_end=t_end)
    out = _base(res, run)
    th, om = res.u[:, 0], res.v[:, 0]
    e = 0.5 * om ** 2 + (1.0 - np.cos(th))
    out["max_rel_energy_error"] = float(np.max(np.abs(e - e[0])) / e[0])
    out["energy_end_over_start"] = float(e[-1] / e[0])
    out["max_abs_theta_over_pi"] = float(np.max(np.abs(th)) / math.pi)
    over = np.nonzero(np.abs(th) > math.pi)[0]
    out["t_over_the_top"] = float(res.t[over[0]]) if len(over) else None
    return out


def hardening(scheme_key: str, omega_dt: float, t_end: float = 100.0) -> dict:
    """Hardening oscillator at dt = omega_dt / omega_tangent_max."""
    dt = omega_dt / OMEGA_TANGENT_MAX
    res, run = _solve(scene("hardening"), scheme_key, dt=dt, t_end=t_end)
    out = _base(res, run)
    p = {k: HARDENING[k] for k in ("m", "k0", "a")}
    e = nvib.exact.hardening_energy(res.u[:, 0], res.v[:, 0], **p)
    out["dt"] = dt
    out["max_rel_energy_error"] = float(np.max(np.abs(e - e[0])) / e[0])
    out["energy_end_over_start"] = float(e[-1] / e[0])
    out["max_abs_u"] = float(np.max(np.abs(res.u)))
    return out


def long_run(scheme_key: str, nsteps: int = 10**6, dt: float = 1e-3) -> dict:
    """10^6 steps of the hardening oscillator (undamped, C++-only model), every state saved."""
    res, run = _solve(scene("hardening"), scheme_key, dt=dt, t_end=nsteps * dt)
    out = _base(res, run)
    e = nvib.exact.hardening_energy(res.u[:, 0], res.v[:, 0], **{k: HARDENING[k] for k in ("m", "k0", "a")})
    err = np.abs(e - e[0]) / e[0]
    out["max_rel_energy_error"] = float(np.max(err))
    out["max_rel_energy_error_first_1e4_steps"] = float(np.max(err[:10001]))
    out["max_rel_energy_error_last_1e4_steps"] = float(np.max(err[-10000:]))
    out["energy_end_over_start"] = float(e[-1] / e[0])
    return out


@functools.lru_cache(maxsize=None)
def building_reference():
    ref = nvib.solve(scene("building"), nvib.CentralDifference(), dt=1e-5, t_end=10.02, save_every=3000)
    return ref.t, ref.u


def building(scheme_key: str, dt: float = 0.03, t_end: float = 10.0) -> dict:
    """Six-storey building at dt = 0.03 s = 0.3 Tmin: error of the top floor against the reference."""
    res, run = _solve(scene("building"), scheme_key, dt=dt, t_end=t_end, energy=True)
    out = _base(res, run)
    t_ref, u_ref = building_reference()
    x6 = np.interp(res.t, t_ref, u_ref[:, 5])
    out["top_floor_error"] = float(np.max(np.abs(res.u[:, 5] - x6)) / np.max(np.abs(u_ref[:, 5])))
    drifts = np.diff(np.concatenate([np.zeros((len(res.t), 1)), res.u], axis=1), axis=1)
    out["max_drift"] = float(np.max(np.abs(drifts)))
    out["energy_balance_error"] = res.energy.relative_balance_error()
    return out


WHEELS = [6, 7, 8, 9]  # z_w1 .. z_w4; contact compression = z_w (rigid smooth rail)


@functools.lru_cache(maxsize=None)
def vehicle_reference():
    ref = nvib.solve(scene("vehicle"), nvib.CentralDifference(), dt=1e-6, t_end=1.0, save_every=1000)
    return ref.t, ref.u


@functools.lru_cache(maxsize=None)
def vehicle_without_contact():
    """The vehicle's effects without the wheel-rail contacts, as a model of its own (the scene
    itself cannot leave them out: without a support it has no static equilibrium)."""
    with open(scene("vehicle").scene["path"], "rb") as fh:
        data = tomllib.load(fh)
    effects = [e for e in data["effect"] if e["type"] != "hertz_contact"]
    return nvib.Model(data["dofs"]["mass"], effects=effects, dofs=data["dofs"]["names"])


def vehicle(scheme_key: str, dt: float = 1e-3, t_end: float = 1.0) -> dict:
    """Railway vehicle impact: wheels leave the rail; the contact force must then be exactly 0."""
    model = scene("vehicle")
    res, run = _solve(model, scheme_key, dt=dt, t_end=t_end, energy=True)
    out = _base(res, run)
    t_ref, u_ref = vehicle_reference()
    w1 = np.interp(res.t, t_ref, u_ref[:, 6])
    out["wheelset1_error"] = float(np.max(np.abs(res.u[:, 6] - w1)) / np.max(np.abs(u_ref[:, 6])))
    body = np.interp(res.t, t_ref, u_ref[:, 0])
    out["carbody_error"] = float(np.max(np.abs(res.u[:, 0] - body)) / np.max(np.abs(u_ref[:, 0] - u_ref[0, 0])))
    off = res.u[:, WHEELS] < 0.0
    out["states_with_a_wheel_off"] = int(np.count_nonzero(off.any(axis=1)))
    out["max_abs_carbody_z"] = float(np.max(np.abs(res.u[:, 0])))
    # With every contact open, the model's force equals that of the model
    # without contacts, bit for bit: an open contact contributes exactly 0.
    free = vehicle_without_contact()
    contacts = {e.index[0]: e for e in model._core.effects if e.type == "hertz_contact"}
    mismatches = 0
    for i in np.nonzero(off.any(axis=1))[0]:
        f = model.evaluate_force(res.u[i], res.v[i], res.t[i])
        g = free.evaluate_force(res.u[i], res.v[i], res.t[i])
        for j, w in enumerate(WHEELS):
            if off[i, j] and (f[w] != g[w] or contacts[w].value(res.u[i, w], res.v[i, w], res.t[i]) != 0.0):
                mismatches += 1
    out["open_contact_force_mismatches"] = mismatches
    out["energy_balance_error"] = res.energy.relative_balance_error()
    return out


# case name -> (function of the scheme key, description)
CASES = {
    "pendulum dt=0.3 15s": (lambda s: pendulum(s, 0.3, 15.0), "pendulum IC1, dt = 0.3 s, t_end = 15 s (C1)"),
    "pendulum dt=0.3 1800s": (lambda s: pendulum(s, 0.3, 1800.0), "pendulum IC1, dt = 0.3 s, t_end = 1800 s (C8)"),
    "pendulum dt=0.8 15s": (lambda s: pendulum(s, 0.8, 15.0), "pendulum IC1, dt = 0.8 s, t_end = 15 s (C8)"),
    "pendulum dt=0.8 18000s": (lambda s: pendulum(s, 0.8, 18000.0),
                               "pendulum IC1, dt = 0.8 s, t_end = 18000 s (22500 steps)"),
    "hardening Omega=1.5": (lambda s: hardening(s, 1.5), "hardening, omega_t,max dt = 1.5, t_end = 100 s"),
    "hardening Omega=1.9": (lambda s: hardening(s, 1.9), "hardening, omega_t,max dt = 1.9, t_end = 100 s"),
    "hardening Omega=2.2": (lambda s: hardening(s, 2.2), "hardening, omega_t,max dt = 2.2, t_end = 100 s"),
    "building dt=0.03": (lambda s: building(s), "building, dt = 0.03 s = 0.3 Tmin, t_end = 10 s (C5)"),
    "vehicle dt=1e-3": (lambda s: vehicle(s), "vehicle impact, dt = 1e-3 s, t_end = 1 s (C7)"),
    "vehicle dt=2e-3": (lambda s: vehicle(s, dt=2e-3),
                        "vehicle impact, dt = 2e-3 s (omega_max dt = 2.04), t_end = 1 s"),
    "1e6 steps": (lambda s: long_run(s), "hardening, dt = 1e-3 s, 10^6 steps (t_end = 1000 s)"),
}


@functools.lru_cache(maxsize=None)
def measure(case: str, scheme_key: str) -> dict:
    """The measurements of one (case, scheme) run (cached: the table and the script share them)."""
    return CASES[case][0](scheme_key)


# --------------------------------------------------------------------------- expected outcomes
# Each row of the table has an expected outcome (qualitative: stable or not, over the top or not,
# dissipative or not; from theory, from the paper, or observed) and regression pins (numbers set
# after measuring, each with the value measured when it was set and a margin of at most 2x).

# An error against the reference below 20 % of the signal counts as accurate; above it, as inaccurate.
ACCURATE = 0.2

THEORY, PAPER, OBSERVED = "theory", "paper", "observed"  # where an expected outcome comes from


@dataclass(frozen=True)
class Pin:
    """A regression pin: the measurement `key` stays below `bound` (upper=True) or above it, where
    `bound` was set from the value `measured` with a margin of at most 2x (checked on creation)."""
    key: str
    bound: float
    measured: float
    upper: bool = True

    def __post_init__(self):
        margin = self.bound / self.measured if self.upper else self.measured / self.bound
        if not 1.0 < margin <= 2.0:
            raise ValueError(f"pin {self}: margin {margin:.3g} over the measured value, expected in (1, 2]")

    def check(self, m: dict) -> list:
        x = m.get(self.key)
        if x is None:
            return [f"pin {self}: not measured"]
        ok = x < self.bound if self.upper else x > self.bound
        return [] if ok else [f"pin {self}: now {x:.4g}"]

    def __str__(self):
        return f"{self.key} {'<' if self.upper else '>'} {self.bound:g} (measured {self.measured:.4g})"


def below(key: str, bound: float, measured: float) -> Pin:
    return Pin(key, bound, measured, upper=True)


def above(key: str, bound: float, measured: float) -> Pin:
    return Pin(key, bound, measured, upper=False)


class Outcome:
    """An expected outcome: check(m) lists what does not hold for the measurements m."""

    def check(self, m: dict) -> list:
        raise NotImplementedError


def _success(m: dict) -> list:
    return [] if m["status"] == "success" else [f"status {m['status']} at t = {m.get('fail_t')}"]


@dataclass(frozen=True)
class Librates(Outcome):
    """Pendulum: the run succeeds and |theta| never passes pi."""

    def check(self, m):
        bad = _success(m)
        if m["t_over_the_top"] is not None:
            bad.append(f"went over the top at t = {m['t_over_the_top']}")
        return bad

    def __str__(self):
        return "stable, libration kept (θ within ±π) for the whole run"


@dataclass(frozen=True)
class OverTheTop(Outcome):
    """Pendulum: no DivergenceError, but the locus leaves the libration (snake-like) within the run."""

    def check(self, m):
        bad = _success(m)
        if m["t_over_the_top"] is None:
            bad.append("never went over the top")
        return bad

    def __str__(self):
        return "goes over the top (θ beyond ±π: snake-like locus) within the run; no DivergenceError"


@dataclass(frozen=True)
class Diverges(Outcome):
    """DivergenceError (status 'diverged'). by="state": the state left the displacement bound or
    became non-finite, and the error names the DOF; by="energy": the energy check stopped it (the
    energy balance error passed max_energy_error, 0.5 by default with energy=True) while the state
    stayed finite and bounded."""
    by: str = "state"

    def check(self, m):
        if m["status"] != "diverged":
            return [f"status {m['status']}, expected diverged"]
        bad = []
        r = m["raised"]
        if self.by == "energy":
            named = r and "energy balance error" in r["message"] and "max_energy_error" in r["message"]
        else:
            named = r and r["dof"] is not None and r["dof"] >= 0
        if not (named and r["type"] == "DivergenceError" and r["t"] == m["fail_t"] and r["step"] == m["fail_step"]):
            bad.append(f"throw=True raised {r}")
        return bad

    def __str__(self):
        return f"DivergenceError{' from the energy check' if self.by == 'energy' else ''}"


@dataclass(frozen=True)
class NewtonFails(Outcome):
    """ConvergenceError (status 'newton_failed') with the residual history."""

    def check(self, m):
        if m["status"] != "newton_failed":
            return [f"status {m['status']}, expected newton_failed"]
        r = m["raised"]
        if not (r and r["type"] == "ConvergenceError" and r["step"] == m["fail_step"] and r["residuals"] > 1):
            return [f"throw=True raised {r}"]
        return []

    def __str__(self):
        return "ConvergenceError"


@dataclass(frozen=True)
class Bounded(Outcome):
    """Stable: the run succeeds; optionally |u| below `amplitude` and no drift of the energy error
    (the last 10^4 steps' largest error at most 1 % above the first 10^4 steps')."""
    amplitude: float = math.inf
    no_drift: bool = False

    def check(self, m):
        bad = _success(m)
        if "max_abs_u" in m and not m["max_abs_u"] < self.amplitude:
            bad.append(f"amplitude {m['max_abs_u']:.3g} >= {self.amplitude}")
        if self.no_drift and not (m["max_rel_energy_error_last_1e4_steps"]
                                  <= 1.01 * m["max_rel_energy_error_first_1e4_steps"]):
            bad.append("the energy error drifts")
        return bad

    def __str__(self):
        s = "stable"
        if self.amplitude < math.inf:
            s += f", amplitude < {self.amplitude:g}"
        return s + (", no drift of the energy error (last 10^4 steps vs first)" if self.no_drift else "")


@dataclass(frozen=True)
class Decays(Outcome):
    """Runs to the end, but numerical dissipation drains energy: E(t_end) < E0."""

    def check(self, m):
        bad = _success(m)
        if not m["energy_end_over_start"] < 1.0:
            bad.append(f"E_end/E0 = {m['energy_end_over_start']:.3g} >= 1")
        return bad

    def __str__(self):
        return "stable but dissipative: E(t_end) < E0"


@dataclass(frozen=True)
class Grows(Outcome):
    """No DivergenceError within the run, but the energy grows: E(t_end) > E0."""

    def check(self, m):
        bad = _success(m)
        if not m["energy_end_over_start"] > 1.0:
            bad.append(f"E_end/E0 = {m['energy_end_over_start']:.3g} <= 1")
        return bad

    def __str__(self):
        return "no DivergenceError, but E(t_end) > E0 (energy instability)"


@dataclass(frozen=True)
class Accurate(Outcome):
    """Stable, and the error against the reference (`key`, relative to the signal) below ACCURATE."""
    key: str

    def check(self, m):
        bad = _success(m)
        if not m[self.key] < ACCURATE:
            bad.append(f"{self.key} = {m[self.key]:.3g} >= {ACCURATE}: not accurate")
        return bad

    def __str__(self):
        return f"stable and accurate: {self.key.replace('_', ' ')} < {ACCURATE:g}"


@dataclass(frozen=True)
class Inaccurate(Outcome):
    """Stable, but not accurate: the error against the reference (`key`) above ACCURATE."""
    key: str

    def check(self, m):
        bad = _success(m)
        if not m[self.key] > ACCURATE:
            bad.append(f"{self.key} = {m[self.key]:.3g} <= {ACCURATE}: accurate, expected inaccurate")
        return bad

    def __str__(self):
        return f"stable but inaccurate: {self.key.replace('_', ' ')} > {ACCURATE:g}"
