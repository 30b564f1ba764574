"""nvib: time integration of nonlinear vibration systems M a + F(u, v, t) = P(t).

Schemes: CentralDifference (leapfrog, LCDM), CEMDTS, Zhai, Newmark,
GeneralizedAlpha, PreciseIntegration (PIM). Models: ``Model(mass, ...)`` with
built-in effects or a Python force callable. ``solve(model, scheme, dt=, t_end=)``
returns a Result; ``Stepper`` integrates step by step. ``reference(model, t_end)``
gives a closed form or a DOP853 solution to measure against; ``cost(model,
schemes, dts)`` and ``cost_scipy(model)`` measure accuracy against wall time.
``nvib.stability``: amplification matrices, spectral radius, period error and
stability limit of each scheme.
"""

from __future__ import annotations

import os

from . import exact, stability
from ._core import expm as _expm
from ._schemes import CEMDTS, CentralDifference, GeneralizedAlpha, Newmark, PreciseIntegration, Zhai
from ._errors import ConvergenceError, DivergenceError, NvibError, SingularMatrixError
from ._model import EFFECT_PARAMETERS, Model
from ._scenes import SceneError, load_scene, scene_names
from ._solve import Energy, Result, Stepper, default_max_displacement, solve
# nvib.reference and nvib.cost are the functions; `from nvib.cost import ...` still reaches the modules
from .reference import Reference, reference
from .cost import cheapest, cost, cost_scipy, markdown_table, plot_work_precision, scheme_label, time_at_error

__version__ = "0.1.0"

__all__ = [
    "CEMDTS", "CentralDifference", "ConvergenceError", "DivergenceError", "EFFECT_PARAMETERS", "Energy",
    "GeneralizedAlpha", "Model", "Newmark", "NvibError", "PreciseIntegration", "Reference", "Result",
    "SceneError", "SingularMatrixError", "Stepper", "Zhai", "cheapest", "cmake_dir", "cost", "cost_scipy",
    "default_max_displacement", "exact", "expm", "include_dir", "load_scene", "markdown_table",
    "plot_work_precision", "reference", "scene_names", "scheme_label", "solve", "stability", "time_at_error",
]


def expm(A, squarings: int = 20):
    """e^A by the 2^N algorithm of the precise integration method (Zhong & Williams 1994)."""
    import numpy as np

    from . import _checks

    A = _checks.real_array("A", A)
    if A.ndim != 2 or A.shape[0] != A.shape[1]:
        raise ValueError(f"A: expected a square matrix, got shape {A.shape}")
    squarings = _checks.integer("squarings", squarings)
    if not 0 <= squarings <= 60:
        raise ValueError(f"squarings: needs 0 <= squarings <= 60, got {squarings}")
    E = _expm(A, squarings)
    if not np.all(np.isfinite(E)):
        raise ValueError(f"A: e^A overflows (max |A_ij| = {np.max(np.abs(A)):g})")
    return E


def include_dir() -> str:
    """Folder of the installed C++ headers (nvib/nvib.hpp)."""
    return os.path.join(os.path.dirname(__file__), "include")


def cmake_dir() -> str:
    """Folder holding nvibConfig.cmake: pass it as nvib_DIR or in CMAKE_PREFIX_PATH."""
    return os.path.join(os.path.dirname(__file__), "share", "cmake", "nvib")
