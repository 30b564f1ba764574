"""Rayleigh damping: the damping ratios of the linearised damped model, from its complex
eigenvalues, are the requested ones at the chosen modes (and follow alpha/(2w) + beta w/2 at the
others); the same from a scene file; bad input named."""

import numpy as np
import pytest

import nvib


def modal_damping(model):
    """(w, zeta) of each mode from the eigenvalues of the first-order system of M, K0, C."""
    M = model.mass_matrix
    K, C = model.tangent_matrices(model.u0, np.zeros(model.n))
    n = model.n
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-np.linalg.solve(M, K), -np.linalg.solve(M, C)]])
    lam = np.linalg.eigvals(A)
    lam = lam[lam.imag > 0]  # one of each conjugate pair (every mode underdamped here)
    w = np.abs(lam)
    order = np.argsort(w)
    return w[order], (-lam.real / np.abs(lam))[order]


def test_modes_get_the_requested_ratio():
    base = nvib.load_scene("building")
    damped = nvib.rayleigh(base, zeta=0.05, modes=[1, 3])
    w, zeta = modal_damping(damped)
    np.testing.assert_allclose(zeta[[0, 2]], 0.05, rtol=0, atol=1e-10)
    a, b = damped.rayleigh["alpha"], damped.rayleigh["beta"]
    np.testing.assert_allclose(zeta, a / (2 * w) + b * w / 2, rtol=0, atol=1e-10)  # classical damping
    np.testing.assert_allclose(w, base.linearized_frequencies(), rtol=1e-9)  # frequencies of the undamped model
    # two ratios at two frequencies (0.02 and 0.07 would need alpha < 0, refused in test_refusals.py)
    pair = nvib.rayleigh(base, zeta=[0.03, 0.05], omegas=base.linearized_frequencies()[[1, 4]])
    np.testing.assert_allclose(modal_damping(pair)[1][[1, 4]], [0.03, 0.05], rtol=0, atol=1e-10)


def test_alpha_beta_assemble_into_c_and_dissipate():
    base = nvib.load_scene("building")
    damped = nvib.rayleigh(base, alpha=0.3, beta=2e-3)
    K0, _ = base.tangent_matrices(base.u0, np.zeros(6))
    np.testing.assert_allclose(damped.C.toarray(), 0.3 * base.mass_matrix + 2e-3 * K0, rtol=1e-15, atol=0)
    res = nvib.solve(damped, nvib.CEMDTS(), dt=1e-3, t_end=2.0, energy=True)
    assert res.energy.dissipated[-1] > 0 and abs(res.energy.relative_balance_error()) < 1e-2
    assert nvib.solve(base, nvib.CEMDTS(), dt=1e-3, t_end=2.0, energy=True).energy.dissipated[-1] == 0


SCENE = """
[scene]
name = "two"
[dofs]
names = ["x1", "x2"]
mass = [1.0, 2.0]
[[effect]]
type = "spring"
measure = {{ x1 = 1.0 }}
k = 100.0
[[effect]]
type = "hardening_spring"
measure = {{ x2 = 1.0, x1 = -1.0 }}
k0 = 50.0
a = 3.0
[damping]
{damping}
"""


def test_scene_damping(tmp_path):
    path = tmp_path / "two.toml"
    path.write_text(SCENE.format(damping="rayleigh = { zeta = 0.04, modes = [1, 2] }"), encoding="utf-8")
    model = nvib.load_scene(str(path))
    np.testing.assert_allclose(modal_damping(model)[1], 0.04, rtol=0, atol=1e-10)
    path.write_text(SCENE.format(damping="rayleigh = { zeta = 0.04, mode = [1, 2] }"), encoding="utf-8")
    with pytest.raises(nvib.SceneError, match=r"two.toml: \[damping\] rayleigh.mode: unknown key"):
        nvib.load_scene(str(path))
    path.write_text(SCENE.format(damping="rayleigh = { zeta = 0.04, modes = [1, 5] }"), encoding="utf-8")
    with pytest.raises(nvib.SceneError, match=r"two.toml: \[damping\] rayleigh.modes: mode 5 asked of a model with 2"):
        nvib.load_scene(str(path))


def test_bad_arguments_named():
    base = nvib.load_scene("building")
    for kw, arg in ((dict(zeta=0.05, modes=[1, 1]), "modes"), (dict(zeta=1.5, modes=[1, 2]), "zeta"),
                    (dict(zeta=0.05, alpha=1.0), "alpha, beta"), (dict(zeta=0.05), "omegas, modes"),
                    (dict(modes=[1, 2]), "zeta"), (dict(zeta=0.05, omegas=[3.0, 3.0]), "omegas")):
        with pytest.raises(nvib.ArgumentError) as exc:
            nvib.rayleigh(base, **kw)
        assert exc.value.argument == arg
    assert nvib.rayleigh_coefficients(0.05, [2.0, 20.0]) == pytest.approx((0.05 * 2 * 2 * 20 / 22, 0.05 * 2 / 22),
                                                                          rel=1e-14)


def test_a_damped_copy_checks_its_step_against_its_own_modes():
    """rayleigh() builds a new model from the given one; what the stability check keeps on a model (its modes
    and their damping ratios) must not follow it there: the damping shrinks an explicit scheme's limit. The
    undamped two-storey model's limit is 0.01236 s; with beta = 0.01 its top mode has zeta = 0.81 and the
    limit falls to 0.00351 s."""
    from nvib.analysis import stability

    undamped = nvib.Model([1.0, 1.0], K=[[2e4, -1e4], [-1e4, 1e4]])
    assert stability.step_warning(undamped, nvib.CentralDifference(), 0.011) is None  # its modes are now kept
    damped = nvib.rayleigh(undamped, alpha=0.0, beta=0.01)
    note = stability.step_warning(damped, nvib.CentralDifference(), 0.011)
    assert note is not None and "dt <= 0.003511 s" in note
    # a copy with the same K and C (other signals, as a batch makes) keeps them: same answer, no new eigensolve
    same = damped._rebuilt(effects=None)
    assert same._linear_modes is damped._linear_modes
    assert stability.step_warning(same, nvib.CentralDifference(), 0.011) == note
