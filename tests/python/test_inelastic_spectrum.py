"""Inelastic spectra (Chopra, Dynamics of Structures, sections 7.2 to 7.5) against what theory says: the
elastic strength at mu = 1, the target reproduced by an SDOF run on its own, the largest of several
strengths giving the same mu, the equal-displacement and equal-acceleration limits, and an error that is
the measured change when the step is halved."""

import math
import os

import numpy as np
import pytest

import nvib
from nvib.analysis.inelastic import SEARCH_TOLERANCE

from _cli import run_cli

HERE = os.path.dirname(os.path.abspath(__file__))
SGM1 = os.path.join(HERE, "..", "..", "python", "nvib", "scenes", "records", "sgm1.AT2")


def record(seed=2, n=400, dt=0.01):
    """4 s of filtered white noise under a Gaussian envelope, PGA about 0.4 g."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) * dt
    a = np.convolve(rng.standard_normal(n), np.ones(4) / 4, "same") * np.exp(-((t - 1.5) / 1.0) ** 2) * 0.4
    return nvib.GroundMotion.from_array(a, dt=dt, name=f"synthetic {seed}", units="g")


def sdof_peak(gm, T, fy, dt, *, damping=0.05, b=0.0, estimate=False):
    """max |u| of the elastic-perfectly plastic (b = 0) SDOF of unit mass, built and run here on its own
    (nvib.solve, Newmark), over the record and two periods after it (and the run's estimated error)."""
    w = 2 * math.pi / T
    model = nvib.Model([1.0], effects=[
        {"type": "bilinear", "measure": {0: 1.0}, "k": w * w, "fy": fy, "b": b},
        {"type": "damper", "measure": {0: 1.0}, "c": 2 * damping * w},
        {"type": "ground_acceleration", "signal": gm}])
    res = nvib.solve(model, nvib.Newmark(), dt=dt, t_end=gm.t[-1] + 2 * T, save_every=1, max_displacement=math.inf)
    peak = float(np.max(np.abs(res.u[:, 0])))
    return (peak, res.error_estimate.max) if estimate else peak


def test_ductility_one_is_the_elastic_strength():
    gm = record()
    periods = [0.05, 0.3, 1.5]
    sp = nvib.inelastic_spectrum(gm, periods, ductility=[1])
    exact = nvib.spectrum(gm, periods)
    assert np.all(sp.fy_ratio == 1.0) and np.all(sp.R_y == 1.0) and np.all(sp.error == 0.0)
    # f_y = k Sd (exact) per unit mass: A_y is the exact PSa, u_y the exact Sd
    np.testing.assert_allclose(sp.Ay[0], exact.PSa, rtol=1e-14)
    np.testing.assert_allclose(sp.uy[0], exact.Sd, rtol=1e-14)
    # the run at the elastic strength stays elastic to within the step's error of its peak (measured up to 2.8e-3)
    assert np.all(np.abs(sp.mu - 1.0) < 5e-3), sp.mu


def test_the_strength_found_gives_the_target_in_a_run_of_its_own():
    gm = record()
    accuracy = 1e-3
    for T in (0.1, 0.7):
        sp = nvib.inelastic_spectrum(gm, [T], ductility=[2, 5], accuracy=accuracy)
        assert not sp.warnings
        for k, target in enumerate(sp.targets):
            fy = sp.fy_ratio[k, 0] * sp.PSa[0]
            mu = sdof_peak(gm, T, fy, sp.dt[k, 0]) / (fy / (2 * math.pi / T) ** 2)
            assert mu == pytest.approx(target, rel=SEARCH_TOLERANCE * accuracy)
            assert sp.mu[k, 0] == pytest.approx(mu, rel=1e-9)  # the runs batched as one model are these runs
            # its estimate is that of the SDOF among the others of its model, whose memory (the dissipation
            # that sets how long an error is carried) is the model's: within the estimate's factor of trust, 3, of
            # the run on its own (measured 0.496 to 1.8 at T = 0.1 to 1.5 s, mu = 2 and 5, R = 2 and 5)
            own = sdof_peak(gm, T, fy, sp.dt[k, 0], estimate=True)[1]
            assert own / 3.0 <= sp.estimate[k, 0] <= 3.0 * own
            assert sp.Cy[k, 0] == pytest.approx(fy) and sp.R_y[k, 0] == pytest.approx(1 / sp.fy_ratio[k, 0])
            assert sp.um[k, 0] == pytest.approx(target * sp.uy[k, 0], rel=SEARCH_TOLERANCE * accuracy)


def test_several_strengths_give_the_target_and_the_largest_is_taken():
    """At T = 0.2 s under this record mu(fbar_y) rises to 3.89 at fbar_y = 0.28, falls to 3.64 at 0.23 and rises
    again: mu = 3.7 is reached three times. Chopra's rule takes the largest strength."""
    gm, T, target = record(seed=2), 0.2, 3.7
    sp = nvib.inelastic_spectrum(gm, [T], ductility=[target], max_halvings=0)
    dense = np.geomspace(1.0, 0.15, 160)
    scan = nvib.inelastic_spectrum(gm, [T], R=1 / dense, max_halvings=0)
    assert np.all(scan.dt == sp.dt[0, 0])  # the same step: the same mu(fbar_y)
    above = scan.mu[:, 0] >= target
    crossings = np.flatnonzero(above[1:] != above[:-1])
    assert crossings.size == 3, dense[crossings]
    first = crossings[0]
    assert dense[first + 1] <= sp.fy_ratio[0, 0] <= dense[first]
    assert sp.fy_ratio[0, 0] > 1.2 * dense[crossings[1]]  # not one of the smaller ones


def test_constant_strength_against_theory():
    gm = record()
    sp = nvib.inelastic_spectrum(gm, [0.05, 0.3, 1.0], R=[1, 2, 4])
    # R = 1: the elastic strength, reached (to the step's error) but not passed
    assert np.all(sp.mu[0] < 1.0 + 5e-3), sp.mu[0]
    # a weaker system yields more: mu grows with R at every period
    assert np.all(np.diff(sp.mu, axis=0) > 0)
    np.testing.assert_allclose(sp.fy_ratio, 1 / sp.targets[:, None] * np.ones((1, 3)), rtol=1e-15)
    np.testing.assert_allclose(sp.um, sp.mu * sp.uy, rtol=1e-14)


def test_equal_displacement_at_a_very_long_period():
    """T >> T_c: the mass stays still, u_m ~ u_o, so mu ~ R (Chopra, chapter 7: equal displacement). Measured
    on SGM-1 (30 s, baseline corrected) at T = 100 s: mu / R = 0.997, 0.992, 0.990 for R = 2, 4, 8; at
    T = 3.4 s, not yet long enough, R_y is 1.9 mu for mu = 6 (benchmarks/results). A record whose
    ground velocity does not return to zero breaks the rule: its free vibration after the record grows
    the weaker system's drift (the uncorrected synthetic record gives mu / R = 1.23, 1.91, 3.05 at
    T = 20 s)."""
    gm = nvib.GroundMotion.from_at2(SGM1)
    sp = nvib.inelastic_spectrum(gm, [100.0], R=[2, 4, 8])
    np.testing.assert_allclose(sp.mu[:, 0] / sp.targets, 1.0, atol=0.02)
    np.testing.assert_allclose(sp.um[:, 0], sp.Sd[0], rtol=0.02)


def test_equal_acceleration_at_a_very_short_period():
    """T -> 0: the system moves with the ground, its elastic force tends to m PGA; a strength below it needs
    a ductility that grows without bound as T falls, one above it stays elastic."""
    gm = record()
    periods = [0.04, 0.02, 0.01]
    weak = nvib.inelastic_spectrum(gm, periods, Cy=[0.5 * gm.pga])
    assert np.all(np.diff(weak.mu[0]) > 0) and weak.mu[0, -1] > 30, weak.mu
    np.testing.assert_allclose(weak.PSa[-1], gm.pga, rtol=0.02)  # measured 1.6 % above it at T = 0.01 s
    strong = nvib.inelastic_spectrum(gm, [0.01], Cy=[1.05 * gm.pga])
    assert strong.mu[0, 0] < 1.0


def test_the_error_is_the_change_measured_when_the_step_is_halved():
    gm = record()
    T = 0.3
    sp = nvib.inelastic_spectrum(gm, [T], R=[3], max_halvings=0)
    fy, dt = sp.Ay[0, 0], sp.dt[0, 0]
    coarse, fine = sdof_peak(gm, T, fy, dt), sdof_peak(gm, T, fy, dt / 2)
    assert sp.um[0, 0] == pytest.approx(coarse, rel=1e-9)
    assert sp.error[0, 0] == pytest.approx(abs(coarse - fine) / fine, rel=1e-6)
    assert sp.error[0, 0] > 0
    # the run reported carries its own estimate: that of the same SDOF run on its own
    assert sp.estimate[0, 0] == pytest.approx(sdof_peak(gm, T, fy, dt, estimate=True)[1], rel=1e-9)


def test_the_ductility_error_is_the_strength_found_at_half_the_step():
    """The same piecewise-linear ground motion sampled twice as often: its long periods run at half the step,
    and the strength found there is the one the first spectrum's error was measured against."""
    gm = record()
    fine_record = nvib.GroundMotion.from_array(gm(np.arange(2 * len(gm) - 1) * gm.dt / 2), dt=gm.dt / 2, units="g")
    T = 1.2  # long enough that the step is the record's
    sp = nvib.inelastic_spectrum(gm, [T], ductility=[3], max_halvings=0)
    half = nvib.inelastic_spectrum(fine_record, [T], ductility=[3], max_halvings=0)
    assert sp.dt[0, 0] == gm.dt and half.dt[0, 0] == gm.dt / 2
    f, f2 = sp.fy_ratio[0, 0], half.fy_ratio[0, 0]
    assert sp.error[0, 0] == pytest.approx(abs(f - f2) / f2, rel=1e-6, abs=1e-12)


def test_periods_that_miss_the_accuracy_run_at_half_the_step():
    gm = record()
    loose = nvib.inelastic_spectrum(gm, [0.2, 0.5], R=[4], max_halvings=0, accuracy=1e-3)
    tight = nvib.inelastic_spectrum(gm, [0.2, 0.5], R=[4], accuracy=1e-5)
    assert np.all(tight.error <= 1e-5) and not tight.warnings
    assert np.all(tight.dt < loose.dt)
    # not met (measured 5.3e-6): said, with the error reached
    never = nvib.inelastic_spectrum(gm, [0.2], R=[4], accuracy=1e-6, max_halvings=0)
    assert never.error[0, 0] > 1e-6
    assert len(never.warnings) == 1 and f"largest {never.error[0, 0]:.2g}" in never.warnings[0]


def test_a_target_no_scanned_strength_reaches_is_said():
    gm = record()
    sp = nvib.inelastic_spectrum(gm, [0.5], ductility=[2, 200], fy_ratios=[1.0, 0.8, 0.5, 0.3])
    assert np.isfinite(sp.fy_ratio[0, 0]) and np.isnan(sp.fy_ratio[1, 0]) and np.isnan(sp.R_y[1, 0])
    assert np.isnan(sp.error[1, 0]) and np.isnan(sp.mu[1, 0])
    assert len(sp.warnings) == 1 and "μ = 200" in sp.warnings[0] and "0.3" in sp.warnings[0]


def test_units_follow_the_record():
    in_g = record()
    in_si = in_g.scaled(nvib.STANDARD_GRAVITY)
    assert in_si.units == "m/s^2"
    a = nvib.inelastic_spectrum(in_g, [0.4], ductility=[3])
    b = nvib.inelastic_spectrum(in_si, [0.4], ductility=[3])
    assert a.units == "g" and b.units == "m/s^2"
    np.testing.assert_allclose(b.Cy, a.Cy, rtol=1e-8)
    np.testing.assert_allclose(b.Ay, a.Ay * nvib.STANDARD_GRAVITY, rtol=1e-8)
    np.testing.assert_allclose(a.in_units("m/s^2").um, b.um, rtol=1e-8)
    assert a.Cy[0, 0] == a.Ay[0, 0]  # in g, C_y = A_y / g is A_y
    unknown = nvib.GroundMotion.from_array(in_g.a, dt=in_g.dt)
    c = nvib.inelastic_spectrum(unknown, [0.4], ductility=[3])
    assert c.Cy is None and c.fy_ratio[0, 0] == pytest.approx(a.fy_ratio[0, 0], rel=1e-12)


def test_other_hysteretic_laws():
    gm = record()
    periods = [0.3, 1.0]
    bilinear = nvib.inelastic_spectrum(gm, periods, R=[3], law={"type": "bilinear", "b": 0.05})
    # Bouc-Wen with a sharp yield (n = 20) and alpha = b is nearly the bilinear law: measured within 0.4 %
    smooth = nvib.inelastic_spectrum(gm, periods, R=[3], law={"type": "bouc_wen", "alpha": 0.05, "n": 20.0})
    np.testing.assert_allclose(smooth.mu, bilinear.mu, rtol=0.01)
    # a peak-oriented law is linear up to f_y too: at R = 1 it stays elastic (to the step's error)
    imk = {"type": "imk_peak_oriented", "up": 1.0, "upc": 1.0, "uu": 10.0, "fcap_fy": 1.1}
    elastic = nvib.inelastic_spectrum(gm, periods, R=[1], law=imk)
    assert np.all(elastic.mu < 1.0 + 5e-3)


@pytest.mark.parametrize("scheme", [nvib.CentralDifference(), nvib.GeneralizedAlpha.from_rho_inf(0.9),
                                    nvib.PreciseIntegration()], ids=["lcdm", "galpha", "pim"])
def test_any_scheme_finds_the_same_strengths_within_the_errors_it_reports(scheme):
    """Second-order schemes: a value at step h is off the converged one by about 4/3 of the change measured
    at h/2, so two schemes agree within (4/3)(e_1 + e_2); asserted with 2 for the terms beyond second order
    (measured at most 0.9 of (4/3)(e_1 + e_2), LCDM at T = 0.15 s)."""
    gm = record()
    newmark = nvib.inelastic_spectrum(gm, [0.15, 0.6], ductility=[3])
    other = nvib.inelastic_spectrum(gm, [0.15, 0.6], ductility=[3], scheme=scheme)
    assert other.scheme == nvib.scheme_label(scheme) and not other.warnings
    gap = np.abs(other.fy_ratio / newmark.fy_ratio - 1)
    assert np.all(gap <= 2 * (newmark.error + other.error)), (gap, newmark.error, other.error)


def test_a_law_that_collapses_gives_an_infinite_ductility_and_says_so():
    gm = record()
    imk = {"type": "imk_peak_oriented", "up": 1e-4, "upc": 1e-4, "uu": 1e-3, "fcap_fy": 1.05}
    sp = nvib.inelastic_spectrum(gm, [0.5], R=[8], law=imk)
    assert np.isinf(sp.mu[0, 0]) and any("collapsed" in w for w in sp.warnings)
    assert np.isnan(sp.estimate[0, 0])  # a run that collapsed has no estimate to report


def test_reduction_factors_and_the_table():
    gm = record()
    sp = nvib.inelastic_spectrum(gm, [0.2, 1.0], ductility=[2, 4])
    R = sp.reduction_factors()
    assert list(R) == [2.0, 4.0]
    np.testing.assert_allclose(R[4.0], 1 / sp.fy_ratio[1], rtol=1e-15)
    assert np.all(R[4.0] > R[2.0]) and np.all(R[2.0] > 1)  # more ductility, less strength
    table = sp.markdown()
    assert "| target μ | T [s] |" in table and "A_y [g]" in table and "u_m [m]" in table
    assert len(table.strip().splitlines()) == 2 + 4


def test_csv_and_plot(tmp_path):
    gm = record()
    sp = nvib.inelastic_spectrum(gm, [0.2, 1.0], ductility=[1, 3])
    sp.to_csv(tmp_path / "s.csv")
    lines = (tmp_path / "s.csv").read_text(encoding="utf-8").splitlines()
    assert lines[0].startswith("target μ [-],period [s],f_y/f_o [-],R_y [-],C_y [-],A_y [g],u_y [m],u_m [m]")
    assert len(lines) == 1 + 4
    row = [float(x) for x in lines[3].split(",")]
    assert row[0] == 3.0 and row[1] == 0.2 and row[2] == sp.fy_ratio[1, 0]
    ax = sp.plot(tmp_path / "s.png")
    assert (tmp_path / "s.png").stat().st_size > 0
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert labels == ["μ = 1 (elastic, exact)", "μ = 3"]
    np.testing.assert_allclose(ax.get_lines()[0].get_ydata(), sp.PSa, rtol=1e-15)  # C_y = PSa / g, in g
    assert "[-]" in ax.get_ylabel() and "[s]" in ax.get_xlabel() and ax.get_xscale() == "log"
    ax = sp.plot(quantity="R_y")
    assert "R_y" in ax.get_ylabel()
    strength = nvib.inelastic_spectrum(gm, [0.2, 1.0], R=[2])
    ax = strength.plot(quantity="um")
    assert "[m]" in ax.get_ylabel() and [t.get_text() for t in ax.get_legend().get_texts()][1] == "$R_y$ = 2"


@pytest.mark.parametrize("kwargs, name", [
    ({"periods": []}, "periods"),
    ({"periods": [0.5, -1.0]}, "periods"),
    ({"periods": [float("nan")]}, "periods"),
    ({"ductility": [0.5]}, "ductility"),
    ({"ductility": 0.0}, "ductility"),
    ({"ductility": [float("inf")]}, "ductility"),
    ({"ductility": None, "R": [0.0]}, "R"),
    ({"ductility": None, "R": [-2.0]}, "R"),
    ({"ductility": None}, "ductility, R, Cy"),
    ({"R": [2.0]}, "ductility, R"),
    ({"damping": 1.0}, "damping"),
    ({"damping": -0.01}, "damping"),
    ({"law": {"type": "spring"}}, "law"),
    ({"law": {"type": "no_such_law"}}, "law"),
    ({"law": "bilinear"}, "law"),
    ({"law": {"type": "bilinear", "fy": 1.0}}, "law.fy"),
    ({"law": {"type": "bilinear", "b": 1.5}}, "law.b"),
    ({"law": {"type": "bilinear", "bb": 0.1}}, "law.bb"),
    ({"law": {"type": "imk_peak_oriented", "up": 1.0}}, "law.upc"),
    ({"accuracy": 0.0}, "accuracy"),
    ({"scheme": "newmark"}, "scheme"),
    ({"fy_ratios": [0.5, 1.5]}, "fy_ratios"),
    ({"ductility": None, "R": [2.0], "fy_ratios": [0.5]}, "fy_ratios"),
    ({"max_halvings": -1}, "max_halvings"),
])
def test_bad_input_names_the_argument(kwargs, name):
    args = {"periods": [0.5], "ductility": [2.0], **kwargs}
    periods = args.pop("periods")
    with pytest.raises((nvib.ArgumentError, nvib.ArgumentTypeError)) as info:
        nvib.inelastic_spectrum(record(), periods, **args)
    assert info.value.argument == name


def test_strength_coefficients_need_the_records_unit():
    unknown = nvib.GroundMotion.from_array(record().a, dt=0.01)
    with pytest.raises(nvib.ArgumentError) as info:
        nvib.inelastic_spectrum(unknown, [0.5], Cy=[0.1])
    assert info.value.argument == "Cy"


def test_command_line_writes_the_table_csv_and_plot(capsys, tmp_path):
    code, out, err = run_cli(capsys, "spectrum", SGM1, "--ductility", "2", "4", "--periods", "0.3,1.5",
                             "--out", tmp_path / "s.csv", "--plot", tmp_path / "s.png")
    assert code == 0, err
    assert "constant ductility, bilinear (b = 0), damping 0.05" in out and "μ = 2:" in out and "μ = 4:" in out
    assert "C_y [-]" in out and "A_y [g]" in out
    assert (tmp_path / "s.png").stat().st_size > 0
    assert (tmp_path / "s.csv").read_text(encoding="utf-8").startswith("target μ [-],period [s]")
    code, out, err = run_cli(capsys, "spectrum", SGM1, "--strength-ratio", "3", "--periods", "0.5",
                             "--hardening", "0.05", "--units", "m/s^2")
    assert code == 0 and "constant strength, bilinear (b = 0.05)" in out and "A_y [m/s^2]" in out


@pytest.mark.parametrize("argv, flag", [
    (["--ductility", "0.5"], "--ductility"),
    (["--ductility", "2", "--strength-ratio", "2"], "--ductility"),
    (["--strength-ratio", "0"], "--strength-ratio"),
    (["--ductility", "2", "--hardening", "1.5"], "--hardening"),
    (["--ductility", "2", "--law", "bouc_wen", "--hardening", "-1"], "--hardening"),
    (["--ductility", "2", "--law", "spring"], "--law"),
    (["--hardening", "0.1"], "--hardening"),
    (["--ductility", "2", "--damping", "0.02", "0.05"], "--damping"),
    (["--ductility", "2", "--damping", "1.5"], "--damping"),
    (["--ductility", "2", "--accuracy", "1e-12"], "--accuracy"),
])
def test_command_line_bad_input_names_the_flag(capsys, argv, flag):
    code, out, err = run_cli(capsys, "spectrum", SGM1, "--periods", "0.5", *argv)
    assert code == 2 and f"argument {flag}" in err, err
