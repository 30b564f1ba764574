"""References: the closed forms (pendulum, hardening oscillator, linear oscillator) against DOP853 and
against periods measured on a numerical solution; which reference each scene gets; the DOP853 driver."""

import math

import numpy as np
import pytest
from scipy import optimize
from scipy.integrate import solve_ivp

import nvib
from nvib import exact


def zero_crossings(f, t0, t1, n=4000):
    """Times where f changes sign on [t0, t1], refined by Brent's method."""
    grid = np.linspace(t0, t1, n)
    vals = np.array([f(t) for t in grid])
    out = []
    for i in np.nonzero(np.sign(vals[:-1]) * np.sign(vals[1:]) < 0)[0]:
        out.append(optimize.brentq(f, grid[i], grid[i + 1], xtol=1e-15, rtol=1e-15))
    return np.array(out)


# ---------------------------------------------------------------- closed forms against DOP853

@pytest.mark.parametrize("scene", ["pendulum", "pendulum_ic2"])
def test_elliptic_pendulum_matches_dop853(scene):
    model = nvib.load_scene(scene)
    t_end = model.scene["t_end"]
    closed = nvib.reference(model, t_end)
    assert closed.kind == "closed_form" and "Jacobi" in closed.description
    num = nvib.reference(model, t_end, method="dop853", rtol=1e-13)
    assert num.kind == "dop853"
    t = np.linspace(0.0, t_end, 3001)
    uc, vc = closed(t)
    un, vn = num(t)
    assert uc.shape == (t.size, 1)
    assert np.max(np.abs(uc - un)) / np.max(np.abs(un)) <= 1e-10
    assert np.max(np.abs(vc - vn)) / np.max(np.abs(vn)) <= 1e-10
    # the start is the scene's
    assert uc[0, 0] == pytest.approx(model.u0[0], abs=1e-14)
    assert vc[0, 0] == pytest.approx(model.v0[0], abs=1e-14)


def test_pendulum_closed_form_any_start_and_its_maximum_angle():
    t = np.linspace(0.0, 20.0, 2001)
    for th0, w0 in [(0.3, -0.7), (-1.0, 0.5), (2.0, 0.3)]:
        sol = solve_ivp(lambda _, y: [y[1], -np.sin(y[0])], (0, 20), [th0, w0], method="DOP853", rtol=1e-13,
                        atol=1e-14, t_eval=t)
        th, om = exact.pendulum(t, theta0=th0, v0=w0)
        assert np.max(np.abs(th - sol.y[0])) <= 1e-10
        assert np.max(np.abs(om - sol.y[1])) <= 1e-10
    # IC2 of the paper: theta(0) = 0, theta'(0) = 1 rad/s swings to pi/3, period 4 K(1/4)
    th, _ = exact.pendulum(np.linspace(0, 7, 70001), theta0=0.0, v0=1.0)
    assert np.max(th) == pytest.approx(math.pi / 3, abs=1e-8)
    assert exact.pendulum_period(theta0=0.0, v0=1.0) == pytest.approx(6.74300142, abs=1e-8)
    assert exact.pendulum_period(theta0=math.pi / 6) == pytest.approx(6.39256801, abs=1e-8)


def test_pendulum_over_the_top_has_no_closed_form_here():
    with pytest.raises(ValueError, match="theta0, v0: the pendulum goes over the top"):
        exact.pendulum([0.0], theta0=0.0, v0=2.5)
    model = nvib.Model([1.0], effects=[{"type": "pendulum_gravity", "measure": {"u0": 1.0}, "m": 1.0, "g": 1.0,
                                        "l": 1.0}], v0=[2.5])
    ref = nvib.reference(model, 2.0)
    assert ref.kind == "dop853"
    with pytest.raises(ValueError, match="method: no closed form"):
        nvib.reference(model, 2.0, method="closed_form")


# ---------------------------------------------------------------- periods measured on a numerical solution

def test_hardening_period_matches_a_measured_one():
    model = nvib.load_scene("hardening")
    num = nvib.reference(model, 0.3, method="dop853", rtol=1e-13)
    crossings = zero_crossings(lambda t: num.u(np.array([t]))[0, 0], 0.0, 0.3)
    assert len(crossings) >= 5
    measured = crossings[4] - crossings[0]  # two periods
    period = exact.hardening_period(m=1.0, k0=100.0, a=30.0, x0=1.5)
    assert measured / 2 == pytest.approx(period, rel=1e-10)
    # the scene gets the closed form, which crosses zero at the same times
    closed = nvib.reference(model, 0.3)
    assert closed.kind == "closed_form"
    assert np.max(np.abs(closed.u(crossings))) <= 1e-9


def test_hardening_from_a_moving_start():
    m, k0, a, x0, v0 = 2.0, 50.0, 4.0, -0.4, 3.0
    T = exact.hardening_period(m=m, k0=k0, a=a, x0=x0, v0=v0)
    sol = solve_ivp(lambda _, y: [y[1], -k0 * (1 + a * y[0] ** 2) * y[0] / m], (0, 3 * T), [x0, v0],
                    method="DOP853", rtol=1e-13, atol=1e-14, dense_output=True)
    t = np.linspace(0, 3 * T, 1501)
    x, v = exact.hardening(t, m=m, k0=k0, a=a, x0=x0, v0=v0)
    assert np.max(np.abs(x - sol.sol(t)[0])) <= 1e-10
    assert np.max(np.abs(v - sol.sol(t)[1])) <= 1e-9
    crossings = zero_crossings(lambda s: sol.sol(s)[0], 0.0, 3 * T)
    assert crossings[2] - crossings[0] == pytest.approx(T, rel=1e-10)
    with pytest.raises(ValueError, match="^a: must be >= 0"):
        exact.hardening([0.0], k0=100.0, a=-1.0, x0=1.0, v0=1.0)


def test_pendulum_period_matches_a_measured_one():
    model = nvib.load_scene("pendulum")  # IC1, near the separatrix
    ref = nvib.reference(model, 35.0, method="dop853", rtol=1e-13)
    crossings = zero_crossings(lambda t: ref.u(np.array([t]))[0, 0], 0.0, 35.0)
    assert len(crossings) == 4
    assert (crossings[3] - crossings[1]) / 1.0 == pytest.approx(exact.pendulum_period(theta0=-0.95 * math.pi), rel=1e-10)


# ---------------------------------------------------------------- the other closed form and the detection

def test_linear_oscillator_closed_form_is_read_from_the_model():
    model = nvib.Model([2.0], effects=[{"type": "spring", "measure": {"x": 2.0}, "k": 2.0},
                                       {"type": "damper", "measure": {"x": 1.0}, "c": 0.4}],
                       dofs=["x"], u0=[1.0], v0=[0.5])
    ref = nvib.reference(model, 5.0)
    assert ref.kind == "closed_form" and "k = 8" in ref.description and "c = 0.4" in ref.description
    num = nvib.reference(model, 5.0, method="dop853")
    t = np.linspace(0, 5, 501)
    assert np.max(np.abs(ref.u(t) - num.u(t))) <= 1e-10
    # from K and C matrices as well
    ref2 = nvib.reference(nvib.Model([2.0], K=[[8.0]], C=[[0.4]], u0=[1.0], v0=[0.5]), 5.0)
    assert ref2.kind == "closed_form"
    assert np.max(np.abs(ref2.u(t) - ref.u(t))) <= 1e-14


def test_models_without_a_closed_form_get_dop853():
    # a Python force: the law is unknown to nvib
    model = nvib.Model([1.0], force=lambda u, v, t: 100.0 * (1 + 30.0 * u ** 2) * u, u0=[1.5],
                       uses_velocity=False, uses_time=False)
    ref = nvib.reference(model, 0.3)
    assert ref.kind == "dop853" and "DOP853" in ref.description and ref.rtol == 1e-12
    t = np.linspace(0, 0.3, 301)
    x, _ = exact.hardening(t, x0=1.5)
    assert np.max(np.abs(ref.u(t)[:, 0] - x)) / 1.5 <= 1e-10
    # a hardening spring with a load on it
    model = nvib.Model([1.0], effects=[{"type": "hardening_spring", "measure": {"x": 1.0}, "k0": 100.0, "a": 30.0},
                                       {"type": "harmonic_force", "measure": {"x": 1.0}, "amplitude": 1.0,
                                        "omega": 3.0}], dofs=["x"])
    assert nvib.reference(model, 0.1).kind == "dop853"


def test_scene_references_and_the_dop853_check():
    building = nvib.load_scene("building")
    ref = nvib.reference(building, 1.0, check=True)
    assert ref.kind == "dop853"
    assert ref.check_rtol == pytest.approx(1e-13)
    assert ref.check_difference.shape == (6,)
    assert np.max(ref.check_difference) <= 1e-9
    assert ref.num_force_evals > 0 and ref.atol.shape == (12,)
    assert np.all(ref.u([0.0]) == 0.0)
    # the vehicle starts from its static equilibrium and restarts at contact events
    vehicle = nvib.load_scene("vehicle")
    ref = nvib.reference(vehicle, 0.05)
    np.testing.assert_allclose(ref.u([0.0])[0], vehicle.u0, rtol=0, atol=1e-15)
    np.testing.assert_allclose(ref.v([0.0])[0], vehicle.v0, rtol=0, atol=1e-15)
    assert ref.num_segments >= 1
    assert ref.u([0.01, 0.02], dofs=["z_w1"]).shape == (2, 1)


def test_the_vehicle_reference_stops_where_a_contact_opens():
    """Contacts that open and close: the solve is split there, and agrees with a tighter one."""
    vehicle = nvib.load_scene("vehicle")
    ref = nvib.reference(vehicle, 0.2, check=True)
    assert ref.num_segments > 1 and "contact events" in ref.description
    assert np.max(ref.check_difference[6:]) <= 1e-8  # wheelsets


def test_references_are_cached_per_model_and_state():
    model = nvib.load_scene("pendulum_ic2")
    a = nvib.reference(model, 10.0)
    assert nvib.reference(model, 10.0) is a
    assert nvib.reference(model, 10.0, v0=[0.5]) is not a
    assert nvib.reference(model, 10.0, cache=False) is not a


def test_reference_bad_input_names_the_argument():
    model = nvib.load_scene("hardening")
    with pytest.raises(ValueError, match="t_end"):
        nvib.reference(model, -1.0)
    with pytest.raises(ValueError, match="method"):
        nvib.reference(model, 1.0, method="rk4")
    with pytest.raises(ValueError, match="rtol"):
        nvib.reference(model, 1.0, method="dop853", rtol=1e-16)
    with pytest.raises(TypeError, match="model"):
        nvib.reference("hardening", 1.0)
    with pytest.raises(ValueError, match="u0"):
        nvib.reference(model, 1.0, u0=[1.0, 2.0])
    ref = nvib.reference(model, 0.3)
    with pytest.raises(ValueError, match="t: the reference covers"):
        ref([0.5])
    with pytest.raises(ValueError, match="dofs"):
        ref.u([0.1], dofs=["y"])


def test_a_model_with_memory_has_no_dop853_reference():
    """DOP853 integrates F(u, v, t) only: a bilinear storey would be followed from its initial state. The
    reference refuses such a model and names its laws, rather than return a wrong trajectory."""
    model = nvib.load_scene("building_inelastic")
    with pytest.raises(nvib.ArgumentError, match=r"model: its laws with memory \(storey1"):
        nvib.reference(model, 1.0)
