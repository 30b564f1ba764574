"""The true error of a run as the error estimate means it: max_t |u_i - u_i,ref| / max_t |u_i,ref| per DOF (a
DOF's peak floored at 1e-3 of the largest, as the references measure it), the worst DOF, at the run's saved
times up to the reference's end."""

from __future__ import annotations

import numpy as np


def true_error(res, ref) -> float:
    keep = res.t <= ref.t_end * (1 + 1e-12)
    u_ref = ref.u(res.t[keep])
    peak = np.max(np.abs(u_ref), axis=0)
    peak = np.maximum(peak, 1e-3 * peak.max())
    return float(np.max(np.max(np.abs(res.u[keep] - u_ref), axis=0) / peak))
