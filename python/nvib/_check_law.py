"""``check_law``: a Python law's declared slopes against central finite differences of its own force,
along a path of deformations, so that a wrong tangent (which costs Newton its quadratic convergence, or
its convergence) is found before a run, with the point where it is worst."""

from __future__ import annotations

import dataclasses

import numpy as np

from . import _checks

__all__ = ["check_law", "LawCheck"]


@dataclasses.dataclass
class LawCheck:
    """The result of ``check_law`` along a path of ``d`` (rates ``rate``, times ``t``): at each point the
    declared slopes ``slope_d`` (df/dd) and ``slope_v`` (df/dd'), their central finite differences
    ``fd_d`` and ``fd_v``, and the relative errors ``error_d``, ``error_v`` (|declared − difference| over
    the larger of the two and ``scale``, a millionth of the largest slope met, so that a slope of zero is
    not divided by). ``kink`` marks points where the force is not smooth (its forward and backward
    differences disagree: a yield point, a contact opening, a stick-slip switch): there either one-sided
    difference is a slope a Newton iteration may use, and the declared slope is judged against the closer
    (``fd_d``, ``fd_v`` hold it). ``worst``: (index, "df/dd" or "df/dd'", declared, difference, error) of the largest error;
    ``ok``: it is within ``tolerance``."""

    d: np.ndarray
    rate: np.ndarray
    t: np.ndarray
    force: np.ndarray
    slope_d: np.ndarray
    slope_v: np.ndarray
    fd_d: np.ndarray
    fd_v: np.ndarray
    error_d: np.ndarray
    error_v: np.ndarray
    kink: np.ndarray
    tolerance: float
    worst: tuple

    @property
    def ok(self) -> bool:
        return not self.worst[4] > self.tolerance

    def __str__(self) -> str:
        k, which, declared, fd, err = self.worst
        head = (f"{'slopes agree' if self.ok else 'WRONG SLOPE'}: worst {which} error {err:.2g} "
                f"(tolerance {self.tolerance:g}) at point {k}: d = {self.d[k]:.6g}, d' = {self.rate[k]:.6g}, "
                f"t = {self.t[k]:.6g}; declared {declared:.6g}, finite difference {fd:.6g}")
        return head + (f"\n{self.d.size} points, {int(self.kink.sum())} at kinks of the force (judged against "
                       "the closer one-sided difference)")

    def __repr__(self) -> str:
        return f"LawCheck({'ok' if self.ok else 'wrong slope'}, worst {self.worst[1]} error {self.worst[4]:.2g})"


def _compiled_as_callable(effect: dict) -> dict:
    """A compiled law's effect as the callable effect that calls it (through ctypes), to be checked alike."""
    import ctypes

    from . import _compiled

    spec = _compiled.lower("effect", {**effect, "measure": {0: 1.0}})
    fn = ctypes.CFUNCTYPE(*_compiled._CTYPES_SIGNATURE)(int(spec["address"]))
    params = (ctypes.c_double * _compiled.MAX_PARAMS)(*[float(spec.get(f"p{k}", 0.0))
                                                        for k in range(_compiled.MAX_PARAMS)])
    width = int(spec.get("state_size", 0))
    owner = effect["law"]  # the object the address lives in (a cfunc, a ctypes pointer): kept alive with the calls

    def call(d, dd, t, state=(), _owner=owner):
        out = (ctypes.c_double * 3)()
        committed = (ctypes.c_double * _compiled.MAX_STATE)(*state)
        trial = (ctypes.c_double * _compiled.MAX_STATE)(*state)
        code = fn(params, committed if width else None, d, dd, t, out, trial if width else None)
        if code != 0:
            raise _checks.value_error("effect.law", f"the compiled law returned {code} (not 0) at d = {d:g}, "
                                                    f"d' = {dd:g}, t = {t:g}")
        return out, tuple(trial[:width])

    if width:
        def law(d, dd, t, s):
            out, trial = call(d, dd, t, s)
            return out[0], trial

        tangent = lambda d, dd, t, s: tuple(call(d, dd, t, s)[0][1:3])  # noqa: E731
        return {"type": "callable", "law": law, "tangent": tangent, "state": [spec[f"s{k}"] for k in range(width)]}
    return {"type": "callable", "law": lambda d, dd, t: call(d, dd, t)[0][0],
            "tangent": lambda d, dd, t: tuple(call(d, dd, t)[0][1:3])}


def check_law(effect: dict, d, *, rate=None, t=None, step: float = 1e-6, tolerance: float = 1e-4) -> LawCheck:
    """Check the slopes a user's law declares against central finite differences of its force along the
    path ``d`` (rates ``rate``, times ``t``; zero by default). ``effect`` is the law's effect dict without
    its measure: a Python law, ``{"type": "callable", "law": f, "tangent": g}`` (and ``"state"``, the
    initial internal variables, for a law with memory: each point is then a trial from the state the path
    has committed so far, as in a run), or a compiled one, ``{"type": "compiled", "law": cfunc, "params":
    [...], "state": [...]}`` (its slopes are the out[1], out[2] it writes). The difference steps are ``step`` times the largest |d| (and
    |d'|) of the path; a slope is wrong where it differs from the difference by more than ``tolerance``
    (relative). Returns a ``LawCheck``; ``print`` it for the worst point."""
    if not isinstance(effect, dict):
        raise _checks.type_error("effect", f"expected a callable effect's dict {{'type': 'callable', 'law': f, "
                                           f"'tangent': g}}, got {type(effect).__name__}")
    if effect.get("type") == "compiled" and "law" in effect:
        if "measure" in effect:
            raise _checks.value_error("effect.measure", "check_law takes the law alone (d is its measure)")
        effect = _compiled_as_callable(effect)
    if effect.get("type") != "callable":
        raise _checks.value_error("effect.type", "check_law checks a user's law ({'type': 'callable', ...} or "
                                                 "{'type': 'compiled', 'law': ...}); the built-in laws' tangents "
                                                 "are checked by nvib's own tests (nvib.drive shows them), got "
                                                 f"{effect.get('type')!r}")
    for key in effect:
        if key not in ("type", "law", "tangent", "state", "uses_velocity", "uses_time", "name", "note"):
            raise _checks.value_error(f"effect.{key}", "check_law takes the law alone (d is its measure): expected "
                                                       "type, law, tangent, state, uses_velocity, uses_time")
    law, tangent = effect.get("law"), effect.get("tangent")
    if not callable(law):
        raise _checks.type_error("effect.law", f"expected a callable, got {type(law).__name__}")
    if not callable(tangent):
        raise _checks.value_error("effect.tangent", "the law declares no tangent (df/dd, df/dd'): there is nothing "
                                                    "to check (without one, runs use finite differences)")
    d = np.ascontiguousarray(_checks.real_array("d", d), dtype=float).reshape(-1)
    if d.size == 0:
        raise _checks.value_error("d", "expected a path of at least one deformation")
    n = d.size
    rate = np.zeros(n) if rate is None else _checks.vector("rate", rate, n)
    t = np.zeros(n) if t is None else _checks.vector("t", t, n)
    step = _checks.real("step", step, positive=True)
    tolerance = _checks.real("tolerance", tolerance, positive=True)
    stateful = effect.get("state") is not None
    state = tuple(_checks.real(f"effect.state[{k}]", x) for k, x in enumerate(effect["state"])) if stateful else ()
    velocity = effect.get("uses_velocity", True)

    def force(x, v, tt, s):
        out = law(x, v, tt, s) if stateful else law(x, v, tt)
        if stateful:
            if not isinstance(out, (tuple, list)) or len(out) != 2:
                raise _checks.type_error("effect.law", "a law with state must return (force, state)")
            return float(out[0]), tuple(float(y) for y in out[1])
        return float(out), s

    hd = step * max(float(np.max(np.abs(d))), 1e-300)
    hv = step * max(float(np.max(np.abs(rate))), 1.0 if not np.any(rate) else 1e-300)
    out = {k: np.zeros(n) for k in ("force", "slope_d", "slope_v", "fd_d", "fd_v", "fwd_d", "bwd_d", "fwd_v",
                                    "bwd_v")}
    for k in range(n):
        x, v, tt = float(d[k]), float(rate[k]), float(t[k])
        f0, committed = force(x, v, tt, state)
        kc = tangent(x, v, tt, state) if stateful else tangent(x, v, tt)
        if not isinstance(kc, (tuple, list)) or len(kc) != 2:
            raise _checks.type_error("effect.tangent", f"must return (df/dd, df/dd'), got {kc!r}")
        out["force"][k], out["slope_d"][k] = f0, float(kc[0])
        out["slope_v"][k] = 0.0 if kc[1] is None else float(kc[1])
        fp, fm = force(x + hd, v, tt, state)[0], force(x - hd, v, tt, state)[0]
        out["fwd_d"][k], out["bwd_d"][k] = (fp - f0) / hd, (f0 - fm) / hd
        if velocity:
            gp, gm = force(x, v + hv, tt, state)[0], force(x, v - hv, tt, state)[0]
            out["fwd_v"][k], out["bwd_v"][k] = (gp - f0) / hv, (f0 - gm) / hv
        state = committed  # the point is accepted: the next trial starts from its state
    largest = max(float(np.max(np.abs(out[k]))) for k in ("fwd_d", "bwd_d", "fwd_v", "bwd_v"))
    scale = 1e-6 * max(largest, 1e-300)
    kink = np.zeros(n, dtype=bool)
    errors = {}
    for which in ("d", "v"):
        fwd, bwd, declared = out["fwd_" + which], out["bwd_" + which], out["slope_" + which]
        # a kink: one-sided differences further apart than a smooth force's (h f'', far below a thousandth of
        # the largest slope)
        at_kink = np.abs(fwd - bwd) > 1e-2 * np.maximum(np.maximum(np.abs(fwd), np.abs(bwd)), 1e3 * scale)
        rel = lambda fd: np.abs(declared - fd) / np.maximum(np.maximum(np.abs(fd), np.abs(declared)), scale)  # noqa: E731
        central = 0.5 * (fwd + bwd)
        closer = np.where(rel(fwd) <= rel(bwd), fwd, bwd)
        out["fd_" + which] = np.where(at_kink, closer, central)
        errors[which] = rel(out["fd_" + which])
        kink |= at_kink
    worst = (0, "df/dd", out["slope_d"][0], out["fd_d"][0], 0.0)
    for which, name, key in (("d", "df/dd", "slope_d"), ("v", "df/dd'", "slope_v")):
        e = errors[which]
        if np.any(~np.isnan(e)):
            k = int(np.nanargmax(e))
            if e[k] > worst[4]:
                worst = (k, name, float(out[key][k]), float(out["fd_" + which][k]), float(e[k]))
    return LawCheck(d, rate, t, out["force"], out["slope_d"], out["slope_v"], out["fd_d"], out["fd_v"],
                    errors["d"], errors["v"], kink, tolerance, worst)

