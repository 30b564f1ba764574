"""Sparse models: the sparse and dense linear solvers and assemblies give the same trajectories,
effect arrays equal effects one by one, generated scenes, and what large models must not do
(allocate n^2, hide their memory, run PIM at any size)."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest
from scipy import sparse

import nvib

from _registry import scheme_variants, with_newton

IMPLICIT = scheme_variants(explicit=False)


def rel(a, b) -> float:
    return float(np.max(np.abs(a - b)) / max(np.max(np.abs(b)), 1e-300))


# ---------------------------------------------------------------- sparse, banded and dense solvers agree
@pytest.mark.parametrize("name", list(IMPLICIT))
@pytest.mark.parametrize("scene", nvib.scene_names())
def test_sparse_banded_and_dense_solvers_agree_on_every_scene(scene, name):
    model = nvib.load_scene(scene)
    dt = model.scene["dt"]
    runs = {}
    for choice in ("dense", "sparse", "banded"):
        scheme = with_newton(IMPLICIT[name], linear_solver=choice)
        try:
            runs[choice] = nvib.solve(model, scheme, dt=dt, t_end=min(model.scene["t_end"], 300 * dt), throw=False)
        except ValueError as e:  # a nonsymmetric iteration matrix has no band LDL^T, and says so
            assert choice == "banded" and "not symmetric" in str(e), str(e)
    d = runs["dense"]
    assert d.stats.linear_solver in ("dense LU", "")  # "" where no factorisation was needed
    assert runs["sparse"].stats.linear_solver in ("sparse LDLT", "sparse LU", "")
    if "banded" in runs:  # (or the sparse LU it falls back to where a pivot needs an exchange)
        assert runs["banded"].stats.linear_solver in ("banded LDLT", "sparse LU", "")
    for choice in runs.keys() - {"dense"}:
        s = runs[choice]
        assert d.status == s.status and len(d.t) == len(s.t)
        # modified Newton converges linearly: where another solver's round-off changes its iteration count,
        # the accepted iterates differ by the tolerance's share of an increment (measured: up to 1.6e-12)
        bound = 1e-11 if "modified" in name else 1e-12
        assert rel(s.u, d.u) <= bound, (scene, name, choice)
        # v_{n+1} = v_n + (gamma / (beta dt)) (u_{n+1} - u_n - ...): the round-off of u, relative to max |u|,
        # reaches v multiplied by gamma / (beta dt) (2 / dt at most here; measured: 2.6e-12 of max |v| on the vehicle)
        v_scale = max(np.max(np.abs(d.v)), 4.0 * np.max(np.abs(d.u)) / dt)
        assert np.max(np.abs(s.v - d.v)) <= bound * v_scale, (scene, name, choice)


def random_model(seed: int, n: int = 40):
    """A random chain-with-shortcuts model of every stiffness law, dampers and loads."""
    rng = np.random.default_rng(seed)
    i = rng.integers(0, n, 3 * n)
    j = rng.integers(-1, n, 3 * n)
    keep = i != j
    i, j = i[keep], j[keep]
    third = len(i) // 3
    effects = [
        {"type": "hardening_spring", "i": i[:third], "j": j[:third], "k0": rng.uniform(50, 150, third), "a": 5.0},
        {"type": "cubic_spring", "i": i[third:2 * third], "j": j[third:2 * third], "k3": 200.0},
        {"type": "spring", "i": np.arange(n), "k": rng.uniform(10, 20, n)},
        {"type": "damper", "i": i[2 * third:], "j": j[2 * third:], "c": rng.uniform(0.1, 0.3, len(i) - 2 * third)},
        {"type": "power_damper", "i": np.arange(n), "c": 0.05, "p": 1.5},
        {"type": "harmonic_force", "i": np.arange(0, n, 3), "amplitude": 2.0, "omega": 7.0},
    ]
    return nvib.Model(rng.uniform(1.0, 2.0, n), effects=effects, u0=rng.normal(0, 0.05, n), v0=rng.normal(0, 0.1, n))


@pytest.mark.parametrize("seed", range(4))
def test_sparse_and_dense_solvers_agree_on_random_models(seed):
    model = random_model(seed)
    for name, scheme in IMPLICIT.items():
        d = nvib.solve(model, with_newton(scheme, linear_solver="dense"), dt=2e-3, t_end=0.5)
        s = nvib.solve(model, with_newton(scheme, linear_solver="sparse"), dt=2e-3, t_end=0.5)
        assert s.stats.linear_solver == "sparse LDLT" and d.stats.linear_solver == "dense LU"
        assert rel(s.u, d.u) <= 1e-12 and rel(s.v, d.v) <= 1e-12, (seed, name)


def test_the_automatic_choice_is_stated():
    # a chain's iteration matrix is tridiagonal: its band, at every size
    small, big = nvib.scenes.chain(10), nvib.scenes.chain(200)
    u0 = np.full(200, 1e-4)
    assert nvib.solve(small, nvib.Newmark(), dt=1e-3, t_end=0.01, u0=u0[:10]).stats.linear_solver == "banded LDLT"
    assert nvib.solve(big, nvib.Newmark(), dt=1e-3, t_end=0.01, u0=u0).stats.linear_solver == "banded LDLT"
    # a lattice's band (nx) holds far more than its entries: sparse LDL^T, supernodal where its factor's
    # fronts are large (20 x 20: 13.6 flops per entry of L; 10 x 10: 7.6), simplicial below; small, dense LU
    for nx, solver in ((5, "dense LU"), (10, "sparse LDLT"), (20, "supernodal LDLT")):
        lattice = nvib.scenes.lattice(nx, nx)
        assert nvib.solve(lattice, nvib.Newmark(), dt=1e-3, t_end=0.002).stats.linear_solver == solver, nx
    # a nonsymmetric linear stiffness: sparse LU
    K = sparse.diags([np.full(199, 50.0)], [1], shape=(200, 200))
    follower = nvib.Model(np.ones(200), K=K, effects=[{"type": "spring", "i": np.arange(200), "k": 1e4}], u0=u0)
    assert nvib.solve(follower, nvib.Newmark(), dt=1e-3, t_end=0.01).stats.linear_solver == "sparse LU"
    with pytest.raises(ValueError, match="^linear_solver: 'banded' factorises a symmetric iteration matrix"):
        nvib.solve(follower, nvib.Newmark(newton=nvib.Newton(linear_solver="banded")), dt=1e-3, t_end=0.01)
    for choice in ("sparse", "banded"):
        with pytest.raises(ValueError, match=f"^linear_solver: '{choice}' needs a model whose tangent"):
            callable_model = nvib.Model([1.0], force=lambda u, v, t: u, u0=[1.0])
            nvib.solve(callable_model, nvib.Newmark(newton=nvib.Newton(linear_solver=choice)), dt=1e-3, t_end=0.01)


def test_the_symmetry_of_K_and_C_is_read_entry_by_entry():
    # S is factorised symmetrically (LDL^T) only where K and C equal their transposes to 1e-14 of their
    # largest entry, an entry without a stored twin counting as one against 0. A chain with a long-range
    # pair (0, 7): mirrored, mirrored up to 1e-15 or up to 1e-9 of it, one-sided (a zero twin given
    # explicitly, or none), or zero both ways. (100 DOFs: above the dense LU's sizes, and no band.)
    n = 100
    rows = list(range(n)) + list(range(1, n)) + list(range(n - 1))
    cols = list(range(n)) + list(range(n - 1)) + list(range(1, n))
    vals = [2e3] * n + [-1e3] * (2 * n - 2)

    def solver(k07, k70, where, twin_stored=True):
        r, c, x = rows + [0], cols + [7], vals + [k07]
        if twin_stored:
            r, c, x = r + [7], c + [0], x + [k70]
        A = sparse.csc_matrix((x, (r, c)), shape=(n, n))
        assert A.nnz == 3 * n - 2 + 1 + twin_stored  # explicit zeros kept
        chain = sparse.csc_matrix((vals, (rows, cols)), shape=(n, n))
        parts = {"K": A} if where == "K" else {"K": chain, "C": A * 1e-3}
        model = nvib.Model(np.ones(n), **parts, effects=[{"type": "hardening_spring", "i": [3], "k0": 1e3, "a": 1.0}])
        return nvib.solve(model, nvib.Newmark(), dt=1e-3, t_end=0.002, u0=np.full(n, 1e-3)).stats.linear_solver

    def symmetric(where, *args, **kw):  # LDL^T, or LU where S is not symmetric (with the low-rank update or not)
        name = solver(*args, where, **kw)
        assert name.split(" + ")[0] in ("sparse LDLT", "supernodal LDLT", "banded LDLT", "sparse LU"), name
        return "LDLT" in name

    for where in ("K", "C"):
        assert symmetric(where, 5.0, 5.0)
        assert symmetric(where, 5.0, 5.0 * (1 + 1e-15))
        assert not symmetric(where, 5.0, 5.0 * (1 + 1e-9))
        assert not symmetric(where, 5.0, 0.0)
        assert not symmetric(where, 5.0, None, twin_stored=False)
        assert symmetric(where, 0.0, 0.0)  # (zeros dropped: the chain alone, banded)


def test_a_band_pivot_that_needs_an_exchange_goes_to_the_sparse_lu():
    # S = 16 M + K (Newmark at dt = 0.5 s, exact in binary) with S[0, 0] = 16 - 1016 + 1000 = 0: LDL^T without
    # pivoting meets a zero pivot on a regular S; the LU with pivoting solves it, as the dense LU does
    effects = [{"type": "spring", "measure": {0: 1.0}, "k": -1016.0},
               {"type": "spring", "measure": {1: 1.0, 0: -1.0}, "k": 1000.0},
               {"type": "harmonic_force", "measure": {1: 1.0}, "amplitude": 1.0, "omega": 1.0}]
    model = nvib.Model([1.0, 1.0], effects=effects)
    runs = {c: nvib.solve(model, nvib.Newmark(newton=nvib.Newton(linear_solver=c)), dt=0.5, t_end=5.0)
            for c in ("banded", "dense")}
    assert runs["banded"].stats.linear_solver == "sparse LU" and runs["dense"].stats.linear_solver == "dense LU"
    assert rel(runs["banded"].u, runs["dense"].u) <= 1e-12


# ---------------------------------------------------------------- sparse and dense assembly agree
@pytest.mark.parametrize("name", list(scheme_variants()))
def test_sparse_and_dense_matrices_and_masses_give_the_same_run(name):
    scheme = scheme_variants()[name]
    n = 30
    rng = np.random.default_rng(3)
    A = rng.normal(size=(n, n)) * (rng.uniform(size=(n, n)) < 0.1)
    K = A @ A.T + 100.0 * np.eye(n)
    C = 0.01 * K
    M = np.diag(rng.uniform(1, 2, n)) + 0.1 * np.diag(np.ones(n - 1), 1) + 0.1 * np.diag(np.ones(n - 1), -1)
    eff = [{"type": "cubic_spring", "i": np.arange(n), "k3": 1e3}]
    u0 = rng.normal(0, 0.01, n)
    dense = nvib.Model(M, K=K, C=C, effects=eff, u0=u0)
    sp = nvib.Model(sparse.csc_matrix(M), K=sparse.csr_matrix(K), C=sparse.coo_matrix(C), effects=eff, u0=u0)
    assert dense._core.mass_kind == "dense" and sp._core.mass_kind == "sparse"
    a = nvib.solve(dense, scheme, dt=1e-3, t_end=0.2)
    b = nvib.solve(sp, scheme, dt=1e-3, t_end=0.2)
    assert rel(b.u, a.u) <= 1e-12 and rel(b.v, a.v) <= 1e-12
    np.testing.assert_array_equal(sp.K.toarray(), K)
    np.testing.assert_array_equal(sp.mass_sparse.toarray(), M)


@pytest.mark.parametrize("name", ["CentralDifference", "Newmark", "GeneralizedAlpha-rho0.8-modified"])
def test_a_solid_whose_factors_fill_in_runs_supernodal_and_as_dense(name):
    # a 3-D block of bricks (540 DOFs): its consistent mass and its iteration matrix have factors with
    # large fronts (the supernodal factorisation); the same model dense (dense Cholesky of the mass,
    # dense LU) gives the same run to round-off
    from _fe_mesh import block

    scheme = scheme_variants()[name]
    K, M = block(5, 5, 5)
    n = K.shape[0]
    u0 = np.sin(np.arange(n)) * 1e-4
    eff = [{"type": "cubic_spring", "i": np.arange(n - 30, n), "k3": 1e14}]
    sp = nvib.Model(M, K=K, C=1e-4 * K, effects=eff, u0=u0)
    dense = nvib.Model(M.toarray(), K=K.toarray(), C=1e-4 * K.toarray(), effects=eff, u0=u0)
    dt = 2e-5 if scheme.is_explicit else 2e-4
    runs = {}
    for label, model, solver in (("sparse", sp, "sparse"), ("auto", sp, "auto"), ("dense", dense, "dense")):
        runs[label] = nvib.solve(model, with_newton(scheme, linear_solver=solver), dt=dt, t_end=200 * dt)
    if not scheme.is_explicit:
        assert runs["sparse"].stats.linear_solver == "supernodal LDLT"
        # 30 nonlinear DOFs of 540: the block's linear part factorised once, the springs as an update
        assert runs["auto"].stats.linear_solver == "supernodal LDLT + low-rank update"
        assert runs["auto"].stats.num_newton_iters == runs["sparse"].stats.num_newton_iters
    # measured: 1.1e-15 (the springs make the runs differ from the linear block's by 6e-5 to 8e-5)
    for label in ("sparse", "auto"):
        assert rel(runs[label].u, runs["dense"].u) <= 1e-13 and rel(runs[label].v, runs["dense"].v) <= 1e-13


def test_rayleigh_damping_is_recognised_and_gives_the_products_to_round_off():
    # C = alpha m + beta K on a lumped mass m: K u + C v taken as K (u + beta v) + alpha m v (half the
    # memory traffic); C on K's pattern otherwise: K's indices read once; a small model keeps the rows
    from _fe_mesh import block

    K, M = block(5, 5, 5)
    n = K.shape[0]
    m = np.asarray(M.sum(axis=1)).ravel()
    alpha, beta = 0.8, 2e-4
    C = (alpha * sparse.diags(m) + beta * K).tocsc()  # as an engineer assembles it
    lumped = nvib.Model(m, K=K, C=C)
    assert lumped.linear_product == "rayleigh"
    assert lumped.linear_product_block == 3  # a brick mesh: K held by the 3 x 3 blocks of its nodes
    assert nvib.Model(M, K=K, C=(alpha * M + beta * K).tocsc()).linear_product == "shared"
    assert nvib.Model(M, K=K, C=(alpha * M + beta * K).tocsc()).linear_product_block == 3
    off = C.copy()
    off[0, 0] *= 1 + 1e-9  # not of the form: the shared pattern
    assert nvib.Model(m, K=K, C=off).linear_product == "shared"
    one_damper = sparse.csc_matrix(([2.0, -2.0, -2.0, 2.0], ([0, 0, n - 1, n - 1], [0, n - 1, 0, n - 1])), shape=(n, n))
    assert nvib.Model(m, K=K, C=one_damper).linear_product == "rows"
    tri = sparse.diags([-np.ones(n - 1), 2 * np.ones(n), -np.ones(n - 1)], [-1, 0, 1]).tocsc()
    assert nvib.Model(m, K=tri, C=0.1 * tri).linear_product == "band"
    assert nvib.scenes.chain(6).linear_product == "none"  # its springs and dampers are effects
    small = block(1, 1, 2)[0]  # 36 DOFs: under 4096 stored entries, the rows' sums
    assert nvib.Model(np.ones(small.shape[0]), K=small, C=1e-3 * small).linear_product == "rows"

    rng = np.random.default_rng(7)
    u, v = rng.standard_normal(n), rng.standard_normal(n)
    f = lumped.evaluate_force(u, v)
    bound = 8 * np.finfo(float).eps * (abs(K) @ abs(u) + abs(C) @ abs(v))
    assert np.all(np.abs(f - (K @ u + C @ v)) <= bound)

    # a free vibration by central difference against the same recurrence in NumPy with C as given
    # (u += h v + h^2/2 a; the damping force at v + h a; v += h/2 (a + a_new)); measured 2e-15
    u0 = np.sin(np.arange(n)) * 1e-4
    dt, steps = 2e-5, 300
    run = nvib.solve(lumped, nvib.CentralDifference(), dt=dt, t_end=steps * dt, u0=u0, save_every=steps)
    uu, vv = u0.copy(), np.zeros(n)
    a = -(K @ uu) / m
    for _ in range(steps):
        uu += dt * vv + 0.5 * dt * dt * a
        a_new = -(K @ uu + C @ (vv + dt * a)) / m
        vv += 0.5 * dt * (a + a_new)
        a = a_new
    assert rel(run.u[-1], uu) <= 1e-13 and rel(run.v[-1], vv) <= 1e-13


def test_sparse_mass_and_matrices_are_checked():
    with pytest.raises(ValueError, match="^mass: the mass matrix is not symmetric"):
        nvib.Model(sparse.csc_matrix(np.array([[1.0, 0.5], [0.0, 1.0]])))
    with pytest.raises(ValueError, match="^mass: the sparse mass matrix is not positive definite"):
        nvib.Model(sparse.csc_matrix(np.array([[1.0, 2.0], [2.0, 1.0]])))
    with pytest.raises(ValueError, match=r"^K: expected shape \(2, 2\)"):
        nvib.Model(np.ones(2), K=sparse.eye(3))
    with pytest.raises(ValueError, match="^C: contains NaN or Inf"):
        nvib.Model(np.ones(2), C=sparse.diags([np.array([1.0, np.nan])], [0]))
    with pytest.raises(ValueError, match="^mass: a dense mass of 2001 DOFs would take .* give it as a sparse matrix"):
        nvib.Model(np.eye(2001) + 1e-3 * np.eye(2001, k=1) + 1e-3 * np.eye(2001, k=-1))
    assert nvib.Model(sparse.diags([np.array([1.0, 2.0])], [0]))._core.mass_kind == "diagonal"


# ---------------------------------------------------------------- effect arrays
def chain_effects(n, as_arrays: bool):
    c = 0.1 * (1 + np.arange(1, n) / n)
    if as_arrays:
        return [{"type": "hardening_spring", "i": np.arange(n), "j": np.arange(n) - 1, "k0": 1e4, "a": 10.0},
                {"type": "damper", "i": np.arange(1, n), "j": np.arange(n - 1), "c": c},
                {"type": "constant_force", "i": [n - 1], "value": 3.0}]
    eff = [{"type": "hardening_spring", "measure": {0: 1.0}, "k0": 1e4, "a": 10.0}]
    eff += [{"type": "hardening_spring", "measure": {i: 1.0, i - 1: -1.0}, "k0": 1e4, "a": 10.0} for i in range(1, n)]
    eff += [{"type": "damper", "measure": {i: 1.0, i - 1: -1.0}, "c": c[i - 1]} for i in range(1, n)]
    return eff + [{"type": "constant_force", "measure": {n - 1: 1.0}, "value": 3.0}]


@pytest.mark.parametrize("name", list(scheme_variants()))
def test_arrays_equal_effects_one_by_one(name):
    scheme = scheme_variants()[name]
    n = 80
    u0 = np.linspace(0.0, 0.01, n)
    one = nvib.Model(np.ones(n), effects=chain_effects(n, False), u0=u0)
    arr = nvib.Model(np.ones(n), effects=chain_effects(n, True), u0=u0)
    assert [len(a) for a in arr.effect_arrays] == [n, n - 1, 1]
    # single linear dampers are assembled into C; an array of them is evaluated by its own kernel
    assert one._core.num_evaluated_effects == n and arr._core.num_evaluated_effects == 2 * n - 1
    assert one.C.nnz == arr.C.nnz == 3 * n - 2  # the dampers shown in C either way
    np.testing.assert_allclose(arr.C.toarray(), one.C.toarray(), rtol=1e-15)
    a = nvib.solve(one, scheme, dt=1e-3, t_end=0.1, energy=True)
    b = nvib.solve(arr, scheme, dt=1e-3, t_end=0.1, energy=True)
    # the damping forces are summed in another order (a matrix product against the kernel): round-off
    assert rel(b.u, a.u) <= 1e-13 and rel(b.v, a.v) <= 1e-13
    np.testing.assert_allclose(b.energy.total, a.energy.total, rtol=1e-12)
    # without the dampers the same operations come in the same order: bit for bit
    undamped = [e for e in chain_effects(n, True) if e["type"] != "damper"]
    undamped_one = [e for e in chain_effects(n, False) if e["type"] != "damper"]
    c = nvib.solve(nvib.Model(np.ones(n), effects=undamped_one, u0=u0), scheme, dt=1e-3, t_end=0.1)
    d = nvib.solve(nvib.Model(np.ones(n), effects=undamped, u0=u0), scheme, dt=1e-3, t_end=0.1)
    assert np.array_equal(c.u, d.u) and np.array_equal(c.v, d.v)


def test_arrays_accept_names_the_ground_and_per_effect_parameters(tmp_path):
    m = nvib.Model([1.0, 2.0, 3.0], dofs=["a", "b", "c"], effects=[
        {"type": "spring", "i": ["a", "b", "c"], "j": [-1, "a", "b"], "k": [10.0, 20.0, 30.0]}])
    np.testing.assert_array_equal(m.K.toarray(), [[30, -20, 0], [-20, 50, -30], [0, -30, 30]])
    arr = m.effect_arrays[0]
    assert arr.type == "spring" and list(arr.i) == [0, 1, 2] and list(arr.j) == [-1, 0, 1]
    np.testing.assert_array_equal(arr.parameters["k"], [10.0, 20.0, 30.0])
    # in a scene file
    path = tmp_path / "s.toml"
    path.write_text('[scene]\nname = "s"\n[dofs]\nnames = ["a", "b"]\nmass = [1.0, 1.0]\n'
                    '[[effect]]\ntype = "hardening_spring"\ni = ["a", "b"]\nj = [-1, "a"]\nk0 = 100.0\na = [1.0, 2.0]\n')
    s = nvib.load_scene(str(path))
    assert len(s.effect_arrays) == 1 and s._core.num_evaluated_effects == 2


@pytest.mark.parametrize("spec, match", [
    ({"type": "spring", "i": [0, 1], "k": [1.0, 2.0, 3.0]}, r"^effects\[0\]\.k: expected one value or 2"),
    ({"type": "spring", "i": [0, 5], "k": 1.0}, r"^effects\[0\]\.i\[1\]: DOF index 5 is out of range"),
    ({"type": "spring", "i": [0, 1], "j": [0, -1], "k": 1.0}, r"^effects\[0\]\.j\[0\]: equals i\[0\]"),
    ({"type": "spring", "i": [0, 1], "j": [-1], "k": 1.0}, r"^effects\[0\]\.j: expected 2 entries"),
    ({"type": "power_damper", "i": [0, 1], "c": 1.0, "p": [1.0, -1.0]}, r"^effects\[0\]\.p\[1\]: the exponent"),
    ({"type": "hardening_spring", "i": [0], "k0": 1.0}, r"^effects\[0\]\.a: missing parameter"),
    ({"type": "spring", "i": [0], "k": np.nan}, r"^effects\[0\]\.k: spring needs a finite k"),
    ({"type": "spring", "i": ["q"], "k": 1.0}, r"^effects\[0\]\.i: unknown DOF 'q'"),
    ({"type": "spring", "i": [0], "kk": 1.0}, r"^effects\[0\]\.kk: unknown parameter of spring"),
    ({"type": "ground_acceleration", "i": [0], "signal": {"kind": "sine", "amplitude": 1.0, "omega": 1.0}},
     r"^effects\[0\]\.type: a ground acceleration acts on the whole model"),
])
def test_bad_arrays_name_the_entry(spec, match):
    with pytest.raises(ValueError, match=match):
        nvib.Model(np.ones(3), effects=[spec])


# ---------------------------------------------------------------- generated scenes
def test_chain_of_six_without_damping_is_the_building():
    chain, building = nvib.scenes.chain(6, damping_ratio=0.0), nvib.load_scene("building")
    for scheme in (nvib.CEMDTS(), nvib.Newmark()):
        a = nvib.solve(chain, scheme, dt=1e-3, t_end=1.0)
        b = nvib.solve(building, scheme, dt=1e-3, t_end=1.0)
        assert np.array_equal(a.u, b.u)


def test_lattice_pattern_and_its_fill_in():
    lat = nvib.scenes.lattice(6, 5)
    assert lat.n == 30 and lat.dofs[7] == "n1_1"
    K = lat.K.toarray()
    # node (1, 1) = DOF 7 is tied to (0, 1), (2, 1), (1, 0), (1, 2): DOFs 6, 8, 1, 13
    assert sorted(np.flatnonzero(K[7])) == [1, 6, 7, 8, 13]
    assert np.allclose(K, K.T)
    res = nvib.solve(nvib.scenes.lattice(12, 12), nvib.Newmark(), dt=1e-3, t_end=0.02)
    assert res.stats.linear_solver == "sparse LDLT" and res.success


@pytest.mark.parametrize("call, argument", [
    (lambda: nvib.scenes.chain(0), "n"), (lambda: nvib.scenes.chain(3, mass=-1.0), "mass"),
    (lambda: nvib.scenes.lattice(2, 2.5), "ny"), (lambda: nvib.scenes.lattice(2, 2, k=0.0), "k"),
])
def test_scene_generators_name_bad_arguments(call, argument):
    with pytest.raises((ValueError, TypeError)) as info:
        call()
    assert info.value.argument == argument


# ---------------------------------------------------------------- what large models must not do
def _run(code: str, limit_bytes: int | None = None, timeout: float = 120.0) -> subprocess.CompletedProcess:
    prelude = ""
    if limit_bytes is not None:
        prelude = (f"import resource\nresource.setrlimit(resource.RLIMIT_AS, ({limit_bytes}, {limit_bytes}))\n")
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(p for p in sys.path if p)
    return subprocess.run([sys.executable, "-c", prelude + textwrap.dedent(code)], capture_output=True, text=True,
                          timeout=timeout, env=env)


@pytest.mark.skipif(sys.platform != "linux", reason="RLIMIT_AS as a memory ceiling")
def test_a_200000_dof_chain_builds_and_runs_under_1_gb():
    # a dense K or C of this size would take 320 GB
    proc = _run("""
        import nvib
        model = nvib.scenes.chain(200_000)
        res = nvib.solve(model, nvib.CentralDifference(), dt=model.scene["dt"], t_end=100 * model.scene["dt"],
                         save_every=50)
        assert res.success and res.stats.num_steps == 100, res
        print("ok", res.u.shape)
    """, limit_bytes=1 << 30)
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert proc.stdout.startswith("ok (3, 200000)")


def test_a_history_too_large_raises_before_it_is_allocated():
    model = nvib.load_scene("building")
    # 10^9 states of 6 DOFs: 152 GB
    with pytest.raises(ValueError, match=r"^save_every, dofs: the saved history would need 152 GB") as info:
        nvib.solve(model, nvib.CentralDifference(), dt=1e-9, t_end=1.0)
    assert info.value.argument == "save_every, dofs"
    est = nvib.estimate(model, nvib.CentralDifference(), dt=1e-9, t_end=1.0, probe_seconds=0.01)
    assert not est.fits and est.history_bytes == pytest.approx(8 * (10**9 + 1) * 19)
    ok = nvib.estimate(model, nvib.CentralDifference(), dt=1e-9, t_end=1.0, save_every=10**6, probe_seconds=0.01)
    assert ok.fits and ok.saved_states == 1001 and ok.seconds_per_step > 0


def test_linearized_frequencies_of_a_large_model_say_what_to_do():
    """Above 2000 DOFs the error named a sparse=True that linearized_frequencies does not take (it came from
    tangent_matrices); it names the model and the way to the lowest frequencies."""
    model = nvib.scenes.chain(3000)
    with pytest.raises(nvib.ArgumentError) as exc:
        model.linearized_frequencies()
    assert exc.value.argument == "model"
    assert "up to 2000 DOFs (this one has 3000" in str(exc.value)
    assert "tangent_matrices(u, v, sparse=True)" in str(exc.value) and "eigsh" in str(exc.value)


def test_a_dense_linear_solver_on_a_large_model_of_effects_names_linear_solver():
    """The model's forces are effects, with a sparse tangent: what is too large is the dense solver asked for,
    not the model (whose message said to declare its forces as effects)."""
    model = nvib.scenes.chain(3000)
    with pytest.raises(nvib.ArgumentError) as exc:
        nvib.solve(model, nvib.Newmark(newton=nvib.Newton(linear_solver="dense")), dt=1e-3, t_end=0.01)
    assert exc.value.argument == "linear_solver"
    assert "declare its forces as effects" not in str(exc.value)
    assert "linear_solver='sparse'" in str(exc.value)


def test_estimate_predicts_the_run():
    model = nvib.scenes.chain(2000)
    est = nvib.estimate(model, nvib.Newmark(), dt=1e-3, t_end=0.5, save_every=10, probe_seconds=0.02)
    res = nvib.solve(model, nvib.Newmark(), dt=1e-3, t_end=0.5, save_every=10)
    assert est.steps == res.stats.num_steps == 500 and est.saved_states == len(res.t) == 51
    assert est.history_bytes == res.t.nbytes + res.u.nbytes + res.v.nbytes + res.a.nbytes
    assert est.linear_solver == res.stats.linear_solver == "banded LDLT"
    assert "steps" in str(est) and "linear solver: banded LDLT" in str(est)


def test_precise_integration_refuses_large_models_with_its_cost():
    model = nvib.scenes.chain(nvib._core.PIM_MAX_DOFS + 1)
    with pytest.raises(ValueError, match=r"^scheme: PreciseIntegration is dense: for 1001 DOFs its set-up would need "
                                         r"about [0-9.]+ GB and [0-9.]+ minutes"):
        nvib.Stepper(model, nvib.PreciseIntegration(), 1e-3)


def test_an_effect_array_takes_one_j_for_every_effect():
    """j = -1 (the ground) or one DOF name given once means the same j for every effect of the array: the
    same model, to the bit, as the list spelled out; a j out of range is still refused, naming it."""
    def run(j):
        m = nvib.Model(np.ones(4), dofs=["a", "b", "c", "d"], u0=[0.1, -0.2, 0.3, 0.0],
                       effects=[{"type": "spring", "i": ["a", "b", "c"], "j": j, "k": [10.0, 20.0, 30.0]}])
        return nvib.solve(m, nvib.CentralDifference(), dt=1e-3, t_end=0.5).u

    assert np.array_equal(run(-1), run([-1, -1, -1]))
    assert np.array_equal(run("d"), run(["d", "d", "d"]))
    assert not np.array_equal(run(-1), run("d"))
    with pytest.raises(nvib.ArgumentError, match=r"effects\[0\]\.j\[0\]"):
        run(4)


def test_a_run_reuses_the_ordering_an_earlier_run_of_the_same_pattern_kept():
    """The fill-reducing orderings of a sparse factorisation are kept by pattern (from 1000 rows): the second
    run on a 1,296-DOF block, and a run on a model built anew from the same arrays with another ground
    motion (a batch's run), order nothing, and give the bits of a run that ordered from scratch."""
    import _fe_mesh
    from nvib import _core

    parts = _fe_mesh.nonlinear_model(8, 8, 5)  # 9 x 9 x 6 nodes, clamped base: 1,296 DOFs
    model = _fe_mesh.nvib_model(parts)
    assert model.n >= 1000
    run = dict(dt=parts[-1] / 50, t_end=3 * parts[-1] / 50)
    assert _core.ordering_cache(clear=True)[0] == 0
    cold = nvib.solve(model, nvib.Newmark(), **run)
    kept, hits = _core.ordering_cache()
    assert kept >= 1  # the iteration matrix's pattern (the mass's was analysed before the clear)
    warm = nvib.solve(model, nvib.Newmark(), **run)
    assert _core.ordering_cache()[1] > hits
    for key in ("u", "v", "a"):
        np.testing.assert_array_equal(getattr(warm, key), getattr(cold, key))
    batch = nvib.solve_many(model, nvib.Newmark(), scales=[1.0, 2.0], threads=2, progress=False, **run)
    for key in ("u", "v", "a"):
        np.testing.assert_array_equal(getattr(batch[0], key), getattr(cold, key))
    _core.ordering_cache(clear=True)
    fresh = nvib.solve(nvib.Model(model._init[0], **{**model._init[1], "effects": [
        dict(e, signal={**e["signal"], "amplitude": 2 * e["signal"]["amplitude"]}) if e["type"] == "ground_acceleration"
        else e for e in model._init[1]["effects"]]}), nvib.Newmark(), **run)
    for key in ("u", "v", "a"):
        np.testing.assert_array_equal(getattr(batch[1], key), getattr(fresh, key))
