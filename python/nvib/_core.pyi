# Type stub of the compiled module nvib._core (python/src/). The scheme
# classes are generated from the C++ registry (cpp/include/nvib/schemes/all.hpp):
# they share the interface of _Scheme and are reached through SCHEMES or
# module attributes; the other types are declared here.
import os
from enum import Enum
from typing import Any, Callable, ClassVar, Sequence

import numpy as np
import numpy.typing as npt

Array = npt.NDArray[np.float64]
DEFAULT_MAX_ENERGY_ERROR: float

class ArgumentError(ValueError):
    argument: str | None
    reason: str | None

class ArgumentTypeError(TypeError):
    argument: str | None
    reason: str | None

class Status(Enum):
    success = 0
    diverged = 1
    newton_failed = 2
    singular_matrix = 3
    interrupted = 4
    collapsed = 5

class Stats:
    num_steps: int
    num_force_evals: int
    num_fd_force_evals: int
    num_tangent_evals: int
    num_newton_iters: int
    num_factorizations: int
    num_reused_factorizations: int
    num_linear_solves: int
    num_expm: int
    num_rejected_steps: int
    num_events: int
    num_check_steps: int
    num_restarts: int
    wall_time: float
    linear_solver: str
    def as_dict(self) -> dict[str, float]: ...

class StopToken:
    """A request to stop shared by runs on several threads (``with token:`` makes it the thread's own)."""
    def __init__(self) -> None: ...
    def set(self) -> None: ...
    @property
    def is_set(self) -> bool: ...
    def __enter__(self) -> StopToken: ...
    def __exit__(self, *exc: object) -> bool: ...

class Failure:
    status: Status
    step: int
    t: float
    dof: int
    residuals: list[float]
    message: str

class Newton:
    iteration: str
    max_iter: int
    rtol: float
    atol: float
    jacobian: str
    accepts_unconverged: bool
    def __init__(self, *, iteration: str = ..., max_iter: int = ..., rtol: float = ..., atol: float = ...,
                 jacobian: str = ...) -> None: ...
    @staticmethod
    def parameters() -> list[dict[str, Any]]: ...

class _Scheme:
    """What every scheme class of the registry has (see SCHEMES)."""
    key: ClassVar[str]
    is_explicit: ClassVar[bool]
    name: str
    label: str
    short_label: str
    order_u: int
    order_v: int
    adaptive: bool
    def __init__(self, *args: Any, **kwargs: Any) -> None: ...
    @staticmethod
    def parameters() -> list[dict[str, Any]]: ...
    @staticmethod
    def factories() -> list[dict[str, str]]: ...

SCHEMES: tuple[tuple[str, type[_Scheme]], ...]

def __getattr__(name: str) -> type[_Scheme]: ...  # the scheme classes, by their names

class Energy:
    kinetic: Array
    potential: Array
    work_in: Array
    dissipated: Array
    balance_error: Array
    total: Array
    def relative_balance_error(self) -> float: ...
    def as_dict(self) -> dict[str, Array]: ...

class Result:
    t: Array
    u: Array
    v: Array
    a: Array
    energy: Energy | None
    effects: dict[str, dict[str, Any]]
    dofs: list[str]
    dof_indices: list[int]
    stats: Stats
    status: Status
    success: bool
    failure: Failure | None
    num_steps_requested: int
    max_residual: float | None
    _peaks: tuple[Array, Array] | None
    _error_estimate: Array | None
    scheme: _Scheme
    dt: float
    # the Python members (nvib/_result.py)
    relative_to_ground: bool
    units: list[str]
    warnings: list[str]
    absolute_a: Array
    error_estimate: Any
    def to_pandas(self) -> Any: ...
    def to_xarray(self) -> Any: ...
    def save(self, path: str | os.PathLike[str], extra: dict[str, Any] | None = ...) -> None: ...

class Effect:
    type: str
    name: str
    index: list[int]
    coef: list[float]
    parameters: dict[str, float]
    uses_velocity: bool
    uses_time: bool
    is_linear: bool
    is_load: bool
    def __init__(self, type: str, index: Sequence[int], coef: Sequence[float], parameters: dict[str, float] = ...,
                 *, name: str = ..., signal: str = ..., amplitude: float = ..., omega: float = ...,
                 phase: float = ..., t: Sequence[float] = ..., values: Sequence[float] = ...) -> None: ...
    def value(self, d: float, dd: float, t: float) -> float: ...

def laws() -> dict[str, dict[str, Any]]: ...

class Model:
    dofs: list[str]
    has_python: bool
    size: int
    uses_velocity: bool
    uses_time: bool
    is_linear: bool
    accounts_energy: bool
    num_evaluated_effects: int
    effects: list[Effect]
    warnings: list[str]
    mass_matrix: Array
    K: Array
    C: Array
    linear_product: str
    linear_product_block: int
    def __init__(self, mass: Array, effects: Sequence[Effect], K: Array, C: Array, dofs: Sequence[str],
                 force: Callable[..., Any] | None = ..., tangent: Callable[..., Any] | None = ...,
                 uses_velocity: bool = ..., uses_time: bool = ..., laws: Sequence[tuple] = ...,
                 arrays: Sequence[Any] = ..., vector_laws: Sequence[tuple] = ...,
                 mass_of: Model | None = ...) -> None: ...
    def same_linear_parts(self, other: Model) -> bool: ...
    def potential(self, u: Array, t: float = ...) -> float: ...
    def kinetic(self, v: Array) -> float: ...
    def force(self, u: Array, v: Array, t: float) -> Array: ...
    def tangent(self, u: Array, v: Array, t: float) -> tuple[Array, Array]: ...
    def static_equilibrium(self, t: float, u_guess: Array, rtol: float, max_iter: int) -> Array: ...

class Stepper:
    t: float
    step_index: int
    dt: float
    u: Array
    v: Array
    a: Array
    stats: Stats
    failure: Failure
    last_residuals: list[float]
    accepted_residual: float | None
    def __init__(self, model: Model, scheme: _Scheme, dt: float) -> None: ...
    def initialize(self, t0: float, u0: Array, v0: Array) -> None: ...
    def step(self) -> tuple[Status, Failure | None]: ...
    def state(self) -> Array: ...
    def set_state(self, t: float, x: Array) -> None: ...
    def integrate(self, t_end: float, options: dict[str, Any],
                  progress: Callable[[int, int], None] | None) -> Result: ...

RUN_DEFAULTS: dict[str, Any]

def solve(model: Model, scheme: _Scheme, dt: float, t_end: float, t0: float, u0: Array, v0: Array,
          options: dict[str, Any], progress: Callable[[int, int], None] | None) -> Result: ...
def expm(A: Array, squarings: int = ...) -> Array: ...
def steps_to_reach(t0: float, t_end: float, dt: float) -> int: ...
def run_steps(t0: float, t_end: float, dt: float) -> int: ...
def check_time_step(dt: float) -> None: ...
def ordering_cache(clear: bool = ...) -> tuple[int, int]: ...
def default_max_displacement(u: Array, v: Array, duration: float) -> float: ...

def elastic_spectrum(ag: Array, dt: float, periods: Array, damping: float | Array = ..., *, per_period: bool = ...,
                     free_vibration: bool = ..., t0: float = ...) -> dict[str, Array]: ...
def elastic_spectrum_at(times: Array, ag: Array, periods: Array, damping: float | Array = ..., *,
                        per_period: bool = ..., free_vibration: bool = ...) -> dict[str, Array]: ...
def rotated_sd(a1: Array, a2: Array, dt: float, periods: Array, damping: float | Array, angles: Array) -> Array: ...
