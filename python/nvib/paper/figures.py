"""The figures of ``nvib paper``: phase loci, histories, long runs, Table 1 and the eta study,
drawn on their own Agg canvases."""

from __future__ import annotations

import math

import numpy as np

from .cases import PAPER_ETA, Case, Setting, _fmt, _is_pendulum

def _color(label: str) -> str:
    """One colour per scheme in every figure (grey is left to the reference)."""
    order = ("LCDM", "LCDM (half-step v)", "CEMDTS", "Newmark (incremental)", "Newmark (one_iteration)",
             "Newmark (newton)", "GαM(0.5,0.5) (incremental)", "GαM(0.5,0.5) (one_iteration)",
             "GαM(0.5,0.5) (newton)", "PIM")
    colors = ("C0", "C1", "C2", "#8c0000", "C3", "C4", "#4d2600", "C5", "C6", "C9")
    for name, c in zip(order, colors):
        if label == name or (name == "CEMDTS" and label.startswith("CEMDTS")):
            return c
    return "C8"


def _figure(width: float, height: float):
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width, height), layout="constrained")
    FigureCanvasAgg(fig)
    return fig


def _axis_labels(s: Setting) -> tuple[str, str, float]:
    """Labels of the phase plane and the factor that scales the displacement axis."""
    if _is_pendulum(s.model):
        return "θ / π", "θ' [rad/s]", 1.0 / math.pi
    return f"{s.dof} [m]", f"{s.dof}' [m/s]", 1.0


def _grid(n: int, ncol: int | None = None, width: float = 4.2, height: float = 3.6):
    ncol = ncol or (4 if n <= 8 else 5 if n <= 10 else 6)
    nrow = math.ceil(n / ncol)
    fig = _figure(width * ncol, height * nrow + 0.7)
    return fig, [fig.add_subplot(nrow, ncol, k + 1) for k in range(n)]


def plot_phase(case: Case, s: Setting, rows: list[dict], runs: list, path: str) -> None:
    """One panel per scheme: the exact phase locus and the computed one, with the run's measures."""
    xlab, ylab, fx = _axis_labels(s)
    fig, axes = _grid(len(runs))
    for ax, row, res in zip(axes, rows, runs):
        ax.plot(s.orbit.u * fx, s.orbit.v, color="k", lw=3.0, alpha=0.25, label="exact")
        u, v = res.u[:, s.col], res.v[:, s.col]
        ax.plot(u * fx, v, color=_color(row["scheme"]), lw=0.9, marker="." if len(u) < 400 else None, ms=3)
        ax.plot([u[-1] * fx], [v[-1]], "s", color="k", ms=4)
        note = f"energy error {_fmt(row['energy_error'])}, locus error {_fmt(row['locus_error'])}"
        if row["t_over_the_top"] != "":
            note += f"\n|θ| > π at t = {row['t_over_the_top']:.4g} s; max |θ| = {row['max_abs_u'] / math.pi:.3g}π"
        ax.set_title(f"{row['scheme']}\n{note}", fontsize=8.5)
        ax.set_xlabel(xlab)
        ax.set_ylabel(ylab)
        ax.grid(True, alpha=0.3)
    fig.suptitle(f"{case.title}\nthick grey: exact phase locus ({s.ref.description}); black square: the state at "
                 f"the end", fontsize=11)
    fig.savefig(path, dpi=90)


def plot_history(case: Case, s: Setting, rows: list[dict], runs: list, path: str) -> None:
    """One panel per scheme (reference and computed displacement of one DOF), and |u - u_ref| of all on a log
    axis in the last panel."""
    fig, axes = _grid(len(runs) + 1, height=3.4)
    offset = float(s.model.u0[s.col])
    unit, factor = ("mm", 1e3) if s.model.scene["name"] == "vehicle" else ("m", 1.0)
    ylab = f"{s.dof}{' - static equilibrium' if offset != 0.0 else ''} [{unit}]"
    tt = np.linspace(0.0, s.t_end, 20001)
    u_ref = (s.ref.u(tt)[:, s.col] - offset) * factor
    peak = 0.0
    for ax, row, res in zip(axes, rows, runs):
        t, u = res.t, res.u[:, s.col]
        ax.plot(tt, u_ref, color="k", lw=2.5, alpha=0.3)
        ax.plot(t, (u - offset) * factor, color=_color(row["scheme"]), lw=0.8)
        ax.set_title(f"{row['scheme']}: error {_fmt(row['max_error'])}", fontsize=9)
        ax.set_xlabel("t [s]")
        ax.set_ylabel(ylab, fontsize=8)
        ax.grid(True, alpha=0.3)
        keep = t <= s.ref.t_end
        err = np.abs(u[keep] - s.ref.u(t[keep])[:, s.col]) * factor
        peak = max(peak, float(np.max(err)))
        axes[-1].semilogy(t[keep][1:], err[1:], color=_color(row["scheme"]), lw=0.7, label=row["scheme"])
    ax = axes[-1]
    ax.set_ylim(peak * 1e-7, peak * 3.0)
    ax.set_title("|u - reference|, colours as in the other panels", fontsize=9)
    ax.set_xlabel("t [s]")
    ax.set_ylabel(f"[{unit}]", fontsize=8)
    ax.grid(True, which="both", alpha=0.3)
    fig.suptitle(f"{case.title}\nthick grey: reference ({s.ref.description}); error: max |u - u_ref| / max |u_ref| "
                 f"over the run", fontsize=11)
    fig.savefig(path, dpi=90)


def plot_long(case: Case, s: Setting, rows: list[dict], runs: list, path: str) -> None:
    """Largest angle so far and the energy over a long run: where each scheme leaves the libration and how its
    energy drifts."""
    fig = _figure(12.0, 8.0)
    top, bottom = fig.subplots(2, 1, sharex=True)
    for k, (row, res) in enumerate(zip(rows, runs)):
        style = ("-", "--", "-.", ":")[k % 4]
        cross = "" if row["t_over_the_top"] == "" else f": |θ| > π at t = {row['t_over_the_top']:.4g} s"
        color = _color(row["scheme"])
        top.plot(res.t, np.maximum.accumulate(np.abs(res.u[:, s.col])) / math.pi, style, color=color, lw=1.2,
                 label=row["scheme"] + cross)
        e = res.energy.total
        bottom.plot(res.t, e / e[0], style, color=color, lw=0.8)
    top.axhline(1.0, color="k", lw=0.8)
    top.text(0.0, 1.0, " |θ| = π: over the top", fontsize=8, va="bottom")
    top.set_yscale("log")
    top.set_ylabel("largest |θ| so far / π")
    top.legend(fontsize=8, loc="upper left")
    top.grid(True, which="both", alpha=0.3)
    bottom.set_yscale("log")
    bottom.set_ylabel("E(t) / E(0)")
    bottom.set_xlabel("t [s]")
    bottom.grid(True, which="both", alpha=0.3)
    fig.suptitle(f"{case.title}\nexact: largest |θ| = π/3 and E(t) = E(0)", fontsize=11)
    fig.savefig(path, dpi=90)


# ---------------------------------------------------------------- the parts

def plot_eta(rows: list[dict], path: str) -> None:
    problems = list(dict.fromkeys(r["problem"] for r in rows))
    fig = _figure(15.0, 5.2)
    axes = fig.subplots(1, 3)
    measures = (("energy_error", "max relative energy error"), ("locus_error", "phase-locus error"),
                ("state_error", "state error (timing included)"))
    for ax, (key, name) in zip(axes, measures):
        for k, p in enumerate(problems):
            pr = [r for r in rows if r["problem"] == p]
            cem = sorted((r for r in pr if r["eta"] != ""), key=lambda r: r["eta"])
            ax.semilogy([r["eta"] for r in cem], [r[key] for r in cem], "o-", color=f"C{k}", ms=3, lw=1.2,
                        label=p)
            half = next(r for r in pr if r["variant"] == "LCDM (half-step v)")
            ax.axhline(half[key], color=f"C{k}", ls=":", lw=1.2)
        for eta, lab in ((1.0 / 12.0, "1/12"), (PAPER_ETA, "0.45 (paper)")):
            ax.axvline(eta, color="0.4", lw=0.8, ls="--")
            ax.text(eta, 1.0, f" η = {lab}", transform=ax.get_xaxis_transform(), fontsize=8, va="top")
        ax.set_xlabel("η")
        ax.set_title(name, fontsize=10)
        ax.grid(True, which="both", alpha=0.3)
    axes[0].legend(fontsize=8, loc="lower right")
    fig.suptitle("CEMDTS against η (η = 0 is LCDM with synchronized velocity; dotted: LCDM with half-step "
                 "velocity); references: closed forms", fontsize=11)
    fig.savefig(path, dpi=90)


def plot_table1(rows: list[dict], path: str) -> None:
    fig = _figure(9.0, 6.0)
    ax = fig.add_subplot()
    labels = list(dict.fromkeys(r["scheme"] for r in rows))
    for k, lab in enumerate(labels):
        rr = sorted((r for r in rows if r["scheme"] == lab), key=lambda r: r["dt"])
        # a marker and a dash per scheme: curves that coincide (LCDM and Newmark with Newton) stay visible
        ax.loglog([r["dt_over_tmin"] for r in rr], [r["energy_error"] for r in rr],
                  ("o", "s", "^", "v", "D", "P", "X", "<", ">", "*")[k % 10] + ("-", "--", "-.", ":")[k % 4],
                  color=_color(lab), lw=1.2, ms=6 if k % 2 else 4, mfc="none" if k % 2 else None, label=lab)
    ax.axvline(1.0 / 20.0, color="0.4", lw=0.8, ls="--")
    ax.text(1.0 / 20.0, 1.0, " Δt = Tmin/20", transform=ax.get_xaxis_transform(), fontsize=8, va="top")
    ax.set_xlabel("Δt / Tmin  (Tmin = 2π / 82.76 rad/s = 75.9 ms)")
    ax.set_ylabel("max relative energy error over 0.3 s")
    ax.set_title("Table 1: hardening oscillator, maximum relative energy error against the step")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.savefig(path, dpi=100)


