"""nvib and OpenSees side by side on the building scene: same model, same schemes, same steps.

The laws with memory (ElasticPP, Steel01, BoucWen, IMK peak-oriented on a zeroLength SDOF and on
the six-storey building) are compared in benchmarks/opensees_hysteresis.py; ``--hysteresis`` here
runs that comparison with the arguments that follow it.

The model. nvib.load_scene("building") (python/nvib/scenes/building.toml): six
floors of 1e5 kg on one axis, storey i a hardening spring between floors i-1
and i (floor 0 the ground) with f = k0 d + k0 a d^3 on the drift d
(k0 = 1e8 N/m, a = 10 1/m^2), ground acceleration a_g(t) = 10 sin(pi t) m/s^2,
displacements relative to the ground, no damping, starting at rest. In
OpenSeesPy (``model('basic', '-ndm', 1, '-ndf', 1)``): nodes 0..6, node 0
fixed, ``mass(i, 1e5)``, storey i a ``zeroLength`` element between nodes i-1
and i in direction 1 with

    uniaxialMaterial('ElasticPowerFunc', 1, '-coeff', k0, k0*a, '-exp', 1.0, 3.0)

(ElasticPowerFunc takes sign(d) |d|^e, which for e = 3 is d^3), and the
ground motion ``timeSeries('Trig', 1, 0, t_end + 2, 2.0, '-factor', 10.0)``
(period 2 s) in ``pattern('UniformExcitation', 1, 1, '-accel', 1)``, whose
effective load is -M r a_g as in nvib. `check_inputs` verifies the material's
force and tangent against the formula and the series with a free mass (its
relative acceleration must be -a_g(t)).

Pitfalls of OpenSees 3.7.1 (openseespy 3.7.1.2) met on the way:
  * the end time of the Trig series must stay near t_end: with a very large
    one (e.g. 1e9) ``analyze`` hangs;
  * ``integrator('Newmark', gamma, beta)`` takes gamma FIRST: Newmark 0.5 0.25
    is the trapezoidal rule (gamma = 1/2, beta = 1/4);
  * ``integrator('HHT', alpha)`` weights the NEW level by alpha,
    x_{n+alpha} = (1 - alpha) x_n + alpha x_{n+1}, with gamma = 3/2 - alpha and
    beta = (2 - alpha)^2 / 4; nvib's alpha_f weights the OLD level, so HHT 0.9
    is nvib GeneralizedAlpha(alpha_m=0, alpha_f=0.1, beta=0.3025, gamma=0.6);
  * ``integrator('GeneralizedAlpha', alphaM, alphaF)`` does not converge for
    alphaM != 1: GeneralizedAlpha::update() gives the domain a_{n+1} instead of
    a_{n+alphaM} while the tangent carries alphaM c3 M, so for alphaM = 1/2
    each Newton step overshoots by 2 and the unbalance stays at
    M a_g(dt/2) = 157 N (at dt = 1e-4) forever; its 4-argument form also
    passes "gamma beta" to a constructor that takes "beta gamma". The
    consistent implementation of the same method is ``integrator(
    'HHTGeneralized', alphaI, alphaF, beta, gamma)``, again with the alphas on
    the new level: HHTGeneralized 0.5 0.5 0.25 0.5 is nvib GeneralizedAlpha()
    (the paper's GaM, alpha_m = alpha_f = 1/2, the implicit midpoint rule),
    1/2 being 1/2 on either level. Scheme "galpha-ops" keeps the failing
    integrator for the OpenSees-only mode, to show the failure;
  * ``integrator('CentralDifference')`` needs ``algorithm('Linear')`` (a
    second update() in a step is an error), solves
    M (u_{n+1} - 2 u_n + u_{n-1}) / dt^2 = P(t_n) - F(u_n), and starts from
    u_{-1} = u_0 (it prints "assuming Ut-1 = Ut" to stderr). This building
    starts at rest with a_g(0) = 0, so a_0 = 0 and that start is exact: the
    displacements are those of nvib.CentralDifference() up to round-off.
    Its reported velocity is a backward difference, (3 u_{n+1} - 4 u_n +
    u_{n-1}) / (2 dt), not nvib's; only displacements are compared.

Schemes compared (SCHEMES):
  newmark  Newmark 0.5 0.25, Newton            nvib.Newmark()                  (full Newton)
  hht      HHT 0.9, Newton                     nvib.GeneralizedAlpha(alpha_m=0, alpha_f=0.1,
                                               beta=0.3025, gamma=0.6)          (full Newton)
  galpha   HHTGeneralized 0.5 0.5 0.25 0.5,    nvib.GeneralizedAlpha()          (full Newton)
           Newton
  cd       CentralDifference,                  nvib.CentralDifference()
           Linear -factorOnce
Common OpenSees settings: ``system('BandGeneral')`` (banded LAPACK dgbsv),
``numberer('Plain')``, ``constraints('Plain')``, ``analysis('Transient')``.
They are OpenSees' fastest here within a few per cent, measured on this
building (dt = 1e-4, 2 s): for Newmark BandSPD and ProfileSPD are 2-4 %
faster than BandGeneral (inside the noise), FullGeneral 10 % slower, SparseSYM
40 %, UmfPack 70 %; for central difference ``-factorOnce`` (its matrix M/dt^2
is constant) saves 20 % over factoring every step, and ``system('Diagonal')``
saves about 5 % more but rounds differently (x6 at 2 s 3e-11 m off nvib's,
against 1e-12 m with BandGeneral), so BandGeneral is kept.
The implicit ones use ``algorithm('Newton')`` (tangent every iteration) and by
default ``test('NormDispIncr', 1e-12, 50, 0, 2)`` (2-norm of the displacement
increment <= 1e-12 m; --test unbalance gives ``test('NormUnbalance', 1e-6, 50,
0, 0)``, the max-norm of the unbalanced force <= 1e-6 N). nvib's test is its
default: max-norm residual <= 1e-10 x (the step's largest inertia/force term,
about 2.5e5 N here) + 1e-12.

Steps. nsteps = floor(t_end / dt) steps of dt exactly, both programs ending at
nsteps dt (9.9995 s at dt = 7e-4, 9.99 s at dt = 0.03, 10 s at dt = 1e-4).

What is measured, per scheme and dt, in one process:
  * OpenSees: the wall time (time.perf_counter) of one ``analyze(nsteps, dt)``
    call, model building excluded (wipe and rebuild before each run);
  * nvib: the wall time of ``nvib.solve(model, scheme, dt=dt, t_end=nsteps*dt,
    save_every=nsteps)``, the whole Python call (neither side records a
    history in the timed runs);
  * best of --repeats runs each, the two programs alternating run by run so
    that a slow spell of the machine hits both; ratio = OpenSees / nvib;
  * agreement, in untimed runs: OpenSees once more with ``analyze(1, dt)`` per
    step, recording nodeDisp(6) (x6, floor 6) and testIter() (the Newton
    iterations of the step; OpenSees exposes only the last step's), which must
    end in the same state as the one-call run; nvib with save_every=1. Reported:
    max over the run of |x6_nvib - x6_OpenSees| in m, and relative to
    max |x6| over the run.
Divergence. nvib stops at the first step whose state is non-finite or beyond
its displacement bound (1e10 m) and raises nvib.DivergenceError naming the time
and step; the table gives that. OpenSees has no such check: its run goes on
with non-finite numbers or fails, and the table gives what analyze() returned,
the final x6 and the first step of the per-step run at which a floor's |u|
passed 1e10 m or stopped being finite (nvib's test on u). OpenSees 3.7.1 does
so silently: analyze() returns 0 and prints nothing.
Central difference's limit on this run lies between dt = 0.031 and 0.0315 s
(the small-amplitude limit 2/omega_max = 0.0326 s, lowered by the hardening
storeys): dt = 0.03 completes in both programs, so the default steps add
dt = 0.035, beyond it, and an untimed scan (--cd-scan) brackets the limit.

    python benchmarks/opensees.py [--dts 7e-4 1e-4 0.03 0.035] [--t-end 10] [--repeats 3]
                                  [--schemes newmark,hht,galpha,cd] [--test dispincr|unbalance]
                                  [--variant-dts 7e-4 1e-4] [--cd-scan 0.03 0.031 0.0315 0.032 0.0325]
                                  [--out benchmarks/results/opensees.md] [--no-report] [--json]

--variant-dts: the implicit schemes again with OpenSees' other test
(NormUnbalance 1e-6 N when the main one is NormDispIncr), a second table.

writes benchmarks/results/opensees.md (and prints it); --json prints one JSON
object per row instead of writing the report. The OpenSees part alone:

    python benchmarks/opensees.py --opensees-only --json [--dt 1e-4] [--t-end 10] [--repeats 3]
           [--schemes newmark,galpha,hht] [--test dispincr] [--history] [--check] [--no-iterations]

prints one JSON object per scheme (steps, best wall time, Newton iterations,
final u/v/a of the six floors, with --history the x6 of every step), the input
for tests/python/test_opensees.py; benchmarks/opensees_building.py is the same
mode with the NormUnbalance test by default (used by benchmarks/implicit.py).

Environment. OpenSeesPy's extension (openseespylinux/opensees.so) loads only
when LD_LIBRARY_PATH, read at process start, contains the folder ``lib``
beside the package ``openseespylinux``; `opensees_env()` returns os.environ
with it prepended (None if openseespy is not installed). Run as a script, this
file re-executes itself once with that environment when the import fails for
want of it; without openseespy it exits with code 3 and a one-line message.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import math
import os
import platform
import shlex
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))

N_FLOORS = 6
MASS = 1e5  # kg per floor
K0 = 1e8  # N/m
A = 10.0  # 1/m^2
AG_AMPLITUDE = 10.0  # m/s^2
AG_PERIOD = 2.0  # s: a_g = 10 sin(2 pi t / 2) = 10 sin(pi t)
U_BOUND = 1e10  # m: nvib's default displacement bound, used to date OpenSees' blow-up

MAX_ITER = 50
SYSTEM = "BandGeneral"
MATERIAL = "ElasticPowerFunc -coeff k0 k0*a -exp 1 3"
TESTS = {
    "dispincr": ("NormDispIncr", 1e-12, MAX_ITER, 0, 2),
    "unbalance": ("NormUnbalance", 1e-6, MAX_ITER, 0, 0),
}
TEST_NOTES = {
    "dispincr": "NormDispIncr 1e-12 50 0 2 (2-norm of the displacement increment, m)",
    "unbalance": "NormUnbalance 1e-06 50 0 0 (max-norm of the unbalanced force, N)",
}

# key: (label, OpenSees integrator arguments, OpenSees algorithm arguments, nvib constructor text)
SCHEMES = {
    "newmark": ("Newmark", ("Newmark", 0.5, 0.25), ("Newton",), "nvib.Newmark()"),
    "hht": ("HHT", ("HHT", 0.9), ("Newton",),
            "nvib.GeneralizedAlpha(alpha_m=0.0, alpha_f=0.1, beta=0.3025, gamma=0.6)"),
    "galpha": ("GαM", ("HHTGeneralized", 0.5, 0.5, 0.25, 0.5), ("Newton",), "nvib.GeneralizedAlpha()"),
    "cd": ("central difference", ("CentralDifference",), ("Linear", "-factorOnce"), "nvib.CentralDifference()"),
    # OpenSees' own GeneralizedAlpha: does not converge here (see the module docstring); OpenSees-only mode
    "galpha-ops": ("GαM (OpenSees GeneralizedAlpha)", ("GeneralizedAlpha", 0.5, 0.5), ("Newton",),
                   "nvib.GeneralizedAlpha() (fails in OpenSees 3.7.1)"),
}
COMPARED = ("newmark", "hht", "galpha", "cd")
DEFAULT_DTS = (7e-4, 1e-4, 0.03, 0.035)

_REEXEC_MARK = "NVIB_OPENSEES_REEXEC"


def nvib_scheme(key: str):
    import nvib

    return {
        "newmark": lambda: nvib.Newmark(),
        "hht": lambda: nvib.GeneralizedAlpha(alpha_m=0.0, alpha_f=0.1, beta=0.3025, gamma=0.6),
        "galpha": lambda: nvib.GeneralizedAlpha(),
        "cd": lambda: nvib.CentralDifference(),
    }[key]()


def is_implicit(key: str) -> bool:
    return SCHEMES[key][2][0] == "Newton"


def steps_for(dt: float, t_end: float) -> int:
    """Whole steps of dt within t_end (at least one)."""
    return max(1, int(math.floor(t_end / dt + 1e-9)))


# ---- OpenSees --------------------------------------------------------------------------
def opensees_lib_dir() -> str | None:
    """The folder ``lib`` beside the package openseespylinux, without importing it; None if absent."""
    try:
        spec = importlib.util.find_spec("openseespylinux")
    except (ImportError, ValueError):
        return None
    if spec is None or spec.origin is None:
        return None
    return os.path.join(os.path.dirname(spec.origin), "lib")


def opensees_env() -> dict | None:
    """os.environ with openseespylinux's lib folder first on LD_LIBRARY_PATH; None if not installed."""
    lib = opensees_lib_dir()
    if lib is None:
        return None
    env = dict(os.environ)
    parts = [p for p in env.get("LD_LIBRARY_PATH", "").split(os.pathsep) if p]
    if lib not in parts:
        env["LD_LIBRARY_PATH"] = os.pathsep.join([lib] + parts)
    return env


def _ops():
    import openseespy.opensees as ops  # raises RuntimeError when the .so cannot load

    return ops


def opensees_version() -> str:
    ops = _ops()
    try:
        from importlib.metadata import version

        pkg = version("openseespy")
    except Exception:
        pkg = "?"
    return f"OpenSees {ops.version()} (openseespy {pkg})"


def build(ops, scheme: str, t_end: float, test: str = "dispincr", system: str = SYSTEM) -> None:
    """Wipe OpenSees and build the building with `scheme`'s integrator, ready to analyze()."""
    ops.wipe()
    ops.model("basic", "-ndm", 1, "-ndf", 1)
    ops.node(0, 0.0)
    ops.fix(0, 1)
    for i in range(1, N_FLOORS + 1):
        ops.node(i, 0.0)
        ops.mass(i, MASS)
    ops.uniaxialMaterial("ElasticPowerFunc", 1, "-coeff", K0, K0 * A, "-exp", 1.0, 3.0)
    for i in range(1, N_FLOORS + 1):
        ops.element("zeroLength", i, i - 1, i, "-mat", 1, "-dir", 1)
    ops.timeSeries("Trig", 1, 0.0, t_end + AG_PERIOD, AG_PERIOD, "-factor", AG_AMPLITUDE)
    ops.pattern("UniformExcitation", 1, 1, "-accel", 1)
    ops.system(system)
    ops.numberer("Plain")
    ops.constraints("Plain")
    _, integrator, algorithm, _ = SCHEMES[scheme]
    if algorithm[0] == "Newton":
        ops.test(*TESTS[test])
    ops.algorithm(*algorithm)
    ops.integrator(*integrator)
    ops.analysis("Transient")


def _state(ops):
    nodes = range(1, N_FLOORS + 1)
    return (
        [ops.nodeDisp(i, 1) for i in nodes],
        [ops.nodeVel(i, 1) for i in nodes],
        [ops.nodeAccel(i, 1) for i in nodes],
    )


def check_inputs() -> dict:
    """Verify the material against f = k0 (1 + a d^2) d and the series against a_g = 10 sin(pi t)."""
    ops = _ops()
    ops.wipe()
    ops.model("basic", "-ndm", 1, "-ndf", 1)
    ops.uniaxialMaterial("ElasticPowerFunc", 1, "-coeff", K0, K0 * A, "-exp", 1.0, 3.0)
    ops.testUniaxialMaterial(1)
    f_err = k_err = 0.0
    for d in (-0.07, -0.03, -1e-3, 0.0, 1e-4, 0.02, 0.05, 0.1):
        ops.setStrain(d)
        f, k = ops.getStress(), ops.getTangent()
        f_ref, k_ref = K0 * (1.0 + A * d * d) * d, K0 * (1.0 + 3.0 * A * d * d)
        f_err = max(f_err, abs(f - f_ref) / max(abs(f_ref), 1.0))
        k_err = max(k_err, abs(k - k_ref) / k_ref)
    # a free mass (spring of stiffness 0) under the same excitation: relative acceleration = -a_g(t)
    ops.wipe()
    ops.model("basic", "-ndm", 1, "-ndf", 1)
    ops.node(0, 0.0)
    ops.fix(0, 1)
    ops.node(1, 0.0)
    ops.mass(1, MASS)
    ops.uniaxialMaterial("Elastic", 1, 0.0)
    ops.element("zeroLength", 1, 0, 1, "-mat", 1, "-dir", 1)
    ops.timeSeries("Trig", 1, 0.0, 10.0 + AG_PERIOD, AG_PERIOD, "-factor", AG_AMPLITUDE)
    ops.pattern("UniformExcitation", 1, 1, "-accel", 1)
    ops.system("FullGeneral")
    ops.numberer("Plain")
    ops.constraints("Plain")
    ops.test("NormUnbalance", 1e-6, 10, 0, 0)
    ops.algorithm("Newton")
    ops.integrator("Newmark", 0.5, 0.25)
    ops.analysis("Transient")
    ag_err = 0.0
    for t in (0.1, 0.25, 0.5, 1.0, 1.3, 1.5, 3.7, 9.9):
        if ops.analyze(1, t - ops.getTime()) != 0:
            raise RuntimeError("free-mass check failed to converge")
        ag_err = max(ag_err, abs(-ops.nodeAccel(1, 1) - AG_AMPLITUDE * math.sin(math.pi * t)))
    ops.wipe()
    return {"material_force_rel_err": f_err, "material_tangent_rel_err": k_err, "a_g_abs_err": ag_err}


def time_opensees_once(scheme: str, dt: float, nsteps: int, test: str, system: str = SYSTEM) -> dict:
    """One timed analyze(nsteps, dt) call on a freshly built model: wall time, return code, final state."""
    ops = _ops()
    build(ops, scheme, nsteps * dt, test, system)
    t0 = time.perf_counter()
    code = ops.analyze(nsteps, dt)
    wall = time.perf_counter() - t0
    u, v, a = _state(ops)
    out = {"wall_time": wall, "code": code, "t_final": ops.getTime(), "u": u, "v": v, "a": a}
    ops.wipe()
    return out


def opensees_per_step(scheme: str, dt: float, nsteps: int, test: str, system: str = SYSTEM,
                      history: bool = True) -> dict:
    """Untimed: analyze(1, dt) per step; x6 of every step, testIter() summed, where it failed or blew up
    (the first step with a floor displacement beyond U_BOUND or not finite, nvib's test on u)."""
    ops = _ops()
    build(ops, scheme, nsteps * dt, test, system)
    iters = 0
    top = [0.0] if history else None
    code, failed_step, blowup_step = 0, None, None
    implicit = is_implicit(scheme)
    for k in range(1, nsteps + 1):
        code = ops.analyze(1, dt)
        if code != 0:
            failed_step = k
            break
        if implicit:
            iters += ops.testIter()
        if history:
            top.append(ops.nodeDisp(N_FLOORS, 1))
        if blowup_step is None and not all(abs(ops.nodeDisp(i, 1)) <= U_BOUND  # also catches NaN
                                           for i in range(1, N_FLOORS + 1)):
            blowup_step = k
    u = _state(ops)[0]
    steps_done = nsteps if failed_step is None else failed_step - 1
    out = {"iterations": iters if implicit else None,
           "iterations_per_step": iters / max(1, steps_done) if implicit else None,
           "code": code, "failed_step": failed_step, "blowup_step": blowup_step,
           "t_final": ops.getTime(), "u": u}
    if history:
        out["x6"] = top
    ops.wipe()
    return out


def run(dt: float = 1e-4, t_end: float = 10.0, scheme: str = "newmark", test: str = "dispincr",
        repeats: int = 3, system: str = SYSTEM, count_iterations: bool = True, history: bool = False) -> dict:
    """OpenSees alone: the best wall time of analyze(nsteps, dt) over `repeats`, final state, iterations."""
    if scheme not in SCHEMES:
        raise ValueError(f"scheme must be one of {sorted(SCHEMES)}, got {scheme!r}")
    if test not in TESTS:
        raise ValueError(f"test must be one of {sorted(TESTS)}, got {test!r}")
    nsteps = steps_for(dt, t_end)
    best, final = float("inf"), None
    for _ in range(max(1, repeats)):
        r = time_opensees_once(scheme, dt, nsteps, test, system)
        if r["code"] != 0:
            raise RuntimeError(f"OpenSees analyze() failed (code {r['code']}) at t = {r['t_final']}")
        best = min(best, r["wall_time"])
        final = r
    out = {
        "scheme": scheme,
        "nvib_equivalent": SCHEMES[scheme][3],
        "integrator": " ".join(str(x) for x in SCHEMES[scheme][1]),
        "dt": dt,
        "t_end": nsteps * dt,
        "t_final": final["t_final"],
        "steps": nsteps,
        "repeats": max(1, repeats),
        "wall_time": best,
        "wall_time_per_step": best / nsteps,
        "iterations": None,
        "iterations_per_step": None,
        "u": final["u"],
        "v": final["v"],
        "a": final["a"],
        "opensees": opensees_version(),
        "material": MATERIAL,
        "test": TEST_NOTES[test] if is_implicit(scheme) else "none (Linear)",
        "algorithm": " ".join(SCHEMES[scheme][2]),
        "system": system,
    }
    if count_iterations or history:
        loop = opensees_per_step(scheme, dt, nsteps, test, system, history)
        if loop["failed_step"] is not None:
            raise RuntimeError(f"OpenSees analyze(1, dt) failed at step {loop['failed_step']}")
        out["iterations"] = loop["iterations"]
        out["iterations_per_step"] = loop["iterations_per_step"]
        out["loop_vs_one_call_max_du"] = max(abs(x - y) for x, y in zip(loop["u"], final["u"]))
        if history:
            out["x6"] = loop["x6"]
    return out


# ---- side by side ----------------------------------------------------------------------
def _nvib_solve(model, key: str, dt: float, nsteps: int, save_every: int):
    """(result or None, error or None, wall time) of one nvib.solve call."""
    import nvib

    scheme = nvib_scheme(key)
    t0 = time.perf_counter()
    try:
        res = nvib.solve(model, scheme, dt=dt, t_end=nsteps * dt, save_every=save_every)
        err = None
    except nvib.NvibError as exc:
        res, err = None, exc
    return res, err, time.perf_counter() - t0


def compare(model, key: str, dt: float, t_end: float, repeats: int, test: str) -> dict:
    """OpenSees and nvib on one scheme and dt: best times (alternating runs), iterations, x6 agreement."""
    import numpy as np

    nsteps = steps_for(dt, t_end)
    ops_best = nvib_best = float("inf")
    ops_run = nvib_err = None
    for _ in range(max(1, repeats)):
        r = time_opensees_once(key, dt, nsteps, test)
        ops_best = min(ops_best, r["wall_time"])
        ops_run = r
        res, err, wall = _nvib_solve(model, key, dt, nsteps, save_every=nsteps)
        nvib_best = min(nvib_best, wall)
        nvib_err = err
        if err is None and res.stats.num_steps != nsteps:
            raise RuntimeError(f"nvib made {res.stats.num_steps} steps, expected {nsteps}")
    loop = opensees_per_step(key, dt, nsteps, test)
    hist, hist_err, _ = _nvib_solve(model, key, dt, nsteps, save_every=1)
    row = {
        "scheme": key, "label": SCHEMES[key][0], "dt": dt, "steps": nsteps, "t_run": nsteps * dt,
        "opensees_integrator": " ".join(str(x) for x in SCHEMES[key][1]),
        "opensees_algorithm": " ".join(SCHEMES[key][2]),
        "opensees_test": TEST_NOTES[test] if is_implicit(key) else "none (Linear)",
        "nvib_scheme": SCHEMES[key][3], "repeats": max(1, repeats),
        "opensees_wall": ops_best, "nvib_wall": nvib_best,
        "opensees_ns_per_step": ops_best / nsteps * 1e9, "nvib_ns_per_step": nvib_best / nsteps * 1e9,
        "ratio": ops_best / nvib_best,
        "opensees_code": ops_run["code"], "opensees_t_final": ops_run["t_final"],
        "opensees_x6_final": ops_run["u"][-1],
        "opensees_finite": all(math.isfinite(x) for x in ops_run["u"]),
        "opensees_failed_step": loop["failed_step"], "opensees_blowup_step": loop["blowup_step"],
        "opensees_iters_per_step": loop["iterations_per_step"],
        "loop_vs_one_call_max_du": (max(abs(x - y) for x, y in zip(loop["u"], ops_run["u"]))
                                    if loop["failed_step"] is None else None),
        "nvib_error": None if nvib_err is None else f"{type(nvib_err).__name__}: {nvib_err}",
        "nvib_error_t": getattr(nvib_err, "t", None), "nvib_error_step": getattr(nvib_err, "step", None),
        "nvib_iters_per_step": None, "max_dx6": None, "max_x6": None, "rel_dx6": None,
    }
    if hist_err is None and (nvib_err is not None):
        raise RuntimeError("nvib's timed and history runs disagree on success")
    if hist is not None:
        x6_nvib = np.asarray(hist.u)[:, N_FLOORS - 1]
        if is_implicit(key):
            row["nvib_iters_per_step"] = hist.stats.num_newton_iters / hist.stats.num_steps
        x6_ops = np.asarray(loop["x6"])
        if len(x6_ops) == len(x6_nvib) and np.all(np.isfinite(x6_ops)):
            row["max_dx6"] = float(np.max(np.abs(x6_nvib - x6_ops)))
            row["max_x6"] = float(np.max(np.abs(x6_nvib)))
            row["rel_dx6"] = row["max_dx6"] / row["max_x6"]
    return row


def linear_dt_crit() -> float:
    """2 / omega_max of the building linearised at rest (k0 storeys): central difference's small-amplitude limit."""
    import numpy as np

    k = np.zeros((N_FLOORS, N_FLOORS))
    for i in range(N_FLOORS):  # storey i + 1 joins floor i (and floor i - 1, or the ground)
        k[i, i] += K0
        if i > 0:
            k[i - 1, i - 1] += K0
            k[i - 1, i] -= K0
            k[i, i - 1] -= K0
    return 2.0 / math.sqrt(float(np.max(np.linalg.eigvalsh(k / MASS))))


def cd_scan(model, dts, t_end: float) -> list[dict]:
    """Central difference near its limit, both programs, untimed: where each stops or blows up."""
    out = []
    for dt in dts:
        nsteps = steps_for(dt, t_end)
        _, err, _ = _nvib_solve(model, "cd", dt, nsteps, save_every=nsteps)
        loop = opensees_per_step("cd", dt, nsteps, "dispincr", history=False)
        out.append({"dt": dt, "steps": nsteps,
                    "nvib": "completed" if err is None else f"DivergenceError at t = {err.t:.4g} s (step {err.step})",
                    "opensees_blowup_step": loop["blowup_step"], "opensees_code": loop["code"],
                    "opensees_x6_final": loop["u"][-1]})
    return out


# ---- report ----------------------------------------------------------------------------
def _fmt_dt(dt: float) -> str:
    return f"{dt:g}"


def _outcome(r: dict) -> str:
    """What each program did when a run did not end normally (empty when both did)."""
    parts = []
    if r["nvib_error"] is not None:
        parts.append(f"nvib: {r['nvib_error'].split(':', 1)[0]} at t = {r['nvib_error_t']:.4g} s "
                     f"(step {r['nvib_error_step']})")
    ops_bad = r["opensees_code"] != 0 or not r["opensees_finite"] or r["opensees_blowup_step"] is not None
    if ops_bad:
        s = f"OpenSees: analyze() returned {r['opensees_code']}, final x6 = {r['opensees_x6_final']:.3g} m"
        if r["opensees_blowup_step"] is not None:
            k = r["opensees_blowup_step"]
            s += f"; a floor's \\|u\\| > 1e10 m or not finite first at step {k} (t = {k * r['dt']:.4g} s)"
        if r["opensees_failed_step"] is not None:
            s += f"; the per-step run failed at step {r['opensees_failed_step']}"
        parts.append(s)
    return "; ".join(parts)


def scheme_table(keys) -> list[str]:
    lines = ["| scheme | OpenSees integrator | OpenSees algorithm | nvib |", "|---|---|---|---|"]
    for k in keys:
        label, integrator, algorithm, nv = SCHEMES[k]
        lines.append(f"| {label} | `{' '.join(str(x) for x in integrator)}` | `{' '.join(algorithm)}` | `{nv}` |")
    return lines


def table(rows: list[dict]) -> list[str]:
    lines = [
        "| scheme | dt [s] | steps | OpenSees analyze() [ms] | nvib solve() [ms] | OpenSees [ns/step] "
        "| nvib [ns/step] | ratio OpenSees / nvib | Newton it./step OpenSees | nvib "
        "| max \\|Δx6\\| [m] | relative to max \\|x6\\| | outcome |",
        "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|",
    ]
    for r in rows:
        it_o = "–" if r["opensees_iters_per_step"] is None else f"{r['opensees_iters_per_step']:.3f}"
        it_n = "–" if r["nvib_iters_per_step"] is None else f"{r['nvib_iters_per_step']:.3f}"
        ok = r["nvib_error"] is None and r["opensees_code"] == 0 and r["opensees_finite"]
        ratio = f"**{r['ratio']:.1f}**" if ok else "–"
        dx = "–" if r["max_dx6"] is None else f"{r['max_dx6']:.1e}"
        rel = "–" if r["rel_dx6"] is None else f"{r['rel_dx6']:.1e}"
        nv_step = f"{r['nvib_ns_per_step']:,.0f}" if r["nvib_error"] is None else "–"
        lines.append(
            f"| {r['label']} | {_fmt_dt(r['dt'])} | {r['steps']:,} | {r['opensees_wall'] * 1e3:.1f} "
            f"| {r['nvib_wall'] * 1e3:.2f} | {r['opensees_ns_per_step']:,.0f} | {nv_step} "
            f"| {ratio} | {it_o} | {it_n} | {dx} | {rel} | {_outcome(r) or 'both completed'} |")
    return lines


def report(rows: list[dict], variant: list[dict], args, load: tuple, checks: dict | None,
           scan: list[dict] | None = None) -> list[str]:
    import numpy as np

    import nvib
    from building import cpu_name, git_revision

    cmd = shlex.join(["python", "benchmarks/opensees.py"] + sys.argv[1:])
    ends = sorted({(r["dt"], r["t_run"]) for r in rows if abs(r["t_run"] - args.t_end) > 1e-9 * args.t_end})
    short = (", so the runs end at " + ", ".join(f"{t:.6g} s for dt = {_fmt_dt(dt)}" for dt, t in ends)) if ends else ""
    test = args.test
    lines = [
        "# nvib and OpenSees side by side on the building scene",
        "",
        f"- date: {time.strftime('%Y-%m-%d %H:%M %Z')}",
        f"- CPU: {cpu_name()}, {os.cpu_count()} logical CPUs; {platform.system()} {platform.release()}; "
        f"1-minute load average {load[0]:.2f} at start, {load[1]:.2f} at the end (a machine shared with "
        "other work, which the load average counts; each pair alternates its runs so that both programs "
        "see the same load)",
        f"- nvib {nvib.__version__} (git {git_revision()}), `nvib._core` from {os.path.dirname(nvib.__file__)}",
        f"- {opensees_version()}; Python {platform.python_version()}, NumPy {np.__version__}",
        f"- command: `{cmd}`",
        "",
        f"Scene `building` (6 DOFs: floors of 1e5 kg, storeys f = k0 d + k0 a d^3 with k0 = 1e8 N/m and "
        f"a = 10 1/m^2, a_g = 10 sin(πt) m/s^2, from rest), over t_end = {args.t_end:g} s: "
        f"floor(t_end / dt) whole steps of dt{short}. OpenSees: the same model with `zeroLength` storeys of "
        "`ElasticPowerFunc -coeff k0 k0*a -exp 1 3`, `UniformExcitation` with a `Trig` series, "
        "`system BandGeneral`, `numberer Plain`, `constraints Plain`; the implicit schemes with "
        f"`algorithm Newton` and `test {TEST_NOTES[test]}`, central difference with "
        "`algorithm Linear -factorOnce` (its matrix M/dt² is constant). nvib: full Newton with its default "
        "test (max-norm residual <= 1e-10 x the largest inertia/force term + 1e-12).",
        "",
        f"Times: best of {args.repeats} runs each, OpenSees' `analyze(nsteps, dt)` (one call, model building "
        "excluded) against the whole `nvib.solve(model, scheme, dt=dt, t_end=nsteps*dt, save_every=nsteps)` "
        "call from Python (neither records a history in these runs), the two alternating. Ratio = OpenSees "
        "time / nvib time. Newton iterations and the x6 (floor 6) histories come from untimed runs: OpenSees "
        "with `analyze(1, dt)` per step (testIter() after each; it ends in the same state as the one-call run), "
        "nvib with save_every = 1. Δx6 = x6_nvib − x6_OpenSees over every step of the run.",
        "",
    ]
    lines += scheme_table(sorted({r["scheme"] for r in rows}, key=list(SCHEMES).index)) + [""] + table(rows)
    ok = [r for r in rows if r["max_dx6"] is not None]

    def span(rs):
        v = [r["ratio"] for r in rs]
        return f"{min(v):.1f}" if min(v) == max(v) or len(v) == 1 else f"{min(v):.1f}–{max(v):.1f}"

    done = [r for r in rows if r["nvib_error"] is None and r["opensees_code"] == 0 and r["opensees_finite"]]
    summary = []
    for dt in dict.fromkeys(r["dt"] for r in done):
        imp = [r for r in done if r["dt"] == dt and is_implicit(r["scheme"])]
        exp = [r for r in done if r["dt"] == dt and not is_implicit(r["scheme"])]
        var = [r for r in variant if r["dt"] == dt]
        part = f"dt = {_fmt_dt(dt)}: "
        if imp:
            part += f"implicit schemes {span(imp)}x"
            if var:
                part += f" ({span(var)}x against OpenSees' other test)"
        if exp:
            part += (", " if imp else "") + f"central difference {span(exp)}x"
        summary.append(part)
    if summary:
        lines += ["", "nvib faster than OpenSees by (ratio OpenSees / nvib): " + "; ".join(summary) + ". "
                  "OpenSees' time per step hardly depends on its linear solver (its other systems are within a few "
                  "per cent, or slower; see benchmarks/opensees.py): it goes to the framework's work per step and "
                  "per Newton iteration, about 4 µs per step even for central difference, whose system is M/dt² "
                  "factored once. "
                  "With NormDispIncr 1e-12 OpenSees often needs a third Newton iteration at the larger steps, "
                  "where NormUnbalance 1e-6 N stops after two; the histories agree equally either way. At "
                  "dt = 0.03 and 0.035 both programs need more Newton iterations per step, and nvib's fixed cost "
                  "per solve() call (about 20 µs for a one-step run) weighs on its 285 to 333 steps, most visibly "
                  "for central difference."]
    loop_du = max((r["loop_vs_one_call_max_du"] or 0.0) for r in rows if r["loop_vs_one_call_max_du"] is not None)
    lines += ["", f"OpenSees' per-step runs end where its one-call runs do (largest difference of the final "
                  f"displacements {loop_du:.1e} m)."]
    if checks is not None:
        lines += ["", "Inputs checked in OpenSees (`check_inputs`): ElasticPowerFunc force and tangent against "
                      f"k0 (1 + a d^2) d and k0 (1 + 3 a d^2) to {checks['material_force_rel_err']:.1e} and "
                      f"{checks['material_tangent_rel_err']:.1e} relative; a free mass under the same excitation "
                      f"has relative acceleration −a_g(t) to {checks['a_g_abs_err']:.1e} m/s^2."]
    if ok:
        worst = max(ok, key=lambda r: r["rel_dx6"])
        lines += ["", f"Agreement: over all completed runs, max |Δx6| <= {max(r['max_dx6'] for r in ok):.1e} m, "
                      f"{worst['rel_dx6']:.1e} of max |x6| (worst: {worst['label']} at dt = {_fmt_dt(worst['dt'])})."]
    if scan:
        lines += ["", f"Central difference near its stability limit (untimed, over t_end = {args.t_end:g} s). "
                      f"Linearised at rest (k0 storeys) the building's highest frequency gives 2/ω_max = "
                      f"{linear_dt_crit():.4f} s; the hardening springs stiffen the storeys under this excitation "
                      "and lower the limit of the run:", "",
                  "| dt [s] | steps | nvib | OpenSees: first step with a floor's \\|u\\| > 1e10 m or not finite "
                  "| OpenSees: analyze() code, final x6 [m] |",
                  "|---:|---:|---|---|---|"]
        for c in scan:
            k = c["opensees_blowup_step"]
            blow = "none (completed)" if k is None else f"step {k} (t = {k * c['dt']:.4g} s)"
            lines.append(f"| {_fmt_dt(c['dt'])} | {c['steps']:,} | {c['nvib']} | {blow} "
                         f"| {c['opensees_code']}, {c['opensees_x6_final']:.3g} |")
    if variant:
        other = "unbalance" if test == "dispincr" else "dispincr"
        lines += ["", f"The implicit schemes again with OpenSees' `test {TEST_NOTES[other]}` instead (nvib "
                      f"unchanged, timed anew beside it), best of {args.repeats}:", "",
                  "| scheme | dt [s] | OpenSees [ns/step] | nvib [ns/step] | ratio OpenSees / nvib "
                  "| Newton it./step OpenSees | max \\|Δx6\\| [m] | relative |",
                  "|---|---:|---:|---:|---:|---:|---:|---:|"]
        for r in variant:
            dx = "–" if r["max_dx6"] is None else f"{r['max_dx6']:.1e}"
            rel = "–" if r["rel_dx6"] is None else f"{r['rel_dx6']:.1e}"
            lines.append(f"| {r['label']} | {_fmt_dt(r['dt'])} | {r['opensees_ns_per_step']:,.0f} "
                         f"| {r['nvib_ns_per_step']:,.0f} | {r['ratio']:.1f} "
                         f"| {r['opensees_iters_per_step']:.3f} | {dx} | {rel} |")
    lines += ["", "OpenSees conventions (3.7.1, openseespy 3.7.1.2) that the mapping follows:", "",
              "- `integrator Newmark gamma beta`: gamma first; `Newmark 0.5 0.25` is nvib `Newmark()` "
              "(beta = 1/4, gamma = 1/2).",
              "- `integrator HHT alpha` weights the new level by alpha, x_{n+α} = (1 − α) x_n + α x_{n+1}, with "
              "gamma = 3/2 − α and beta = (2 − α)²/4; nvib's alpha_f weights the old level. `HHT 0.9` is "
              "`GeneralizedAlpha(alpha_m=0, alpha_f=0.1, beta=0.3025, gamma=0.6)`.",
              "- `integrator GeneralizedAlpha alphaM alphaF` does not converge for alphaM ≠ 1 in 3.7.1.2 (its "
              "update gives the domain a_{n+1} where the tangent assumes a_{n+αM}; for alphaM = 1/2 the "
              "unbalance stays at M a_g(dt/2)). `HHTGeneralized alphaI alphaF beta gamma` is the consistent "
              "implementation of the same method, alphas again on the new level: `HHTGeneralized 0.5 0.5 "
              "0.25 0.5` is nvib `GeneralizedAlpha()` (the paper's GαM, α_m = α_f = 1/2).",
              "- `integrator CentralDifference` requires `algorithm Linear` and starts from u_{-1} = u_0; the "
              "building starts at rest with a_g(0) = 0, where that start is exact, so its displacements are "
              "nvib `CentralDifference()`'s up to round-off. It reports a backward-difference velocity; only "
              "displacements are compared.",
              "- The `Trig` series is given an end time of t_end + 2 s: with a very large one (1e9) "
              "`analyze` hangs.",
              "",
              "Divergence: nvib checks every step's state against non-finite values and its displacement "
              "bound (1e10 m) and stops with `nvib.DivergenceError` naming the time and step. OpenSees' "
              "central difference has no such check (and `algorithm Linear` no convergence test): its run goes "
              "on to the last step silently (`analyze()` returns 0, success, and prints nothing) with "
              "non-finite displacements; the outcome column gives what `analyze()` returned, the final x6, and "
              "the first step of the per-step run at which a floor's |u| passed 1e10 m or stopped being finite "
              "(nvib's test on u, so both name the same step)."]
    return lines


def _ops_importable() -> Exception | None:
    try:
        _ops()
    except Exception as exc:  # openseespy raises RuntimeError when its .so cannot load
        return exc
    return None


def _reexec_or_fail() -> int:
    """Re-run this command once with opensees_env(); return 3 (after a message) if that is not possible."""
    exc = _ops_importable()
    if exc is None:
        return 0
    env = opensees_env()
    if env is not None and not os.environ.get(_REEXEC_MARK) and env != dict(os.environ):
        env[_REEXEC_MARK] = "1"
        sys.stdout.flush()
        os.execve(sys.executable, [sys.executable, os.path.abspath(sys.argv[0])] + sys.argv[1:], env)
    print(f"openseespy is not importable ({type(exc).__name__}: {exc}); "
          "install openseespy and start with opensees_env()'s LD_LIBRARY_PATH", file=sys.stderr)
    return 3


def opensees_only_main(argv=None, default_test: str = "dispincr",
                       default_schemes: tuple = ("newmark", "galpha", "hht")) -> int:
    """The OpenSees-only command line: one JSON object (or text line) per scheme."""
    p = argparse.ArgumentParser(description="OpenSees alone on the building scene")
    p.add_argument("--opensees-only", action="store_true", help=argparse.SUPPRESS)
    p.add_argument("--json", action="store_true", help="one JSON object per scheme and line")
    p.add_argument("--dt", type=float, default=1e-4)
    p.add_argument("--t-end", type=float, default=10.0)
    p.add_argument("--repeats", type=int, default=3)
    p.add_argument("--schemes", default=",".join(default_schemes), help="comma-separated: " + ", ".join(SCHEMES))
    p.add_argument("--test", choices=sorted(TESTS), default=default_test, help="Newton's convergence test")
    p.add_argument("--system", default=SYSTEM)
    p.add_argument("--no-iterations", action="store_true", help="skip the untimed per-step run")
    p.add_argument("--history", action="store_true", help="x6 of every step (from the per-step run)")
    p.add_argument("--check", action="store_true", help="also verify material and a_g (check_inputs)")
    args = p.parse_args(argv)
    code = _reexec_or_fail()
    if code:
        return code
    if args.check:
        chk = check_inputs()
        print(json.dumps({"check": chk}) if args.json else f"checks: {chk}", flush=True)
    for scheme in [s.strip() for s in args.schemes.split(",") if s.strip()]:
        r = run(args.dt, args.t_end, scheme, test=args.test, repeats=args.repeats, system=args.system,
                count_iterations=not args.no_iterations, history=args.history)
        if args.json:
            print(json.dumps(r), flush=True)
        else:
            it = "?" if r["iterations_per_step"] is None else f"{r['iterations_per_step']:.3f}"
            print(f"{scheme:8s} {r['steps']} steps  best {r['wall_time']:.4f} s "
                  f"({r['wall_time_per_step'] * 1e6:.3f} us/step)  Newton it/step {it}  "
                  f"u6 = {r['u'][-1]:.15g}", flush=True)
    return 0


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if argv[:1] == ["--hysteresis"]:
        sys.path.insert(0, HERE)
        import opensees_hysteresis
        return opensees_hysteresis.main(argv[1:])
    if "--opensees-only" in argv:
        return opensees_only_main(argv)
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--hysteresis", action="store_true",
                   help="as the first argument: the laws with memory against OpenSees' uniaxial materials "
                        "(benchmarks/opensees_hysteresis.py), with the arguments that follow")
    p.add_argument("--dts", type=float, nargs="+", default=list(DEFAULT_DTS))
    p.add_argument("--t-end", type=float, default=10.0)
    p.add_argument("--repeats", type=int, default=3)
    p.add_argument("--schemes", default=",".join(COMPARED), help="comma-separated: " + ", ".join(COMPARED))
    p.add_argument("--test", choices=sorted(TESTS), default="dispincr", help="OpenSees' Newton test")
    p.add_argument("--variant-dts", type=float, nargs="*", default=[7e-4, 1e-4],
                   help="dts at which the implicit schemes also run with the other OpenSees test (none: skip)")
    p.add_argument("--cd-scan", type=float, nargs="*", default=[0.030, 0.031, 0.0315, 0.032, 0.0325],
                   help="dts of the untimed central-difference stability scan (none: skip)")
    p.add_argument("--out", default=os.path.join(HERE, "results", "opensees.md"))
    p.add_argument("--no-report", action="store_true", help="print the table only, write nothing")
    p.add_argument("--json", action="store_true", help="one JSON object per row, no report")
    p.add_argument("--opensees-only", action="store_true", help="OpenSees alone (see the module docstring)")
    args = p.parse_args(argv)
    if args.repeats < 1:
        p.error("--repeats must be >= 1")
    schemes = [s.strip() for s in args.schemes.split(",") if s.strip()]
    bad = [s for s in schemes if s not in COMPARED]
    if bad:
        p.error(f"unknown scheme(s) {bad}; choose from {', '.join(COMPARED)}")
    code = _reexec_or_fail()
    if code:
        return code
    sys.path.insert(0, HERE)
    import nvib

    load_start = os.getloadavg()[0]
    checks = check_inputs()
    model = nvib.load_scene("building")
    rows = []
    for dt in args.dts:
        for key in schemes:
            r = compare(model, key, dt, args.t_end, args.repeats, args.test)
            rows.append(r)
            if args.json:
                print(json.dumps(r), flush=True)
            else:
                print(f"{key:8s} dt {dt:<7g} OpenSees {r['opensees_ns_per_step']:9.0f} ns/step  nvib "
                      f"{r['nvib_ns_per_step']:7.0f} ns/step  ratio {r['ratio']:6.1f}  max|dx6| "
                      f"{r['max_dx6'] if r['max_dx6'] is not None else float('nan'):.1e}  {_outcome(r)}",
                      file=sys.stderr, flush=True)
    other = "unbalance" if args.test == "dispincr" else "dispincr"
    variant = []
    for dt in args.variant_dts or []:
        for key in schemes:
            if is_implicit(key):
                variant.append(compare(model, key, dt, args.t_end, args.repeats, other))
    scan = cd_scan(model, args.cd_scan, args.t_end) if "cd" in schemes and args.cd_scan else []
    load_end = os.getloadavg()[0]
    if args.json:
        for r in variant:
            print(json.dumps(dict(r, variant_test=other)), flush=True)
        return 0
    lines = report(rows, variant, args, (load_start, load_end), checks, scan)
    if args.no_report:
        print("\n".join(lines))
        return 0
    from building import write_report

    write_report(args.out, lines)
    return 0


if __name__ == "__main__":
    sys.exit(main())
