"""Plots of runs (PNG, SVG or PDF via matplotlib, imported only when a plot is made).

``plot_run(result, model, dof, path)`` draws the displacement histories, the
phase locus of one DOF (or of an effect's measure) and, when the run recorded
energy, the energy terms, every axis with its unit; under a ground motion, the
ground acceleration on the same time axis; for a building with storeys, the
peak drift ratio over the height and the hysteresis of the critical storey.
``run_figure`` returns the same figure instead of writing it. ``plot_spectrum(spectra, path, units="g")`` draws response
spectra (pseudo and absolute Sa, Sd) with the accelerations in g or m/s^2.
The figures are drawn on their own Agg canvas: no pyplot state is touched,
so this works the same in scripts, servers and notebooks.
"""

from __future__ import annotations

import numpy as np

from . import _checks
from ._labels import status_text
from ._model import rate_unit
from ._records import STANDARD_GRAVITY, GroundMotion

MAX_POINTS = 50_000  # per curve; longer histories are thinned evenly (always keeping the last point)
MAX_OTHER_DOFS = 4   # beside the highlighted DOF when a model has more than MAX_ALL_DOFS
MAX_ALL_DOFS = 6


def _new_figure(ncols: int, left_rows: int, width: float = 5.6, height: float = 4.8, *, split=(),
                width_ratios=None, min_height: float = 0.0):
    """Figure on its own Agg canvas; the first column is split in ``left_rows`` rows (sharing no axes: a
    zoom panel has its own time range), the other columns span the full height, except those in ``split``,
    which hold two panels one above the other (returned as a pair). ``width_ratios``: of the columns (the
    figure's width is ``width`` times their sum)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    wide = sum(width_ratios) if width_ratios is not None else ncols
    fig = Figure(figsize=(width * wide, max(min_height, height * (1.0 + 0.25 * max(0, left_rows - 2)))),
                 layout="constrained")
    FigureCanvasAgg(fig)
    gs = fig.add_gridspec(left_rows, ncols, width_ratios=width_ratios)
    first = [fig.add_subplot(gs[i, 0]) for i in range(left_rows)]
    others = []
    for j in range(1, ncols):
        if j in split:
            sub = gs[:, j].subgridspec(2, 1)
            others.append((fig.add_subplot(sub[0]), fig.add_subplot(sub[1])))
        else:
            others.append(fig.add_subplot(gs[:, j]))
    return fig, first, others


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


def default_title(result, model, *, ground: str | None = None) -> str:
    """The scene's title (or name), what was left out, the scheme and dt. ``ground``: the ground motion that
    replaced the scene's own (its title names the scene's), as "<scene name> under <ground>"."""
    scene = getattr(model, "scene", None) or {}
    head = scene.get("title") or scene.get("name") or model.name or "nvib run"
    if ground is not None:
        head = f"{scene.get('name') or model.name or 'nvib run'} under {ground}"
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
    collapse = _collapse(result)
    if collapse is not None:
        return f"{what}{where}: {collapse[1]}; the run stops there"
    return f"{what}{where}: partial history"


def _collapse(result) -> tuple[float, str] | None:
    """(time [s], what failed: "storey1 (imk_peak_oriented) lost its strength") of a run that collapsed, else None."""
    f = result.failure
    if result.status.name != "collapsed" or f is None:
        return None
    _, _, what = f.message.partition("): ")  # "collapsed at t = 10.242 (step 5121): storey1 (...) lost ..."
    return float(f.t), what or f.message


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


GROUND_UNITS = {"g": STANDARD_GRAVITY, "m/s^2": 1.0}  # the accelerations a ground panel converts between, in m/s^2
SINE_POINTS_PER_PERIOD = 40


def _thin_keeping_peak(y: np.ndarray, max_points: int = MAX_POINTS) -> slice | np.ndarray:
    """``_thin``, with the sample of the largest |y| kept (a record's PGA must not be thinned away)."""
    sel = _thin(len(y), max_points)
    if isinstance(sel, slice) or not len(y):
        return sel
    return np.union1d(sel, [int(np.argmax(np.abs(y)))])


def ground_series(signal, t0: float, t1: float) -> tuple[np.ndarray, np.ndarray]:
    """(t [s], a_g) of a ground acceleration's signal over the span [t0, t1], as the run applies it (values in
    the model's acceleration unit): a record (a GroundMotion, a table, a record file) by its own samples inside
    the span, with its values at the ends of the span, linear between samples and 0 outside the record; a sine
    on an even grid of at least 40 points a period."""
    if isinstance(signal, dict) and signal.get("kind") == "sine":
        amplitude, omega = float(signal["amplitude"]), float(signal["omega"])
        periods = abs(omega) * (t1 - t0) / (2.0 * np.pi)
        n = int(min(MAX_POINTS, max(2001, SINE_POINTS_PER_PERIOD * periods + 1)))
        ts = np.linspace(t0, t1, n)
        return ts, amplitude * np.sin(omega * ts + float(signal.get("phase", 0.0)))
    gm = _ground_record(signal)
    t, a = gm.t, gm.a
    if t1 < t[0] or t0 > t[-1]:  # the whole run before or after the record
        return np.array([t0, t1]), np.zeros(2)
    k0, k1 = int(np.searchsorted(t, t0, side="left")), int(np.searchsorted(t, t1, side="right"))
    head_t, head_a, tail_t, tail_a = [], [], [], []
    if t0 < t[0]:
        head_t, head_a = [t0, t[0]], [0.0, 0.0]
    elif k0 >= k1 or t[k0] > t0:
        head_t, head_a = [t0], [float(gm(t0))]
    if t1 > t[-1]:
        tail_t, tail_a = [t[-1], t1], [0.0, 0.0]
    elif k0 >= k1 or t[k1 - 1] < t1:
        tail_t, tail_a = [t1], [float(gm(t1))]
    return (np.concatenate([head_t, t[k0:k1], tail_t]).astype(float),
            np.concatenate([head_a, a[k0:k1], tail_a]).astype(float))


def _ground_record(signal) -> GroundMotion:
    """A record signal as a GroundMotion (a table or a scene's record file is read as one)."""
    if isinstance(signal, GroundMotion):
        return signal
    if isinstance(signal, dict) and signal.get("kind") == "table":
        return GroundMotion(np.asarray(signal["t"], dtype=float), np.asarray(signal["values"], dtype=float))
    return GroundMotion.from_spec("signal", signal)


def _ground_source(signal, unit: str) -> str:
    """What drives the ground: the record's name, or the sine's formula in the run's unit."""
    if isinstance(signal, dict) and signal.get("kind") == "sine":
        phase = float(signal.get("phase", 0.0))
        return (f"{float(signal['amplitude']):g} {unit} x sin({float(signal['omega']):g} t"
                + (f" + {phase:g}" if phase else "") + ")")
    if isinstance(signal, dict) and signal.get("kind") == "table":
        return "a table of samples"
    gm = _ground_record(signal)
    return gm.name or gm.label or "a record"


def _check_ground_units(ground_units) -> None:
    if ground_units is not None and ground_units not in GROUND_UNITS:
        raise _checks.value_error("ground_units", f"expected one of {', '.join(map(repr, GROUND_UNITS))} or None, "
                                                  f"got {ground_units!r}")


def _ground_panel(ax, result, model, grounds, ground_units) -> None:
    """a_g(t) of each ground motion over the run's span, in ``ground_units`` (default g) when its unit is an
    acceleration nvib knows, with the other unit on the right-hand axis, its peak marked."""
    t = np.asarray(result.t)
    t0, t1 = (float(t[0]), float(t[-1])) if len(t) else (0.0, 0.0)
    shown = None
    notes, peaks, sources = [], [], []
    for k, (name, r, signal) in enumerate(grounds):
        sine = isinstance(signal, dict) and signal.get("kind") == "sine"
        signal = signal if sine else _ground_record(signal)
        run_unit = rate_unit(_unit_of([model.units[i] for i in np.flatnonzero(r)] or ["m"]), 2)
        ts, a = ground_series(signal, t0, t1)
        unit, factor = run_unit, 1.0
        if run_unit in GROUND_UNITS:
            unit = ground_units or "g"
            factor = GROUND_UNITS[run_unit] / GROUND_UNITS[unit]
        if shown is None:
            shown = unit  # one axis for all: the unit of the first
        said = getattr(signal, "units", "")
        if said and said != run_unit:
            notes.append(f"the record says {said}; the run took its values as {run_unit}")
        y = a * factor
        sel = _thin_keeping_peak(y)
        sources.append(_ground_source(signal, run_unit))
        ax.plot(ts[sel], y[sel], lw=0.8, color="0.25" if len(grounds) == 1 else f"C{k}",
                label=None if len(grounds) == 1 else f"{name or 'ground'}: {sources[-1]}")
        if len(y):
            j = int(np.argmax(np.abs(y)))
            peak = f"PGA {abs(y[j]):#.3g} {unit} at t = {ts[j]:.4g} s"
            if not sine and signal.pga * factor > abs(y[j]) * (1.0 + 1e-9):  # the record's peak is not in the run
                i = int(np.argmax(np.abs(signal.a)))
                peak = (f"peak in the run {abs(y[j]):#.3g} {unit} at t = {ts[j]:.4g} s (the record's PGA: "
                        f"{signal.pga * factor:#.3g} {unit} at t = {signal.t[i]:.4g} s)")
            peaks.append(peak)
            ax.plot(ts[j], y[j], "v" if y[j] < 0 else "^", color="C3" if len(grounds) == 1 else f"C{k}", ms=7,
                    zorder=3, label=None if len(grounds) == 1 else f"peak {abs(y[j]):#.3g} {unit}")
    unit = shown
    ax.axhline(0.0, color="0.6", lw=0.6)
    ax.set_ylabel(f"a_g [{unit}]")
    ax.set_xlabel("t [s]")
    if unit in GROUND_UNITS:
        other = "m/s^2" if unit == "g" else "g"
        f = GROUND_UNITS[unit] / GROUND_UNITS[other]
        right = ax.secondary_yaxis("right", functions=(lambda x: x * f, lambda x: x / f))
        right.set_ylabel(f"a_g [{other}]")
    if len(grounds) == 1:  # the peak in the title: a legend would hide part of a record, which fills the panel
        head = f"Ground acceleration: {sources[0]}" + (f"\n{peaks[0]}" if peaks else "")
    else:
        head = f"Ground acceleration: {len(grounds)} ground motions"
        ax.legend(fontsize=7, loc="upper right", ncol=2, framealpha=0.6)
    ax.set_title(head + (f"\n({'; '.join(notes)})" if notes else ""), fontsize=10)
    ax.grid(True, alpha=0.3)


def _storey_limits(model, heights: dict, collapse_deformation) -> list[tuple[str, np.ndarray]]:
    """(label, drift ratio per storey) of the limits a storey collapses at: the run's collapse deformation and
    the ultimate deformation of a law that has one (imk_peak_oriented's uu, the nearer side)."""
    out = []
    h = np.array(list(heights.values()))
    if collapse_deformation is not None:
        out.append((f"collapse deformation {collapse_deformation:g} m", collapse_deformation / h))
    effects = {e.name: e for e in model.effects or [] if e.name}
    ultimate = []
    for name in heights:
        p = effects[name].parameters
        uu = [abs(float(p[k])) for k in ("uu", "uu_neg") if k in p and np.isfinite(p[k]) and p[k] != 0]
        ultimate.append(min(uu) if uu else np.nan)
    if not np.all(np.isnan(ultimate)):
        out.append(("ultimate deformation of the law (uu)", np.array(ultimate) / h))
    return out


def _step_profile(values: np.ndarray, levels: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(x, y) of a storey-by-storey profile: each storey's value held from its floor to its ceiling."""
    return np.repeat(values, 2), np.column_stack([levels[:-1], levels[1:]]).ravel()


def _envelope_panel(ax, heights: dict, peaks: dict, critical: str | None, limits, collapse, saved_every: int) -> None:
    """Peak |drift ratio| of each storey [%] against the height [m], the critical storey marked."""
    names = list(heights)
    h = np.array([heights[n] for n in names])
    levels = np.concatenate([[0.0], np.cumsum(h)])
    r = 100.0 * np.array([peaks[n] for n in names])
    x, y = _step_profile(r, levels)
    ax.plot(x, y, color="C0", lw=1.8, label="peak |drift ratio|")
    mids = 0.5 * (levels[:-1] + levels[1:])
    ax.plot(r, mids, "o", color="C0", ms=4)
    if len(names) <= 16:
        for k, (x_k, y_k) in enumerate(zip(r, mids)):
            if names[k] != critical and np.isfinite(x_k):
                ax.annotate(f"{x_k:.3g}", (x_k, y_k), xytext=(5, 3), textcoords="offset points", fontsize=7,
                            color="C0")
    for k, (label, ratio) in enumerate(limits):
        lx, ly = _step_profile(100.0 * ratio, levels)
        ax.plot(lx, ly, ls="--" if k == 0 else ":", color="C3", lw=1.2, label=label)
    ax.set_ylim(0.0, levels[-1])
    right = 1.15 * max([np.nanmax(r)] + [np.nanmax(100 * q) for _, q in limits]) if np.any(np.isfinite(r)) else 1.0
    ax.set_xlim(0.0, right)
    if critical is not None:
        j = names.index(critical)
        failed = collapse is not None and collapse[1].startswith(critical + " ")
        ax.plot(r[j], mids[j], "o", color="C3", ms=8, zorder=3)
        inward = -1 if r[j] > 0.5 * right else 1  # the label on the side with room
        ax.annotate(f"{critical}: {r[j]:.3g} %" + (" (failed)" if failed else ""), (r[j], mids[j]),
                    xytext=(8 * inward, 10), textcoords="offset points", ha="right" if inward < 0 else "left",
                    fontsize=9, color="C3", bbox={"boxstyle": "round,pad=0.2", "fc": "white", "ec": "none",
                                                  "alpha": 0.8})
    if len(levels) <= 16:
        ax.set_yticks(levels)
        names_axis = ax.secondary_yaxis("right")
        names_axis.set_yticks(mids, labels=names, fontsize=8)
        names_axis.tick_params(length=0)
    ax.set_xlabel("peak |drift| / storey height [%]")
    ax.set_ylabel("height above the ground [m]")
    title = "Peak drift ratio over the height"
    if collapse is not None:
        title += f"\nup to the collapse at t = {collapse[0]:g} s"
    if saved_every > 1:
        title += f"\n(from the states saved every {saved_every} steps)"
    ax.set_title(title, fontsize=10)
    low = critical is not None and mids[names.index(critical)] < 0.5 * levels[-1]
    ax.legend(fontsize=8, loc="upper right" if low else "lower right")  # away from the critical storey's label
    ax.grid(True, alpha=0.3)


def _critical_panel(ax, result, crit: str, h: float, peak: float, unit: str, sel, collapse) -> None:
    """The force-deformation loop of the critical storey: its recorded force against its drift ratio [%],
    the drift [m] on the top axis; or a note that it was not recorded."""
    from matplotlib.ticker import MaxNLocator

    rec = result.effects.get(crit)
    ax.set_title(f"Critical storey {crit}\npeak drift ratio {100 * peak:.3g} %", fontsize=10)
    if rec is None or rec.count != 1:
        ax.text(0.5, 0.5, f"{crit} was not recorded: its loop needs\nsolve(..., record=[{crit!r}])\n"
                          f"(nvib run: --record-effect {crit})", ha="center", va="center", transform=ax.transAxes,
                fontsize=9)
        ax.set_xticks([])
        ax.set_yticks([])
        return
    t = np.asarray(result.t)
    d, f = np.asarray(rec.measure), np.asarray(rec.force)
    force_unit = _force_unit(unit)
    scale, force_unit = (1e3, "k" + force_unit) if force_unit in ("N", "N m") else (1.0, force_unit)
    x, y = 100.0 * d / h, f / scale
    ax.plot(x[sel], y[sel], lw=0.9, color="C0")
    if len(x):
        ax.plot(x[0], y[0], "o", color="C2", label=f"t = {t[0]:g} s")
        ax.plot(x[-1], y[-1], "X" if collapse is not None else "s", color="C3", ms=8 if collapse else 6,
                label=f"t = {t[-1]:g} s" + (" (collapse)" if collapse is not None else ""))
        ax.legend(fontsize=8, loc="best")
    ax.axhline(0.0, color="0.6", lw=0.6)
    ax.axvline(0.0, color="0.6", lw=0.6)
    ax.set_xlabel(f"drift ratio of {crit} (drift / {h:g} m) [%]")
    ax.set_ylabel(f"force of {crit} [{force_unit}]")
    top = ax.secondary_xaxis("top", functions=(lambda p: p * h / 100.0, lambda q: 100.0 * q / h))
    top.set_xlabel(f"drift [{unit}]", fontsize=9)
    top.xaxis.set_major_locator(MaxNLocator(nbins=5))
    ax.set_title(f"Critical storey {crit} ({rec.type})\npeak drift ratio {100 * peak:.3g} %", fontsize=10)
    ax.grid(True, alpha=0.3)


def plot_run(result, model, dof, path, title: str | None = None, *, measure: str | None = None, storeys=None,
             ground_units: str | None = None, collapse_deformation: float | None = None, dpi: int = 110) -> None:
    """Write ``run_figure(result, model, dof, title, ...)`` to ``path`` (format from the extension: .png,
    .svg, .pdf)."""
    run_figure(result, model, dof, title, measure=measure, storeys=storeys, ground_units=ground_units,
               collapse_deformation=collapse_deformation).savefig(path, dpi=dpi)


def run_figure(result, model, dof, title: str | None = None, *, measure: str | None = None, storeys=None,
               ground_units: str | None = None, collapse_deformation: float | None = None):
    """The figure of one run (a matplotlib Figure on its own Agg canvas).

    Left: the displacement history of ``dof`` (or, with ``measure``, the measure d = g . u of the effect
    of that name, such as a storey drift) on its own axes; under a ground motion (a ground_acceleration
    effect), the ground acceleration a_g(t) the run applied below it, on the same time axis, its peak (PGA)
    marked; a history that oscillates densely (more than 150 cycles) gets a panel zoomed on its first
    cycles; below, the other DOFs (for more than six DOFs only the four that move most). Next: the phase
    locus (u, v) of ``dof`` (or d, d'), or, for a ``measure`` the run recorded (``solve(record=[...])``),
    the effect's force-deformation loop. With ``result.energy``: a panel with the energy terms and the
    balance.

    For a model with storeys (``storeys`` {effect name: height [m]}, storey 1 first; default the scene's
    ``[storeys]``): the peak |drift ratio| (drift / height, in %) of each storey against the height above
    the ground [m], the largest marked, with the collapse limits (``collapse_deformation`` [m], the run's,
    and a law's ultimate deformation); and the hysteresis of that critical storey (its recorded force
    against its drift ratio; a note when the run did not record it). A run that collapsed shows when and
    where.

    Every axis carries its unit (``result.units``; time in s); under a ground motion the displacements are
    labelled relative to the ground. a_g is drawn in ``ground_units`` ("g" or "m/s^2"; default g) when the
    run's acceleration unit is one of them, the other on the right-hand axis. ``dof`` is a DOF name or model
    index; ``title`` defaults to the scene title, the scheme and dt. A failed run (partial history) is drawn
    with its failure noted.
    """
    from ._solve import ground_motions
    from ._storeys import peak_drift_ratios, storey_heights

    _check_ground_units(ground_units)
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
    grounds = ground_motions(model) if len(t) else []
    collapse = _collapse(result)

    heights = storey_heights(model, storeys) if storeys is not None or _declared_storeys(model) else None
    peaks = critical = missing = None
    if heights is not None and len(t):
        try:
            peaks = peak_drift_ratios(model, result, heights)
        except ValueError as exc:  # a drift needs a DOF the result did not save
            missing = str(exc).removeprefix("result: ")
        else:
            finite = {k: v for k, v in peaks.items() if np.isfinite(v)}
            critical = max(finite, key=finite.get) if finite else None

    rows = ["response"] + ["ground"] * bool(grounds) + ["zoom"] * zoom + ["others"] * bool(others)
    if heights is not None:
        side = ["envelope", ("critical", "phase") if critical is not None else "phase"]
        side += ["energy"] * (energy is not None)
        fig, left, axes = _new_figure(1 + len(side), len(rows), width=5.0, split={2} if critical is not None else (),
                                      width_ratios=[1.45, 0.8, 1.05] + [1.05] * (energy is not None), min_height=8.0)
    else:
        side = ["phase"] + ["energy"] * (energy is not None)
        fig, left, axes = _new_figure(1 + len(side), len(rows), min_height=7.0 if grounds else 0.0)
    panel = dict(zip(rows, left))
    for key, ax in zip(side, axes):
        panel.update(zip(key, ax) if isinstance(key, tuple) else [(key, ax)])
    for key in ("ground", "others"):  # the time panels share the response's axis (the zoom has its own)
        if key in panel:
            panel[key].sharex(panel["response"])

    # The selected quantity gets its own axes: other DOFs may move on another scale (or in other units).
    failed = not result.success
    ax = panel["response"]
    ax.plot(ts, y[sel], lw=1.0 if zoom else 1.6, color="k")
    if failed:
        _log_if_blown_up(ax, [y])
    ax.set_ylabel(f"{short} [{unit}]")
    ax.set_title(f"{'Measure' if measure is not None else 'Displacement of'} {label}{rel_y}", fontsize=10)
    ax.set_xlabel("t [s]")
    ax.grid(True, alpha=0.3)
    if grounds:
        _ground_panel(panel["ground"], result, model, grounds, ground_units)
    if zoom:
        # the first ZOOM_CYCLES cycles at full resolution: the whole run is a solid band at this density
        t_end = t[0] + (t[-1] - t[0]) * ZOOM_CYCLES / n_cycles
        k = max(3, int(np.searchsorted(t, t_end, side="right")))
        panel["response"].axvspan(t[0], t[k - 1], color="C1", alpha=0.25, lw=0)
        ax = panel["zoom"]
        ax.plot(t[:k], y[:k], lw=1.2, color="k", marker="." if k < 200 else None, ms=3)
        ax.set_ylabel(f"{short} [{unit}]")
        ax.set_xlabel("t [s]")
        ax.set_title(f"First {ZOOM_CYCLES} of {n_cycles:.0f} cycles (shaded above)", fontsize=10)
        ax.grid(True, alpha=0.3)
    if others:
        ax = panel["others"]
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
    if collapse is not None:
        for key in ("response", "ground", "others"):
            if key in panel:
                panel[key].axvline(collapse[0], color="C3", ls="--", lw=1.0)
        ax = panel.get("ground", panel["response"])
        ax.annotate(f"collapse, t = {collapse[0]:g} s", (collapse[0], 1.0), xycoords=("data", "axes fraction"),
                    xytext=(-4, -4), textcoords="offset points", ha="right", va="top", fontsize=8, color="C3",
                    bbox={"boxstyle": "round,pad=0.2", "fc": "white", "ec": "none", "alpha": 0.85})

    if heights is not None:
        ax = panel["envelope"]
        if peaks is None:
            ax.text(0.5, 0.5, "no drift ratios:\n" + (missing or "no saved state"), ha="center", va="center",
                    transform=ax.transAxes, fontsize=9, wrap=True)
            ax.set_xticks([])
            ax.set_yticks([])
            ax.set_title("Peak drift ratio over the height", fontsize=10)
        else:
            every = int(round((t[1] - t[0]) / result.dt)) if len(t) > 2 and result.dt > 0 else 1
            _envelope_panel(ax, heights, peaks, critical,
                            _storey_limits(model, heights, collapse_deformation), collapse, every)
        if critical is not None:
            e = next(x for x in model.effects if x.name == critical)
            crit_unit = _unit_of([model.units[int(i)] for i in e.index])
            _critical_panel(panel["critical"], result, critical, heights[critical], peaks[critical], crit_unit,
                            sel, collapse)

    ax = panel["phase"]
    recorded = result.effects.get(measure) if measure is not None and measure != critical else None
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
        note = f"\ndissipated {float(dissipated[-1]):.4g} {_energy_unit(units)}" if dissipated is not None else ""
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
        ax = panel["energy"]
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


def _declared_storeys(model) -> bool:
    from ._storeys import declared

    return bool(declared(model))


def tidy_ticks(ax) -> None:
    """Tick labels that do not run into each other: at most six per axis, and values below 1e-3 or above
    1e4 as a mantissa with a common power of ten at the end of the axis. Ticks placed on purpose (the floor
    levels of a drift profile) are kept."""
    from matplotlib.ticker import FixedLocator, MaxNLocator, ScalarFormatter

    for axis in (ax.xaxis, ax.yaxis):
        if isinstance(axis.get_major_locator(), FixedLocator):
            continue
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
