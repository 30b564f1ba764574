"""Shared by the tests of the laws with memory (test_hysteresis*.py): every scheme and variant, every
law that is not a load with parameters that make it act on a small chain under a ground motion, and
the closed forms and references the tests compare against."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import nvib

from _compiled_laws import BILINEAR, HARDENING, address

# Every scheme and the variants that take other paths through the commit: the synchronized and the
# half-step central difference, the two explicit two-step methods, Newmark with every Newton mode,
# generalized-alpha at its default (the implicit midpoint rule, alpha_f = 1/2: the commit is a new
# trial at the end of the step) and HHT, and the precise integration method.
NEWTON_MODES = ("newton", "modified", "initial", "incremental", "one_iteration")
SCHEMES = [
    ("CentralDifference", nvib.CentralDifference()),
    ("CentralDifference-half_step", nvib.CentralDifference(velocity="half_step")),
    ("CEMDTS", nvib.CEMDTS()),
    ("Zhai", nvib.Zhai()),
    *[(f"Newmark-{mode}", nvib.Newmark(iteration=mode)) for mode in NEWTON_MODES],
    ("GeneralizedAlpha", nvib.GeneralizedAlpha()),
    ("HHT", nvib.GeneralizedAlpha.hht(-0.1)),
    ("PreciseIntegration", nvib.PreciseIntegration()),
]
SCHEME_IDS = [name for name, _ in SCHEMES]
# The Newton modes that linearise each step about its start (incremental) or accept one iteration
# from it (one_iteration): their accuracy rests on the tangent at the committed state.
START_TANGENT = ("Newmark-incremental", "Newmark-one_iteration")


def scheme(name: str):
    return dict(SCHEMES)[name]


def laws_with_memory() -> set[str]:
    return {t for t, law in nvib._core.laws().items() if law["state"]}


def loads() -> set[str]:
    return {t for t, law in nvib._core.laws().items() if law["is_load"]}


# Each law that is not a load, with parameters under which it does what makes it nonlinear on the
# chain below (yields, slips, deteriorates past its capping point, closes, engages), and a test on its
# recorded history that it did. Variants of a law are "<type>-<variant>".
LAW_CASES = {
    "spring": ({"k": 200.0}, lambda r: np.ptp(r.force) > 1.0),
    "damper": ({"c": 2.0}, lambda r: np.ptp(r.force) > 0.1),
    "hardening_spring": ({"k0": 200.0, "a": 300.0}, lambda r: np.max(300.0 * r.measure**2) > 0.1),
    "cubic_spring": ({"k3": 5e4}, lambda r: np.ptp(r.force) > 0.1),
    "power_damper": ({"c": 2.0, "p": 1.5}, lambda r: np.ptp(r.force) > 0.1),
    "pendulum_gravity": ({"m": 1.0, "g": 9.81, "l": 0.5}, lambda r: np.ptp(r.force) > 0.1),
    "hertz_contact": ({"G": 1e-3}, lambda r: np.any(r.force == 0.0) and np.any(r.force > 0.1)),
    "gap": ({"k": 500.0, "gap": 0.005}, lambda r: np.any(r.force == 0.0) and np.any(r.force < -0.1)),
    "hook": ({"k": 500.0, "slack": 0.005}, lambda r: np.any(r.force == 0.0) and np.any(r.force > 0.1)),
    "p_delta": ({"P": 50.0, "h": 1.0}, lambda r: np.ptp(r.force) > 0.1),
    "bilinear": ({"k": 300.0, "fy": 3.0, "b": 0.05}, lambda r: np.ptp(r.state["plastic_deformation"]) > 0.02),
    "bouc_wen": ({"k": 300.0, "fy": 3.0, "alpha": 0.05, "n": 2.0}, lambda r: np.abs(r.state["z"]).max() > 0.99),
    "bouc_wen-backward_euler": ({"k": 300.0, "fy": 3.0, "alpha": 0.05, "n": 2.0, "integration": "backward_euler"},
                                lambda r: np.abs(r.state["z"]).max() > 0.99),
    "friction": ({"k": 300.0, "fs": 3.0}, lambda r: np.ptp(r.state["slip"]) > 0.02),
    "friction-mu_N": ({"k": 300.0, "mu": 0.25, "N": 12.0}, lambda r: np.ptp(r.state["slip"]) > 0.02),
    # deteriorating in every mode; past its capping point on both sides, never failing in 3 s
    "imk_peak_oriented": ({"k": 300.0, "fy": 3.0, "up": 0.02, "upc": 0.1, "uu": 1.0, "fcap_fy": 1.2,
                           "fres_fy": 0.3, "lambda_s": 5.0, "lambda_c": 5.0, "lambda_a": 5.0, "lambda_k": 5.0},
                          lambda r: {6.0, 16.0} <= set(r.state["branch"]) and not r.state["failed"].any()),
    # compiled laws (through ctypes pointers): the hardening spring's and the bilinear law's arithmetic
    "compiled": ({"address": address(HARDENING), "uses_time": 0.0, "p0": 200.0, "p1": 300.0},
                 lambda r: np.max(300.0 * r.measure**2) > 0.1),
    "compiled_state": ({"address": address(BILINEAR), "uses_time": 0.0, "state_size": 3.0, "p0": 300.0, "p1": 3.0,
                        "p2": 0.05}, lambda r: np.ptp(r.state["s0"]) > 0.02),
}


def law_type(case: str) -> str:
    return case.split("-")[0]


def chain(case: str, *, amplitude: float = 6.0, omega: float = 7.0, t0_force: bool = False) -> nvib.Model:
    """Two unit masses: x1 on a spring (400) and a light damper to the ground, the law under test (named
    "law") and a spring (100) between x2 and x1, the ground shaking as amplitude sin(omega t)."""
    params, _ = LAW_CASES[case]
    eff = [{"type": "spring", "measure": {"x1": 1.0}, "k": 400.0},
           {"type": "spring", "measure": {"x2": 1.0, "x1": -1.0}, "k": 100.0},
           {"type": "damper", "measure": {"x1": 1.0}, "c": 0.5},
           dict(params, type=law_type(case), name="law", measure={"x2": 1.0, "x1": -1.0}),
           {"type": "ground_acceleration", "name": "ground",
            "signal": {"kind": "sine", "amplitude": amplitude, "omega": omega}}]
    return nvib.Model([1.0, 1.0], effects=eff, dofs=["x1", "x2"])


def memory_chain(shaking: float = 0.0, **model_kw) -> nvib.Model:
    """Three unit masses in a chain, held by every law with memory (each yields when the chain is
    started from u = 0 with v0 below): a bilinear storey, a friction slider, a Bouc-Wen element of each
    integration and an IMK storey; no load and no time, so a run depends on its state alone (with
    shaking != 0: a ground acceleration shaking sin(7 t) as well)."""
    eff = [
        {"type": "bilinear", "name": "bilinear", "measure": {"a": 1.0}, "k": 400.0, "fy": 4.0, "b": 0.05},
        {"type": "spring", "measure": {"a": 1.0}, "k": 50.0},
        {"type": "friction", "name": "friction", "measure": {"b": 1.0, "a": -1.0}, "k": 300.0, "fs": 2.0},
        {"type": "spring", "measure": {"b": 1.0, "a": -1.0}, "k": 80.0},
        {"type": "bouc_wen", "name": "bouc_wen", "measure": {"c": 1.0, "b": -1.0}, "k": 300.0, "fy": 2.5,
         "alpha": 0.1, "n": 2.0},
        {"type": "bouc_wen", "name": "bouc_wen_euler", "measure": {"c": 1.0, "a": -1.0}, "k": 100.0, "dy": 0.02,
         "alpha": 0.2, "integration": "backward_euler"},
        {"type": "imk_peak_oriented", "name": "imk", "measure": {"c": 1.0}, "k": 300.0, "fy": 3.0, "up": 0.02,
         "upc": 0.3, "uu": 2.0, "fcap_fy": 1.2, "fres_fy": 0.3, "lambda_s": 20.0, "lambda_k": 30.0},
        {"type": "damper", "measure": {"a": 1.0}, "c": 0.3},
    ]
    if shaking:
        eff.append({"type": "ground_acceleration", "signal": {"kind": "sine", "amplitude": shaking, "omega": 7.0}})
    kw = dict(v0=[1.5, -1.0, 2.0])
    kw.update(model_kw)
    return nvib.Model([1.0, 1.0, 1.0], effects=eff, dofs=["a", "b", "c"], **kw)


MEMORY_NAMES = ["bilinear", "friction", "bouc_wen", "bouc_wen_euler", "imk"]


def imk_dissipated(record) -> np.ndarray:
    """The IMK law's dissipated energy from its recorded state: its work less what unloading gives back."""
    s = record.state
    return np.where(s["failed"] != 0.0, s["energy"], s["energy"] - 0.5 * record.force**2 / s["k_unload"])


def fitted_order(dts, errors) -> float:
    return float(np.polyfit(np.log(dts), np.log(errors), 1)[0])


# ---------------------------------------------------------------------------
# references

def bouc_wen_reference(t, *, m, k, fy, alpha, n, load, c=0.0, beta=0.5, gamma=0.5, A=1.0) -> np.ndarray:
    """(x, v, z) at the times t of m x'' + c x' + alpha k x + (1 - alpha) fy z = load(t), z' = x' Phi / dy
    from rest, by DOP853 at rtol 1e-13 (the right-hand side is continuous where x' changes sign: dz/dt
    carries the factor x')."""
    dy = fy / k

    def rhs(time, y):
        x, v, z = y
        sz = 1.0 if v * z > 0.0 else -1.0
        return [v, (load(time) - c * v - alpha * k * x - (1.0 - alpha) * fy * z) / m,
                v * (A - abs(z) ** n * (beta * sz + gamma)) / dy]

    t = np.asarray(t, float)
    sol = solve_ivp(rhs, (0.0, float(t[-1])), [0.0, 0.0, 0.0], method="DOP853", rtol=1e-13, atol=1e-15, t_eval=t)
    assert sol.success
    return sol.y.T


def bilinear_reference(t, *, m, k, fy, b, ag) -> np.ndarray:
    """(x, v) at the times t of m x'' + f(x) = -m ag(t) from rest, f the bilinear law with kinematic
    hardening, integrated by DOP853 (rtol 1e-13) phase by phase between its events: elastic (dp fixed)
    until |k (x - dp) - H dp| reaches fy, then plastic (f = (k H x + s k fy) / (k + H), H = b k / (1 - b))
    until x' reverses."""
    H = b * k / (1.0 - b)
    t = np.asarray(t, float)
    t_end = float(t[-1])
    pieces, t0, y, dp, phase = [], 0.0, [0.0, 0.0], 0.0, 0
    while t0 < t_end:
        if phase == 0:
            def rhs(time, y, dp=dp):
                return [y[1], -ag(time) - k * (y[0] - dp) / m]

            def up(time, y, dp=dp):
                return k * (y[0] - dp) - H * dp - fy

            def down(time, y, dp=dp):
                return k * (y[0] - dp) - H * dp + fy
            up.terminal = down.terminal = True
            up.direction, down.direction = 1, -1
            events = [up, down]
        else:
            def rhs(time, y, s=phase):
                return [y[1], -ag(time) - (k * H * y[0] + s * k * fy) / (k + H) / m]

            def stop(time, y):
                return y[1]
            stop.terminal, stop.direction = True, -phase
            events = [stop]
        sol = solve_ivp(rhs, (t0, t_end), y, method="DOP853", rtol=1e-13, atol=1e-15, events=events,
                        dense_output=True)
        assert sol.success
        pieces.append((t0, sol.t[-1], sol.sol))
        y = list(sol.y[:, -1])
        if sol.status == 1:  # an event
            if phase == 0:
                phase = 1 if len(sol.t_events[0]) else -1
            else:
                dp = (k * y[0] - phase * fy) / (k + H)
                phase = 0
        t0 = sol.t[-1]
    out = np.empty((len(t), 2))
    for i, ti in enumerate(t):
        for a, z, f in pieces:
            if a <= ti <= z:
                out[i] = f(ti)
                break
    return out


def ground_sine(amplitude: float, omega: float):
    return lambda time: amplitude * math.sin(omega * time)


def step_until_it_fails(st, limit=5000):
    """Steps until one fails: the state, time and index before it."""
    for _ in range(limit):
        before, t, k = st.state(), st.t, st.step_index
        try:
            st.step()
        except nvib.ConvergenceError:
            return before, t, k
    pytest.fail("no step failed")
