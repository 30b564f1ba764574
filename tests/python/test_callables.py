"""Python force callables: the same physics as the built-in effects, and
errors raised or returned by callbacks reach the caller intact."""

from __future__ import annotations

import numpy as np
import pytest

import nvib

from _registry import is_implicit, scheme_variants, with_newton

M, K0, A, X0 = 1.0, 100.0, 30.0, 1.5
DT, T_END = 1e-3, 0.5


# Same floating-point operations as the C++ law k0 (1 + a d^2) d and its derivative.
def hardening_force(u, v, t):
    return K0 * (1.0 + A * u * u) * u


def hardening_tangent(u, v, t):
    return np.array([[K0 * (1.0 + 3.0 * A * u[0] * u[0])]]), None


def effect_model():
    return nvib.Model([M], effects=[{"type": "hardening_spring", "measure": {"x": 1.0}, "k0": K0, "a": A}],
                      dofs=["x"], u0=[X0])


def callable_model(with_tangent: bool, **flags):
    return nvib.Model([M], force=hardening_force, tangent=hardening_tangent if with_tangent else None, u0=[X0],
                      **flags)


SCHEMES = scheme_variants()
# The schemes that take tangents (implicit ones, and PIM for its linear part), as a short run shows.
TANGENT_USERS = [name for name, s in SCHEMES.items()
                 if nvib.solve(effect_model(), s, dt=DT, t_end=10 * DT).stats.num_tangent_evals > 0]


def assert_same(r, ref, rel, what):
    for attr in ("u", "v", "a"):
        x, y = getattr(r, attr), getattr(ref, attr)
        scale = np.max(np.abs(y))
        err = np.max(np.abs(x - y))
        assert err <= rel * scale, f"{what}, {attr}: max |diff| = {err:.3e} (scale {scale:.3e})"


@pytest.mark.parametrize("flags", [{}, {"uses_velocity": False, "uses_time": False}], ids=["default", "flags-off"])
@pytest.mark.parametrize("name", list(SCHEMES))
def test_callable_with_tangent_matches_effect(name, flags):
    ref = nvib.solve(effect_model(), SCHEMES[name], dt=DT, t_end=T_END)
    r = nvib.solve(callable_model(True, **flags), SCHEMES[name], dt=DT, t_end=T_END)
    assert_same(r, ref, 1e-12, name)
    assert r.stats.num_force_evals == ref.stats.num_force_evals
    assert r.stats.num_fd_force_evals == 0


@pytest.mark.parametrize("name", list(SCHEMES))
def test_callable_without_tangent_matches_effect(name):
    """Without a tangent the callable is differentiated numerically. Newton-type
    schemes are then compared with the effect model run with
    jacobian="finite_difference" (the same differences of the same function);
    PIM's linear part is the tangent at the origin, whose central difference
    k0 (1 + a h^2), h = eps^(1/3), is off by a h^2 ~ 1e-9 relative, which only
    moves the linear/nonlinear split: allow 1e-9 relative there."""
    scheme = SCHEMES[name]
    ref = nvib.solve(effect_model(), with_newton(scheme, jacobian="finite_difference"), dt=DT, t_end=T_END)
    r = nvib.solve(callable_model(False, uses_velocity=False, uses_time=False), scheme, dt=DT, t_end=T_END)
    split_only = name in TANGENT_USERS and not is_implicit(scheme)  # PIM: the tangent sets the linear part
    assert_same(r, ref, 1e-9 if split_only else 1e-12, name)
    # every tangent a scheme takes is then a finite difference; a scheme without tangents takes none
    assert (r.stats.num_fd_force_evals > 0) == (name in TANGENT_USERS)
    if name not in TANGENT_USERS:
        assert r.stats.num_tangent_evals == 0


def test_multi_dof_callable_matches_effects():
    """A 2-DOF chain with a coupling measure: effects vs the equivalent callable with tangent."""
    eff = [{"type": "spring", "measure": {"a": 1.0}, "k": 200.0},
           {"type": "hardening_spring", "measure": {"b": 1.0, "a": -1.0}, "k0": 50.0, "a": 20.0},
           {"type": "damper", "measure": {"b": 1.0, "a": -1.0}, "c": 0.4},
           {"type": "harmonic_force", "measure": {"b": 1.0}, "amplitude": 3.0, "omega": 5.0, "phase": 0.1}]
    md = nvib.Model([1.0, 0.5], effects=eff, dofs=["a", "b"], u0=[0.1, 0.4])

    def force(u, v, t):
        d = u[1] - u[0]
        f = 50.0 * (1.0 + 20.0 * d * d) * d
        p = -3.0 * np.sin(5.0 * t + 0.1)
        return np.array([-f, f + p])

    def tangent(u, v, t):
        d = u[1] - u[0]
        k = 50.0 * (1.0 + 3.0 * 20.0 * d * d)
        return np.array([[k, -k], [-k, k]]), None

    K = np.array([[200.0, 0.0], [0.0, 0.0]])
    C = np.array([[0.4, -0.4], [-0.4, 0.4]])
    mc = nvib.Model([1.0, 0.5], K=K, C=C, force=force, tangent=tangent, u0=[0.1, 0.4], uses_velocity=False)
    for name in SCHEMES:
        ref = nvib.solve(md, SCHEMES[name], dt=DT, t_end=T_END)
        r = nvib.solve(mc, SCHEMES[name], dt=DT, t_end=T_END)
        # the load is summed in another order than in C++: round-off only
        assert_same(r, ref, 1e-11, name)


# --------------------------------------------------------------------------- errors
class CustomError(Exception):
    pass


ERROR_SCHEMES = list(SCHEMES)


def raising_force(when):
    def force(u, v, t):
        if t >= when:
            raise CustomError(f"custom failure at t={t:.4f}")
        return hardening_force(u, v, t)
    return force


@pytest.mark.parametrize("when", [0.0, 0.0105], ids=["at-a0", "mid-run"])
@pytest.mark.parametrize("name", ERROR_SCHEMES)
def test_force_exception_propagates(name, when):
    md = nvib.Model([M], force=raising_force(when), tangent=hardening_tangent, u0=[X0])
    with pytest.raises(CustomError, match=r"^custom failure at t=") as info:
        nvib.solve(md, SCHEMES[name], dt=DT, t_end=T_END)
    assert type(info.value) is CustomError
    # also through the Stepper
    with pytest.raises(CustomError):
        st = nvib.Stepper(md, SCHEMES[name], DT)
        st.step(100)


@pytest.mark.parametrize("name", TANGENT_USERS)
def test_tangent_exception_propagates(name):
    def tangent(u, v, t):
        raise CustomError("tangent failure")

    md = nvib.Model([M], force=hardening_force, tangent=tangent, u0=[X0])
    with pytest.raises(CustomError, match=r"^tangent failure$"):
        nvib.solve(md, SCHEMES[name], dt=DT, t_end=T_END)


@pytest.mark.parametrize("name", ERROR_SCHEMES)
def test_zero_division_in_force_propagates(name):
    def force(u, v, t):
        if t > 0.005:
            return np.array([1.0 / 0.0])
        return hardening_force(u, v, t)

    md = nvib.Model([M], force=force, tangent=hardening_tangent, u0=[X0])
    with pytest.raises(ZeroDivisionError):
        nvib.solve(md, SCHEMES[name], dt=DT, t_end=T_END)


def test_zero_division_in_tangent_propagates():
    def tangent(u, v, t):
        return np.array([[1 / 0]]), None

    md = nvib.Model([M], force=hardening_force, tangent=tangent, u0=[X0])
    with pytest.raises(ZeroDivisionError):
        nvib.solve(md, nvib.Newmark(), dt=DT, t_end=T_END)


@pytest.mark.parametrize("name", ERROR_SCHEMES)
def test_keyboard_interrupt_in_force_propagates(name):
    def force(u, v, t):
        if t > 0.02:
            raise KeyboardInterrupt
        return hardening_force(u, v, t)

    md = nvib.Model([M], force=force, tangent=hardening_tangent, u0=[X0])
    with pytest.raises(KeyboardInterrupt):
        nvib.solve(md, SCHEMES[name], dt=DT, t_end=T_END)


def test_keyboard_interrupt_in_tangent_propagates():
    def tangent(u, v, t):
        raise KeyboardInterrupt

    md = nvib.Model([M], force=hardening_force, tangent=tangent, u0=[X0])
    with pytest.raises(KeyboardInterrupt):
        nvib.solve(md, nvib.Newmark(), dt=DT, t_end=T_END)


BAD_SHAPES = {
    "too long": lambda u, v, t: np.zeros(3),
    "2-D": lambda u, v, t: np.zeros((1, 1)),
    "empty": lambda u, v, t: np.zeros(0),
}


@pytest.mark.parametrize("name", list(SCHEMES))
@pytest.mark.parametrize("bad", list(BAD_SHAPES))
def test_wrong_shape_raises_value_error(bad, name):
    md = nvib.Model([M], force=BAD_SHAPES[bad], tangent=hardening_tangent, u0=[X0])
    with pytest.raises(ValueError, match="force"):
        nvib.solve(md, SCHEMES[name], dt=DT, t_end=T_END)


def test_wrong_shape_multi_dof_and_later_in_the_run():
    def force(u, v, t):
        return np.zeros(2) if t < 0.01 else np.zeros(3)

    md = nvib.Model([1.0, 1.0], force=force, u0=[0.0, 0.0])
    with pytest.raises(ValueError, match=r"force.*shape \(3,\)"):
        nvib.solve(md, nvib.CentralDifference(), dt=DT, t_end=T_END)


def test_wrong_tangent_shape_raises_value_error():
    md = nvib.Model([M], force=hardening_force, tangent=lambda u, v, t: (np.zeros((2, 2)), None), u0=[X0])
    with pytest.raises(ValueError, match="tangent"):
        nvib.solve(md, nvib.Newmark(), dt=DT, t_end=T_END)


@pytest.mark.parametrize("value", [np.array([1.0 + 2.0j]), np.array(["a"]), np.array([b"x"]), "abc"],
                         ids=["complex", "str-array", "bytes-array", "str"])
@pytest.mark.parametrize("name", list(SCHEMES))
def test_non_real_return_raises_type_error(value, name):
    md = nvib.Model([M], force=lambda u, v, t: value, tangent=hardening_tangent, u0=[X0])
    with pytest.raises(TypeError, match="force"):
        nvib.solve(md, SCHEMES[name], dt=DT, t_end=T_END)


def test_none_return_raises_type_error():
    md = nvib.Model([M], force=lambda u, v, t: None, u0=[X0])
    with pytest.raises(TypeError, match="force"):
        nvib.solve(md, nvib.CentralDifference(), dt=DT, t_end=T_END)


def test_list_and_integer_returns_are_accepted():
    r1 = nvib.solve(nvib.Model([M], force=lambda u, v, t: [100.0 * u[0]], u0=[1.0]), nvib.CentralDifference(),
                    dt=DT, t_end=0.1)
    r2 = nvib.solve(nvib.Model([M], K=[[100.0]], u0=[1.0]), nvib.CentralDifference(), dt=DT, t_end=0.1)
    assert np.array_equal(r1.u, r2.u)
    r3 = nvib.solve(nvib.Model([M], force=lambda u, v, t: np.array([0]), u0=[1.0], v0=[2.0]),
                    nvib.CentralDifference(), dt=DT, t_end=0.1)
    assert r3.u[-1, 0] == pytest.approx(1.0 + 2.0 * 0.1, rel=1e-12)


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
@pytest.mark.parametrize("name", list(SCHEMES))
def test_non_finite_at_a_normal_state_raises_value_error(name, bad):
    def force(u, v, t):
        return np.array([bad]) if t > 0.01 else hardening_force(u, v, t)

    md = nvib.Model([M], force=force, tangent=hardening_tangent, u0=[X0])
    with pytest.raises(ValueError, match="non-finite"):
        nvib.solve(md, SCHEMES[name], dt=DT, t_end=T_END)


def test_non_finite_tangent_raises_value_error():
    md = nvib.Model([M], force=hardening_force, tangent=lambda u, v, t: (np.array([[np.nan]]), None), u0=[X0])
    with pytest.raises(ValueError, match="tangent"):
        nvib.solve(md, nvib.Newmark(), dt=DT, t_end=T_END)


def test_overflow_of_a_diverging_run_is_divergence_not_a_callback_error():
    """NaN from the callback once the state is astronomically large is reported as divergence."""
    def force(u, v, t):
        if abs(u[0]) > 1e31:
            return np.array([np.nan])
        return 1e4 * u

    md = nvib.Model([M], force=force, u0=[1.0], uses_velocity=False, uses_time=False)
    res = nvib.solve(md, nvib.CentralDifference(), dt=0.03, t_end=100.0, throw=False)
    assert res.status == nvib.Status.diverged
    with pytest.raises(nvib.DivergenceError):
        nvib.solve(md, nvib.CentralDifference(), dt=0.03, t_end=100.0)


def _overflowing_force(u, v, t):
    """A stiffening law whose value overflows to inf near |u| = 3e7, far below 1e30 but beyond the bound."""
    with np.errstate(over="ignore"):
        return 100.0 * u + u ** 41


@pytest.mark.parametrize("via", ["solve", "stepper"])
def test_force_overflow_beyond_the_divergence_bound_is_divergence_with_partial_history(via):
    """Past the run's divergence bound (1e10 here) an overflowing force is a divergence of the run, reported
    with its step, time and DOF and the partial history, not a callback error that loses the history."""
    md = nvib.Model([M], force=_overflowing_force, u0=[1.0], uses_velocity=False, uses_time=False)
    if via == "solve":
        res = nvib.solve(md, nvib.CentralDifference(), dt=0.3, t_end=10.0, throw=False)
    else:
        res = nvib.Stepper(md, nvib.CentralDifference(), 0.3).integrate(10.0, throw=False)
    assert res.status == nvib.Status.diverged
    assert res.failure.step == 2 and res.failure.t == pytest.approx(0.6) and res.failure.dof == 0
    assert "beyond the bound 1e+10" in res.failure.message
    np.testing.assert_array_equal(res.t, [0.0, 0.3])  # the states before the divergence are kept
    assert np.all(np.isfinite(res.u))


def test_force_overflow_within_a_raised_bound_is_a_callback_error():
    """With the bound raised above the state where the law overflows, the same inf is a callback error."""
    md = nvib.Model([M], force=_overflowing_force, u0=[1.0], uses_velocity=False, uses_time=False)
    with pytest.raises(ValueError, match="force returned a non-finite value at t = 0.6"):
        nvib.solve(md, nvib.CentralDifference(), dt=0.3, t_end=10.0, max_displacement=1e25)


def test_callback_receives_fresh_arrays_and_time():
    seen = []

    def force(u, v, t):
        assert isinstance(u, np.ndarray) and isinstance(v, np.ndarray) and isinstance(t, float)
        assert u.shape == (2,) and v.shape == (2,) and u.dtype == np.float64
        seen.append((t, u.copy()))
        u[:] = 1e9  # mutating the argument must not corrupt the integrator
        return np.array([10.0, 10.0])

    md = nvib.Model([1.0, 1.0], force=force, u0=[0.5, -0.5], v0=[0.0, 0.0], uses_velocity=False)
    res = nvib.solve(md, nvib.CentralDifference(), dt=0.1, t_end=1.3, t0=1.0)
    assert [t for t, _ in seen] == pytest.approx([1.0, 1.1, 1.2, 1.3])
    # constant force: u = u0 - 10 t^2 / 2 exactly up to round-off
    tt = res.t - 1.0
    assert np.allclose(res.u, np.array([0.5, -0.5]) - 5.0 * tt[:, None] ** 2, rtol=0, atol=1e-12)
