"""Reference solutions: ``reference(model, t_end)``.

A closed form where one exists for the model as declared:

- one DOF with only linear springs and dampers (damping ratio < 1): the
  free linear oscillator (``exact.linear_sdof``);
- one DOF with one hardening spring: x = A cn(w (t + tau) | m_e)
  (``exact.hardening``);
- one DOF with one pendulum gravity law that swings (does not go over the
  top): theta = 2 arcsin(k sn(w0 t + u0 | k^2)) (``exact.pendulum``).

Otherwise a DOP853 solve of the first-order form y = [u; v],
y' = [v; M^-1 (-f(u, v, t))], where f is the model's own force
(``Model.evaluate_force``: the C++ effects, or the user's callable), at
rtol = 1e-12 and atol_i = rtol x scale_i, scale_i = the peak of |y_i| in a
pilot solve (rtol 1e-6), floored at 1e-3 x the largest peak of its kind
(displacements, velocities) so that a component that stays at zero (the
pitch of a symmetric vehicle) does not demand an absolute error of 1e-30.
The Hertz contact force (d/G)^{3/2} has an unbounded second derivative
where a contact opens or closes; the solve stops there (an event on the
contact measure) and restarts, so no step straddles the kink. The result
carries DOP853's dense output (its 7th-order interpolant), so it can be
evaluated at any time, and ``check=True`` repeats the solve at rtol / 10 and
records the largest difference (``check_difference``, relative to the peak
of each DOF's displacement).
"""

from __future__ import annotations

import math
import weakref

import numpy as np

from .. import _checks
from .._model import Model
from . import exact

DOP853_RTOL = 1e-12
SCALE_FLOOR = 1e-3  # a component's tolerance scale is at least this fraction of its kind's largest peak
_CACHE: "weakref.WeakKeyDictionary[Model, dict]" = weakref.WeakKeyDictionary()


class Reference:
    """A reference trajectory: ``ref(t) -> (u, v)``, each of shape (len(t), n).

    kind : 'closed_form' or 'dop853'; description : what it is, in words;
    for DOP853 also rtol, atol (per component of [u; v]), num_force_evals,
    num_segments (restarts at contact events + 1) and, when checked,
    check_rtol and check_difference (max over 20,001 times of |u - u_tighter| per DOF,
    relative to that DOF's peak |u|, floored like the tolerance scale)."""

    def __init__(self, model: Model, kind: str, description: str, t0: float, t_end: float, evaluate):
        self.kind = kind
        self.description = description
        self.t0 = t0
        self.t_end = t_end
        self.n = model.n
        self.dofs = list(model.dofs)
        self._evaluate = evaluate
        self.rtol = None
        self.atol = None
        self.num_force_evals = 0
        self.num_segments = 0
        self.check_rtol = None
        self.check_difference = None

    def __call__(self, t) -> tuple[np.ndarray, np.ndarray]:
        t = np.atleast_1d(np.asarray(t, dtype=float))
        if t.ndim != 1:
            raise _checks.value_error("t", f"expected a 1-D array of times, got shape {t.shape}")
        span = self.t_end - self.t0
        if t.size and (t.min() < self.t0 - 1e-9 * span or t.max() > self.t_end + 1e-9 * span):
            raise _checks.value_error("t", f"the reference covers [{self.t0:g}, {self.t_end:g}], "
                             f"got times in [{t.min():g}, {t.max():g}]")
        return self._evaluate(t)

    def u(self, t, dofs=None) -> np.ndarray:
        """Displacements at the times t (len(t), n), or of the given DOFs only."""
        u = self(t)[0]
        return u if dofs is None else u[:, self._columns(dofs)]

    def v(self, t, dofs=None) -> np.ndarray:
        v = self(t)[1]
        return v if dofs is None else v[:, self._columns(dofs)]

    def _columns(self, dofs) -> list[int]:
        if isinstance(dofs, (str, int)):
            dofs = [dofs]
        out = []
        for d in dofs:
            if isinstance(d, str):
                if d not in self.dofs:
                    raise _checks.value_error("dofs", f"unknown DOF {d!r} (known: {', '.join(self.dofs)})")
                out.append(self.dofs.index(d))
            else:
                if not 0 <= int(d) < self.n:
                    raise _checks.value_error("dofs", f"index {d} out of range for {self.n} DOFs")
                out.append(int(d))
        return out

    def __repr__(self) -> str:
        return f"Reference({self.kind!r}, t = [{self.t0:g}, {self.t_end:g}]: {self.description})"


# ---------------------------------------------------------------- first-order form (shared with cost's SciPy peers)

class FirstOrder:
    """y = [u; v], y' = rhs(t, y) = [v; -M^-1 f(u, v, t)] with the model's own force, and its Jacobian."""

    def __init__(self, model: Model):
        self.n = n = model.n
        self._force = model._core.force
        self._tangent = model._core.tangent
        mass = np.asarray(model.mass_matrix, dtype=float)
        self.diagonal = bool(np.all(mass == np.diag(np.diag(mass))))
        if self.diagonal:
            self._minv = 1.0 / np.diag(mass)
        else:
            from scipy import linalg

            self._cho = linalg.cho_factor(mass)
        self.num_rhs = 0
        self.num_jac = 0
        del n

    def minv(self, x: np.ndarray) -> np.ndarray:
        if self.diagonal:
            return (self._minv * x.T).T if x.ndim == 2 else self._minv * x
        from scipy import linalg

        return linalg.cho_solve(self._cho, x)

    def rhs(self, t: float, y: np.ndarray) -> np.ndarray:
        n = self.n
        self.num_rhs += 1
        u = np.ascontiguousarray(y[:n])
        v = np.ascontiguousarray(y[n:])
        out = np.empty(2 * n)
        out[:n] = v
        out[n:] = -self.minv(self._force(u, v, t))
        return out

    def jac(self, t: float, y: np.ndarray) -> np.ndarray:
        n = self.n
        self.num_jac += 1
        K, C = self._tangent(np.ascontiguousarray(y[:n]), np.ascontiguousarray(y[n:]), t)
        J = np.zeros((2 * n, 2 * n))
        J[:n, n:] = np.eye(n)
        J[n:, :n] = -self.minv(np.asarray(K))
        J[n:, n:] = -self.minv(np.asarray(C))
        return J


def contact_measures(model: Model) -> np.ndarray:
    """Rows g of the measures d = g . u of the Hertz contacts on a smooth rail (where the force has its kink)."""
    rows = []
    for e in model.effects or []:
        if e.type == "hertz_contact" and not e.uses_time:  # with an irregularity the kink is at d = r(t)
            g = np.zeros(model.n)
            g[list(e.index)] = list(e.coef)
            rows.append(g)
    return np.array(rows).reshape(len(rows), model.n)


def tolerance_scale(model: Model, t0: float, t_end: float, u0: np.ndarray, v0: np.ndarray) -> np.ndarray:
    """Per-component scale of [u; v] for atol = rtol x scale: peaks of a pilot DOP853 solve (rtol 1e-6),
    each floored at SCALE_FLOOR x the largest peak of its kind."""
    from scipy.integrate import solve_ivp

    sys = FirstOrder(model)
    y0 = np.concatenate((u0, v0))
    base = max(1.0, float(np.max(np.abs(y0))))
    sol = solve_ivp(sys.rhs, (t0, t_end), y0, method="DOP853", rtol=1e-6, atol=1e-9 * base)
    if not sol.success or not np.all(np.isfinite(sol.y)):
        raise _checks.value_error("model", f"the pilot solve for the tolerance scales failed ({sol.message})")
    return scale_from_peaks(np.max(np.abs(sol.y), axis=1), model.n)


def scale_from_peaks(peak: np.ndarray, n: int) -> np.ndarray:
    """Per-component scale of [u; v] from their peaks, each floored at SCALE_FLOOR x the
    largest peak of its kind (displacements, velocities); 1 where a kind never moves."""
    scale = np.empty_like(peak)
    for part in (slice(0, n), slice(n, 2 * n)):
        top = float(np.max(peak[part]))
        scale[part] = np.maximum(peak[part], SCALE_FLOOR * top) if top > 0 else 1.0
    return scale


# ---------------------------------------------------------------- closed forms

def _closed_form(model: Model, u0: np.ndarray, v0: np.ndarray):
    """(description, evaluate) for the one-DOF models with a known solution, else None."""
    if model.n != 1 or model.force is not None or model.python_laws:
        return None
    effects = list(model.effects or [])
    if any(e.is_load or e.uses_time for e in effects):
        return None
    m = float(model.mass_matrix[0, 0])
    x0, xv0 = float(u0[0]), float(v0[0])
    k_lin = float(model.K.toarray()[0, 0])
    c_lin = float(model.C.toarray()[0, 0])
    nonlinear = [e for e in effects if not e.is_linear]
    if not nonlinear:
        if k_lin <= 0:
            return None
        w = math.sqrt(k_lin / m)
        xi = c_lin / (2.0 * m * w)
        if not 0.0 <= xi < 1.0:
            return None

        def linear(t):
            x, v = exact.linear_sdof(t, m=m, k=k_lin, c=c_lin, x0=x0, v0=xv0)
            return x[:, None], v[:, None]

        return f"closed form: free linear oscillator (m = {m:g}, k = {k_lin:g}, c = {c_lin:g})", linear
    if len(nonlinear) != 1 or k_lin != 0.0 or c_lin != 0.0:
        return None
    e = nonlinear[0]
    (g,) = e.coef
    p = e.parameters  # the law's declared parameters by name
    if e.type == "hardening_spring":
        # law f(d) = k0 (1 + a d^2) d acting on d = g x: m x'' + g k0 (1 + a g^2 x^2) g x = 0
        if not (p["k0"] > 0 and p["a"] >= 0):
            return None
        kk, aa = g * g * p["k0"], p["a"] * g * g

        def hardening(t):
            x, v = exact.hardening(t, m=m, k0=kk, a=aa, x0=x0, v0=xv0)
            return x[:, None], v[:, None]

        return (f"closed form: x = A cn(w (t + tau) | m) of m x'' + k0 (1 + a x^2) x = 0 "
                f"(m = {m:g}, k0 = {kk:g}, a = {aa:g})"), hardening
    if e.type == "pendulum_gravity":
        # law f(d) = m g l sin(d)
        mgl = p["m"] * p["g"] * p["l"]
        if not mgl > 0:
            return None
        # phi = g theta: phi'' + w0^2 sin(phi) = 0 with w0^2 = g^2 m g l / I
        w0 = math.sqrt(g * g * mgl / m)
        try:
            exact.pendulum_period(omega0=w0, theta0=g * x0, v0=g * xv0)
        except ValueError:  # over the top: no closed form here
            return None

        def pendulum(t):
            th, om = exact.pendulum(t, omega0=w0, theta0=g * x0, v0=g * xv0)
            return (th / g)[:, None], (om / g)[:, None]

        return (f"closed form: theta = 2 arcsin(k sn(w0 t + u0 | k^2)) (Jacobi elliptic), w0 = {w0:.6g} rad/s",
                pendulum)
    return None


# ---------------------------------------------------------------- DOP853

def _segmented_dop853(model: Model, t0: float, t_end: float, y0: np.ndarray, rtol: float, atol: np.ndarray):
    """DOP853 from t0 to t_end, stopping and restarting where a contact measure crosses zero.
    Returns (list of OdeSolution pieces, their end times, number of force evaluations)."""
    from scipy.integrate import solve_ivp

    sys = FirstOrder(model)
    G = contact_measures(model)
    n = model.n
    pieces, ends = [], []
    t, y = t0, y0.copy()
    for _ in range(100_000):
        events = []
        if len(G):
            gu, gv = G @ y[:n], G @ y[n:]
            tiny = 1e-12 * max(float(np.max(np.abs(y[:n]))), 1e-300)
            # the side each measure is on now (just at a crossing: the side it is heading to)
            side = np.where(np.abs(gu) > tiny, np.sign(gu), np.sign(gv))
            for j in range(len(G)):
                if side[j] == 0:
                    continue

                def crossing(tt, yy, g=G[j], s=side[j]):
                    return s * float(g @ yy[:n])

                crossing.terminal = True
                crossing.direction = -1
                events.append(crossing)
        sol = solve_ivp(sys.rhs, (t, t_end), y, method="DOP853", rtol=rtol, atol=atol, dense_output=True,
                        events=events or None)
        if sol.status == -1 or not np.all(np.isfinite(sol.y)):
            raise _checks.value_error("model", f"the DOP853 reference failed at t = {sol.t[-1]:g} ({sol.message})")
        if sol.t[-1] > t:
            pieces.append(sol.sol)
            ends.append(sol.t[-1])
        if sol.status == 0:
            break
        t, y = float(sol.t[-1]), sol.y[:, -1].copy()
    else:
        raise _checks.value_error("model", "the DOP853 reference stopped at 100000 contact events")
    return pieces, np.array(ends), sys.num_rhs


def _piecewise(pieces, ends, n: int):
    def evaluate(t):
        out = np.empty((2 * n, t.size))
        which = np.minimum(np.searchsorted(ends, t), len(pieces) - 1)
        for k in np.unique(which):
            sel = which == k
            out[:, sel] = pieces[k](t[sel])
        return np.ascontiguousarray(out[:n].T), np.ascontiguousarray(out[n:].T)

    return evaluate


def reference(model: Model, t_end: float, *, t0: float = 0.0, u0=None, v0=None, method: str = "auto",
              rtol: float = DOP853_RTOL, check: bool = False, cache: bool = True) -> Reference:
    """The reference solution of ``model`` on [t0, t_end] (from the model's u0, v0 unless given).

    method : 'auto' (a closed form where one exists, else DOP853), 'closed_form'
    (ValueError if there is none) or 'dop853'. rtol : DOP853's relative
    tolerance (atol scaled per component, see the module docstring). check :
    for DOP853, solve again at rtol / 10 and record the difference in
    ``check_difference``. References are cached per model within the process
    (same t0, t_end, initial state, method and rtol)."""
    if not isinstance(model, Model):
        raise _checks.type_error("model", f"expected nvib.Model, got {type(model).__name__}")
    t0 = _checks.real("t0", t0)
    t_end = _checks.real("t_end", t_end)
    if t_end <= t0:
        raise _checks.value_error("t_end", f"must be > t0 = {t0}, got {t_end}")
    if method not in ("auto", "closed_form", "dop853"):
        raise _checks.value_error("method", f"expected 'auto', 'closed_form' or 'dop853', got {method!r}")
    rtol = _checks.real("rtol", rtol, positive=True)
    if not 2.3e-14 <= rtol < 1.0:
        raise _checks.value_error("rtol", f"must be in [2.3e-14, 1) (DOP853 cannot go below 100 machine epsilons), got {rtol}")
    memory = [e.name or e.type for e in (model.effects or []) if e.has_state]
    if memory:  # DOP853 sees F(u, v, t) only: it would integrate every such law from its initial state
        raise _checks.value_error("model", f"its laws with memory ({', '.join(dict.fromkeys(memory))}) carry internal "
                                           "variables that DOP853 on F(u, v, t) cannot follow; measure against an "
                                           "nvib run at a much smaller step, or an adaptive run with a tight tol "
                                           "(its Result.error_estimate is measured against a companion run)")
    u0 = model.u0 if u0 is None else _checks.vector("u0", u0, model.n)
    v0 = model.v0 if v0 is None else _checks.vector("v0", v0, model.n)
    key = (t0, t_end, u0.tobytes(), v0.tobytes(), method, rtol)
    store = _CACHE.setdefault(model, {}) if cache else {}
    hit = store.get(key)
    if hit is not None and (not check or hit.kind != "dop853" or hit.check_difference is not None):
        return hit

    closed = None if method == "dop853" else _closed_form(model, u0, v0)
    if closed is not None:
        description, fn = closed
        shift = t0

        def evaluate(t):
            return fn(t - shift)

        ref = Reference(model, "closed_form", description, t0, t_end, evaluate)
    elif method == "closed_form":
        raise _checks.value_error("method", "no closed form is known for this model (one DOF with linear springs and "
                         "dampers, one hardening spring, or one swinging pendulum); use 'auto' or 'dop853'")
    else:
        scale = tolerance_scale(model, t0, t_end, u0, v0)
        y0 = np.concatenate((u0, v0))
        pieces, ends, nfev = _segmented_dop853(model, t0, t_end, y0, rtol, rtol * scale)
        nseg = len(pieces)
        ref = Reference(model, "dop853",
                        f"DOP853 (scipy), rtol = {rtol:g}, atol = rtol x per-component scale"
                        + (f", restarted at {nseg - 1} contact events" if nseg > 1 else ""),
                        t0, t_end, _piecewise(pieces, ends, model.n))
        ref.rtol, ref.atol, ref.num_force_evals, ref.num_segments = rtol, rtol * scale, nfev, nseg
        if check:
            tight = max(rtol / 10.0, 2.3e-14)
            p2, e2, _ = _segmented_dop853(model, t0, t_end, y0, tight, tight * scale)
            grid = np.linspace(t0, t_end, 20_001)
            ua = ref.u(grid)
            ub = _piecewise(p2, e2, model.n)(grid)[0]
            peak = np.max(np.abs(ub), axis=0)
            peak = np.maximum(peak, max(SCALE_FLOOR * float(np.max(peak)), 1e-300))
            ref.check_rtol = tight
            ref.check_difference = np.max(np.abs(ua - ub), axis=0) / peak
    if cache:
        store[key] = ref
    return ref
