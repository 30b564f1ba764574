"""Incremental dynamic analysis: the table equals the runs' own peaks, fractiles are the records'
percentiles, a collapse is kept as such (not a crash), and the curves plot."""

import numpy as np
import pytest

import nvib

from test_batch import motions, two_storeys


def test_ida_table_fractiles_and_collapse(tmp_path):
    base = two_storeys(motions()[0])
    # the last scale drives the hardening storeys past the central difference's stability limit at this
    # step (their tangent stiffness grows with the drift): a collapse
    scales = [0.5, 1.0, 2.0, 1e6]
    res = nvib.ida(base, motions(), scales, scheme=nvib.CentralDifference(), dt=1e-3, progress=False,
                   measure="peak_drift")
    assert res.records == ["decay", "square"] and res.measure.shape == (2, 4)
    for i, gm in enumerate(motions()):
        for j, s in enumerate(scales[:3]):
            h = nvib.solve(two_storeys(gm.scaled(s)), nvib.CentralDifference(), dt=1e-3, t_end=gm.t[-1])
            drift = max(np.max(np.abs(h.u[:, 0])), np.max(np.abs(h.u[:, 1] - h.u[:, 0])))
            assert res.measure[i, j] == drift
    np.testing.assert_array_equal(res.median[:3], np.percentile(res.measure[:, :3], 50, axis=0))
    np.testing.assert_array_equal(res.p84[:3], np.percentile(res.measure[:, :3], 84, axis=0))
    assert np.all(res.p16 <= res.median) and np.all(res.median <= res.p84)
    assert np.all(np.diff(res.measure[:, :3], axis=1) > 0)  # more shaking, more drift
    # the collapse is kept, with its message
    assert not res.collapsed[:, :3].any() and res.collapsed[:, 3].any()
    for i, j in zip(*np.nonzero(res.collapsed)):
        assert np.isinf(res.measure[i, j]) and "diverged" in res.messages[(i, j)]
    assert np.isinf(res.p84[3])  # the fractile reaches into the collapse
    assert "collapse" in res.markdown()
    png = tmp_path / "ida.png"
    res.plot(png, units="m")
    assert png.stat().st_size > 10_000


def test_ida_measures_and_arguments():
    base = two_storeys(motions()[0])
    res = nvib.ida(base, motions()[:1], [1.0], dt=1e-3, measure="storey2", progress=False)
    h = nvib.solve(base, nvib.CEMDTS(), dt=1e-3, t_end=motions()[0].t[-1])
    assert res.measure[0, 0] == np.max(np.abs(h.u[:, 1] - h.u[:, 0]))
    with pytest.raises(nvib.ArgumentError) as exc:
        nvib.ida(base, motions()[:1], [1.0], dt=1e-3, measure="storey9", progress=False)
    assert exc.value.argument == "measure"
    with pytest.raises(nvib.ArgumentTypeError) as exc:
        nvib.ida(base, [[0.0, 1.0]], [1.0], dt=1e-3)
    assert exc.value.argument == "records[0]"


def test_records_are_scaled_to_each_level_of_sa_t1():
    """im='sa': each record is scaled so that its exact Sa(T1) equals the level (Vamvatsikos & Cornell 2002)."""
    records = motions()
    levels = [0.5, 1.0, 2.0]
    res = nvib.ida(two_storeys(records[0]), records, levels, im="sa", period=0.5, dt=1e-3, progress=False)
    assert res.im_name == "Sa(T1 = 0.5 s, 5 %)" and res.factors.shape == (2, 3)
    for i, r in enumerate(records):
        for j, level in enumerate(levels):
            sa = nvib._core.elastic_spectrum(r.a * res.factors[i, j], r.dt, [0.5], 0.05)["PSa"][0]
            assert sa == pytest.approx(level, rel=1e-12)
    assert "Sa(T1 = 0.5 s, 5 %)" in res.markdown().splitlines()[0]


def test_a_linear_models_ida_curve_is_a_straight_line_through_the_origin():
    """Drift of a linear model is proportional to the record's scale, so to Sa(T1): drift / Sa is the same
    at every level of a record (a straight line through the origin), to round-off."""
    records = motions()
    levels = [0.1, 0.4, 1.6, 6.4]
    res = nvib.ida(two_storeys(records[0], a=0.0), records, levels, im="sa", period=0.3,
                   scheme=nvib.Newmark(), dt=2e-3, progress=False)
    slope = res.measure / np.asarray(levels)[None, :]
    np.testing.assert_allclose(slope, slope[:, :1] * np.ones_like(slope), rtol=1e-9)
    assert not np.allclose(slope[0, 0], slope[1, 0], rtol=1e-3)  # each record its own line


def test_intensity_measures_and_their_arguments():
    r = motions()[0]
    assert nvib.analysis.ida.intensity(r, "pga") == np.max(np.abs(r.a))
    assert nvib.analysis.ida.intensity(r, lambda g: 2.0) == 2.0
    for kw, arg in ((dict(im="sa"), "period"), (dict(im="sA", period=1.0), "im"), (dict(im=lambda g: -1.0), "im")):
        with pytest.raises(nvib.ArgumentError) as exc:
            nvib.analysis.ida.intensity(r, **kw)
        assert exc.value.argument == arg
    res = nvib.ida(two_storeys(r), [r], [0.5, 1.0], im="pga", dt=1e-3, progress=False)
    np.testing.assert_allclose(res.factors[0] * np.max(np.abs(r.a)), [0.5, 1.0], rtol=1e-15)
