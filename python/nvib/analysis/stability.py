"""Linear stability and accuracy of the schemes, measured on the stepper itself.

The test problem is the linear oscillator ü + 2ξω u̇ + ω² u = 0, built as
``Model([1], K=[[1]], C=[[2ξ]])`` (ω = 1 rad/s) and stepped with Δt = Ω, so
Ω = ωΔt. One step of a linear model is a linear map of the carried state
(``Stepper.state()``: [u; v; a] and the scheme's history), so stepping once
from each unit state gives the amplification matrix column by column: the
C++ stepper itself is measured, not a formula written beside it. The matrix
is returned in the scaled state (u, Δt v, Δt² a, Δt² a_{n-1}, Δt² r, ...),
the form of Hughes (2000, section 9.1) in which it depends on Ω and ξ only.

Eigenvalues of a one-step scheme for this problem:

* The **spectral radius** ρ(Ω) is the largest |λ| over *all* eigenvalues,
  spurious ones included: the state carries a and the history as independent
  numbers, and a growing spurious mode is an instability like any other
  (damped central difference has such a root that leaves the unit circle
  first). The extra roots are often 0 (Newmark: a_{n+1} is fixed by u_{n+1}
  and v_{n+1}; PIM: its history of nonlinear remainders is 0 for a linear
  model).
* The **principal roots** are the complex-conjugate pair that tends to the
  exact exp(Ω(-ξ ± i√(1-ξ²))) as Ω → 0. They are found at Ω = 1e-3 (the
  upper root nearest the exact one) and continued in Ω in small steps, the
  step shrinking wherever two roots are near enough to be confused. Where the
  continued root reaches the real axis, the principal pair, and with it the
  period and damping, is undefined from there on and those functions return
  NaN. This happens where the pair splits into two real roots (central
  difference at Ω = 2 undamped, a little below its limit when damped) and
  where it passes through -1 (the exact root of PIM at Ω = π: beyond the
  Nyquist frequency π/Δt no sampled solution shows the true frequency).
  Schemes whose root only approaches -1 (Newmark, generalized-α) stay defined.

Period and damping of the principal root λ (the standard definitions of
Hughes 2000, section 9.3, and Chung & Hulbert 1993, written for a damped
oscillator): with s = ln λ (arg λ in (0, π)), the numerical solution is that
of an oscillator of natural frequency ω̄ = |s|/Δt, damping ratio
ξ̄ = -Re s/|s| and damped frequency ω̄_d = Im s/Δt. ``period_error`` is the
relative elongation of the damped period, T̄_d/T_d - 1 = Ω√(1-ξ²)/arg λ - 1;
``damping_ratio`` is ξ̄, so the algorithmic damping is ξ̄ - ξ. With ξ = 0
these are Hughes' (T̄ - T)/T exactly, and his ξ̄ = -ln|λ|/arg λ (= ξ̄/√(1-ξ̄²))
to third order in ξ̄; for the exact integrator they are 0 and ξ for every ξ.
Round-off bounds both to about ε/Ω² absolute (measured: 1e-10 at Ω = 1e-3,
1e-12 at Ω = 1e-2), the two roots being only 2Ω apart near λ = 1.

References: Hughes T.J.R., *The Finite Element Method*, Dover 2000, ch. 9;
Chung J., Hulbert G.M., J. Appl. Mech. 60 (1993) 371-375.
"""

from __future__ import annotations

import math
import dataclasses

import numpy as np

from .. import _checks, _core, _labels
from .._errors import NvibError
from .._model import Model
from .._schemes import check_scheme
from .._solve import Stepper

OMEGA_START = 1e-3   # where the principal roots are picked out (nearest the exact root)
OMEGA_LIMIT = 1e4    # default upper end of the search for Ω_crit
RHO_TOL = 1e-6       # ρ > 1 + RHO_TOL counts as unstable (see critical_omega_h)
# Ω accepted: the scaling spans Ω^±2 between entries; below 1e-6 the implicit schemes'
# residuals underflow, and every scheme other than PIM still steps at 1e7
OMEGA_RANGE = (1e-6, 1e7)
_MAX_RATIO = 1.1     # largest ratio between consecutive Ω of the continuation
_MIN_RATIO = 1e-9    # below this step (relative) an ambiguous match is accepted


# ---------------------------------------------------------------- input checks

XI_MAX = 1e8        # largest damping ratio the amplification matrix is built for (C = 2ξ on ω = 1)


def _check_xi(xi, *, overdamped: bool = False) -> float:
    """ξ in [0, 1): the principal roots (period, damping) need an oscillating pair; with ``overdamped``
    ξ ≥ 1 too (up to XI_MAX): the amplification matrix, its spectral radius and Ω_crit need no such pair."""
    xi = _checks.real("xi", xi)
    if overdamped:
        if not 0.0 <= xi <= XI_MAX:
            raise _checks.value_error("xi", f"the damping ratio needs 0 <= xi <= {XI_MAX:g}, got {xi}")
    elif not 0.0 <= xi < 1.0:
        raise _checks.value_error("xi", f"the damping ratio needs 0 <= xi < 1 (an oscillating principal pair), "
                                        f"got {xi}")
    return xi


def _omegas(omega_h) -> tuple[np.ndarray, tuple]:
    """Ω as a flat float array and the shape to give results (() for a scalar)."""
    if isinstance(omega_h, (bool, np.bool_)):
        raise _checks.type_error("omega_h", "expected a real number or an array of them, got bool")
    try:
        arr = np.asarray(omega_h)
    except (TypeError, ValueError) as exc:
        raise _checks.type_error("omega_h", f"expected a real number or an array of them ({exc})") from None
    if arr.dtype == bool or not (np.issubdtype(arr.dtype, np.integer) or np.issubdtype(arr.dtype, np.floating)):
        raise _checks.type_error("omega_h", f"expected a real number or an array of them, got {arr.dtype} values")
    arr = arr.astype(float)
    if not np.all(np.isfinite(arr)):
        raise _checks.value_error("omega_h", "must be finite, got NaN or Inf")
    if np.any(arr <= 0.0):
        raise _checks.value_error("omega_h", f"must be > 0, got {arr[arr <= 0.0].flat[0]}")
    bad = (arr < OMEGA_RANGE[0]) | (arr > OMEGA_RANGE[1])
    if np.any(bad):
        raise _checks.value_error("omega_h", f"must lie in [{OMEGA_RANGE[0]:g}, {OMEGA_RANGE[1]:g}], got {arr[bad].flat[0]:g}")
    return arr.reshape(-1), arr.shape


def _shaped(values: np.ndarray, shape: tuple):
    out = values.reshape(shape)
    return out.item() if shape == () else out


def _oscillator(xi: float) -> Model:
    return Model([1.0], K=[[1.0]], C=[[2.0 * xi]])


# ---------------------------------------------------------------- amplification matrix

class _StepOverflow(ValueError):
    pass


def _matrix(scheme, om: float, model: Model) -> np.ndarray:
    """Amplification matrix of one step of Δt = om on the model, in the scaled state."""
    st = Stepper(model, scheme, om)
    n = st.state().size
    A = np.empty((n, n))
    e = np.zeros(n)
    for j in range(n):
        e[j] = 1.0
        st.set_state(e, 0.0)
        try:
            st.step()
        except NvibError as exc:  # the step itself is not finite (PIM's exponential at huge Ω)
            raise _StepOverflow(f"omega_h: one step at omega_h = {om:g} is not finite ({exc})") from None
        A[:, j] = st.state()
        e[j] = 0.0
    # (u, v, a, history...) -> (u, Δt v, Δt² a, Δt² history...): a, a_{n-1} and the
    # PIM remainders are all accelerations.
    d = np.full(n, om * om)
    d[0], d[1] = 1.0, om
    return A * d[:, None] / d[None, :]


def amplification_matrix(scheme, omega_h: float, xi: float = 0.0) -> np.ndarray:
    """Amplification matrix A of ``scheme`` for ü + 2ξω u̇ + ω² u = 0 at Ω = ωΔt.

    Built from the C++ stepper: column j is one step from the j-th unit state.
    x_{n+1} = A x_n with x = (u, Δt v, Δt² a, then the scheme's history scaled
    as accelerations: a_{n-1} for CEMDTS and Zhai, the order + 1 remainders of
    PreciseIntegration), with v = v_{n-1/2} for CentralDifference(half_step).
    Its size is 3 for CentralDifference, Newmark and GeneralizedAlpha, 4 for
    CEMDTS and Zhai, 3 + order + 1 for PreciseIntegration.
    """
    check_scheme("scheme", scheme)
    om = _checks.real("omega_h", omega_h, positive=True)
    _omegas(om)
    return _matrix(scheme, om, _oscillator(_check_xi(xi, overdamped=True)))


def _eigenvalues(scheme, om: float, model: Model) -> np.ndarray:
    """Eigenvalues of the amplification matrix; [inf] where one step is not finite."""
    try:
        return np.linalg.eigvals(_matrix(scheme, om, model))
    except _StepOverflow:
        return np.array([complex(math.inf, 0.0)])


def spectral_radius(scheme, omega_h, xi: float = 0.0):
    """max |λ| over all eigenvalues of the amplification matrix (spurious ones too);
    inf where one step from a unit state is not finite (PreciseIntegration with 20
    squarings from Ω ≈ 3e6: its exponential overflows).

    ``omega_h`` may be an array (values in OMEGA_RANGE): the result then has its shape; ``xi`` may be 1
    or more (an overdamped oscillator)."""
    check_scheme("scheme", scheme)
    xi = _check_xi(xi, overdamped=True)
    oms, shape = _omegas(omega_h)
    model = _oscillator(xi)
    rho = np.array([np.max(np.abs(_eigenvalues(scheme, om, model))) for om in oms])
    return _shaped(rho, shape)


# ---------------------------------------------------------------- principal roots

def _track(scheme, oms: np.ndarray, xi: float, model: Model) -> np.ndarray:
    """Upper principal root at each Ω of the ascending array ``oms`` (NaN where undefined).

    Predictor-corrector continuation: the root is predicted by linear extrapolation
    in Ω and matched to the nearest eigenvalue; a step is taken only if that match
    is unambiguous (the runner-up at least twice as far) and the root moved by less
    than 0.3 of its distance to the other roots (its conjugate aside), else the step
    is shortened. The continuation stops where the matched root is real or in the
    lower half-plane: the pair has split on the real axis, or passed through -1.
    """
    out = np.full(oms.size, complex(math.nan, math.nan))
    if oms.size == 0:
        return out
    om = min(OMEGA_START, float(oms[0]))
    lam = _eigenvalues(scheme, om, model)
    upper = lam[lam.imag > 0.0]
    if upper.size == 0:
        return out
    exact = np.exp(om * complex(-xi, math.sqrt(1.0 - xi * xi)))
    cur = upper[np.argmin(np.abs(upper - exact))]
    prev = None  # (Ω, root) of the step before, for the predictor
    i = 0
    while i < oms.size and oms[i] <= om:
        out[i] = cur
        i += 1
    ratio = _MAX_RATIO
    while i < oms.size:
        others = np.delete(lam, np.argsort(np.abs(lam - cur))[:1])
        if others.size:  # drop the conjugate too
            others = np.delete(others, np.argmin(np.abs(others - np.conj(cur))))
        gap = float(np.min(np.abs(others - cur))) if others.size else math.inf
        nxt = min(float(oms[i]), om * ratio)
        pred = cur if prev is None else cur + (cur - prev[1]) * (nxt - om) / (om - prev[0])
        new = _eigenvalues(scheme, nxt, model)
        if not np.all(np.isfinite(new)):
            break
        dist = np.abs(new - pred)
        order = np.argsort(dist)
        best = new[order[0]]
        ambiguous = new.size > 1 and dist[order[1]] < 2.0 * dist[order[0]]
        if (ambiguous or abs(best - cur) > 0.3 * gap) and nxt / om - 1.0 > _MIN_RATIO:
            ratio = math.sqrt(nxt / om)
            continue
        if best.imag <= 0.0:  # on or across the real axis: no principal pair from here on
            break
        prev, cur, om, lam = (om, cur), best, nxt, new
        if nxt == oms[i]:
            out[i] = cur
            i += 1
        ratio = min(_MAX_RATIO, ratio * ratio)
    return out


def principal_eigenvalue(scheme, omega_h, xi: float = 0.0):
    """The principal root λ with Im λ > 0 (its conjugate is the other one), NaN where
    the principal pair has become real. ``omega_h`` may be an array."""
    check_scheme("scheme", scheme)
    xi = _check_xi(xi)
    oms, shape = _omegas(omega_h)
    uniq, back = np.unique(oms, return_inverse=True)
    lam = _track(scheme, uniq, xi, _oscillator(xi))[back.reshape(-1)]
    return _shaped(lam, shape)


def _log_root(lam):
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.log(np.asarray(lam, dtype=complex))


def period_error(scheme, omega_h, xi: float = 0.0):
    """Relative elongation of the damped period, T̄_d/T_d - 1 = Ω√(1-ξ²)/arg λ - 1,
    of the principal root λ (see the module notes); NaN where the principal pair is real.
    ``omega_h`` may be an array."""
    xi = _check_xi(xi)
    lam = principal_eigenvalue(scheme, omega_h, xi)
    oms = np.asarray(omega_h, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        err = oms * math.sqrt(1.0 - xi * xi) / np.angle(lam) - 1.0
    return err.item() if np.ndim(err) == 0 else err


def damping_ratio(scheme, omega_h, xi: float = 0.0):
    """Damping ratio ξ̄ = -Re(ln λ)/|ln λ| of the numerical solution along the principal
    root λ (the algorithmic part is ξ̄ - ξ); NaN where the principal pair is real.
    ``omega_h`` may be an array."""
    xi = _check_xi(xi)
    s = _log_root(principal_eigenvalue(scheme, omega_h, xi))
    with np.errstate(divide="ignore", invalid="ignore"):
        zeta = -s.real / np.abs(s)
    return zeta.item() if np.ndim(zeta) == 0 else zeta


# ---------------------------------------------------------------- Ω_crit

def critical_omega_h(scheme, xi: float = 0.0, *, omega_max: float = OMEGA_LIMIT, tol: float = RHO_TOL,
                     points_per_decade: int = 50, omega_min: float = OMEGA_START) -> float:
    """Smallest Ω = ωΔt at which the spectral radius exceeds 1 + tol; math.inf if none
    up to ``omega_max`` (implicit schemes, PIM).

    A scan of ``points_per_decade`` log-spaced Ω from ``omega_min`` to ``omega_max``
    (both within OMEGA_RANGE) finds the first unstable point, then bisection between
    it and the stable point before it narrows the limit to 1e-10 relative. If the
    first point is already unstable the bisection starts from OMEGA_RANGE[0] = 1e-6
    (every consistent scheme has ρ → 1 as Ω → 0), which is returned if even that is
    unstable. An unstable window narrower than the scan spacing (a ratio
    10^(1/points_per_decade)) can be missed. A step that is not finite counts as
    unstable (see ``spectral_radius``).

    Why tol = 1e-6: ρ is the modulus of an eigenvalue of a matrix computed in floating
    point. Where ρ = 1 exactly it comes out within a few ulp, but where the principal
    pair coalesces (central difference at Ω = 2, a double root at -1) the eigenvalue
    error grows to √ε ≈ 1e-8, and the 2^N exponential of PIM carries round-off
    amplified 2^N times (ρ - 1 = 1e-10 at Ω = 1e6 with 30 squarings). 1e-6 sits well
    above these, and a growth of 1e-6 per step needs 7e5 steps to double an amplitude.
    Where ρ leaves 1 like √(Ω - Ω_crit) (a pair splitting on the real axis) the offset
    this causes in Ω_crit is ~1e-12; where it leaves 1 linearly it is ~tol.

    ``xi`` may be 1 or more: damping shrinks an explicit scheme's limit (central difference, whose
    damping force takes the predicted velocity v_n + Δt a_n, and Zhai(1/2, 1/2):
    Ω_crit = 2(√(1+4ξ²) - 2ξ), about 1/(2ξ) for large ξ), so a heavily damped top mode sets it.
    """
    check_scheme("scheme", scheme)
    xi = _check_xi(xi, overdamped=True)
    omega_max = _checks.real("omega_max", omega_max, positive=True)
    omega_min = _checks.real("omega_min", omega_min, positive=True)
    if omega_max > OMEGA_RANGE[1]:
        raise _checks.value_error("omega_max", f"must be <= {OMEGA_RANGE[1]:g}, got {omega_max:g}")
    if not OMEGA_RANGE[0] <= omega_min < omega_max:
        raise _checks.value_error("omega_min", f"must lie in [{OMEGA_RANGE[0]:g}, omega_max = {omega_max:g}), got {omega_min:g}")
    tol = _checks.real("tol", tol, positive=True)
    points_per_decade = _checks.integer("points_per_decade", points_per_decade, minimum=2)
    model = _oscillator(xi)

    def unstable(om: float) -> bool:
        return float(np.max(np.abs(_eigenvalues(scheme, om, model)))) > 1.0 + tol

    n = max(2, math.ceil(points_per_decade * math.log10(omega_max / omega_min)) + 1)
    lo = OMEGA_RANGE[0]
    if unstable(omega_min) and (omega_min == lo or unstable(lo)):
        return lo
    for om in np.geomspace(omega_min, omega_max, n):
        if unstable(float(om)):
            hi = float(om)
            break
        lo = float(om)
    else:
        return math.inf
    while hi - lo > 1e-10 * hi:
        mid = 0.5 * (lo + hi)
        if unstable(mid):
            hi = mid
        else:
            lo = mid
    return 0.5 * (lo + hi)


# ---------------------------------------------------------------- the step limit of a model

_DENSE_MODES = 300   # up to this many DOFs every mode is found (dense eigh), above it the top one (eigsh)


@dataclasses.dataclass(frozen=True)
class StepLimit:
    """The stability limit of an explicit scheme on a model's linear part (K and C, the linear springs
    and dampers included), at the mode that sets it: ``dt`` with that mode's damping ratio ``zeta``,
    ``dt_undamped`` the limit without damping, ``omega`` the mode's circular frequency [rad/s]."""

    dt: float
    dt_undamped: float
    omega: float
    zeta: float


def _modes(model: Model):
    """(ω, ζ) of the undamped modes of the model's linear part, symmetric parts of K and C (every mode
    up to _DENSE_MODES DOFs, else the highest one only); ζ_i = φ_iᵀ C φ_i / (2 ω_i) for the
    mass-normalised φ_i (modal damping; the coupling a non-proportional C adds is left out)."""
    from scipy import linalg, sparse
    from scipy.sparse import linalg as splinalg

    K, C, M = model.K, model.C, model.mass_sparse
    if K.nnz == 0:
        return np.empty(0), np.empty(0)
    K = 0.5 * (K + K.T)
    C = 0.5 * (C + C.T)
    if model.n <= _DENSE_MODES:
        w2, V = linalg.eigh(K.toarray(), M.toarray())
    else:
        d = M.diagonal()
        try:
            if M.nnz == model.n and np.all(d > 0):  # lumped: the symmetric form D^-1/2 K D^-1/2
                s = sparse.diags(1.0 / np.sqrt(d))
                w2, V = splinalg.eigsh(s @ K @ s, k=1, which="LA", tol=1e-6, maxiter=50 * model.n)
                V = s @ V
            else:
                w2, V = splinalg.eigsh(K, k=1, M=M, which="LA", tol=1e-6, maxiter=50 * model.n)
        except splinalg.ArpackNoConvergence as exc:  # the best Ritz pair found (the limit from below)
            if len(exc.eigenvalues) == 0:
                return np.empty(0), np.empty(0)
            w2, V = exc.eigenvalues, exc.eigenvectors
        V = V / np.sqrt(np.einsum("ij,ij->j", V, M @ V))
    keep = w2 > 0.0
    w = np.sqrt(w2[keep])
    V = V[:, keep]
    zeta = np.einsum("ij,ij->j", V, C @ V) / (2.0 * w)
    return w, np.clip(zeta, 0.0, None)


def _model_modes(model: Model):
    """_modes(model), kept on the model (its K, C and mass never change)."""
    cached = getattr(model, "_linear_modes", None)
    if cached is None:
        cached = _modes(model)
        try:
            model._linear_modes = cached
        except AttributeError:
            pass
    return cached


def _cd_limits(w: np.ndarray, zeta: np.ndarray) -> np.ndarray:
    """Central difference's step limit of each mode, 2(√(1+4ζ²) - 2ζ)/ω, written without cancellation."""
    return 2.0 / (w * (np.hypot(1.0, 2.0 * zeta) + 2.0 * zeta))  # hypot: no overflow for a huge zeta


def _unstable(scheme, om: float, xi: float) -> bool:
    """ρ > 1 + RHO_TOL for Ω = om and damping ratio xi (beyond OMEGA_RANGE: above it unstable, below stable)."""
    if om > OMEGA_RANGE[1]:
        return True
    if om < OMEGA_RANGE[0]:
        return False
    return float(np.max(np.abs(_eigenvalues(scheme, om, _oscillator(min(xi, XI_MAX)))))) > 1.0 + RHO_TOL


def _explicit(scheme) -> bool:
    return bool(scheme.is_explicit) and scheme.key != "pim"


def _limit_at(scheme, om_unstable: float, xi: float) -> float:
    """Ω_crit for xi, knowing Ω = om_unstable is unstable (so the scan ends there)."""
    hi = min(max(om_unstable, OMEGA_START * 1.01), OMEGA_RANGE[1])
    lo = OMEGA_START if hi > OMEGA_START * 1.001 else OMEGA_RANGE[0]
    return critical_omega_h(scheme, min(xi, XI_MAX), omega_max=hi, omega_min=lo)


def step_limit(model: Model, scheme) -> StepLimit | None:
    """The largest stable step of an explicit ``scheme`` on ``model``'s linear part, or None where there is
    none to find (an implicit scheme, PreciseIntegration, which integrates the linear part exactly, or a
    model without a linear stiffness).

    Every mode's limit is estimated by central difference's Ω_crit = 2(√(1+4ζ²) - 2ζ) for its damping
    ratio ζ; the mode with the smallest is then measured with ``scheme``'s own amplification matrix
    (``critical_omega_h``). Damping shrinks the limit of an explicit scheme, since the damping force is
    explicit too: Rayleigh damping C = αM + βK gives the top modes ζ ≈ βω/2, and a ζ of 100 divides
    central difference's step limit by about 400. Nonlinear effects are left out (their tangent changes along the run)."""
    check_scheme("scheme", scheme)
    if not isinstance(model, Model):
        raise _checks.type_error("model", f"expected nvib.Model, got {type(model).__name__}")
    if not _explicit(scheme):
        return None
    w, zeta = _model_modes(model)
    if w.size == 0:
        return None
    k = int(np.argmin(_cd_limits(w, zeta)))
    om, z, top = float(w[k]), float(zeta[k]), float(w.max())
    damped = _limit_at(scheme, OMEGA_RANGE[1], z) if z > 0.0 else critical_omega_h(scheme, 0.0)
    return StepLimit(dt=damped / om, dt_undamped=critical_omega_h(scheme, 0.0) / top, omega=om, zeta=z)


def step_warning(model: Model, scheme, dt: float) -> str | None:
    """What ``solve(model, scheme, dt=dt)`` has to be told before it runs: a dt above the explicit
    scheme's stability limit on the model's linear part, naming the mode, its damping ratio and the
    limit; else None. Cheap when dt is stable: the modes (kept on the model) and one amplification
    matrix at each of the two modes that may set the limit (the highest, and the one with the smallest
    central-difference limit for its damping)."""
    dt = _checks.number("dt", dt)
    _core.check_time_step(dt)
    if not _explicit(scheme):
        return None
    w, zeta = _model_modes(model)
    if w.size == 0:
        return None
    for k in dict.fromkeys((int(np.argmin(_cd_limits(w, zeta))), int(np.argmax(w)))):
        om, z = float(w[k]), float(zeta[k])
        if _unstable(scheme, om * dt, z):
            break
    else:
        return None
    top = float(w.max())
    limit = _limit_at(scheme, om * dt, z) / om
    undamped = critical_omega_h(scheme, 0.0) / top
    text = (f"dt = {dt:.4g} s is above the stability limit of {scheme_label(scheme)} on this model, "
            f"dt <= {limit:.4g} s, set by its mode of omega = {om:.4g} rad/s")
    if z > 0.0 and limit < (1.0 - 1e-6) * undamped:
        text += (f" with the damping ratio zeta = {z:.4g} (from C): damping shrinks an explicit scheme's limit, "
                 f"its damping force being explicit too ({undamped / limit:.3g}x below the undamped limit "
                 f"{undamped:.4g} s; central difference, whose damping force takes the predicted velocity "
                 f"v + dt a: omega dt <= 2 (sqrt(1 + 4 zeta^2) - 2 zeta), about 1/(2 zeta) for a large zeta); "
                 f"reduce dt, or the damping of the top modes (Rayleigh's beta gives them "
                 f"zeta = beta omega / 2), or use an implicit scheme")
    else:
        text += f" (zeta = {z:.3g}); reduce dt or use an implicit scheme"
    return text + ": the run will diverge"


# ---------------------------------------------------------------- labels and plot

def scheme_label(scheme) -> str:
    """A short name for tables and legends (the equilibrium iteration left out: it changes nothing here)."""
    check_scheme("scheme", scheme)
    return _labels.scheme_label(scheme, iteration=False)


def plot_spectral_radius(schemes, path: str, *, xi: float = 0.0, omega_h=None, labels=None,
                         critical=None, title: str | None = None) -> None:
    """Write ``stability_figure(...)`` (same arguments) to ``path`` (PNG, SVG or PDF by its extension)."""
    stability_figure(schemes, xi=xi, omega_h=omega_h, labels=labels, critical=critical,
                     title=title).savefig(path, dpi=120)


def stability_figure(schemes, *, xi: float = 0.0, omega_h=None, labels=None, critical=None,
                     title: str | None = None):
    """Spectral radius and period error against Ω (log axes), one line per scheme. ``omega_h``: the Ω to evaluate (default 300
    points from 1e-2 to 1e2); ``critical``: Ω_crit per scheme, marked on the curves
    (computed when None)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    schemes = list(schemes)
    for s in schemes:
        check_scheme("schemes", s)
    xi = _check_xi(xi)
    oms = np.geomspace(1e-2, 1e2, 300) if omega_h is None else _omegas(omega_h)[0]
    oms = np.sort(oms)
    labels = [scheme_label(s) for s in schemes] if labels is None else list(labels)
    if len(labels) != len(schemes):
        raise _checks.value_error("labels", f"expected {len(schemes)} labels, got {len(labels)}")
    if critical is None:
        critical = [critical_omega_h(s, xi, omega_max=max(OMEGA_LIMIT, float(oms[-1]))) for s in schemes]

    fig = Figure(figsize=(13.0, 5.0), layout="constrained")
    FigureCanvasAgg(fig)
    ax, ax_t = fig.subplots(1, 2)
    ymax = 1.3
    for k, (s, lab, oc) in enumerate(zip(schemes, labels, critical)):
        rho = spectral_radius(s, oms, xi)
        crit = "none" if math.isinf(oc) else f"{oc:.4g}"
        # schemes often share a curve (the central-difference family): dashes and widths keep each visible
        (line,) = ax.plot(oms, np.minimum(rho, 10 * ymax), ("-", "--", "-.", ":")[k % 4], lw=max(1.0, 2.6 - 0.3 * k),
                          label=f"{lab}: Ω_crit = {crit}")
        if math.isfinite(oc) and oms[0] <= oc <= oms[-1]:
            ax.plot([oc], [1.0], "o", color=line.get_color(), ms=5)
    if xi > 0:
        ax.plot(oms, np.exp(-xi * oms), "k:", lw=1.0, label="exact exp(-ξΩ)")
    ax.axhline(1.0, color="0.6", lw=0.8)
    ax.set_xscale("log")
    ax.set_xlim(oms[0], oms[-1])
    ax.set_ylim(0.0, ymax)
    ax.set_xlabel("Ω = ω Δt")
    ax.set_ylabel("spectral radius ρ")
    ax.set_title("Spectral radius of the amplification matrix", fontsize=11)
    ax.grid(True, which="both", alpha=0.25)
    ax.legend(fontsize=8, loc="lower left")

    # Schemes that share rho = 1 (no numerical dissipation) differ in their period error: the second panel.
    floor = 1e-12
    for k, (s, lab) in enumerate(zip(schemes, labels)):
        err = np.asarray(period_error(s, oms, xi), dtype=float)
        finite = err[np.isfinite(err)]
        how = ("" if not finite.size else " (exact)" if np.max(np.abs(finite)) < 1e3 * floor
               else " (lengthens)" if finite[0] > 0 else " (shortens)")
        ax_t.plot(oms, np.maximum(np.abs(err), floor), ("-", "--", "-.", ":")[k % 4], lw=max(1.0, 2.6 - 0.3 * k),
                  label=f"{lab}{how}")
    ax_t.set_xscale("log")
    ax_t.set_yscale("log")
    ax_t.set_xlim(oms[0], oms[-1])
    ax_t.set_ylim(floor / 2, 10.0)
    ax_t.set_xlabel("Ω = ω Δt")
    ax_t.set_ylabel("period error |T̄/T - 1| [-]")
    ax_t.set_title(f"Period error of the principal root (below {floor:g}: exact to round-off)", fontsize=11)
    ax_t.grid(True, which="both", alpha=0.25)
    ax_t.legend(fontsize=8, loc="lower right")
    fig.suptitle(title or f"Linear SDOF u'' + 2ξωu' + ω²u = 0, ξ = {xi:g}", fontsize=12)
    return fig
