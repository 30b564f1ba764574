"""Exceptions: a run that stopped early raises an NvibError (carrying the
failure and the partial result); bad input raises ArgumentError (a
ValueError) or ArgumentTypeError (a TypeError), whose ``.argument`` names it."""

from __future__ import annotations

from ._core import ArgumentError, ArgumentTypeError, Status

__all__ = ["ArgumentError", "ArgumentTypeError", "ConvergenceError", "DivergenceError", "NvibError",
           "SingularMatrixError", "error_for"]

ArgumentError.__module__ = ArgumentTypeError.__module__ = "nvib"


class NvibError(RuntimeError):
    """A run stopped before t_end. ``failure`` says where and why; ``result`` holds the partial trajectory
    (None when stepping by hand); ``t``, ``step``, ``dof`` and ``residuals`` are the failure's."""

    def __init__(self, message: str, failure=None, result=None):
        super().__init__(message)
        self.failure = failure
        self.result = result
        self.t = failure.t if failure is not None else None
        self.step = failure.step if failure is not None else None
        self.dof = failure.dof if failure is not None else None
        self.residuals = list(failure.residuals) if failure is not None else []


class DivergenceError(NvibError):
    """The state became non-finite, left the displacement bound or created energy (time, step and DOF given)."""


class ConvergenceError(NvibError):
    """Newton's iteration did not converge, or stalled above its tolerance (time, step and residual history)."""


class SingularMatrixError(NvibError):
    """The iteration matrix of an implicit scheme was singular."""


_BY_STATUS = {
    Status.diverged: DivergenceError,
    Status.newton_failed: ConvergenceError,
    Status.singular_matrix: SingularMatrixError,
}


def error_for(failure, result=None) -> NvibError:
    """The exception for a failure (a ``Failure``), carrying the partial result."""
    return _BY_STATUS.get(failure.status, NvibError)(failure.message or failure.status.name, failure, result)
