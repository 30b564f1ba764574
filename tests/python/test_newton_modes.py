"""The Newton component: its options object, its five modes, and that no
unconverged step is ever accepted by the iterating modes. Every implicit
scheme of the registry is checked."""

from __future__ import annotations

import pickle

import numpy as np
import pytest

import nvib

M, K0, A, X0 = 1.0, 100.0, 30.0, 1.5
MODES = ("newton", "modified", "initial", "incremental", "one_iteration")
ITERATING = ("newton", "modified", "initial")


def implicit_classes():
    return [cls for cls in nvib.schemes().values() if not cls.is_explicit]


def hardening(tangent_factor: float = 1.0) -> nvib.Model:
    """The hardening oscillator as Python callables, with its tangent scaled (1: correct)."""
    def force(u, v, t):
        return np.array([K0 * (1.0 + A * u[0] ** 2) * u[0]])

    def tangent(u, v, t):
        return np.array([[tangent_factor * K0 * (1.0 + 3.0 * A * u[0] ** 2)]]), None

    return nvib.Model([M], force=force, tangent=tangent, u0=[X0], uses_velocity=False, uses_time=False)


# ---------------------------------------------------------------- the options object

def test_newton_options_are_one_validated_object():
    n = nvib.Newton(iteration="modified", rtol=1e-8, max_iter=50)
    assert (n.iteration, n.rtol, n.max_iter, n.atol, n.jacobian) == ("modified", 1e-8, 50, 1e-12, "analytic")
    assert repr(n) == "Newton(iteration='modified', max_iter=50, rtol=1e-08)"
    assert pickle.loads(pickle.dumps(n)) == n and n != nvib.Newton()
    s = nvib.Newmark(newton=n)
    assert s.newton == n and s.iteration == "modified"
    assert nvib.Newmark(iteration="initial").newton == nvib.Newton(iteration="initial")


@pytest.mark.parametrize("make, argument, text", [
    (lambda: nvib.Newton(rtol=-1.0), "rtol", r"Newton needs rtol >= 0"),
    (lambda: nvib.Newton(max_iter=0), "max_iter", r"Newton needs 1 <= max_iter <= 1000, got 0"),
    (lambda: nvib.Newton(rtol=0.0, atol=0.0), "rtol, atol", r"at least one tolerance"),
    (lambda: nvib.Newton(iteration="none"), "iteration", r"'none' is now 'one_iteration'"),
    (lambda: nvib.Newmark(iteration="none"), "iteration", r"'none' is now 'one_iteration'"),
    (lambda: nvib.Newton(iteration="fast"), "iteration", r"expected 'newton', 'modified', 'initial', 'incremental' or "
                                                r"'one_iteration', got 'fast'"),
    (lambda: nvib.Newmark(iteration="modified", newton=nvib.Newton()), "iteration", r"not both"),
    (lambda: nvib.Newton(mode="modified"), "mode", r"renamed iteration in Newton .*give iteration=modified"),
    (lambda: nvib.Newmark(rtol=1e-8), "rtol", r"unknown parameter of Newmark \(expected beta, gamma, newton\)"),
    (lambda: nvib.Newmark(newton={"rtol": 1e-8}), "newton", r"expected nvib.Newton"),
    (lambda: nvib.Newton(1e-8), "Newton", r"takes at most 0 positional arguments"),
])
def test_bad_options_name_the_argument(make, argument, text):
    with pytest.raises((nvib.ArgumentError, nvib.ArgumentTypeError), match=text) as exc:
        make()
    assert exc.value.argument == argument
    assert str(exc.value).startswith(argument + ": ")


# ---------------------------------------------------------------- never accept an unconverged step

@pytest.mark.parametrize("mode", ITERATING)
def test_a_lying_tangent_is_a_convergence_error(mode):
    """Correct force, tangent x 1e30: the increment is negligible and the residual does not fall."""
    for cls in implicit_classes():
        with pytest.raises(nvib.ConvergenceError) as exc:
            nvib.solve(hardening(1e30), cls(iteration=mode), dt=1e-3, t_end=0.3)
        err = exc.value
        assert err.step == 1 and len(err.residuals) >= 2, (cls, mode, err)
        assert err.residuals[-1] > 1e-3 * err.residuals[0], (cls, mode, err.residuals)
        assert err.result is not None and err.result.status == nvib.Status.newton_failed


@pytest.mark.parametrize("mode", ["incremental", "one_iteration"])
def test_the_accepting_modes_report_the_residual_they_leave(mode):
    for cls in implicit_classes():
        lying = nvib.solve(hardening(1e30), cls(iteration=mode), dt=1e-3, t_end=0.3)
        assert lying.success and lying.max_residual > 0.1, (cls, mode, lying.max_residual)
        assert len(nvib.Stepper(hardening(1e30), cls(iteration=mode), dt=1e-3).last_residuals) == 0


@pytest.mark.parametrize("mode", ITERATING)
def test_converged_steps_report_at_most_rtol(mode):
    """With a tolerance above the round-off of the residual every accepted step is below it; at the
    default 1e-10 a step may end at that round-off instead (8 eps times the terms that cancel in it)."""
    for cls in implicit_classes():
        res = nvib.solve(hardening(), cls(newton=nvib.Newton(iteration=mode, rtol=1e-7)), dt=1e-3, t_end=0.3)
        assert res.success and res.max_residual <= 1e-7, (cls, mode, res.max_residual)
        assert nvib.solve(hardening(), cls(iteration=mode), dt=1e-3, t_end=0.3).success


def test_quadratic_convergence():
    """Full Newton: each residual is about the square of the last (relative to the force scale)."""
    for cls in implicit_classes():
        st = nvib.Stepper(hardening(), cls(), dt=2e-3)
        st.step(20)
        r = np.array(st.last_residuals) / (K0 * (1.0 + A * X0 ** 2) * X0)
        r = r[r > 1e-13]  # above round-off
        assert len(r) >= 3, (cls, r)
        # Order estimate log(r_k+1 / r_k) / log(r_k / r_k-1): measured 1.993 (Newmark, r = 10.3, 1.26e-2,
        # 1.97e-8) and 1.997 (GeneralizedAlpha, r = 5.24, 3.20e-3, 1.22e-9). The ratio log r_k+1 / log r_k
        # checked before (> 1.8) measured 4.06 and 3.57: it is not the order unless the constant is 1.
        orders = np.log(r[2:] / r[1:-1]) / np.log(r[1:-1] / r[:-2])
        assert np.all(np.abs(orders - 2.0) <= 0.1), (cls, r, orders)


def test_tangent_evaluations_per_mode():
    """modified: one factorisation per step; initial: one per run; newton: one per iteration."""
    for cls in implicit_classes():
        n = {m: nvib.solve(hardening(), cls(iteration=m), dt=1e-3, t_end=0.3).stats for m in MODES}
        assert n["initial"].num_factorizations == 1
        assert n["modified"].num_factorizations == n["modified"].num_steps == 300
        assert n["newton"].num_factorizations + n["newton"].num_reused_factorizations == n["newton"].num_newton_iters > 300
        assert n["incremental"].num_factorizations == n["incremental"].num_newton_iters == 300
        assert n["one_iteration"].num_newton_iters == 300


# ---------------------------------------------------------------- the textbook incremental format

def chopra_incremental(m, c, k_tangent, f_load, u0, v0, dt, n, beta=0.25, gamma=0.5, a0=None):
    """Newmark's method in the incremental format without iteration, transcribed from Chopra,
    Dynamics of Structures, section 5.7 (tangent stiffness k_T at the start of each step);
    a0 defaults to the acceleration in equilibrium at the start."""
    a1 = m / (beta * dt) + gamma / beta * c
    b = m / (2.0 * beta) + dt * (gamma / (2.0 * beta) - 1.0) * c
    u, v = u0, v0
    a = (f_load(0.0) - c * v - f_spring(u)) / m if a0 is None else a0
    out = [(u, v, a)]
    for i in range(n):
        dp_hat = f_load((i + 1) * dt) - f_load(i * dt) + a1 * v + b * a
        k_hat = k_tangent(u) + gamma / (beta * dt) * c + m / (beta * dt * dt)
        du = dp_hat / k_hat
        dv = gamma / (beta * dt) * du - gamma / beta * v + dt * (1.0 - gamma / (2.0 * beta)) * a
        da = du / (beta * dt * dt) - v / (beta * dt) - a / (2.0 * beta)
        u, v, a = u + du, v + dv, a + da
        out.append((u, v, a))
    return np.array(out)


def f_spring(u):
    return K0 * (1.0 + A * u * u) * u


@pytest.mark.parametrize("damped", [False, True])
def test_incremental_matches_the_textbook(damped):
    c, amp, w = (0.8, 300.0, 12.0) if damped else (0.0, 0.0, 0.0)
    effects = [{"type": "hardening_spring", "measure": {"x": 1.0}, "k0": K0, "a": A}]
    if damped:
        effects += [{"type": "damper", "measure": {"x": 1.0}, "c": c},
                    {"type": "harmonic_force", "measure": {"x": 1.0}, "amplitude": amp, "omega": w}]
    model = nvib.Model([M], effects=effects, dofs=["x"], u0=[X0])
    dt, n = 1e-3, 300
    res = nvib.solve(model, nvib.Newmark(iteration="incremental"), dt=dt, t_end=n * dt)
    k_t, load = (lambda u: K0 * (1.0 + 3.0 * A * u * u)), (lambda t: amp * np.sin(w * t))
    # Every step of the 300, from nvib's own state, to 1e-12 of each quantity's scale. (nvib's unknown
    # is u_{n+1}, so its a_{n+1} carries c0 ulp(u), 9e-10 here, where the textbook's carries c0 ulp(du).)
    scale = [np.max(np.abs(q)) for q in (res.u, res.v, res.a)]
    for i in range(n):
        t0 = i * dt
        step = chopra_incremental(M, c, k_t, lambda t: load(t0 + t), res.u[i, 0], res.v[i, 0], dt, 1,
                                  a0=res.a[i, 0])[1]
        for j, q in enumerate((res.u, res.v, res.a)):
            assert abs(q[i + 1, 0] - step[j]) <= 1e-12 * scale[j], (i, j)
    # The whole run from the same start, over 20 steps: the oscillator amplifies round-off (a 1e-15
    # change of x0 grows 200-fold by 0.3 s), so the histories part by more than 1e-12 later on.
    ref = chopra_incremental(M, c, k_t, load, X0, 0.0, dt, 20)
    for j, q in enumerate((res.u[:21, 0], res.v[:21, 0], res.a[:21, 0])):
        assert np.max(np.abs(q - ref[:, j])) <= 1e-12 * np.max(np.abs(ref[:, j])), j
    # and it is not the one-iteration mode, which corrects the equilibrium error of earlier steps
    other = nvib.solve(model, nvib.Newmark(iteration="one_iteration"), dt=dt, t_end=n * dt)
    assert np.max(np.abs(other.u - res.u)) > 1e-3


def test_generalized_alpha_incremental_follows_its_formula():
    """(1-am) M (a1 - a_n) + (1-af) [K_t du + C_t dv + dG_t] = 0, tangent at the start of the step."""
    s = nvib.GeneralizedAlpha.from_rho_inf(0.8, iteration="incremental")
    am, af, beta, gamma = s.alpha_m, s.alpha_f, s.beta, s.gamma
    model = nvib.Model([M], effects=[{"type": "hardening_spring", "measure": {"x": 1.0}, "k0": K0, "a": A}],
                       dofs=["x"], u0=[X0])
    dt, n = 1e-3, 300
    res = nvib.solve(model, s, dt=dt, t_end=n * dt)
    for i in range(n):  # each step from nvib's state, to round-off
        u, v, a = res.u[i, 0], res.v[i, 0], res.a[i, 0]
        kt = K0 * (1.0 + 3.0 * A * u * u)
        c0 = 1.0 / (beta * dt * dt)
        da_pred = -v / (beta * dt) - a / (2.0 * beta)  # a1 - a_n at du = 0
        du = -(1.0 - am) * M * da_pred / ((1.0 - am) * c0 * M + (1.0 - af) * kt)
        a1 = c0 * (du - dt * v) - (0.5 / beta - 1.0) * a
        v, a, u = v + dt * (1.0 - gamma) * a + dt * gamma * a1, a1, u + du
        for q, x in ((res.u, u), (res.v, v), (res.a, a)):
            assert abs(q[i + 1, 0] - x) <= 1e-12 * np.max(np.abs(q)), i


# ---------------------------------------------------------------- the static equilibrium solve

def test_static_equilibrium_uses_the_newton_component():
    """A preloaded hardening spring: k0 (1 + a u^2) u = P, residual at round-off, and no support is an error."""
    model = nvib.Model([M], effects=[{"type": "hardening_spring", "measure": {"x": 1.0}, "k0": K0, "a": A},
                                     {"type": "constant_force", "measure": {"x": 1.0}, "value": 500.0}], dofs=["x"])
    u = model.static_equilibrium()
    assert abs(f_spring(u[0]) - 500.0) <= 1e-12 * 500.0
    free = nvib.Model([M], effects=[{"type": "constant_force", "measure": {"x": 1.0}, "value": 1.0}], dofs=["x"])
    with pytest.raises(nvib.ArgumentError, match="no static equilibrium") as exc:
        free.static_equilibrium()
    assert exc.value.argument == "initial"
