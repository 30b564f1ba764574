"""No unknown key, no impossible value is accepted (issue 19, item 3): each was taken without a word before,
and is now refused at the entry point with an error that names the argument (or the scene's key)."""

from __future__ import annotations

import math
from decimal import Decimal

import numpy as np
import pytest

import nvib
from nvib import GroundMotion
from nvib.analysis import spectrum as spectrum_module

from _cli import run_cli
from test_batch import two_storeys


def oscillator():
    return nvib.Model([1.0], effects=[{"type": "spring", "name": "s", "measure": {0: 1.0}, "k": 100.0}], u0=[0.1])


def refused(exc_type, argument, fn, *args, **kwargs):
    with pytest.raises(exc_type) as info:
        fn(*args, **kwargs)
    assert getattr(info.value, "argument", None) == argument, str(info.value)
    return str(info.value)


# ---- a record signal's keys ------------------------------------------------------------------------

SCENE = ('[scene]\nt_end = 0.5\ndt = 0.01\n\n[dofs]\nnames = ["x"]\nmass = [1.0]\n\n'
         '[[effect]]\ntype = "spring"\nmeasure = {{ x = 1.0 }}\nk = 100.0\n\n'
         '[[effect]]\ntype = "ground_acceleration"\nsignal = {{ kind = "record", file = "rec.txt", dt = 0.01, '
         '{key} = 9.80665 }}\n')


def test_a_record_signal_refuses_an_unknown_key_in_a_scene_a_model_and_the_command_line(tmp_path, capsys):
    np.savetxt(tmp_path / "rec.txt", np.sin(0.07 * np.arange(200)))
    (tmp_path / "good.toml").write_text(SCENE.format(key="scale"))
    (tmp_path / "bad.toml").write_text(SCENE.format(key="scael"))
    assert nvib.load_scene(str(tmp_path / "good.toml")) is not None
    with pytest.raises(nvib.SceneError, match=r"bad.toml: effects\[1\].signal.scael: unknown key for a record "
                                              r"signal \(did you mean 'scale'\?\)"):
        nvib.load_scene(str(tmp_path / "bad.toml"))
    spec = {"kind": "record", "file": str(tmp_path / "rec.txt"), "dt": 0.01, "scael": 9.80665}
    message = refused(nvib.ArgumentError, "effects[0].signal.scael", nvib.Model, [1.0],
                      effects=[{"type": "ground_acceleration", "signal": spec}])
    assert "did you mean 'scale'" in message
    code, _, err = run_cli(capsys, "run", tmp_path / "bad.toml")
    assert code == 2 and "scael" in err and "did you mean 'scale'" in err
    # the sine and table signals say the close name too
    message = refused(nvib.ArgumentError, "effects[0].signal.amplitud", nvib.Model, [1.0], effects=[
        {"type": "ground_acceleration", "signal": {"kind": "sine", "amplitud": 1.0, "omega": 2.0}}])
    assert "did you mean 'amplitude'" in message


# ---- solve_many --------------------------------------------------------------------------------------

@pytest.mark.parametrize("threads", [0, -1, 2.5, "4", True])
def test_solve_many_threads_must_be_a_positive_integer(threads):
    refused((ValueError, TypeError), "threads", nvib.solve_many, [oscillator()], nvib.Newmark(), dt=0.01, t_end=0.1,
            threads=threads, progress=False)


@pytest.mark.parametrize("processes", ["no", 0, 1])
def test_solve_many_processes_must_be_a_bool(processes):
    refused(TypeError, "processes", nvib.solve_many, [oscillator()], nvib.Newmark(), dt=0.01, t_end=0.1,
            processes=processes, progress=False)


def test_solve_many_refuses_an_empty_variation_as_it_refuses_empty_scales():
    refused(nvib.ArgumentError, "variations['storey1.k0']", nvib.solve_many, two_storeys(), nvib.CEMDTS(),
            variations={"storey1.k0": []}, dt=1e-3, t_end=0.1, progress=False)
    refused(nvib.ArgumentError, "scales", nvib.solve_many, two_storeys(), nvib.CEMDTS(), scales=[], dt=1e-3,
            t_end=0.1, progress=False)


def test_solve_many_refuses_a_misspelt_solve_keyword_and_bad_settings_once():
    model = oscillator()
    message = refused(TypeError, "save_evry", nvib.solve_many, [model], nvib.Newmark(), dt=0.01, t_end=0.1,
                      save_evry=10, progress=False)
    assert "did you mean 'save_every'" in message
    for kw, arg in ((dict(max_displacement=math.nan), "max_displacement"), (dict(save_every=0), "save_every"),
                    (dict(t0=math.inf), "t0"), (dict(energy="yes"), "energy"), (dict(dt=math.nan), "dt"),
                    (dict(t_end=math.inf), "t_end"), (dict(throw=True), "throw"), (dict(dt=1.0), "dt")):
        kw = {"dt": 0.01, "t_end": 0.1, **kw}
        refused((ValueError, TypeError), arg, nvib.solve_many, [model], nvib.Newmark(), progress=False, **kw)


def _saved_states(monkeypatch):
    """The save_every each run was made with and the states it saved, from the core's solve."""
    seen = []
    core_solve = nvib._core.solve

    def spy(*args):  # (model, scheme, dt, t_end, t0, u0, v0, options, progress)
        res = core_solve(*args)
        seen.append((args[7].get("save_every"), len(res.t)))
        return res

    monkeypatch.setattr(nvib._core, "solve", spy)
    return seen


def test_keep_peaks_honours_save_every_and_its_peaks_are_over_every_step(monkeypatch):
    base = two_storeys()
    run = dict(dt=1e-3, t_end=2.5, threads=1, progress=False, energy=True)
    hist = nvib.solve_many(base, nvib.CEMDTS(), scales=[1.0, 2.0], **run)
    seen = _saved_states(monkeypatch)
    peaks = nvib.solve_many(base, nvib.CEMDTS(), scales=[1.0, 2.0], keep="peaks", save_every=1000, **run)
    assert seen == [(1000, 4), (1000, 4)]  # steps 0, 1000, 2000 and the last: the caller's save_every
    for h, p in zip(hist, peaks):
        np.testing.assert_array_equal(p.peak_u, np.max(np.abs(h.u), axis=0))
        assert p.peak_measures["storey2"] == np.max(np.abs(h.u[:, 1] - h.u[:, 0]))
        assert p.peak_measures["storey1"] == np.max(np.abs(h.u[:, 0]))
        np.testing.assert_array_equal(p.u_final, h.u[-1])
        np.testing.assert_array_equal(p.v_final, h.v[-1])
        assert p.t_final == h.t[-1]
        assert p.energy_error == h.energy.relative_balance_error()  # over every step too
    # without save_every a summary run saves at most MAX_SUMMARY_STATES states, not its whole history
    seen.clear()
    nvib.solve_many(base, nvib.CEMDTS(), keep="peaks", dt=1e-4, t_end=2.5, threads=1, progress=False)
    (every, states), = seen
    assert every == 25 and states == 1001
    refused(nvib.ArgumentError, "dofs", nvib.solve_many, base, nvib.CEMDTS(), keep="peaks", dofs=["x1"], dt=1e-3,
            t_end=0.1, progress=False)


def test_keep_peaks_of_effect_arrays_are_over_every_step():
    chain = nvib.scenes.chain(4)
    hist = nvib.solve_many([chain], nvib.Newmark(), dt=0.01, t_end=3.0, progress=False)[0]
    p = nvib.solve_many([chain], nvib.Newmark(), dt=0.01, t_end=3.0, progress=False, keep="peaks", save_every=50)[0]
    drift = np.diff(np.column_stack([np.zeros(len(hist.u)), hist.u]), axis=1)
    np.testing.assert_array_equal(p.peak_measures["storeys"], np.max(np.abs(drift), axis=0))
    np.testing.assert_array_equal(p.peak_u, np.max(np.abs(hist.u), axis=0))


# ---- spectrum and ida --------------------------------------------------------------------------------

def _record():
    t = np.arange(300) * 0.01
    return GroundMotion.from_array(np.sin(7 * t) * np.exp(-0.5 * t), dt=0.01, name="r")


@pytest.mark.parametrize("halvings, exc", [(-1, ValueError), (1.5, TypeError), ("2", TypeError)])
def test_spectrum_max_halvings_must_be_a_non_negative_integer(halvings, exc):
    refused(exc, "max_halvings", nvib.spectrum, _record(), [0.5], scheme=nvib.Newmark(), max_halvings=halvings)


def test_a_spectrum_whose_error_is_not_finite_misses_its_accuracy(monkeypatch):
    first = nvib.spectrum(_record(), [0.5], scheme=nvib.Newmark(), max_halvings=2)
    monkeypatch.setattr(spectrum_module._core, "elastic_spectrum_at", lambda t, ag, periods, damping, **kw: {
        "Sd": np.full(len(periods), np.nan), "Sa": np.full(len(periods), np.nan)})
    sp = nvib.spectrum(_record(), [0.5], scheme=nvib.Newmark(), max_halvings=2)
    assert np.isnan(sp.error[0])
    # halved as far as allowed, as for any error above the accuracy: two halvings, and dt is the step of the
    # last runs, the ones the error is of
    assert sp.dt[0] == first.dt[0] / 4


def test_ida_checks_its_measure_before_any_run(monkeypatch):
    model = two_storeys()
    # every run of this diverges (the central difference far beyond its stable step)
    refused(nvib.ArgumentError, "measure", nvib.ida, model, [_record()], [1.0, 2.0], im="scale",
            scheme=nvib.CentralDifference(), dt=0.5, tail=20.0, measure="bogus", progress=False)
    message = refused(nvib.ArgumentError, "measure", nvib.ida, model, [_record()], [1.0], im="scale", dt=1e-3,
                      measure="storey3", progress=False)
    assert "storey1" in message
    out = nvib.ida(model, [_record()], [1.0], im="scale", dt=1e-3, measure="storey2", progress=False)
    assert np.isfinite(out.measure).all()


# ---- Rayleigh damping --------------------------------------------------------------------------------

def test_rayleigh_refuses_non_finite_frequencies_negative_coefficients_and_a_second_application():
    base = two_storeys()
    refused(nvib.ArgumentError, "omegas", nvib.rayleigh, base, zeta=0.05, omegas=[10.0, math.inf])
    refused(nvib.ArgumentError, "omegas", nvib.rayleigh_coefficients, 0.05, [math.nan, 10.0])
    refused(nvib.ArgumentError, "alpha", nvib.rayleigh, base, alpha=-0.1)
    refused(nvib.ArgumentError, "beta", nvib.rayleigh, base, alpha=0.1, beta=-1e-3)
    # 0.1 at 1 rad/s and 0.005 at 10 rad/s need beta < 0: every mode above 14.1 rad/s damped negatively
    message = refused(nvib.ArgumentError, "zeta", nvib.rayleigh, base, zeta=[0.1, 0.005], omegas=[1.0, 10.0])
    assert "beta = -0.0010101" in message and "above 14.11 rad/s" in message and "negatively" in message
    message = refused(nvib.ArgumentError, "zeta", nvib.rayleigh_coefficients, [0.01, 0.2], [1.0, 10.0])
    assert "alpha = " in message and "below" in message
    damped = nvib.rayleigh(base, zeta=0.05, omegas=[10.0, 40.0])
    message = refused(nvib.ArgumentError, "model", nvib.rayleigh, damped, zeta=0.05, omegas=[10.0, 40.0])
    assert "already has Rayleigh damping" in message
    # a model derived from a damped one (a batch's variation) keeps its damping and its record of it
    assert damped._rebuilt().rayleigh == damped.rayleigh


# ---- solve's step ------------------------------------------------------------------------------------

def test_a_step_longer_than_the_run_is_refused_naming_dt(capsys, tmp_path):
    model = oscillator()
    message = refused(nvib.ArgumentError, "dt", nvib.solve, model, nvib.Newmark(), dt=1.0, t_end=0.1)
    assert "past t_end" in message
    refused(nvib.ArgumentError, "dt", nvib.solve, model, nvib.Newmark(), dt=0.5, t0=1.0, t_end=1.2)
    # a step that divides the run to round-off is one step, not refused
    assert len(nvib.solve(model, nvib.Newmark(), dt=0.1, t0=0.7, t_end=0.8).t) == 2
    code, _, err = run_cli(capsys, "run", "building", "--dt", "1", "--t-end", "0.1")
    assert code == 2 and "--dt" in err and "past t_end" in err
    refused(nvib.ArgumentError, "dts", nvib.cost, model, [nvib.Newmark()], [0.01, 1.0], t_end=0.1, repeats=1)
    code, _, err = run_cli(capsys, "cost", "pendulum", "--dt", "100", "0.01", "--repeats", "1", "--no-scipy")
    assert code == 2 and "argument --dt: the step 100 is longer than the run" in err


# ---- the arrays' entries -----------------------------------------------------------------------------

def test_arrays_of_objects_must_hold_real_numbers():
    message = refused(TypeError, "mass", nvib.Model, np.array([Decimal(1), "2"], dtype=object))
    assert "Decimal" in message
    refused(TypeError, "mass", nvib.Model, [1.0, "2"])
    refused(TypeError, "u0", nvib.Model, [1.0, 1.0], u0=[0.0, "1"])
    refused(TypeError, "K", nvib.Model, [1.0], K=np.array([[Decimal(2)]], dtype=object))
    refused(TypeError, "v0", nvib.solve, oscillator(), nvib.Newmark(), dt=0.01, t_end=0.1, v0=[True])
    from fractions import Fraction

    assert nvib.Model(np.array([Fraction(1, 2), 1], dtype=object)).mass_matrix[0, 0] == 0.5  # real numbers are fine
