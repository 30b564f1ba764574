"""Incremental dynamic analysis: stripes equal the runs' own peaks; records are scaled to Sa(T1); a linear
model's curve is a straight line through the origin; hunt and fill brackets each collapse to the tolerance,
and each collapse is named by its cause and confirmed by a run of its own; fractiles count collapses; each
run's checked error is the change at half the step; runs end at their own record's end plus the tail."""

import os

import numpy as np
import pytest

import nvib
import nvib.cli
from nvib.analysis.ida import read_ida

from test_batch import motions, two_storeys

STOREYS = {"storey1": 3.0, "storey2": 2.5}


def drift_ratio(h, storeys=STOREYS):
    """The maximum drift ratio [%] of a two-storey history, from its displacements."""
    d1, d2 = np.abs(h.u[:, 0]), np.abs(h.u[:, 1] - h.u[:, 0])
    return 100.0 * max(d1.max() / storeys["storey1"], d2.max() / storeys["storey2"])


def test_stripes_equal_the_runs_and_a_divergence_is_a_named_collapse(tmp_path):
    records = motions()
    # the last level drives the hardening storeys past the central difference's stability limit at this step
    # (their tangent stiffness grows with the drift): the run diverges, a collapse by non-convergence
    # (the drift limit is set out of reach: the divergence itself ends the curve)
    levels = [0.5, 1.0, 2.0, 1e7]
    res = nvib.ida(two_storeys(), records, levels, im="scale", storeys=STOREYS, scheme=nvib.CentralDifference(),
                   dt=1e-3, tail=0.0, drift_limit=1e9, check=False, progress=False)
    assert res.records == ["decay", "square"] and res.measure.shape == (2, 4)
    assert res.measure_name == "max interstorey drift ratio" and res.measure_unit == "%"
    for i, gm in enumerate(records):
        for j, s in enumerate(levels[:3]):
            h = nvib.solve(two_storeys(gm.scaled(s)), nvib.CentralDifference(), dt=1e-3, t_end=gm.t[-1])
            assert res.measure[i, j] == drift_ratio(h)
            assert res.curves[i].estimate[j] == h.error_estimate.max  # each run's own estimate, as solve gives it
        c = res.curves[i]
        assert c.collapsed[3] and c.cause[3] == "non-convergence" and "diverged" in c.message[3]
        assert c.capacity == 2.0 and c.collapse_im == 1e7
    np.testing.assert_array_equal(res.median[:3], np.percentile(res.measure[:, :3], 50, axis=0))
    assert np.all(np.isinf(res.measure[:, 3])) and np.isinf(res.median[3])
    assert "non-convergence" in res.markdown() and "collapse" in res.markdown()
    res.plot(tmp_path / "ida.png")
    assert (tmp_path / "ida.png").stat().st_size > 10_000


def test_measures_and_arguments():
    base = two_storeys()
    res = nvib.ida(base, motions()[:1], [1.0], im="scale", measure="storey2", dt=1e-3, tail=0.0, check=False,
                   progress=False)
    h = nvib.solve(base, nvib.CEMDTS(), dt=1e-3, t_end=motions()[0].t[-1])
    assert res.measure[0, 0] == np.max(np.abs(h.u[:, 1] - h.u[:, 0]))
    for kw, arg in ((dict(measure="storey9"), "measure"), (dict(), "storeys"),
                    (dict(storeys={"storey3": 3.0}), "storeys['storey3']"),
                    (dict(storeys={"storey1": -3.0}), "storeys['storey1']"),
                    (dict(storeys=STOREYS, tolerance=0.0), "tolerance"),
                    (dict(storeys=STOREYS, slope_limit=1.5), "slope_limit"),
                    (dict(storeys=STOREYS, tail=-1.0), "tail"), (dict(storeys=STOREYS, max_runs=1), "max_runs")):
        with pytest.raises(nvib.ArgumentError) as exc:
            nvib.ida(base, motions()[:1], [1.0], im="scale", dt=1e-3, progress=False, **kw)
        assert exc.value.argument == arg, kw
    with pytest.raises(nvib.ArgumentTypeError) as exc:
        nvib.ida(base, [[0.0, 1.0]], [1.0], dt=1e-3)
    assert exc.value.argument == "records[0]"


def test_records_are_scaled_to_each_level_of_sa_t1():
    """im='sa': each record is scaled so that its exact Sa(T1) equals the level (Vamvatsikos & Cornell 2002)."""
    records = motions()
    levels = [0.5, 1.0, 2.0]
    res = nvib.ida(two_storeys(), records, levels, im="sa", period=0.5, storeys=STOREYS, dt=1e-3, check=False,
                   progress=False)
    assert res.im_name == "Sa(T1 = 0.5 s, 5 %)"
    for i, r in enumerate(records):
        for j, level in enumerate(levels):
            sa = nvib._core.elastic_spectrum(r.a * res.curves[i].factor[j], r.dt, [0.5], 0.05)["PSa"][0]
            assert sa == pytest.approx(level, rel=1e-12)
    assert "Sa(T1 = 0.5 s, 5 %)" in res.markdown()
    # without a period, T1 is the model's own first period
    T1 = 2 * np.pi / two_storeys().linearized_frequencies()[0]
    res = nvib.ida(two_storeys(), records[:1], [1.0], storeys=STOREYS, dt=1e-3, check=False, progress=False)
    assert res.im_name == f"Sa(T1 = {T1:.3g} s, 5 %)"


def test_a_linear_models_ida_curve_is_a_straight_line_through_the_origin():
    """The drift ratio of a linear model is proportional to the record's scale, so to Sa(T1): demand / Sa is
    the same at every level of a record (a straight line through the origin), to round-off."""
    records = motions()
    levels = [0.1, 0.4, 1.6, 6.4]
    res = nvib.ida(two_storeys(a=0.0), records, levels, im="sa", period=0.3, storeys=STOREYS,
                   scheme=nvib.Newmark(), dt=2e-3, check=False, progress=False)
    slope = res.measure / np.asarray(levels)[None, :]
    np.testing.assert_allclose(slope, slope[:, :1] * np.ones_like(slope), rtol=1e-9)
    assert not np.allclose(slope[0, 0], slope[1, 0], rtol=1e-3)  # each record its own line


def test_each_run_ends_at_its_own_records_end_plus_the_tail():
    square = motions()[1]
    # two cuts of a square wave whose peak drift comes in the free vibration after them (measured: 0.30 % at
    # the end of the 0.4-s cut, 0.56 % 0.4 s later; 0.61 % and 0.71 % for the 0.6-s cut)
    cuts = [nvib.GroundMotion.from_array(square.a[:n], dt=square.dt, name=f"{n} samples") for n in (80, 120)]
    tail = 0.4
    res = nvib.ida(two_storeys(), cuts, [1.0], im="scale", storeys=STOREYS, dt=1e-3, tail=tail, check=False,
                   progress=False)
    for i, gm in enumerate(cuts):
        h = nvib.solve(two_storeys(gm), nvib.CEMDTS(), dt=1e-3, t_end=gm.t[-1] + tail)
        assert res.measure[i, 0] == drift_ratio(h)
        until_end = nvib.solve(two_storeys(gm), nvib.CEMDTS(), dt=1e-3, t_end=gm.t[-1])
        assert drift_ratio(until_end) < 0.9 * drift_ratio(h)


def test_runs_report_their_estimates_and_those_above_warn_error_are_named(tmp_path, capsys):
    gm = motions()[0]
    levels = [0.5, 1.0, 2.0]
    res = nvib.ida(two_storeys(), [gm], levels, im="scale", storeys=STOREYS, dt=2e-3, tail=0.0, check=False,
                   progress=False)
    est = res.curves[0].estimate
    assert np.all((est > 0) & (est < 1e-2)) and not any("warn_error" in w for w in res.warnings)
    worst = int(np.argmax(est))
    line = res.estimate_summary()
    assert f"worst {est[worst]:.2g} (decay at {levels[worst]:.4g})" in line and "3 of 3 runs estimated" in line
    assert "worst estimate" in res.markdown() and f"{est.max():.2g} |" in res.markdown()
    # a threshold between the runs' estimates: only the runs above it are counted, the worst named
    limit = float(np.sort(est)[0] * 1.0001)
    low = nvib.ida(two_storeys(), [gm], levels, im="scale", storeys=STOREYS, dt=2e-3, tail=0.0, check=False,
                   progress=False, warn_error=limit)
    np.testing.assert_array_equal(low.curves[0].estimate, est)
    [w] = [w for w in low.warnings if "warn_error" in w]
    assert w.startswith(f"decay: 2 of 3 runs estimate their error above warn_error = {limit:g} (worst {est[worst]:.2g}")
    # the estimates travel through the CSV (a file without the column reads back with NaN)
    res.to_csv(tmp_path / "ida.csv")
    np.testing.assert_array_equal(read_ida(tmp_path / "ida.csv").curves[0].estimate, est)
    lines = (tmp_path / "ida.csv").read_text().splitlines()
    old = [line if line.startswith("#") else line.rsplit(",", 1)[0] for line in lines]
    (tmp_path / "old.csv").write_text("\n".join(old) + "\n")
    assert np.all(np.isnan(read_ida(tmp_path / "old.csv").curves[0].estimate))


def test_the_checked_error_is_the_change_at_half_the_step():
    gm = motions()[0]
    res = nvib.ida(two_storeys(), [gm], [2.0], im="scale", storeys=STOREYS, dt=2e-3, tail=0.0, progress=False)
    full = drift_ratio(nvib.solve(two_storeys(gm.scaled(2.0)), nvib.CEMDTS(), dt=2e-3, t_end=gm.t[-1]))
    half = drift_ratio(nvib.solve(two_storeys(gm.scaled(2.0)), nvib.CEMDTS(), dt=1e-3, t_end=gm.t[-1]))
    assert res.curves[0].error[0] == pytest.approx(abs(full - half) / half, rel=1e-12)
    assert 0 < res.curves[0].error[0] < 1e-2


@pytest.fixture(scope="module")
def collapse_records():
    """Three 12-s windows of SGM-1 (in g) for the deteriorating building."""
    at2 = os.path.join(os.path.dirname(nvib.__file__), "scenes", "records", "sgm1.AT2")
    gm = nvib.GroundMotion.from_at2(at2)
    out = []
    for start in (0, 6, 12):
        i = int(round(start / gm.dt))
        out.append(nvib.GroundMotion.from_array(gm.a[i:i + 1200], dt=gm.dt, units="g", name=f"SGM-1 from {start} s"))
    return out


def test_hunt_and_fill_brackets_each_collapse_to_the_tolerance(collapse_records):
    model = nvib.load_scene("building_collapse")
    tol = 0.03
    res = nvib.ida(model, collapse_records, dt=0.002, tolerance=tol, check=False, progress=False)
    assert res.tolerance == tol and res.im_unit == "g" and not res.warnings
    for c in res.curves:
        assert np.all(np.diff(c.im) > 0)
        assert np.isfinite(c.collapse_im) and 0 < c.capacity < c.collapse_im <= (1 + tol) * c.capacity
        # below the capacity nothing collapsed, at the first collapse the cause is one of the named ones
        first = int(np.argmax(c.collapsed))
        assert not c.collapsed[:first].any() and c.cause[first] in nvib.analysis.ida.CAUSES
        assert c.im.size <= 16
    # the capacities' fractiles count the records, and the summary's median is infinite above the median capacity
    caps = np.sort(res.capacities)
    assert res.capacity_fractile(50) == caps[1]
    above = res.levels > caps[1]
    assert np.all(np.isinf(res.median[above])) and np.all(np.isfinite(res.median[~above]))


def test_a_degrading_model_collapses_by_lost_strength_confirmed_by_its_own_run(collapse_records):
    """With the dynamic-instability criterion made loose (slope_limit 0.01), the deteriorating storeys' own
    failure ends the curve: the cause is "strength lost", and a run of its own at that level stops collapsed,
    naming a storey, while the capacity level survives."""
    model = nvib.load_scene("building_collapse")
    gm = collapse_records[2]
    res = nvib.ida(model, [gm], dt=0.002, slope_limit=0.01, check=False, progress=False)
    c = res.curves[0]
    assert c.collapse_cause == "strength lost" and "storey" in c.message[int(np.argmax(c.collapsed))]
    for level, collapses in ((c.collapse_im, True), (c.capacity, False)):
        f = level / gm.psa([res_period(res)])[0]
        run = nvib.solve(nvib.load_scene("building_collapse", ground_motion=gm.scaled(f)), nvib.CEMDTS(), dt=0.002,
                         t_end=gm.t[-1] + 2 * res_period(res), throw=False)
        assert (run.status == nvib.Status.collapsed) == collapses


def res_period(res) -> float:
    return float(res.im_name.split("= ")[1].split(" s")[0])


def test_a_drift_limit_ends_the_curve_of_a_model_that_keeps_its_strength(collapse_records):
    """The bilinear building never loses strength: its curve ends where the drift ratio reaches the limit,
    and the first collapse's own run reaches it while the capacity's does not."""
    model = nvib.load_scene("building_inelastic")
    gm = collapse_records[0]
    limit = 0.02
    res = nvib.ida(model, [gm], dt=0.002, drift_limit=limit, slope_limit=0.01, tolerance=0.05, check=False,
                   progress=False)
    c = res.curves[0]
    assert c.collapse_cause == "drift limit"
    first = int(np.argmax(c.collapsed))
    assert c.run_demand[first] >= 100 * limit > np.max(c.demand[:first])


def test_dynamic_instability_is_a_flattening_of_the_curve(collapse_records):
    model = nvib.load_scene("building_collapse")
    res = nvib.ida(model, collapse_records[:1], dt=0.002, check=False, progress=False)
    c = res.curves[0]
    assert c.collapse_cause == "dynamic instability"
    k = int(np.argmax(c.collapsed))
    elastic = c.im[0] / c.demand[0]
    slope = (c.im[k] - c.im[k - 1]) / (c.run_demand[k] - c.demand[k - 1])
    assert 0 < slope < 0.2 * elastic
    # every level survived below it climbs at least as steeply as the limit from the one before
    for j in range(1, k):
        if c.demand[j] > c.demand[j - 1]:
            assert (c.im[j] - c.im[j - 1]) / (c.demand[j] - c.demand[j - 1]) >= 0.2 * elastic


def test_the_csv_reads_back_and_the_command_line_runs_ida_and_fragility(tmp_path, collapse_records, capsys):
    files = []
    for gm in collapse_records:
        path = tmp_path / (gm.name.replace(" ", "_") + ".txt")
        np.savetxt(path, gm.a)
        files.append(str(path))
    out, png, frag = tmp_path / "ida.csv", tmp_path / "ida.png", tmp_path / "fragility.png"
    code = nvib.cli.main(["ida", "building_collapse", *files, "--record-dt", "0.01", "--record-units", "g",
                          "--out", str(out), "--plot", str(png), "--no-check", "--no-progress"])
    text = capsys.readouterr().out
    assert code == 0 and "collapse capacity: median" in text and "dynamic instability" in text
    assert "estimated error of the runs (relative to the peaks): median" in text
    res = read_ida(out)
    assert len(res.curves) == 3 and res.im_unit == "g" and res.measure_unit == "%"
    direct = nvib.ida(nvib.load_scene("building_collapse"), [nvib.GroundMotion.from_file(f, dt=0.01, units="g")
                                                             for f in files], dt=0.002, check=False, progress=False)
    for a, b in zip(res.curves, direct.curves):
        np.testing.assert_array_equal(a.im, b.im)
        np.testing.assert_array_equal(a.demand, b.demand)
        assert a.cause == b.cause
    assert png.stat().st_size > 10_000
    code = nvib.cli.main(["fragility", str(out), "--demand-limit", "1", "--plot", str(frag)])
    text = capsys.readouterr().out
    assert code == 0 and "| collapse |" in text and "> 1 %" in text and frag.stat().st_size > 10_000
    with pytest.raises(SystemExit) as exc:
        nvib.cli.main(["ida", "building_collapse", files[0], "--record-dt", "0.01", "--record-units", "g",
                       "--tolerance", "-1"])
    assert exc.value.code == 2
    assert "--tolerance" in capsys.readouterr().err


def test_intensity_measures_and_their_arguments():
    r = motions()[0]
    assert nvib.analysis.ida.intensity(r, "pga") == np.max(np.abs(r.a))
    assert nvib.analysis.ida.intensity(r, lambda g: 2.0) == 2.0
    for kw, arg in ((dict(im="sa"), "period"), (dict(im="sA", period=1.0), "im"), (dict(im=lambda g: -1.0), "im")):
        with pytest.raises(nvib.ArgumentError) as exc:
            nvib.analysis.ida.intensity(r, **kw)
        assert exc.value.argument == arg
    res = nvib.ida(two_storeys(r), [r], [0.5, 1.0], im="pga", storeys=STOREYS, dt=1e-3, check=False, progress=False)
    np.testing.assert_allclose(res.curves[0].factor * np.max(np.abs(r.a)), [0.5, 1.0], rtol=1e-15)
