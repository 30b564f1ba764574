"""Fragility functions: the probability that a structure collapses, or that a demand exceeds a limit,
given the intensity measure (IM) of the ground motion, as a lognormal CDF

    P(event | IM = x) = Phi(ln(x / theta) / beta)

with median ``theta`` (in the IM's units) and dispersion ``beta``, fitted by maximum likelihood
(Baker 2015, "Efficient analytical fragility function fitting using dynamic structural analysis",
Earthquake Spectra 31(1)):

- ``fit_collapse_ims(ims, censored=...)``: the IM at which each record made the structure collapse
  (an incremental dynamic analysis). Without censoring the MLE is ln theta = mean of ln IM and beta =
  their standard deviation with n in the denominator; Baker's eq. 3 uses n - 1, given as
  ``beta_sample``. A record that did not collapse up to the highest IM it was run at (the IDA was
  truncated there) contributes ln(1 - Phi(ln(im_max / theta) / beta)) instead of its density.
- ``fit_stripes(ims, n, z)``: multiple-stripe analysis, z_j of n_j runs exceed at IM level x_j; the
  likelihood is the product of binomials, sum_j ln C(n_j, z_j) + z_j ln Phi(u_j) + (n_j - z_j) ln(1 - Phi(u_j)).
- ``from_ida(ida, demand_limit=...)``: either fragility from an ``nvib.ida`` result.

Both likelihoods are concave in (a, b) = (1 / beta, -ln theta / beta) (the probit model, and Olsen 1978
for the censored normal), so the maximum, when it exists, is unique and Newton's method with a
backtracking line search on the analytic gradient and Hessian finds it from any start. It does not
exist when the data are separated (every run below some IM exceeds nothing and every run above it
exceeds: beta -> 0), when nothing or everything exceeds (theta -> infinity or 0), or with fewer than
two distinct collapse IMs: such data are refused, naming the argument.

Standard errors come from the observed information matrix: the inverse of minus the analytic Hessian
of the log-likelihood at the maximum, carried to (ln theta, beta); SE(theta) = theta SE(ln theta)
(the delta method). For uncensored collapse IMs these are beta / sqrt(n) for ln theta and
beta / sqrt(2 n) for beta.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from .. import _checks

__all__ = ["Fragility", "fit_collapse_ims", "fit_stripes", "from_ida", "markdown_table"]

SE_METHOD = ("observed information (analytic Hessian of the log-likelihood at the maximum); "
             "SE(theta) = theta SE(ln theta), the delta method")
_MAX_NEWTON = 200


@dataclasses.dataclass
class Fragility:
    """A lognormal fragility function and the data it was fitted to.

    ``theta``: the median IM (in ``im_unit``), ``beta``: the lognormal dispersion, ``se_theta`` and
    ``se_beta`` their standard errors (``se_method`` says how), ``method``: "collapse IM values",
    "truncated" (collapse IMs with records that did not collapse up to their highest IM) or "multiple
    stripes". The data: ``levels``, ``n`` and ``z`` (the IM of each stripe, the runs and the
    exceedances there) for stripes; ``collapse_ims`` and ``censored_ims`` (the highest IM of each record
    that did not collapse) otherwise. ``event``: what the probability is of ("collapse", "peak_drift >
    0.02 m"). ``beta_sample``: Baker's sample standard deviation (n - 1) of uncensored collapse IMs."""

    theta: float
    beta: float
    se_theta: float
    se_beta: float
    method: str
    im_name: str
    im_unit: str
    event: str
    log_likelihood: float
    levels: np.ndarray | None = None
    n: np.ndarray | None = None
    z: np.ndarray | None = None
    collapse_ims: np.ndarray | None = None
    censored_ims: np.ndarray | None = None
    beta_sample: float | None = None
    se_method: str = SE_METHOD

    def probability(self, im):
        """Phi(ln(im / theta) / beta): the probability of the event at ``im`` (a number or an array, >= 0)."""
        from scipy.special import ndtr

        x = _checks.real_array("im", im)
        if not np.all(np.isfinite(x)) or np.any(x < 0):
            raise _checks.value_error("im", "expected finite intensities >= 0")
        with np.errstate(divide="ignore"):
            p = ndtr(np.log(x / self.theta) / self.beta)
        return float(p) if p.ndim == 0 else p

    @property
    def im_label(self) -> str:
        return f"{self.im_name} [{self.im_unit or '-'}]"

    def _unit(self) -> str:
        return f" {self.im_unit}" if self.im_unit and self.im_unit != "-" else ""

    def __repr__(self) -> str:
        u = self._unit()
        if self.levels is not None:
            data = f"{self.levels.size} stripes, {int(self.n.sum())} runs, {int(self.z.sum())} exceeded"
        else:
            data = f"{self.collapse_ims.size} collapse IMs"
            if self.censored_ims.size:
                data += f", {self.censored_ims.size} censored"
        return (f"Fragility({self.event}, {self.method}: theta = {self.theta:.4g}{u} (SE {self.se_theta:.2g}), "
                f"beta = {self.beta:.3f} (SE {self.se_beta:.2g}), {data})")

    def row(self) -> str:
        """This fragility as a row of ``markdown_table``."""
        if self.levels is not None:
            data = f"{self.levels.size} stripes, {int(self.n.sum())} runs, {int(self.z.sum())} exceeded"
        else:
            reached = "collapsed" if self.event == "collapse" else "reached"
            data = f"{self.collapse_ims.size} {reached}, {self.censored_ims.size} censored"
        return (f"| {self.event} | {self.method} | {self.im_label} | {self.theta:.4g} | {self.se_theta:.2g} | "
                f"{self.beta:.4f} | {self.se_beta:.2g} | {data} |")

    def data_table(self) -> str:
        """The data as a markdown table: per stripe the IM, n, z and z / n; or each record's collapse IM
        (or the highest IM it was run at without collapsing)."""
        if self.levels is not None:
            rows = [f"| {self.im_label} | n | z | z / n | fitted P |", "|---:|---:|---:|---:|---:|"]
            for x, n, z in zip(self.levels, self.n, self.z):
                rows.append(f"| {x:.4g} | {int(n)} | {int(z)} | {z / n:.3f} | {self.probability(x):.3f} |")
        else:
            rows = [f"| {self.im_label} | record | empirical P | fitted P |", "|---:|---|---:|---:|"]
            total = self.collapse_ims.size + self.censored_ims.size
            for k, x in enumerate(np.sort(self.collapse_ims), 1):
                rows.append(f"| {x:.4g} | collapsed | {k / total:.3f} | {self.probability(x):.3f} |")
            for x in np.sort(self.censored_ims):
                rows.append(f"| > {x:.4g} | did not collapse | | |")
        return "\n".join(rows) + "\n"

    def markdown(self) -> str:
        """The fitted theta and beta with their standard errors, then the data."""
        return markdown_table([self]) + "\n" + self.data_table()

    def plot(self, path=None, *, ax=None):
        """The data and the fitted curve: per stripe the fraction exceeded (marker area growing with the
        runs n, each labelled z/n), or the empirical CDF of the collapse IMs (step i / N over all N
        records; a record that did not collapse is a triangle at the IM it reached); theta and beta in the
        legend, the IM with its unit on the x axis, the probability from 0 to 1 on the y axis. Saves to
        ``path`` (PNG, SVG, PDF) if given; returns the axes."""
        fig = None
        if ax is None:
            from matplotlib.backends.backend_agg import FigureCanvasAgg
            from matplotlib.figure import Figure

            fig = Figure(figsize=(6.4, 4.6), layout="constrained")
            FigureCanvasAgg(fig)
            ax = fig.add_subplot()
        if self.levels is not None:
            top = float(self.levels.max())
            frac = self.z / self.n
            ax.scatter(self.levels, frac, s=12.0 + 200.0 * self.n / self.n.max(), facecolors="none",
                       edgecolors="C0", lw=1.5, zorder=3, label="fraction exceeded, z/n (area ~ n)")
            for x, f, n, z in zip(self.levels, frac, self.n, self.z):
                ax.annotate(f"{int(z)}/{int(n)}", (x, f), textcoords="offset points", xytext=(6, -10), fontsize=7)
        else:
            total = self.collapse_ims.size + self.censored_ims.size
            xs = np.sort(self.collapse_ims)
            ecdf = np.arange(1, xs.size + 1) / total
            ax.step(np.concatenate([[0.0], xs]), np.concatenate([[0.0], ecdf]), where="post", color="C0", lw=1)
            what = "collapse" if self.event == "collapse" else "exceedance"
            ax.plot(xs, ecdf, "o", color="C0", ms=5, zorder=3, label=f"{what} IMs, empirical CDF ({total} records)")
            top = float(xs.max())
            if self.censored_ims.size:
                ax.plot(self.censored_ims, np.full(self.censored_ims.size, ecdf[-1]), ">", color="C3", ms=7,
                        label=f"no {what} up to this IM ({self.censored_ims.size})")
                top = max(top, float(self.censored_ims.max()))
        top = max(top, float(self.theta * math.exp(2.0 * self.beta)))
        x = np.linspace(0.0, 1.15 * top, 400)
        ax.plot(x, self.probability(x), "k-", lw=2,
                label=f"lognormal MLE: θ = {self.theta:.3g}{self._unit()} (SE {self.se_theta:.2g}), "
                      f"β = {self.beta:.3f} (SE {self.se_beta:.2g})")
        ax.set_xlim(0.0, 1.15 * top)
        ax.set_ylim(-0.02, 1.02)  # the probability from 0 to 1, the points on 0 and 1 whole
        ax.set_xlabel(self.im_label)
        ax.set_ylabel(f"P({self.event} | IM) [-]")
        ax.set_title(f"Fragility, {self.method}", fontsize=10)
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7, loc="lower right")
        if fig is not None and path is not None:
            fig.savefig(path, dpi=120)
        return ax


def markdown_table(fragilities) -> str:
    """One row per fragility: the event, the method, the IM, theta and beta with their standard errors,
    and the data's size."""
    fragilities = list(fragilities)
    for k, f in enumerate(fragilities):
        if not isinstance(f, Fragility):
            raise _checks.type_error(f"fragilities[{k}]", f"expected a Fragility, got {type(f).__name__}")
    rows = ["| event | method | IM | θ | SE(θ) | β | SE(β) | data |", "|---|---|---|---:|---:|---:|---:|---|"]
    return "\n".join(rows + [f.row() for f in fragilities]) + "\n"


# ---- the likelihood in (a, b) = (1 / beta, -ln theta / beta) ------------------------------------------

def _log_ndtr_and_mills(u):
    """ln Phi(u) and the inverse Mills ratio phi(u) / Phi(u), without underflow far in the tails."""
    from scipy.special import log_ndtr

    log_cdf = log_ndtr(u)
    mills = np.exp(-0.5 * u * u - 0.5 * math.log(2.0 * math.pi) - log_cdf)
    return log_cdf, mills


class _Likelihood:
    """The log-likelihood of ln IM data: binomial stripes (x, n, z), exact values (density terms) and
    right-censored values, with its gradient and Hessian in (a, b); u = a x + b."""

    def __init__(self, *, x_stripes=(), n=(), z=(), x_exact=(), x_censored=()):
        from scipy.special import gammaln

        self.xs, self.n, self.z = (np.asarray(v, dtype=float) for v in (x_stripes, n, z))
        self.xe = np.asarray(x_exact, dtype=float)
        self.xc = np.asarray(x_censored, dtype=float)
        # the constants: ln C(n, z) of the binomials, ln(1 / (IM sqrt(2 pi))) of the densities of the IMs
        self.constant = float(np.sum(gammaln(self.n + 1) - gammaln(self.z + 1) - gammaln(self.n - self.z + 1))
                              - np.sum(self.xe) - 0.5 * self.xe.size * math.log(2.0 * math.pi))

    def __call__(self, p, derivatives: bool = True):
        a, b = p
        value, g, H = self.constant, np.zeros(2), np.zeros((2, 2))
        terms = []  # (x, weight of ln Phi(s u), s): d/du and d2/du2 of ln Phi(s u) are s m and -m (s u + m)
        if self.xs.size:
            terms += [(self.xs, self.z, 1.0), (self.xs, self.n - self.z, -1.0)]
        if self.xc.size:
            terms.append((self.xc, np.ones(self.xc.size), -1.0))
        for x, w, s in terms:
            u = s * (a * x + b)
            log_cdf, m = _log_ndtr_and_mills(u)
            keep = w > 0  # 0 ln Phi(-inf) is 0
            value += float(np.sum(w[keep] * log_cdf[keep]))
            if derivatives:
                d1 = np.where(keep, w * s * m, 0.0)
                d2 = np.where(keep, -w * m * (u + m), 0.0)
                g += [np.sum(d1 * x), np.sum(d1)]
                H += [[np.sum(d2 * x * x), np.sum(d2 * x)], [np.sum(d2 * x), np.sum(d2)]]
        if self.xe.size:  # ln a - u^2 / 2 per value (plus the constant)
            u = a * self.xe + b
            value += self.xe.size * math.log(a) - 0.5 * float(np.sum(u * u))
            if derivatives:
                g += [self.xe.size / a - np.sum(u * self.xe), -np.sum(u)]
                H += [[-self.xe.size / a**2 - np.sum(self.xe**2), -np.sum(self.xe)],
                      [-np.sum(self.xe), -float(self.xe.size)]]
        return value, g, H

    def maximise(self, start):
        """Newton's method on the concave log-likelihood, halving the step until it rises (and a stays
        > 0 where densities need it)."""
        p = np.asarray(start, dtype=float)
        value, g, H = self(p)
        for _ in range(_MAX_NEWTON):
            try:
                step = -np.linalg.solve(H, g)
            except np.linalg.LinAlgError:
                step = g * 1e-3
            if g @ step <= 0:  # not an ascent direction (round-off near the maximum): steepest ascent
                step = g / max(1.0, float(np.abs(H).max()))
            t = 1.0
            while t > 1e-12:
                q = p + t * step
                if not (self.xe.size and q[0] <= 0):
                    v, gq, Hq = self(q)
                    if np.isfinite(v) and v >= value - 1e-12 * abs(value):
                        break
                t *= 0.5
            else:
                break
            done = np.max(np.abs(q - p)) <= 1e-13 * (1.0 + np.max(np.abs(p)))
            p, value, g, H = q, v, gq, Hq
            if done:
                break
        return p, value, H


def _result(lik: _Likelihood, start, **fields) -> Fragility:
    blame = fields.pop("_blame")
    (a, b), value, H = lik.maximise(start)
    if not a > 0:
        raise _checks.value_error(blame, "the fraction exceeded falls as the IM rises: no increasing lognormal "
                                         "fragility fits these data")
    mu, beta = -b / a, 1.0 / a
    # observed information in (a, b), carried to (mu, beta) = (-b / a, 1 / a): at the maximum the
    # covariance transforms with the Jacobian J of that map, cov = J (-H)^-1 J^T
    J = np.array([[b / a**2, -1.0 / a], [-1.0 / a**2, 0.0]])
    try:
        cov = J @ np.linalg.inv(-H) @ J.T
        se_mu, se_beta = (math.sqrt(v) if v >= 0 else math.nan for v in np.diag(cov))
    except np.linalg.LinAlgError:
        se_mu = se_beta = math.nan
    theta = math.exp(mu)
    return Fragility(theta=theta, beta=beta, se_theta=theta * se_mu, se_beta=se_beta, log_likelihood=value,
                     **fields)


def _positive_ims(name: str, x, *, allow_empty: bool = False) -> np.ndarray:
    a = _checks.real_array(name, x)
    if a.ndim == 0:
        a = a.reshape(1)
    if a.ndim != 1:
        raise _checks.value_error(name, f"expected a list of intensities, got shape {a.shape}")
    if a.size == 0 and not allow_empty:
        raise _checks.value_error(name, "expected at least one intensity")
    if not np.all(np.isfinite(a)):
        raise _checks.value_error(name, "the intensities contain NaN or Inf")
    if np.any(a <= 0):
        raise _checks.value_error(name, f"intensities must be > 0, got {a[a <= 0][0]:g}")
    return a


def _label(name: str, value) -> str:
    if not isinstance(value, str):
        raise _checks.type_error(name, f"expected a string, got {type(value).__name__}")
    return value


def fit_collapse_ims(ims, *, censored=(), im_name: str = "IM", im_unit: str = "", event: str = "collapse") -> Fragility:
    """The lognormal fragility of the IMs at which the records made the structure collapse, by maximum
    likelihood. ``ims``: one collapse IM per record that collapsed. ``censored``: for each record that did
    not collapse, the highest IM it was run at (an IDA truncated there); it contributes the probability
    of collapsing above it, 1 - Phi(ln(im / theta) / beta). Without censoring the result is closed form:
    ln theta = mean(ln ims), beta = their standard deviation (n in the denominator; ``beta_sample`` has
    n - 1, Baker 2015 eq. 3). ``im_name``, ``im_unit`` and ``event`` label the table and the plot."""
    x_ims = _positive_ims("ims", ims)
    c_ims = _positive_ims("censored", censored, allow_empty=True)
    im_name, im_unit, event = _label("im_name", im_name), _label("im_unit", im_unit), _label("event", event)
    xe, xc = np.log(x_ims), np.log(c_ims)
    distinct = np.unique(xe)
    if distinct.size < 2 and not np.any(xc > distinct[0]):
        raise _checks.value_error("ims", f"every collapse IM is {x_ims[0]:g} and no record outlasted it: the "
                                         "dispersion has no maximum-likelihood estimate (beta -> 0); at least "
                                         "two distinct collapse IMs are needed")
    fields = dict(method="truncated" if c_ims.size else "collapse IM values", im_name=im_name, im_unit=im_unit,
                  event=event, collapse_ims=x_ims, censored_ims=c_ims, _blame="ims")
    lik = _Likelihood(x_exact=xe, x_censored=xc)
    sd = float(np.std(xe)) if distinct.size > 1 else float(np.std(np.concatenate([xe, xc])))
    start = (1.0 / sd, -float(np.mean(xe)) / sd)
    frag = _result(lik, start, **fields)
    if not c_ims.size:
        # the closed form; the Newton result equals it to round-off, this removes even that
        mu, beta = float(np.mean(xe)), float(np.std(xe))
        frag.theta, frag.beta = math.exp(mu), beta
        frag.se_theta, frag.se_beta = frag.theta * beta / math.sqrt(xe.size), beta / math.sqrt(2.0 * xe.size)
        frag.log_likelihood = lik((1.0 / beta, -mu / beta), derivatives=False)[0]
        frag.beta_sample = float(np.std(xe, ddof=1)) if xe.size > 1 else None
    return frag


def _counts(name: str, x, size: int) -> np.ndarray:
    a = _checks.real_array(name, x)
    if a.ndim == 0:
        a = np.full(size, float(a))
    if a.shape != (size,):
        raise _checks.value_error(name, f"expected {size} counts (one per IM level), got shape {a.shape}")
    if not np.all(np.isfinite(a)) or np.any(a != np.round(a)) or np.any(a < 0):
        raise _checks.value_error(name, "expected whole numbers >= 0")
    return a


def fit_stripes(ims, n, z, *, im_name: str = "IM", im_unit: str = "", event: str = "exceedance") -> Fragility:
    """The lognormal fragility of multiple-stripe data by maximum likelihood (Baker 2015): at the IM level
    ``ims[j]``, ``z[j]`` of ``n[j]`` runs exceeded (``n`` may be one number for every level). Truncated
    IDA data fit the same way: a record stopped below a level counts at the levels it was run at.
    Refused (naming ``z``) when the maximum does not exist: no exceedance at all, all runs exceeded at
    every level, or the data separated by an IM (nothing exceeds below it, everything above it)."""
    x_ims = _positive_ims("ims", ims)
    n = _counts("n", n, x_ims.size)
    z = _counts("z", z, x_ims.size)
    if np.any(n < 1):
        raise _checks.value_error("n", "every IM level needs at least one run")
    if np.any(z > n):
        j = int(np.argmax(z > n))
        raise _checks.value_error("z", f"more exceedances than runs at IM {x_ims[j]:g} ({z[j]:g} > {n[j]:g})")
    im_name, im_unit, event = _label("im_name", im_name), _label("im_unit", im_unit), _label("event", event)
    order = np.argsort(x_ims, kind="stable")
    x_ims, n, z = x_ims[order], n[order], z[order]
    if not z.any():
        raise _checks.value_error("z", "no run exceeded at any IM level: the median lies beyond the data and "
                                       "the maximum-likelihood estimate does not exist (theta -> infinity)")
    if np.all(z == n):
        raise _checks.value_error("z", "every run exceeded at every IM level: the maximum-likelihood estimate "
                                       "does not exist (theta -> 0)")
    lowest_exceeded = x_ims[z > 0].min()
    highest_not = x_ims[z < n].max()
    if highest_not <= lowest_exceeded:
        raise _checks.value_error("z", f"the data are separated at IM {lowest_exceeded:g}: no run exceeds below "
                                       "it and none is left unexceeded above it, so the likelihood grows as "
                                       "beta -> 0 and has no maximum; more runs, or IM levels in between, "
                                       "are needed")
    if x_ims[z < n].min() >= x_ims[z > 0].max():
        raise _checks.value_error("z", "every exceedance lies below every non-exceedance: the fraction "
                                       "exceeded falls as the IM rises and no increasing fragility fits")
    xs = np.log(x_ims)
    # start: a least-squares probit line through the fractions pulled off 0 and 1
    from scipy.special import ndtri

    q = ndtri((z + 0.5) / (n + 1.0))
    slope, intercept = np.polyfit(xs, q, 1, w=np.sqrt(n)) if np.unique(xs).size > 1 else (1.0, 0.0)
    start = (slope, intercept) if slope > 0 else (1.0 / max(np.std(xs), 0.1), -np.mean(xs) / max(np.std(xs), 0.1))
    lik = _Likelihood(x_stripes=xs, n=n, z=z)
    return _result(lik, start, method="multiple stripes", im_name=im_name, im_unit=im_unit, event=event,
                   levels=x_ims, n=n.astype(int), z=z.astype(int), _blame="z")


# ---- from an incremental dynamic analysis -------------------------------------------------------------

def from_ida(ida, *, demand_limit: float | None = None) -> Fragility:
    """A fragility from an incremental dynamic analysis (``nvib.ida``), the IM being the IDA's intensity
    measure (Sa(T1), PGA, a scale factor ...).

    Without ``demand_limit``: the collapse fragility, from each record's first collapsing intensity (traced
    by hunt and fill, within the IDA's tolerance of its capacity); a record that never collapsed is censored
    at the highest intensity it was run at (``fit_collapse_ims``). With ``demand_limit`` (in the units of
    the IDA's measure, % for a drift ratio): the fragility of the demand exceeding it, a collapse counted as
    an exceedance: from each traced curve's intensity where the demand reaches the limit (interpolated
    between its runs; censored at its highest run when it never does), or for stripes from the number of
    records exceeding it at each level (``fit_stripes``)."""
    from .ida import IDA

    if not isinstance(ida, IDA):
        raise _checks.type_error("ida", f"expected an IDA (nvib.ida's result), got {type(ida).__name__}")
    if demand_limit is not None:
        demand_limit = _checks.real("demand_limit", demand_limit, positive=True)
    name, unit = ida.im_name, ida.im_unit
    if any(np.any(c.im <= 0) for c in ida.curves):
        raise _checks.value_error("ida", "its intensities must be > 0 for a lognormal fragility")
    if demand_limit is None:
        first = [c.collapse_im for c in ida.curves if np.isfinite(c.collapse_im)]
        censored = [float(c.im.max()) for c in ida.curves if not np.isfinite(c.collapse_im)]
        if not first:
            raise _checks.value_error("ida", "no record collapsed at any intensity: there is no collapse "
                                             "fragility to fit (raise the intensities)")
        return fit_collapse_ims(first, censored=censored, im_name=name, im_unit=unit, event="collapse")
    limit = f"{demand_limit:g}" + (f" {ida.measure_unit}" if ida.measure_unit else "")
    event = f"{ida.measure_name} > {limit}"
    try:
        if ida.tolerance is not None:  # traced curves: the intensity where each reaches the limit
            reached = [c.im_at(demand_limit) for c in ida.curves]
            ims = [x for x in reached if np.isfinite(x)]
            censored = [float(c.im.max()) for c, x in zip(ida.curves, reached) if not np.isfinite(x)]
            if not ims:
                raise _checks.value_error("demand_limit", f"no record reached {limit}: raise the intensities")
            return fit_collapse_ims(ims, censored=censored, im_name=name, im_unit=unit, event=event)
        exceeded = ida.collapsed | (ida.measure > demand_limit)
        n = np.full(ida.levels.size, len(ida.records))
        return fit_stripes(ida.levels, n, exceeded.sum(axis=0).astype(float), im_name=name, im_unit=unit,
                           event=event)
    except _checks.ArgumentError as exc:
        if exc.argument == "demand_limit":
            raise
        raise _checks.value_error("demand_limit", f"at {limit}, {exc.reason}") from None
