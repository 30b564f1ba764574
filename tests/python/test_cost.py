"""Accuracy against cost: the rows of cost() and cost_scipy(), how a failed run is reported, how the
error and energy error are measured, the helpers, the plot and `nvib cost`. No timing is asserted."""

import math
import os

import numpy as np
import pytest

import nvib

from _cli import run_cli
from nvib import exact
from nvib.analysis.cost import FIELDS

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


@pytest.fixture(scope="module")
def hardening():
    return nvib.load_scene("hardening")


@pytest.fixture(scope="module")
def rows(hardening):
    out = nvib.cost(hardening, [nvib.CEMDTS(), nvib.Newmark(), nvib.PreciseIntegration()], [1e-3, 5e-4],
                    repeats=2)
    return out + nvib.cost_scipy(hardening, ["DOP853", "Radau"], [1e-6, 1e-9], repeats=2)


def test_every_row_has_every_field(rows):
    assert len(rows) == 3 * 2 + 2 * 2
    for r in rows:
        assert tuple(r) == FIELDS
        # plain scalars, as pandas.DataFrame(rows) wants them
        assert all(isinstance(v, (str, int, float)) for v in r.values()), r
        assert r["status"] == "success" and r["message"] == ""
        assert 0 < r["max_error"] < 1e-2
        assert 0 < r["energy_error"] < 1e-1
        assert r["wall_time"] > 0 and 1 <= r["repeats"] <= 2
        assert r["force_evals"] > 0
        assert r["t_end"] == 0.3 and r["dofs"] == "x"
        assert r["reference"].startswith("closed form")
    nv = [r for r in rows if r["contender"] == "nvib"]
    assert {r["label"] for r in nv} == {"CEMDTS(0.45)", "Newmark (newton)", "PIM"}
    for r in nv:
        assert r["num_steps"] == round(0.3 / r["dt"]) and math.isnan(r["rtol"])
        assert r["newton_iters"] >= 0 and r["factorizations"] >= 0
    newmark = [r for r in nv if r["label"] == "Newmark (newton)"]
    assert all(r["newton_iters"] > r["num_steps"] and r["factorizations"] > 0 for r in newmark)
    sp = [r for r in rows if r["contender"] == "scipy"]
    for r in sp:
        assert math.isnan(r["dt"]) and r["rtol"] in (1e-6, 1e-9)
        assert math.isnan(r["newton_iters"])  # SciPy does not report them
    radau = [r for r in sp if r["scheme"] == "Radau"]
    assert all(r["factorizations"] > 0 and r["tangent_evals"] > 0 for r in radau)


def test_error_and_energy_error_are_measured_as_documented(hardening, rows):
    row = next(r for r in rows if r["label"] == "CEMDTS(0.45)" and r["dt"] == 1e-3)
    res = nvib.solve(hardening, nvib.CEMDTS(), dt=1e-3, t_end=0.3, energy=True)
    x, _ = exact.hardening(res.t, x0=1.5)
    assert row["max_error"] == pytest.approx(np.max(np.abs(res.u[:, 0] - x)) / np.max(np.abs(x)), rel=1e-12)
    assert row["energy_error"] == pytest.approx(res.energy.relative_balance_error(), rel=1e-12)
    # the timed runs leave the energy accounting out: the states are the same
    plain = nvib.solve(hardening, nvib.CEMDTS(), dt=1e-3, t_end=0.3)
    assert np.array_equal(plain.u, res.u)
    # SciPy: the error at its own steps; the energy drift for a conservative model
    dop = next(r for r in rows if r["scheme"] == "DOP853" and r["rtol"] == 1e-9)
    assert dop["max_error"] < 1e-7 and dop["energy_error"] < 1e-7 and dop["num_steps"] > 10


def test_smaller_steps_and_tighter_tolerances_are_more_accurate(rows):
    for label in ("CEMDTS(0.45)", "Newmark (newton)", "PIM", "SciPy DOP853", "SciPy Radau"):
        errs = [r["max_error"] for r in rows if r["label"] == label]
        assert errs[1] < errs[0], label


def test_a_diverged_run_is_a_row_marked_diverged_not_a_tiny_error(hardening):
    rows = nvib.cost(hardening, [nvib.CEMDTS(), nvib.PreciseIntegration()], [0.04, 1e-3], repeats=1)
    bad = [r for r in rows if r["dt"] == 0.04]
    assert len(bad) == 2
    for r in bad:
        assert r["status"] == "diverged"
        assert r["max_error"] == math.inf and r["energy_error"] == math.inf
        assert "diverged at t =" in r["message"]
        assert r["num_steps"] < round(0.3 / 0.04) and r["repeats"] == 1
    assert all(r["status"] == "success" for r in rows if r["dt"] == 1e-3)
    # left out of "cheapest", counted in the plot's legend
    assert nvib.cheapest(rows, 1.0)["dt"] == 1e-3


def test_a_newton_failure_is_reported_too():
    model = nvib.load_scene("hardening")
    rows = nvib.cost(model, [nvib.Newmark(newton=nvib.Newton(max_iter=1))], [1e-3], repeats=1)
    (r,) = rows
    assert r["status"] == "newton_failed" and r["max_error"] == math.inf


def test_energy_error_is_nan_where_the_model_does_not_account_for_energy():
    model = nvib.Model([1.0], force=lambda u, v, t: 100.0 * (1 + 30.0 * u ** 2) * u, u0=[1.5],
                       uses_velocity=False, uses_time=False)
    (r,) = nvib.cost(model, [nvib.CEMDTS()], [1e-3], t_end=0.1, repeats=1)
    assert r["status"] == "success" and math.isnan(r["energy_error"]) and r["max_error"] < 1e-2
    (s,) = nvib.cost_scipy(model, ["RK45"], [1e-6], t_end=0.1, repeats=1)
    assert math.isnan(s["energy_error"]) and s["max_error"] < 1e-4


def test_chosen_dofs_and_a_given_reference():
    model = nvib.load_scene("building")
    ref = nvib.reference(model, 0.5)
    rows = nvib.cost(model, [nvib.CEMDTS()], [1e-3], t_end=0.5, dofs=["x6"], reference=ref, repeats=1)
    res = nvib.solve(model, nvib.CEMDTS(), dt=1e-3, t_end=0.5, dofs=["x6"])
    u_ref = ref.u(res.t, dofs=["x6"])
    assert rows[0]["dofs"] == "x6"
    assert rows[0]["max_error"] == pytest.approx(np.max(np.abs(res.u - u_ref)) / np.max(np.abs(u_ref)), rel=1e-12)
    with pytest.raises(ValueError, match="reference: covers"):
        nvib.cost(model, [nvib.CEMDTS()], [1e-3], t_end=1.0, reference=ref)
    # SciPy on the same model from the same state; the energy is not conserved under a load: NaN
    (s,) = nvib.cost_scipy(model, ["DOP853"], [1e-8], t_end=0.5, dofs=["x6"], reference=ref, n_eval=500)
    assert s["status"] == "success" and s["max_error"] < 1e-6 and math.isnan(s["energy_error"])
    assert math.isnan(s["num_steps"])  # output at given times: no step count


def test_slow_scipy_tolerances_are_skipped_rows(hardening):
    rows = nvib.cost_scipy(hardening, ["RK45"], [1e-4, 1e-6, 1e-8], repeats=1, max_time=1e-9)
    assert [r["status"] for r in rows] == ["success", "skipped", "skipped"]
    assert all(math.isnan(r["max_error"]) for r in rows[1:])
    assert "max_time" in rows[1]["message"]


def test_a_tolerance_below_solve_ivps_floor_is_refused(hardening):
    """solve_ivp raises an rtol below 100 machine epsilons to that floor with a warning: 1e-300 ran as
    2.2e-14 for as long as that took (minutes with RK23)."""
    with pytest.raises(nvib.ArgumentError) as exc:
        nvib.cost_scipy(hardening, ["RK23"], [1e-6, 1e-300], repeats=1)
    assert exc.value.argument == "rtols" and "got 1e-300" in str(exc.value)


def test_cheapest_and_time_at_error():
    def row(who, label, dt, err, wall, status="success"):
        return {"contender": who, "label": label, "dt": dt, "rtol": dt, "max_error": err, "wall_time": wall,
                "status": status}

    rows = [row("nvib", "A", 1e-2, 1e-2, 1.0), row("nvib", "A", 1e-3, 1e-4, 10.0),
            row("nvib", "A", 1e-4, 1e-6, 100.0), row("nvib", "B", 1e-2, 0.0 + math.inf, 0.1, "diverged"),
            row("scipy", "S", 1e-6, 1e-5, 30.0)]
    assert nvib.cheapest(rows, 1e-4)["wall_time"] == 10.0
    assert nvib.cheapest(rows, 1e-5, contender="scipy")["label"] == "S"
    assert nvib.cheapest(rows, 1e-9) is None
    at = nvib.time_at_error(rows, 1e-3)
    assert at[("nvib", "A")] == pytest.approx(math.sqrt(10.0))  # half-way in log between 1 s and 10 s
    assert math.isnan(at[("nvib", "B")])


def test_table_and_plot(rows, tmp_path):
    text = nvib.markdown_table(rows)
    assert text.count("\n") == len(rows) + 1
    assert "| nvib | PIM | 0.001 |" in text
    path = tmp_path / "wp.png"
    nvib.plot_work_precision(rows, str(path), title="hardening", target=1e-5)
    assert path.read_bytes()[:8] == PNG_SIGNATURE


def test_cost_bad_input_names_the_argument(hardening):
    with pytest.raises(ValueError, match="schemes"):
        nvib.cost(hardening, [], [1e-3])
    with pytest.raises(TypeError, match="schemes"):
        nvib.cost(hardening, ["cemdts"], [1e-3])
    with pytest.raises(ValueError, match="dts"):
        nvib.cost(hardening, [nvib.CEMDTS()], [-1e-3])
    with pytest.raises(ValueError, match="dofs"):
        nvib.cost(hardening, [nvib.CEMDTS()], [1e-3], dofs=["y"])
    with pytest.raises(ValueError, match="repeats"):
        nvib.cost(hardening, [nvib.CEMDTS()], [1e-3], repeats=0)
    with pytest.raises(TypeError, match="model"):
        nvib.cost("hardening", [nvib.CEMDTS()], [1e-3])
    with pytest.raises(ValueError, match="t_end"):
        nvib.cost(nvib.Model([1.0], effects=[{"type": "spring", "measure": {"u0": 1.0}, "k": 1.0}]),
                  [nvib.CEMDTS()], [1e-3])
    with pytest.raises(ValueError, match="methods"):
        nvib.cost_scipy(hardening, ["Euler"], [1e-6])
    with pytest.raises(TypeError, match="reference"):
        nvib.cost(hardening, [nvib.CEMDTS()], [1e-3], reference="exact")




def test_cli_cost_writes_the_diagram_and_the_table(capsys, tmp_path):
    png, md = tmp_path / "h.png", tmp_path / "h.md"
    code, out, _ = run_cli(capsys, "cost", "hardening", "--schemes", "cemdts", "newmark:one_iteration", "--dt", "1e-3",
                           "5e-4", "--scipy", "DOP853", "--rtol", "1e-6", "--repeats", "1", "--target", "1e-3",
                           "--plot", png, "--table", md)
    assert code == 0
    assert png.read_bytes()[:8] == PNG_SIGNATURE
    text = md.read_text()
    assert "reference: closed form" in text and "Cheapest run with error <= 0.001" in text
    assert "| nvib | Newmark (one_iteration) | 0.0005 |" in text and "| scipy | SciPy DOP853 |" in text
    assert f"wrote {md}" in out and f"wrote {png}" in out


def test_cli_cost_defaults_and_bad_input(capsys, tmp_path):
    cwd = os.getcwd()
    os.chdir(tmp_path)
    try:
        code, out, _ = run_cli(capsys, "cost", "pendulum_ic2", "--no-scipy", "--schemes", "lcdm", "--repeats", "1")
        assert code == 0
        assert (tmp_path / "cost_pendulum_ic2.png").is_file() and (tmp_path / "cost_pendulum_ic2.md").is_file()
        assert out.count("| nvib | LCDM |") == 8  # the scene's dt x 4 ... / 32
    finally:
        os.chdir(cwd)
    code, _, err = run_cli(capsys, "cost", "hardening", "--schemes", "rk4")
    assert code == 2 and "--schemes" in err
    code, _, err = run_cli(capsys, "cost", "hardening", "--schemes", "cemdts:newton")
    assert code == 2 and "only the implicit schemes take a Newton mode" in err
    code, _, err = run_cli(capsys, "cost", "hardening", "--schemes", "newmark:none")
    assert code == 2 and "--schemes" in err
    code, _, err = run_cli(capsys, "cost", "hardening", "--dof", "y")
    assert code == 2 and "--dof" in err
    code, _, err = run_cli(capsys, "cost", "hardening", "--plot", str(tmp_path / "x.txt"))
    assert code == 2 and "--plot" in err


def test_work_precision_diagram_stars_the_cheapest_run_at_the_target(rows):
    from nvib.analysis.cost import work_precision_figure

    ok = [r for r in rows if r["status"] == "success"]
    target = 1.5 * max(min(r["max_error"] for r in ok if r["contender"] == who) for who in ("nvib", "scipy"))
    ax = work_precision_figure(rows, target=target).axes[0]
    stars = [ln for ln in ax.lines if ln.get_marker() == "*"]
    best = {who: nvib.cheapest(rows, target, contender=who) for who in ("nvib", "scipy")}
    expected = {(b["wall_time"], b["max_error"]) for b in best.values() if b is not None}
    assert {(ln.get_xdata()[0], ln.get_ydata()[0]) for ln in stars} == expected and expected
    labels = [t.get_text() for t in ax.texts]
    assert any(best["nvib"]["label"] in t and f"dt = {best['nvib']['dt']:g} s" in t for t in labels)
    # without a target nothing is starred
    assert not [ln for ln in work_precision_figure(rows).axes[0].lines if ln.get_marker() == "*"]


def test_adaptive_runs_are_a_curve_of_their_own(hardening):
    """tols= adds one row per (scheme that takes a tol, tol), labelled '<scheme>, tol', its error within
    3 tol on the measured DOF (the tol holds on every DOF); PIM, without a local control, has none."""
    rows = nvib.cost(hardening, [nvib.Newmark(), nvib.PreciseIntegration()], [1e-3], tols=[1e-3, 1e-4], repeats=1)
    adaptive = [r for r in rows if not math.isnan(r["tol"])]
    assert [(r["label"], r["tol"]) for r in adaptive] == [("Newmark (newton), tol", 1e-3), ("Newmark (newton), tol", 1e-4)]
    for r in adaptive:
        assert r["status"] == "success" and r["max_error"] <= 3.0 * r["tol"] and r["dt"] == 1e-3
    assert adaptive[1]["num_steps"] > adaptive[0]["num_steps"]
    assert all(math.isnan(r["tol"]) for r in rows if r["label"].startswith("PIM"))
    with pytest.raises(nvib.ArgumentError, match="tols"):
        nvib.cost(hardening, [nvib.Newmark()], [1e-3], tols=[2.0])
