"""Plots of runs (PNG, SVG or PDF via matplotlib, imported only when a plot is made).

``plot_run(result, model, dof, path)`` draws the displacement histories, the
phase locus of one DOF (or of an effect's measure) and, when the run recorded
energy, the energy terms, every axis with its unit; ``run_figure`` returns
the same figure instead of writing it. ``plot_spectrum(spectra, path, units="g")`` draws response
spectra (pseudo and absolute Sa, Sd) with the accelerations in g or m/s^2.
The figures are drawn on their own Agg canvas: no pyplot state is touched,
so this works the same in scripts, servers and notebooks.
"""

from __future__ import annotations

import numpy as np

from . import _checks
from ._labels import status_text
from ._model import rate_unit

MAX_POINTS = 50_000  # per curve; longer histories are thinned evenly (always keeping the last point)
MAX_OTHER_DOFS = 4   # beside the highlighted DOF when a model has more than MAX_ALL_DOFS
MAX_ALL_DOFS = 6


def _new_figure(ncols: int, left_rows: int, width: float = 5.6, height: float = 4.8):
    """Figure on its own Agg canvas; the first column is split in ``left_rows`` rows (sharing no axes: a
    zoom panel has its own time range), the other columns span the full height."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width * ncols, height * (1.0 + 0.25 * max(0, left_rows - 2))), layout="constrained")
    FigureCanvasAgg(fig)
    gs = fig.add_gridspec(left_rows, ncols)
    first = [fig.add_subplot(gs[i, 0]) for i in range(left_rows)]
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
    what = status_text(result.status)
    f = result.failure
    where = f" at t = {f.t:g} s (step {f.step})" if f is not None else ""
    return f"{what}{where}: partial history"


DENSE_CYCLES = 150  # a history with more cycles than this over the run gets a zoom panel
ZOOM_CYCLES = 8      # cycles shown in the zoom panel


def cycles(y: np.ndarray) -> float:
    """Oscillation cycles in a history: half its crossings of its mean (0 for fewer than three samples)."""
    y = np.asarray(y, dtype=float)
    y = y[np.isfinite(y)]
    if y.size < 3:
        return 0.0
    s = np.signbit(y - y.mean())
    return 0.5 * float(np.count_nonzero(s[1:] != s[:-1]))


def _unit_of(units: list[str]) -> str:
    """One unit for a set of DOFs ("m"), or the distinct ones ("m, rad")."""
    return ", ".join(dict.fromkeys(units))


def _energy_unit(units: list[str]) -> str:
    """J where the DOFs are in SI (m, rad) and the mass in kg, else the model's own energy unit."""
    return "J" if set(units) <= {"m", "rad"} else "model units"


def _force_unit(unit: str) -> str:
    """The unit of a force on a measure in ``unit``: N on metres, N m on radians (SI), else the model's own."""
    return {"m": "N", "rad": "N m"}.get(unit, "model units")


def _measure_series(result, model, measure: str):
    """(label, d, d', unit, moves with the ground) of the effect named ``measure``: d = g . u over its
    measure's DOFs. A measure whose coefficients sum to zero (a storey drift) does not see a rigid motion
    of the ground: it is the same whether u is relative or absolute."""
    effects = [e for e in (model.effects or []) if e.name == measure]
    if not effects:
        names = sorted({e.name for e in (model.effects or []) if e.name})
        raise _checks.value_error("measure", f"no effect named {measure!r} in this model (named effects: "
                                             f"{', '.join(names) or 'none'})")
    e = effects[0]
    names = list(result.dofs)
    cols = []
    for i in e.index:
        dof = model.dofs[int(i)]
        if dof not in names:
            raise _checks.value_error("measure", f"{measure!r} measures {dof!r}, which this result did not save")
        cols.append(names.index(dof))
    g = np.asarray(e.coef, dtype=float)
    d = np.asarray(result.u)[:, cols] @ g
    dd = np.asarray(result.v)[:, cols] @ g
    unit = _unit_of([result.units[c] for c in cols])
    terms = " ".join(f"{'+' if c >= 0 else '-'} {'' if abs(c) == 1 else f'{abs(c):g} '}{names[k]}"
                     for c, k in zip(g, cols))
    terms = terms[2:] if terms.startswith("+ ") else "-" + terms[2:]
    return f"{measure} ({e.type}: d = {terms})", d, dd, unit, bool(abs(g.sum()) > 1e-12 * np.abs(g).sum())


def plot_run(result, model, dof, path, title: str | None = None, *, measure: str | None = None,
             dpi: int = 110) -> None:
    """Write ``run_figure(result, model, dof, title, measure=measure)`` to ``path`` (format from the
    extension: .png, .svg, .pdf)."""
    run_figure(result, model, dof, title, measure=measure).savefig(path, dpi=dpi)


def run_figure(result, model, dof, title: str | None = None, *, measure: str | None = None):
    """The figure of one run (a matplotlib Figure on its own Agg canvas).

    Left: the displacement history of ``dof`` (or, with ``measure``, the measure d = g . u of the effect
    of that name, such as a storey drift) on its own axes; a history that oscillates densely (more than
    150 cycles) gets a second panel zoomed on its first cycles; below, the other DOFs (for more than six
    DOFs only the four that move most). Next: the phase locus (u, v) of ``dof`` (or d, d'), or, for a
    ``measure`` the run recorded (``solve(record=[...])``), the effect's force-deformation loop. With
    ``result.energy``: a third panel with the energy terms and the balance. Every axis carries its unit
    (``result.units``; time in s); under a ground motion the displacements are labelled relative to the
    ground. ``dof`` is a DOF name or model index; ``title`` defaults to the scene title, the scheme and
    dt. A failed run (partial history) is drawn with its failure noted.
    """
    col = _dof_column(result, model, dof)
    name = result.dofs[col]
    units = list(result.units)
    rel = " relative to the ground" if result.relative_to_ground else ""
    if measure is not None:
        label, y, yd, unit, grounded = _measure_series(result, model, measure)
        short = measure
        rel_y = rel if grounded else ""
    else:
        label, y, yd, unit = name, np.asarray(result.u)[:, col], np.asarray(result.v)[:, col], units[col]
        short, rel_y = name, rel
    energy = getattr(result, "energy", None)
    t = np.asarray(result.t)
    sel = _thin(len(t))
    ts = t[sel]
    shown = shown_dofs(result, col)
    others = [j for j in shown if j != col] if measure is None else shown
    n_cycles = cycles(y)
    zoom = n_cycles > DENSE_CYCLES and len(t) > 2 and result.success
    fig, left, axes = _new_figure(3 if energy is not None else 2, 1 + int(zoom) + int(bool(others)))

    # The selected quantity gets its own axes: other DOFs may move on another scale (or in other units).
    failed = not result.success
    ax = left[0]
    ax.plot(ts, y[sel], lw=1.0 if zoom else 1.6, color="k")
    if failed:
        _log_if_blown_up(ax, [y])
    ax.set_ylabel(f"{short} [{unit}]")
    ax.set_title(f"{'Measure' if measure is not None else 'Displacement of'} {label}{rel_y}", fontsize=10)
    ax.set_xlabel("t [s]")
    ax.grid(True, alpha=0.3)
    row = 1
    if zoom:
        # the first ZOOM_CYCLES cycles at full resolution: the whole run is a solid band at this density
        t_end = t[0] + (t[-1] - t[0]) * ZOOM_CYCLES / n_cycles
        k = max(3, int(np.searchsorted(t, t_end, side="right")))
        ax.axvspan(t[0], t[k - 1], color="C1", alpha=0.25, lw=0)
        ax = left[row]
        ax.plot(t[:k], y[:k], lw=1.2, color="k", marker="." if k < 200 else None, ms=3)
        ax.set_ylabel(f"{short} [{unit}]")
        ax.set_xlabel("t [s]")
        ax.set_title(f"First {ZOOM_CYCLES} of {n_cycles:.0f} cycles (shaded above)", fontsize=10)
        ax.grid(True, alpha=0.3)
        row += 1
    if others:
        ax = left[row]
        mixed = len({units[j] for j in others}) > 1
        for j in others:
            ax.plot(ts, result.u[sel, j], lw=1.0, alpha=0.85,
                    label=f"{result.dofs[j]} [{units[j]}]" if mixed else result.dofs[j])
        if failed:
            _log_if_blown_up(ax, [result.u[:, j] for j in others])
        hidden = len(result.dofs) - len(shown)
        ax.set_ylabel("u [" + ("see legend" if mixed else units[others[0]]) + "]")
        what = "DOFs" if measure is not None else "Other DOFs"
        total = len(result.dofs) - (0 if measure is not None else 1)
        ax.set_title(what + (f" ({len(others)} of {total}: those that move most)" if hidden else "") + rel,
                     fontsize=10)
        ax.legend(fontsize=7, loc="best", ncol=1 if len(others) <= 3 else 2)
        ax.grid(True, alpha=0.3)
        ax.set_xlabel("t [s]")

    ax = axes[0]
    recorded = result.effects.get(measure) if measure is not None else None
    if recorded is not None and recorded.count == 1:
        # The force-deformation loop of the effect (its hysteresis, where it has memory).
        f = np.asarray(recorded.force)
        ax.plot(np.asarray(recorded.measure)[sel], f[sel], lw=1.0, color="C0")
        if len(f):
            ax.plot(recorded.measure[0], f[0], "o", color="C2", label=f"t = {t[0]:g} s")
            ax.plot(recorded.measure[-1], f[-1], "s", color="C3", label=f"t = {t[-1]:g} s")
            ax.legend(fontsize=8, loc="best")
        ax.axhline(0.0, color="0.6", lw=0.6)
        ax.axvline(0.0, color="0.6", lw=0.6)
        ax.set_xlabel(f"{short} [{unit}]")
        ax.set_ylabel(f"force of {short} [{_force_unit(unit)}]")
        dissipated = recorded.state.get("dissipated")
        note = f"; dissipated {float(dissipated[-1]):.4g} {_energy_unit(units)}" if dissipated is not None else ""
        ax.set_title(f"Force-deformation loop of {short} ({recorded.type}){note}", fontsize=10)
        ax.grid(True, alpha=0.3)
    else:
        u, v = y[sel], yd[sel]
        ax.plot(u, v, lw=1.0 if not zoom else 0.5, color="C0")
        if len(u):
            ax.plot(u[0], v[0], "o", color="C2", label=f"t = {t[0]:g} s")
            ax.plot(u[-1], v[-1], "s", color="C3", label=f"t = {t[-1]:g} s")
            ax.legend(fontsize=8, loc="best")
        if failed:
            _log_if_blown_up(ax, [y], axis="x")
            _log_if_blown_up(ax, [yd], axis="y")
        ax.set_xlabel(f"{short} [{unit}]")
        ax.set_ylabel(f"d{short}/dt [{rate_unit(unit, 1)}]")
        ax.set_title(f"Phase locus of {short}{rel_y}", fontsize=10)
        ax.grid(True, alpha=0.3)

    if energy is not None:
        ax = axes[1]
        terms = [("kinetic", energy.kinetic), ("potential", energy.potential), ("work in", energy.work_in),
                 ("dissipated", energy.dissipated), ("hysteretic", energy.hysteretic)]
        for lab, e in terms:
            if np.any(e != 0):
                ax.plot(ts, np.asarray(e)[sel], lw=1.0, label=lab)
        with np.errstate(all="ignore"):  # a run that blew up may carry inf energies
            balance = energy.kinetic + energy.potential + energy.dissipated + energy.hysteretic - energy.work_in
            relerr = energy.relative_balance_error()
        ax.plot(ts, balance[sel], "k--", lw=1.2, label="K + P + D + H - W")
        if failed:
            _log_if_blown_up(ax, [e for _, e in terms] + [balance])
        ax.set_xlabel("t [s]")
        ax.set_ylabel(f"energy [{_energy_unit(units)}]")
        ax.set_title(f"Energy (max rel. balance error {relerr:.2e})" if np.isfinite(relerr) else "Energy",
                     fontsize=10)
        ax.legend(fontsize=8, loc="best")
        ax.grid(True, alpha=0.3)

    for ax in fig.axes:
        tidy_ticks(ax)
    note = _status_note(result)
    head = default_title(result, model) if title is None else title
    fig.suptitle(head + (f"\n{note}" if note else ""), fontsize=11, color="k" if note is None else "C3")
    return fig


def tidy_ticks(ax) -> None:
    """Tick labels that do not run into each other: at most six per axis, and values below 1e-3 or above
    1e4 as a mantissa with a common power of ten at the end of the axis."""
    from matplotlib.ticker import MaxNLocator, ScalarFormatter

    for axis in (ax.xaxis, ax.yaxis):
        if isinstance(axis.get_major_formatter(), ScalarFormatter):  # not the symmetric-log axes of a blow-up
            axis.set_major_locator(MaxNLocator(nbins=6))
            fmt = ScalarFormatter(useMathText=True)
            fmt.set_powerlimits((-3, 4))
            axis.set_major_formatter(fmt)


def spectrum_figure(spectra, *, units: str | None = None, title: str | None = None):
    """Response spectra (one ``Spectrum`` or a list, e.g. one per damping): PSa and the absolute Sa, and Sd,
    against the period on log axes. ``units``: "g" or "m/s^2" for the accelerations (Sd then in m when the
    record's unit is known); default the record's own."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    from .analysis.spectrum import unit_labels

    spectra = [spectra] if not isinstance(spectra, (list, tuple)) else list(spectra)
    spectra = [row for sp in spectra for row in sp.by_damping()]  # one curve per damping ratio
    if not spectra:
        raise _checks.value_error("spectra", "expected at least one spectrum")
    shown = [sp.in_units(units) if units is not None else sp for sp in spectra]
    # Sd in metres whenever the unit is known (a displacement in g s^2 means little to a reader)
    sd = [sp.in_units("m/s^2") if sp.units in ("g", "m/s^2") else sp for sp in spectra]
    labels = unit_labels(shown[0].units)
    fig = Figure(figsize=(12, 4.5), layout="constrained")
    FigureCanvasAgg(fig)
    ax1, ax2 = fig.subplots(1, 2)
    for sp, d in zip(shown, sd):
        line, = ax1.loglog(sp.periods, sp.PSa, label=f"PSa, ζ = {sp.damping:g}")
        ax1.loglog(sp.periods, sp.Sa, ":", color=line.get_color(), label=f"Sa (absolute), ζ = {sp.damping:g}")
        ax2.loglog(d.periods, d.Sd, color=line.get_color(), label=f"Sd, ζ = {sp.damping:g}")
    ax1.set_ylabel(f"spectral acceleration [{labels['PSa']}]")
    ax2.set_ylabel(f"spectral displacement [{unit_labels(sd[0].units)['Sd']}]")
    for ax in (ax1, ax2):
        ax.set_xlabel("period T [s]")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
    fig.suptitle(title if title is not None else f"{spectra[0].record}: {spectra[0].scheme}")
    return fig


def plot_spectrum(spectra, path, *, units: str | None = None, title: str | None = None, dpi: int = 120) -> None:
    """Write ``spectrum_figure(spectra, units=units, title=title)`` to ``path`` (.png, .svg, .pdf)."""
    spectrum_figure(spectra, units=units, title=title).savefig(path, dpi=dpi)
