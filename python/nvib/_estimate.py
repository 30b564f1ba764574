"""What a run will cost before it is made: the memory of its saved history (against the limit
solve() enforces: half the memory available) and its time, from a short timed probe."""

from __future__ import annotations

import time
from dataclasses import dataclass

from . import _checks, _core
from ._errors import NvibError
from ._model import Model
from ._solve import RUN_OPTIONS


@dataclass(frozen=True)
class Estimate:
    """The cost of a run. Bytes are of the saved history (t, u, v, a and the energy columns); times in
    seconds: the set-up (stepper, initial acceleration, PIM's exponential, the first step with its
    factorisation set-up) and the steps after it, measured on a probe of about ``probe_seconds``."""

    steps: int
    saved_states: int
    history_bytes: float
    history_limit_bytes: float
    setup_seconds: float
    seconds_per_step: float
    seconds: float
    linear_solver: str

    @property
    def fits(self) -> bool:
        """The history fits under the limit solve() enforces."""
        return self.history_limit_bytes <= 0 or self.history_bytes <= self.history_limit_bytes

    def __str__(self) -> str:
        lines = [f"{self.steps:,} steps, {self.saved_states:,} states saved: {self.history_bytes / 1e6:.3g} MB "
                 f"(limit {self.history_limit_bytes / 1e6:.3g} MB){'' if self.fits else ' - too large'}",
                 f"set-up {self.setup_seconds:.3g} s, {self.seconds_per_step * 1e6:.3g} us per step: "
                 f"about {self.seconds:.3g} s in all"]
        if self.linear_solver:
            lines.append(f"linear solver: {self.linear_solver}")
        return "\n".join(lines)


def estimate(model: Model, scheme, *, dt: float, t_end: float, t0: float = 0.0,
             save_every: int = RUN_OPTIONS["save_every"], dofs=RUN_OPTIONS["dofs"],
             energy: bool = RUN_OPTIONS["energy"], probe_seconds: float = 0.05) -> Estimate:
    """The memory and time of ``solve(model, scheme, dt=dt, t_end=t_end, save_every=..., dofs=..., energy=...)``
    without making it: the history's bytes from the counts, the time from a probe of the first steps
    (about ``probe_seconds`` of them, at most the whole run) on a Stepper."""
    from ._solve import Stepper, _dof_indices

    if not isinstance(model, Model):
        raise _checks.type_error("model", f"expected nvib.Model, got {type(model).__name__}")
    dt, t0, t_end = _checks.number("dt", dt), _checks.number("t0", t0), _checks.number("t_end", t_end)
    save_every = _checks.integer("save_every", save_every, minimum=1)
    probe_seconds = _checks.real("probe_seconds", probe_seconds, positive=True)
    steps = _core.run_steps(t0, t_end, dt)  # checks dt, t0 and t_end as solve does
    saved = steps // save_every + 1 + (1 if steps % save_every else 0)
    m = len(_dof_indices(model, dofs)) or model.n
    t_start = time.perf_counter()
    st = Stepper(model, scheme, dt, t0=t0)
    done = 0
    try:
        st.step()
        done = 1
        setup = time.perf_counter() - t_start
        per_step, batch, spent = 0.0, 1, 0.0
        while done < steps and spent < probe_seconds:  # the C++ loop, in doubling stretches
            n = min(batch, steps - done)
            res = st.integrate(t0 + (done + n) * dt, save_every=n)
            spent += res.stats.wall_time
            done += res.stats.num_steps
            batch *= 2
        if done > 1:
            per_step = spent / (done - 1)
    except NvibError:  # the probe failed: what was measured stands (solve() would report the failure)
        setup = time.perf_counter() - t_start
        per_step = 0.0
    return Estimate(steps=steps, saved_states=saved, history_bytes=_core.history_bytes(saved, m, energy),
                    history_limit_bytes=0.5 * _core.available_memory(), setup_seconds=setup,
                    seconds_per_step=per_step, seconds=setup + per_step * max(steps - 1, 0),
                    linear_solver=st.stats.linear_solver)
