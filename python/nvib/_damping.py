"""Rayleigh damping: C = alpha M + beta K0, K0 the tangent stiffness at the initial state.

The damping ratio of a mode of circular frequency w is then zeta(w) = alpha / (2 w) + beta w / 2, so
two ratios at two frequencies fix alpha and beta (Chopra, Dynamics of Structures, section 11.4). The
frequencies are given (``omegas``) or taken from the model linearised at its initial state
(``modes``, counted from 1). The damping assembles into the model's sparse C like a damper and stays
constant during the run.
"""

from __future__ import annotations

import numpy as np

from . import _checks
from ._model import Model

__all__ = ["rayleigh", "rayleigh_coefficients"]


def rayleigh_coefficients(zeta, omegas) -> tuple[float, float]:
    """(alpha, beta) giving the damping ratios ``zeta`` (one for both, or a pair) at the circular
    frequencies ``omegas`` = (w1, w2) [rad/s], w1 != w2."""
    w = _checks.real_array("omegas", omegas)
    if w.shape != (2,) or not np.all(np.isfinite(w)) or not np.all(w > 0) or w[0] == w[1]:
        raise _checks.value_error("omegas", f"expected two different positive finite circular frequencies, "
                                            f"got {w.tolist()}")
    z = _checks.real_array("zeta", zeta)
    if z.shape not in ((), (1,), (2,)):
        raise _checks.value_error("zeta", f"expected a damping ratio or two (one per frequency), got shape {z.shape}")
    z = np.broadcast_to(z, (2,)).astype(float)
    if not np.all((z >= 0) & (z < 1)):
        raise _checks.value_error("zeta", f"expected damping ratios 0 <= zeta < 1, got {z.tolist()}")
    A = np.array([[1.0 / (2.0 * w[0]), w[0] / 2.0], [1.0 / (2.0 * w[1]), w[1] / 2.0]])
    alpha, beta = (float(x) for x in np.linalg.solve(A, z))
    if alpha < 0.0 or beta < 0.0:
        # zeta(w) = alpha / (2 w) + beta w / 2 changes sign at w = sqrt(-alpha / beta)
        cross = float(np.sqrt(-alpha / beta)) if alpha * beta < 0.0 else 0.0
        which, side = ("beta", "above") if beta < 0.0 else ("alpha", "below")
        raise _checks.value_error("zeta", f"the ratios {z.tolist()} at the frequencies {w.tolist()} rad/s give "
                                          f"{which} = {alpha if which == 'alpha' else beta:.6g} < 0 (alpha = {alpha:.6g}, "
                                          f"beta = {beta:.6g}): every mode {side} {cross:.4g} rad/s would be damped "
                                          "negatively (its energy would grow); give ratios that change less "
                                          f"from {w[0]:.4g} to {w[1]:.4g} rad/s, or alpha and beta >= 0")
    return alpha, beta


def _mode_frequencies(model: Model, K0, modes) -> np.ndarray:
    """Circular frequencies of the given modes (from 1) of the model linearised at its initial state."""
    from scipy import linalg, sparse
    from scipy.sparse import linalg as sla

    top = max(modes)
    if top > model.n:
        raise _checks.value_error("modes", f"mode {top} asked of a model with {model.n} degrees of freedom")
    if model.n <= 2000:
        K = K0.toarray() if sparse.issparse(K0) else np.asarray(K0)
        w2 = linalg.eigh(0.5 * (K + K.T), model.mass_matrix, eigvals_only=True)
    else:  # the lowest modes by shift-invert around zero
        w2 = np.sort(sla.eigsh(sparse.csc_matrix(K0), k=top, M=model.mass_sparse, sigma=0.0, which="LM",
                               return_eigenvectors=False))
    if np.any(w2[:top] <= 0):
        raise _checks.value_error("modes", "the linearised model has a zero or negative stiffness mode (a rigid-body "
                                           "motion): give omegas instead")
    return np.sqrt(w2[np.asarray(modes) - 1])


def rayleigh(model: Model, *, zeta=None, omegas=None, modes=None, alpha: float | None = None,
             beta: float | None = None, u=None) -> Model:
    """The model with Rayleigh damping C = alpha M + beta K0 added (K0: the tangent stiffness at ``u``,
    default the model's u0). Give ``zeta`` (a ratio, or one per frequency) with ``omegas`` (two circular
    frequencies [rad/s]) or ``modes`` (two mode numbers, from 1, of the linearised model), or ``alpha``
    and/or ``beta`` directly. The returned model records what was added in ``model.rayleigh``."""
    if not isinstance(model, Model):
        raise _checks.type_error("model", f"expected a Model, got {type(model).__name__}")
    before = getattr(model, "rayleigh", None)
    if before is not None:
        raise _checks.value_error("model", f"already has Rayleigh damping (alpha = {before['alpha']:.6g}, beta = "
                                           f"{before['beta']:.6g}) in its C; a second would add to it while "
                                           "model.rayleigh told of the second alone: apply rayleigh once, to the model "
                                           "built without it (a scene's damping is its [damping] table)")
    direct = alpha is not None or beta is not None
    if direct and (zeta is not None or omegas is not None or modes is not None):
        raise _checks.value_error("alpha, beta", "give alpha/beta, or zeta with omegas or modes, not both")
    u = model.u0 if u is None else _checks.vector("u", u, model.n)
    K0, _ = model.tangent_matrices(u, np.zeros(model.n), 0.0, sparse=model.n > 2000)
    if direct:
        alpha = 0.0 if alpha is None else _checks.real("alpha", alpha)
        beta = 0.0 if beta is None else _checks.real("beta", beta)
        for name, value in (("alpha", alpha), ("beta", beta)):
            if value < 0.0:
                raise _checks.value_error(name, f"must be >= 0, got {value:g} (a negative coefficient damps "
                                                "modes negatively: their energy would grow)")
        w = None
    else:
        if zeta is None:
            raise _checks.value_error("zeta", "give the damping ratio (with omegas or modes), or alpha/beta")
        if (omegas is None) == (modes is None):
            raise _checks.value_error("omegas, modes", "give either two circular frequencies or two mode numbers")
        if modes is not None:
            modes = [_checks.integer(f"modes[{k}]", m, minimum=1) for k, m in enumerate(modes)]
            if len(modes) != 2 or modes[0] == modes[1]:
                raise _checks.value_error("modes", f"expected two different mode numbers, got {modes}")
            w = _mode_frequencies(model, K0, modes)
        else:
            w = _checks.real_array("omegas", omegas)
        alpha, beta = rayleigh_coefficients(zeta, w)
    from scipy import sparse

    C_add = alpha * model.mass_sparse + beta * sparse.csc_matrix(K0)
    C = model._init[1].get("C")
    if C is not None:
        C_add = C_add + (sparse.csc_matrix(C) if sparse.issparse(C) else sparse.csc_matrix(np.asarray(C, dtype=float)))
    out = model._rebuilt(C=C_add)
    out.rayleigh = {"alpha": alpha, "beta": beta, "omegas": None if w is None else [float(x) for x in w],
                    "zeta": zeta, "modes": modes}
    return out
