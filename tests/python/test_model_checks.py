"""Real models are checked: a stiffness or damping stored as one triangle, a mass that is singular,
indefinite or nearly singular, a damped top mode that shrinks an explicit scheme's step limit, and the
divergence bound of a model in other units or loaded hard in its own."""

import math

import numpy as np
import pytest
import scipy.sparse as sps

import nvib
from nvib import stability as stab

FULL = np.array([[2.0, -1.0, 0.0], [-1.0, 2.0, -1.0], [0.0, -1.0, 1.0]])


# ---------------------------------------------------------------- one triangle of K or C

@pytest.mark.parametrize("part", ["K", "C"])
@pytest.mark.parametrize("sparse", [False, True], ids=["dense", "sparse"])
def test_one_triangle_of_a_linear_part_is_refused_naming_it(part, sparse):
    """A stiffness or damping stored as one triangle with its diagonal (as some programs write a symmetric
    matrix) would be solved as another matrix: refused, naming it."""
    for tri, side in ((np.triu(FULL), "above"), (np.tril(FULL), "below")):
        with pytest.raises(nvib.ArgumentError, match=rf"^{part}: the matrix has entries {side} its diagonal and "
                                                     r"on its diagonal only \(one triangle") as exc:
            nvib.Model(np.ones(3), **{part: sps.csc_matrix(tri) if sparse else tri})
        assert exc.value.argument == part


@pytest.mark.parametrize("part", ["K", "C"])
def test_non_symmetric_and_one_sided_linear_parts_stay_accepted(part):
    """Entries on both sides (follower forces, gyroscopic terms) and a strictly triangular coupling without a
    diagonal (a one-sided coupling), also with grounded springs or dampers on the diagonal, are legitimate."""
    gyro = FULL + np.array([[0.0, 0.5, 0.0], [-0.5, 0.0, 0.0], [0.0, 0.0, 0.0]])
    one_sided = np.triu(np.ones((3, 3)), 1)
    for A in (gyro, one_sided, sps.csc_matrix(one_sided)):
        assert nvib.Model(np.ones(3), **{part: A}).warnings == []
    law = {"K": {"type": "spring", "i": [0, 1, 2], "k": 1e3}, "C": {"type": "damper", "i": [0, 1, 2], "c": 1.0}}
    model = nvib.Model(np.ones(3), **{part: one_sided}, effects=[law[part]])
    assert model.warnings == []


@pytest.mark.parametrize("part", ["K", "C"])
def test_a_nearly_symmetric_linear_part_is_accepted_with_a_warning(part):
    """A K or C symmetric up to 1e-8 of its entries is taken as given, but every run says it looks like
    round-off in an assembly meant to be symmetric."""
    A = FULL.copy()
    A[0, 1] = -1.0 + 2.0 ** -43  # 1.1e-13 off, exactly
    model = nvib.Model(np.ones(3), **{part: A}, dofs=["a", "b", "c"])
    assert len(model.warnings) == 1
    assert model.warnings[0].startswith(f"{part}: the matrix is symmetric only up to 5.68434e-14 of its largest "
                                        f"entry (|{part}[1, 0] - {part}[0, 1]| = 1.13687e-13)")
    assert "round-off" in model.warnings[0]
    res = nvib.solve(model, nvib.Newmark(), dt=0.01, t_end=0.05)
    assert res.warnings == model.warnings
    assert nvib.Model(np.ones(3), **{part: FULL}).warnings == []
    A[0, 1] += 1e-3  # plainly non-symmetric: no warning
    assert nvib.Model(np.ones(3), **{part: A}).warnings == []


# ---------------------------------------------------------------- the mass

@pytest.mark.parametrize("sparse", [False, True], ids=["dense", "sparse"])
def test_a_singular_mass_names_the_dof_without_mass(sparse):
    kind = "sparse" if sparse else "dense"
    wrap = sps.csc_matrix if sparse else np.asarray
    # a DOF with no mass on the diagonal (coupled to the others)
    M = np.array([[1.0, 0.0, 0.1], [0.0, 0.0, 0.2], [0.1, 0.2, 1.0]])
    with pytest.raises(nvib.ArgumentError, match=rf"^mass: the {kind} mass matrix is not positive definite: it is "
                                                 r"singular: DOF 1 \(b\) has no mass") as exc:
        nvib.Model(wrap(M), dofs=["a", "b", "c"])
    assert exc.value.argument == "mass"
    # a row that depends on the rows before it: the pivot of DOF 1 is 0
    M = np.array([[1.0, 1.0, 0.0], [1.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
    with pytest.raises(nvib.ArgumentError, match=rf"^mass: the {kind} mass matrix is not positive definite: it is "
                                                 r"singular: the pivot of DOF 1 \(b\) after eliminating the DOFs "
                                                 r"before it is 0"):
        nvib.Model(wrap(M), dofs=["a", "b", "c"])


@pytest.mark.parametrize("sparse", [False, True], ids=["dense", "sparse"])
def test_an_indefinite_mass_names_the_negative_pivot(sparse):
    kind = "sparse" if sparse else "dense"
    wrap = sps.csc_matrix if sparse else np.asarray
    with pytest.raises(nvib.ArgumentError, match=rf"^mass: the {kind} mass matrix is not positive definite: it is "
                                                 r"indefinite: the pivot of DOF 1 \(u1\) after eliminating the DOFs "
                                                 r"before it is -3 < 0"):
        nvib.Model(wrap(np.array([[1.0, 2.0], [2.0, 1.0]])))
    with pytest.raises(nvib.ArgumentError, match=r"indefinite: DOF 1 \(y\) has the negative mass -1 on the diagonal"):
        nvib.Model(wrap(np.array([[1.0, 0.1], [0.1, -1.0]])), dofs=["x", "y"])
    with pytest.raises(nvib.ArgumentError, match=r"^mass: entry 1 is -1, every mass must be > 0 \(DOF 1 \(y\)\)"):
        nvib.Model([1.0, -1.0], dofs=["x", "y"])


@pytest.mark.parametrize("form", ["lumped", "dense", "sparse"])
def test_a_nearly_singular_mass_is_accepted_with_a_warning_naming_the_dof(form):
    if form == "lumped":
        M = np.array([1.0, 2.0, 1e-14])
        which = "the mass of DOF 2 (c) is 1e-14"
    else:
        M = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 1.0], [0.0, 1.0, 1.0 + 1e-14]])
        M = sps.csc_matrix(M) if form == "sparse" else M
        which = "the Cholesky pivot of DOF"
    model = nvib.Model(M, K=np.eye(3), dofs=["a", "b", "c"])
    assert len(model.warnings) == 1
    w = model.warnings[0]
    assert w.startswith("mass: the mass matrix is nearly singular: ") and which in w
    if form != "lumped":
        assert "DOF 1 (b)" in w or "DOF 2 (c)" in w
    assert nvib.solve(model, nvib.Newmark(), dt=0.01, t_end=0.02).warnings == model.warnings
    assert nvib.Model(np.ones(3), K=np.eye(3)).warnings == []


# ---------------------------------------------------------------- the damped step limit

def _rayleigh_chain(n=20, k=1e4, m=1.0, beta=0.1):
    K = sps.diags([np.full(n - 1, -k), np.full(n, 2 * k), np.full(n - 1, -k)], [-1, 0, 1]).tocsc()
    M = np.full(n, m)
    return nvib.Model(M, K=K, C=beta * K, u0=np.linspace(0.0, 1e-3, n))


def test_stability_takes_overdamped_ratios():
    """Central difference's limit 2(sqrt(1 + 4 xi^2) - 2 xi) (its damping force takes the predicted
    velocity v_n + dt a_n; Zhai(1/2, 1/2) has the same) holds for xi >= 1 too: 230 000x below the undamped
    limit at xi = 57 000. The amplification matrix and spectral radius take xi >= 1."""
    for scheme in (nvib.CentralDifference(), nvib.CentralDifference(velocity="half_step"), nvib.Zhai()):
        for xi in (1.0, 5.0, 57000.0):
            assert stab.critical_omega_h(scheme, xi) == pytest.approx(
                2.0 / (math.sqrt(1.0 + 4.0 * xi * xi) + 2.0 * xi), rel=1e-6)
    assert 2.0 / stab.critical_omega_h(nvib.CentralDifference(), 57000.0) == pytest.approx(228000.0, rel=1e-5)
    assert stab.spectral_radius(nvib.CentralDifference(), 0.06, xi=10.0) > 1.0
    assert stab.spectral_radius(nvib.CentralDifference(), 0.045, xi=10.0) <= 1.0 + 1e-9
    assert stab.amplification_matrix(nvib.CentralDifference(), 0.1, xi=2.0).shape == (3, 3)
    with pytest.raises(nvib.ArgumentError, match="^xi: "):
        stab.period_error(nvib.Newmark(), 1.0, xi=1.0)  # no oscillating principal pair


def test_a_damped_top_mode_above_the_step_limit_is_named_before_the_run():
    """Rayleigh damping that gives the top mode zeta ~ 10 shrinks central difference's limit ~40x: a run at
    0.9 of the undamped limit diverges within a few steps, and says why."""
    model = _rayleigh_chain()
    w = model.linearized_frequencies()
    top = w[-1]
    zeta = 0.1 * top / 2.0
    assert zeta > 9.0
    dt = 0.9 * 2.0 / top
    lim = stab.step_limit(model, nvib.CentralDifference())
    assert lim.omega == pytest.approx(top, rel=1e-9) and lim.zeta == pytest.approx(zeta, rel=1e-9)
    assert lim.dt == pytest.approx(2.0 / (top * (math.sqrt(1.0 + 4.0 * zeta ** 2) + 2.0 * zeta)), rel=1e-6)
    assert lim.dt_undamped == pytest.approx(2.0 / top, rel=1e-6)
    with pytest.raises(nvib.DivergenceError) as exc:
        nvib.solve(model, nvib.CentralDifference(), dt=dt, t_end=1.0)
    text = str(exc.value)
    assert text.startswith("diverged at t = ")
    assert f"dt = {dt:.4g} s is above the stability limit of" in text
    assert f"dt <= {lim.dt:.4g} s" in text and f"zeta = {zeta:.4g}" in text and "damping shrinks" in text
    res = exc.value.result
    assert any("above the stability limit" in w for w in res.warnings)
    # below the damped limit: no warning, no divergence, the same trajectory as before
    ok = nvib.solve(model, nvib.CentralDifference(), dt=0.9 * lim.dt, t_end=0.05)
    assert ok.success and ok.warnings == []


@pytest.mark.parametrize("scheme", [nvib.Zhai(), nvib.CEMDTS(0.45)], ids=["zhai", "cemdts"])
def test_other_explicit_schemes_have_their_own_damped_limit(scheme):
    model = _rayleigh_chain(beta=0.01)
    lim = stab.step_limit(model, scheme)
    assert lim.dt < lim.dt_undamped
    assert stab.step_warning(model, scheme, 0.95 * lim.dt) is None
    assert "above the stability limit" in stab.step_warning(model, scheme, 1.05 * lim.dt)
    res = nvib.solve(model, scheme, dt=1.05 * lim.dt, t_end=0.5, throw=False)
    assert any("above the stability limit" in w for w in res.warnings)


def test_implicit_schemes_and_pim_get_no_step_warning():
    model = _rayleigh_chain()
    for scheme in (nvib.Newmark(), nvib.GeneralizedAlpha(), nvib.PreciseIntegration()):
        assert stab.step_limit(model, scheme) is None and stab.step_warning(model, scheme, 1.0) is None


def test_an_undamped_model_above_its_limit_is_named():
    model = nvib.Model([1.0], K=[[1e4]], u0=[1.0])
    res = nvib.solve(model, nvib.CentralDifference(), dt=0.03, t_end=1.0, throw=False)
    assert res.status == nvib.Status.diverged
    assert len(res.warnings) == 1 and "dt <= 0.02 s, set by its mode of omega = 100 rad/s" in res.warnings[0]


# ---------------------------------------------------------------- the divergence bound

def _loaded_oscillator(scale: float, load: str):
    """m u'' + k u = F in units scale x m: the same physical model whatever the scale."""
    if load == "force":
        eff = [{"type": "constant_force", "measure": {"x": 1.0}, "value": 200.0}]
    else:  # a ground acceleration of 200 m/s^2 (in the model's units)
        eff = [{"type": "ground_acceleration", "signal": {"kind": "sine", "amplitude": 200.0 * scale,
                                                           "omega": 0.3}}]
    return nvib.Model([1.0 / scale], K=[[1.0 / scale]], C=[[0.2 / scale]], effects=eff, dofs=["x"])


@pytest.mark.parametrize("load", ["force", "ground"])
def test_the_divergence_bound_follows_the_model_in_other_units(load):
    """A stable run whose response is 1e11 in the model's own units (a model in nm loaded to about 100 m) is
    not called diverged: the bound is relative to the static displacement of its loads. The same model in m
    gives the same trajectory, scaled."""
    ref = nvib.solve(_loaded_oscillator(1.0, load), nvib.CentralDifference(), dt=0.05, t_end=20.0)
    nm = nvib.solve(_loaded_oscillator(1e9, load), nvib.CentralDifference(), dt=0.05, t_end=20.0)
    assert np.abs(nm.u).max() > 1e10
    np.testing.assert_allclose(nm.u, 1e9 * ref.u, rtol=1e-9, atol=1e-9 * np.abs(nm.u).max())


def test_a_blow_up_of_a_loaded_model_is_still_caught_fast():
    model = _loaded_oscillator(1e9, "force")
    res = nvib.solve(model, nvib.CentralDifference(), dt=2.5, t_end=1000.0, throw=False)
    assert res.status == nvib.Status.diverged and res.failure.step < 100
    assert "beyond the bound" in res.failure.message and "displacement scale" in res.failure.message
