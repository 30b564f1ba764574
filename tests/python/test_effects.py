"""Built-in effects against their laws computed by hand in NumPy, their
tangents against central finite differences, the unilateral Hertz contact,
signals, loads, flags and ``without=``."""

from __future__ import annotations

import math
import zlib

import numpy as np
import pytest

import nvib

from _compiled_laws import BILINEAR, HARDENING, address

DOFS = ["a", "b", "c", "d"]
MASS = [1.0, 2.0, 0.5, 3.0]
MEASURE = {"a": 0.7, "c": -1.3, "d": 2.1}
G_ROW = np.array([0.7, 0.0, -1.3, 2.1])  # the same measure as a row over the DOFs


def _hertz(G, n, r=lambda t: 0.0):
    def law(d, dd, t):
        delta = d - r(t)
        return n * (delta / G) ** 1.5 if delta > 0 else 0.0
    return law


def _sine(A, w, phi):
    return lambda t: A * math.sin(w * t + phi)


def _table(ts, ys):
    def r(t):
        return float(np.interp(t, ts, ys)) if ts[0] <= t <= ts[-1] else 0.0  # 0 outside the table
    return r


SINE_IRR = {"kind": "sine", "amplitude": 0.05, "omega": 3.0, "phase": 0.3}
TABLE_IRR = {"kind": "table", "t": [0.0, 1.0, 2.5, 4.0, 6.0], "values": [0.0, 0.08, -0.06, 0.02, 0.1]}

# (id, effect parameters, scalar law f(d, d', t) by hand; loads as -P)
LAWS = [
    ("spring", {"type": "spring", "k": 350.0}, lambda d, dd, t: 350.0 * d),
    ("damper", {"type": "damper", "c": 12.0}, lambda d, dd, t: 12.0 * dd),
    ("hardening_spring", {"type": "hardening_spring", "k0": 100.0, "a": 30.0},
     lambda d, dd, t: 100.0 * (1.0 + 30.0 * d * d) * d),
    ("cubic_spring", {"type": "cubic_spring", "k3": 7e3}, lambda d, dd, t: 7e3 * d**3),
    *[(f"power_damper_p{p}", {"type": "power_damper", "c": 5.0, "p": p},
       (lambda p: lambda d, dd, t: 5.0 * abs(dd) ** p * np.sign(dd))(p)) for p in (0.5, 1.0, 1.7, 3.0)],
    ("pendulum_gravity", {"type": "pendulum_gravity", "m": 1.3, "g": 9.81, "l": 0.7},
     lambda d, dd, t: 1.3 * 9.81 * 0.7 * math.sin(d)),
    ("hertz_contact", {"type": "hertz_contact", "G": 1e-3, "contacts": 2.0}, _hertz(1e-3, 2.0)),
    ("hertz_contact_default_contacts", {"type": "hertz_contact", "G": 1e-3}, _hertz(1e-3, 1.0)),
    ("hertz_contact_sine", {"type": "hertz_contact", "G": 1e-3, "contacts": 2.0, "irregularity": SINE_IRR},
     _hertz(1e-3, 2.0, _sine(0.05, 3.0, 0.3))),
    ("hertz_contact_table", {"type": "hertz_contact", "G": 1e-3, "contacts": 2.0, "irregularity": TABLE_IRR},
     _hertz(1e-3, 2.0, _table(TABLE_IRR["t"], TABLE_IRR["values"]))),
    ("constant_force", {"type": "constant_force", "value": 4.2}, lambda d, dd, t: -4.2),
    ("harmonic_force", {"type": "harmonic_force", "amplitude": 3.0, "omega": 2.5, "phase": 0.4},
     lambda d, dd, t: -3.0 * math.sin(2.5 * t + 0.4)),
    ("harmonic_force_no_phase", {"type": "harmonic_force", "amplitude": 3.0, "omega": 2.5},
     lambda d, dd, t: -3.0 * math.sin(2.5 * t)),
    # compression-only after the gap closes at d = -gap; tension-only after the slack at d = slack
    ("gap", {"type": "gap", "k": 800.0, "gap": 0.1}, lambda d, dd, t: 800.0 * (d + 0.1) if d < -0.1 else 0.0),
    ("gap_closed", {"type": "gap", "k": 800.0}, lambda d, dd, t: 800.0 * d if d < 0.0 else 0.0),
    ("hook", {"type": "hook", "k": 600.0, "slack": 0.1}, lambda d, dd, t: 600.0 * (d - 0.1) if d > 0.1 else 0.0),
    ("hook_taut", {"type": "hook", "k": 600.0}, lambda d, dd, t: 600.0 * d if d > 0.0 else 0.0),
    # a negative spring -(P / h) d
    ("p_delta", {"type": "p_delta", "P": 2e3, "h": 3.5}, lambda d, dd, t: -(2e3 / 3.5) * d),
    # a compiled law (through a ctypes pointer) doing the hardening spring's arithmetic
    ("compiled", {"type": "compiled", "address": address(HARDENING), "p0": 100.0, "p1": 30.0},
     lambda d, dd, t: 100.0 * (1.0 + 30.0 * d * d) * d),
]


def one_effect_model(params, mass=MASS, measure=MEASURE):
    return nvib.Model(mass, effects=[dict(params, measure=measure)], dofs=DOFS)


def random_states(rng, law_id, count=12):
    """Random (u, v, t), away from the kinks of the unilateral contact and of |d'|^p."""
    out = []
    while len(out) < count:
        u = rng.normal(0.0, 0.3, 4)
        v = rng.normal(0.0, 2.0, 4)
        t = rng.uniform(0.0, 7.0)
        d, dd = G_ROW @ u, G_ROW @ v
        if law_id.startswith("hertz") and abs(d) < 0.15:
            continue  # |d - r(t)| > 0.05 (|r| <= 0.1): keeps finite differences off the kink
        if law_id.startswith("power_damper") and abs(dd) < 0.05:
            continue
        if law_id.startswith(("gap", "hook")) and min(abs(d - 0.1), abs(d), abs(d + 0.1)) < 0.05:
            continue  # off the kinks where the gap closes (d = -0.1, 0) or the hook engages (0.1, 0)
        out.append((u, v, t))
    return out


def fd_tangent(model, u, v, t, h=1e-6):
    n = len(u)
    K, C = np.zeros((n, n)), np.zeros((n, n))
    for j in range(n):
        e = np.zeros(n)
        e[j] = h
        K[:, j] = (model.evaluate_force(u + e, v, t) - model.evaluate_force(u - e, v, t)) / (2 * h)
        C[:, j] = (model.evaluate_force(u, v + e, t) - model.evaluate_force(u, v - e, t)) / (2 * h)
    return K, C


@pytest.mark.parametrize("law_id, params, law", LAWS, ids=[x[0] for x in LAWS])
def test_force_equals_the_law_by_hand(law_id, params, law):
    model = one_effect_model(params)
    rng = np.random.default_rng(zlib.crc32(law_id.encode()))
    for u, v, t in random_states(rng, law_id):
        expected = G_ROW * law(G_ROW @ u, G_ROW @ v, t)  # g^T f(g.u, g.v, t)
        got = model.evaluate_force(u, v, t)
        np.testing.assert_allclose(got, expected, rtol=1e-12, atol=1e-12 * max(1.0, np.abs(expected).max()))
        assert got[1] == 0.0  # DOF b is not in the measure


@pytest.mark.parametrize("law_id, params, law", LAWS, ids=[x[0] for x in LAWS])
def test_tangent_equals_finite_difference(law_id, params, law):
    model = one_effect_model(params)
    rng = np.random.default_rng(1 + zlib.crc32(law_id.encode()))
    for u, v, t in random_states(rng, law_id, count=6):
        K, C = model.tangent_matrices(u, v, t)
        Kfd, Cfd = fd_tangent(model, u, v, t)
        scale = max(1.0, np.abs(Kfd).max(), np.abs(Cfd).max())
        np.testing.assert_allclose(K, Kfd, rtol=1e-6, atol=1e-7 * scale)
        np.testing.assert_allclose(C, Cfd, rtol=1e-6, atol=1e-7 * scale)
        # a scalar law on a measure: the tangents are rank one along g g^T
        assert np.all(K[1] == 0.0) and np.all(K[:, 1] == 0.0)


def test_combined_effects_add_up():
    rng = np.random.default_rng(7)
    effects = [dict(p, measure=m) for (_, p, _), m in zip(LAWS, [
        MEASURE, {"b": 1.0}, {"a": 1.0, "b": -1.0}, {"c": 1.0, "d": -0.5}, {"d": 1.0}, {"a": 2.0},
        {"b": 1.0, "c": 1.0}, {"c": -1.0}, {"d": 1.0}, {"a": 1.0}, {"b": 1.0}, {"a": 0.5, "b": 0.5},
        {"c": 1.0}, {"d": -2.0}, {"a": 1.0}, {"b": 3.0}, {"a": 1.0},
        {"a": 1.0, "d": -1.0}, {"c": 1.0}, {"b": 1.0, "c": -0.5}, {"d": 1.0}, {"a": 0.4, "b": 1.0}])]
    assert len(effects) == len(LAWS)
    model = nvib.Model(MASS, effects=effects, dofs=DOFS)
    singles = [nvib.Model(MASS, effects=[e], dofs=DOFS) for e in effects]
    for _ in range(5):
        u, v, t = rng.normal(0, 0.3, 4), rng.normal(0, 2.0, 4), rng.uniform(0, 7)
        total = sum(s.evaluate_force(u, v, t) for s in singles)
        np.testing.assert_allclose(model.evaluate_force(u, v, t), total, rtol=1e-12,
                                   atol=1e-12 * np.abs(total).max())
        Ks = sum(s.tangent_matrices(u, v, t)[0] for s in singles)
        np.testing.assert_allclose(model.tangent_matrices(u, v, t)[0], Ks, rtol=1e-12, atol=1e-12 * np.abs(Ks).max())


# Measures of every shape the evaluation stores differently: d = u_i, d = u_i - u_j,
# any two coefficients, one entry with another coefficient, a sparse list
# (fewer than half the DOFs) and a dense row (at least half).
WIDE_DOFS = [f"q{i}" for i in range(8)]
MEASURE_SHAPES = {
    "unit": {"q2": 1.0},
    "difference": {"q5": 1.0, "q1": -1.0},
    "difference_reversed": {"q1": -1.0, "q5": 1.0},
    "two": {"q0": 0.7, "q6": -1.3},
    "one_scaled": {"q3": -2.0},
    "sparse": {"q0": 0.4, "q4": -1.1, "q7": 0.9},
    "dense": {f"q{i}": 0.1 * (i + 1) * (-1) ** i for i in range(6)},
}


def _row(measure):
    g = np.zeros(len(WIDE_DOFS))
    for dof, c in measure.items():
        g[WIDE_DOFS.index(dof)] += c
    return g


@pytest.mark.parametrize("seed", range(6))
def test_every_measure_storage_matches_the_laws(seed):
    """Random mixtures of every law on every measure shape: the force is the sum of
    g^T f(g.u, g.v, t) computed in NumPy, and the tangent matches finite differences."""
    rng = np.random.default_rng(100 + seed)
    shapes = list(MEASURE_SHAPES)
    chosen = [LAWS[i] for i in rng.choice(len(LAWS), size=10)]
    effects, reference = [], []
    for law_id, params, law in chosen:
        if law_id.startswith(("hertz", "power_damper", "gap", "hook")):
            continue  # kinks: covered one by one above
        measure = MEASURE_SHAPES[shapes[rng.integers(len(shapes))]]
        effects.append(dict(params, measure=measure))
        reference.append((_row(measure), law))
    if seed % 2 == 0:  # with and without a ground acceleration (a dense load evaluated first)
        effects.append({"type": "ground_acceleration", "signal": {"kind": "sine", "amplitude": 2.0, "omega": 1.5}})
    mass = rng.uniform(0.5, 3.0, len(WIDE_DOFS))
    model = nvib.Model(mass, effects=effects, dofs=WIDE_DOFS)
    for _ in range(5):
        u, v, t = rng.normal(0, 0.3, 8), rng.normal(0, 2.0, 8), rng.uniform(0, 7)
        expected = sum(g * law(g @ u, g @ v, t) for g, law in reference)
        if seed % 2 == 0:
            expected = expected + mass * 2.0 * math.sin(1.5 * t)  # -P = M r a_g
        got = model.evaluate_force(u, v, t)
        np.testing.assert_allclose(got, expected, rtol=1e-12, atol=1e-12 * max(1.0, np.abs(expected).max()))
        K, C = model.tangent_matrices(u, v, t)
        Kfd, Cfd = fd_tangent(model, u, v, t)
        scale = max(1.0, np.abs(Kfd).max(), np.abs(Cfd).max())
        np.testing.assert_allclose(K, Kfd, rtol=1e-6, atol=1e-7 * scale)
        np.testing.assert_allclose(C, Cfd, rtol=1e-6, atol=1e-7 * scale)


def test_several_dense_loads_add_up():
    """Two dense harmonic loads, a ground acceleration and a constant load: every one counts
    (only the first dense load may write the force vector, the others add to it)."""
    dense = MEASURE_SHAPES["dense"]
    g = _row(dense)
    mass = np.linspace(1.0, 2.0, 8)
    model = nvib.Model(mass, dofs=WIDE_DOFS, effects=[
        {"type": "harmonic_force", "measure": dense, "amplitude": 3.0, "omega": 2.0},
        {"type": "constant_force", "measure": {"q7": 1.0}, "value": 1.5},
        {"type": "ground_acceleration", "signal": {"kind": "sine", "amplitude": 2.0, "omega": 1.5}},
        {"type": "harmonic_force", "measure": dense, "amplitude": -0.5, "omega": 0.3, "phase": 1.0},
    ])
    for t in (0.0, 0.4, 2.9):
        expected = (-3.0 * math.sin(2.0 * t) + 0.5 * math.sin(0.3 * t + 1.0)) * g + mass * 2.0 * math.sin(1.5 * t)
        expected[7] -= 1.5
        np.testing.assert_allclose(model.evaluate_force(np.zeros(8), np.zeros(8), t), expected, rtol=1e-13, atol=1e-13)


@pytest.mark.parametrize("shape", list(MEASURE_SHAPES))
def test_hertz_contact_on_every_measure_storage(shape):
    """An open contact adds exactly nothing whatever the storage of its measure."""
    measure = MEASURE_SHAPES[shape]
    g = _row(measure)
    model = nvib.Model(np.ones(8), effects=[{"type": "hertz_contact", "measure": measure, "G": 1e-3},
                                            {"type": "constant_force", "measure": {"q7": 1.0}, "value": 2.5}],
                       dofs=WIDE_DOFS)
    rng = np.random.default_rng(len(shape))
    for _ in range(20):
        u = rng.normal(0, 0.3, 8)
        d = g @ u
        expected = g * ((d / 1e-3) ** 1.5 if d > 0 else 0.0)
        expected[7] -= 2.5
        got = model.evaluate_force(u, np.zeros(8), 0.0)
        np.testing.assert_allclose(got, expected, rtol=1e-12, atol=1e-12 * np.abs(expected).max())
        if d <= 0:
            assert np.array_equal(got, expected)  # exactly: the open contact contributes no rounding


def test_measure_by_index_and_repeated_dof():
    # DOFs may be named or given by index; a DOF named twice adds its coefficients
    m = nvib.Model([1.0, 1.0], effects=[{"type": "hardening_spring", "measure": {"u0": 1.0, 0: 2.0, 1: -1.0},
                                         "k0": 10.0, "a": 2.0}])
    u = np.array([0.3, 0.1])
    d = 3.0 * 0.3 - 0.1
    f = 10.0 * (1 + 2.0 * d * d) * d
    np.testing.assert_allclose(m.evaluate_force(u, [0.0, 0.0]), [3.0 * f, -f], rtol=1e-14)
    k = 10.0 * (1 + 3 * 2.0 * d * d)
    np.testing.assert_allclose(m.tangent_matrices(u, [0.0, 0.0])[0], k * np.outer([3.0, -1.0], [3.0, -1.0]),
                               rtol=1e-14)


# ---------------------------------------------------------------------------
# Hertz contact: unilateral and exactly zero when open


def contact_model(irregularity=None, G=2e-4, n=2.0):
    eff = {"type": "hertz_contact", "measure": {"w": 1.0}, "G": G, "contacts": n}
    if irregularity is not None:
        eff["irregularity"] = irregularity
    return nvib.Model([10.0], effects=[eff], dofs=["w"])


@pytest.mark.parametrize("z", [-1e-3, -1e-9, -1e-300, 0.0, -0.0])
def test_hertz_open_contact_is_exactly_zero(z):
    m = contact_model()
    f = m.evaluate_force([z], [3.0], 0.7)
    K, C = m.tangent_matrices([z], [3.0], 0.7)
    assert f[0] == 0.0 and K[0, 0] == 0.0 and C[0, 0] == 0.0


def test_hertz_closed_contact():
    G, n = 2e-4, 2.0
    m = contact_model(G=G, n=n)
    for z in (1e-12, 1e-6, 3e-4, 2e-2):
        assert m.evaluate_force([z], [0.0])[0] == pytest.approx(n * (z / G) ** 1.5, rel=1e-14)
        assert m.tangent_matrices([z], [0.0])[0][0, 0] == pytest.approx(1.5 * n / G * math.sqrt(z / G), rel=1e-14)
    # continuous at closure: force and stiffness go to 0 as z -> 0+
    assert m.evaluate_force([1e-300], [0.0])[0] < 1e-300


def test_hertz_follows_a_sine_irregularity():
    A, w, phi, G, n = 1e-3, 30.0, 0.2, 2e-4, 2.0
    m = contact_model({"kind": "sine", "amplitude": A, "omega": w, "phase": phi}, G=G, n=n)
    z = 5e-4
    opened = closed = 0
    for t in np.linspace(0.0, 1.0, 401):
        delta = z - A * math.sin(w * t + phi)
        f = m.evaluate_force([z], [0.0], t)[0]
        k = m.tangent_matrices([z], [0.0], t)[0][0, 0]
        if delta > 0:
            closed += 1
            assert f == pytest.approx(n * (delta / G) ** 1.5, rel=1e-12)
            assert k == pytest.approx(1.5 * n / G * math.sqrt(delta / G), rel=1e-12)
        else:
            opened += 1
            assert f == 0.0 and k == 0.0
    assert opened > 50 and closed > 50
    assert m.uses_time


def test_hertz_follows_a_table_irregularity():
    ts, ys = [0.1, 0.2, 0.45, 0.6], [0.0, 1e-3, -5e-4, 2e-4]
    G, n = 2e-4, 2.0
    m = contact_model({"kind": "table", "t": ts, "values": ys}, G=G, n=n)
    z = 4e-4
    times = [0.0, 0.05, 0.1, 0.125, 0.15, 0.2, 0.3, 0.45, 0.5, 0.6, 0.61, 1.0] + list(np.linspace(0.1, 0.6, 37))
    for t in times:
        r = float(np.interp(t, ts, ys)) if ts[0] <= t <= ts[-1] else 0.0
        delta = z - r
        f = m.evaluate_force([z], [0.0], t)[0]
        if delta > 0:
            assert f == pytest.approx(n * (delta / G) ** 1.5, rel=1e-12), t
        else:
            assert f == 0.0, t
    # at t = 0.2 the rail is 1e-3 down, the wheel 4e-4: open
    assert m.evaluate_force([z], [0.0], 0.2)[0] == 0.0


def test_hertz_parameters_are_validated():
    with pytest.raises(ValueError, match=r"effects\[0\].*G"):
        contact_model(G=-1.0)
    with pytest.raises(ValueError, match=r"effects\[0\].*contacts"):
        contact_model(n=0.0)


# ---------------------------------------------------------------------------
# loads


def spd(rng, n):
    A = rng.normal(size=(n, n))
    return A @ A.T + n * np.eye(n)


@pytest.mark.parametrize("dense", [False, True])
@pytest.mark.parametrize("signal", [
    {"kind": "sine", "amplitude": 10.0, "omega": math.pi},
    {"kind": "sine", "amplitude": -2.0, "omega": 7.0, "phase": 1.1},
    {"kind": "table", "t": [0.0, 0.5, 1.0, 2.0], "values": [0.0, 3.0, -1.0, 4.0]},
], ids=["sine", "sine_phase", "table"])
def test_ground_acceleration_is_m_r_ag(dense, signal):
    rng = np.random.default_rng(3)
    M = spd(rng, 4) if dense else np.diag(MASS)
    mass = M if dense else MASS
    if signal["kind"] == "sine":
        ag = _sine(signal["amplitude"], signal["omega"], signal.get("phase", 0.0))
    else:
        ag = _table(signal["t"], signal["values"])
    every = nvib.Model(mass, effects=[{"type": "ground_acceleration", "signal": signal}], dofs=DOFS)
    some = nvib.Model(mass, effects=[{"type": "ground_acceleration", "signal": signal,
                                      "measure": {"a": 1.0, "c": 0.5}}], dofs=DOFS)
    r_all, r_some = np.ones(4), np.array([1.0, 0.0, 0.5, 0.0])
    for t in [0.0, 0.25, 0.5, 0.75, 1.3, 2.0, 2.5]:
        u, v = rng.normal(size=4), rng.normal(size=4)  # a load: independent of the state
        # M a + F = 0 with F = -P = M r a_g(t)
        np.testing.assert_allclose(every.evaluate_force(u, v, t), M @ r_all * ag(t), rtol=1e-13, atol=1e-13)
        np.testing.assert_allclose(some.evaluate_force(u, v, t), M @ r_some * ag(t), rtol=1e-13, atol=1e-13)
        K, C = some.tangent_matrices(u, v, t)
        assert np.all(K == 0.0) and np.all(C == 0.0)


def test_mass_given_as_a_strided_view():
    # a NumPy view (every other entry, a diagonal, a sub-matrix) is as good as a copy
    ag = {"kind": "sine", "amplitude": 2.0, "omega": 1.0, "phase": 0.5}
    eff = [{"type": "ground_acceleration", "signal": ag}]
    lumped = np.array([1.0, 2.0, 3.0, 4.0])[::2]
    m = nvib.Model(lumped, effects=eff, dofs=["p", "q"])
    np.testing.assert_array_equal(m.mass_matrix, np.diag([1.0, 3.0]))
    np.testing.assert_allclose(m.evaluate_force([0, 0], [0, 0], 0.0), np.array([1.0, 3.0]) * 2.0 * math.sin(0.5),
                               rtol=1e-15)
    np.testing.assert_array_equal(nvib.Model(np.diag([3.0, 1.0, 2.0]).diagonal(), effects=eff).mass_matrix,
                                  np.diag([3.0, 1.0, 2.0]))
    big = np.zeros((4, 4))
    big[::2, ::2] = [[2.0, 0.5], [0.5, 3.0]]
    np.testing.assert_array_equal(nvib.Model(big[::2, ::2], effects=eff).mass_matrix, [[2.0, 0.5], [0.5, 3.0]])


def test_ground_acceleration_drives_relative_motion_opposite_to_the_ground():
    # a free mass (no spring) sees a = -a_g(t): u(t) = -∫∫ a_g = -(A/w^2)(w t - sin w t)
    A, w = 2.0, 3.0
    m = nvib.Model([5.0], effects=[{"type": "ground_acceleration",
                                    "signal": {"kind": "sine", "amplitude": A, "omega": w}}])
    res = nvib.solve(m, nvib.Newmark(), dt=1e-4, t_end=1.0, save_every=1000)
    np.testing.assert_allclose(res.u[:, 0], -(A / w**2) * (w * res.t - np.sin(w * res.t)), atol=1e-8)


def test_constant_loads():
    m = nvib.Model([1.0, 2.0, 3.0], effects=[
        {"type": "spring", "measure": {"x": 1.0}, "k": 100.0},
        {"type": "spring", "measure": {"y": 1.0, "x": -1.0}, "k": 50.0},
        {"type": "spring", "measure": {"z": 1.0, "y": -1.0}, "k": 20.0},
        {"type": "constant_force", "measure": {"z": 1.0}, "value": 6.0},
        {"type": "constant_force", "measure": {"z": 1.0}, "value": -1.0},
        {"type": "constant_force", "measure": {"x": 2.0, "y": 1.0}, "value": 1.5},
    ], dofs=["x", "y", "z"])
    P = np.array([3.0, 1.5, 5.0])  # sum of value * g
    zero = np.zeros(3)
    for t in (0.0, 1.0, 123.4):
        np.testing.assert_array_equal(m.evaluate_force(zero, zero, t), -P)
    K = np.array([[150.0, -50.0, 0.0], [-50.0, 70.0, -20.0], [0.0, -20.0, 20.0]])
    np.testing.assert_allclose(m.tangent_matrices(zero, zero)[0], K, rtol=1e-15)
    np.testing.assert_allclose(m.static_equilibrium(), np.linalg.solve(K, P), rtol=1e-12)
    assert m.is_linear and not m.uses_time and not m.uses_velocity


# ---------------------------------------------------------------------------
# flags, per effect and combined

FLAG_CASES = [
    # (id, params, uses_velocity, uses_time, is_linear)
    ("spring", {"type": "spring", "k": 1.0}, False, False, True),
    ("damper", {"type": "damper", "c": 1.0}, True, False, True),
    ("hardening_spring", {"type": "hardening_spring", "k0": 1.0, "a": 1.0}, False, False, False),
    ("cubic_spring", {"type": "cubic_spring", "k3": 1.0}, False, False, False),
    ("power_damper", {"type": "power_damper", "c": 1.0, "p": 1.7}, True, False, False),
    ("power_damper_p1", {"type": "power_damper", "c": 1.0, "p": 1.0}, True, False, True),  # a linear damper
    ("pendulum_gravity", {"type": "pendulum_gravity", "m": 1.0, "g": 9.8, "l": 1.0}, False, False, False),
    ("hertz_contact", {"type": "hertz_contact", "G": 1e-3}, False, False, False),
    ("hertz_contact_irregular", {"type": "hertz_contact", "G": 1e-3, "irregularity": SINE_IRR}, False, True, False),
    ("constant_force", {"type": "constant_force", "value": 1.0}, False, False, True),
    ("harmonic_force", {"type": "harmonic_force", "amplitude": 1.0, "omega": 1.0}, False, True, True),
    ("ground_acceleration", {"type": "ground_acceleration", "signal": SINE_IRR}, False, True, True),
    ("gap", {"type": "gap", "k": 1.0, "gap": 0.1}, False, False, False),
    ("hook", {"type": "hook", "k": 1.0, "slack": 0.1}, False, False, False),
    ("p_delta", {"type": "p_delta", "P": 1.0, "h": 3.0}, False, False, True),  # linear: assembled into K
    # laws with memory are never linear, whatever their parameters (a yielding spring with b -> 1,
    # a Bouc-Wen law that is nearly elastic): their force depends on the path
    ("bilinear", {"type": "bilinear", "k": 1.0, "fy": 1.0, "b": 0.5}, False, False, False),
    ("bouc_wen", {"type": "bouc_wen", "k": 1.0, "fy": 1.0, "alpha": 0.99}, False, False, False),
    ("bouc_wen_euler", {"type": "bouc_wen", "k": 1.0, "dy": 1.0, "integration": "backward_euler"},
     False, False, False),
    ("friction", {"type": "friction", "k": 1.0, "fs": 1.0}, False, False, False),
    ("friction_mu_N", {"type": "friction", "k": 1.0, "mu": 0.3, "N": 10.0}, False, False, False),
    ("imk_peak_oriented", {"type": "imk_peak_oriented", "k": 1.0, "fy": 1.0, "up": 1.0, "upc": 2.0, "uu": 5.0,
                           "fcap_fy": 1.1}, False, False, False),
    # a compiled law declares its use of time; its use of the velocity is not known, so it is assumed
    ("compiled", {"type": "compiled", "address": address(HARDENING), "uses_time": 0.0}, True, False, False),
    ("compiled_uses_time", {"type": "compiled", "address": address(HARDENING)}, True, True, False),
    ("compiled_state", {"type": "compiled_state", "address": address(BILINEAR), "uses_time": 0.0, "state_size": 3.0,
                        "p0": 1.0, "p1": 1.0}, True, False, False),
]


def laws_without_memory() -> set[str]:
    return {t for t, law in nvib._core.laws().items() if not law["state"]}


def test_every_effect_type_has_a_flag_case():
    assert {c[1]["type"] for c in FLAG_CASES} == set(nvib.EFFECT_PARAMETERS)
    # LAWS holds the laws without memory (a force by hand); the laws with memory are in test_hysteresis*.py
    assert {p["type"] for _, p, _ in LAWS} | {"ground_acceleration"} == laws_without_memory()
    assert laws_without_memory() < set(nvib.EFFECT_PARAMETERS)  # some law has memory


@pytest.mark.parametrize("case", FLAG_CASES, ids=[c[0] for c in FLAG_CASES])
def test_flags_per_effect(case):
    _, params, uses_velocity, uses_time, is_linear = case
    m = one_effect_model(params)
    assert (m.uses_velocity, m.uses_time, m.is_linear) == (uses_velocity, uses_time, is_linear)


@pytest.mark.parametrize("i", range(len(FLAG_CASES)))
@pytest.mark.parametrize("j", range(len(FLAG_CASES)))
def test_flags_combine(i, j):
    a, b = FLAG_CASES[i], FLAG_CASES[j]
    m = nvib.Model(MASS, effects=[dict(a[1], measure=MEASURE), dict(b[1], measure={"b": 1.0})], dofs=DOFS)
    assert m.uses_velocity == (a[2] or b[2])
    assert m.uses_time == (a[3] or b[3])
    assert m.is_linear == (a[4] and b[4])


# ---------------------------------------------------------------------------
# without=


def building_storey_force(u, skip=()):
    """Storey springs k0 (1 + a d^2) d on the drifts, by hand."""
    x = np.concatenate([[0.0], u])
    f = np.zeros(6)
    for s in range(6):
        if s + 1 in skip:
            continue
        d = x[s + 1] - x[s]
        fs = 1e8 * (1 + 10.0 * d * d) * d
        f[s] += fs
        if s > 0:
            f[s - 1] -= fs
    return f


def test_without_by_name_and_by_type():
    rng = np.random.default_rng(11)
    u, v, t = rng.normal(0, 0.05, 6), rng.normal(size=6), 0.3
    ground = 1e5 * 10.0 * math.sin(math.pi * t) * np.ones(6)
    full = nvib.load_scene("building")
    np.testing.assert_allclose(full.evaluate_force(u, v, t), building_storey_force(u) + ground, rtol=1e-12)
    for w in (["ground"], ["ground_acceleration"]):
        m = nvib.load_scene("building", without=w)
        np.testing.assert_allclose(m.evaluate_force(u, v, t), building_storey_force(u), rtol=1e-12)
        assert not m.uses_time
    m = nvib.load_scene("building", without=["storey3"])
    np.testing.assert_allclose(m.evaluate_force(u, v, t), building_storey_force(u, skip=(3,)) + ground, rtol=1e-12)
    m = nvib.load_scene("building", without=["hardening_spring"])
    np.testing.assert_allclose(m.evaluate_force(u, v, t), ground, rtol=1e-12)
    assert m.is_linear


def test_without_removes_every_effect_sharing_a_name():
    veh = nvib.load_scene("vehicle", without=["gravity"])  # seven constant forces share the name
    np.testing.assert_array_equal(veh.evaluate_force(np.zeros(10), np.zeros(10)), np.zeros(10))
    np.testing.assert_array_equal(veh.u0, np.zeros(10))  # no load: the equilibrium is the origin


def test_without_on_a_python_model():
    eff = [{"type": "spring", "measure": {"x": 1.0}, "k": 4.0, "name": "s"},
           {"type": "constant_force", "measure": {"x": 1.0}, "value": 2.0}]
    m = nvib.Model([1.0], effects=eff, dofs=["x"], without=["s"])
    np.testing.assert_array_equal(m.evaluate_force([1.0], [0.0]), [-2.0])
    m = nvib.Model([1.0], effects=eff, dofs=["x"], without=["constant_force"])
    np.testing.assert_array_equal(m.evaluate_force([1.0], [0.0]), [4.0])


def test_without_unknown_name_is_an_error():
    with pytest.raises(ValueError, match="nosuch"):
        nvib.load_scene("building", without=["nosuch"])
    with pytest.raises(ValueError, match="without.*nosuch"):
        nvib.Model([1.0], effects=[{"type": "spring", "measure": {"u0": 1.0}, "k": 1.0}], without=["nosuch"])
    with pytest.raises(ValueError, match="without"):
        nvib.Model([1.0], force=lambda u, v, t: u, without=["spring"])
