"""nvib.stability: amplification matrices taken from the steppers, against closed forms
(Hughes 2000, ch. 9; Chung & Hulbert 1993), and the ``nvib stability`` command."""

import math
import re

import numpy as np
import pytest

import nvib

from _cli import run_cli
from nvib import stability as stab

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
CD_FAMILY = [nvib.CentralDifference(), nvib.CentralDifference(velocity="half_step")] + [
    nvib.CEMDTS(eta) for eta in (0.0, 0.25, 0.45, 0.5)]
# Settings beyond each registry scheme's defaults, by registry key (the defaults are run for every key).
VARIANTS = {
    "lcdm": [nvib.CentralDifference(velocity="half_step")],
    "cemdts": [nvib.CEMDTS(eta) for eta in (0.0, 0.25, 0.5)],
    "zhai": [nvib.Zhai(0.6, 0.6)],
    "newmark": [nvib.Newmark(iteration="one_iteration"), nvib.Newmark(1 / 6, 0.5)],
    "galpha": [nvib.GeneralizedAlpha.from_rho_inf(0.8), nvib.GeneralizedAlpha.hht(-0.1)],
    "pim": [nvib.PreciseIntegration(interpolation=1, corrections=2)],
}


def newmark_matrix(beta, gamma, om, xi=0.0):
    """Hughes' Newmark amplification matrix in the state (u, dt v, dt^2 a): A1 x_{n+1} = A2 x_n."""
    a1 = np.array([[1.0, 0.0, -beta], [0.0, 1.0, -gamma], [om * om, 2.0 * xi * om, 1.0]])
    a2 = np.array([[1.0, 1.0, 0.5 - beta], [0.0, 1.0, 1.0 - gamma], [0.0, 0.0, 0.0]])
    return np.linalg.solve(a1, a2)


# ---------------------------------------------------------------- the matrix is the stepper's map

def test_matrix_reproduces_a_step_for_every_registry_scheme(scheme_class):
    for scheme in [scheme_class()] + VARIANTS.get(scheme_class.key, []):
        check_matrix_reproduces_a_step(scheme)


@pytest.mark.parametrize("xi", [0.0, 0.05])
def test_every_registry_scheme_is_stable_below_its_limit_and_not_above(scheme_class, xi):
    """The spectral radius is at most 1 (to round-off) on a log grid of Omega below the computed
    stability limit, and above 1 just past a finite limit."""
    scheme = scheme_class()
    limit = stab.critical_omega_h(scheme, xi, omega_max=1e3)
    top = min(limit, 1e3)
    rho = stab.spectral_radius(scheme, np.geomspace(1e-3, 0.99 * top, 60), xi)
    assert np.all(rho <= 1.0 + 1e-9), float(np.max(rho))
    if math.isfinite(limit):
        assert stab.spectral_radius(scheme, 1.01 * limit, xi) > 1.0 + 1e-9


def check_matrix_reproduces_a_step(scheme):
    om, xi = 0.7, 0.05
    A = stab.amplification_matrix(scheme, om, xi)
    st = nvib.Stepper(nvib.Model([1.0], K=[[1.0]], C=[[2 * xi]]), scheme, om)
    x = np.random.default_rng(1).standard_normal(A.shape[0])
    st.set_state(x, 0.0)
    st.step()
    d = np.r_[1.0, om, np.full(A.shape[0] - 2, om * om)]  # the scaling (u, dt v, dt^2 a, ...)
    np.testing.assert_allclose(A @ (d * x), d * st.state(), rtol=1e-12, atol=1e-13)


@pytest.mark.parametrize("beta, gamma", [(0.25, 0.5), (1 / 6, 0.5), (0.3025, 0.6)])
@pytest.mark.parametrize("xi", [0.0, 0.05])
def test_newmark_matrix_is_the_closed_form(beta, gamma, xi):
    for om in (0.1, 1.0, 3.0, 100.0):
        A = stab.amplification_matrix(nvib.Newmark(beta, gamma), om, xi)
        np.testing.assert_allclose(A, newmark_matrix(beta, gamma, om, xi), rtol=1e-12, atol=1e-12)


def test_undamped_central_difference_is_newmark_beta_0():
    for om in (0.1, 1.0, 1.9, 5.0):
        A = stab.amplification_matrix(nvib.CentralDifference(), om)
        np.testing.assert_allclose(A, newmark_matrix(0.0, 0.5, om), rtol=1e-13, atol=1e-13)


# ---------------------------------------------------------------- stability limits

@pytest.mark.parametrize("scheme", CD_FAMILY, ids=repr)
def test_undamped_limit_of_the_central_difference_family_is_2(scheme):
    oc = stab.critical_omega_h(scheme)
    assert oc == pytest.approx(2.0, rel=1e-6)  # the issue asks for 1 %
    # below the limit nothing grows and nothing decays
    np.testing.assert_allclose(stab.spectral_radius(scheme, np.linspace(0.05, 1.99, 12)), 1.0, atol=1e-9)


@pytest.mark.parametrize("xi", [0.05, 0.1, 0.3])
def test_damped_zhai_limit(xi):
    expected = 2.0 * (math.sqrt(1.0 + 4.0 * xi * xi) - 2.0 * xi)  # an eigenvalue passes through -1 there
    assert stab.critical_omega_h(nvib.Zhai(0.5, 0.5), xi) == pytest.approx(expected, rel=1e-6)


@pytest.mark.parametrize("scheme", [nvib.CentralDifference(), nvib.CEMDTS(0.45)], ids=repr)
def test_damped_central_difference_family_shares_zhais_limit(scheme):
    # the synchronized velocity predictor v_n + dt a_n extrapolates like Zhai's velocity
    xi = 0.05
    assert stab.critical_omega_h(scheme, xi) == pytest.approx(2.0 * (math.sqrt(1.0 + 4.0 * xi * xi) - 2.0 * xi),
                                                              rel=1e-6)


def test_zhai_dissipative_member_and_newmark_linear_acceleration():
    assert stab.critical_omega_h(nvib.Zhai(0.6, 0.6)) == pytest.approx(math.sqrt(2.0 / 0.6), rel=1e-6)
    assert stab.critical_omega_h(nvib.Newmark(1 / 6, 0.5)) == pytest.approx(math.sqrt(12.0), rel=1e-6)


@pytest.mark.parametrize("scheme", (nvib.Newmark(), nvib.GeneralizedAlpha(), nvib.GeneralizedAlpha.from_rho_inf(0.5),
                                    nvib.PreciseIntegration()), ids=repr)
def test_unconditionally_stable_schemes_have_no_limit(scheme):
    assert stab.critical_omega_h(scheme, 0.05, omega_max=1e3) == math.inf


def test_trapezoidal_newmark_has_unit_spectral_radius_up_to_1e4():
    oms = np.geomspace(1e-3, 1e4, 29)
    np.testing.assert_allclose(stab.spectral_radius(nvib.Newmark(0.25, 0.5), oms), 1.0, rtol=0, atol=1e-12)


@pytest.mark.parametrize("rho_inf", [0.0, 0.5, 0.8, 1.0])
def test_generalized_alpha_tends_to_rho_inf(rho_inf):
    rho = stab.spectral_radius(nvib.GeneralizedAlpha.from_rho_inf(rho_inf), [1e2, 1e4, 1e6])
    gap = np.abs(rho - rho_inf)
    assert gap[-1] < 2e-4  # the roots meet at -rho_inf like Omega^(-2/3): 1e-4 at 1e6
    assert rho_inf == 1.0 or (gap[0] > gap[1] > gap[2])


@pytest.mark.parametrize("scheme, rho_inf", [(nvib.GeneralizedAlpha.hht(-0.3), 0.7 / 1.3),
                                             (nvib.GeneralizedAlpha.wbz(-0.3), 0.7 / 1.3)], ids=["hht", "wbz"])
def test_hht_and_wbz_limits(scheme, rho_inf):
    assert stab.spectral_radius(scheme, 1e7) == pytest.approx(rho_inf, abs=1e-4)


# ---------------------------------------------------------------- accuracy against closed forms

@pytest.mark.parametrize("xi", [0.0, 0.05, 0.2])
def test_precise_integration_is_exact_on_the_linear_oscillator(xi):
    oms = np.geomspace(0.01, 30.0, 10)
    pim = nvib.PreciseIntegration()
    np.testing.assert_allclose(stab.spectral_radius(pim, oms, xi), np.exp(-xi * oms), rtol=1e-9)
    below = oms[oms < 3.0]  # the principal root passes -1 at Omega = pi
    np.testing.assert_allclose(stab.period_error(pim, below, xi), 0.0, atol=1e-10)
    np.testing.assert_allclose(stab.damping_ratio(pim, below, xi), xi, atol=1e-10)
    assert np.isnan(stab.period_error(pim, 4.0, xi))


def test_central_difference_period_error_closed_form():
    oms = np.array([0.01, 0.1, 0.5, 1.0, 1.5, 1.9, 1.99])
    for scheme in (nvib.CentralDifference(), nvib.CEMDTS(0.45), nvib.Zhai()):
        # cos(Omega_bar) = 1 - Omega^2/2, i.e. Omega_bar = 2 arcsin(Omega/2) (the arcsin form keeps its digits at
        # small Omega, where arccos(1 - Omega^2/2) loses half of them). The period error ~ Omega^2/24 is a small
        # difference: an error of a few eps in the eigenvalue's angle is a relative error of about
        # eps / Omega^3 = 1e-10 of it at Omega = 0.01, hence rtol 1e-7.
        expected = oms / (2.0 * np.arcsin(oms / 2.0)) - 1.0
        np.testing.assert_allclose(stab.period_error(scheme, oms), expected, rtol=1e-7, atol=1e-12)
        np.testing.assert_allclose(stab.damping_ratio(scheme, oms), 0.0, atol=1e-10)
        assert np.isnan(stab.period_error(scheme, 2.5)) and np.isnan(stab.damping_ratio(scheme, 2.5))


def test_trapezoidal_newmark_period_error_closed_form():
    oms = np.geomspace(0.01, 1e3, 15)
    np.testing.assert_allclose(stab.period_error(nvib.Newmark(), oms), oms / (2.0 * np.arctan(oms / 2.0)) - 1.0,
                               rtol=1e-8, atol=1e-12)


def test_generalized_alpha_damps_high_frequencies_only():
    ga = nvib.GeneralizedAlpha.from_rho_inf(0.8)
    zeta = stab.damping_ratio(ga, [0.01, 0.1, 10.0])
    assert zeta[0] < 1e-8 < zeta[1] < 1e-5 < zeta[2]  # third-order dissipation at low Omega


def test_a_step_that_overflows_counts_as_unstable():
    pim = nvib.PreciseIntegration(squarings=8)  # the 2^N exponential overflows at large Omega
    assert stab.spectral_radius(pim, 1e5) == math.inf
    assert np.isnan(stab.period_error(pim, 1e5))
    assert stab.critical_omega_h(pim) < 1e3


def test_vectorised_results_keep_the_shape():
    oms = np.array([[0.1, 0.5, 1.0], [1.5, 1.9, 3.0]])
    rho = stab.spectral_radius(nvib.CEMDTS(), oms, 0.02)
    assert rho.shape == (2, 3)
    assert rho[1, 1] == stab.spectral_radius(nvib.CEMDTS(), 1.9, 0.02)
    assert isinstance(stab.period_error(nvib.Newmark(), 0.3), float)
    assert stab.period_error(nvib.Newmark(), oms).shape == (2, 3)


# ---------------------------------------------------------------- bad input

@pytest.mark.parametrize("call, exc, name", [
    (lambda: stab.spectral_radius(nvib.Newmark(), 0.0), ValueError, "omega_h"),
    (lambda: stab.spectral_radius(nvib.Newmark(), [1.0, -1.0]), ValueError, "omega_h"),
    (lambda: stab.spectral_radius(nvib.Newmark(), math.nan), ValueError, "omega_h"),
    (lambda: stab.spectral_radius(nvib.Newmark(), math.inf), ValueError, "omega_h"),
    (lambda: stab.spectral_radius(nvib.Newmark(), "1.0"), TypeError, "omega_h"),
    (lambda: stab.spectral_radius(nvib.Newmark(), True), TypeError, "omega_h"),
    (lambda: stab.amplification_matrix(nvib.Newmark(), [1.0, 2.0]), TypeError, "omega_h"),
    (lambda: stab.period_error(nvib.Newmark(), 1.0, xi=1.0), ValueError, "xi"),
    (lambda: stab.damping_ratio(nvib.Newmark(), 1.0, xi=-0.1), ValueError, "xi"),
    (lambda: stab.spectral_radius(nvib.Newmark(), 1.0, xi=math.nan), ValueError, "xi"),
    (lambda: stab.critical_omega_h(nvib.Newmark(), xi="0.1"), TypeError, "xi"),
    (lambda: stab.spectral_radius("newmark", 1.0), TypeError, "scheme"),
    (lambda: stab.critical_omega_h(None), TypeError, "scheme"),
    (lambda: stab.critical_omega_h(nvib.Newmark(), omega_max=-1.0), ValueError, "omega_max"),
    (lambda: stab.critical_omega_h(nvib.Newmark(), tol=0.0), ValueError, "tol"),
    (lambda: stab.critical_omega_h(nvib.Newmark(), omega_max=1e9), ValueError, "omega_max"),
    (lambda: stab.critical_omega_h(nvib.Newmark(), omega_min=2e4), ValueError, "omega_min"),
    (lambda: stab.spectral_radius(nvib.Newmark(), 1e-7), ValueError, "omega_h"),
    (lambda: stab.amplification_matrix(nvib.Newmark(), 1e8), ValueError, "omega_h"),
    (lambda: stab.amplification_matrix(nvib.PreciseIntegration(squarings=8), 1e5), ValueError, "omega_h"),
])
def test_bad_input_names_the_argument(call, exc, name):
    with pytest.raises(exc, match=rf"^{name}: "):
        call()


# ---------------------------------------------------------------- nvib stability



def table_rows(out: str) -> dict:
    """{scheme: [Omega_crit, rho(0.1), ...]} from the printed table (columns apart by 2+ spaces)."""
    lines = out.splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith("scheme")) + 2
    rows = {}
    for line in lines[start:]:
        if not line.strip():
            break
        cells = re.split(r"\s{2,}", line.strip())
        rows[cells[0]] = cells[1:]
    return rows


def test_cli_prints_the_limits_and_plots(capsys, tmp_path):
    png = tmp_path / "rho.png"
    code, out, err = run_cli(capsys, "stability", "--schemes", "lcdm", "lcdm", "newmark", "--xi", "0.05",
                             "--omega-max", "10", "--points", "40", "--plot", png)
    assert code == 0, err
    rows = table_rows(out)
    assert list(rows) == ["LCDM", "Newmark"]  # a scheme given twice is shown once
    assert float(rows["LCDM"][0]) == pytest.approx(2 * (math.sqrt(1.01) - 0.1), rel=1e-5)
    assert rows["Newmark"][0] == "none"
    assert png.read_bytes()[:8] == PNG_SIGNATURE


def test_cli_passes_scheme_parameters(capsys):
    code, out, _ = run_cli(capsys, "stability", "--schemes", "zhai", "galpha", "--psi", "0.6", "--phi", "0.6",
                           "--rho-inf", "0.5")
    assert code == 0
    rows = table_rows(out)
    assert float(rows["Zhai(0.6,0.6)"][0]) == pytest.approx(math.sqrt(2 / 0.6), rel=1e-5)
    galpha = rows["GαM(0,1/3,4/9,5/6)"]  # alpha_m, alpha_f, beta, gamma of rho_inf = 1/2
    assert galpha[0] == "none"
    assert float(galpha[-1]) == pytest.approx(0.5, abs=0.05)  # rho(100) on its way to 0.5


@pytest.mark.parametrize("argv, argument", [
    (["--xi", "1"], "argument --xi"),
    (["--xi", "-0.1"], "argument --xi"),
    (["--xi", "abc"], "argument --xi"),
    (["--schemes", "lcdm", "--eta", "0.3"], "argument --eta"),
    (["--schemes", "cd"], "argument --schemes"),
    (["--schemes", "cemdts", "--eta", "2"], "argument --eta"),
    (["--schemes", "rk4"], "argument --schemes"),
    (["--omega-max", "0"], "argument --omega-max"),
    (["--omega-min", "10", "--omega-max", "1"], "argument --omega-min"),
    (["--omega-min", "1e-9"], "argument --omega-min"),
    (["--omega-max", "1e9"], "argument --omega-max"),
    (["--plot", "rho.jpg"], "argument --plot"),
])
def test_cli_bad_input_exits_2_naming_the_argument(capsys, argv, argument):
    code, _, err = run_cli(capsys, "stability", *argv)
    assert code == 2
    assert argument in err
    assert err.strip().splitlines()[-1].startswith("nvib stability: error:")


def test_stability_figure_separates_schemes_of_equal_spectral_radius_by_their_period_error():
    """Undamped, every scheme here has rho = 1 below its limit: the period-error panel tells them apart,
    CentralDifference shortening the period (Omega^2/24), Newmark lengthening it (Omega^2/12), PIM exact."""
    pytest.importorskip("matplotlib")
    from nvib.analysis.stability import stability_figure

    schemes = [nvib.CentralDifference(), nvib.Newmark(), nvib.PreciseIntegration()]
    fig = stability_figure(schemes, omega_h=np.geomspace(1e-2, 1e1, 60))
    rho_ax, period_ax = fig.axes
    legend = [t.get_text() for t in period_ax.get_legend().get_texts()]
    assert [lab.rsplit(" ", 1)[1] for lab in legend] == ["(shortens)", "(lengthens)", "(exact)"]
    assert period_ax.get_ylabel() == "period error |T̄/T - 1| [-]" and rho_ax.get_ylabel() == "spectral radius ρ"
    lcdm, newmark = period_ax.lines[0], period_ax.lines[1]
    k = 0  # at Omega = 0.01 the leading terms hold to ~1e-5 relative
    assert lcdm.get_ydata()[k] == pytest.approx(1e-4 / 24, rel=1e-3)
    assert newmark.get_ydata()[k] == pytest.approx(1e-4 / 12, rel=1e-3)
