"""Fragility functions: the maximum-likelihood fits recover theta and beta of synthetic lognormal data
within their standard errors (coverage over many datasets), equal the closed forms and a brute-force
maximisation of the same likelihood, refuse data without a maximum and bad intensities naming the
argument, plot with labelled axes, and read an IDA's collapses and exceedances as counted there."""

import math
import os

import numpy as np
import pytest
from scipy import stats

import nvib
from nvib import fragility

THETA, BETA = 1.2, 0.4
DATASETS = 200


def coverage(fits, n_obs):
    """The fraction of fits whose ±2 SE interval holds the true theta and beta, and a check that the
    estimates are unbiased: the mean over the datasets within 4 standard errors of that mean, plus
    beta / n_obs for the O(1/n) small-sample bias of a maximum-likelihood dispersion."""
    theta = np.array([f.theta for f in fits])
    beta = np.array([f.beta for f in fits])
    se_theta = np.array([f.se_theta for f in fits])
    se_beta = np.array([f.se_beta for f in fits])
    assert np.all(np.isfinite(se_theta)) and np.all(se_theta > 0) and np.all(se_beta > 0)
    cover = (np.mean(np.abs(theta - THETA) <= 2 * se_theta), np.mean(np.abs(beta - BETA) <= 2 * se_beta))
    for est, true in ((theta, THETA), (beta, BETA)):
        tol = 4 * est.std() / math.sqrt(est.size) + BETA * true / n_obs
        assert abs(est.mean() - true) <= tol, (est.mean(), true, tol)
    return cover


def test_collapse_ims_recover_theta_and_beta_within_their_standard_errors():
    rng = np.random.default_rng(20)
    n = 40
    fits = [fragility.fit_collapse_ims(np.exp(rng.normal(math.log(THETA), BETA, n))) for _ in range(DATASETS)]
    c_theta, c_beta = coverage(fits, n)
    assert c_theta >= 0.85 and c_beta >= 0.85, (c_theta, c_beta)
    f = fits[0]
    assert f.method == "collapse IM values" and f.censored_ims.size == 0
    # the closed forms: the mean and standard deviation (ddof 0) of ln IM; Baker's n - 1 beside them
    x = np.log(f.collapse_ims)
    assert f.theta == pytest.approx(math.exp(x.mean()), rel=1e-14)
    assert f.beta == pytest.approx(x.std(), rel=1e-14)
    assert f.beta_sample == pytest.approx(x.std(ddof=1), rel=1e-14)
    assert f.se_theta == pytest.approx(f.theta * f.beta / math.sqrt(n), rel=1e-14)
    assert f.se_beta == pytest.approx(f.beta / math.sqrt(2 * n), rel=1e-14)


def test_the_newton_maximum_equals_the_closed_form_without_censoring():
    # the general path (Newton on the censored likelihood) with nothing censored gives the closed form
    from nvib.analysis.fragility import _Likelihood

    x = np.log(np.exp(np.random.default_rng(3).normal(0.1, 0.5, 25)))
    (a, b), _, _ = _Likelihood(x_exact=x).maximise((1.0, 0.0))
    assert 1 / a == pytest.approx(x.std(), rel=1e-12) and -b / a == pytest.approx(x.mean(), abs=1e-12)


def test_censored_collapse_ims_recover_theta_and_beta():
    # an IDA truncated at the 75th percentile of the collapse IMs: a quarter of the records did not collapse
    rng = np.random.default_rng(21)
    n = 40
    cap = THETA * math.exp(BETA * stats.norm.ppf(0.75))
    fits = []
    for _ in range(DATASETS):
        ims = np.exp(rng.normal(math.log(THETA), BETA, n))
        fits.append(fragility.fit_collapse_ims(ims[ims <= cap], censored=np.full(np.sum(ims > cap), cap)))
    c_theta, c_beta = coverage(fits, n)
    assert c_theta >= 0.85 and c_beta >= 0.85, (c_theta, c_beta)
    assert all(f.method == "truncated" for f in fits) and fits[0].beta_sample is None


def test_censored_fit_equals_a_brute_force_maximisation():
    rng = np.random.default_rng(5)
    ims = np.exp(rng.normal(math.log(THETA), BETA, 15))
    cap = 1.4
    f = fragility.fit_collapse_ims(ims[ims <= cap], censored=np.full(np.sum(ims > cap), cap))

    def loglik(mu, beta):
        x = np.log(ims[ims <= cap])
        return (np.sum(stats.norm.logpdf(x, mu, beta)) + np.sum(ims > cap) * stats.norm.logsf(math.log(cap), mu, beta))

    mu, beta = grid_maximum(loglik, (-1.0, 2.0), (0.05, 2.0))
    assert math.log(f.theta) == pytest.approx(mu, abs=1e-6) and f.beta == pytest.approx(beta, abs=1e-6)


LEVELS = np.array([0.3, 0.5, 0.7, 0.9, 1.1, 1.4, 1.8, 2.5])


def test_stripes_recover_theta_and_beta_within_their_standard_errors():
    rng = np.random.default_rng(22)
    n = 20
    p = stats.norm.cdf(np.log(LEVELS / THETA) / BETA)
    fits = [fragility.fit_stripes(LEVELS, n, rng.binomial(n, p)) for _ in range(DATASETS)]
    c_theta, c_beta = coverage(fits, n)
    assert c_theta >= 0.85 and c_beta >= 0.85, (c_theta, c_beta)
    assert fits[0].method == "multiple stripes" and list(fits[0].n) == [n] * LEVELS.size


def test_two_stripes_give_the_exact_solution():
    # two levels, two parameters: the fitted curve passes through both fractions exactly
    f = fragility.fit_stripes([0.5, 1.5], [10, 20], [2, 15])
    u1, u2 = stats.norm.ppf(0.2), stats.norm.ppf(0.75)
    beta = math.log(1.5 / 0.5) / (u2 - u1)
    theta = 0.5 * math.exp(-beta * u1)
    assert f.beta == pytest.approx(beta, rel=1e-10) and f.theta == pytest.approx(theta, rel=1e-10)
    np.testing.assert_allclose(f.probability([0.5, 1.5]), [0.2, 0.75], rtol=1e-10)


def grid_maximum(loglik, mu_range, beta_range, points=41):
    """The maximum of loglik(mu, beta) by grids zoomed on the best point until they are 1e-9 wide."""
    (m0, m1), (b0, b1) = mu_range, beta_range
    while max(m1 - m0, b1 - b0) > 1e-9:
        mus, betas = np.linspace(m0, m1, points), np.linspace(b0, b1, points)
        values = np.array([[loglik(m, b) for b in betas] for m in mus])
        i, j = np.unravel_index(np.argmax(values), values.shape)
        dm, db = 2 * (m1 - m0) / (points - 1), 2 * (b1 - b0) / (points - 1)
        m0, m1 = mus[i] - dm, mus[i] + dm
        b0, b1 = max(betas[j] - db, 1e-6), betas[j] + db
    return 0.5 * (m0 + m1), 0.5 * (b0 + b1)


def test_stripes_equal_a_brute_force_maximisation_of_the_same_likelihood():
    n = np.array([12, 15, 20, 20, 18, 10, 9, 6])
    z = np.array([0, 1, 4, 9, 11, 8, 9, 5])
    f = fragility.fit_stripes(LEVELS, n, z)

    def loglik(mu, beta):
        p = stats.norm.cdf((np.log(LEVELS) - mu) / beta)
        return np.sum(stats.binom.logpmf(z, n, p))

    mu, beta = grid_maximum(loglik, (-2.0, 2.0), (0.05, 2.0))
    assert math.log(f.theta) == pytest.approx(mu, abs=1e-6) and f.beta == pytest.approx(beta, abs=1e-6)
    assert f.log_likelihood == pytest.approx(loglik(mu, beta), abs=1e-9)
    # unordered levels with n given once are the same data
    k = np.argsort(-LEVELS)
    g = fragility.fit_stripes(LEVELS[k], n[k], z[k])
    assert g.theta == pytest.approx(f.theta, rel=1e-12) and list(g.levels) == list(LEVELS)


@pytest.mark.parametrize("z, words", [
    ([0, 0, 0, 0], "no run exceeded"),
    ([10, 10, 10, 10], "every run exceeded"),
    ([0, 0, 10, 10], "separated"),
    ([0, 4, 10, 10], "separated"),      # one mixed level: beta -> 0 still
    ([10, 10, 0, 0], "falls"),
    ([10, 3, 6, 0], "falls"),           # overlapping, but decreasing
])
def test_stripes_without_a_maximum_are_refused_naming_z(z, words):
    with pytest.raises(nvib.ArgumentError) as exc:
        fragility.fit_stripes([0.5, 1.0, 1.5, 2.0], 10, z)
    assert exc.value.argument == "z" and words in str(exc.value)


def test_collapse_ims_without_a_maximum_are_refused():
    with pytest.raises(nvib.ArgumentError) as exc:
        fragility.fit_collapse_ims([1.0, 1.0, 1.0])
    assert exc.value.argument == "ims" and "beta -> 0" in str(exc.value)
    # one collapse IM, but a record outlasted it: the censored likelihood has a maximum
    f = fragility.fit_collapse_ims([1.0, 1.0], censored=[2.0])
    assert 1.0 < f.theta and 0 < f.beta < 5


@pytest.mark.parametrize("call, argument", [
    (lambda: fragility.fit_collapse_ims([1.0, np.nan, 2.0]), "ims"),
    (lambda: fragility.fit_collapse_ims([1.0, np.inf, 2.0]), "ims"),
    (lambda: fragility.fit_collapse_ims([1.0, -0.5, 2.0]), "ims"),
    (lambda: fragility.fit_collapse_ims([1.0, 0.0, 2.0]), "ims"),
    (lambda: fragility.fit_collapse_ims([]), "ims"),
    (lambda: fragility.fit_collapse_ims([1.0, 2.0], censored=[np.inf]), "censored"),
    (lambda: fragility.fit_collapse_ims([1.0, 2.0], censored=[-1.0]), "censored"),
    (lambda: fragility.fit_stripes([0.5, np.nan], 10, [1, 5]), "ims"),
    (lambda: fragility.fit_stripes([-0.5, 1.0], 10, [1, 5]), "ims"),
    (lambda: fragility.fit_stripes([0.5, 1.0], [10, 10], [1, 11]), "z"),
    (lambda: fragility.fit_stripes([0.5, 1.0], [10, 10], [1, -1]), "z"),
    (lambda: fragility.fit_stripes([0.5, 1.0], [10, 10.5], [1, 5]), "n"),
    (lambda: fragility.fit_stripes([0.5, 1.0], [10, 0], [1, 0]), "n"),
    (lambda: fragility.fit_stripes([0.5, 1.0], [10, 10, 10], [1, 5]), "n"),
    (lambda: fragility.fit_stripes([0.5, 1.0, 2.0], 10, [1, 5]), "z"),
])
def test_bad_intensities_and_counts_are_refused_naming_them(call, argument):
    with pytest.raises(nvib.ArgumentError) as exc:
        call()
    assert exc.value.argument == argument


def test_type_errors_name_the_argument():
    with pytest.raises(nvib.ArgumentTypeError) as exc:
        fragility.fit_collapse_ims(["1.0", "2.0"])
    assert exc.value.argument == "ims"
    with pytest.raises(nvib.ArgumentTypeError) as exc:
        fragility.fit_stripes([1.0, 2.0], 10, [1, 5], im_unit=9.81)
    assert exc.value.argument == "im_unit"
    with pytest.raises(nvib.ArgumentTypeError) as exc:
        fragility.from_ida([[1.0]])
    assert exc.value.argument == "ida"


def test_probability_is_the_lognormal_cdf_and_checks_its_im():
    f = fragility.fit_stripes([0.5, 1.0, 1.5, 2.0], 10, [1, 4, 6, 9])
    x = np.array([0.0, 0.3, f.theta, 4.0])
    np.testing.assert_allclose(f.probability(x), stats.lognorm.cdf(x, f.beta, scale=f.theta), rtol=1e-12)
    assert f.probability(f.theta) == pytest.approx(0.5) and isinstance(f.probability(1.0), float)
    with pytest.raises(nvib.ArgumentError) as exc:
        f.probability(-1.0)
    assert exc.value.argument == "im"


def test_repr_and_tables_show_theta_beta_and_the_data():
    f = fragility.fit_stripes([0.5, 1.0, 1.5, 2.0], [10, 10, 10, 8], [1, 4, 6, 7], im_name="Sa(T1 = 0.8 s, 5 %)",
                              im_unit="g", event="drift ratio > 0.02")
    text = repr(f)
    assert f"{f.theta:.4g} g" in text and f"{f.beta:.3f}" in text and "4 stripes" in text
    md = f.markdown()
    assert "| drift ratio > 0.02 | multiple stripes | Sa(T1 = 0.8 s, 5 %) [g] |" in md
    assert "| 2 | 8 | 7 | 0.875 |" in md
    c = fragility.fit_collapse_ims([0.8, 1.1, 1.3], censored=[2.0])
    assert "> 2 | did not collapse" in c.markdown() and "3 collapsed, 1 censored" in fragility.markdown_table([f, c])


@pytest.mark.parametrize("kind", ["stripes", "collapse"])
def test_the_plot_writes_a_file_with_labelled_axes(kind, tmp_path):
    if kind == "stripes":
        f = fragility.fit_stripes([0.5, 1.0, 1.5, 2.0], 10, [1, 4, 6, 9], im_name="Sa(T1 = 0.8 s, 5 %)", im_unit="g")
    else:
        f = fragility.fit_collapse_ims([0.8, 1.1, 1.3, 0.9], censored=[2.0, 2.0], im_name="Sa(T1 = 0.8 s, 5 %)",
                                       im_unit="g")
    path = tmp_path / "fragility.png"
    ax = f.plot(path)
    assert path.stat().st_size > 10_000
    assert ax.get_xlabel() == "Sa(T1 = 0.8 s, 5 %) [g]"
    assert ax.get_ylabel() == f"P({f.event} | IM) [-]"
    lo, hi = ax.get_ylim()
    assert lo <= 0 and 1 <= hi < 1.05
    legend = " ".join(t.get_text() for t in ax.get_legend().get_texts())
    assert f"θ = {f.theta:.3g} g" in legend and f"β = {f.beta:.3f}" in legend
    # the data are drawn: the stripes' fractions, or the empirical CDF of the collapse IMs
    drawn = np.concatenate([np.asarray(c.get_offsets())[:, 1] for c in ax.collections]
                           + [line.get_ydata() for line in ax.lines])
    want = f.z / f.n if kind == "stripes" else np.arange(1, 5) / 6
    assert all(np.any(np.isclose(drawn, w)) for w in want)


# ---- from an incremental dynamic analysis ---------------------------------------------------------------

@pytest.fixture(scope="module")
def small_ida():
    """The deteriorating building scene under five 12-s windows of its record at four scale factors
    (0.1 s of computing): some records collapse, some outlast the highest level."""
    model = nvib.load_scene("building_collapse")
    at2 = os.path.join(os.path.dirname(nvib.__file__), "scenes", "records", "sgm1.AT2")
    gm = nvib.GroundMotion.from_at2(at2, scale=nvib.STANDARD_GRAVITY)
    records = []
    for start in (0, 4, 8, 12, 16):
        i = int(round(start / gm.dt))
        records.append(nvib.GroundMotion.from_array(gm.a[i:i + 1200], dt=gm.dt, name=f"SGM-1 from {start} s"))
    return nvib.ida(model, records, [0.3, 0.6, 0.9, 1.2], im="scale", dt=0.002, tail=0.0, check=False,
                    progress=False)


def test_from_ida_collapse_fragility_reads_each_records_first_collapse(small_ida):
    ida = small_ida
    assert ida.collapsed.any() and not ida.collapsed.all(axis=1).all()
    f = fragility.from_ida(ida)
    first = [ida.levels[np.argmax(row)] for row in ida.collapsed if row.any()]
    never = [ida.levels.max() for row in ida.collapsed if not row.any()]
    assert sorted(f.collapse_ims) == sorted(first) and list(f.censored_ims) == never
    assert f.method == ("truncated" if never else "collapse IM values") and f.event == "collapse"
    assert f.im_name == "scale factor of the records" and f.im_unit == "-"
    p = f.probability(np.linspace(0, 3, 200))
    assert np.all(np.diff(p) >= 0) and p[0] == 0 and p[-1] > 0.9


def test_from_ida_exceedance_fragility_counts_the_ida(small_ida):
    ida = small_ida
    limit = 0.6  # % drift ratio
    f = fragility.from_ida(ida, demand_limit=limit)
    exceeded = ida.collapsed | (ida.measure > limit)
    np.testing.assert_array_equal(f.levels, ida.levels)
    np.testing.assert_array_equal(f.n, [len(ida.records)] * ida.levels.size)
    np.testing.assert_array_equal(f.z, exceeded.sum(axis=0))
    assert f.event == f"{ida.measure_name} > 0.6 %" and f.method == "multiple stripes"
    p = f.probability(np.linspace(0, 3, 200))
    assert np.all(np.diff(p) >= 0)
    # a limit the data separate (nothing exceeds it below one level, everything above) is refused naming it
    with pytest.raises(nvib.ArgumentError) as exc:
        fragility.from_ida(ida, demand_limit=1e-9)
    assert exc.value.argument == "demand_limit"


def test_from_ida_reads_the_intensity_measure_of_an_ida_on_sa():
    # an IDA on Sa(T1) (each record scaled to each level) labels the fragility with it, in the record's unit
    model = nvib.load_scene("building_collapse")
    at2 = os.path.join(os.path.dirname(nvib.__file__), "scenes", "records", "sgm1.AT2")
    gm = nvib.GroundMotion.from_at2(at2)  # in g
    starts = [int(round(s / gm.dt)) for s in (0, 4, 8, 12, 16)]
    records = [nvib.GroundMotion.from_array(gm.a[i:i + 1200] * nvib.STANDARD_GRAVITY, dt=gm.dt, units="m/s^2",
                                            name=f"SGM-1 from {i}") for i in starts]
    ida = nvib.ida(model, records, [2.0, 4.0, 8.0, 16.0], im="sa", period=0.8, dt=0.002, tail=0.0, check=False,
                   progress=False)
    f = fragility.from_ida(ida)
    assert f.im_label == "Sa(T1 = 0.8 s, 5 %) [m/s^2]"
    first = [ida.levels[np.argmax(row)] for row in ida.collapsed if row.any()]
    assert sorted(f.collapse_ims) == sorted(first) and len(first) >= 2