"""The exact elastic spectrum kernel (nvib._core.elastic_spectrum, cpp/include/nvib/solve/spectrum.hpp)
against an independent closed form of the piecewise-linear record (a sum of ramp responses), the
continuous-time peak between samples, the NumPy recurrence at the samples (exact_sdof_peaks), and its
argument checks. The step and ramp closed forms for every damping regime are in tests/cpp/test_spectrum.cpp."""

import math
import threading

import numpy as np
import pytest

import nvib
from nvib import _core
from nvib.analysis.spectrum import exact_sdof_peaks


def ramp_responses(t, knots, slopes, T, z):
    """u, u' of u'' + 2 z w u' + w^2 u = -a_g from rest, a_g = sum_k slopes[k] (t - knots[k])_+ (a record that is
    0 at t = 0 and linear between the knots), by superposing the closed-form response to a unit ramp:
    x = t - 2z/w + e^{-z w t}((2z/w) cos wd t - ((1 - 2z^2)/wd) sin wd t), u = -x / w^2."""
    w = 2 * math.pi / T
    wd = w * math.sqrt(1 - z * z)
    tau = np.maximum(t[:, None] - knots[None, :], 0.0)
    e = np.exp(-z * w * tau)
    x = tau - 2 * z / w + e * ((2 * z / w) * np.cos(wd * tau) - ((1 - 2 * z * z) / wd) * np.sin(wd * tau))
    dx = 1 - e * (np.cos(wd * tau) + z * w / wd * np.sin(wd * tau))
    return -(x @ slopes) / w**2, -(dx @ slopes) / w**2


def closed_form_peaks(tk, ag, T, z):
    """(Sd, Sv, Sa) over [0, t_end] of the record linear between the samples (tk, ag), ag[0] = 0: a dense grid,
    then golden sections around the best grid points of each quantity."""
    slopes = np.diff(ag) / np.diff(tk)
    knots = tk[:-1]
    dslope = np.concatenate([[slopes[0]], np.diff(slopes)])
    w = 2 * math.pi / T

    def values(t):
        u, v = ramp_responses(np.atleast_1d(t), knots, dslope, T, z)
        return np.stack([u, v, 2 * z * w * v + w * w * u])

    grid = np.linspace(tk[0], tk[-1], 40 * tk.size)
    vals = np.abs(values(grid))
    out = []
    for q in range(3):
        best = -1.0
        for i in np.argsort(vals[q])[-5:]:
            lo, hi = grid[max(i - 1, 0)], grid[min(i + 1, grid.size - 1)]
            r = 0.5 * (math.sqrt(5) - 1)
            for _ in range(80):
                x1, x2 = hi - r * (hi - lo), lo + r * (hi - lo)
                if abs(values(x1)[q, 0]) > abs(values(x2)[q, 0]):
                    hi = x2
                else:
                    lo = x1
            best = max(best, abs(values(0.5 * (lo + hi))[q, 0]), vals[q, i])
        out.append(best)
    return out


@pytest.mark.parametrize("z", [0.0, 0.05])
@pytest.mark.parametrize("T", [0.013, 0.15, 1.3])
def test_sine_record_against_the_sum_of_ramp_responses(T, z):
    """a_g = A sin(W t) sampled 12 times a cycle: the kernel's Sd, Sv, Sa equal the closed form of that
    piecewise-linear record to 1e-12 (the peaks fall between the samples)."""
    dt = 0.02
    tk = np.arange(121) * dt
    ag = 3.0 * np.sin(2 * math.pi / (12 * dt) * tk)
    got = _core.elastic_spectrum(ag, dt, [T], z, free_vibration=False)
    sd, sv, sa = closed_form_peaks(tk, ag, T, z)
    assert got["Sd"][0] == pytest.approx(sd, rel=1e-12, abs=0)
    assert got["Sv"][0] == pytest.approx(sv, rel=1e-12, abs=0)
    assert got["Sa"][0] == pytest.approx(sa, rel=1e-12, abs=0)


def test_peak_between_samples_that_the_samples_miss():
    """A step a_g = A, T = 0.05 s, dt = 0.01 s: the first peak, at pi / wd = 0.025 s, is mid-interval; the
    samples miss it by more than 1 %, the kernel finds it to 1e-12."""
    A, T, z, dt = 2.0, 0.05, 0.02, 0.01
    w = 2 * math.pi / T
    wd = w * math.sqrt(1 - z * z)
    exact = A / w**2 * (1 + math.exp(-z * w * math.pi / wd))
    t = np.arange(101) * dt
    sampled, _ = exact_sdof_peaks(t, np.full(t.size, A), [T], z)
    assert sampled[0] < 0.99 * exact
    got = _core.elastic_spectrum(np.full(t.size, A), dt, [T], z, free_vibration=False)
    assert got["Sd"][0] == pytest.approx(exact, rel=1e-12)
    assert got["t_Sd"][0] == pytest.approx(math.pi / wd, abs=1e-9 * dt)
    assert got["PSa"][0] == pytest.approx(w * w * got["Sd"][0], rel=1e-15)


def test_period_shorter_than_the_step():
    """T = 0.003 s with dt = 0.01 s: several extrema in each interval; the first peak of the step response."""
    A, dt = 1.0, 0.01
    for T, z in ((0.003, 0.0), (0.003, 0.05), (0.0071, 0.2)):
        w = 2 * math.pi / T
        wd = w * math.sqrt(1 - z * z)
        got = _core.elastic_spectrum(np.full(21, A), dt, [T], z, free_vibration=False)
        assert got["Sd"][0] == pytest.approx(A / w**2 * (1 + math.exp(-z * w * math.pi / wd)), rel=1e-12)


def _sgm1_path():
    import os
    return os.path.join(os.path.dirname(nvib.__file__), "scenes", "records", "sgm1.AT2")


def test_kernel_bounds_the_sampled_peaks_and_meets_them_when_refined():
    """Against exact_sdof_peaks (the NumPy recurrence, peaks at its times): the kernel is never below, and
    the samples' peaks approach it as the record is sampled more finely (the same piecewise-linear record)."""
    rec = nvib.GroundMotion.from_at2(_sgm1_path())
    a = np.asarray(rec.a) * 9.80665
    periods = np.geomspace(0.03, 5.0, 12)
    z = 0.05
    got = _core.elastic_spectrum(a, rec.dt, periods, z, free_vibration=False)
    sd, sa = exact_sdof_peaks(rec.t, a, periods, z)
    assert np.all(got["Sd"] >= sd * (1 - 1e-12))
    assert np.all(got["Sa"] >= sa * (1 - 1e-12))
    gaps = []
    for k in (1, 4, 16):
        tf = np.linspace(rec.t[0], rec.t[-1], (rec.t.size - 1) * k + 1)
        sdk, _ = exact_sdof_peaks(tf, np.interp(tf, rec.t, a), periods, z)
        assert np.all(got["Sd"] >= sdk * (1 - 1e-12))
        gaps.append(np.max((got["Sd"] - sdk) / got["Sd"]))
    assert gaps[0] > 1e-3  # the samples miss peaks at the record's own step
    assert gaps[0] > gaps[1] > gaps[2] and gaps[2] < gaps[0] / 50  # about (w dt / k)^2
    # the kernel on the refined record: the same spectrum
    tf = np.linspace(rec.t[0], rec.t[-1], (rec.t.size - 1) * 16 + 1)
    fine = _core.elastic_spectrum(np.interp(tf, rec.t, a), rec.dt / 16, periods, z, free_vibration=False)
    for q in ("Sd", "Sv", "Sa"):
        np.testing.assert_allclose(fine[q], got[q], rtol=1e-11)


def test_free_vibration_after_the_record():
    """A ramp cut at t_end, zeta = 0: the free vibration's amplitude sqrt(u^2 + (v/w)^2) is Sd; without
    the free vibration Sd is |u(t_end)|."""
    c, dt, T = 1.5, 0.01, 2.3
    w = 2 * math.pi / T
    t = np.arange(401) * dt
    L = t[-1]
    uL, vL = -(c / w**2) * (L - math.sin(w * L) / w), -(c / w**2) * (1 - math.cos(w * L))
    got = _core.elastic_spectrum(c * t, dt, [T], 0.0)
    assert got["Sd"][0] == pytest.approx(math.hypot(uL, vL / w), rel=1e-12)
    assert got["t_Sd"][0] > L
    cut = _core.elastic_spectrum(c * t, dt, [T], 0.0, free_vibration=False)
    assert cut["Sd"][0] == pytest.approx(abs(uL), rel=1e-12)


def test_dampings_shapes_and_spacing():
    rec = nvib.GroundMotion.from_at2(_sgm1_path())
    a = np.asarray(rec.a)
    periods = np.array([0.1, 0.5, 2.0])
    grid = _core.elastic_spectrum(a, rec.dt, periods, [0.0, 0.02, 0.05, 1.0, 2.0])
    assert grid["Sd"].shape == (5, 3)
    for k, z in enumerate([0.0, 0.02, 0.05, 1.0, 2.0]):
        one = _core.elastic_spectrum(a, rec.dt, periods, z)
        assert one["Sd"].shape == (3,)
        np.testing.assert_array_equal(grid["Sd"][k], one["Sd"])
        np.testing.assert_array_equal(grid["damping"][k], z)
    assert np.all(np.diff(grid["Sd"][:, 0]) < 0)  # more damping, smaller response
    pp = _core.elastic_spectrum(a, rec.dt, periods, [0.0, 0.05, 2.0], per_period=True)
    np.testing.assert_array_equal(pp["Sd"], [grid["Sd"][0, 0], grid["Sd"][2, 1], grid["Sd"][4, 2]])
    # the same samples given with their times
    at = _core.elastic_spectrum_at(rec.t, a, periods, 0.05)
    np.testing.assert_allclose(at["Sd"], grid["Sd"][2], rtol=1e-9)
    uneven = np.sort(np.concatenate([rec.t, rec.t[:-1] + 0.3 * rec.dt]))
    at = _core.elastic_spectrum_at(uneven, np.interp(uneven, rec.t, a), periods, 0.05)
    np.testing.assert_allclose(at["Sd"], grid["Sd"][2], rtol=1e-10)


@pytest.mark.parametrize("call, argument", [
    (lambda a: _core.elastic_spectrum(a, 0.0, [1.0], 0.05), "dt"),
    (lambda a: _core.elastic_spectrum(a, math.nan, [1.0], 0.05), "dt"),
    (lambda a: _core.elastic_spectrum(a, 0.01, [0.0], 0.05), "periods"),
    (lambda a: _core.elastic_spectrum(a, 0.01, [math.inf], 0.05), "periods"),
    (lambda a: _core.elastic_spectrum(a, 0.01, [], 0.05), "periods"),
    (lambda a: _core.elastic_spectrum(a, 0.01, [1.0], -0.01), "damping"),
    (lambda a: _core.elastic_spectrum(a, 0.01, [1.0], [0.05, math.nan]), "damping"),
    (lambda a: _core.elastic_spectrum(a, 0.01, [1.0, 2.0], [0.05], per_period=True), "damping"),
    (lambda a: _core.elastic_spectrum(a[:1], 0.01, [1.0], 0.05), "ag"),
    (lambda a: _core.elastic_spectrum(np.where(np.arange(a.size) == 3, np.nan, a), 0.01, [1.0], 0.05), "ag"),
    (lambda a: _core.elastic_spectrum_at(np.arange(a.size)[::-1] * 0.01, a, [1.0], 0.05), "times"),
    (lambda a: _core.elastic_spectrum_at(np.arange(a.size - 1) * 0.01, a, [1.0], 0.05), "times"),
])
def test_bad_input_names_the_argument(call, argument):
    with pytest.raises(nvib.ArgumentError) as info:
        call(np.ones(10))
    assert info.value.argument == argument


def test_runs_without_the_gil():
    """Two threads compute at once and agree with one thread (the GIL is released during the computation)."""
    a = np.sin(np.arange(20001) * 0.01) * np.exp(-np.arange(20001) * 1e-4)
    periods = np.geomspace(0.05, 5, 50)
    ref = _core.elastic_spectrum(a, 0.01, periods, 0.05)
    out = [None, None]

    def work(i):
        out[i] = _core.elastic_spectrum(a, 0.01, periods, 0.05)

    threads = [threading.Thread(target=work, args=(i,)) for i in range(2)]
    for th in threads:
        th.start()
    for th in threads:
        th.join()
    for o in out:
        np.testing.assert_array_equal(o["Sd"], ref["Sd"])


def test_rotd_of_one_component_and_of_two_equal_ones():
    """u_theta = u1 cos(theta) + u2 sin(theta): with a2 = 0 the peak at theta is |cos theta| Sd1 (RotD100 = Sd1
    at 0 degrees); with a2 = a1 it is |cos theta + sin theta| Sd1, largest at 45 degrees (sqrt(2) Sd1)."""
    from nvib.analysis.spectrum import rotd_spectrum
    rec = nvib.GroundMotion.from_at2(_sgm1_path())
    a = np.asarray(rec.a)
    periods = np.array([0.1, 0.7, 3.0])
    sd1 = _core.elastic_spectrum(a, rec.dt, periods, 0.05)["Sd"]
    one = rotd_spectrum(a, np.zeros_like(a), rec.dt, periods, 0.05)
    theta = np.radians(one["angles"])
    np.testing.assert_allclose(one["Sd"], np.abs(np.cos(theta))[:, None] * sd1, rtol=1e-12, atol=1e-300)
    np.testing.assert_allclose(one["RotD100"], sd1, rtol=1e-15)
    np.testing.assert_allclose(one["RotD50"], np.median(np.abs(np.cos(theta))) * sd1, rtol=1e-12)
    two = rotd_spectrum(a, a, rec.dt, periods, 0.05)
    np.testing.assert_allclose(two["RotD100"], math.sqrt(2) * sd1, rtol=1e-12)
    np.testing.assert_allclose(two["RotD100_PSa"], (2 * math.pi / periods) ** 2 * two["RotD100"], rtol=1e-15)


def test_rotated_sd_is_the_spectrum_of_the_rotated_record():
    """rotated_sd combines the responses to the two components; each angle's Sd equals the kernel's Sd of
    the rotated record itself."""
    rec = nvib.GroundMotion.from_at2(_sgm1_path())
    a1 = np.asarray(rec.a)
    a2 = np.roll(a1, 150) * 0.7
    periods = np.array([0.015, 0.2, 1.1, 4.0])
    angles = np.array([0.0, 17.0, 45.0, 90.0, 133.0])
    sd = _core.rotated_sd(a1, a2, rec.dt, periods, 0.05, angles)
    for k, th in enumerate(np.radians(angles)):
        one = _core.elastic_spectrum(math.cos(th) * a1 + math.sin(th) * a2, rec.dt, periods, 0.05)
        np.testing.assert_allclose(sd[k], one["Sd"], rtol=1e-12)


@pytest.mark.parametrize("call, argument", [
    (lambda a: _core.rotated_sd(a, a[:-1], 0.01, [1.0], 0.05, [0.0]), "a2"),
    (lambda a: _core.rotated_sd(a, a, 0.01, [1.0], 0.05, []), "angles"),
    (lambda a: _core.rotated_sd(a, a, 0.01, [-1.0], 0.05, [0.0]), "periods"),
    (lambda a: _core.rotated_sd(a, a, 0.0, [1.0], 0.05, [0.0]), "dt"),
])
def test_rotated_sd_bad_input_names_the_argument(call, argument):
    with pytest.raises(nvib.ArgumentError) as info:
        call(np.ones(10))
    assert info.value.argument == argument
