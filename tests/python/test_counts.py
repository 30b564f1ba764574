"""Exact work counters of a run of N steps. solve() counts include the
start-up: one force evaluation for a0 (and, for PIM, one tangent evaluation
at the origin and one matrix exponential)."""

from __future__ import annotations

import numpy as np
import pytest

import nvib

N = 40
DT = 1e-3
T_END = N * DT
K0, A = 100.0, 30.0


class Counted:
    """A Python force (and tangent) that counts its calls."""

    def __init__(self, damping=0.0):
        self.c = damping
        self.force_calls = 0
        self.tangent_calls = 0

    def force(self, u, v, t):
        self.force_calls += 1
        return K0 * (1.0 + A * u * u) * u + self.c * v

    def tangent(self, u, v, t):
        self.tangent_calls += 1
        Kt = np.array([[K0 * (1.0 + 3.0 * A * u[0] * u[0])]])
        return Kt, (np.array([[self.c]]) if self.c else None)


def effect_model(damped):
    eff = [{"type": "hardening_spring", "measure": {"x": 1.0}, "k0": K0, "a": A}]
    if damped:
        eff.append({"type": "damper", "measure": {"x": 1.0}, "c": 2.0})
    return nvib.Model([1.0], effects=eff, dofs=["x"], u0=[1.5])


def callable_model(damped, counter=None):
    counter = counter or Counted(2.0 if damped else 0.0)
    return nvib.Model([1.0], force=counter.force, tangent=counter.tangent, u0=[1.5],
                      uses_velocity=damped, uses_time=False), counter


MODEL_KINDS = ["effects", "effects+damper", "callable", "callable+damper"]


def build(kind):
    damped = kind.endswith("damper")
    if kind.startswith("effects"):
        return effect_model(damped), None
    return callable_model(damped)


def stats_of(kind, scheme):
    model, counter = build(kind)
    res = nvib.solve(model, scheme, dt=DT, t_end=T_END)
    s = res.stats
    assert s.num_steps == N and res.status == nvib.Status.success
    if counter is not None:  # the counters match the Python calls actually made
        assert counter.force_calls == s.num_force_evals + s.num_fd_force_evals
        assert counter.tangent_calls == s.num_tangent_evals
    return s


EXPLICIT = {
    "CentralDifference": lambda: nvib.CentralDifference(),
    "CentralDifference(half_step)": lambda: nvib.CentralDifference(velocity="half_step"),
    "Zhai": lambda: nvib.Zhai(0.5, 0.5),
    "Zhai(0.3,0.7)": lambda: nvib.Zhai(0.3, 0.7),
    "CEMDTS(0.45)": lambda: nvib.CEMDTS(0.45),
    "CEMDTS(0)": lambda: nvib.CEMDTS(0.0),
}


@pytest.mark.parametrize("kind", MODEL_KINDS)
@pytest.mark.parametrize("name", list(EXPLICIT))
def test_explicit_one_force_evaluation_per_step(name, kind):
    s = stats_of(kind, EXPLICIT[name]())
    assert s.num_force_evals == N + 1
    assert s.num_fd_force_evals == 0
    assert s.num_tangent_evals == 0
    assert s.num_newton_iters == s.num_factorizations == s.num_linear_solves == 0
    assert s.num_expm == 0


@pytest.mark.parametrize("kind", MODEL_KINDS)
@pytest.mark.parametrize("corrections", [0, 1, 2, 3])
@pytest.mark.parametrize("order", [1, 2, 3])
def test_pim_counts(order, corrections, kind):
    s = stats_of(kind, nvib.PreciseIntegration(interpolation=order, corrections=corrections))
    assert s.num_force_evals == (1 + corrections) * N + 1
    assert s.num_expm == 1
    assert s.num_tangent_evals == 1
    assert s.num_fd_force_evals == 0
    assert s.num_newton_iters == s.num_factorizations == s.num_linear_solves == 0


def test_pim_counts_linear_model():
    md = nvib.Model([1.0], K=[[100.0]], u0=[1.0])
    s = nvib.solve(md, nvib.PreciseIntegration(corrections=2), dt=DT, t_end=T_END).stats
    assert (s.num_force_evals, s.num_expm, s.num_tangent_evals) == (3 * N + 1, 1, 1)


IMPLICIT = {
    "Newmark": lambda **kw: nvib.Newmark(0.25, 0.5, **kw),
    "GeneralizedAlpha": lambda **kw: nvib.GeneralizedAlpha(**kw),
    "GeneralizedAlpha-rho0.8": lambda **kw: nvib.GeneralizedAlpha.from_rho_inf(0.8, **kw),
    "HHT(-0.1)": lambda **kw: nvib.GeneralizedAlpha.hht(-0.1, **kw),
}


@pytest.mark.parametrize("kind", MODEL_KINDS)
@pytest.mark.parametrize("name", list(IMPLICIT))
def test_incremental_format_counts(name, kind):
    s = stats_of(kind, IMPLICIT[name](iteration="one_iteration"))
    # a0, then per step the predictor's residual and the residual left after
    # the single solve (evaluated so that no step is accepted unseen)
    assert s.num_force_evals == 2 * N + 1
    assert s.num_tangent_evals == N
    assert s.num_factorizations == N
    assert s.num_linear_solves == N
    assert s.num_newton_iters == N
    assert s.num_fd_force_evals == 0 and s.num_expm == 0


@pytest.mark.parametrize("kind", MODEL_KINDS)
@pytest.mark.parametrize("name", list(IMPLICIT))
def test_full_newton_counts(name, kind):
    s = stats_of(kind, IMPLICIT[name](iteration="newton"))
    iters = s.num_newton_iters
    assert iters >= 2 * N  # strongly nonlinear: at least two iterations per step
    # a new factorisation every iteration, unless the iteration matrix is bit for bit the last one
    assert s.num_factorizations + s.num_reused_factorizations == iters
    assert s.num_linear_solves == iters
    assert s.num_tangent_evals == iters
    assert s.num_force_evals == N + 1 + iters
    assert s.num_fd_force_evals == 0 and s.num_expm == 0


@pytest.mark.parametrize("kind", MODEL_KINDS)
@pytest.mark.parametrize("name", list(IMPLICIT))
def test_modified_newton_counts(name, kind):
    s = stats_of(kind, IMPLICIT[name](newton=nvib.Newton(iteration="modified", max_iter=100)))
    iters = s.num_newton_iters
    assert iters > 2 * N
    assert s.num_factorizations == N
    assert s.num_tangent_evals == N
    assert s.num_linear_solves == iters
    assert s.num_force_evals == N + 1 + iters


LINEAR_MODELS = {
    "K only": lambda: nvib.Model([1.0, 2.0], K=[[300.0, -100.0], [-100.0, 100.0]], u0=[1.0, 0.0]),
    "K and C": lambda: nvib.Model([1.0, 2.0], K=[[300.0, -100.0], [-100.0, 100.0]], C=[[0.5, 0.0], [0.0, 0.2]],
                                  u0=[1.0, 0.0]),
    "springs": lambda: nvib.Model([1.0, 2.0], effects=[
        {"type": "spring", "measure": {"a": 1.0}, "k": 200.0},
        {"type": "spring", "measure": {"b": 1.0, "a": -1.0}, "k": 100.0},
        {"type": "damper", "measure": {"b": 1.0}, "c": 0.3}], dofs=["a", "b"], u0=[1.0, 0.0]),
    "springs + constant load": lambda: nvib.Model([1.0, 2.0], effects=[
        {"type": "spring", "measure": {"a": 1.0}, "k": 200.0},
        {"type": "spring", "measure": {"b": 1.0, "a": -1.0}, "k": 100.0},
        {"type": "constant_force", "measure": {"b": 1.0}, "value": 5.0}], dofs=["a", "b"], u0=[1.0, 0.0]),
}


@pytest.mark.parametrize("iteration", ["newton", "modified", "one_iteration"])
@pytest.mark.parametrize("name", list(IMPLICIT))
@pytest.mark.parametrize("model", list(LINEAR_MODELS))
def test_linear_model_factorizes_once(model, name, iteration):
    md = LINEAR_MODELS[model]()
    assert md.is_linear
    s = nvib.solve(md, IMPLICIT[name](iteration=iteration), dt=DT, t_end=T_END).stats
    assert s.num_factorizations == 1
    assert s.num_tangent_evals == 1
    assert s.num_newton_iters == N
    assert s.num_linear_solves == N
    assert s.num_force_evals == N + 1


def test_stepper_counts_are_cumulative_and_integrate_counts_its_own_stretch():
    md = effect_model(False)
    st = nvib.Stepper(md, nvib.CentralDifference(), DT)
    assert st.stats.num_force_evals == 1 and st.stats.num_steps == 0  # a0
    st.step(10)
    assert st.stats.num_force_evals == 11 and st.stats.num_steps == 10
    res = st.integrate(st.t + 5 * DT)
    assert res.stats.num_steps == 5 and res.stats.num_force_evals == 5
    assert st.stats.num_steps == 15 and st.stats.num_force_evals == 16


def test_stats_as_dict():
    s = nvib.solve(effect_model(True), nvib.Newmark(), dt=DT, t_end=T_END).stats
    d = s.as_dict()
    assert set(d) == {"num_steps", "num_force_evals", "num_fd_force_evals", "num_tangent_evals", "num_newton_iters",
                      "num_factorizations", "num_reused_factorizations", "num_linear_solves", "num_expm", "num_rejected_steps",
                      "num_events", "num_check_steps", "num_restarts", "wall_time",
                      "linear_solver"}
    for k, v in d.items():
        assert v == getattr(s, k)
    assert d["wall_time"] >= 0.0
    assert d["linear_solver"] == "banded LDLT"  # one DOF: a band of width 0
    assert nvib.solve(effect_model(True), nvib.CEMDTS(), dt=DT, t_end=T_END).stats.linear_solver == ""
