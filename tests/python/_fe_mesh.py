"""A generated finite-element model like the ones engineers bring: a 3-D elastic block of trilinear
hexahedra (8 nodes, 2 x 2 x 2 Gauss points, isotropic linear elasticity) with its stiffness K and
consistent mass M, clamped at z = 0, assembled with scipy.sparse. ``nonlinear_model`` adds a few
hardening springs to ground and Rayleigh damping, as in the real models the convergence test is
meant for."""

from __future__ import annotations

import itertools

import numpy as np
import scipy.sparse as sp

_GAUSS = np.array([-1.0, 1.0]) / np.sqrt(3.0)
_CORNERS = np.array([[-1, -1, -1], [1, -1, -1], [1, 1, -1], [-1, 1, -1],
                     [-1, -1, 1], [1, -1, 1], [1, 1, 1], [-1, 1, 1]], dtype=float)


def hexahedron(size: tuple[float, float, float], E: float, nu: float, rho: float) -> tuple[np.ndarray, np.ndarray]:
    """Stiffness and consistent mass (24 x 24) of a brick of edges ``size``."""
    lam = E * nu / ((1 + nu) * (1 - 2 * nu))
    mu = E / (2 * (1 + nu))
    D = np.zeros((6, 6))
    D[:3, :3] = lam
    D[np.arange(3), np.arange(3)] += 2 * mu
    D[np.arange(3, 6), np.arange(3, 6)] = mu
    half = np.asarray(size, dtype=float) / 2
    det = float(np.prod(half))
    Ke = np.zeros((24, 24))
    Me = np.zeros((24, 24))
    for xi, eta, zeta in itertools.product(_GAUSS, _GAUSS, _GAUSS):
        p = np.array([xi, eta, zeta])
        N = np.prod(1 + _CORNERS * p, axis=1) / 8
        dN = np.empty((8, 3))
        for a in range(3):
            others = [b for b in range(3) if b != a]
            dN[:, a] = _CORNERS[:, a] * np.prod(1 + _CORNERS[:, others] * p[others], axis=1) / 8 / half[a]
        B = np.zeros((6, 24))
        for i in range(8):
            bx, by, bz = dN[i]
            B[:, 3 * i:3 * i + 3] = [[bx, 0, 0], [0, by, 0], [0, 0, bz], [by, bx, 0], [0, bz, by], [bz, 0, bx]]
        Ke += B.T @ D @ B * det
        Nm = np.kron(N, np.eye(3))
        Me += rho * Nm.T @ Nm * det
    return Ke, Me


def block(nx: int, ny: int, nz: int, size=(1.0, 1.0, 1.0), E=3e10, nu=0.2, rho=2500.0):
    """K, M (CSC) of an nx x ny x nz block of bricks, the nodes at z = 0 clamped; 3 DOFs a node."""
    Ke, Me = hexahedron(size, E, nu, rho)
    node = np.arange((nx + 1) * (ny + 1) * (nz + 1)).reshape(nz + 1, ny + 1, nx + 1)
    rows, cols, kv, mv = [], [], [], []
    for k, j, i in itertools.product(range(nz), range(ny), range(nx)):
        corners = [node[k, j, i], node[k, j, i + 1], node[k, j + 1, i + 1], node[k, j + 1, i],
                   node[k + 1, j, i], node[k + 1, j, i + 1], node[k + 1, j + 1, i + 1], node[k + 1, j + 1, i]]
        dofs = np.array([[3 * c, 3 * c + 1, 3 * c + 2] for c in corners]).ravel()
        rows.append(np.repeat(dofs, 24))
        cols.append(np.tile(dofs, 24))
        kv.append(Ke.ravel())
        mv.append(Me.ravel())
    n_all = 3 * node.size
    r, c = np.concatenate(rows), np.concatenate(cols)
    K = sp.csc_matrix((np.concatenate(kv), (r, c)), shape=(n_all, n_all))
    M = sp.csc_matrix((np.concatenate(mv), (r, c)), shape=(n_all, n_all))
    free = np.arange(3 * (nx + 1) * (ny + 1), n_all)  # every node above z = 0
    K = K[free][:, free]
    M = M[free][:, free]
    K = ((K + K.T) / 2).tocsc()
    M = ((M + M.T) / 2).tocsc()
    return K, M


def rayleigh(K, M, zeta: float, w1: float, w2: float):
    a = 2 * zeta * w1 * w2 / (w1 + w2)
    b = 2 * zeta / (w1 + w2)
    return (a * M + b * K).tocsc()


def nonlinear_model(nx: int, ny: int, nz: int, size=(1.0, 1.0, 1.0), springs: int = 4, a: float = 1e4,
                    amplitude: float = 3.0):
    """The block with Rayleigh damping of 2 % on modes 1 and 3, ``springs`` hardening springs to ground
    (k0 a tenth of the largest diagonal stiffness, f = k0 (d + a d^3)) on the x DOFs of top nodes, and a
    sine ground acceleration along x at the first mode's frequency. Returns (K, M, C, spring DOFs, k0,
    a, r, omega, amplitude, T1): what a plain loop needs as well as nvib."""
    import scipy.sparse.linalg as spla

    K, M = block(nx, ny, nz, size)
    n = K.shape[0]
    w = np.sqrt(np.sort(np.abs(spla.eigsh(K, k=3, M=M, sigma=0, which="LM", return_eigenvectors=False))))
    C = rayleigh(K, M, 0.02, w[0], w[2])
    top = np.arange(n - 3 * (nx + 1) * (ny + 1), n, 3)[:springs]
    k0 = 0.1 * float(K.diagonal().max())
    r = np.zeros(n)
    r[0::3] = 1.0
    return K, M, C, top, k0, a, r, float(w[0]), amplitude, 2 * np.pi / float(w[0])


def nvib_model(parts):
    import nvib

    K, M, C, top, k0, a, r, omega, amplitude, _ = parts
    effects = [{"type": "hardening_spring", "measure": {int(i): 1.0}, "k0": k0, "a": a} for i in top]
    effects.append({"type": "ground_acceleration", "measure": {int(i): 1.0 for i in np.flatnonzero(r)},
                    "signal": {"kind": "sine", "amplitude": amplitude, "omega": omega}})
    return nvib.Model(M, K=K, C=C, effects=effects)


def scipy_newmark_newton(parts, dt: float, steps: int, rtol: float = 1e-8):
    """The loop an engineer writes: Newmark (1/2, 1/4), full Newton with a sparse LU of the iteration
    matrix each iteration, stopping when the increment is below rtol of the displacement. Returns the
    final u and the number of Newton iterations (linear solves)."""
    import scipy.sparse.linalg as spla

    K, M, C, top, k0, a, r, omega, amplitude, _ = parts
    n = K.shape[0]
    c0, c1 = 4 / dt**2, 2 / dt
    u, v = np.zeros(n), np.zeros(n)
    acc = np.zeros(n)
    Mr = M @ r
    Kc = (K + c1 * C + c0 * M).tocsc()
    iters = 0
    for s in range(1, steps + 1):
        t = s * dt
        P = -Mr * amplitude * np.sin(omega * t)
        u1 = u.copy()
        for _ in range(50):
            a1 = c0 * (u1 - u) - 4 / dt * v - acc
            v1 = v + dt / 2 * (acc + a1)
            d = u1[top]
            fs = k0 * (d + a * d**3)
            R = M @ a1 + C @ v1 + K @ u1 - P
            R[top] += fs
            kt = np.zeros(n)
            kt[top] = k0 * (1 + 3 * a * d**2)
            S = (Kc + __import__("scipy.sparse", fromlist=["diags"]).diags(kt)).tocsc()
            du = -spla.splu(S).solve(R)
            u1 += du
            iters += 1
            if np.max(np.abs(du)) <= rtol * max(np.max(np.abs(u1)), 1e-300):
                break
        else:
            raise RuntimeError(f"the plain loop did not converge at step {s}")
        a1 = c0 * (u1 - u) - 4 / dt * v - acc
        v = v + dt / 2 * (acc + a1)
        u, acc = u1, a1
    return u, iters
