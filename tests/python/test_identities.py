"""Exact algebraic identities between the schemes, checked to round-off on a
nonlinear 3-DOF chain (hardening and cubic springs, a harmonic load and,
where the identity allows it, a linear damper)."""

from __future__ import annotations

import numpy as np
import pytest

import nvib

DT, T_END = 1e-3, 2.0
REL = 1e-12


def chain(damped: bool) -> nvib.Model:
    effects = [
        {"type": "spring", "measure": {"a": 1.0}, "k": 400.0},
        {"type": "hardening_spring", "measure": {"b": 1.0, "a": -1.0}, "k0": 150.0, "a": 40.0},
        {"type": "cubic_spring", "measure": {"c": 1.0, "b": -1.0}, "k3": 900.0},
        {"type": "spring", "measure": {"c": 1.0, "b": -1.0}, "k": 80.0},
        {"type": "harmonic_force", "measure": {"c": 1.0}, "amplitude": 30.0, "omega": 9.0, "phase": 0.2},
    ]
    if damped:
        effects += [{"type": "damper", "measure": {"a": 1.0}, "c": 1.5},
                    {"type": "damper", "measure": {"c": 1.0, "b": -1.0}, "c": 0.8}]
    return nvib.Model([1.0, 2.0, 1.5], effects=effects, dofs=["a", "b", "c"], u0=[0.2, -0.3, 0.5], v0=[0.0, 1.0, -0.5])


def callable_chain(damped: bool) -> nvib.Model:
    """The same kind of system as a Python callable (forces the callable code path)."""
    k, c = 300.0, (1.2 if damped else 0.0)

    def force(u, v, t):
        d0, d1 = u[0], u[1] - u[0]
        f0 = k * (1.0 + 25.0 * d0 ** 2) * d0
        f1 = 200.0 * d1 + 500.0 * d1 ** 3
        return np.array([f0 - f1 + c * v[0], f1 - 20.0 * np.sin(7.0 * t)])

    def tangent(u, v, t):
        d0, d1 = u[0], u[1] - u[0]
        k0 = k * (1.0 + 75.0 * d0 ** 2)
        k1 = 200.0 + 1500.0 * d1 ** 2
        Kt = np.array([[k0 + k1, -k1], [-k1, k1]])
        return Kt, (np.array([[c, 0.0], [0.0, 0.0]]) if damped else None)

    return nvib.Model([1.0, 0.7], force=force, tangent=tangent, u0=[0.3, -0.2], v0=[0.5, 0.0],
                      uses_velocity=damped)


def run(model, scheme):
    res = nvib.solve(model, scheme, dt=DT, t_end=T_END)
    assert res.status == nvib.Status.success
    return res


def assert_close(x, ref, what):
    scale = np.max(np.abs(ref))
    assert scale > 0
    err = np.max(np.abs(x - ref))
    assert err <= REL * scale, f"{what}: max |diff| = {err:.3e}, scale {scale:.3e} (rel {err / scale:.2e})"


MODELS = {
    "effects-damped": lambda: chain(True),
    "effects-undamped": lambda: chain(False),
    "callable-damped": lambda: callable_chain(True),
}
UNDAMPED = {
    "effects-undamped": lambda: chain(False),
    "callable-undamped": lambda: callable_chain(False),
}


@pytest.mark.parametrize("model", list(MODELS))
def test_cemdts_eta0_is_central_difference(model):
    md = MODELS[model]()
    r1, r2 = run(md, nvib.CEMDTS(eta=0.0)), run(md, nvib.CentralDifference())
    for attr in ("u", "v", "a"):
        assert_close(getattr(r1, attr), getattr(r2, attr), f"CEMDTS(0) vs CentralDifference, {attr}")


@pytest.mark.parametrize("model", list(MODELS))
def test_cemdts_eta_half_is_zhai(model):
    md = MODELS[model]()
    r1, r2 = run(md, nvib.CEMDTS(eta=0.5)), run(md, nvib.Zhai(0.5, 0.5))
    for attr in ("u", "v", "a"):
        assert_close(getattr(r1, attr), getattr(r2, attr), f"CEMDTS(0.5) vs Zhai(0.5, 0.5), {attr}")


@pytest.mark.parametrize("iteration", ["newton", "one_iteration", "modified"])
@pytest.mark.parametrize("beta, gamma", [(0.25, 0.5), (0.3025, 0.6)])
@pytest.mark.parametrize("model", list(MODELS))
def test_generalized_alpha_zero_alphas_is_newmark(model, beta, gamma, iteration):
    md = MODELS[model]()
    ga = nvib.GeneralizedAlpha(alpha_m=0.0, alpha_f=0.0, beta=beta, gamma=gamma, iteration=iteration)
    r1, r2 = run(md, ga), run(md, nvib.Newmark(beta, gamma, iteration=iteration))
    for attr in ("u", "v", "a"):
        assert_close(getattr(r1, attr), getattr(r2, attr), f"GeneralizedAlpha(0, 0, {beta}, {gamma}) vs Newmark, {attr}")
    assert r1.stats.num_newton_iters == r2.stats.num_newton_iters


@pytest.mark.parametrize("velocity", ["synchronized", "half_step"])
@pytest.mark.parametrize("model", list(UNDAMPED))
def test_zhai_displacements_are_central_difference(model, velocity):
    md = UNDAMPED[model]()
    r1, r2 = run(md, nvib.Zhai(0.5, 0.5)), run(md, nvib.CentralDifference(velocity=velocity))
    assert_close(r1.u, r2.u, f"Zhai(0.5, 0.5) vs CentralDifference({velocity}), u")
    assert_close(r1.a, r2.a, f"Zhai(0.5, 0.5) vs CentralDifference({velocity}), a")


@pytest.mark.parametrize("eta", [0.0, 1.0 / 12.0, 0.25, 0.45, 0.5, 0.75, 1.0])
@pytest.mark.parametrize("model", list(UNDAMPED))
def test_cemdts_displacements_are_central_difference(model, eta):
    md = UNDAMPED[model]()
    r1, r2 = run(md, nvib.CEMDTS(eta=eta)), run(md, nvib.CentralDifference())
    assert_close(r1.u, r2.u, f"CEMDTS({eta}) vs CentralDifference, u")
    r3 = run(md, nvib.CentralDifference(velocity="half_step"))
    assert_close(r1.u, r3.u, f"CEMDTS({eta}) vs CentralDifference(half_step), u")


@pytest.mark.parametrize("eta", [0.0, 1.0 / 12.0, 0.45, 0.5, 1.0])
@pytest.mark.parametrize("model", ["effects-damped", "callable-damped"])
def test_cemdts_and_zhai_displacements_are_central_difference_even_when_damped(model, eta):
    """A consequence of the update formulas: in CentralDifference(synchronized),
    CEMDTS(eta) and Zhai(1/2, 1/2) the velocity fed to the force at t_{n+1} is
    (u_{n+1} - u_n)/h + h a_n/2, so u and a coincide for velocity-dependent
    forces too; only the reported velocity differs."""
    md = MODELS[model]()
    ref = run(md, nvib.CentralDifference())
    for scheme in (nvib.CEMDTS(eta=eta), nvib.Zhai(0.5, 0.5)):
        r = run(md, scheme)
        assert_close(r.u, ref.u, f"{scheme.name} vs CentralDifference, u (damped)")
        assert_close(r.a, ref.a, f"{scheme.name} vs CentralDifference, a (damped)")
    # ... while the reported velocities do differ (eta != 0).
    if eta != 0.0:
        r = run(md, nvib.CEMDTS(eta=eta))
        assert np.max(np.abs(r.v - ref.v)) > 1e-9 * np.max(np.abs(ref.v))


def test_damped_models_exercise_the_velocity_path():
    """With dampers the velocity enters the force: both LCDM variants feed it the
    second-order estimate v_n + h a_n (= v_{n+1/2} + h/2 a_n), so their
    displacements agree to round-off while the reported velocities differ
    (half_step reports v_{n+1/2}), and a run without the dampers differs."""
    md = chain(True)
    r1, r2 = run(md, nvib.CentralDifference(velocity="half_step")), run(md, nvib.CentralDifference())
    scale = np.max(np.abs(r2.u))
    assert np.max(np.abs(r1.u - r2.u)) <= 1e-12 * scale
    assert np.max(np.abs(r1.v - r2.v)) > 1e-6 * np.max(np.abs(r2.v))
    undamped = run(chain(False), nvib.CentralDifference())
    assert np.max(np.abs(undamped.u - r2.u)) > 1e-6 * scale


@pytest.mark.parametrize("scene, dt, t_end", [("hardening", 1e-3, 0.3), ("vehicle", 1e-3, 0.2),
                                              ("building", 0.03, 3.0)])
def test_incremental_paper_galpha_is_incremental_newmark(scene, dt, t_end):
    """In the incremental format the equation at t_n is taken as satisfied and subtracted, so the step of
    generalized-alpha with alpha_m = alpha_f is Newmark's divided by (1 - alpha_m): the paper's GaM
    (1/2, 1/2, 1/4, 1/2) and Newmark(1/4, 1/2) take the same steps, to the last bit. Iterated, they differ
    (the implicit midpoint rule against the trapezoidal rule), and so do other alphas."""
    model = nvib.load_scene(scene)
    newmark = nvib.solve(model, nvib.Newmark(0.25, 0.5, iteration="incremental"), dt=dt, t_end=t_end)
    galpha = nvib.solve(model, nvib.GeneralizedAlpha(0.5, 0.5, 0.25, 0.5, iteration="incremental"), dt=dt,
                        t_end=t_end)
    np.testing.assert_array_equal(galpha.u, newmark.u)
    np.testing.assert_array_equal(galpha.v, newmark.v)
    iterated = [nvib.solve(model, cls(*args, iteration="one_iteration"), dt=dt, t_end=t_end).u
                for cls, args in ((nvib.Newmark, (0.25, 0.5)), (nvib.GeneralizedAlpha, (0.5, 0.5, 0.25, 0.5)))]
    assert np.max(np.abs(iterated[0] - iterated[1])) > 1e-3 * np.max(np.abs(iterated[0]))
    other = nvib.solve(model, nvib.GeneralizedAlpha.from_rho_inf(0.8, iteration="incremental"), dt=dt, t_end=t_end)
    assert np.max(np.abs(other.u - newmark.u)) > 1e-4 * np.max(np.abs(newmark.u))
