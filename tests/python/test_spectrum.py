"""Response spectra: the exact piecewise-linear SDOF solution against closed forms and an ODE solver,
and nvib's spectra within the requested accuracy of it at every period."""

import math

import numpy as np
import pytest

import nvib
from nvib.analysis.spectrum import exact_sdof_peaks


def record(n=400, dt=0.01, seed=3):
    rng = np.random.default_rng(seed)
    t = np.arange(n) * dt
    a = np.convolve(rng.standard_normal(n), np.ones(4) / 4, "same") * np.exp(-((t - 1.5) / 1.0) ** 2) * 4.0
    return nvib.GroundMotion.from_array(a, dt=dt, name="synthetic")


def test_exact_solution_of_a_constant_ground_acceleration():
    """a_g = a0 from t = 0: u = -(a0/w^2) (1 - e^{-z w t} (cos wd t + z/sqrt(1-z^2) sin wd t))."""
    t = np.arange(2001) * 0.001
    a0, z = 2.5, 0.07
    for T in (0.05, 0.3, 1.7):
        w = 2 * math.pi / T
        wd = w * math.sqrt(1 - z * z)
        u = -(a0 / w**2) * (1 - np.exp(-z * w * t) * (np.cos(wd * t) + z / math.sqrt(1 - z * z) * np.sin(wd * t)))
        sd, _ = exact_sdof_peaks(t, np.full(t.size, a0), [T], z)
        assert sd[0] == pytest.approx(np.max(np.abs(u)), rel=1e-11)


def test_exact_solution_against_an_ode_solver_and_itself():
    from scipy.integrate import solve_ivp

    gm = record()
    z = 0.05
    for T in (0.08, 0.6):
        w = 2 * math.pi / T
        sol = solve_ivp(lambda t, y: [y[1], -2 * z * w * y[1] - w * w * y[0] - gm(t)], (0, gm.t[-1]), [0.0, 0.0],
                        t_eval=gm.t, rtol=1e-11, atol=1e-14, max_step=0.002)
        sd, sa = exact_sdof_peaks(gm.t, gm.a, [T], z)
        assert sd[0] == pytest.approx(np.max(np.abs(sol.y[0])), rel=1e-7)
        assert sa[0] == pytest.approx(np.max(np.abs(2 * z * w * sol.y[1] + w * w * sol.y[0])), rel=1e-7)
    # evenly spaced samples take the filter path; times moved by 1e-7 of a step take the interval-by-interval
    # one: the same samples at nearly the same times give the same peaks to about that much
    t_uneven = gm.t + 1e-9 * np.sin(np.arange(gm.t.size))
    t_uneven[0] = 0.0
    for T in (0.2, 1.0):
        np.testing.assert_allclose(exact_sdof_peaks(t_uneven, gm.a, [T], 0.02), exact_sdof_peaks(gm.t, gm.a, [T], 0.02),
                                   rtol=1e-6)


@pytest.mark.parametrize("accuracy", [1e-3, 1e-4])
def test_elastic_spectrum_meets_the_requested_accuracy(accuracy):
    gm = record()
    periods = np.geomspace(0.05, 3.0, 25)
    sp = nvib.spectrum(gm, periods, damping=0.05, scheme=nvib.Newmark(), accuracy=accuracy)
    assert sp.check == "exact check" and np.all(sp.error <= accuracy)
    # independently: the true peaks (between samples too) over the span each period ran, Sd and absolute Sa
    t_end = gm.t[-1] + 2 * periods.max()
    for k in (0, 12, 24):
        grid = np.arange(0.0, t_end + sp.dt[k] / 2, sp.dt[k])
        true = nvib._core.elastic_spectrum_at(grid, gm(grid), [periods[k]], 0.05, free_vibration=False)
        assert abs(sp.Sd[k] - true["Sd"][0]) <= accuracy * true["Sd"][0]
        assert abs(sp.Sa[k] - true["Sa"][0]) <= accuracy * true["Sa"][0]
    w = 2 * math.pi / periods
    np.testing.assert_allclose(sp.PSv, w * sp.Sd, rtol=1e-15)
    np.testing.assert_allclose(sp.PSa, w * w * sp.Sd, rtol=1e-15)
    assert np.all(sp.dt <= gm.dt) and sp.wall_time > 0
    # each run reports its estimate: that of the same run made by solve; an estimate of the history's error
    # (phase included) bounds the error of its peak (at most the largest error over the history), so it may
    # not understate it by more than its own factor of trust, 3 (measured: 1.4 to 350 times the peak's error)
    k = 12
    h = nvib.solve(nvib.analysis.spectrum._sdof(periods[k], 0.05, gm, None), nvib.Newmark(), dt=sp.dt[k], t_end=t_end)
    assert sp.estimate[k] == h.error_estimate.max
    assert np.all(sp.estimate >= sp.error / 3.0)


def test_inelastic_spectrum_checks_itself_by_step_halving():
    gm = record()
    periods = [0.1, 0.5, 1.5]
    linear = nvib.spectrum(gm, periods)
    # a hardening spring with a = 0 is the linear spring: the same spectrum, checked by halving instead
    same = nvib.spectrum(gm, periods, accuracy=1e-3, law={"type": "hardening_spring", "a": 0.0})
    assert same.check == "half step" and np.all(same.error <= 1e-3)
    np.testing.assert_allclose(same.Sd, linear.Sd, rtol=3e-3)
    stiff = nvib.spectrum(gm, periods, accuracy=1e-3, law={"type": "hardening_spring", "a": 5e4})
    assert np.all(stiff.Sd < linear.Sd)  # hardening keeps the displacement smaller


def test_arguments_named():
    gm = record()
    for kw, arg in ((dict(periods=[0.1, -1.0]), "periods"), (dict(periods=[0.1], damping=-0.5), "damping"),
                    (dict(periods=[0.1], scheme=nvib.Newmark(), damping=1.5), "damping"),
                    (dict(periods=[0.1], scheme=nvib.Newmark(), accuracy=0.0), "accuracy")):
        with pytest.raises(nvib.ArgumentError) as exc:
            nvib.spectrum(gm, **kw)
        assert exc.value.argument == arg
    with pytest.raises(nvib.ArgumentTypeError) as exc:
        nvib.spectrum([0.0, 1.0], [0.1])
    assert exc.value.argument == "record"


def test_runs_that_would_not_fit_in_memory_are_refused_naming_periods():
    """A period so short that its step count explodes is refused before anything is allocated (it was a
    std::bad_alloc, or gigabytes, then "dt: too many steps"), naming the argument the caller gave."""
    gm = nvib.GroundMotion.from_array(np.sin(0.07 * np.arange(4000)), dt=0.01)  # 40 s
    cases = [(dict(periods=[1e-6]), "periods", "T = 1e-06 s takes 2.29e+09 steps of 1.74e-08 s"),
             (dict(periods=[1e300]), "periods", "T = 1e+300 s takes 2e+302 steps"),
             (dict(periods=[0.1, 1e12]), "periods", "the longest period, 1e+12 s, makes t_end"),
             (dict(periods=[0.1], t_end=1e12), "t_end", "give a shorter t_end"),
             (dict(periods=[0.1], accuracy=1e-300), "accuracy", "must be >= 1e-09")]
    for kw, arg, needle in cases:
        with pytest.raises(nvib.ArgumentError) as exc:
            nvib.spectrum(gm, scheme=nvib.Newmark(), **kw)
        assert exc.value.argument == arg and needle in str(exc.value), str(exc.value)
        assert "dt:" not in str(exc.value)


def test_a_halving_that_would_not_fit_is_not_made(monkeypatch):
    """The first run of T = 0.05 s misses 1e-3 and would be halved; with memory for that run but not for
    one at half its step, the spectrum keeps the first and reports the error it reached."""
    from nvib.analysis import spectrum as module

    gm = record()
    T, accuracy = 0.05, 1e-3
    dt = gm.dt / math.ceil(gm.dt / (T * math.sqrt(12 * accuracy) / (2 * math.pi)))
    need = module._memory_needed(1, (gm.t[-1] + 2 * T) / dt, True)
    monkeypatch.setattr(module._core, "available_memory", lambda: 3.0 * need)  # a limit of 1.5 x need
    sp = nvib.spectrum(gm, [T], scheme=nvib.Newmark(), accuracy=accuracy)
    assert sp.dt[0] == pytest.approx(dt) and sp.error[0] > accuracy


def test_a_failed_run_names_its_period():
    gm = record().scaled(1e306)
    with pytest.raises(nvib.DivergenceError, match=r"the run at T = 0\.5 s \(dt = [0-9.e-]+ s\) failed: diverged"):
        nvib.spectrum(gm, [0.5, 1.0], scheme=nvib.Newmark())


def test_command_line(tmp_path, capsys):
    from nvib.cli import main

    gm = record()
    path = tmp_path / "rec.txt"
    path.write_text("\n".join(repr(float(x)) for x in gm.a) + "\n", encoding="utf-8")
    out = tmp_path / "sa.csv"
    assert main(["spectrum", str(path), "--dt", "0.01", "--periods", "0.1,0.5,2", "--damping", "0.02", "0.05",
                 "--out", str(out)]) == 0
    lines = out.read_text(encoding="utf-8").splitlines()
    # a plain file says nothing of its unit: the header says the values are the record's
    assert lines[0] == ("damping,period [s],Sd [record units s^2],PSv [record units s],PSa [record units],"
                        "Sa [record units],error,dt [s],estimate") and len(lines) == 1 + 2 * 3
    sp = nvib.spectrum(gm, [0.1, 0.5, 2.0], damping=0.05)
    assert float(lines[4].split(",")[2]) == sp.Sd[0]  # the CSV holds the library's numbers
    # runs of a scheme: the table and the CSV carry each run's estimate beside its checked error
    assert main(["spectrum", str(path), "--dt", "0.01", "--periods", "0.5,2", "--scheme", "newmark",
                 "--out", str(out)]) == 0
    text = capsys.readouterr().out
    ran = nvib.spectrum(gm, [0.5, 2.0], scheme=nvib.Newmark())
    assert f"the runs' own estimates: largest {ran.estimate.max():.1e}" in text and "estimate" in text
    rows = out.read_text(encoding="utf-8").splitlines()[1:]
    assert [float(r.split(",")[-1]) for r in rows] == list(ran.estimate)
    for argv, arg in ((["spectrum", str(path)], "--dt"),
                      (["spectrum", str(path), "--dt", "0.01", "--damping", "-0.1"], "--damping"),
                      (["spectrum", str(path), "--dt", "0.01", "--scheme", "newmark", "--damping", "2"], "--damping")):
        with pytest.raises(SystemExit) as exc:
            main(argv)
        assert exc.value.code == 2 and f"argument {arg}" in capsys.readouterr().err


# ---- the exact elastic spectrum (the default) ----------------------------------------------------------------

def test_the_elastic_spectrum_is_the_exact_kernels():
    gm = record()
    periods = np.geomspace(0.02, 5.0, 40)
    sp = nvib.spectrum(gm, periods, damping=0.05)
    ref = nvib._core.elastic_spectrum(gm.a, gm.dt, periods, 0.05)
    assert sp.check == "exact" and sp.error is None and np.all(sp.dt == gm.dt)
    for k in ("Sd", "Sv", "PSv", "PSa", "Sa"):
        np.testing.assert_array_equal(getattr(sp, k), ref[k])
    w = 2 * math.pi / periods
    np.testing.assert_allclose(sp.PSa, w * w * sp.Sd, rtol=1e-15)
    # never below the peaks at the samples (exact_sdof_peaks looks only there), and above them by more than
    # 1 % at some short period, where the peak falls between samples
    sampled, _ = exact_sdof_peaks(gm.t, gm.a, periods, 0.05)
    assert np.all(sp.Sd >= sampled * (1 - 1e-12)) and np.max(sp.Sd / sampled) > 1.01


def test_the_exact_spectrum_takes_several_damping_ratios_and_any_damping():
    gm = record()
    periods = [0.1, 0.5, 2.0]
    sp = nvib.spectrum(gm, periods, damping=[0.02, 0.05, 1.5])
    assert sp.Sd.shape == (3, 3) and list(sp.damping) == [0.02, 0.05, 1.5]
    for row, z in enumerate((0.02, 0.05, 1.5)):
        np.testing.assert_array_equal(sp.Sd[row], nvib.spectrum(gm, periods, damping=z).Sd)
    assert np.all(sp.Sd[0] > sp.Sd[2])  # more damping, less response
    rows = sp.by_damping()
    assert [r.damping for r in rows] == [0.02, 0.05, 1.5]
    np.testing.assert_array_equal(rows[1].Sa, sp.Sa[1])
    from nvib.plot import spectrum_figure

    assert len(spectrum_figure(sp).axes[0].lines) == 2 * 3  # PSa and Sa for each damping ratio


@pytest.mark.parametrize("kw", [dict(accuracy=1e-3), dict(t_end=10.0), dict(max_halvings=2), dict(threads=2)])
def test_settings_of_runs_are_refused_by_the_exact_spectrum(kw):
    (name,) = kw
    with pytest.raises(nvib.ArgumentError, match=rf"^{name}: the elastic spectrum is exact") as exc:
        nvib.spectrum(record(), [0.5], **kw)
    assert exc.value.argument == name


def test_a_record_too_large_for_doubles_is_named():
    with pytest.raises(nvib.ArgumentError, match=r"^record: its response at T = 0\.5 s is not finite") as exc:
        nvib.spectrum(record().scaled(1e306), [0.5, 1.0])
    assert exc.value.argument == "record"


def test_spectra_in_g_carry_their_units(tmp_path, capsys):
    """A record in g stays in g at any --scale: the table and CSV headers say so, --units turns the
    accelerations into m/s^2 or g (Sd in m whenever the unit is known), and the plot is drawn in g."""
    from nvib.cli import main
    from nvib.plot import spectrum_figure

    gm = record()
    path = tmp_path / "rec.txt"
    path.write_text("\n".join(repr(float(x)) for x in gm.a) + "\n", encoding="utf-8")
    args = ["spectrum", str(path), "--dt", "0.01", "--periods", "0.1,0.5,2", "--record-units", "g", "--scale", "2"]
    assert main(args + ["--out", str(tmp_path / "g.csv")]) == 0
    out = capsys.readouterr().out
    assert "Sd [m]" in out and "PSa [g]" in out and "Sa [g]" in out
    assert main(args + ["--units", "m/s^2", "--out", str(tmp_path / "si.csv"), "--plot", str(tmp_path / "s.png")]) == 0
    assert "PSa [m/s^2]" in capsys.readouterr().out and (tmp_path / "s.png").stat().st_size > 0
    g = (tmp_path / "g.csv").read_text(encoding="utf-8").splitlines()
    si = (tmp_path / "si.csv").read_text(encoding="utf-8").splitlines()
    assert g[0] == "damping,period [s],Sd [m],PSv [m/s],PSa [g],Sa [g],error,dt [s],estimate"
    assert si[0] == "damping,period [s],Sd [m],PSv [m/s],PSa [m/s^2],Sa [m/s^2],error,dt [s],estimate"
    sp = nvib.spectrum(gm.scaled(2.0), [0.1, 0.5, 2.0])
    row_g, row_si = [float(x) for x in g[2].split(",")], [float(x) for x in si[2].split(",")]
    assert row_g[4] == pytest.approx(sp.PSa[1], rel=1e-12)  # in g, as the record
    assert row_si[4] == pytest.approx(sp.PSa[1] * nvib.STANDARD_GRAVITY, rel=1e-12)
    assert row_g[2] == row_si[2] == pytest.approx(sp.Sd[1] * nvib.STANDARD_GRAVITY, rel=1e-12)  # Sd in m
    with pytest.raises(SystemExit) as exc:  # a plain file's unit is not known: --units cannot convert it
        main(["spectrum", str(path), "--dt", "0.01", "--units", "g"])
    assert exc.value.code == 2 and "argument --units" in capsys.readouterr().err

    spec = nvib.spectrum(nvib.GroundMotion.from_array(gm.a, 0.01, units="m/s^2"), [0.2, 1.0])
    assert spec.units == "m/s^2" and spec.in_units("g").PSa[0] == pytest.approx(spec.PSa[0] / 9.80665, rel=1e-15)
    fig = spectrum_figure(spec, units="g")
    assert fig.axes[0].get_ylabel() == "spectral acceleration [g]" and fig.axes[1].get_ylabel().endswith("[m]")
    with pytest.raises(nvib.ArgumentError, match="unit is not known") as exc:
        spectrum_figure(nvib.spectrum(nvib.GroundMotion.from_array(gm.a, 0.01), [1.0]), units="g")
    assert exc.value.argument == "units"
