"""``nvib paper``: one run of the full command (within 3 minutes), every figure and table written and
non-trivial, and numbers of its tables recomputed here by independent code (plain NumPy loops of the
schemes' textbook formulas, closed-form energies, SciPy's DOP853 on a hand-written building)."""

import csv
import math
import os
import struct
import subprocess
import sys

import numpy as np
import pytest

import nvib
from nvib import paper

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
FIGURES = [c.key for c in paper.CASES] + ["table1_energy_error", "eta_study"]
TABLES = ("runs.csv", "table1.csv", "cpu_time.csv", "eta_study.csv")
PHASE_SCHEMES = ["LCDM", "LCDM (half-step v)", "CEMDTS(0.45)",
                 "Newmark (incremental)", "Newmark (one_iteration)", "Newmark (newton)",
                 "GαM(0.5,0.5) (incremental)", "GαM(0.5,0.5) (one_iteration)", "GαM(0.5,0.5) (newton)", "PIM"]
HISTORY_SCHEMES = [s for s in PHASE_SCHEMES if s != "LCDM (half-step v)"]
M, K0, A, X0 = 1.0, 100.0, 30.0, 1.5  # the hardening oscillator (section 4.2)


def _env():
    env = dict(os.environ)
    root = os.path.dirname(os.path.dirname(os.path.abspath(nvib.__file__)))
    env["PYTHONPATH"] = os.pathsep.join([root] + ([env["PYTHONPATH"]] if env.get("PYTHONPATH") else []))
    return env


@pytest.fixture(scope="module")
def out(tmp_path_factory):
    """The folder written by one run of `nvib paper` (the full command, its default settings)."""
    folder = tmp_path_factory.mktemp("paper") / "figures"  # not there yet: the command creates it
    proc = subprocess.run([sys.executable, "-m", "nvib", "paper", str(folder)], env=_env(), capture_output=True,
                          text=True, timeout=900)  # a guard against a hang, not a speed test (about 25 s here)
    assert proc.returncode == 0, proc.stderr
    assert "Traceback" not in proc.stderr
    return folder


def _rows(folder, name):
    with open(folder / name, newline="") as fh:
        return list(csv.DictReader(fh))


def _num(x: str) -> float:
    return math.nan if x == "" else float(x)


# ---------------------------------------------------------------- files

def test_every_figure_is_a_real_png(out):
    from matplotlib.image import imread

    for name in FIGURES:
        path = out / f"{name}.png"
        data = path.read_bytes()
        assert data[:8] == PNG_SIGNATURE, name
        width, height = struct.unpack(">II", data[16:24])  # the IHDR chunk
        assert width >= 800 and height >= 450, (name, width, height)
        img = imread(str(path))[:, :, :3]
        ink = np.mean(np.any(img < 0.85, axis=2))  # share of pixels that are not (near) white
        colours = len(np.unique((img[::3, ::3] * 255).astype(np.uint8).reshape(-1, 3), axis=0))
        assert ink > 0.03 and colours > 50, (name, ink, colours)


def test_tables_have_the_expected_rows(out):
    runs = _rows(out, "runs.csv")
    for case in paper.CASES:
        got = [r["scheme"] for r in runs if r["case"] == case.key]
        assert got == (HISTORY_SCHEMES if case.kind == "history" else PHASE_SCHEMES), case.key
    assert len(runs) == sum(len(HISTORY_SCHEMES if c.kind == "history" else PHASE_SCHEMES) for c in paper.CASES)
    assert all(r["status"] == "success" for r in runs)
    for r in runs:  # every run is measured against its reference, and timed
        assert math.isfinite(float(r["max_error"])) and float(r["wall_time"]) > 0
        # and reports its own estimate
        assert float(r["error_estimate"] or "nan") > 0, r["scheme"]  # NaN is written as an empty cell
    # A run more than 10 % off estimates itself above 1 % (it warns), except the formats that do not iterate
    # to equilibrium (incremental, one_iteration), whose drift the phase estimate does not see: known misses
    # of issue 21's item 2, measured on the pendulum of IC1 (Newmark incremental estimated 0.61 %; Newmark
    # one_iteration) and the hardening oscillator (Newmark and GαM incremental)
    missed = [(r["case"], r["scheme"]) for r in runs if float(r["max_error"]) > 0.1
              and not float(r["error_estimate"] or "nan") > 0.01]
    # PIM's estimate propagates its errors with the linear part at rest, so the phase drift of the pendulum's
    # amplitude-dependent period over its long runs escapes it (error_estimate.hpp): known misses too,
    # measured on fig03b (2000 s), fig10 (1800 s) and fig11 (dt 0.8 s)
    pim_drift = {"fig03b_pendulum_ic2_2000s", "fig10_pendulum_ic1_1800s", "fig11_pendulum_ic1_dt0.8"}
    assert all("incremental" in scheme or "one_iteration" in scheme or (scheme == "PIM" and case in pim_drift)
               for case, scheme in missed), missed
    t1 = _rows(out, "table1.csv")
    assert sorted({float(r["dt"]) for r in t1}) == pytest.approx(sorted(paper.cases.TABLE1_DTS))
    for dt in paper.cases.TABLE1_DTS:
        assert [r["scheme"] for r in t1 if math.isclose(float(r["dt"]), dt)] == PHASE_SCHEMES
    cpu = _rows(out, "cpu_time.csv")
    assert [r["label"] for r in cpu] == HISTORY_SCHEMES
    eta = _rows(out, "eta_study.csv")
    assert len(eta) == len(paper.cases.ETA_PROBLEMS) * (len(paper.cases.ETA_GRID) + 2)
    summary = (out / "summary.md").read_text()
    for name in FIGURES:
        assert f"({name}.png)" in summary
    assert "Recommended η" in summary and "Table 1" in summary


def test_cpu_time_table(out):
    cpu = {r["label"]: r for r in _rows(out, "cpu_time.csv")}
    for label, r in cpu.items():
        assert r["status"] == "success" and int(r["num_steps"]) == 100_000, label
        assert float(r["wall_time"]) > 0 and int(r["repeats"]) >= 1  # measured (its size is benchmarks' business)
        if "incremental" not in label:  # at 1e-4 s every iterated or explicit scheme follows the building closely
            assert float(r["max_error"]) < 1e-5, label
    # The incremental format is first order (its linearisation error is never corrected): its error at 1e-4 s
    # is far above the iterated formats' (pin: measured 9.88e-5 for both, 74x Newton's 1.34e-6)
    for family in ("Newmark", "GαM(0.5,0.5)"):
        inc, newton = float(cpu[f"{family} (incremental)"]["max_error"]), float(cpu[f"{family} (newton)"]["max_error"])
        assert 10 * newton < inc < 2e-4, family
    # one force evaluation per step and one at the start for the explicit schemes, two per step for PIM
    # (predictor and corrector), one per Newton iteration plus one per step for the implicit ones
    assert int(cpu["CEMDTS(0.45)"]["force_evals"]) == 100_001
    assert int(cpu["PIM"]["force_evals"]) == 200_001
    assert int(cpu["Newmark (one_iteration)"]["newton_iters"]) == 100_000
    assert float(cpu["PIM"]["paper_2017_s"]) == 11.12 and math.isnan(_num(cpu["LCDM"]["paper_2017_s"]))
    assert float(cpu["CEMDTS(0.45)"]["over_cemdts"]) == 1.0


# ---------------------------------------------------------------- numbers recomputed independently

def _hardening_accel(x):
    return -K0 * (1.0 + A * x * x) * x / M


def _hardening_energy(x, v):
    return 0.5 * M * v * v + K0 * (0.5 * x * x + 0.25 * A * x ** 4)


def _cemdts(accel, u0, v0, h, n, eta):
    """CEMDTS as cpp/include/nvib/schemes/cemdts.hpp states it (eta = 0 is the synchronized leapfrog);
    a_{-1} = a_0."""
    u, v = np.empty(n + 1), np.empty(n + 1)
    u[0], v[0] = u0, v0
    a_prev = a = accel(u0)
    for k in range(n):
        u[k + 1] = u[k] + h * v[k] + h * h * ((0.5 + eta) * a - eta * a_prev)
        a_new = accel(u[k + 1])
        v[k + 1] = v[k] + h * ((0.5 - eta) * a_new + (0.5 + 2 * eta) * a - eta * a_prev)
        a_prev, a = a, a_new
    return u, v


def _half_step_leapfrog(accel, u0, v0, h, n):
    """Textbook leapfrog; the velocity reported at t_n is the carried v_{n-1/2} (v_0 at the start)."""
    u, v = np.empty(n + 1), np.empty(n + 1)
    u[0], v[0] = u0, v0
    w = v0 + 0.5 * h * accel(u0)
    for k in range(n):
        u[k + 1] = u[k] + h * w
        v[k + 1] = w
        w = w + h * accel(u[k + 1])
    return u, v


def _trapezoidal_newton(accel, stiffness, u0, v0, h, n, iterations):
    """Newmark(1/4, 1/2) for u'' = accel(u): Newton from u_n on the residual a(u) - accel(u); iterations=1 is
    the one-iteration format (one Newton iteration on the full residual per step, accepted as is)."""
    u, v = np.empty(n + 1), np.empty(n + 1)
    u[0], v[0] = u0, v0
    a = accel(u0)
    for k in range(n):
        x = u[k]
        for _ in range(iterations):
            a1 = 4.0 / h ** 2 * (x - u[k] - h * v[k]) - a
            r = a1 - accel(x)
            x -= r / (4.0 / h ** 2 + stiffness(x))
        a1 = 4.0 / h ** 2 * (x - u[k] - h * v[k]) - a
        v[k + 1] = v[k] + 0.5 * h * (a + a1)
        u[k + 1], a = x, a1
    return u, v


def _max_rel_energy(energy, u, v):
    e = energy(u, v)
    return float(np.max(np.abs(e - e[0])) / e[0])


def test_table1_energy_errors_recomputed(out):
    t1 = {(r["scheme"], float(r["dt"])): float(r["energy_error"]) for r in _rows(out, "table1.csv")}
    for dt in (1e-3, paper.cases.TABLE1_DTS[3]):
        n = math.ceil(0.3 / dt - 1e-9)
        lcdm = _max_rel_energy(_hardening_energy, *_cemdts(_hardening_accel, X0, 0.0, dt, n, 0.0))
        cem = _max_rel_energy(_hardening_energy, *_cemdts(_hardening_accel, X0, 0.0, dt, n, 0.45))
        half = _max_rel_energy(_hardening_energy, *_half_step_leapfrog(_hardening_accel, X0, 0.0, dt, n))
        newton = _max_rel_energy(_hardening_energy, *_trapezoidal_newton(
            _hardening_accel, lambda x: K0 * (1 + 3 * A * x * x) / M, X0, 0.0, dt, n, iterations=30))
        key = [k for k in t1 if math.isclose(k[1], dt)][0][1]
        assert t1[("LCDM", key)] == pytest.approx(lcdm, rel=1e-9)
        assert t1[("CEMDTS(0.45)", key)] == pytest.approx(cem, rel=1e-9)
        assert t1[("LCDM (half-step v)", key)] == pytest.approx(half, rel=1e-9)
        assert t1[("Newmark (newton)", key)] == pytest.approx(newton, rel=1e-6)
    # the measured value at the paper's step, for the record: CEMDTS(0.45) between the two LCDM variants
    assert t1[("LCDM", 1e-3)] < t1[("CEMDTS(0.45)", 1e-3)] < t1[("LCDM (half-step v)", 1e-3)]


def test_pendulum_numbers_recomputed(out):
    runs = {(r["case"], r["scheme"]): r for r in _rows(out, "runs.csv")}
    th0 = -0.95 * math.pi

    def accel(x):
        return -math.sin(x)

    def energy(x, v):
        return 0.5 * v * v + 1.0 - np.cos(x)

    # the one-iteration Newmark leaves the libration (|theta| > pi) at the same step
    u, _ = _trapezoidal_newton(accel, math.cos, th0, 0.0, 0.3, 50, iterations=1)
    first = 0.3 * int(np.flatnonzero(np.abs(u) > math.pi)[0])
    row = runs[("fig02_pendulum_ic1", "Newmark (one_iteration)")]
    assert float(row["t_over_the_top"]) == pytest.approx(first, abs=1e-9)
    assert float(row["max_abs_u"]) == pytest.approx(float(np.max(np.abs(u))), rel=1e-9)
    # with Newton it stays in the libration
    u, v = _trapezoidal_newton(accel, math.cos, th0, 0.0, 0.3, 50, iterations=30)
    row = runs[("fig02_pendulum_ic1", "Newmark (newton)")]
    assert row["t_over_the_top"] == "" and np.max(np.abs(u)) < math.pi
    assert float(row["energy_error"]) == pytest.approx(_max_rel_energy(energy, u, v), rel=1e-6)
    # the eta study's CEMDTS(1/12) on IC1
    eta = {(r["problem"], r["variant"]): r for r in _rows(out, "eta_study.csv")}
    got = float(eta[("pendulum IC1, Δt = 0.3 s", "CEMDTS(1/12)")]["energy_error"])
    assert got == pytest.approx(_max_rel_energy(energy, *_cemdts(accel, th0, 0.0, 0.3, 50, 1.0 / 12.0)), rel=1e-9)
    # eta = 0 is LCDM, and the eta study agrees with the figure runs
    assert eta[("pendulum IC1, Δt = 0.3 s", "CEMDTS(0)")]["energy_error"] == \
        eta[("pendulum IC1, Δt = 0.3 s", "LCDM")]["energy_error"]
    assert float(eta[("pendulum IC1, Δt = 0.3 s", "CEMDTS(0.45)")]["energy_error"]) == \
        pytest.approx(float(runs[("fig02_pendulum_ic1", "CEMDTS(0.45)")]["energy_error"]), rel=1e-12)


def test_locus_error_recomputed(out):
    """The phase-locus error of LCDM on the hardening oscillator, against the energy level set of the exact
    motion (v as a function of x, brute-force nearest point) instead of the sampled closed form."""
    eta = {(r["problem"], r["variant"]): r for r in _rows(out, "eta_study.csv")}
    got = float(eta[("hardening, Δt = 1e-3 s", "LCDM")]["locus_error"])
    u, v = _cemdts(_hardening_accel, X0, 0.0, 1e-3, 300, 0.0)
    e0 = _hardening_energy(X0, 0.0)
    phi = np.linspace(0.0, 2 * np.pi, 100_001)
    x = X0 * np.cos(phi)  # dense near the turning points, where v(x) is steep
    vx = np.sign(np.sin(phi)) * np.sqrt(np.maximum(2.0 * (e0 - K0 * (0.5 * x * x + 0.25 * A * x ** 4)) / M, 0.0))
    U, V = X0, math.sqrt(2.0 * e0 / M)
    curve = np.column_stack((x / U, vx / V))
    pts = np.column_stack((u / U, v / V))
    best = max(float(np.min(np.hypot(*(curve - p).T))) for p in pts)
    assert got == pytest.approx(best, rel=2e-3)


def test_building_error_recomputed(out):
    """Fig. 7's LCDM error on floor 6 (dt = 0.03 s) against a hand-written building and leapfrog, with
    SciPy's DOP853 as the reference."""
    from scipy.integrate import solve_ivp

    m, k0, a = 1e5, 1e8, 10.0

    def accel(x, t):
        d = np.diff(np.concatenate(([0.0], x)))
        f = k0 * (1.0 + a * d * d) * d  # storey forces on the drifts
        return (-(f - np.append(f[1:], 0.0))) / m - 10.0 * math.sin(math.pi * t)

    h, n = 0.03, math.ceil(10.0 / 0.03 - 1e-9)
    x, v = np.zeros(6), np.zeros(6)
    acc = accel(x, 0.0)
    xs = [x.copy()]
    for k in range(n):
        x = x + h * v + 0.5 * h * h * acc
        acc_new = accel(x, (k + 1) * h)
        v = v + 0.5 * h * (acc + acc_new)
        acc = acc_new
        xs.append(x.copy())
    t = h * np.arange(n + 1)
    sol = solve_ivp(lambda tt, y: np.concatenate((y[6:], accel(y[:6], tt))), (0.0, t[-1]), np.zeros(12),
                    method="DOP853", rtol=1e-11, atol=1e-13, t_eval=t)
    ref6 = sol.y[5]
    # over the whole run (its last step ends at 10.02 s): the reference covers it
    err = np.max(np.abs(np.array(xs)[:, 5] - ref6)) / np.max(np.abs(ref6))
    runs = {(r["case"], r["scheme"]): r for r in _rows(out, "runs.csv")}
    assert float(runs[("fig07_building_floor6", "LCDM")]["max_error"]) == pytest.approx(err, rel=1e-6)


def test_recommended_eta_follows_the_table(out):
    """The recommendation printed in summary.md is the minimax-regret choice over the written table."""
    rows = _rows(out, "eta_study.csv")
    cem = [r for r in rows if r["eta"] != ""]
    best = {}
    for r in cem:
        best[r["problem"]] = min(best.get(r["problem"], math.inf), float(r["energy_error"]))
    worst = {}
    for r in cem:
        e = float(r["eta"])
        worst[e] = max(worst.get(e, 0.0), float(r["energy_error"]) / best[r["problem"]])
    choice = min(worst, key=lambda e: (worst[e], e))
    assert f"**{choice:.4g}**" in (out / "summary.md").read_text()


def test_bad_outdir_is_named(tmp_path):
    target = tmp_path / "a_file"
    target.write_text("")
    proc = subprocess.run([sys.executable, "-m", "nvib", "paper", str(target)], env=_env(), capture_output=True,
                          text=True, timeout=60)
    assert proc.returncode == 2 and "OUTDIR" in proc.stderr and "not a folder" in proc.stderr
