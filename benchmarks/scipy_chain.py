"""nvib's fixed-step second-order schemes against SciPy's solve_ivp on one large case: the shear chain
``nvib.scenes.chain(n)`` (n = 10^4 storeys by default).

The chain: storey masses 1e5 kg, hardening storey springs k0 (1 + a d^2) d (k0 = 1e8 N/m, a = 10),
dampers c = 2 * 0.02 * sqrt(k0 m) on the drifts, ground acceleration 10 sin(pi t) m/s^2 on every DOF,
from rest, t_end = 2 s. Its linear highest frequency is omega_max = 2 sqrt(k0 / m) = 63 rad/s (the
central-difference limit 2 / omega_max = 0.032 s; the scene's suggested step is a fifth of it).

Contenders, each over a grid of steps or tolerances:
  * nvib: CentralDifference, CEMDTS(0.45) (explicit) and Newmark, GeneralizedAlpha (implicit, full
    Newton, sparse LDLT) at dt = T_s * 2^-k (T_s = the saving interval, 0.02 s) and, for the implicit
    ones, also at steps above T_s;
  * SciPy solve_ivp: RK45 and DOP853 (explicit), BDF (the analytic sparse Jacobian as a callable) and
    LSODA (the analytic Jacobian in banded storage, the state interleaved as [u1, v1, u2, v2, ...] so
    that the Jacobian has 3 sub- and 2 super-diagonals: LSODA's stiff mode takes a dense or a banded
    Jacobian, and a dense one would be a 2n x 2n array, 3.2 GB at n = 10^4) over rtol = 1e-3 ... 1e-8,
    atol = rtol * 1e-2 (m and m/s), t_eval = the saving times.
The right-hand side for SciPy calls ``model._core.force`` (the C++ force, no Python argument checks).

Error: on DOFs x1 and x<n>, max over the saving times of |u - u_ref| divided by that DOF's max |u_ref|,
the larger of the two. Reference: CentralDifference at a small step h, refined by halvings until its
estimated error 4/3 max|u_h - u_{h/2}| (Richardson, second order) is at least 100x below the smallest
error of any run (or until the next refinement would take longer than --ref-budget seconds).

Writes <out>/scipy_chain.md (machine, settings, equal-error table, every run) and <out>/scipy_chain.png
(error against wall time).

    /work/venv/bin/python benchmarks/scipy_chain.py [--n 10000] [--t-end 2] [--out benchmarks/results]
"""

from __future__ import annotations

import argparse
import datetime
import math
import os
import platform
import subprocess
import sys
import time

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import scipy  # noqa: E402
import scipy.sparse as sp  # noqa: E402
from scipy.integrate import solve_ivp  # noqa: E402

import nvib  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)

ETA = 0.45
RTOLS = [1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8]
ATOL_SCALE = 1e-2  # atol = rtol * 1e-2 (m for u, m/s for v)
TARGETS = [1e-2, 1e-4, 1e-6, 1e-8]
UNSTABLE = 1.0  # a run whose relative error exceeds this has gone unstable (not plotted)
EXPLICIT_K = range(-1, 10)   # dt = T_s * 2^-k: 0.04 (above the stability limit) ... T_s / 512
IMPLICIT_DT_FACTORS = [10, 5, 2, 1]  # dt = T_s * factor, then T_s * 2^-k
IMPLICIT_K = range(1, 6)

NVIB = {
    "nvib CentralDifference": (lambda: nvib.CentralDifference(), "explicit"),
    f"nvib CEMDTS({ETA})": (lambda: nvib.CEMDTS(ETA), "explicit"),
    "nvib Newmark (Newton)": (lambda: nvib.Newmark(), "implicit"),
    "nvib GeneralizedAlpha (Newton)": (lambda: nvib.GeneralizedAlpha(), "implicit"),
}
SCIPY = ["RK45", "DOP853", "BDF", "LSODA"]


# ---------------------------------------------------------------- machine

def machine_info() -> list[str]:
    cpu = "unknown"
    try:
        with open("/proc/cpuinfo") as fh:
            for line in fh:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    try:
        rev = subprocess.run(["git", "-C", ROOT, "describe", "--always", "--dirty"], capture_output=True,
                             text=True).stdout.strip() or "unknown"
    except OSError:
        rev = "unknown"
    return [
        f"- date: {datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC",
        f"- CPU: {cpu}, {os.cpu_count()} logical CPUs; {platform.system()} {platform.release()}",
        f"- nvib {nvib.__version__} (git {rev}), `nvib._core` from {os.path.dirname(nvib.__file__)}",
        f"- Python {platform.python_version()}, NumPy {np.__version__}, SciPy {scipy.__version__}, "
        f"Matplotlib {matplotlib.__version__}",
    ]


# ---------------------------------------------------------------- runs

def repeats_for(seconds: float) -> int:
    """Total runs: best of 3 below 2 s, of 2 below 10 s, one run above."""
    return 3 if seconds < 2.0 else 2 if seconds < 10.0 else 1


class Case:
    def __init__(self, n: int, t_end: float, t_save: float):
        self.model = nvib.scenes.chain(n)
        self.n = n
        self.t_end = t_end
        self.t_save = t_save
        self.n_save = int(round(t_end / t_save))
        self.t_eval = np.arange(self.n_save + 1) * t_save
        self.cols = [0, n - 1]
        self.dofs = [self.model.dofs[c] for c in self.cols]
        self.minv = 1.0 / np.asarray(self.model.mass_sparse.diagonal(), dtype=float)
        self.core = self.model._core

    # -- nvib
    def nvib_run(self, scheme, dt: float):
        if dt <= self.t_save:
            every = int(round(self.t_save / dt))
        else:
            every = 1
        t0 = time.perf_counter()
        res = nvib.solve(self.model, scheme, dt=dt, t_end=self.t_end, save_every=every, dofs=self.dofs,
                         throw=False)
        call = time.perf_counter() - t0
        return res, call

    def align(self, t: np.ndarray) -> np.ndarray:
        """Indices into the saving grid of the times t (which must lie on it)."""
        k = np.rint(t / self.t_save).astype(int)
        if np.max(np.abs(k * self.t_save - t)) > 1e-9 * max(1.0, self.t_end):
            raise RuntimeError("saved times off the saving grid")
        return k

    # -- SciPy, [u; v] order
    def rhs(self, t, y):
        n = self.n
        out = np.empty(2 * n)
        out[:n] = y[n:]
        out[n:] = -self.minv * self.core.force(y[:n], y[n:], t)
        return out

    def jac_sparse(self, t, y):
        n = self.n
        K, C = self.core.tangent_sparse(y[:n], y[n:], t)
        D = sp.diags(-self.minv)
        return sp.bmat([[None, sp.identity(n, format="csc")], [D @ K, D @ C]], format="csc")

    # -- SciPy, interleaved [u1, v1, u2, v2, ...] with a banded Jacobian (LSODA)
    def rhs_interleaved(self, t, z):
        u = np.ascontiguousarray(z[0::2])
        v = np.ascontiguousarray(z[1::2])
        out = np.empty(2 * self.n)
        out[0::2] = v
        out[1::2] = -self.minv * self.core.force(u, v, t)
        return out

    def _interleaved_coo(self, t, z):
        n = self.n
        J = self.jac_sparse(t, np.concatenate((z[0::2], z[1::2]))).tocoo()
        inv = np.empty(2 * n, dtype=np.int64)  # position in z of entry k of [u; v]
        inv[:n] = 2 * np.arange(n)
        inv[n:] = 2 * np.arange(n) + 1
        return inv[J.row], inv[J.col], J.data

    def bands(self) -> tuple[int, int]:
        r, c, _ = self._interleaved_coo(0.0, np.zeros(2 * self.n))
        return int(np.max(r - c)), int(np.max(c - r))

    def jac_banded(self, lband: int, uband: int):
        def jac(t, z):
            r, c, d = self._interleaved_coo(t, z)
            P = np.zeros((lband + uband + 1, 2 * self.n))
            np.add.at(P, (uband + r - c, c), d)
            return P
        return jac

    def scipy_run(self, method: str, rtol: float, bands):
        kw = dict(method=method, t_eval=self.t_eval, rtol=rtol, atol=rtol * ATOL_SCALE)
        rhs, y0 = self.rhs, np.zeros(2 * self.n)
        state_cols = self.cols
        if method == "BDF":
            kw["jac"] = self.jac_sparse
        elif method == "LSODA":
            lband, uband = bands
            rhs = self.rhs_interleaved
            kw.update(jac=self.jac_banded(lband, uband), lband=lband, uband=uband)
            state_cols = [2 * c for c in self.cols]
        t0 = time.perf_counter()
        sol = solve_ivp(rhs, (0.0, self.t_end), y0, **kw)
        call = time.perf_counter() - t0
        return sol, call, state_cols


def rel_error(u: np.ndarray, idx: np.ndarray, ref: np.ndarray) -> float:
    """max over DOFs of max_t |u - ref| / max_t |ref| (the DOF's own peak on the whole saving grid)."""
    peak = np.max(np.abs(ref), axis=0)
    return float(np.max(np.max(np.abs(u - ref[idx]), axis=0) / peak))


def fmt_dt(dt: float) -> str:
    return f"{dt:.4g}"


# ---------------------------------------------------------------- main

def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--n", type=int, default=10_000, help="storeys of the chain (default 10000)")
    p.add_argument("--t-end", type=float, default=2.0, help="end time [s] (default 2; rounded to the saving grid)")
    p.add_argument("--t-save", type=float, default=0.02, help="saving interval [s] (default 0.02)")
    p.add_argument("--out", default=os.path.join(HERE, "results"), help="output folder (default benchmarks/results)")
    p.add_argument("--max-run", type=float, default=120.0,
                   help="a contender whose single run takes longer skips its finer settings [s] (default 120)")
    p.add_argument("--ref-budget", type=float, default=150.0,
                   help="longest reference run allowed when refining the reference [s] (default 150)")
    args = p.parse_args(argv)
    t_start = time.perf_counter()
    load0 = os.getloadavg()[0]

    t_save = args.t_save
    t_end = round(args.t_end / t_save) * t_save
    case = Case(args.n, t_end, t_save)
    model = case.model
    n = case.n
    dt_scene = model.scene["dt"]
    m0, k0 = 1e5, 1e8
    omega_max = 2.0 * math.sqrt(k0 / m0)
    print(f"chain({n}), t_end = {t_end:g} s, scene dt = {dt_scene:.5g} s", flush=True)

    def divides(dt):
        q = t_end / dt
        return abs(q - round(q)) < 1e-9 * q

    # -- overhead of the checked force against the core's
    u = np.zeros(n)
    reps = 200
    t0 = time.perf_counter()
    for _ in range(reps):
        model.evaluate_force(u, u, 0.5)
    t_checked = (time.perf_counter() - t0) / reps
    t0 = time.perf_counter()
    for _ in range(reps):
        case.core.force(u, u, 0.5)
    t_core = (time.perf_counter() - t0) / reps
    t0 = time.perf_counter()
    for _ in range(reps):
        case.rhs(0.5, np.zeros(2 * n))
    t_rhs = (time.perf_counter() - t0) / reps

    rows: list[dict] = []

    # -- nvib
    for label, (make, kind) in NVIB.items():
        if kind == "explicit":
            dts = [t_save * 2.0 ** -k for k in EXPLICIT_K]
        else:
            dts = [t_save * f for f in IMPLICIT_DT_FACTORS] + [t_save * 2.0 ** -k for k in IMPLICIT_K]
        dts = [dt for dt in dts if divides(dt)]
        too_long = None
        for dt in dts:
            row = dict(contender=label, family="nvib", kind=kind, setting=f"dt = {fmt_dt(dt)}", dt=dt)
            if too_long is not None:
                row.update(status="skipped", note=f"a coarser step took {too_long:.0f} s > {args.max_run:g} s")
                rows.append(row)
                continue
            res, call = case.nvib_run(make(), dt)
            best_call, best_inner = call, res.stats.wall_time
            if res.success:
                for _ in range(repeats_for(call) - 1):
                    r2, c2 = case.nvib_run(make(), dt)
                    best_call, best_inner = min(best_call, c2), min(best_inner, r2.stats.wall_time)
            s = res.stats
            row.update(status=res.status.name, call=best_call, inner=best_inner, repeats=repeats_for(call) if res.success else 1,
                       steps=s.num_steps, force_evals=s.num_force_evals, tangent_evals=s.num_tangent_evals,
                       newton=s.num_newton_iters, factorizations=s.num_factorizations, solver=s.linear_solver,
                       t=np.asarray(res.t), u=np.asarray(res.u))
            if not res.success:
                row["note"] = f"{res.status.name} at t = {res.failure.t:.3g} s" if res.failure is not None else ""
            rows.append(row)
            print(f"{label:34s} dt={dt:.4g} {res.status.name} call {best_call:.3f} s (inner {best_inner:.3f})",
                  flush=True)
            if call > args.max_run:
                too_long = call

    # -- SciPy
    bands = case.bands()
    for method in SCIPY:
        too_long = None
        for rtol in RTOLS:
            row = dict(contender=f"SciPy {method}", family="scipy", kind=method, setting=f"rtol = {rtol:.0e}",
                       rtol=rtol)
            if too_long is not None:
                row.update(status="skipped", note=f"rtol {too_long[0]:.0e} took {too_long[1]:.0f} s > {args.max_run:g} s")
                rows.append(row)
                print(f"SciPy {method:8s} rtol={rtol:.0e} skipped", flush=True)
                continue
            sol, call, state_cols = case.scipy_run(method, rtol, bands)
            best = call
            ok = sol.status == 0 and sol.y.shape[1] == case.t_eval.size and np.all(np.isfinite(sol.y))
            nrep = repeats_for(call) if ok else 1
            for _ in range(nrep - 1):
                best = min(best, case.scipy_run(method, rtol, bands)[1])
            row.update(status="success" if ok else "failed", call=best, repeats=nrep, nfev=sol.nfev, njev=sol.njev,
                       nlu=sol.nlu, steps=None)
            if ok:
                row.update(t=np.asarray(sol.t), u=np.asarray(sol.y[state_cols].T))
            else:
                row["note"] = str(sol.message)
            rows.append(row)
            print(f"SciPy {method:8s} rtol={rtol:.0e} call {best:.3f} s nfev {sol.nfev} njev {sol.njev} "
                  f"nlu {sol.nlu}", flush=True)
            if call > args.max_run:
                too_long = (rtol, call)

    # -- reference: CentralDifference at h and h/2, refined until 100 x its estimated error is below every error
    ref_runs: dict[int, dict] = {}

    def ref_run(level: int) -> dict:  # h = t_save * 2^-level
        if level not in ref_runs:
            h = t_save * 2.0 ** -level
            res, call = case.nvib_run(nvib.CentralDifference(), h)
            if not res.success:
                raise RuntimeError(f"reference run at h = {h:g} failed: {res.status}")
            case.align(np.asarray(res.t))
            ref_runs[level] = dict(h=h, u=np.asarray(res.u), call=call, steps=res.stats.num_steps)
            print(f"reference CentralDifference h = {h:.4g} s: {res.stats.num_steps} steps, {call:.1f} s", flush=True)
        return ref_runs[level]

    def est_error(level: int) -> float:
        a, b = ref_run(level)["u"], ref_run(level + 1)["u"]
        peak = np.max(np.abs(b), axis=0)
        return float(4.0 / 3.0 * np.max(np.max(np.abs(a - b), axis=0) / peak))

    def compute_errors(ref: np.ndarray) -> float:
        smallest = math.inf
        for row in rows:
            if "u" in row:
                idx = case.align(row["t"])
                row["error"] = rel_error(row["u"], idx, ref)
                if np.isfinite(row["error"]):
                    smallest = min(smallest, row["error"])
        return smallest

    level = max(EXPLICIT_K) + 2  # two halvings below the finest run's step
    while True:
        est = est_error(level)
        smallest = compute_errors(ref_run(level)["u"])
        print(f"reference level {level}: est. error {est:.2e}, smallest run error {smallest:.2e}", flush=True)
        if 100.0 * est <= smallest:
            ref_ok = True
            break
        if ref_run(level + 1)["call"] * 2.0 > args.ref_budget:
            ref_ok = False
            break
        level += 1
    ref = ref_run(level)
    ref_est = est
    diffs = []  # max relative differences between successive reference levels (ratio ~4 if asymptotic)
    lv = sorted(ref_runs)
    for a, b in zip(lv, lv[1:]):
        peak = np.max(np.abs(ref_runs[b]["u"]), axis=0)
        diffs.append((ref_runs[a]["h"], float(np.max(np.max(np.abs(ref_runs[a]["u"] - ref_runs[b]["u"]), axis=0) / peak))))
    floor = 100.0 * ref_est
    # the top storey before the wave from the base arrives: rigid, u = -(A / w^2)(w t - sin w t)
    A, w = 10.0, math.pi
    exact_top = -(A / w ** 2) * (w * case.t_eval - np.sin(w * case.t_eval))
    top_dev = float(np.max(np.abs(ref["u"][:, 1] - exact_top)) / np.max(np.abs(exact_top)))
    ref_peaks = np.max(np.abs(ref["u"]), axis=0)

    # -- equal-error table
    contenders = list(NVIB) + [f"SciPy {m}" for m in SCIPY]

    def cheapest(label, target):
        ok = [r for r in rows if r["contender"] == label and r.get("status") == "success"
              and r.get("error", math.inf) <= target]
        return min(ok, key=lambda r: r["call"]) if ok else None

    eq_lines = ["| target error | contender | cheapest run reaching it | error | wall time [s] | "
                "x the fastest nvib run |", "|---:|---|---|---:|---:|---:|"]
    summary = []
    for target in TARGETS:
        best = {c: cheapest(c, target) for c in contenders}
        nv = [best[c] for c in NVIB if best[c] is not None]
        sc = [best[c] for c in contenders if c.startswith("SciPy") and best[c] is not None]
        bn = min(nv, key=lambda r: r["call"]) if nv else None
        bs = min(sc, key=lambda r: r["call"]) if sc else None
        for c in contenders:
            r = best[c]
            if r is None:
                eq_lines.append(f"| {target:.0e} | {c} | not reached in its grid | | | |")
            else:
                ratio = f"{r['call'] / bn['call']:.2f}" if bn else ""
                eq_lines.append(f"| {target:.0e} | {c} | {r['setting']} | {r['error']:.2e} | {r['call']:.3f} | {ratio} |")
        summary.append((target, bn, bs))
    eq_lines.append("")
    eq_lines.append("| target error | fastest nvib | fastest SciPy | SciPy / nvib |")
    eq_lines.append("|---:|---|---|---:|")
    for target, bn, bs in summary:
        def d(r):
            return f"{r['contender']}, {r['setting']}: {r['call']:.3f} s" if r else "none reaches it"
        ratio = f"**{bs['call'] / bn['call']:.1f}**" if bn and bs else "—"
        eq_lines.append(f"| {target:.0e} | {d(bn)} | {d(bs)} | {ratio} |")

    # -- plot
    def plotted(r):
        return r.get("status") == "success" and np.isfinite(r.get("error", np.nan)) and r["error"] <= UNSTABLE

    fig, ax = plt.subplots(figsize=(10.5, 6.0))
    styles = {
        "nvib CentralDifference": ("C0", "o", "-"), f"nvib CEMDTS({ETA})": ("C1", "s", "-"),
        "nvib Newmark (Newton)": ("C2", "^", "-"), "nvib GeneralizedAlpha (Newton)": ("C3", "v", "-"),
        "SciPy RK45": ("C4", "D", "--"), "SciPy DOP853": ("C5", "P", "--"), "SciPy BDF": ("C6", "X", "--"),
        "SciPy LSODA": ("C7", "*", "--"),
    }
    for c in contenders:  # in the order of the grid (dt, rtol from coarse to fine), as run
        pts = [(r["call"], r["error"]) for r in rows if r["contender"] == c and plotted(r)]
        if not pts:
            continue
        col, mk, ls = styles[c]
        ax.loglog([q[0] for q in pts], [q[1] for q in pts], ls, color=col, marker=mk, ms=6, lw=1.5, label=c)
    ax.axhline(floor, color="0.5", lw=0.8, ls=":", label=f"100 x reference error ({floor:.0e})")
    for target in TARGETS:
        ax.axhline(target, color="0.85", lw=0.6, zorder=0)
    hidden = [r for r in rows if r.get("status") not in (None, "skipped") and not plotted(r)]
    if hidden:
        ax.text(0.01, 0.01, "not shown (unstable: diverged or error > 1): " + "; ".join(
            f"{r['contender'].replace('nvib ', '')} {r['setting']}" for r in hidden),
            transform=ax.transAxes, fontsize=8, color="0.3", va="bottom", ha="left")
    ax.set_xlabel("wall time of the whole call, nvib.solve / solve_ivp [s]")
    ax.set_ylabel("max relative error in u on x1 and x%d [-]" % n)
    ax.set_title(f"chain({n}), t_end = {t_end:g} s: error against wall time")
    ax.grid(True, which="major", alpha=0.3)
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=9, frameon=False)
    fig.tight_layout()
    os.makedirs(args.out, exist_ok=True)
    png = os.path.join(args.out, "scipy_chain.png")
    fig.savefig(png, dpi=130)
    plt.close(fig)

    # -- run table
    run_lines = ["| contender | setting | status | error | wall time, call [s] | nvib stats.wall_time [s] | runs | "
                 "steps | force evals (nfev) | Jacobians (njev / tangents) | LU (nlu / factorizations) | Newton it. | note |",
                 "|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|"]
    for r in rows:
        def g(key, f="{}"):
            v = r.get(key)
            return "" if v is None else f.format(v)
        err = r.get("error")
        err_s = "" if err is None else (f"{err:.2e}" if np.isfinite(err) else "inf")
        if err is not None and np.isfinite(err) and err < floor:
            err_s += " ‡"
        if r["family"] == "nvib":
            jac, lu, newton = g("tangent_evals"), g("factorizations"), g("newton")
            fe = g("force_evals")
        else:
            jac, lu, newton, fe = g("njev"), g("nlu"), "", g("nfev")
        note = r.get("note", "")
        if err is not None and r.get("status") == "success" and not err <= UNSTABLE:
            note = (note + "; " if note else "") + "unstable: error > 1 (not plotted)"
        run_lines.append(f"| {r['contender']} | {r['setting']} | {r.get('status', '')} | {err_s} | {g('call', '{:.4f}')} | "
                         f"{g('inner', '{:.4f}')} | {g('repeats')} | {g('steps')} | {fe} | {jac} | {lu} | {newton} | "
                         f"{note} |")

    # -- where the fixed-step scheme wins, from the numbers
    def at(target):
        return next(s for s in summary if s[0] == target)

    points = []
    for target, bn, bs in summary:
        if bn and bs:
            who = "nvib" if bn["call"] < bs["call"] else "SciPy"
            points.append(f"- at {target:.0e}: fastest nvib {bn['contender']} ({bn['setting']}, {bn['call']:.3f} s), "
                          f"fastest SciPy {bs['contender']} ({bs['setting']}, {bs['call']:.3f} s): "
                          f"**{who}** faster, SciPy / nvib = {bs['call'] / bn['call']:.2f}")
        elif bn:
            points.append(f"- at {target:.0e}: only nvib reaches it in these grids ({bn['contender']}, {bn['setting']})")
        elif bs:
            points.append(f"- at {target:.0e}: only SciPy reaches it in these grids ({bs['contender']}, {bs['setting']})")
        else:
            points.append(f"- at {target:.0e}: no run reaches it")
    cd = [r for r in rows if r["contender"] == "nvib CentralDifference"]
    cd_div = [r for r in cd if r.get("status") not in ("success", "skipped")]
    cd_ok = [r for r in cd if r.get("status") == "success"]
    rk = {m: [r for r in rows if r["contender"] == f"SciPy {m}" and r.get("status") == "success"] for m in SCIPY}

    def nfev_range(m):
        v = [r["nfev"] for r in rk[m]]
        return f"{min(v)}–{max(v)}" if v else "—"

    def err_range(m):
        v = [r["error"] for r in rk[m]]
        return f"{max(v):.1e} (rtol 1e-3) to {min(v):.1e}" if v else "—"

    us_per_step = [1e6 * r["inner"] / r["steps"] for r in cd_ok if r["steps"] >= 1000]

    total = time.perf_counter() - t_start
    load1 = os.getloadavg()[0]

    md = []
    md.append(f"# nvib against SciPy solve_ivp on a {n}-storey shear chain\n")
    md += machine_info()
    md.append(f"- 1-minute load average: {load0:.2f} at the start, {load1:.2f} at the end (2 cores, shared with "
              "other work: best-of-N timings, quote ratios rather than lone times); whole script "
              f"{total / 60:.1f} min")
    md.append("")
    md.append("Written by `benchmarks/scipy_chain.py` "
              f"(`/work/venv/bin/python benchmarks/scipy_chain.py --n {n} --t-end {args.t_end:g}`).\n")
    md.append("## Case\n")
    md.append(f"`nvib.scenes.chain({n})`: {n} storeys of 1e5 kg, hardening storey springs k0 (1 + a d²) d "
              f"(k0 = 1e8 N/m, a = 10), dampers c = 2·0.02·√(k0 m) on the drifts, ground acceleration "
              f"10 sin(πt) m/s² on every DOF, from rest, t_end = {t_end:g} s. Linear highest frequency "
              f"ω_max = 2√(k0/m) = {omega_max:.1f} rad/s: the central-difference limit is 2/ω_max = "
              f"{2 / omega_max:.4f} s, the scene's suggested step `model.scene['dt']` = {dt_scene:.5f} s (a fifth "
              "of it). In 2 s the disturbance from the base travels about √(k0/m)·t ≈ "
              f"{math.sqrt(k0 / m0) * t_end:.0f} storeys; the storeys above move rigidly with −(A/ω²)(ωt − sin ωt). "
              f"Peaks of the reference: |x1| = {ref_peaks[0]:.4f} m, |x{n}| = {ref_peaks[1]:.4f} m.\n")
    md.append(f"**Error**: on x1 and x{n}, saved every T_s = {t_save:g} s ({case.n_save + 1} times, t = 0 included; "
              f"runs with dt > T_s only at their own steps, which lie on that grid), "
              f"max over the times of |u − u_ref| divided by that DOF's own max |u_ref|; the larger of the two. "
              "(Relative to each DOF's peak, not to the overall max |u_ref| = the rigid top's 6.4 m, which would "
              "make x1's error look 36x smaller.)\n")
    md.append("**Reference**: " + (
        f"nvib CentralDifference at h = T_s/2^{level} = {ref['h']:.4g} s ({ref['steps']} steps, {ref['call']:.1f} s). "
        f"Estimated error 4/3 · max|u_h − u_(h/2)| (Richardson, second order; the run at h/2 took "
        f"{ref_runs[level + 1]['call']:.1f} s) = **{ref_est:.1e}**; smallest error of any run "
        f"{smallest:.1e}, " + (f"so the reference is {smallest / ref_est:.0f}x below it (>= 100x required)."
                               if ref_ok else
                               f"so NOT 100x below it: errors below {floor:.1e} are marked ‡ (not resolved)."))
              + " Successive refinements: " + ", ".join(f"h = {h:.3g} s → max rel. diff to h/2 {d:.2e}"
                                                        for h, d in diffs)
              + (f" (ratios {', '.join(f'{a / b:.2f}' for (_, a), (_, b) in zip(diffs, diffs[1:]))}: second-order, "
                 "as assumed)." if len(diffs) > 1 else ".")
              + f" Check: x{n} of the reference against the rigid closed form: max deviation {top_dev:.1e} relative.\n")
    md.append("**Contenders** (each run from Python, timed around the whole call; nvib's `stats.wall_time` is "
              "its C++ loop alone):\n")
    md.append(f"- nvib CentralDifference and CEMDTS({ETA}) (explicit, one force evaluation per step) at dt = "
              f"{fmt_dt(t_save * 2)} … {fmt_dt(t_save * 2.0 ** -max(EXPLICIT_K))} s by halvings (the first is above "
              "the stability limit); Newmark (β = 1/4, γ = 1/2) and GeneralizedAlpha (α_m = α_f = 1/2), full "
              "Newton (nvib's defaults: rtol 1e-10), sparse LDLT, at dt = "
              + ", ".join(fmt_dt(t_save * f) for f in IMPLICIT_DT_FACTORS) + ", then halvings down to "
              + f"{fmt_dt(t_save * 2.0 ** -max(IMPLICIT_K))} s. `save_every` = T_s/dt, `dofs` = x1, x{n}.")
    md.append(f"- SciPy `solve_ivp` on y = [u; v], y' = [v; −M⁻¹(K u + C v + F(u, v, t))], rtol = "
              f"{RTOLS[0]:.0e} … {RTOLS[-1]:.0e}, atol = rtol·{ATOL_SCALE:g} (m, m/s), `t_eval` = the saving times, "
              "`first_step` default. The right-hand side calls `model._core.force` (the C++ force, "
              f"{1e6 * t_core:.0f} µs per call at n = {n}; `model.evaluate_force`, which checks its arguments in "
              f"Python first, takes {1e6 * t_checked:.0f} µs; the whole right-hand side {1e6 * t_rhs:.0f} µs). "
              "RK45, DOP853: explicit, no Jacobian. BDF: `jac` = the analytic Jacobian "
              "[[0, I], [−M⁻¹K_t, −M⁻¹C_t]] as a scipy.sparse CSC matrix (from `tangent_sparse`, assembled with "
              f"`scipy.sparse.bmat`; SciPy factorises it with SuperLU). LSODA: its stiff mode takes a dense or a "
              f"banded Jacobian only (a dense one: a {2 * n} x {2 * n} array, {8 * (2 * n) ** 2 / 1e9:.1f} GB), so the "
              f"state is interleaved as [u1, v1, u2, v2, …] and the same analytic Jacobian handed over in banded "
              f"storage (lband = {bands[0]}, uband = {bands[1]}).")
    md.append(f"- Timing: best of 3 runs below 2 s, of 2 below 10 s, one run above; a contender whose single run "
              f"exceeds {args.max_run:g} s skips its finer settings (listed as skipped).\n")
    md.append("## Equal error\n")
    md.append("The cheapest run of each contender whose error is at most the target (whole-call wall time); "
              "last column: its time over the fastest nvib run's time at that target.\n")
    md += eq_lines
    md.append("")
    md.append("## Where the fixed-step second-order scheme wins, and where it does not\n")
    md += points
    md.append("")
    md.append(WHERE_TEXT.format(
        n=n, cd_us=(f"{np.median(us_per_step):.0f}" if us_per_step else "?"),
        cd_div=(", ".join(f"dt = {fmt_dt(r['dt'])}" for r in cd_div) or "none"),
        rk45_nfev=nfev_range("RK45"), rk45_err=err_range("RK45"),
        dop_nfev=nfev_range("DOP853"), dop_err=err_range("DOP853"),
        rhs_us=f"{1e6 * t_rhs:.0f}", lsoda_err=err_range("LSODA"), bdf_err=err_range("BDF")))
    md.append("")
    md.append(f"![error against wall time](scipy_chain.png)\n")
    md.append("## Every run\n")
    md.append("‡: below 100x the reference's estimated error (not resolved). nvib: force evals, tangents, "
              "factorizations and Newton iterations from `stats`; SciPy: nfev, njev, nlu. Status `diverged`: "
              "nvib stopped the run (|u| beyond its bound).\n")
    md += run_lines
    md.append("")
    mdpath = os.path.join(args.out, "scipy_chain.md")
    with open(mdpath, "w") as fh:
        fh.write("\n".join(md))
    print(f"wrote {mdpath} and {png} in {total / 60:.1f} min", flush=True)
    return 0


WHERE_TEXT = """\
In words (numbers above from this run):

- **The fixed-step scheme wins at engineering accuracies.** Central difference makes one C++ force evaluation per \
step and nothing else ({cd_us} µs per step at n = {n}, inside the C++ loop); the SciPy methods pay \
Python and NumPy work on 2n-vectors at every stage (the right-hand side alone costs {rhs_us} µs), error \
control, dense output for `t_eval`, and for BDF/LSODA Jacobians and LU factorisations. Where an error \
of 1e-2 to 1e-6 suffices, a second-order step near the scene's dt is already that accurate on this smooth \
response, and the equal-error ratios above are in nvib's favour.
- **The explicit schemes are stuck below the stability limit.** Central difference diverges above \
2/ω_max (here: {cd_div}), whatever the accuracy needed; so do RK45 and DOP853 in their own way: their \
steps are capped by the highest frequency of the chain, not by the tolerance — RK45 spends \
{rk45_nfev} right-hand sides over all tolerances (error {rk45_err}), DOP853 {dop_nfev} ({dop_err}). \
At loose tolerances they do not get cheaper, and their error stays well above rtol at rtol 1e-3.
- **The implicit ones are not faster here.** Newmark and generalized-α are unconditionally stable, but \
each step costs Newton iterations with a sparse factorisation of a 10^4 system, and a step much above \
the explicit limit gives up accuracy (the response itself has the chain's frequencies in it); on this \
case they lose to the central difference at every error level. They and BDF/LSODA would pay off only on \
a problem where the stiff modes carry no response (much larger ω_max t_end than 2 x 63).
- **Where it does not win: tight tolerances.** The error of a second-order scheme falls as dt², so each \
extra digit costs √10 ≈ 3.2x more steps; a variable-order method (LSODA, BDF up to order 5) or an \
8th-order one (DOP853) gains digits much more cheaply. At the tightest target the high-order/adaptive \
methods close the gap or win (LSODA's errors: {lsoda_err}; BDF's: {bdf_err}): see the last rows of \
the equal-error table.
"""


if __name__ == "__main__":
    sys.exit(main())
