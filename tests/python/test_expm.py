"""nvib.expm (the 2^N algorithm of the precise integration method) against
scipy.linalg.expm, norm-wise: ||E - E_ref||_F / ||E_ref||_F."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as sla

import nvib

SIZES = (2, 3, 5, 8, 13, 20)


def rel_error(A, squarings=20) -> float:
    E = nvib.expm(A, squarings=squarings)
    R = sla.expm(A)
    assert E.shape == R.shape
    return float(np.linalg.norm(E - R) / np.linalg.norm(R))


def random_spd(rng, n, shift):
    B = rng.standard_normal((n, n))
    return B @ B.T + shift * np.eye(n)


def state_matrix(M, K, C):
    n = M.shape[0]
    Mi = np.linalg.inv(M)
    return np.block([[np.zeros((n, n)), np.eye(n)], [-Mi @ K, -Mi @ C]])


@pytest.mark.parametrize("n", SIZES)
def test_random_matrices_unit_norm(n):
    rng = np.random.default_rng(1000 + n)
    for _ in range(5):
        A = rng.standard_normal((n, n))
        A *= rng.uniform(0.05, 1.0) / np.linalg.norm(A, 2)
        err = rel_error(A)
        assert err <= 1e-13, f"n={n}: rel. error {err:.2e}"


@pytest.mark.parametrize("ndof", (1, 2, 4, 6, 10))
def test_damped_oscillator_state_matrices(ndof):
    rng = np.random.default_rng(2000 + ndof)
    for _ in range(4):
        M = random_spd(rng, ndof, ndof)
        K = random_spd(rng, ndof, 0.1)
        w2 = sla.eigh(K, M, eigvals_only=True)
        # Rayleigh damping, about 2-5 % at the extreme modes
        C = 0.04 / np.sqrt(w2.max()) * K + 0.1 * np.sqrt(w2.min()) * M
        H = state_matrix(M, K, C)
        h = rng.uniform(0.1, 1.0) / np.linalg.norm(H, 2)
        err = rel_error(H * h)
        assert err <= 1e-13, f"{ndof} DOF, ||Hh|| = {np.linalg.norm(H * h, 2):.2f}: rel. error {err:.2e}"


@pytest.mark.parametrize("norm", (1.0, 10.0, 30.0, 100.0))
@pytest.mark.parametrize("ndof", (1, 2, 5, 10))
def test_undamped_oscillator_state_matrices_large_norm(ndof, norm):
    rng = np.random.default_rng(3000 + 7 * ndof + int(norm))
    M = np.diag(rng.uniform(1.0, 2.0, ndof))
    K = random_spd(rng, ndof, 0.5)
    H = state_matrix(M, K, np.zeros((ndof, ndof)))
    A = H * (norm / np.linalg.norm(H, 2))
    err = rel_error(A)
    assert err <= 1e-11, f"{ndof} DOF, ||Hh|| = {norm}: rel. error {err:.2e}"


@pytest.mark.parametrize("norm", (1.0, 10.0, 30.0, 100.0))
@pytest.mark.parametrize("n", (2, 5, 10, 20))
def test_skew_like_matrices_large_norm(n, norm):
    rng = np.random.default_rng(4000 + 7 * n + int(norm))
    B = rng.standard_normal((n, n))
    S = B - B.T + 1e-3 * rng.standard_normal((n, n))  # nearly skew: eigenvalues close to the imaginary axis
    A = S * (norm / np.linalg.norm(S, 2))
    err = rel_error(A)
    assert err <= 1e-11, f"n={n}, ||A|| = {norm}: rel. error {err:.2e}"


def test_exact_cases():
    assert np.array_equal(nvib.expm(np.zeros((3, 3))), np.eye(3))
    d = np.array([-2.0, -0.5, 0.0, 0.3, 1.0])
    E = nvib.expm(np.diag(d))
    assert np.allclose(E, np.diag(np.exp(d)), rtol=1e-14, atol=0.0)
    # Rotation: exp([[0, t], [-t, 0]]) = [[cos t, sin t], [-sin t, cos t]]
    for t in (0.1, 1.0, 5.0, 40.0):
        E = nvib.expm(np.array([[0.0, t], [-t, 0.0]]))
        R = np.array([[np.cos(t), np.sin(t)], [-np.sin(t), np.cos(t)]])
        assert np.max(np.abs(E - R)) <= 1e-12 * max(1.0, t)
    # Nilpotent: exp(N) = I + N + N^2/2 exactly
    N = np.triu(np.ones((4, 4)), 1)
    assert np.allclose(nvib.expm(N), np.eye(4) + N + N @ N / 2 + N @ N @ N / 6, rtol=1e-14, atol=1e-15)


def test_small_norm_keeps_the_increment():
    """e^A - I for tiny A must not be lost to round-off (the point of the incremental form)."""
    rng = np.random.default_rng(5)
    A = 1e-8 * rng.standard_normal((6, 6))
    inc = nvib.expm(A) - np.eye(6)
    ref = sla.expm(A) - np.eye(6)
    assert np.linalg.norm(inc - ref) <= 1e-7 * np.linalg.norm(ref)


def test_input_validation():
    with pytest.raises(ValueError, match=r"^A"):
        nvib.expm(np.ones((2, 3)))
    with pytest.raises(ValueError, match=r"^A"):
        nvib.expm(np.ones(3))
    with pytest.raises(ValueError, match=r"^A"):
        nvib.expm(np.array([[np.nan]]))
    with pytest.raises(ValueError, match=r"^squarings"):
        nvib.expm(np.eye(2), squarings=-1)


@pytest.mark.parametrize("squarings", (10, 20, 30))
def test_squarings_parameter(squarings):
    rng = np.random.default_rng(6)
    A = rng.standard_normal((5, 5))
    A /= np.linalg.norm(A, 2)
    assert rel_error(A, squarings) <= 1e-12
