"""Exceptions raised by nvib runs (bad input raises ValueError/TypeError naming the argument)."""

from __future__ import annotations


class NvibError(RuntimeError):
    """A run stopped before t_end. ``result`` holds the partial trajectory."""

    def __init__(self, message: str, failure: dict | None = None, result=None):
        super().__init__(message)
        failure = failure or {}
        self.result = result
        self.t = failure.get("t")
        self.step = failure.get("step")
        self.dof = failure.get("dof")
        self.residuals = list(failure.get("residuals", []))


class DivergenceError(NvibError):
    """The state became non-finite or left the displacement bound (time, step and DOF given)."""


class ConvergenceError(NvibError):
    """Newton's iteration did not converge within max_iter (time, step and residual history given)."""


class SingularMatrixError(NvibError):
    """The iteration matrix of an implicit scheme was singular."""


_BY_STATUS = {
    "diverged": DivergenceError,
    "newton_failed": ConvergenceError,
    "singular_matrix": SingularMatrixError,
}


def error_for(status: str, failure: dict, result) -> NvibError:
    cls = _BY_STATUS.get(status, NvibError)
    return cls(failure.get("message") or status, failure, result)
