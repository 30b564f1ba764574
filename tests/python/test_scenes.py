"""Built-in scenes checked against physics computed by hand (the paper's
numbers, the vehicle's static checks, closed forms), and scene-file errors
that name the file, the effect index and the key."""

from __future__ import annotations

import math
import sys

import numpy as np
import pytest

import nvib

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

# ---------------------------------------------------------------------------
# Vehicle parameters, from Huo & Dai, Shock and Vibration 2019, article 2015465, Table 1 (the source
# vehicle.toml cites; not read back from the library).
M_C, J_C, M_T, J_T, M_W = 34500.0, 1.5604e6, 3500.0, 1722.0, 2200.0
K_PZ, K_SZ = 1.173e6, 0.61e6  # per axle box / per side; x2 per wheelset / bogie
G_HERTZ = 5.18e-8
GRAV = 9.81
VEHICLE_DOFS = ["z_c", "beta_c", "z_t1", "beta_t1", "z_t2", "beta_t2", "z_w1", "z_w2", "z_w3", "z_w4"]
WHEELSETS = [6, 7, 8, 9]
P0 = (M_C + 2 * M_T + 4 * M_W) * GRAV / 8.0  # static load per wheel


@pytest.fixture(scope="module")
def vehicle():
    return nvib.load_scene("vehicle")


@pytest.fixture(scope="module")
def vehicle_contacts():
    """The vehicle's Hertz contacts alone, as the scene file declares them: its
    force on wheelset j is the total wheel-rail force of that wheelset."""
    with open(nvib.load_scene("vehicle").scene["path"], "rb") as fh:
        data = tomllib.load(fh)
    contacts = [e for e in data["effect"] if e["type"] == "hertz_contact"]
    assert len(contacts) == 4 and all(e["contacts"] == 2.0 for e in contacts)
    return nvib.Model(data["dofs"]["mass"], effects=contacts, dofs=data["dofs"]["names"])


# ---------------------------------------------------------------------------
# every scene loads, with the settings and initial state of the paper


@pytest.mark.parametrize("name", nvib.scene_names())
def test_every_builtin_scene_loads(name):
    m = nvib.load_scene(name)
    assert m.scene["name"] == name
    assert m.scene["dt"] > 0 and m.scene["t_end"] > m.scene["dt"]
    assert m.scene["plot_dof"] in m.dofs
    assert m.scene["source"], "every built-in scene cites its source"
    assert m.u0.shape == m.v0.shape == (m.n,)
    assert np.all(np.isfinite(m.evaluate_force(m.u0, m.v0, 0.0)))
    res = nvib.solve(m, nvib.CEMDTS(), dt=m.scene["dt"], t_end=10 * m.scene["dt"])
    assert res.success


def test_builtin_scene_names():
    assert set(nvib.scene_names()) >= {"pendulum", "pendulum_ic2", "hardening", "building", "vehicle"}


def test_scene_settings_match_the_paper():
    pend1, pend2 = nvib.load_scene("pendulum"), nvib.load_scene("pendulum_ic2")
    assert pend1.u0[0] == pytest.approx(-0.95 * math.pi, rel=1e-15) and pend1.v0[0] == 0.0
    assert pend2.u0[0] == 0.0 and pend2.v0[0] == 1.0
    for p, t_end in ((pend1, 15.0), (pend2, 10.0)):
        assert (p.scene["dt"], p.scene["t_end"]) == (0.3, t_end)
        # g/l = 1: the small-amplitude circular frequency is 1 rad/s
        assert p.linearized_frequencies()[0] == pytest.approx(1.0, rel=1e-12)
    hard = nvib.load_scene("hardening")
    assert (hard.u0[0], hard.v0[0], hard.scene["dt"], hard.scene["t_end"]) == (1.5, 0.0, 0.001, 0.3)
    # m x'' + k0 (1 + a x^2) x with m = 1, k0 = 100, a = 30
    assert hard.mass_matrix[0, 0] == 1.0
    assert hard.evaluate_force([1.5], [0.0])[0] == pytest.approx(100.0 * (1 + 30.0 * 1.5**2) * 1.5, rel=1e-15)
    assert hard.linearized_frequencies()[0] == pytest.approx(10.0, rel=1e-14)
    # secant omega_max = sqrt(k0 (1 + a x0^2) / m) = 82.76 rad/s (Yang et al. 2017, section 4.2)
    assert math.sqrt(hard.evaluate_force([1.5], [0.0])[0] / 1.5) == pytest.approx(82.76, abs=0.005)
    bld = nvib.load_scene("building")
    assert np.all(bld.u0 == 0) and np.all(bld.v0 == 0)
    veh = nvib.load_scene("vehicle")
    assert veh.dofs == VEHICLE_DOFS
    np.testing.assert_array_equal(veh.v0, [0, 0, 0.5, 0, 0.5, 0, 0.5, 0.5, 0.5, 0.5])
    np.testing.assert_array_equal(np.diag(veh.mass_matrix), [M_C, J_C, M_T, J_T, M_T, J_T, M_W, M_W, M_W, M_W])


# ---------------------------------------------------------------------------
# building


def test_building_linearised_frequencies():
    w = nvib.load_scene("building").linearized_frequencies()
    assert w.shape == (6,)
    # the paper's numbers
    assert w[0] == pytest.approx(7.62, abs=0.01)
    assert w[-1] == pytest.approx(61.41, abs=0.01)
    # closed form of a uniform shear chain, fixed at the ground, free at the top:
    # omega_j = 2 sqrt(k/m) sin((2j - 1) pi / (2 (2n + 1)))
    n, k, m = 6, 1e8, 1e5
    j = np.arange(1, n + 1)
    expected = 2 * math.sqrt(k / m) * np.sin((2 * j - 1) * math.pi / (2 * (2 * n + 1)))
    np.testing.assert_allclose(w, expected, rtol=1e-10)
    assert 2 * math.pi / w[-1] == pytest.approx(0.1, abs=0.0025)  # Tmin ~ 0.1 s


def test_building_ground_load_is_minus_m_ag():
    bld = nvib.load_scene("building")
    z = np.zeros(6)
    for t in (0.0, 0.25, 0.5, 1.3):
        # F = K u - P with P = -M 1 a_g(t), a_g = 10 sin(pi t)
        np.testing.assert_allclose(bld.evaluate_force(z, z, t), 1e5 * 10.0 * math.sin(math.pi * t) * np.ones(6),
                                   rtol=1e-14, atol=1e-8)


# ---------------------------------------------------------------------------
# vehicle: static equilibrium under gravity, frequencies


def test_vehicle_static_wheel_load(vehicle, vehicle_contacts):
    assert P0 == pytest.approx(61.7e3, abs=50.0)
    u0 = vehicle.u0
    assert vehicle.scene["initial_u"] == "static_equilibrium"
    for j in WHEELSETS:
        delta = u0[j]  # rigid smooth rail at z = 0, z positive down: compression = z_w
        assert delta > 0
        per_wheel = (delta / G_HERTZ) ** 1.5  # Hertz law by hand
        assert per_wheel == pytest.approx(P0, rel=1e-9)
    # the same from the model's own contact force (two wheels per wheelset)
    f = vehicle_contacts.evaluate_force(u0, np.zeros(10), 0.0)
    np.testing.assert_allclose(f[WHEELSETS] / 2.0, P0, rtol=1e-9)
    assert np.all(f[:6] == 0.0)


def test_vehicle_static_hertz_compression(vehicle):
    delta0 = G_HERTZ * P0 ** (2.0 / 3.0)
    assert delta0 == pytest.approx(8.1e-5, rel=0.01)
    np.testing.assert_allclose(vehicle.u0[WHEELSETS], delta0, rtol=1e-9)


def test_vehicle_static_suspension_deflections(vehicle):
    u = dict(zip(VEHICLE_DOFS, vehicle.u0))
    # secondary suspension (2 K_sz per bogie) carries half the carbody weight
    assert u["z_c"] - u["z_t1"] == pytest.approx(M_C * GRAV / 2 / (2 * K_SZ), rel=1e-9)
    assert u["z_c"] - u["z_t2"] == pytest.approx(M_C * GRAV / 2 / (2 * K_SZ), rel=1e-9)
    # primary suspension (2 K_pz per wheelset) carries a quarter of carbody + half a bogie frame
    for t, w in (("z_t1", "z_w1"), ("z_t1", "z_w2"), ("z_t2", "z_w3"), ("z_t2", "z_w4")):
        assert u[t] - u[w] == pytest.approx((M_C / 4 + M_T / 2) * GRAV / (2 * K_PZ), rel=1e-9)
    # symmetric vehicle: no pitch
    for b in ("beta_c", "beta_t1", "beta_t2"):
        assert abs(u[b]) < 1e-15


def test_vehicle_linearised_contact_stiffness(vehicle, vehicle_contacts):
    k_wheel = 1.5 * P0 ** (1.0 / 3.0) / G_HERTZ
    assert k_wheel == pytest.approx(1.14e9, rel=0.005)
    K, C = vehicle_contacts.tangent_matrices(vehicle.u0, np.zeros(10), 0.0)
    np.testing.assert_allclose(np.diag(K)[WHEELSETS], 2 * k_wheel, rtol=1e-9)
    assert np.all(C == 0.0)


def test_vehicle_highest_linearised_frequency(vehicle):
    w = vehicle.linearized_frequencies(vehicle.u0)
    assert w[-1] == pytest.approx(1020.0, rel=0.01)
    # the wheelset bouncing on its two contacts and its primary springs
    k_wheel = 1.5 * P0 ** (1.0 / 3.0) / G_HERTZ
    assert w[-1] == pytest.approx(math.sqrt((2 * k_wheel + 2 * K_PZ) / M_W), rel=1e-3)
    assert w[-1] * 1e-3 < 2.0  # explicit schemes stable at the paper's dt = 1e-3 (Yang et al. 2017, 5.2)


def test_vehicle_equilibrium_residual(vehicle):
    r = vehicle.evaluate_force(vehicle.u0, np.zeros(10), 0.0)
    weight = M_C * GRAV
    assert np.max(np.abs(r)) <= 1e-8 * weight


def test_vehicle_contact_force_is_exactly_zero_when_the_wheel_leaves_the_rail(vehicle, vehicle_contacts):
    res = nvib.solve(vehicle, nvib.CEMDTS(), dt=1e-4, t_end=vehicle.scene["t_end"], save_every=1)
    assert res.success and len(res.t) == 10001
    zero_v = np.zeros(10)
    left = 0
    for i in range(len(res.t)):
        f = vehicle_contacts.evaluate_force(res.u[i], zero_v, res.t[i])
        for j in WHEELSETS:
            z = res.u[i, j]
            if z < 0.0:  # wheel above the rail (z positive down)
                assert f[j] == 0.0, (res.t[i], j, z, f[j])
                left += 1
            elif z > 0.0:
                assert f[j] == pytest.approx(2 * (z / G_HERTZ) ** 1.5, rel=1e-12)
    # each wheelset leaves the rail at some point in this run
    airborne = (res.u[:, WHEELSETS] < 0.0).sum(axis=0)
    assert np.all(airborne > 0), airborne
    assert left == airborne.sum()


# ---------------------------------------------------------------------------
# pendulum IC2 and hardening references


def test_pendulum_ic2_maximum_angle_is_pi_over_3():
    p = nvib.load_scene("pendulum_ic2")
    # energy: 1/2 theta'(0)^2 = (g/l)(1 - cos theta_max) -> theta_max = 2 arcsin(1/2)
    assert 2 * math.asin(0.5 * p.v0[0]) == pytest.approx(math.pi / 3, rel=1e-15)
    res = nvib.solve(p, nvib.CEMDTS(), dt=1e-3, t_end=10.0)
    assert abs(res.u[:, 0].max() - math.pi / 3) < 1e-4
    assert abs(res.u[:, 0].min() + math.pi / 3) < 1e-4


def test_hardening_exact_solution_conserves_energy():
    t = np.linspace(0.0, 3.0, 30001)  # about 34 periods
    x, v = nvib.exact.hardening(t, m=1.0, k0=100.0, a=30.0, x0=1.5)
    assert x[0] == 1.5 and v[0] == 0.0
    E = nvib.exact.hardening_energy(x, v, m=1.0, k0=100.0, a=30.0)
    E0 = 100.0 * (0.5 * 1.5**2 + 0.25 * 30.0 * 1.5**4)
    assert E[0] == pytest.approx(E0, rel=1e-15)
    assert np.max(np.abs(E - E0)) / E0 < 1e-12


def test_hardening_exact_solution_against_dop853():
    from scipy.integrate import solve_ivp

    m, k0, a, x0 = 1.0, 100.0, 30.0, 1.5
    t = np.linspace(0.0, 0.6, 601)
    sol = solve_ivp(lambda _, y: [y[1], -k0 * (1 + a * y[0] ** 2) * y[0] / m], (0.0, 0.6), [x0, 0.0],
                    method="DOP853", rtol=1e-12, atol=1e-12, t_eval=t)
    assert sol.success
    x, v = nvib.exact.hardening(t, m=m, k0=k0, a=a, x0=x0)
    vmax = np.max(np.abs(v))
    assert np.max(np.abs(sol.y[0] - x)) < 1e-8 * x0
    assert np.max(np.abs(sol.y[1] - v)) < 1e-8 * vmax
    # period: back at x0 with zero velocity, at -x0 after half a period
    T = nvib.exact.hardening_period(m=m, k0=k0, a=a, x0=x0)
    xs, vs = nvib.exact.hardening(np.array([T / 2, T]), m=m, k0=k0, a=a, x0=x0)
    np.testing.assert_allclose(xs, [-x0, x0], rtol=1e-12)
    np.testing.assert_allclose(vs, 0.0, atol=1e-10 * vmax)
    sol_T = solve_ivp(lambda _, y: [y[1], -k0 * (1 + a * y[0] ** 2) * y[0] / m], (0.0, T), [x0, 0.0],
                      method="DOP853", rtol=1e-12, atol=1e-12)
    assert sol_T.y[0, -1] == pytest.approx(x0, rel=1e-9)


def test_hardening_scene_matches_the_exact_solution():
    h = nvib.load_scene("hardening")
    res = nvib.solve(h, nvib.Newmark(), dt=1e-5, t_end=0.3, save_every=100)
    x, _ = nvib.exact.hardening(res.t, m=1.0, k0=100.0, a=30.0, x0=1.5)
    assert np.max(np.abs(res.u[:, 0] - x)) < 1e-4


# ---------------------------------------------------------------------------
# scene-file errors: the message names the file, the effect index and the key

GOOD = """\
[scene]
name = "chain"
dt = 0.001
t_end = 0.1

[dofs]
names = ["x1", "x2", "x3"]
mass = [1.0, 2.0, 3.0]

[initial]
u = [0.0, 0.1, 0.0]

[[effect]]
type = "spring"
measure = { x1 = 1.0 }
k = 100.0

[[effect]]
type = "damper"
measure = { x2 = 1.0, x1 = -1.0 }
c = 0.5

[[effect]]
type = "cubic_spring"
measure = { x3 = 1.0, x2 = -1.0 }
k3 = 10.0

[[effect]]
type = "hardening_spring"
measure = { x3 = 1.0 }
k0 = 100.0
a = 2.0
"""


def write(tmp_path, text, name="scene.toml"):
    p = tmp_path / name
    p.write_text(text)
    return str(p)


def scene_error(tmp_path, text):
    path = write(tmp_path, text)
    with pytest.raises(nvib.SceneError) as info:
        nvib.load_scene(path)
    msg = str(info.value)
    assert msg.startswith(path), msg
    return msg


def test_the_good_scene_loads(tmp_path):
    m = nvib.load_scene(write(tmp_path, GOOD))
    assert m.dofs == ["x1", "x2", "x3"] and m.scene["name"] == "chain"
    assert issubclass(nvib.SceneError, ValueError)


def test_error_unknown_effect_type(tmp_path):
    msg = scene_error(tmp_path, GOOD.replace('type = "cubic_spring"', 'type = "cubic_sprung"'))
    assert "effects[2].type" in msg and "cubic_sprung" in msg


def test_error_unknown_dof_in_a_measure(tmp_path):
    msg = scene_error(tmp_path, GOOD.replace("measure = { x3 = 1.0, x2 = -1.0 }", "measure = { x3 = 1.0, x9 = -1.0 }"))
    assert "effects[2].measure" in msg and "x9" in msg


def test_error_wrong_mass_length(tmp_path):
    msg = scene_error(tmp_path, GOOD.replace("mass = [1.0, 2.0, 3.0]", "mass = [1.0, 2.0]"))
    assert "mass" in msg and "3" in msg


def test_error_missing_parameter(tmp_path):
    msg = scene_error(tmp_path, GOOD.replace("k0 = 100.0\n", ""))
    assert "effects[3].k0" in msg and "missing" in msg


def test_error_missing_measure(tmp_path):
    msg = scene_error(tmp_path, GOOD.replace("measure = { x2 = 1.0, x1 = -1.0 }\n", ""))
    assert "effects[1].measure" in msg and "missing" in msg


def test_error_unknown_parameter(tmp_path):
    msg = scene_error(tmp_path, GOOD.replace("k3 = 10.0", "k3 = 10.0\nk4 = 1.0"))
    assert "effects[2].k4" in msg


def test_error_bad_parameter_value(tmp_path):
    msg = scene_error(tmp_path, GOOD.replace("k3 = 10.0", 'k3 = "ten"'))
    assert "effects[2].k3" in msg


def test_error_negative_mass(tmp_path):
    msg = scene_error(tmp_path, GOOD.replace("mass = [1.0, 2.0, 3.0]", "mass = [1.0, -2.0, 3.0]"))
    assert "mass" in msg and "x2" in msg


def test_error_dense_mass_not_positive_definite(tmp_path):
    msg = scene_error(tmp_path, GOOD.replace("mass = [1.0, 2.0, 3.0]",
                                             "mass = [[1.0, 0.0, 0.0], [0.0, -2.0, 0.0], [0.0, 0.0, 3.0]]"))
    assert "mass" in msg


def test_error_malformed_toml(tmp_path):
    msg = scene_error(tmp_path, GOOD.replace("k = 100.0", "k = = 100.0"))
    assert "TOML" in msg and "line 16" in msg


def test_error_unknown_top_level_table(tmp_path):
    msg = scene_error(tmp_path, GOOD + "\n[solver]\nscheme = \"CEMDTS\"\n")
    assert "solver" in msg


def test_error_unknown_scene_key(tmp_path):
    msg = scene_error(tmp_path, GOOD.replace("dt = 0.001", "dt = 0.001\nschme = \"CEMDTS\""))
    assert "[scene]" in msg and "schme" in msg


def test_error_static_equilibrium_misspelled(tmp_path):
    msg = scene_error(tmp_path, GOOD.replace("u = [0.0, 0.1, 0.0]", 'u = "static_equilibrum"'))
    assert "[initial] u" in msg and "static_equilibrum" in msg and "static_equilibrium" in msg


def test_error_initial_state_wrong_length_and_unknown_dof(tmp_path):
    msg = scene_error(tmp_path, GOOD.replace("u = [0.0, 0.1, 0.0]", "u = [0.0, 0.1]"))
    assert "[initial] u" in msg
    msg = scene_error(tmp_path, GOOD.replace("u = [0.0, 0.1, 0.0]", "u = { x7 = 0.1 }"))
    assert "[initial] u" in msg and "x7" in msg


def test_error_unknown_plot_dof(tmp_path):
    msg = scene_error(tmp_path, GOOD.replace("dt = 0.001", 'dt = 0.001\nplot_dof = "x8"'))
    assert "plot_dof" in msg and "x8" in msg


def test_error_bad_signal(tmp_path):
    text = GOOD + '\n[[effect]]\ntype = "ground_acceleration"\nsignal = { kind = "square", amplitude = 1.0 }\n'
    msg = scene_error(tmp_path, text)
    assert "effects[4].signal.kind" in msg
    text = GOOD + '\n[[effect]]\ntype = "ground_acceleration"\nsignal = { kind = "table", t = [0.0, 1.0], values = [1.0] }\n'
    msg = scene_error(tmp_path, text)
    assert "effects[4].signal.values" in msg


def test_static_equilibrium_from_a_scene(tmp_path):
    text = GOOD.replace("u = [0.0, 0.1, 0.0]", 'u = "static_equilibrium"') + (
        '\n[[effect]]\ntype = "constant_force"\nmeasure = { x1 = 1.0 }\nvalue = 5.0\n')
    m = nvib.load_scene(write(tmp_path, text))
    assert m.scene["initial_u"] == "static_equilibrium"
    np.testing.assert_allclose(m.evaluate_force(m.u0, np.zeros(3)), 0.0, atol=1e-10)
    # only the spring on x1 carries the load: x1 = 5 / 100
    assert m.u0[0] == pytest.approx(0.05, rel=1e-12)


def test_unknown_builtin_scene():
    with pytest.raises(ValueError, match="nosuchscene"):
        nvib.load_scene("nosuchscene")


WHEELSET_ON_RAIL = """\
[scene]
name = "wheelset"
dt = 1e-4
t_end = 0.01

[dofs]
names = ["z_w"]
mass = [2200.0]

[initial]
u = "static_equilibrium"

[[effect]]
type = "constant_force"
name = "gravity"
measure = { z_w = 1.0 }
value = 21582.0

[[effect]]
type = "hertz_contact"
name = "contact"
measure = { z_w = 1.0 }
G = 5.18e-08
contacts = 2.0
"""


def test_static_equilibrium_of_a_body_held_only_by_a_contact(tmp_path):
    # the simplest body a contact holds: a wheelset resting on the rail under
    # its weight W. Equilibrium: 2 (z/G)^{3/2} = W  ->  z = G (W/2)^{2/3}.
    m = nvib.load_scene(write(tmp_path, WHEELSET_ON_RAIL))
    assert m.u0[0] == pytest.approx(G_HERTZ * (21582.0 / 2) ** (2.0 / 3.0), rel=1e-9)
