"""nvib: time integration of nonlinear vibration systems M a + F(u, v, t) = P(t).

Schemes: every scheme of the C++ registry (cpp/include/nvib/schemes/all.hpp),
``schemes()`` maps their command-line keys to the classes: CentralDifference
(leapfrog, LCDM), CEMDTS, Zhai, Newmark, GeneralizedAlpha, PreciseIntegration
(PIM); the implicit ones take ``newton=Newton(iteration=..., rtol=..., ...)``.
Models: ``Model(mass, ...)`` with built-in effects or Python callables.
``solve(model, scheme, dt=, t_end=)`` returns a Result; ``Stepper``
integrates step by step. Tools: ``reference(model, t_end)`` (a closed form or
a DOP853 solution to measure against), ``cost(model, schemes, dts)`` and
``cost_scipy(model)`` (accuracy against wall time), ``nvib.stability``
(amplification matrices, spectral radius, period error and stability limits),
``spectrum`` and ``ida`` (response spectra, incremental dynamic analysis),
``inelastic_spectrum`` (constant-ductility and constant-strength spectra) and
``nvib.fragility`` (lognormal fragility functions by maximum likelihood).
nvib is unit-agnostic; the built-in scenes use SI units (m, kg, s, N, rad).
"""

# No ``from __future__ import annotations`` here: it would bind ``annotations`` in the package's
# namespace (dir(nvib)); an annotation naming what only the type stubs hold is a string instead.
# Modules the package itself uses are imported under private names, for the same reason.
import os as _os

from . import _core, _schemes
from ._core import DEFAULT_MAX_ENERGY_ERROR
from ._estimate import Estimate, estimate
from ._errors import (ArgumentError, ArgumentTypeError, ConvergenceError, DivergenceError, NvibError,
                      SingularMatrixError)
from ._labels import scheme_label
from ._model import EFFECT_PARAMETERS, LawResponse, Model, drive
from ._check_law import LawCheck, check_law
from ._compiled import LAW_SIGNATURE
from ._records import STANDARD_GRAVITY, GroundMotion, RecordError
from ._batch import Batch, RunError, RunSummary, solve_many
from ._damping import rayleigh, rayleigh_coefficients
from ._tables import load_result
from . import _result  # noqa: F401  (Result's Python members)
from ._scenes import SceneError, load_scene, scene_names
from ._schemes import Newton, schemes
from ._solve import ENERGY_WARNING, ERROR_WARNING, Energy, Failure, Result, Stats, Status, Stepper, default_max_displacement, solve
from .analysis import exact, stability
from .analysis.spectrum import Spectrum, spectrum
from .analysis.inelastic import InelasticSpectrum, inelastic_spectrum
from .analysis.ida import IDA, ida
from .analysis import fragility
from .analysis.fragility import Fragility
from . import scenes
from .analysis.cost import cheapest, cost, cost_scipy, markdown_table, plot_work_precision, time_at_error
from .analysis.reference import Reference, reference

globals().update({cls.__name__: cls for cls in _schemes.scheme_classes()})

__version__ = "0.1.0"

__all__ = sorted([
    "ArgumentError", "ArgumentTypeError", "ConvergenceError", "DEFAULT_MAX_ENERGY_ERROR", "DivergenceError", "ENERGY_WARNING", "ERROR_WARNING",
    "Estimate", "estimate", "GroundMotion", "RecordError", "STANDARD_GRAVITY",
    "Batch", "RunError", "RunSummary", "solve_many", "Spectrum", "spectrum", "InelasticSpectrum", "inelastic_spectrum", "IDA", "ida", "Fragility", "fragility", "rayleigh", "rayleigh_coefficients", "load_result",
    "EFFECT_PARAMETERS", "Energy", "LawResponse", "LawCheck", "LAW_SIGNATURE", "check_law", "drive", "Failure", "Model", "Newton", "NvibError", "Reference", "Result", "SceneError",
    "SingularMatrixError", "Stats", "Status", "Stepper", "cheapest", "cmake_dir", "cost", "cost_scipy",
    "default_max_displacement", "exact", "expm", "include_dir", "load_scene", "markdown_table",
    "plot_work_precision", "reference", "scene_names", "scenes", "scheme_label", "schemes", "solve",
    "stability",
    "time_at_error",
] + [cls.__name__ for cls in _schemes.scheme_classes()])


def expm(A, squarings: int = 20):
    """e^A by the 2^N algorithm of the precise integration method (Zhong & Williams 1994)."""
    import numpy as np

    from . import _checks, _core

    A = _checks.real_array("A", A)
    if A.ndim != 2 or A.shape[0] != A.shape[1]:
        raise _checks.value_error("A", f"expected a square matrix, got shape {A.shape}")
    squarings = _checks.integer("squarings", squarings, maximum=None)
    if not 0 <= squarings <= 60:
        raise _checks.value_error("squarings", f"needs 0 <= squarings <= 60, got {squarings}")
    E = _core.expm(A, squarings)
    if not np.all(np.isfinite(E)):
        raise _checks.value_error("A", f"e^A overflows (max |A_ij| = {np.max(np.abs(A)):g})")
    return E


def include_dir() -> str:
    """Folder of the installed C++ headers (nvib/nvib.hpp)."""
    return _os.path.join(_os.path.dirname(__file__), "include")


def cmake_dir() -> str:
    """Folder holding nvibConfig.cmake: pass it as nvib_DIR or in CMAKE_PREFIX_PATH."""
    return _os.path.join(_os.path.dirname(__file__), "share", "cmake", "nvib")


def __getattr__(name: str) -> "type[_core._Scheme]":
    # Only for names not found otherwise; tells type checkers that the scheme
    # classes, set from the registry above, are attributes of nvib.
    raise AttributeError(f"module 'nvib' has no attribute {name!r}")
