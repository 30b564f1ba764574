"""solve(), the step-by-step Stepper and the Result they return."""

from __future__ import annotations

import math

import numpy as np

from . import _checks, _core
from ._errors import error_for
from ._model import Model

SCHEMES = (_core.CentralDifference, _core.Zhai, _core.CEMDTS, _core.Newmark, _core.GeneralizedAlpha,
           _core.PreciseIntegration)


class Energy:
    """Energy accounting at the saved states: kinetic, potential (conservative
    effects and K), work_in (work done by loads and moving supports since t0),
    dissipated (by dampers since t0) and balance_error =
    kinetic + potential + dissipated - work_in - (kinetic + potential at t0)."""

    def __init__(self, table: np.ndarray):
        self.kinetic = table[:, 0]
        self.potential = table[:, 1]
        self.work_in = table[:, 2]
        self.dissipated = table[:, 3]
        self.balance_error = table[:, 4]

    @property
    def total(self) -> np.ndarray:
        return self.kinetic + self.potential

    def relative_balance_error(self) -> float:
        """max |balance error| over the largest energy magnitude seen in the run."""
        parts = np.abs(self.kinetic) + np.abs(self.potential) + np.abs(self.work_in) + np.abs(self.dissipated)
        if not (np.all(np.isfinite(parts)) and np.all(np.isfinite(self.balance_error))):
            return float("inf")  # a run that blew up
        scale = np.max(parts)
        return float(np.max(np.abs(self.balance_error)) / scale) if scale > 0 else 0.0

    def as_dict(self) -> dict:
        return {"kinetic": self.kinetic, "potential": self.potential, "work_in": self.work_in,
                "dissipated": self.dissipated, "balance_error": self.balance_error}


class Result:
    """A run: times ``t`` (n_saved,), histories ``u``, ``v``, ``a`` (n_saved, n_saved_dofs),
    the saved DOF names ``dofs``, counters ``stats`` and ``status``
    ('success', 'diverged', 'newton_failed' or 'singular_matrix').

    ``max_residual``: for the implicit schemes, the largest equilibrium
    residual of an accepted step relative to its force scale (below about
    ``rtol`` with Newton; with ``iteration="none"``, which accepts every step
    without an equilibrium check, the unbalance the run left); None for the
    explicit schemes and for linear models (one solve is exact)."""

    def __init__(self, raw: dict, model: Model, scheme, dt: float):
        self.t = raw["t"]
        self.u = raw["u"]
        self.v = raw["v"]
        self.a = raw["a"]
        self.dof_indices = list(raw["dofs"])
        self.dofs = [model.dofs[i] for i in self.dof_indices]
        self.stats = raw["stats"]
        self.status = raw["status"]
        self.failure = raw["failure"] if self.status != "success" else None
        self.num_steps_requested = raw["num_steps_requested"]
        mr = raw.get("max_residual", math.nan)
        self.max_residual = None if math.isnan(mr) else mr
        self.energy = Energy(raw["energy"]) if "energy" in raw else None
        self.scheme = scheme
        self.dt = dt

    @property
    def success(self) -> bool:
        return self.status == "success"

    def __repr__(self) -> str:
        return (f"Result({self.scheme!r}, status={self.status!r}, saved={len(self.t)}, "
                f"steps={self.stats.num_steps}, wall_time={self.stats.wall_time:.3g}s)")


def _check_scheme(scheme):
    if not isinstance(scheme, SCHEMES):
        names = ", ".join(s.__name__ for s in SCHEMES)
        raise TypeError(f"scheme: expected one of {names}, got {type(scheme).__name__}")


def _check_model(model):
    if not isinstance(model, Model):
        raise TypeError(f"model: expected nvib.Model, got {type(model).__name__}")


def _dof_indices(model: Model, dofs) -> list[int]:
    if dofs is None:
        return []
    if isinstance(dofs, (str, int)):
        dofs = [dofs]
    return [model._dof_index("dofs", d) for d in dofs]


class Stepper:
    """Step-by-step integration: ``st = Stepper(model, scheme, dt); st.step(); st.u``."""

    def __init__(self, model: Model, scheme, dt: float, *, t0: float = 0.0, u0=None, v0=None):
        _check_model(model)
        _check_scheme(scheme)
        self.model = model
        self.scheme = scheme
        self.dt = _checks.real("dt", dt, positive=True)
        t0 = _checks.real("t0", t0)
        u0 = model.u0 if u0 is None else _checks.vector("u0", u0, model.n)
        v0 = model.v0 if v0 is None else _checks.vector("v0", v0, model.n)
        self._st = _core.make_stepper(model._core, scheme, self.dt)
        self._st.initialize(t0, u0, v0)

    t = property(lambda self: self._st.t, doc="current time")
    u = property(lambda self: self._st.u, doc="current displacement")
    v = property(lambda self: self._st.v, doc="current velocity")
    a = property(lambda self: self._st.a, doc="current acceleration")
    stats = property(lambda self: self._st.stats, doc="counters since construction")
    step_index = property(lambda self: self._st.step_index)
    last_residuals = property(lambda self: list(self._st.last_residuals),
                              doc="Newton residual norms of the last step (implicit schemes); with "
                                  "iteration='none' the predictor's and the one left after the step")

    @property
    def accepted_residual(self) -> float | None:
        """Equilibrium residual of the last accepted step relative to its force scale (implicit
        schemes; None where it is not evaluated)."""
        r = self._st.accepted_residual
        return None if math.isnan(r) else r

    def state(self) -> np.ndarray:
        """The carried state as one vector: [u; v; a] followed by the scheme's history
        (a_{n-1} for CEMDTS and Zhai; the order + 1 interpolated remainders, newest first,
        for PreciseIntegration; with CentralDifference(velocity="half_step") v is v_{n-1/2})."""
        return self._st.state()

    def set_state(self, x, t: float | None = None) -> None:
        """Continue from the carried state x (as ``state()`` returns it) at time t (default: now)."""
        t = self.t if t is None else _checks.real("t", t)
        try:
            x = np.asarray(x, dtype=float)
        except (TypeError, ValueError) as exc:
            raise TypeError(f"x: expected an array of real numbers ({exc})") from None
        if x.ndim != 1:
            raise ValueError(f"x: expected a 1-D state vector, got shape {x.shape}")
        self._st.set_state(t, x)

    def step(self, n: int = 1) -> None:
        """Advance n steps; raises DivergenceError / ConvergenceError on failure."""
        n = _checks.integer("n", n, minimum=1)
        for _ in range(n):
            status = self._st.step()
            if status == "success":
                for name in ("u", "v", "a"):
                    x = getattr(self._st, name)
                    if not np.all(np.isfinite(x)):
                        dof = int(np.argmax(~np.isfinite(x)))
                        failure = {"message": f"diverged at t = {self._st.t:g} (step {self._st.step_index}): "
                                              f"{name}[{dof}] = {x[dof]:g}, not finite",
                                   "t": self._st.t, "step": self._st.step_index, "dof": dof, "residuals": []}
                        raise error_for("diverged", failure, None)
            if status != "success":
                raise error_for(status, self._st.failure, None)

    def integrate(self, t_end: float, *, save_every: int = 1, dofs=None, throw: bool = True,
                  max_displacement: float | None = None, progress=None, energy: bool = False,
                  max_energy_error: float | None = None) -> Result:
        """Continue to t_end and return the saved history of this stretch (options as in ``solve``)."""
        t_end = _checks.real("t_end", t_end)
        if t_end <= self.t:
            raise ValueError(f"t_end: must be > the current time {self.t}, got {t_end}")
        save_every = _checks.integer("save_every", save_every, minimum=1)
        bound = _limit("max_displacement", max_displacement,
                       default=default_max_displacement(self.u, self.v, t_end - self.t))
        if progress is not None and not callable(progress):
            raise TypeError("progress: expected a callable progress(step, n_steps)")
        if not isinstance(energy, bool):
            raise TypeError(f"energy: expected True or False, got {type(energy).__name__}")
        energy_limit = _limit("max_energy_error", max_energy_error,
                              default=DEFAULT_MAX_ENERGY_ERROR if energy else math.inf)
        if max_energy_error is not None and energy_limit < math.inf and not energy:
            raise ValueError("max_energy_error: needs the energy accounting (energy=True)")
        raw = self._st.integrate(t_end, save_every, _dof_indices(self.model, dofs), bound, 4096, progress,
                                 energy, energy_limit)
        res = Result(raw, self.model, self.scheme, self.dt)
        if throw and res.status != "success":
            raise error_for(res.status, res.failure, res)
        return res


def _limit(name: str, value, *, default: float) -> float:
    """A run limit: None for the default, math.inf for none, else a positive real (named when not)."""
    if value is None:
        return default
    if isinstance(value, (int, float)) and value == math.inf:
        return math.inf
    return _checks.real(name, value, positive=True)


# With energy=True, a run whose energy balance error exceeds half the energy scale stops as diverged.
DEFAULT_MAX_ENERGY_ERROR = 0.5


def default_max_displacement(u, v, duration: float) -> float:
    """The default divergence bound on |u_i|: 1e10 x max(1, max|u|, max|v| x duration).

    Far beyond any physical response of the model started from (u, v), yet
    reached long before a diverging state overflows, so such a run stops with
    a message naming the DOF instead of running on with inf or NaN. The same
    bound is the default of the C++ solve()."""
    u = np.atleast_1d(_checks.real_array("u", u)).ravel()
    v = np.atleast_1d(_checks.real_array("v", v)).ravel()
    return _core.default_max_displacement(u, v, _checks.real("duration", duration))


def solve(model: Model, scheme, *, dt: float, t_end: float, t0: float = 0.0, u0=None, v0=None,
          save_every: int = 1, dofs=None, throw: bool = True, max_displacement: float | None = None,
          progress=None, energy: bool = False, max_energy_error: float | None = None) -> Result:
    """Integrate ``model`` with ``scheme`` from t0 to t_end in steps of dt.

    Saves steps 0, save_every, 2 save_every, ... and always the last one. A
    run whose state becomes non-finite or whose |u_i| exceeds
    ``max_displacement`` (default: ``default_max_displacement``, 1e10 times
    the scale of the initial state; ``math.inf`` for none) stops within one
    step with status 'diverged'. Newton that does not converge stops the run
    with status 'newton_failed' (the residual history in the failure);
    ``iteration="none"`` never iterates and reports what it leaves unbalanced
    in ``Result.max_residual``. If
    (t_end - t0)/dt is not an integer the run ends at the first multiple of dt
    past t_end. With ``throw=False`` a failed run returns its partial history
    with ``status`` set instead of raising. ``energy=True`` records the
    energy accounting (``Result.energy``) for models of declared effects,
    and then also checks it every step: a run whose energy balance error
    exceeds ``max_energy_error`` (default 0.5) times the energy scale (the
    largest |kinetic| + |potential| + |work in| + |dissipated| so far) stops
    as diverged. That catches an instability that stays finite, such as a
    vehicle launched off its rails, which no displacement bound sees; a sound
    run's balance error is orders of magnitude smaller. ``math.inf`` turns it off.
    """
    _check_model(model)
    _check_scheme(scheme)
    dt = _checks.real("dt", dt, positive=True)
    t0 = _checks.real("t0", t0)
    t_end = _checks.real("t_end", t_end)
    if t_end <= t0:
        raise ValueError(f"t_end: must be > t0 = {t0}, got {t_end}")
    _checks.integer("save_every", save_every, minimum=1)
    _core.steps_to_reach(t0, t_end, dt)
    st = Stepper(model, scheme, dt, t0=t0, u0=u0, v0=v0)
    init = st.stats
    res = st.integrate(t_end, save_every=save_every, dofs=dofs, throw=False, max_displacement=max_displacement,
                       progress=progress, energy=energy, max_energy_error=max_energy_error)
    res.stats = _add_stats(res.stats, init)
    if throw and res.status != "success":
        raise error_for(res.status, res.failure, res)
    return res


class _SummedStats:
    """Stats of a whole solve: the start-up (a0, PIM's exponential) plus the steps."""

    _FIELDS = ("num_steps", "num_force_evals", "num_fd_force_evals", "num_tangent_evals", "num_newton_iters",
               "num_factorizations", "num_linear_solves", "num_expm", "wall_time")

    def __init__(self, **kw):
        for k in self._FIELDS:
            setattr(self, k, kw[k])

    def as_dict(self) -> dict:
        return {k: getattr(self, k) for k in self._FIELDS}

    def __repr__(self) -> str:
        return "Stats(" + ", ".join(f"{k}={getattr(self, k)!r}" for k in self._FIELDS) + ")"


def _add_stats(run, init) -> _SummedStats:
    a, b = run.as_dict(), init.as_dict()
    return _SummedStats(**{k: a[k] + b[k] for k in _SummedStats._FIELDS})
