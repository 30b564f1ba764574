"""The run figure of a building on shaking ground: the ground acceleration under the response (the record's
samples over the run, in g, its peak marked), the peak drift ratio of each storey over the height, the loop of
the critical storey, the collapse time; and figures of models without storeys or ground motion left as
they were."""

from __future__ import annotations

import os

import numpy as np
import pytest

import nvib
from nvib import GroundMotion

pytest.importorskip("matplotlib")
from nvib.plot import ground_series, run_figure  # noqa: E402

SGM1 = os.path.join(os.path.dirname(nvib.__file__), "scenes", "records", "sgm1.AT2")
STOREYS = [f"storey{k}" for k in range(1, 7)]


def _axes(fig, *, title: str = "", xlabel: str = "", ylabel: str = ""):
    """The one axes whose title, x label and y label start with the given texts."""
    found = [ax for ax in fig.axes if ax.get_title().startswith(title) and ax.get_xlabel().startswith(xlabel)
             and ax.get_ylabel().startswith(ylabel)]
    assert len(found) == 1, [(ax.get_title(), ax.get_xlabel(), ax.get_ylabel()) for ax in fig.axes]
    return found[0]


def _drifts(res) -> np.ndarray:
    """The six storey drifts of a building run, (saved states, 6), from its displacements alone."""
    u = np.asarray(res.u)
    return np.diff(np.hstack([np.zeros((len(u), 1)), u]), axis=1)


@pytest.fixture(scope="module")
def inelastic():
    model = nvib.load_scene("building_inelastic")
    return model, nvib.solve(model, nvib.CEMDTS(), dt=0.002, t_end=4.0, record=STOREYS)


def test_ground_panel_draws_the_record_in_g_over_the_run(inelastic):
    """The scene's record (SGM-1, an AT2 file in g that the scene scales to m/s^2 for the run) is drawn in g:
    the file's samples from t = 0 to the end of the run, its peak marked, m/s^2 on the right-hand axis, on the
    time axis of the response."""
    model, res = inelastic
    fig = run_figure(res, model, "x1")
    ax = _axes(fig, ylabel="a_g")
    assert ax.get_ylabel() == "a_g [g]" and ax.get_xlabel() == "t [s]"
    assert [c.get_ylabel() for c in ax.child_axes] == ["a_g [m/s^2]"]
    record = GroundMotion.from_at2(SGM1)
    assert record.units == "g"
    inside = record.t <= res.t[-1] * (1 + 1e-12)
    line = ax.lines[0]
    np.testing.assert_array_equal(line.get_xdata(), record.t[inside])
    np.testing.assert_allclose(line.get_ydata(), record.a[inside], rtol=1e-14, atol=0)
    assert line.get_xdata()[0] == 0.0 and line.get_xdata()[-1] == pytest.approx(res.t[-1], abs=1e-12)
    k = int(np.argmax(np.abs(record.a[inside])))
    marker = ax.lines[1]
    assert marker.get_xdata()[0] == record.t[k] and marker.get_ydata()[0] == pytest.approx(record.a[k], rel=1e-14)
    peak = abs(record.a[k])
    assert f"peak in the run {peak:#.3g} g at t = {record.t[k]:.4g} s" in ax.get_title()
    assert f"the record's PGA: {record.pga:#.3g} g" in ax.get_title()  # the record's peak comes after t = 4 s
    response = _axes(fig, title="Displacement of x1")
    assert ax.get_shared_x_axes().joined(ax, response)

    ax = _axes(run_figure(res, model, "x1", ground_units="m/s^2"), ylabel="a_g")
    assert ax.get_ylabel() == "a_g [m/s^2]" and [c.get_ylabel() for c in ax.child_axes] == ["a_g [g]"]
    run_record = nvib.load_scene("building_inelastic")._init[1]["effects"][-1]["signal"]  # what the run applied
    assert run_record.units == "m/s^2"
    np.testing.assert_array_equal(ax.lines[0].get_ydata(), run_record.a[inside])
    with pytest.raises(ValueError, match="ground_units") as info:
        run_figure(res, model, "x1", ground_units="cm/s^2")
    assert info.value.argument == "ground_units"


def test_ground_series_is_what_the_run_applies():
    """Samples inside the span, the interpolated values at its ends, 0 before and after the record (as the
    solver sees a record); a sine on an even grid."""
    gm = GroundMotion.from_array([1.0, -2.0, 3.0, 0.5], dt=0.1, t0=0.2)
    t, a = ground_series(gm, 0.0, 1.0)
    np.testing.assert_allclose(t, [0.0, 0.2, 0.2, 0.3, 0.4, 0.5, 0.5, 1.0])
    np.testing.assert_array_equal(a, [0.0, 0.0, 1.0, -2.0, 3.0, 0.5, 0.0, 0.0])
    t, a = ground_series(gm, 0.25, 0.45)
    np.testing.assert_allclose(t, [0.25, 0.3, 0.4, 0.45])
    np.testing.assert_allclose(a, [-0.5, -2.0, 3.0, 1.75])
    np.testing.assert_allclose(a, gm(t))
    t, a = ground_series({"kind": "sine", "amplitude": 2.0, "omega": 3.0}, 0.0, 10.0)
    assert t[0] == 0.0 and t[-1] == 10.0 and np.all(np.diff(t) <= 2 * np.pi / 3.0 / 40)
    np.testing.assert_allclose(a, 2.0 * np.sin(3.0 * t))


def test_drift_envelope_is_the_peak_drift_over_the_height(inelastic):
    """The profile holds max |drift| / 3.5 m of each storey (in %) from its floor to its ceiling, computed here
    from the displacements alone; the largest is marked and named."""
    model, res = inelastic
    fig = run_figure(res, model, "x1")
    ax = _axes(fig, xlabel="peak |drift| / storey height [%]")
    assert ax.get_ylabel() == "height above the ground [m]"
    want = 100.0 * np.max(np.abs(_drifts(res)), axis=0) / 3.5
    profile = ax.lines[0]
    np.testing.assert_allclose(profile.get_xdata()[::2], want, rtol=1e-13)
    np.testing.assert_allclose(profile.get_xdata()[1::2], want, rtol=1e-13)
    np.testing.assert_allclose(profile.get_ydata(), np.repeat(3.5 * np.arange(7), 2)[1:-1])
    np.testing.assert_allclose(ax.get_yticks(), 3.5 * np.arange(7))
    critical = STOREYS[int(np.argmax(want))]
    assert [t.get_text() for t in ax.texts if t.get_text().startswith(critical + ":")] == \
        [f"{critical}: {want.max():.3g} %"]
    assert [t.get_text() for t in ax.child_axes[0].get_yticklabels()] == STOREYS


def test_hysteresis_panel_is_the_storey_with_the_largest_drift_ratio(inelastic):
    """With storey1 declared 14 m high its drift ratio is no longer the largest: the loop drawn is that of the
    storey whose drift ratio is, its recorded force [kN] against its drift ratio [%]."""
    model, res = inelastic
    heights = dict.fromkeys(STOREYS, 3.5) | {"storey1": 14.0}
    ratio = np.max(np.abs(_drifts(res)), axis=0) / np.array(list(heights.values()))
    k = int(np.argmax(ratio))
    critical = STOREYS[k]
    assert critical != "storey1"
    fig = run_figure(res, model, "x1", storeys=heights)
    ax = _axes(fig, title=f"Critical storey {critical} (bilinear)")
    assert ax.get_title().endswith(f"peak drift ratio {100 * ratio[k]:.3g} %")
    assert ax.get_xlabel() == f"drift ratio of {critical} (drift / 3.5 m) [%]"
    assert ax.get_ylabel() == f"force of {critical} [kN]"
    assert [c.get_xlabel() for c in ax.child_axes] == ["drift [m]"]
    rec = res.effects[critical]
    np.testing.assert_allclose(ax.lines[0].get_xdata(), 100 * _drifts(res)[:, k] / 3.5, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(ax.lines[0].get_xdata(), 100 * np.asarray(rec.measure) / 3.5, rtol=1e-12)
    np.testing.assert_array_equal(ax.lines[0].get_ydata(), np.asarray(rec.force) / 1e3)
    envelope = _axes(fig, xlabel="peak |drift| / storey height [%]")
    np.testing.assert_allclose(envelope.lines[0].get_ydata()[:3], [0.0, 14.0, 14.0])


def test_an_unrecorded_critical_storey_is_said_to_be_so():
    model = nvib.load_scene("building_inelastic")
    res = nvib.solve(model, nvib.CEMDTS(), dt=0.002, t_end=3.0, record=["storey4"])
    fig = run_figure(res, model, "x1")
    ax = _axes(fig, title="Critical storey storey1")
    assert not ax.lines and "storey1 was not recorded" in ax.texts[0].get_text()
    assert "--record-effect storey1" in ax.texts[0].get_text()


def test_collapse_is_shown_where_and_when():
    """building_collapse loses its first storey at t = 10.242 s: the time panels mark it, the drift profile
    says the peaks end there and draws the law's ultimate drift (uu / h), the loop ends at the collapse."""
    model = nvib.load_scene("building_collapse")
    res = nvib.solve(model, nvib.CEMDTS(), dt=0.002, t_end=11.0, record=STOREYS, throw=False)
    assert res.status == nvib.Status.collapsed and res.failure.t == pytest.approx(10.242)
    fig = run_figure(res, model, "x1")
    assert "collapsed at t = 10.242 s (step 5121): storey1 (imk_peak_oriented) lost its strength" in \
        fig.get_suptitle()
    for ax in (_axes(fig, title="Displacement of x1"), _axes(fig, ylabel="a_g"), _axes(fig, title="Other DOFs")):
        assert any(list(line.get_xdata()) == [10.242, 10.242] for line in ax.lines)
    assert any(t.get_text() == "collapse, t = 10.242 s" for t in _axes(fig, ylabel="a_g").texts)
    envelope = _axes(fig, xlabel="peak |drift| / storey height [%]")
    assert "up to the collapse at t = 10.242 s" in envelope.get_title()
    limit = next(line for line in envelope.lines if line.get_label() == "ultimate deformation of the law (uu)")
    np.testing.assert_allclose(limit.get_xdata(), 100 * 0.25 / 3.5)
    assert any(t.get_text().startswith("storey1: ") and t.get_text().endswith("% (failed)") for t in envelope.texts)
    loop = _axes(fig, title="Critical storey storey1 (imk_peak_oriented)")
    assert loop.get_legend().get_texts()[-1].get_text() == "t = 10.242 s (collapse)"
    limited = run_figure(res, model, "x1", collapse_deformation=0.2)
    envelope = _axes(limited, xlabel="peak |drift| / storey height [%]")
    assert [line.get_label() for line in envelope.lines if not line.get_label().startswith("_")] == [
        "peak |drift ratio|", "collapse deformation 0.2 m", "ultimate deformation of the law (uu)"]


def test_storeys_whose_dofs_were_not_saved_are_named():
    model = nvib.load_scene("building")
    res = nvib.solve(model, nvib.CEMDTS(), dt=7e-4, t_end=0.5, dofs=["x1", "x6"])
    fig = run_figure(res, model, "x6")
    ax = _axes(fig, title="Peak drift ratio over the height")
    assert "the drift of 'storey2' needs 'x2', which this result did not save" in ax.texts[0].get_text()
    assert not [a for a in fig.axes if a.get_title().startswith("Critical storey")]


def test_a_python_model_with_storeys_and_a_record():
    """A Model built in Python: storeys given to the figure, a record in m/s^2 drawn in g; a record whose
    unit differs from the one the run takes its values in is said to."""
    gm = GroundMotion.from_array(np.sin(np.arange(400) * 0.05), dt=0.005, units="m/s^2", name="pulse")
    model = nvib.Model([1e3, 1e3], dofs=["x1", "x2"], units="m", effects=[
        {"type": "bilinear", "name": "s1", "measure": {"x1": 1.0}, "k": 4e5, "fy": 500.0, "b": 0.05},
        {"type": "bilinear", "name": "s2", "measure": {"x2": 1.0, "x1": -1.0}, "k": 3e5, "fy": 300.0, "b": 0.05},
        {"type": "ground_acceleration", "name": "ground", "signal": gm}])
    res = nvib.solve(model, nvib.Newmark(), dt=1e-3, t_end=2.5, record=["s1", "s2"])
    fig = run_figure(res, model, "x2", storeys={"s1": 3.0, "s2": 2.5})
    ax = _axes(fig, ylabel="a_g")
    assert ax.get_title().startswith("Ground acceleration: pulse\nPGA ")
    ts, ys = ax.lines[0].get_xdata(), ax.lines[0].get_ydata()
    during = np.arange(len(gm))  # the record's samples, then its end (1.995 s), where a_g drops to 0 until 2.5 s
    np.testing.assert_array_equal(ts[during], gm.t)
    np.testing.assert_allclose(ys[during], gm.a / nvib.STANDARD_GRAVITY, rtol=1e-14)
    np.testing.assert_allclose(ts[len(gm):], [gm.t[-1], 2.5])
    np.testing.assert_array_equal(ys[len(gm):], [0.0, 0.0])
    peaks = np.max(np.abs(np.diff(np.hstack([np.zeros((len(res.t), 1)), res.u]), axis=1)), axis=0) / [3.0, 2.5]
    envelope = _axes(fig, xlabel="peak |drift| / storey height [%]")
    np.testing.assert_allclose(envelope.lines[0].get_xdata()[::2], 100 * peaks, rtol=1e-13)
    _axes(fig, title=f"Critical storey s{int(np.argmax(peaks)) + 1} (bilinear)")

    in_g = nvib.Model([1e3], dofs=["x"], units="m", effects=[
        {"type": "spring", "name": "s", "measure": {"x": 1.0}, "k": 4e5},
        {"type": "ground_acceleration", "name": "ground", "signal": gm.scaled(1 / nvib.STANDARD_GRAVITY)}])
    res = nvib.solve(in_g, nvib.Newmark(), dt=1e-3, t_end=1.0)
    title = _axes(run_figure(res, in_g, "x"), ylabel="a_g").get_title()
    assert "the record says g; the run took its values as m/s^2" in title


@pytest.mark.parametrize("scene, dof", [("pendulum", "theta"), ("vehicle", "z_w1"), ("hardening", None)])
def test_scenes_without_storeys_or_ground_keep_their_figure(scene, dof):
    """No ground panel, no drift profile, no secondary axes: the response, the other DOFs, the phase locus and
    the energy, as before."""
    model = nvib.load_scene(scene)
    res = nvib.solve(model, nvib.CEMDTS(), dt=1e-3, t_end=0.5, energy=True)
    fig = run_figure(res, model, dof or model.scene["plot_dof"])
    titles = [ax.get_title() for ax in fig.axes]
    assert not any(t.startswith(("Ground", "Peak drift", "Critical")) for t in titles)
    assert not any(ax.child_axes for ax in fig.axes)
    assert titles[-2].startswith("Phase locus") and titles[-1].startswith("Energy")
    assert len(fig.axes) == 3 + (model.n > 1)
    assert tuple(fig.get_size_inches()) == (5.6 * 3, 4.8)


@pytest.fixture
def figures(monkeypatch):
    """The (result, keyword arguments, figure) of each run figure nvib run draws in this test."""
    import nvib.plot

    drawn, real = [], nvib.plot.run_figure

    def spy(result, model, dof, title=None, **kwargs):
        fig = real(result, model, dof, title, **kwargs)
        drawn.append((result, kwargs, fig))
        return fig

    monkeypatch.setattr(nvib.plot, "run_figure", spy)
    return drawn


def test_nvib_run_records_every_storey_for_its_figure(capsys, tmp_path, figures):
    """--plot records all six storeys (the scene asks for storey1 alone) so that the loop drawn is the critical
    storey's, whichever it is; the summary lists what was asked for, as without --plot."""
    from _cli import run_cli

    code, out, err = run_cli(capsys, "run", "building_inelastic", "--t-end", "3", "--plot", tmp_path / "b.png")
    assert code == 0, err
    res, kwargs, fig = figures[-1]
    assert sorted(res.effects) == STOREYS
    assert [ln.split()[0] for ln in out.splitlines() if ln.startswith("storey")] == ["storey1"]
    critical = STOREYS[int(np.argmax(np.max(np.abs(_drifts(res)), axis=0)))]
    assert _axes(fig, title=f"Critical storey {critical} (bilinear)").lines
    code, out, err = run_cli(capsys, "run", "building_inelastic", "--t-end", "1", "--out", tmp_path / "b.npz")
    assert code == 0 and list(nvib.load_result(tmp_path / "b.npz").effects) == ["storey1"]


def test_nvib_run_leaves_the_storeys_unrecorded_past_its_memory_budget(capsys, tmp_path, figures, monkeypatch):
    from _cli import run_cli
    from nvib.cli import run

    monkeypatch.setattr(run, "STOREY_RECORD_BYTES", 1e3)
    code, out, err = run_cli(capsys, "run", "building_inelastic", "--t-end", "3", "--record-effect", "storey6",
                             "--plot", tmp_path / "b.png")
    assert code == 0, err
    assert "note: --plot does not record the storeys (0.36 MB for 1501 saved states)" in err
    res, _, fig = figures[-1]
    assert list(res.effects) == ["storey6"]
    assert "storey1 was not recorded" in _axes(fig, title="Critical storey storey1").texts[0].get_text()


def test_nvib_run_under_a_record_scaled_to_sa_draws_that_record(capsys, tmp_path, figures):
    """--record FILE --sa T1 VALUE: the ground panel draws the record as scaled, in g (the file's unit), and the
    title names it in place of the scene's own."""
    from _cli import run_cli
    from test_records import northridge_like

    path = northridge_like(tmp_path)
    code, out, err = run_cli(capsys, "run", "building_inelastic", "--record", path, "--sa", "0.9", "0.5", "--t-end",
                             "2", "--plot", tmp_path / "sa.png")
    assert code == 0, err
    scaled, factor = GroundMotion.from_at2(path).scaled_to_sa(0.9, 0.5)
    res, kwargs, fig = figures[-1]
    assert kwargs["ground_units"] == "g"
    assert fig.get_suptitle().startswith(f"building_inelastic under RSN1086_NORTHR_SYL360.AT2 x {factor:.4g}: "
                                         "Sa(T1 = 0.9 s, 5 %) = 0.5 g\n")
    ax = _axes(fig, ylabel="a_g [g]")
    inside = scaled.t <= 2.0 + 1e-9
    np.testing.assert_allclose(ax.lines[0].get_xdata(), scaled.t[inside])
    np.testing.assert_allclose(ax.lines[0].get_ydata(), scaled.a[inside], rtol=1e-13)
    assert f"PGA {scaled.pga:#.3g} g" in ax.get_title()


def test_drift_ratios_read_the_saved_columns():
    """A result that saved x2 before x1 (and nothing else) still gives storey1 = x1 / h, storey2 = (x2 - x1) / h."""
    from nvib._storeys import drift_ratio_histories, peak_drift_ratios

    model = nvib.load_scene("building")
    res = nvib.solve(model, nvib.CEMDTS(), dt=7e-4, t_end=0.3, dofs=["x2", "x1"])
    heights = {"storey1": 3.5, "storey2": 2.0}
    ratios = drift_ratio_histories(model, res, heights)
    np.testing.assert_array_equal(ratios["storey1"], res.u[:, 1] / 3.5)
    np.testing.assert_allclose(ratios["storey2"], (res.u[:, 0] - res.u[:, 1]) / 2.0, rtol=1e-14, atol=1e-18)
    assert peak_drift_ratios(model, res, heights) == {k: float(np.max(np.abs(v))) for k, v in ratios.items()}
