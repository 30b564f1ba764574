"""Linear stability of every scheme, measured on the steppers, against the closed forms.

For the linear SDOF u'' + 2 xi w u' + w^2 u = 0, nvib.stability builds each
scheme's amplification matrix by stepping the C++ stepper once from each unit
state (Omega = w dt), and from it the spectral radius, the period error and
damping ratio of the principal roots, and Omega_crit (smallest Omega with
spectral radius > 1 + 1e-6, scan and bisection up to 1e4).

Measured here, each against its closed form where one exists:
  * Omega_crit at xi = 0 and 0.05 for the central-difference family (LCDM,
    CEMDTS at several eta), Zhai (psi = phi = 1/2 and 0.6), Newmark (trapezoidal
    and linear acceleration), generalized-alpha and PIM;
  * the spectral radius at Omega = 1 (xi = 0.05) and at Omega = 1e4 (xi = 0);
  * the largest deviation from closed forms over grids of Omega: Hughes' Newmark
    matrix, the period error of central difference and of the trapezoidal rule,
    PIM's exp(-xi Omega), generalized-alpha's rho_inf;
  * the spectral radius of PIM (20 squarings) at very large Omega.
No timing: these are accuracy checks, so the numbers do not depend on the machine.

    PYTHONPATH=python python benchmarks/stability.py [--out benchmarks/results/stability.md]
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

import numpy as np

import nvib
from nvib import stability as stab

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
XI = 0.05


def zhai_limit(xi: float) -> float:
    """2(sqrt(1 + 4 xi^2) - 2 xi): Zhai(1/2, 1/2) with modal damping, where an eigenvalue of the
    amplification matrix passes through -1."""
    return 2.0 * (math.sqrt(1.0 + 4.0 * xi * xi) - 2.0 * xi)


def schemes() -> list[tuple[object, float | None, float | None]]:
    """(scheme, closed-form Omega_crit at xi = 0, at xi = XI); None where none is known."""
    cd = (2.0, zhai_limit(XI))  # u_{n+1} - 2u_n + u_{n-1} = dt^2 a_n, same velocity in the force: Zhai's recurrence
    return [
        (nvib.CentralDifference(), *cd),
        (nvib.CentralDifference(velocity="half_step"), *cd),
        (nvib.CEMDTS(0.0), *cd),
        (nvib.CEMDTS(1 / 12), *cd),
        (nvib.CEMDTS(0.25), *cd),
        (nvib.CEMDTS(0.45), *cd),
        (nvib.CEMDTS(0.5), *cd),
        (nvib.CEMDTS(1.0), *cd),
        (nvib.Zhai(0.5, 0.5), *cd),
        (nvib.Zhai(0.6, 0.6), math.sqrt(2.0 / 0.6), None),  # sqrt(2/p) for psi = phi = p > 1/2 (an eigenvalue at -1)
        (nvib.Newmark(0.25, 0.5), math.inf, math.inf),
        (nvib.Newmark(1 / 6, 0.5), math.sqrt(12.0), math.sqrt(12.0)),  # (gamma/2 - beta)^(-1/2), any xi at gamma = 1/2
        (nvib.GeneralizedAlpha(), math.inf, math.inf),
        (nvib.GeneralizedAlpha.from_rho_inf(0.8), math.inf, math.inf),
        (nvib.GeneralizedAlpha.hht(-0.1), math.inf, math.inf),
        (nvib.PreciseIntegration(), math.inf, math.inf),
    ]


def fmt(x: float | None, digits: int = 7) -> str:
    if x is None:
        return "-"
    if math.isinf(x):
        return "none" if x > 0 else "-inf"
    return f"{x:.{digits}g}"


def rel(a: float, b: float | None) -> str:
    if b is None:
        return "-"
    if math.isinf(a) and math.isinf(b):
        return "0"
    if math.isinf(a) or math.isinf(b):
        return "**differs**"
    return f"{abs(a - b) / b:.1e}"


def newmark_matrix(beta, gamma, om, xi):
    a1 = np.array([[1.0, 0.0, -beta], [0.0, 1.0, -gamma], [om * om, 2.0 * xi * om, 1.0]])
    a2 = np.array([[1.0, 1.0, 0.5 - beta], [0.0, 1.0, 1.0 - gamma], [0.0, 0.0, 0.0]])
    return np.linalg.solve(a1, a2)


def closed_form_checks() -> list[list[str]]:
    rows = []
    oms = np.geomspace(1e-2, 1e3, 41)
    dev = 0.0
    for beta, gamma in ((0.25, 0.5), (1 / 6, 0.5), (0.3025, 0.6)):
        for xi in (0.0, XI):
            for om in oms:
                A = stab.amplification_matrix(nvib.Newmark(beta, gamma), float(om), xi)
                ref = newmark_matrix(beta, gamma, om, xi)
                dev = max(dev, float(np.max(np.abs(A - ref)) / max(1.0, np.max(np.abs(ref)))))
    rows.append(["Newmark amplification matrix, (beta, gamma) = (1/4, 1/2), (1/6, 1/2), (0.3025, 0.6); "
                 "xi = 0, 0.05", "Hughes' A1^-1 A2 in (u, dt v, dt^2 a)", "Omega = 1e-2 .. 1e3 (41)",
                 f"{dev:.1e} (max abs / max(1, max abs entry))"])
    below = np.linspace(0.01, 1.99, 40)
    dev = max(float(np.max(np.abs(stab.period_error(s, below) - (below / np.arccos(1 - below**2 / 2) - 1))))
              for s in (nvib.CentralDifference(), nvib.CEMDTS(0.45), nvib.Zhai()))
    rows.append(["period error of LCDM, CEMDTS(0.45), Zhai(1/2, 1/2), xi = 0", "Omega/arccos(1 - Omega^2/2) - 1",
                 "Omega = 0.01 .. 1.99 (40)", f"{dev:.1e} (abs)"])
    pe = stab.period_error(nvib.Newmark(), oms)
    dev = float(np.max(np.abs(pe - (oms / (2 * np.arctan(oms / 2)) - 1)) / (oms / (2 * np.arctan(oms / 2)))))
    rows.append(["period error of Newmark(1/4, 1/2), xi = 0", "Omega/(2 arctan(Omega/2)) - 1",
                 "Omega = 1e-2 .. 1e3 (41)", f"{dev:.1e} (relative to T_bar/T)"])
    big = np.geomspace(1e-3, 1e4, 36)
    dev = float(np.max(np.abs(stab.spectral_radius(nvib.Newmark(), big) - 1.0)))
    rows.append(["spectral radius of Newmark(1/4, 1/2), xi = 0", "1", "Omega = 1e-3 .. 1e4 (36)", f"{dev:.1e} (abs)"])
    pim = nvib.PreciseIntegration()
    grid = np.geomspace(1e-2, 30.0, 25)
    dev = max(float(np.max(np.abs(stab.spectral_radius(pim, grid, xi) / np.exp(-xi * grid) - 1.0)))
              for xi in (0.0, XI, 0.2))
    rows.append(["spectral radius of PIM, xi = 0, 0.05, 0.2", "exp(-xi Omega)", "Omega = 1e-2 .. 30 (25)",
                 f"{dev:.1e} (relative)"])
    sub = grid[grid < 3.0]
    dev = max(max(float(np.max(np.abs(stab.period_error(pim, sub, xi)))),
                  float(np.max(np.abs(stab.damping_ratio(pim, sub, xi) - xi)))) for xi in (0.0, XI, 0.2))
    rows.append(["period error and damping ratio of PIM, xi = 0, 0.05, 0.2", "0 and xi", "Omega = 1e-2 .. 3",
                 f"{dev:.1e} (abs)"])
    for r in (0.0, 0.5, 0.8):
        rho = stab.spectral_radius(nvib.GeneralizedAlpha.from_rho_inf(r), [1e2, 1e4, 1e6])
        rows.append([f"spectral radius of GeneralizedAlpha.from_rho_inf({r:g})", f"rho_inf = {r:g} as Omega -> inf",
                     "Omega = 1e2, 1e4, 1e6", ", ".join(f"{x - r:+.1e}" for x in rho)])
    for xi in (XI, 0.1, 0.3):
        oc = stab.critical_omega_h(nvib.Zhai(), xi)
        rows.append([f"Omega_crit of Zhai(1/2, 1/2), xi = {xi:g}", f"2(sqrt(1+4xi^2) - 2xi) = {zhai_limit(xi):.9g}",
                     "scan + bisection", f"{oc:.9g} ({abs(oc - zhai_limit(xi)) / zhai_limit(xi):.1e} relative)"])
    return rows


def md_table(head: list[str], rows: list[list[str]], right: set[int] = frozenset()) -> list[str]:
    out = ["| " + " | ".join(head) + " |", "|" + "|".join("---:" if i in right else "---" for i in range(len(head))) + "|"]
    out += ["| " + " | ".join(r) + " |" for r in rows]
    return out


def git_rev() -> str:
    try:
        return subprocess.run(["git", "-C", ROOT, "describe", "--always", "--dirty"], capture_output=True,
                              text=True, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=os.path.join(HERE, "results", "stability.md"))
    args = ap.parse_args()
    t0 = time.perf_counter()
    folder = os.path.dirname(os.path.abspath(args.out))

    rows, worst = [], 0.0
    for scheme, ref0, ref1 in schemes():
        oc0 = stab.critical_omega_h(scheme, 0.0)
        oc1 = stab.critical_omega_h(scheme, XI)
        rho1 = stab.spectral_radius(scheme, 1.0, XI)
        rho_big = stab.spectral_radius(scheme, 1e4, 0.0)
        pe = stab.period_error(scheme, 0.5)
        zeta = stab.damping_ratio(scheme, 1.0)
        rows.append([stab.scheme_label(scheme), fmt(oc0), fmt(ref0), rel(oc0, ref0), fmt(oc1), fmt(ref1), rel(oc1, ref1),
                     fmt(rho1, 6), fmt(rho_big, 6), f"{pe:+.3e}", f"{zeta:.2e}"])
        for oc, ref in ((oc0, ref0), (oc1, ref1)):
            if ref is not None and math.isfinite(ref):
                worst = max(worst, abs(oc - ref) / ref)
            elif ref is not None and math.isfinite(oc):
                worst = math.inf  # a limit where none should be

    # which root leaves the unit circle first with damping (LCDM just past its limit)
    lcdm_crit = stab.critical_omega_h(nvib.CentralDifference(), XI)
    lam = np.linalg.eigvals(stab.amplification_matrix(nvib.CentralDifference(), lcdm_crit * 1.001, XI))
    top = lam[np.argmax(np.abs(lam))]
    principal = stab.principal_eigenvalue(nvib.CentralDifference(), lcdm_crit * 1.001, XI)
    # the paper's generalized-alpha: its spurious root at a few Omega, damped
    ga = nvib.GeneralizedAlpha()
    ga_spurious = []
    for om in (0.01, 1.0, 100.0):
        lam_ga = np.linalg.eigvals(stab.amplification_matrix(ga, om, XI))
        ga_spurious.append(lam_ga[np.argmin(np.abs(lam_ga.imag) + (np.abs(lam_ga.imag) > 0) * 1e9)])
    newmark_damped = stab.spectral_radius(nvib.Newmark(), 1e4, XI)

    pim = nvib.PreciseIntegration()
    pim_rho = stab.spectral_radius(pim, [1e3, 1e4, 1e5, 1e6, 3e6])
    pim_crit = stab.critical_omega_h(pim, 0.0, omega_max=1e7)

    plots = []
    for xi, name in ((0.0, "stability_xi0.png"), (XI, "stability_xi005.png")):
        chosen = [nvib.CentralDifference(), nvib.CEMDTS(0.45), nvib.Zhai(), nvib.Zhai(0.6, 0.6), nvib.Newmark(),
                  nvib.GeneralizedAlpha(), nvib.GeneralizedAlpha.from_rho_inf(0.8), nvib.PreciseIntegration()]
        stab.plot_spectral_radius(chosen, os.path.join(folder, name), xi=xi, omega_h=np.geomspace(1e-2, 1e3, 400))
        plots.append((xi, name))

    lines = [
        "# Linear stability of the schemes, measured on the steppers",
        "",
        f"- date: {datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC; nvib {nvib.__version__} "
        f"(git {git_rev()}); Python {platform.python_version()}, NumPy {np.__version__}",
        f"- produced by `benchmarks/stability.py` in {time.perf_counter() - t0:.1f} s (no timings below: "
        "accuracy only, machine-independent up to round-off)",
        "",
        "**What is measured.** For the linear SDOF u'' + 2ξω u' + ω² u = 0 (`Model([1], K=[[1]], C=[[2ξ]])`, "
        "Δt = Ω), `nvib.stability` steps each scheme's C++ stepper once from every unit state "
        "(`Stepper.set_state`) to get its amplification matrix, in the state (u, Δt v, Δt² a, history). "
        "The spectral radius ρ is the largest |λ| over all its eigenvalues (spurious ones too). "
        "Ω_crit is the smallest Ω with ρ > 1 + 1e-6 (a scan of 50 points per decade from 1e-3, then "
        "bisection to 1e-10; 'none' = stable up to Ω = 1e4). Period error T̄_d/T_d − 1 and damping ratio ξ̄ "
        "come from the principal root, continued from Ω → 0 (see the `nvib.stability` docstring).",
        "",
        "**Against what.** The closed forms: Ω_crit = 2 for the central-difference family undamped; "
        "2(√(1+4ξ²) − 2ξ) for Zhai(½, ½) with damping and √(2/p) for Zhai(p, p), p > ½ (each where an "
        "eigenvalue of the amplification matrix passes through −1); (γ/2 − β)^(−1/2) = √12 for Newmark "
        "linear acceleration (Hughes 2000, ch. 9; independent of ξ at γ = ½); none for the unconditionally "
        "stable ones. LCDM and CEMDTS share Zhai's damped limit: all "
        "three satisfy u_{n+1} − 2u_n + u_{n−1} = Δt² a_n and evaluate the force with the same velocity "
        "(u_{n+1} − u_n)/Δt + Δt a_n/2, so their displacement recurrences are one and the same.",
        "",
        f"## Ω_crit and spectral radius (ξ = 0 and ξ = {XI:g})",
        "",
    ]
    lines += md_table(["scheme", "Ω_crit ξ=0", "closed form", "rel. diff", f"Ω_crit ξ={XI:g}", "closed form",
                       "rel. diff", f"ρ(Ω=1) ξ={XI:g}", "ρ(Ω=1e4) ξ=0", "period error Ω=0.5 ξ=0",
                       "ξ̄ at Ω=1 ξ=0"], rows, right=set(range(1, 11)))
    lines += [
        "",
        "## Against closed forms over grids of Ω",
        "",
    ]
    lines += md_table(["quantity", "closed form", "Ω", "largest deviation"], closed_form_checks())
    lines += [
        "",
        "## Findings",
        "",
        f"- Largest relative difference between a measured Ω_crit and its closed form in the first table: "
        f"{worst:.1e} (the threshold ρ > 1 + 1e-6 moves each limit slightly upward).",
        f"- The central-difference family (LCDM, both velocity variants, and CEMDTS at every η tried) has the "
        f"same damped limit as Zhai(½, ½), {zhai_limit(XI):.6g} at ξ = {XI:g}, not the "
        f"2(√(1+ξ²) − ξ) = {2 * (math.sqrt(1 + XI**2) - XI):.6g} of central difference with a lagged velocity: "
        "nvib's LCDM evaluates damping forces with the predictor v_n + Δt a_n. Just past the limit "
        f"(Ω = 1.001 Ω_crit) the root of largest modulus of LCDM is λ = {top.real:.6g}{top.imag:+.2g}i, while "
        f"the principal pair {'has already split (real)' if np.isnan(principal) else f'is {principal:.4g}'}: "
        "with damping the instability is not a principal pair leaving the unit circle.",
        "- `GeneralizedAlpha()` (the paper's αm = αf = ½, β = ¼, γ = ½, = `from_rho_inf(1)`) has the real "
        "spurious root " + ", ".join(f"{z.real:.15g} (Ω = {o:g})" for z, o in zip(ga_spurious, (0.01, 1.0, 100.0)))
        + f" at ξ = {XI:g}, i.e. −αm/(1 − αm) = −1 whatever Ω and ξ: ρ ≡ 1 even with physical damping, so an "
        "error in the carried acceleration neither grows nor decays (it alternates in sign).",
        f"- The trapezoidal Newmark keeps ρ → 1 as Ω → ∞ even with damping: ρ(Ω = 1e4, ξ = {XI:g}) = "
        f"{newmark_damped:.8g}.",
        "- PIM with the default 20 squarings keeps ρ = 1 (ξ = 0) to round-off up to Ω = 1e3; beyond, its 2^N "
        "exponential (4th-order Taylor at Δt/2^20) loses accuracy: ρ(Ω) at ξ = 0 = "
        + ", ".join(f"{r:.10g} (Ω = {o:g})" for o, r in zip([1e3, 1e4, 1e5, 1e6, 3e6], pim_rho))
        + f"; searched up to 1e7 its Ω_crit is {pim_crit:.4g} (the exponential overflows). Models whose linear "
        "part has ω_max Δt ≳ 1e4 need more squarings.",
        "",
        "## Plots",
        "",
    ]
    for xi, name in plots:
        lines.append(f"![spectral radius, ξ = {xi:g}]({name})")
        lines.append("")
    lines.append(f"Spectral radius against Ω (log axis) at ξ = 0 and ξ = {XI:g}, as drawn by "
                 "`nvib stability --xi ... --plot`; dots mark Ω_crit.")
    text = "\n".join(lines) + "\n"
    with open(args.out, "w", encoding="utf-8") as fh:
        fh.write(text)
    print(text)
    print(f"wrote {args.out} and {', '.join(n for _, n in plots)}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
