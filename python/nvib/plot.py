"""Plots of runs (PNG, SVG or PDF via matplotlib, imported only when a plot is made).

``plot_run(result, model, dof, path)`` draws the displacement histories, the
phase locus of one DOF and, when the run recorded energy, the energy terms.
The figures are drawn on their own Agg canvas: no pyplot state is touched,
so this works the same in scripts, servers and notebooks.
"""

from __future__ import annotations

import numpy as np

from . import _checks

MAX_POINTS = 50_000  # per curve; longer histories are thinned evenly (always keeping the last point)
MAX_OTHER_DOFS = 4   # beside the highlighted DOF when a model has more than MAX_ALL_DOFS
MAX_ALL_DOFS = 6


def _new_figure(ncols: int, split_first: bool, width: float = 5.6, height: float = 4.8):
    """Figure on its own Agg canvas; the first column is split in two rows when asked."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width * ncols, height), layout="constrained")
    FigureCanvasAgg(fig)
    gs = fig.add_gridspec(2, ncols)
    if split_first:
        top = fig.add_subplot(gs[0, 0])
        first = [top, fig.add_subplot(gs[1, 0], sharex=top)]
    else:
        first = [fig.add_subplot(gs[:, 0])]
    return fig, first, [fig.add_subplot(gs[:, j]) for j in range(1, ncols)]


def _thin(n: int, max_points: int = MAX_POINTS) -> slice | np.ndarray:
    if n <= max_points:
        return slice(None)
    idx = np.arange(0, n, int(np.ceil(n / max_points)))
    return idx if idx[-1] == n - 1 else np.append(idx, n - 1)


def _dof_column(result, model, dof) -> int:
    """Column of ``dof`` (a name or a model index) in the result's saved DOFs."""
    names = list(result.dofs)
    if isinstance(dof, (int, np.integer)) and not isinstance(dof, bool):
        if not 0 <= int(dof) < model.n:
            raise _checks.value_error("dof", f"index {dof} is out of range for {model.n} degrees of freedom")
        dof = model.dofs[int(dof)]
    if dof not in names:
        where = "the model" if dof not in model.dofs else "the saved DOFs of this result"
        raise _checks.value_error("dof", f"{dof!r} is not in {where} (saved: {', '.join(names)})")
    return names.index(dof)


def shown_dofs(result, column: int, max_others: int = MAX_OTHER_DOFS) -> list[int]:
    """Columns to draw: all of them for small models; otherwise ``column`` and the
    ``max_others`` others that move most (largest peak-to-peak displacement), in model order."""
    m = result.u.shape[1]
    if m <= MAX_ALL_DOFS:
        return list(range(m))
    u = result.u
    with np.errstate(invalid="ignore", over="ignore"):
        span = np.where(np.all(np.isfinite(u), axis=0), np.ptp(u, axis=0) if len(u) else 0.0, np.inf)
    others = [j for j in np.argsort(-span, kind="stable") if j != column][:max_others]
    return sorted([column, *others])


def _log_if_blown_up(ax, ys, axis: str = "y") -> None:
    """A failed run that blew up spans hundreds of decades: use a symmetric log scale,
    linear up to the size the values had over the first half of the history."""
    ys = [np.asarray(y, dtype=float) for y in ys]
    ys = [y[np.isfinite(y)] for y in ys if y.size]
    ys = [y for y in ys if y.size]
    if not ys:
        return
    peak = max(float(np.max(np.abs(y))) for y in ys)
    early = max(float(np.max(np.abs(y[: max(1, y.size // 2)]))) for y in ys)
    if peak > 1e3 * max(early, 1e-300):
        from matplotlib.ticker import SymmetricalLogLocator

        lin = early if early > 0 else peak * 1e-12
        decades = np.log10(peak / lin)
        # give the linear part (the run before it blew up) room, and keep the ticks few
        (ax.set_yscale if axis == "y" else ax.set_xscale)("symlog", linthresh=lin, linscale=max(1.0, decades / 6))
        loc = SymmetricalLogLocator(linthresh=lin, base=10)
        loc.set_params(numticks=6)
        (ax.yaxis if axis == "y" else ax.xaxis).set_major_locator(loc)


def default_title(result, model) -> str:
    scene = getattr(model, "scene", None) or {}
    head = scene.get("title") or scene.get("name") or model.name or "nvib run"
    without = getattr(model, "without", ())
    if without:
        head += f" (without {', '.join(without)})"
    return f"{head}\n{result.scheme!r}, dt = {result.dt:g} s"


def _status_note(result) -> str | None:
    if result.success:
        return None
    what = {"diverged": "diverged", "newton_failed": "Newton failed",
            "singular_matrix": "singular iteration matrix"}.get(result.status.name, result.status.name)
    f = result.failure
    where = f" at t = {f.t:g} s (step {f.step})" if f is not None else ""
    return f"{what}{where}: partial history"


def plot_run(result, model, dof, path, title: str | None = None, *, dpi: int = 110) -> None:
    """Write a figure of one run to ``path`` (format from the extension: .png, .svg, .pdf).

    Left: the displacement history of ``dof`` on its own axes, below it the
    other DOFs (for more than six DOFs only the four that move most). Next:
    the phase locus (u, v) of ``dof``. With ``result.energy``: a third panel with the
    energy terms and the balance. ``dof`` is a DOF name or model index;
    ``title`` defaults to the scene title, the scheme and dt. A failed run
    (partial history) is drawn with its failure noted.
    """
    col = _dof_column(result, model, dof)
    name = result.dofs[col]
    energy = getattr(result, "energy", None)
    t = np.asarray(result.t)
    sel = _thin(len(t))
    ts = t[sel]
    shown = shown_dofs(result, col)
    others = [j for j in shown if j != col]
    fig, left, axes = _new_figure(3 if energy is not None else 2, split_first=bool(others))

    # The selected DOF gets its own axes: other DOFs may move on another scale (or in other units).
    failed = not result.success
    ax = left[0]
    ax.plot(ts, result.u[sel, col], lw=1.6, color="k")
    if failed:
        _log_if_blown_up(ax, [result.u[:, col]])
    ax.set_ylabel(f"u  ({name})")
    ax.set_title(f"Displacement of {name}")
    ax.grid(True, alpha=0.3)
    if others:
        ax.tick_params(labelbottom=False)
        ax = left[1]
        for j in others:
            ax.plot(ts, result.u[sel, j], lw=1.0, alpha=0.85, label=result.dofs[j])
        if failed:
            _log_if_blown_up(ax, [result.u[:, j] for j in others])
        hidden = len(result.dofs) - len(shown)
        ax.set_ylabel("u")
        ax.set_title("Other DOFs" + (f" ({len(others)} of {len(result.dofs) - 1}: those that move most)"
                                     if hidden else ""), fontsize=10)
        ax.legend(fontsize=7, loc="best", ncol=1 if len(others) <= 3 else 2)
        ax.grid(True, alpha=0.3)
    ax.set_xlabel("t [s]")

    ax = axes[0]
    u, v = result.u[sel, col], result.v[sel, col]
    ax.plot(u, v, lw=1.0, color="C0")
    if len(u):
        ax.plot(u[0], v[0], "o", color="C2", label=f"t = {t[0]:g} s")
        ax.plot(u[-1], v[-1], "s", color="C3", label=f"t = {t[-1]:g} s")
        ax.legend(fontsize=8, loc="best")
    if failed:
        _log_if_blown_up(ax, [result.u[:, col]], axis="x")
        _log_if_blown_up(ax, [result.v[:, col]], axis="y")
    ax.set_xlabel(f"u  ({name})")
    ax.set_ylabel(f"v  ({name})")
    ax.set_title(f"Phase locus of {name}")
    ax.grid(True, alpha=0.3)

    if energy is not None:
        ax = axes[1]
        terms = [("kinetic", energy.kinetic), ("potential", energy.potential), ("work in", energy.work_in),
                 ("dissipated", energy.dissipated)]
        for label, y in terms:
            if np.any(y != 0):
                ax.plot(ts, np.asarray(y)[sel], lw=1.0, label=label)
        with np.errstate(all="ignore"):  # a run that blew up may carry inf energies
            balance = energy.kinetic + energy.potential + energy.dissipated - energy.work_in
            rel = energy.relative_balance_error()
        ax.plot(ts, balance[sel], "k--", lw=1.2, label="K + P + D - W")
        if failed:
            _log_if_blown_up(ax, [y for _, y in terms] + [balance])
        ax.set_xlabel("t [s]")
        ax.set_ylabel("energy [J]")
        ax.set_title(f"Energy (max rel. balance error {rel:.2e})" if np.isfinite(rel) else "Energy")
        ax.legend(fontsize=8, loc="best")
        ax.grid(True, alpha=0.3)

    note = _status_note(result)
    head = default_title(result, model) if title is None else title
    fig.suptitle(head + (f"\n{note}" if note else ""), fontsize=11, color="k" if note is None else "C3")
    fig.savefig(path, dpi=dpi)
