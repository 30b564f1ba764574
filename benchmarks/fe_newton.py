"""nvib against the loops a structural engineer writes with SciPy, on generated finite-element models.

The models (``fe_models.py``: plane-stress walls, 3-D hexahedral blocks, 3-D beam-column frames,
rotors of beam elements on bearings; 768 to 15,840 DOFs and a 29,376-DOF block) carry a consistent
mass, Rayleigh damping of 2 % on modes 1 and 5, 4 to 8 hardening springs to ground
f = k0 (d + a d^3) and a sine ground acceleration at the first mode's frequency through M r, and
start from a deflected state in which the springs' cubic term equals their linear one. For each:

* explicit: nvib ``CentralDifference`` against a vectorised scipy.sparse central-difference loop
  (the same recurrence: velocity predictor v + dt a for the damping force), with the consistent mass
  (factorised once, solved every step) and with the row-sum lumped mass where its rows are all
  positive (the solid models; its Rayleigh damping is that of the lumped mass, C = alpha diag(m) +
  beta K with the consistent model's alpha and beta, as an engineer assembles it: nvib recognises
  that form and takes K (u + beta v) + alpha m v, linear_product.hpp), at 0.8 of the stable step (2 (sqrt(1 + 4 xi^2) - 2 xi) / omega_max,
  omega_max from ARPACK with the springs stiffened, xi its Rayleigh damping ratio);
* linear Newmark (the model without its springs): nvib ``Newmark()`` against a loop that factorises
  K + 2/dt C + 4/dt^2 M once and solves the effective load every step;
* Newmark + full Newton: nvib ``Newmark()`` (default Newton: residual below 1e-12 + 1e-10 of the
  step's force scale, or at its round-off) and ``Newmark(newton=Newton(iteration="modified"))``
  against the plain SciPy loop: predictor u_{n+1} = u_n, the iteration matrix assembled and
  factorised (SuperLU) every iteration, stop when max |du| <= 1e-8 max |u|.

Every SciPy factorisation is ``scipy.sparse.linalg.splu`` in symmetric mode (minimum degree on
A^T + A, no pivoting): splu's defaults (COLAMD, partial pivoting) take 20 to 200 times as long on
these symmetric matrices (23 s against 0.1 s for the 15,840-DOF frame), and a loop that slow would
not be a fair opponent. The loops are in this file, about 40 lines each.

Timing: per comparison the step count is grown until the faster contender takes at least
``--target`` seconds (capped so that the slower one stays under ``--max-run``), then the
contenders run in interleaved rounds (nvib, SciPy, nvib, SciPy, ...) and the best wall time of each
is kept; a comparison whose round took over ``--max-comparison`` seconds gets no further round.
The wall time of nvib is one ``nvib.solve()`` call on a model built beforehand (its construction,
which factorises a consistent mass, and the stability check of its first explicit ``solve()``, are
reported as set-up); that of SciPy is the loop from the initial state, its factorisations inside,
except the explicit loop's mass factorisation (set-up too). Ratio = SciPy time / nvib time: above 1
nvib is faster, below 1 it is slower. Agreement = max |u_nvib - u_SciPy| / max |u_SciPy| at the last
step; a comparison whose agreement is above 1e-6 is void and flagged.

The section "Why nvib iterates more" steps nvib one step at a time (``nvib.Stepper``) to count
its iterations per step against the loop's and, on the step where it exceeds the loop most,
prints the residual norms of nvib's iterations (``Stepper.last_residuals``) beside the loop's
iterates from the same state (their residuals by nvib's definition, the increments it tests).

    python benchmarks/fe_newton.py [--quick] [--models NAME ...] [--out benchmarks/results/fe_newton.md]
"""

from __future__ import annotations

import argparse
import dataclasses
import datetime
import math
import os
import sys
import time

import numpy as np
import scipy.sparse as sp

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.path.insert(0, HERE)

import fe_models as fm  # noqa: E402


def _import_nvib(wait: float = 180.0):
    """nvib, waiting while it is being reinstalled (an import that fails is retried for ``wait`` s)."""
    t0 = time.monotonic()
    while True:
        try:
            import nvib as mod

            return mod
        except ImportError:
            if time.monotonic() - t0 > wait:
                raise
            for name in [m for m in sys.modules if m == "nvib" or m.startswith("nvib.")]:
                del sys.modules[name]
            time.sleep(10.0)


nvib = _import_nvib()

LOOP_RTOL = 1e-8      # the loop's test: max |du| <= LOOP_RTOL max |u|
AGREEMENT = 1e-6      # a comparison whose final displacements differ by more (relative) is void
EPS = np.finfo(float).eps


# ---------------------------------------------------------------- models for nvib

def nvib_model(case: fm.Case, springs: bool = True, lumped: np.ndarray | None = None):
    """The case as an nvib Model: K, C, the consistent mass (or ``lumped``, a diagonal), one
    hardening_spring effect per spring, and the ground acceleration on r."""
    effects = []
    if springs:
        effects += [{"type": "hardening_spring", "measure": {int(i): 1.0}, "k0": float(k), "a": float(a)}
                    for i, k, a in zip(case.springs, case.k0, case.a)]
    nz = np.flatnonzero(case.r)
    effects.append({"type": "ground_acceleration", "measure": {int(i): float(case.r[i]) for i in nz},
                    "signal": {"kind": "sine", "amplitude": case.ground_amplitude, "omega": case.omega1}})
    return nvib.Model(case.M if lumped is None else lumped, K=case.K, C=case.C, effects=effects, u0=case.u0,
                      v0=case.v0)


def lumped_mass(case: fm.Case) -> np.ndarray | None:
    """Row sums of the consistent mass, or None where one is not positive (beam models: a rotation's
    row sums its inertia with translational terms of other units)."""
    m = np.asarray(case.M.sum(axis=1)).ravel()
    return m if np.all(m > 0) else None


def lumped_case(case: fm.Case, ml: np.ndarray) -> fm.Case:
    """The case with the lumped mass ``ml``'s Rayleigh damping, C = alpha diag(ml) + beta K."""
    C = (case.alpha * sp.diags(ml) + case.beta * case.K).tocsc()
    return dataclasses.replace(case, C=C)


# ---------------------------------------------------------------- the SciPy loops

def spring_force(case, u):
    d = u[case.springs]
    return case.k0 * (d + case.a * d**3)


def scipy_central_difference(case, dt, steps, solve_mass, mass_r):
    """Central difference as nvib's LCDM: u += dt v + dt^2/2 a; a_new from the forces at (u, v + dt a);
    v += dt/2 (a + a_new). ``solve_mass``: M^-1 applied (a factorised consistent mass, or division by
    a lumped one); ``mass_r``: M r."""
    K, C = case.K.tocsr(), case.C.tocsr()
    sp_ = case.springs
    u, v = case.u0.copy(), case.v0.copy()
    f = K @ u + C @ v + mass_r * case.ground(0.0)
    f[sp_] += spring_force(case, u)
    a = solve_mass(-f)
    h, hh = dt, 0.5 * dt * dt
    for s in range(1, steps + 1):
        u += h * v + hh * a
        f = K @ u + C @ (v + h * a) + mass_r * case.ground(s * dt)
        f[sp_] += spring_force(case, u)
        a_new = solve_mass(-f)
        v += 0.5 * h * (a + a_new)
        a = a_new
    return u


def scipy_newmark_linear(case, dt, steps, mass_solve, form="residual"):
    """Linear Newmark (1/4, 1/2) on the model without springs, S = K + 2/dt C + 4/dt^2 M factorised
    once. ``form="residual"``: from the predictor u_{n+1} = u_n, one solve of S du = -r with r the
    equilibrium residual there (nvib's form; its round-off is relative to du). ``form="effective"``:
    the textbook effective load, u_{n+1} = S^-1 [P_{n+1} + M (c0 u + 4/dt v + a) + C (2/dt u + v)]
    (two products instead of three, but its round-off is relative to u, and on ill-conditioned models
    it drifts from both: see the column "effective-load form")."""
    K, M, C = case.K.tocsr(), case.M.tocsr(), case.C.tocsr()
    c0, c1 = 4 / dt**2, 2 / dt
    lu = fm.factorize(K + c1 * C + c0 * M)
    mr = M @ case.r
    u, v = case.u0.copy(), case.v0.copy()
    a = mass_solve(-(K @ u + C @ v + mr * case.ground(0.0)))  # M factorised in the set-up, as nvib's Model() does
    for s in range(1, steps + 1):
        if form == "residual":
            a1, v1 = -4 / dt * v - a, -v  # at the predictor
            du = -lu.solve(M @ a1 + C @ v1 + K @ u + mr * case.ground(s * dt))
            u, v, a = u + du, v1 + c1 * du, a1 + c0 * du
        else:
            rhs = -mr * case.ground(s * dt) + M @ (c0 * u + 4 / dt * v + a) + C @ (c1 * u + v)
            u1 = lu.solve(rhs)
            a1 = c0 * (u1 - u) - 4 / dt * v - a
            v = v + dt / 2 * (a + a1)
            u, a = u1, a1
    return u


def scipy_newmark_newton(case, dt, steps, mass_solve=None, rtol=LOOP_RTOL, state=None, t0=0.0, trace=None):
    """The loop an engineer writes: Newmark (1/4, 1/2), predictor u_{n+1} = u_n, full Newton with the
    iteration matrix assembled and factorised every iteration, stop when max |du| <= rtol max |u|.
    ``mass_solve`` applies M^-1 (for the initial acceleration). Returns the final u, the iterations of
    each step and the largest |d| of each spring.
    ``state`` = (u, v, a) starts it elsewhere; ``trace`` (a list) receives, for each iteration of the
    first step, the residual at the iterate by nvib's definition and the increment."""
    K, M, C = case.K.tocsr(), case.M.tocsr(), case.C.tocsr()
    n, sp_ = case.n, case.springs
    c0, c1 = 4 / dt**2, 2 / dt
    mr = M @ case.r
    Kc = (K + c1 * C + c0 * M).tocsc()
    if state is None:
        u, v = case.u0.copy(), case.v0.copy()
        f = K @ u + C @ v + mr * case.ground(t0)
        f[sp_] += spring_force(case, u)
        a = mass_solve(-f)  # M factorised in the set-up, as nvib's Model() does
    else:
        u, v, a = (x.copy() for x in state)
    iters = np.zeros(steps, dtype=int)
    dmax = np.abs(u[sp_])
    for s in range(1, steps + 1):
        t = t0 + s * dt
        load = mr * case.ground(t)
        u1 = u.copy()
        for it in range(1, 51):
            a1 = c0 * (u1 - u) - 4 / dt * v - a
            v1 = v + dt / 2 * (a + a1)
            d = u1[sp_]
            R = M @ a1 + C @ v1 + K @ u1 + load
            R[sp_] += case.k0 * (d + case.a * d**3)
            kt = np.zeros(n)
            kt[sp_] = case.k0 * (1 + 3 * case.a * d**2)
            du = -fm.factorize(Kc + sp.diags(kt)).solve(R)
            if trace is not None and s == 1:
                trace.append(_trace_row(case, dt, u, v, a, u1, t, R, du))
            u1 += du
            if np.max(np.abs(du)) <= rtol * np.max(np.abs(u1)):
                if trace is not None and s == 1:  # the residual it leaves
                    a1 = c0 * (u1 - u) - 4 / dt * v - a
                    R = M @ a1 + C @ (v + dt / 2 * (a + a1)) + K @ u1 + load
                    R[sp_] += spring_force(case, u1)
                    trace.append(_trace_row(case, dt, u, v, a, u1, t, R, None))
                break
        else:
            raise RuntimeError(f"the SciPy loop did not converge in 50 iterations at step {s}")
        iters[s - 1] = it
        a1 = c0 * (u1 - u) - 4 / dt * v - a
        v = v + dt / 2 * (a + a1)
        u, a = u1, a1
        dmax = np.maximum(dmax, np.abs(u[sp_]))
    return u, iters, dmax


def _trace_row(case, dt, u, v, a, u1, t, R, du) -> dict:
    """One iterate of the loop seen with nvib's eyes: the residual max |r| (r = M a1 + K u1 + C v1 + f_s
    + M r a_g), nvib's force scale (the larger of max |M a1| and max |G|, G the force terms) and its
    round-off bound 8 eps max(|M| (c0 (|u1 - u| + dt |v|) + |a|) + |K| |u1| + |C| |v1| + |f_s| + |M r a_g|),
    recomputed here; the increment that follows, relative to max |u1 + du|."""
    c0 = 4 / dt**2
    a1 = c0 * (u1 - u) - 4 / dt * v - a
    v1 = v + dt / 2 * (a + a1)
    Ma = case.M @ a1
    G = R - Ma
    fs = np.zeros(case.n)
    fs[case.springs] = spring_force(case, u1)
    absM, absK, absC = abs(case.M), abs(case.K), abs(case.C)
    mag = (absM @ (c0 * (np.abs(u1 - u) + dt * np.abs(v)) + np.abs(a)) + absK @ np.abs(u1) + absC @ np.abs(v1)
           + np.abs(fs) + np.abs(case.M @ case.r) * abs(case.ground(t)))
    row = {"r": float(np.max(np.abs(R))), "scale": float(max(np.max(np.abs(Ma)), np.max(np.abs(G)))),
           "roundoff": float(8 * EPS * np.max(mag))}
    if du is not None:
        row["du"] = float(np.max(np.abs(du)) / np.max(np.abs(u1 + du)))
    return row


# ---------------------------------------------------------------- timing

class Contender:
    def __init__(self, label: str, run, kind: str):
        self.label, self.run, self.kind = label, run, kind  # run(steps) -> (u, info); kind "nvib" / "scipy"
        self.times: list[float] = []
        self.u = None
        self.info: dict = {}
        self.error: str | None = None

    def once(self, steps: int) -> float:
        t0 = time.perf_counter()
        try:
            self.u, self.info = self.run(steps)
        except Exception as exc:  # a failed run is reported, not fatal
            self.error = f"{type(exc).__name__}: {str(exc).splitlines()[0][:160]}"
            self.u, self.info = None, {}
            return math.inf
        dt = time.perf_counter() - t0
        self.times.append(dt)
        return dt

    @property
    def best(self) -> float:
        return min(self.times) if self.times else math.nan


def race(contenders: list[Contender], first: int, args) -> int:
    """Grow the step count from ``first`` until the fastest contender takes ``args.target`` s (the
    slowest capped at ``args.max_run`` s), then interleaved rounds until ``args.rounds`` or until the
    rounds have taken ``args.max_comparison`` s; the best time of each is kept. The last calibration
    run is the first round. Returns the step count."""
    steps = first
    while True:
        for c in contenders:
            c.times.clear()
        times = [c.once(steps) if c.error is None else math.inf for c in contenders]
        ok = [t for t in times if math.isfinite(t)]
        if not ok or min(ok) >= args.target:
            break
        per_step = [t / steps for t in ok]
        want = math.ceil(1.5 * args.target / min(per_step))
        cap = math.floor(args.max_run / max(per_step))
        grown = max(steps + 1, min(want, cap))
        if grown <= steps or cap <= steps:
            break
        steps = grown
    spent = sum(t for t in times if math.isfinite(t))
    for _ in range(args.rounds - 1):
        if spent > args.max_comparison:
            break
        for c in contenders:
            if c.error is None:
                c.once(steps)
        spent += sum(c.times[-1] for c in contenders if c.times and c.error is None)
    return steps


def skip(contenders: list[Contender], note: str):
    for c in contenders:
        c.error = note
        c.skipped = True


def failures(*contenders) -> str:
    """What went wrong, once: the note of a comparison not run, or each failed contender's error."""
    if any(getattr(c, "skipped", False) for c in contenders):
        return " " + contenders[0].error
    return "".join(f" {c.label} failed: {c.error}" for c in contenders if c.error)


def agreement(u, ref) -> float:
    if u is None or ref is None:
        return math.nan
    return float(np.max(np.abs(u - ref)) / np.max(np.abs(ref)))


def nvib_runner(model, scheme, dt):
    def run(steps):
        # Every run analyses its matrices as a first run does: the ordering an earlier run of the same
        # pattern kept (nvib reuses it: a batch's runs) is forgotten, as SciPy's splu orders in every run.
        nvib._core.ordering_cache(clear=True)
        res = nvib.solve(model, scheme, dt=dt, t_end=steps * dt, save_every=steps)
        st = res.stats
        if st.num_steps != steps:
            raise RuntimeError(f"nvib took {st.num_steps} steps for {steps}")
        return res.u[-1].copy(), {"iters": st.num_newton_iters, "fact": st.num_factorizations,
                                  "reused": st.num_reused_factorizations, "solver": st.linear_solver,
                                  "warnings": list(res.warnings)}
    return run


# ---------------------------------------------------------------- formatting

def f_s(t: float) -> str:
    if not math.isfinite(t):
        return "–"
    return f"{t:.3g}" if t < 100 else f"{t:.0f}"


def f_step(t: float, steps: int) -> str:
    if not math.isfinite(t):
        return "–"
    us = t / steps * 1e6
    return f"{us:.3g} µs" if us < 1000 else f"{us / 1000:.3g} ms" if us < 1e6 else f"{us / 1e6:.3g} s"


def f_ratio(a: float, b: float) -> str:
    """a / b, the SciPy time over nvib's: > 1 nvib faster; in bold where nvib is slower."""
    if not (math.isfinite(a) and math.isfinite(b)) or b <= 0:
        return "–"
    r = a / b
    return f"**{r:.2f}**" if r < 1 else f"{r:.2f}"


def f_g(x, spec: str = ".2g") -> str:
    return format(x, spec) if x is not None and math.isfinite(x) else "–"


def f_agree(x: float) -> str:
    if not math.isfinite(x):
        return "–"
    return f"{x:.1e}" + (" **void**" if x > AGREEMENT else "")


# ---------------------------------------------------------------- one model

def run_model(name: str, args, log) -> dict:
    t_model = time.perf_counter()
    case = fm.make(name)
    out = {"name": name, "case": case, "n": case.n}
    kr, mr = case.diagonal_ratios()
    out.update(kr=kr, mr=mr)
    dt_exp, dt_imp = case.explicit_dt(), case.T1 / 50
    out.update(dt_exp=dt_exp, dt_imp=dt_imp)
    log(f"\n## {name}: {case.n} DOFs, built in {case.build_time:.1f} s; dt {dt_imp:.3g} s (Newmark), "
        f"{dt_exp:.3g} s (explicit)")

    t0 = time.perf_counter()
    model = nvib_model(case)
    out["setup_nvib"] = time.perf_counter() - t0
    linear = nvib_model(case, springs=False)

    # ---- explicit
    cd = nvib.CentralDifference()
    t0 = time.perf_counter()
    warning = nvib.stability.step_warning(model, cd, dt_exp)  # the first call's modal analysis, kept on the model
    out["check_nvib"] = time.perf_counter() - t0
    out["explicit_warning"] = warning
    t0 = time.perf_counter()
    mlu = fm.factorize(case.M)
    out["setup_scipy"] = time.perf_counter() - t0
    mass_r = case.M @ case.r
    variants = [("consistent", nvib_runner(model, cd, dt_exp),
                 lambda steps: (scipy_central_difference(case, dt_exp, steps, mlu.solve, mass_r), {}))]
    ml = lumped_mass(case)
    if ml is not None:
        # the lumped model's Rayleigh damping is that of its own mass, C = alpha diag(m) + beta K (the same
        # alpha and beta), assembled as an engineer does; nvib and SciPy get the same C
        lcase = lumped_case(case, ml)
        lumped_model = nvib_model(lcase, lumped=ml)
        nvib.stability.step_warning(lumped_model, cd, dt_exp)
        variants.append(("lumped", nvib_runner(lumped_model, cd, dt_exp),
                         lambda steps: (scipy_central_difference(lcase, dt_exp, steps, lambda f: f / ml, ml * lcase.r), {})))
    out["explicit"] = []
    for label, nv, sc in variants:
        cs = [Contender("nvib", nv, "nvib"), Contender("SciPy", sc, "scipy")]
        steps = race(cs, 20, args)
        row = dict(mass=label, steps=steps, nvib=cs[0], scipy=cs[1], agree=agreement(cs[0].u, cs[1].u))
        out["explicit"].append(row)
        log(f"explicit ({label}): {steps} steps, nvib {f_s(cs[0].best)} s, SciPy {f_s(cs[1].best)} s, "
            f"ratio {f_ratio(cs[1].best, cs[0].best)}, agreement {f_agree(row['agree'])}"
            + (f"; errors: {cs[0].error} {cs[1].error}" if cs[0].error or cs[1].error else ""))

    # ---- linear Newmark
    cs = [Contender("nvib", nvib_runner(linear, nvib.Newmark(), dt_imp), "nvib"),
          Contender("SciPy", lambda steps: (scipy_newmark_linear(case, dt_imp, steps, mlu.solve), {}), "scipy")]
    # a model above --big DOFs factorises for minutes (the 29,376-DOF block: 30 s SciPy, 100 s nvib)
    remaining = args.budget - (time.perf_counter() - args.t_start)
    if case.n > args.big and remaining <= 0:
        skip(cs, f"not run: the --budget of {args.budget:.0f} s is spent and the model has over {args.big} DOFs "
                 f"(its factorisations take minutes); --budget 3600 runs it")
        steps = 0
    else:
        steps = race(cs, 5, args)
    out["linear"] = dict(steps=steps, nvib=cs[0], scipy=cs[1], agree=agreement(cs[0].u, cs[1].u))
    if math.isfinite(cs[1].best) and cs[1].best < 10.0:
        t0 = time.perf_counter()
        u_eff = scipy_newmark_linear(case, dt_imp, steps, mlu.solve, form="effective")
        out["linear"].update(effective_time=time.perf_counter() - t0, effective_agree=agreement(u_eff, cs[0].u))
    else:
        out["linear"].update(effective_time=math.nan, effective_agree=math.nan)
    log(f"linear Newmark: {steps} steps, nvib {f_s(cs[0].best)} s, SciPy {f_s(cs[1].best)} s, "
        f"ratio {f_ratio(cs[1].best, cs[0].best)}, agreement {f_agree(out['linear']['agree'])}")

    # ---- Newmark + Newton
    loop_out = {}

    def loop(steps):
        u, iters, dmax = scipy_newmark_newton(case, dt_imp, steps, mlu.solve)
        loop_out.update(iters=iters, dmax=dmax)
        return u, {"iters": int(iters.sum()), "fact": int(iters.sum())}

    cs = [Contender("nvib", nvib_runner(model, nvib.Newmark(), dt_imp), "nvib"),
          Contender("SciPy", loop, "scipy"),
          Contender("nvib modified", nvib_runner(model, nvib.Newmark(newton=nvib.Newton(iteration="modified")),
                                                 dt_imp), "nvib")]
    # A step of full Newton costs about 4 factorisations; one linear run, about one (and its steps).
    fa, fb = out["linear"]["nvib"].best, out["linear"]["scipy"].best
    estimate = 4 * (fa + fb) + 1.5 * fa if math.isfinite(fa + fb) else math.inf
    remaining = args.budget - (time.perf_counter() - args.t_start)
    if estimate > 60.0 and estimate > remaining:
        note = (f"not run: one step would take about {estimate:.0f} s (4 factorisations each, from the linear "
                f"runs: nvib {fa:.0f} s, SciPy {fb:.0f} s), beyond what is left of --budget ({max(remaining, 0):.0f} "
                f"of {args.budget:.0f} s)" if math.isfinite(estimate) else
                f"not run: the --budget of {args.budget:.0f} s is spent and the model has over {args.big} DOFs; "
                "--budget 3600 runs it")
        skip(cs, note)
        steps = 0
    else:
        steps = race(cs, 1, args)
    ref = cs[1].u
    nl = dict(steps=steps, nvib=cs[0], scipy=cs[1], modified=cs[2], agree=agreement(cs[0].u, ref),
              agree_mod=agreement(cs[2].u, ref), loop_iters=loop_out.get("iters"))
    # how nonlinear: the same steps without the springs, and the springs' largest a d^2
    if ref is not None:
        lin = nvib.solve(linear, nvib.Newmark(), dt=dt_imp, t_end=steps * dt_imp, save_every=steps)
        nl["linear_diff"] = agreement(lin.u[-1], ref)
        nl["ad2"] = float(np.max(case.a * loop_out["dmax"] ** 2))
    out["newton"] = nl
    log(f"Newton: {steps} steps, nvib {f_s(cs[0].best)} s ({cs[0].info.get('iters')} it.), SciPy "
        f"{f_s(cs[1].best)} s ({cs[1].info.get('iters')} it.), modified {f_s(cs[2].best)} s "
        f"({cs[2].info.get('iters')} it.), ratio {f_ratio(cs[1].best, cs[0].best)}, agreement "
        f"{f_agree(nl['agree'])}, without springs {nl.get('linear_diff', math.nan):.2g}"
        + "".join(f"; {c.label}: {c.error}" for c in cs if c.error))

    # ---- per-step iterations (nvib stepped one at a time), for the analysis
    if cs[0].error is None and ref is not None and steps > 1 and not args.no_steps and cs[0].best < 30:
        st = nvib.Stepper(model, nvib.Newmark(), dt_imp)
        per, last = np.zeros(steps, dtype=int), 0
        for k in range(steps):
            st.step()
            it = st.stats.num_newton_iters
            per[k], last = it - last, it
        nl["nvib_iters"] = per
    out["wall"] = time.perf_counter() - t_model
    log(f"({name}: {out['wall']:.0f} s; {time.perf_counter() - args.t_start:.0f} s since the start)")
    return out


def explain(out: dict, args, log) -> list[str]:
    """Why nvib iterates more on this model: iterations per step, and the residuals of the step where
    nvib exceeds the loop most, nvib's against the loop's from the same state."""
    case, nl = out["case"], out["newton"]
    per, loop = nl.get("nvib_iters"), nl.get("loop_iters")
    if per is None or loop is None:
        return []
    dt = out["dt_imp"]
    lines = [f"### {out['name']}: nvib {int(per.sum())} iterations, the loop {int(loop.sum())}, over "
             f"{per.size} steps", ""]
    top = int(max(per.max(), loop.max()))
    lines += ["| iterations in a step | " + " | ".join(str(k) for k in range(1, top + 1)) + " |",
              "|---|" + "---:|" * top,
              "| steps, nvib | " + " | ".join(str(int(np.sum(per == k))) for k in range(1, top + 1)) + " |",
              "| steps, loop | " + " | ".join(str(int(np.sum(loop == k))) for k in range(1, top + 1)) + " |", ""]
    more, fewer = int(np.sum(per > loop)), int(np.sum(per < loop))
    lines.append(f"nvib iterates more than the loop on {more} steps, fewer on {fewer}, as often on "
                 f"{per.size - more - fewer}.")
    lines.append("")
    k = int(np.argmax((per - loop) * 1000 + per))  # the step (0-based) where nvib exceeds the loop most
    st = nvib.Stepper(nvib_model(case), nvib.Newmark(), dt)
    if k:
        st.step(k)
    state = (st.u.copy(), st.v.copy(), st.a.copy())
    t_before = st.t
    st.step()
    res = list(st.last_residuals)
    acc = st.accepted_residual
    trace: list = []
    scipy_newmark_newton(case, dt, 1, state=state, t0=t_before, trace=trace)  # from nvib's state: no M solve
    newton = nvib.Newton()
    # nvib's own force scale at its last iterate, from its accepted residual r / (scale + atol / rtol)
    scale_nvib = res[-1] / acc - newton.atol / newton.rtol if acc else math.nan
    lines.append(f"Step {k + 1} (t = {t_before + dt:.4g} s): nvib {len(res) - 1} iterations, the loop "
                 f"{len(trace) - 1}. Residuals max |r| in force units (r = M a + K u + C v + f_s + M r a_g at "
                 f"each iterate; the loop's recomputed by nvib's definition); nvib's tolerance is "
                 f"atol + rtol x scale = {newton.atol:g} + {newton.rtol:g} x {scale_nvib:.4g} = "
                 f"{newton.atol + newton.rtol * scale_nvib:.3g} (its accepted residual {acc:.3g} of the scale); "
                 f"the round-off bound 8 eps |terms| is recomputed in Python from the loop's iterates.")
    tol = newton.atol + newton.rtol * scale_nvib
    how = ("the plain test (max |r| <= tol)" if acc is not None and acc <= newton.rtol else
           "the round-off test (max |r| <= tol + its round-off bound, the increment settled below 1e-8 of u "
           "or the residual no longer falling)")
    lines.append(f"nvib accepted iterate {len(res) - 1} by {how}; the loop stops at the first increment "
                 f"below {LOOP_RTOL:g} of u.")
    lines += ["", "| k | nvib max \\|r_k\\| | loop max \\|r_k\\| | loop r_k / scale | round-off bound at iterate k "
              "(Python) | loop's increment of solve k, max \\|du_k\\| / max \\|u_k\\| |", "|---:|---:|---:|---:|---:|---:|"]
    loop_stop = next((i + 1 for i, row in enumerate(trace) if row.get("du", 1.0) <= LOOP_RTOL), None)
    for k in range(max(len(res), len(trace))):
        nv = f"{res[k]:.3e}" + (" (accepted)" if k == len(res) - 1 else "") if k < len(res) else "–"
        lp = rel = ro = "–"
        if k < len(trace):
            lp, rel, ro = f"{trace[k]['r']:.3e}", f"{trace[k]['r'] / trace[k]['scale']:.2e}", f"{trace[k]['roundoff']:.2e}"
        du = "–"
        if 1 <= k <= len(trace) and "du" in trace[k - 1]:
            du = f"{trace[k - 1]['du']:.2e}" + (" (stops)" if k == loop_stop else "")
        lines.append(f"| {k} | {nv} | {lp} | {rel} | {ro} | {du} |")
    lines.append(f"\nk = 0 is the predictor (u_n); nvib's tolerance here: {tol:.3g}.")
    floor = min(row["r"] for row in trace)
    if floor > tol:
        lines.append(f"The residual never goes below {floor:.3g} ({floor / tol:.3g} x nvib's tolerance, "
                     f"{floor / trace[-1]['scale']:.2g} of the force scale): the round-off of its evaluation; only "
                     "the round-off test can accept such a step.")
    within = next((j for j in range(1, min(len(res), len(trace))) if res[j] <= tol + trace[j]["roundoff"]), None)
    if within is not None and within < len(res) - 1:
        du = trace[within - 1].get("du", math.nan)
        lines.append(f"nvib's residual was within its tolerance plus the round-off bound (as recomputed here) "
                     f"from iterate {within} on; it went on because the increment that led there ({du:.2g} of u) "
                     f"was above 1e-8 of u and the residual was still falling: "
                     f"{len(res) - 1 - within} more iteration(s) than that test alone would take.")
    lines.append("")
    return lines


# ---------------------------------------------------------------- report

def tables(results: list[dict]) -> list[str]:
    L = ["## Models", "",
         "| model | kind | DOFs | nnz(K) | T1 [s] | omega_max / omega_1 | diag K max/min | diag M max/min | "
         "springs | dt Newmark [s] | dt explicit [s] | nvib `Model()` [s] | SciPy splu(M) [s] | what makes it hard |",
         "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|"]
    for o in results:
        c = o["case"]
        L.append(f"| {o['name']} | {c.kind} | {c.n} | {c.K.nnz} | {c.T1:.3g} | {c.omega_max / c.omega1:.3g} | "
                 f"{o['kr']:.2g} | {o['mr']:.2g} | {c.springs.size} | {o['dt_imp']:.3g} | {o['dt_exp']:.3g} | "
                 f"{o['setup_nvib']:.2f} | {o['setup_scipy']:.2f} | {c.hard} |")
    L += ["", "## Explicit: nvib CentralDifference against a scipy.sparse central-difference loop", "",
          "Ratio = SciPy time / nvib time (> 1: nvib faster; **bold** where nvib is slower). nvib's first "
          "explicit `solve()` on a model also runs its stability check (ARPACK for the top mode), shown apart "
          "and not in the times; the explicit step is 0.8 of the limit with the springs stiffened, and nvib's "
          "own check (`nvib.stability.step_warning`) found it stable unless said.", "",
          "| model | mass | dt [s] | steps | nvib [s] | SciPy [s] | nvib per step | SciPy per step | ratio | "
          "agreement | nvib stability check, 1st call [s] |", "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for o in results:
        for row in o["explicit"]:
            a, b = row["nvib"], row["scipy"]
            warn = " (nvib warns: above its limit)" if o["explicit_warning"] else ""
            err = failures(a, b)
            L.append(f"| {o['name']} | {row['mass']} | {o['dt_exp']:.3g}{warn} | {row['steps']} | {f_s(a.best)} | "
                     f"{f_s(b.best)} | {f_step(a.best, row['steps'])} | {f_step(b.best, row['steps'])} | "
                     f"{f_ratio(b.best, a.best)} | {f_agree(row['agree'])}{err} | "
                     f"{o['check_nvib']:.2f} |")
    L += ["", "## Linear Newmark (the models without their springs)", "",
          "nvib `Newmark()` on the linear model (one factorisation per run) against the loop that factorises "
          "the iteration matrix once and solves, every step, for the increment from the predictor u_n (the "
          "residual form, nvib's). Ratio = SciPy / nvib. The last column is the textbook effective-load form "
          "(u_{n+1} = S^-1 [P + M (c0 u + 4/dt v + a) + C (2/dt u + v)]), run once: cheaper by a product, but "
          "its round-off is relative to u rather than to the increment, and on ill-conditioned models it "
          "drifts further from both.", "",
          "| model | dt [s] | steps | nvib [s] | SciPy [s] | nvib per step | SciPy per step | ratio | "
          "nvib factorisations | nvib linear solver | agreement | effective-load form: [s] (one run), agreement "
          "with nvib |", "|---|---:|---:|---:|---:|---:|---:|---:|---:|---|---:|---:|"]
    for o in results:
        row = o["linear"]
        a, b = row["nvib"], row["scipy"]
        err = failures(a, b)
        L.append(f"| {o['name']} | {o['dt_imp']:.3g} | {row['steps']} | {f_s(a.best)} | {f_s(b.best)} | "
                 f"{f_step(a.best, row['steps'])} | {f_step(b.best, row['steps'])} | {f_ratio(b.best, a.best)} | "
                 f"{a.info.get('fact', '–')} | {a.info.get('solver', '–')} | {f_agree(row['agree'])}{err} | "
                 f"{f_s(row['effective_time'])}, {f_g(row['effective_agree'], '.1e')} |")
    L += ["", "## Newmark + full Newton", "",
          "nvib `Newmark()` (default Newton) and `Newmark(newton=Newton(iteration=\"modified\"))` against the "
          "plain SciPy loop (splu every iteration, stop at max |du| <= 1e-8 max |u|). Ratio = SciPy / nvib "
          "(> 1: nvib faster; **bold** where nvib is slower). Iterations: Newton iterations (linear solves) "
          "over the run; factorisations: nvib's counted ones (reused: an iteration matrix identical to the "
          "last, kept); the loop factorises at every iteration. Per iteration: wall time / iterations. "
          "Nonlinearity: max |u_without springs - u| / max |u| at the last step (nvib, same steps), and the "
          "springs' largest a d^2 over the run (the cubic term over the linear one).", "",
          "| model | dt [s] | steps | nvib [s] | SciPy [s] | ratio | nvib it. | loop it. | it. nvib / loop | "
          "nvib fact. (reused) | per it. nvib | per it. loop | nvib linear solver | agreement | "
          "without springs | max a d^2 (1 at the start) |",
          "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|---:|---:|---:|"]
    for o in results:
        row = o["newton"]
        a, b = row["nvib"], row["scipy"]
        ia, ib = a.info.get("iters"), b.info.get("iters")
        itr = f"{ia / ib:.2f}" if ia and ib else "–"
        if ia and ib and ia > ib:
            itr = f"**{itr}**"
        err = failures(a, b)
        L.append(f"| {o['name']} | {o['dt_imp']:.3g} | {row['steps']} | {f_s(a.best)} | {f_s(b.best)} | "
                 f"{f_ratio(b.best, a.best)} | {ia if ia is not None else '–'} | {ib if ib is not None else '–'} | "
                 f"{itr} | {a.info.get('fact', '–')} ({a.info.get('reused', '–')}) | "
                 f"{f_step(a.best, ia) if ia else '–'} | {f_step(b.best, ib) if ib else '–'} | "
                 f"{a.info.get('solver', '–')} | {f_agree(row['agree'])}{err} | "
                 f"{f_g(row.get('linear_diff'))} | {f_g(row.get('ad2'))} |")
    L += ["", "### Modified Newton", "",
          "nvib `Newmark(newton=Newton(iteration=\"modified\"))`: the tangent factorised once per step. Ratio = "
          "the full-Newton SciPy loop's time / this row's time.", "",
          "| model | steps | nvib modified [s] | ratio to the SciPy loop | ratio to nvib full Newton | iterations | "
          "factorisations (reused) | agreement with the loop |", "|---|---:|---:|---:|---:|---:|---:|---:|"]
    for o in results:
        row = o["newton"]
        m, a, b = row["modified"], row["nvib"], row["scipy"]
        err = failures(m)
        L.append(f"| {o['name']} | {row['steps']} | {f_s(m.best)} | {f_ratio(b.best, m.best)} | "
                 f"{f_ratio(a.best, m.best)} | {m.info.get('iters', '–')} | {m.info.get('fact', '–')} "
                 f"({m.info.get('reused', '–')}) | {f_agree(row['agree_mod'])}{err} |")
    return L


def summary(results: list[dict]) -> list[str]:
    L = ["## Where nvib stands", ""]

    def span(values):
        v = [x for x in values if math.isfinite(x)]
        return f"{min(v):.2f} to {max(v):.2f}" if v else "–"

    for title, get in (("explicit, consistent mass", lambda o: [r for r in o["explicit"] if r["mass"] == "consistent"]),
                       ("explicit, lumped mass", lambda o: [r for r in o["explicit"] if r["mass"] == "lumped"]),
                       ("linear Newmark", lambda o: [o["linear"]]),
                       ("Newmark + Newton", lambda o: [o["newton"]])):
        ratios, slower = [], []
        for o in results:
            for r in get(o):
                x = r["scipy"].best / r["nvib"].best
                ratios.append(x)
                if x < 1:
                    slower.append(f"{o['name']} ({x:.2f})")
        if ratios:
            L.append(f"- {title}: SciPy / nvib = {span(ratios)}" +
                     (f"; nvib is **slower** on {len(slower)} of {len(ratios)}: {', '.join(slower)}" if slower
                      else f"; nvib is faster on all {len(ratios)}"))
    more = [o for o in results if (o["newton"]["nvib"].info.get("iters") or 0) > (o["newton"]["scipy"].info.get("iters") or 1e18)]
    L.append(f"- Newton iterations: nvib makes more than the loop on {len(more)} of {len(results)} models"
             + (": " + ", ".join(f"{o['name']} ({o['newton']['nvib'].info['iters']} against "
                                 f"{o['newton']['scipy'].info['iters']})" for o in more) if more else ""))
    void = [o["name"] for o in results for r in [*o["explicit"], o["linear"], o["newton"]]
            if math.isfinite(r["agree"]) and r["agree"] > AGREEMENT]
    L.append(f"- agreement: every final displacement within {AGREEMENT:g} of the SciPy loop's" if not void else
             f"- agreement above {AGREEMENT:g} (comparison void) on: {', '.join(void)}")
    L.append("")
    return L


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 epilog=__doc__.split("\n\n", 1)[1], formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true", help=f"the small models only ({', '.join(fm.QUICK)}), "
                                                         "target 0.2 s, 2 rounds (under a minute)")
    ap.add_argument("--models", nargs="+", metavar="NAME", help=f"these models (of: {'; '.join(fm.MODELS)})")
    ap.add_argument("--out", default=os.path.join(HERE, "results", "fe_newton.md"), help="markdown file to write")
    ap.add_argument("--target", type=float, default=None, help="seconds the faster contender must take (0.5)")
    ap.add_argument("--rounds", type=int, default=None, help="interleaved rounds, best kept (3)")
    ap.add_argument("--max-run", type=float, default=None, help="cap on the slower contender's run when "
                                                                 "growing the step count (15 s; --quick 4 s)")
    ap.add_argument("--max-comparison", type=float, default=None,
                    help="no further round once a comparison's rounds have taken this long (15 s; --quick 4 s)")
    ap.add_argument("--big", type=int, default=20000,
                    help="models over this many DOFs get their linear and Newton comparisons only while the "
                         "--budget lasts (20000)")
    ap.add_argument("--no-steps", action="store_true", help="skip the per-step iteration counts")
    ap.add_argument("--budget", type=float, default=600.0,
                    help="seconds for the whole run: a Newton comparison whose estimated cost (from the linear "
                         "runs) exceeds what is left, and a minute, is not run but reported, and so are the linear "
                         "and Newton comparisons of a model over --big DOFs once it is spent (600; with 3600 the "
                         "29,376-DOF block's run too, 15 to 20 min more)")
    args = ap.parse_args(argv)
    if args.models:
        bad = [m for m in args.models if m not in fm.MODELS]
        if bad:
            ap.error(f"unknown model(s) {bad}; known: {list(fm.MODELS)}")
    names = args.models or (fm.QUICK if args.quick else list(fm.MODELS))
    args.target = args.target if args.target is not None else (0.2 if args.quick else 0.5)
    args.rounds = args.rounds if args.rounds is not None else (2 if args.quick else 3)
    args.max_comparison = args.max_comparison if args.max_comparison is not None else (4.0 if args.quick else 15.0)
    args.max_run = args.max_run if args.max_run is not None else (4.0 if args.quick else 15.0)

    from building import machine_info

    t_start = args.t_start = time.perf_counter()
    load_before = os.getloadavg()[0]
    head = ["# nvib against SciPy loops on generated finite-element models", "",
            "Written by `benchmarks/fe_newton.py " + " ".join(
                [a if a.startswith("-") or " " not in a else repr(a) for a in (argv if argv is not None else sys.argv[1:])
                 if a != "--out" and not a.endswith(".md")]) + "`.", ""]
    head += machine_info(os.environ.get("CXX", "g++"), load_before)
    core = [f for f in os.listdir(os.path.dirname(nvib.__file__)) if f.startswith("_core")]
    if core:
        built = datetime.datetime.fromtimestamp(os.path.getmtime(os.path.join(os.path.dirname(nvib.__file__), core[0])))
        head.append(f"- `nvib._core` installed {built.astimezone():%Y-%m-%d %H:%M %Z} (nvib is being reworked on this "
                    "machine: the numbers are those of that build)")
    head += [f"- the machine has {os.cpu_count()} logical CPUs and other work runs on it (another engineer "
             "builds and tests nvib on it): times vary from run to run; the rounds are interleaved (nvib, "
             "SciPy, nvib, SciPy, ...) and the best of each is kept, so compare the ratios of one run",
             f"- settings: target {args.target} s for the faster contender, up to {args.rounds} rounds, cap "
             f"{args.max_run} s a run while growing the steps, no further round once a comparison's rounds have "
             f"taken {args.max_comparison} s; budget {args.budget:.0f} s (models over {args.big} DOFs get their "
             f"linear and Newton comparisons only within it); the loop stops at max |du| <= {LOOP_RTOL:g} max |u|; SciPy factorises with `splu` in "
             "symmetric mode (MMD on A^T + A, no pivoting); single-threaded both (SuperLU and nvib's Eigen "
             "factorisations are sequential)", ""]
    print("\n".join(head), flush=True)
    results, notes = [], []

    def log(msg):
        print(msg, flush=True)

    def write(final: bool):
        body = head + tables(results) + [""] + summary(results) + notes
        if final:
            load_after = os.getloadavg()[0]
            body += ["", f"1-minute load average: {load_before:.2f} before, {load_after:.2f} after; the whole "
                         f"script took {time.perf_counter() - t_start:.0f} s "
                         f"({datetime.datetime.now().astimezone():%H:%M %Z})."]
        os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
        with open(args.out, "w", encoding="utf-8") as fh:
            fh.write("\n".join(body) + "\n")
        return body

    for name in names:
        o = run_model(name, args, log)
        results.append(o)
        write(False)

    notes += ["## Why nvib iterates more (or not)", "",
              "Both start each step from the same predictor (u_{n+1} = u_n) with the same full Newton, so "
              "their iterates agree to round-off; what differs is when they stop. nvib tests the residual "
              "(max |r| <= 1e-12 + 1e-10 x the step's force scale, or within its round-off bound once the "
              "increment has settled or the residual stops falling); the loop tests the increment "
              "(max |du| <= 1e-8 max |u|). Per-step iteration counts come from `nvib.Stepper` stepping the "
              "same run one step at a time.", ""]
    worst = sorted(results, key=lambda o: -((o["newton"]["nvib"].info.get("iters") or 0) /
                                            max(1, o["newton"]["scipy"].info.get("iters") or 1)))
    shown = [o for o in worst if (o["newton"]["nvib"].info.get("iters") or 0) >
             (o["newton"]["scipy"].info.get("iters") or 1e18)]
    if not shown:
        notes.append("nvib made no more Newton iterations than the loop on any model of this run; the models "
                     "where it comes closest, per step, and on each the step where nvib iterates most against "
                     "the loop:")
        notes.append("")
        shown = [o for o in worst if o["newton"].get("nvib_iters") is not None][:2]
    for o in shown:
        notes += explain(o, args, log)
    body = write(True)
    print("\n".join(body[len(head):]))
    print(f"\nwrote {os.path.relpath(args.out)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
