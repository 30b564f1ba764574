"""OpenSees peer of nvib's "building" scene: the same model integrated by OpenSeesPy.

What it builds (OpenSeesPy, ``model('basic', '-ndm', 1, '-ndf', 1)``): the scene
of ``nvib.load_scene("building")`` (python/nvib/scenes/building.toml) --
nodes 0..6 on one axis, node 0 fixed (the ground), floors 1..6 of mass 1e5 kg
(``mass``), storey i a ``zeroLength`` element between nodes i-1 and i in
direction 1 whose material is

    uniaxialMaterial('ElasticPowerFunc', tag, '-coeff', k0, k0*a, '-exp', 1.0, 3.0)

so that the force on the drift d is f = k0 d + k0 a d^3 = k0 (1 + a d^2) d
(k0 = 1e8 N/m, a = 10; ElasticPowerFunc takes sign(d) |d|^e, which for e = 3
is d^3; `check_inputs` verifies force and tangent against the formula).
The ground acceleration a_g(t) = 10 sin(pi t) m/s^2 is
``timeSeries('Trig', ts, 0, t_end + 2, 2.0, '-factor', 10.0)`` (period 2 s) in
``pattern('UniformExcitation', p, 1, '-accel', ts)``: the effective load
-M r a_g, displacements relative to the ground, as in nvib. (`check_inputs`
verifies it with a free mass, whose relative acceleration must be -a_g(t).
The end time of the series is kept near t_end: OpenSees 3.7.1 hangs in
``analyze`` when it is very large, e.g. 1e9.) No damping; starts at rest.

Analysis, scheme by scheme (--schemes; default newmark,galpha,hht):
  * "newmark": ``integrator('Newmark', 0.5, 0.25)`` = nvib Newmark();
  * "galpha": ``integrator('HHTGeneralized', 0.5, 0.5, 0.25, 0.5)``
    (alpha_I, alpha_F, beta, gamma) = nvib GeneralizedAlpha(), the paper's GaM
    alpha_m = alpha_f = 1/2 (the implicit midpoint rule). OpenSees weights the
    NEW level by alpha, x_{n+alpha} = (1 - alpha) x_n + alpha x_{n+1}, nvib the
    old one, and 1/2 is 1/2 in both;
  * "hht": ``integrator('HHT', 0.9)`` (gamma = 1.5 - alpha = 0.6, beta =
    (2 - alpha)^2 / 4 = 0.3025) = nvib GeneralizedAlpha(alpha_m=0,
    alpha_f=0.1, beta=0.3025, gamma=0.6);
  * "galpha-ops": ``integrator('GeneralizedAlpha', 0.5, 0.5)``, kept only to
    show that it FAILS: in OpenSees 3.7.1 GeneralizedAlpha::update() gives the
    domain a_{n+1} instead of a_{n+alphaM} while the tangent carries
    alphaM c3 M, so for alphaM = 1/2 each Newton step overshoots by 2 and the
    unbalance stays at M a_g(dt/2) = 157.08 N forever. (Its 4-argument form
    also passes "gamma beta" into a constructor that takes "beta gamma".)
    HHTGeneralized is the consistent implementation of the same method.
Common to all: ``algorithm('Newton')`` (full Newton, tangent every
iteration), ``test('NormUnbalance', tol, 50, 0, 0)`` -- the max-norm (norm
type 0) of the unbalanced force, absolute, default tol = 1e-6 N (TOL); nvib's
test is max-norm residual <= 1e-10 * (largest inertia/force term, about
2.5e5 N here) + 1e-12. Against 1e-6 N, at t = 2 s, tol = 1e-9 N moves the
final displacements by 1e-15 m, 1e-4 N by 6e-13 m, 1e-2 N by 8e-10 m, all
well below or at the OpenSees-nvib difference; 1e-6 N needs 1.98 iterations
per step, 1e-9 N 2.67, and OpenSees' residual floor is about 1e-9 N. ``system('BandGeneral')`` (banded LAPACK
dgbsv; 'FullGeneral' gives the same final u and is about 8 % slower),
``numberer('Plain')``, ``constraints('Plain')``, ``analysis('Transient')``,
then ``analyze(nsteps, dt)`` in ONE call.

Measured (OpenSees 3.7.1 / openseespy 3.7.1.2, this machine, dt = 1e-4,
10 s = 1e5 steps, best of 5): newmark 8.4 us/step, galpha 9.8, hht 10.0
(nvib.solve: about 1.0 us/step for each). Newton iterations per step:
OpenSees 2.00 (all three), nvib 2.91 / 2.81 / 2.90. Final displacements
against nvib at the same dt: max |du| = 5.9e-12 / 1.3e-11 / 6.5e-12 m
(relative to max |u| = 0.050 m: 1.2e-10 / 2.7e-10 / 1.3e-10).

What it measures: the wall time (time.perf_counter) of that analyze() call
only, model building excluded, best of `repeats` runs (wipe and rebuild
between them); the final displacements, velocities and (relative)
accelerations of the six floors (nodeDisp/nodeVel/nodeAccel). OpenSees
exposes the Newton iteration count of the LAST step only (testIter()), so the
iterations are counted in a separate, untimed run that calls analyze(1, dt)
per step (it also records the top-floor displacement of every step when
history=True, and must end in the same state as the one-call runs).

How to call it. OpenSeesPy's extension (openseespylinux/opensees.so) loads
only when LD_LIBRARY_PATH, read at process start, contains the folder ``lib``
beside the package ``openseespylinux``. `opensees_env()` returns os.environ
with that folder prepended (None if openseespy is not installed); start
Python in a subprocess with it:

    env = opensees_env()
    subprocess.run([sys.executable, "benchmarks/opensees_building.py", "--json"], env=env)

Run as a script it re-executes itself once with that environment when the
import fails for want of it:

    python benchmarks/opensees_building.py --json [--dt 1e-4] [--t-end 10] [--repeats 3]
                                                  [--schemes newmark,galpha,hht] [--tol 1e-6]
                                                  [--system BandGeneral] [--check] [--no-iterations]

prints one JSON object per line and scheme (scheme, dt, steps, best wall time,
wall time per step, Newton iterations, final u/v/a lists, OpenSees version,
material, test and system used; with --check first a line {"check": ...}
of check_inputs()); without --json a short text summary.
Without openseespy importable it exits with code 3 and a one-line message.
As a module (in a process started with opensees_env()): ``run(dt, t_end,
scheme="newmark", tol=TOL, repeats=3)`` returns the same dict.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import os
import sys
import time

N_FLOORS = 6
MASS = 1e5  # kg per floor
K0 = 1e8  # N/m
A = 10.0  # 1/m^2
AG_AMPLITUDE = 10.0  # m/s^2
AG_PERIOD = 2.0  # s: a_g = 10 sin(2 pi t / 2) = 10 sin(pi t)

TOL = 1e-6  # N, max-norm of the unbalanced force
MAX_ITER = 50
SYSTEM = "BandGeneral"  # LAPACK dgbsv; FullGeneral (dgesv) gives the same u and is ~8% slower
MATERIAL = "ElasticPowerFunc -coeff k0 k0*a -exp 1 3"
SCHEMES = {
    # name: (integrator arguments, nvib equivalent)
    "newmark": (("Newmark", 0.5, 0.25), "nvib.Newmark()"),
    "galpha": (("HHTGeneralized", 0.5, 0.5, 0.25, 0.5), "nvib.GeneralizedAlpha()"),
    "hht": (("HHT", 0.9), "nvib.GeneralizedAlpha(alpha_m=0.0, alpha_f=0.1, beta=0.3025, gamma=0.6)"),
    # OpenSees' own GeneralizedAlpha is not usable here, see the module docstring
    "galpha-ops": (("GeneralizedAlpha", 0.5, 0.5), "nvib.GeneralizedAlpha() (fails in OpenSees 3.7.1)"),
}
DEFAULT_SCHEMES = ("newmark", "galpha", "hht")

_REEXEC_MARK = "NVIB_OPENSEES_REEXEC"


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


def _build(ops, scheme: str, t_end: float, tol: float, system: str) -> None:
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
    ops.test("NormUnbalance", tol, MAX_ITER, 0, 0)
    ops.algorithm("Newton")
    ops.integrator(*SCHEMES[scheme][0])
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
    import math

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


def run(
    dt: float = 1e-4,
    t_end: float = 10.0,
    scheme: str = "newmark",
    tol: float = TOL,
    repeats: int = 3,
    system: str = SYSTEM,
    count_iterations: bool = True,
    history: bool = False,
) -> dict:
    """Integrate the building in OpenSees; the best wall time of analyze(nsteps, dt) over `repeats`."""
    if scheme not in SCHEMES:
        raise ValueError(f"scheme must be one of {sorted(SCHEMES)}, got {scheme!r}")
    ops = _ops()
    nsteps = int(round(t_end / dt))
    best = float("inf")
    final = None
    for _ in range(max(1, repeats)):
        _build(ops, scheme, t_end, tol, system)
        t0 = time.perf_counter()
        ok = ops.analyze(nsteps, dt)
        wall = time.perf_counter() - t0
        if ok != 0:
            raise RuntimeError(f"OpenSees analyze() failed (code {ok}) at t = {ops.getTime()}")
        best = min(best, wall)
        final = _state(ops)
        t_final = ops.getTime()
    out = {
        "scheme": scheme,
        "nvib_equivalent": SCHEMES[scheme][1],
        "integrator": " ".join(str(x) for x in SCHEMES[scheme][0]),
        "dt": dt,
        "t_end": t_end,
        "t_final": t_final,
        "steps": nsteps,
        "repeats": max(1, repeats),
        "wall_time": best,
        "wall_time_per_step": best / nsteps,
        "iterations": None,
        "iterations_per_step": None,
        "u": final[0],
        "v": final[1],
        "a": final[2],
        "opensees": opensees_version(),
        "material": MATERIAL,
        "test": f"NormUnbalance {tol:g} {MAX_ITER} 0 0 (max-norm, N)",
        "algorithm": "Newton",
        "system": system,
    }
    if count_iterations or history:
        # untimed: one analyze(1, dt) per step, testIter() after each
        _build(ops, scheme, t_end, tol, system)
        iters = 0
        top = [0.0] if history else None
        for _ in range(nsteps):
            if ops.analyze(1, dt) != 0:
                raise RuntimeError(f"OpenSees analyze(1, dt) failed at t = {ops.getTime()}")
            iters += ops.testIter()
            if history:
                top.append(ops.nodeDisp(N_FLOORS, 1))
        u_loop = _state(ops)[0]
        out["iterations"] = iters
        out["iterations_per_step"] = iters / nsteps
        out["loop_vs_one_call_max_du"] = max(abs(x - y) for x, y in zip(u_loop, final[0]))
        if history:
            out["u_top_history"] = top
    ops.wipe()
    return out


def _main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n", 1)[0])
    p.add_argument("--json", action="store_true", help="one JSON object per scheme and line")
    p.add_argument("--dt", type=float, default=1e-4)
    p.add_argument("--t-end", type=float, default=10.0)
    p.add_argument("--repeats", type=int, default=3)
    p.add_argument("--schemes", default=",".join(DEFAULT_SCHEMES), help="comma-separated: " + ", ".join(SCHEMES))
    p.add_argument("--tol", type=float, default=TOL, help="NormUnbalance tolerance, N (max-norm)")
    p.add_argument("--system", default=SYSTEM)
    p.add_argument("--no-iterations", action="store_true", help="skip the untimed per-step counting run")
    p.add_argument("--check", action="store_true", help="also verify material and a_g (check_inputs)")
    args = p.parse_args(argv)

    try:
        _ops()
    except Exception as exc:  # openseespy raises RuntimeError when its .so cannot load
        env = opensees_env()
        if env is not None and not os.environ.get(_REEXEC_MARK) and env != dict(os.environ):
            env[_REEXEC_MARK] = "1"
            sys.stdout.flush()
            os.execve(sys.executable, [sys.executable, os.path.abspath(__file__)] + sys.argv[1:], env)
        print(f"openseespy is not importable ({type(exc).__name__}: {exc}); "
              "install openseespy and start with opensees_env()'s LD_LIBRARY_PATH", file=sys.stderr)
        return 3

    if args.check:
        chk = check_inputs()
        print(json.dumps({"check": chk}) if args.json else f"checks: {chk}", flush=True)
    for scheme in [s.strip() for s in args.schemes.split(",") if s.strip()]:
        r = run(args.dt, args.t_end, scheme, tol=args.tol, repeats=args.repeats,
                system=args.system, count_iterations=not args.no_iterations)
        if args.json:
            print(json.dumps(r), flush=True)
        else:
            it = "?" if r["iterations"] is None else f"{r['iterations_per_step']:.3f}"
            print(f"{scheme:8s} {r['steps']} steps  best {r['wall_time']:.4f} s "
                  f"({r['wall_time_per_step'] * 1e6:.3f} us/step)  Newton it/step {it}  "
                  f"u6 = {r['u'][-1]:.15g}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(_main())
