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
