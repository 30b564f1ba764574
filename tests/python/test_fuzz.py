"""Fuzz test of the public API: random shapes, values, scheme parameters,
scene files and callbacks that misbehave. Whatever goes in, nvib answers with
a result or a Python exception of the documented type, never a crash (a
segfault or abort would kill pytest: that is what this file is for) and never
a silent NaN:

- bad input: ValueError or TypeError (SceneError is a ValueError) whose
  message starts with the name of what is wrong ("dt: ...", "effects[2].k: ...");
- a run that fails: nvib.DivergenceError, ConvergenceError or SingularMatrixError;
- a callback that raises: its own exception, unchanged.

A successful run holds only finite values. Examples are derandomized so CI is
reproducible; the counts are set explicitly (500 runs and 150 constructions
per scheme of the registry, 400 scene files)."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

import nvib

FUZZ = settings(derandomize=True, deadline=None, database=None, print_blob=True,
                suppress_health_check=list(HealthCheck))

RUN_ERRORS = (nvib.DivergenceError, nvib.ConvergenceError, nvib.SingularMatrixError)
# A message that names what is wrong: "name: ...", "effects[2].k: ...", "path.toml: ...",
# or the callback that misbehaved: "force returned shape ...", "effects[1].law must return ...".
NAMED = re.compile(r"^([\w./\[\]'-]+(, [\w./\[\]'-]+)*: |(force|tangent|effects\[\d+\]\.(law|tangent))\b)")


class CallbackBoom(Exception):
    """Raised by the misbehaving callbacks: it must reach the caller unchanged."""


# --------------------------------------------------------------------------- drawing
class Draw:
    """Draws the inputs of one example. Half of the examples are clean (every
    argument valid, so the run itself is exercised); in the others each
    argument is bad with a small probability, so most errors come alone."""

    def __init__(self, data):
        self.data = data
        self.bad_percent = data.draw(st.sampled_from([0, 0, 4, 12]), label="bad %")

    def __call__(self, strategy, label=None):
        return self.data.draw(strategy, label=label)

    def pick(self, good, bad, label=None):
        if self.bad_percent and self.data.draw(st.integers(0, 99)) < self.bad_percent:
            return self.data.draw(bad, label=label)
        return self.data.draw(good, label=label)

    def chance(self, percent: int) -> bool:
        return self.data.draw(st.integers(0, 99)) < percent


BAD_REALS = st.sampled_from([math.nan, math.inf, -math.inf, "1.0", None, True, 10**400, [1.0], 1 + 2j, -1.0, 0.0])


def bad_vectors(n):
    return st.one_of(
        st.lists(st.floats(-10, 10), min_size=0, max_size=n + 2).filter(lambda x: len(x) != n),
        st.lists(st.sampled_from([math.nan, math.inf, 1.0]), min_size=n, max_size=n).filter(
            lambda x: not all(map(math.isfinite, x))),
        st.just([[1.0] * n]), st.just("abc"), st.just([1j] * n), st.just([True] * n), st.just({"a": 1.0}),
    )


def good_vectors(n, scale=2.0):
    return st.lists(st.floats(-scale, scale), min_size=n, max_size=n)


# --------------------------------------------------------------------------- callbacks
GOOD_FORCES = ["good"]
BAD_FORCES = ["raises", "raises_later", "wrong_shape", "complex", "string", "nan", "none", "list", "int", "huge",
              "scalar", "matrix", "tuple", "object"]
GOOD_TANGENTS = ["good", "c_none"]
BAD_TANGENTS = ["raises", "wrong_shape", "not_tuple", "triple", "nan", "complex"]


def make_force(kind: str, n: int, k: float):
    calls = {"n": 0}

    @np.errstate(all="ignore")  # a diverging run hands the callback huge states: not the point here
    def force(u, v, t):
        calls["n"] += 1
        f = k * u + 0.1 * u ** 3
        if kind == "good":
            return f
        if kind == "raises":
            raise CallbackBoom("force failed")
        if kind == "raises_later":
            if calls["n"] > 3:
                raise CallbackBoom("force failed later")
            return f
        if kind == "wrong_shape":
            return np.zeros(n + 1)
        if kind == "complex":
            return f.astype(complex)
        if kind == "string":
            return "force"
        if kind == "nan":
            return np.full(n, math.nan)
        if kind == "none":
            return None
        if kind == "list":
            return list(f)
        if kind == "int":
            return np.zeros(n, dtype=np.int64)
        if kind == "huge":
            return f * 1e300
        if kind == "scalar":
            return 1.0
        if kind == "matrix":
            return np.zeros((n, n))
        if kind == "tuple":
            return (f, f)
        return object()

    return force


def make_tangent(kind: str, n: int, k: float):
    @np.errstate(all="ignore")
    def tangent(u, v, t):
        K = np.diag(k + 0.3 * u ** 2)
        if kind == "good":
            return K, None
        if kind == "c_none":
            return K, np.zeros((n, n))
        if kind == "raises":
            raise CallbackBoom("tangent failed")
        if kind == "wrong_shape":
            return np.zeros((n + 1, n)), None
        if kind == "not_tuple":
            return K
        if kind == "triple":
            return K, None, None
        if kind == "nan":
            return np.full((n, n), math.nan), None
        return K.astype(complex), None

    return tangent


def make_law(kind: str):
    def law(d, dd, t):
        if kind == "good":
            return 3.0 * d + d * d * d
        if kind == "raises":
            raise CallbackBoom("law failed")
        if kind == "nan":
            return math.nan
        if kind == "string":
            return "x"
        if kind == "vector":
            return [1.0, 2.0]
        return None

    return law


# --------------------------------------------------------------------------- effects and masses
PARAMS = {  # type -> {parameter: range of valid values}
    "spring": {"k": (0.0, 1e4)}, "damper": {"c": (0.0, 10.0)},
    "hardening_spring": {"k0": (0.0, 1e4), "a": (0.0, 100.0)},
    "cubic_spring": {"k3": (0.0, 1e4)}, "power_damper": {"c": (0.0, 10.0), "p": (0.5, 3.0)},
    "pendulum_gravity": {"m": (0.1, 10.0), "g": (0.0, 10.0), "l": (0.1, 10.0)}, "hertz_contact": {"G": (1e-8, 1e-3)},
    "constant_force": {"value": (-100.0, 100.0)}, "harmonic_force": {"amplitude": (-10.0, 10.0), "omega": (0.0, 50.0)},
    "ground_acceleration": {}, "callable": {},
}


def effect(draw: Draw, dofs):
    kind = draw(st.sampled_from(list(PARAMS)), label="effect type")
    measure = draw(st.dictionaries(st.sampled_from(dofs), st.floats(-2, 2), min_size=1, max_size=3))
    spec = {"type": kind, "measure": measure}
    for p, (lo, hi) in PARAMS[kind].items():
        spec[p] = draw.pick(st.floats(lo, hi), BAD_REALS, label=p)
    if kind == "ground_acceleration":
        spec["signal"] = draw.pick(st.one_of(
            st.fixed_dictionaries({"kind": st.just("sine"), "amplitude": st.floats(-10, 10),
                                   "omega": st.floats(0, 20)}),
            st.fixed_dictionaries({"kind": st.just("table"), "t": st.just([0.0, 0.5, 2.0]),
                                   "values": good_vectors(3, 10.0)})),
            st.one_of(st.just({"kind": "square"}), st.just(3.0),
                      st.just({"kind": "table", "t": [1.0, 0.0], "values": [0.0, 1.0]}),
                      st.just({"kind": "table", "t": [0.0, 1.0], "values": [0.0]}),
                      st.just({"kind": "sine", "amplitude": 1.0}),
                      st.just({"kind": "table", "t": ["a", "b"], "values": [0.0, 1.0]})), label="signal")
        if draw(st.booleans()):
            del spec["measure"]
    if kind == "hertz_contact" and draw(st.booleans()):
        spec["irregularity"] = {"kind": "sine", "amplitude": draw(st.floats(0, 1e-4)), "omega": 2.0}
    if kind == "callable":
        spec["law"] = make_law(draw.pick(st.just("good"), st.sampled_from(["raises", "nan", "string", "vector",
                                                                          "none"]), label="law"))
        if draw(st.booleans()):
            spec["tangent"] = draw.pick(st.just(lambda d, dd, t: (3.0 + 3 * d * d, 0.0)),
                                        st.sampled_from([lambda d, dd, t: (math.nan, 0.0), lambda d, dd, t: 5.0]))
        spec["uses_velocity"] = draw.pick(st.booleans(), st.just("yes"))
        spec["uses_time"] = draw(st.booleans())
    # mistakes in the spec itself
    mistake = draw.pick(st.just(None), st.sampled_from(["type", "measure", "dof", "coef", "key", "drop", "name"]),
                        label="effect mistake")
    if mistake == "type":
        spec["type"] = draw(st.sampled_from(["bogus", 3, None]))
    elif mistake == "measure":
        spec["measure"] = draw(st.sampled_from([{}, 3, None, [1.0]]))
    elif mistake == "dof":
        spec["measure"] = {draw(st.sampled_from(["nope", 7, -1, True])): 1.0}
    elif mistake == "coef":
        spec["measure"] = {dofs[0]: draw(BAD_REALS)}
    elif mistake == "key":
        spec["unknown_key"] = 1.0
    elif mistake == "drop" and PARAMS[kind]:
        del spec[next(iter(PARAMS[kind]))]
    elif mistake == "name":
        spec["name"] = 3
    return spec


def mass(draw: Draw, n: int):
    form = draw(st.sampled_from(["diag", "diag", "dense"]))
    if form == "diag":
        good = st.lists(st.floats(1e-2, 1e3), min_size=n, max_size=n)
    else:
        good = st.lists(st.floats(-1, 1), min_size=n * n, max_size=n * n).map(
            lambda a: (lambda A: A @ A.T + np.eye(n))(np.array(a).reshape(n, n)))
    bad = st.one_of(
        st.just([1.0] * (n - 1) + [0.0]), st.just([-1.0] * n), st.just([math.nan] * n), st.just([1e-320] * n),
        st.just(np.eye(n) + np.triu(np.ones((n, n)), 1)),  # not symmetric (n > 1)
        st.just(np.eye(n) - 2 * np.ones((n, n))),  # symmetric, indefinite
        st.sampled_from([[], [[1.0, 2.0]], np.ones((2, 2, 2)), "mass", None, [1 + 1j], [[1.0]] * 3, [True]]))
    return draw.pick(good, bad, label="mass")


def valid_value(p: dict):
    """A valid value of a declared parameter (its "range" from the registry), kept near its default
    where the declaration has no bound, and a run's worth of iterations or squarings at most."""
    kind, rng, default = p["kind"], p["range"], p["default"]
    if kind == "choice":
        return st.sampled_from(rng)
    if kind == "newton":
        return newton_options()
    lo, hi, lo_open, hi_open = rng
    if kind == "int":
        return st.integers(lo, min(hi, lo + 30))
    spread = 10.0 * abs(default) + 1e-3
    lo, lo_open = (lo, lo_open) if math.isfinite(lo) else (min(default, 0.0) - spread, False)
    hi, hi_open = (hi, hi_open) if math.isfinite(hi) else (max(default, 0.0) + spread, False)
    return st.floats(lo, hi, exclude_min=lo_open, exclude_max=hi_open)


@st.composite
def newton_options(draw):
    """nvib.Newton with each declared option either its default or a valid value."""
    kw = {p["name"]: draw(valid_value(p)) for p in nvib.Newton.parameters() if draw(st.booleans())}
    try:
        return nvib.Newton(**kw)
    except ValueError:  # rtol = atol = 0
        return nvib.Newton()


def make_scheme(draw: Draw, cls):
    """A valid scheme of class ``cls`` drawn from its declaration: each parameter its default or a valid
    value, or one of the class's named constructors. Combinations that the scheme's own cross-checks
    reject (generalized-alpha's unconditional stability) fall back to the defaults."""
    factories = cls.factories()
    if factories and draw(st.booleans()):
        f = draw(st.sampled_from(factories))
        p = next(q for q in cls.parameters() if q["kind"] == "newton")
        make = getattr(cls, f["method"])
        for x in draw(st.lists(st.floats(-1, 1), min_size=3, max_size=3)):
            try:
                return make(x, newton=draw(valid_value(p)))
            except ValueError:
                continue
        return cls()
    kw = {p["name"]: draw(valid_value(p)) for p in cls.parameters() if draw(st.booleans())}
    try:
        return cls(**kw)
    except ValueError:
        return cls()


def category(exc: BaseException) -> str:
    """The exception is one nvib documents, and bad input names what is wrong."""
    if isinstance(exc, CallbackBoom):
        return "callback's own exception"
    if isinstance(exc, RUN_ERRORS):
        assert exc.t is not None and exc.step is not None, exc
        return type(exc).__name__
    assert isinstance(exc, (ValueError, TypeError)), f"{type(exc).__name__}: {exc}"
    assert NAMED.match(str(exc)), f"message does not name the argument: {type(exc).__name__}: {exc}"
    if isinstance(exc, (nvib.ArgumentError, nvib.ArgumentTypeError)) and not isinstance(exc, nvib.SceneError):
        # .argument is what the message names (a SceneError names the file and has .argument "scene")
        assert exc.argument and str(exc).startswith(exc.argument), f"{exc.argument!r}: {exc}"
    return type(exc).__name__


def check_result(res) -> str:
    assert isinstance(res.status, nvib.Status)
    for name in ("t", "u", "v", "a"):
        arr = getattr(res, name)
        assert np.all(np.isfinite(arr)), f"{name} holds a non-finite value in a returned result"
    assert len(res.t) == res.u.shape[0] == res.v.shape[0] == res.a.shape[0]
    if res.status != nvib.Status.success:
        assert res.failure.step >= 1
    return f"status {res.status}"


def exercise(data, scheme_class) -> str:
    draw = Draw(data)
    n = draw(st.integers(1, 4), label="n")
    kw = {}
    if draw(st.booleans()):
        dofs = [f"d{i}" for i in range(n)]
        kw["dofs"] = draw.pick(st.just(dofs), st.sampled_from([dofs[:-1], dofs + ["x"], ["d0"] * n, 5]))
    else:
        dofs = [f"u{i}" for i in range(n)]
    if draw(st.booleans()):
        kw["u0"] = draw.pick(good_vectors(n), bad_vectors(n), label="u0")
    if draw(st.booleans()):
        kw["v0"] = draw.pick(good_vectors(n), bad_vectors(n), label="v0")
    if draw.chance(25):
        kw["K"] = draw.pick(st.floats(0, 1e4).map(lambda k: k * np.eye(n)),
                            st.sampled_from([np.eye(n + 1), np.full((n, n), math.nan), "K", [[1j]]]), label="K")
    if draw.chance(20):
        kw["C"] = draw.pick(st.floats(0, 10).map(lambda c: c * np.eye(n)), st.just(np.eye(n + 1)), label="C")
    if draw.chance(35):
        k = draw(st.floats(0.0, 1e4))
        kw["force"] = make_force(draw.pick(st.sampled_from(GOOD_FORCES), st.sampled_from(BAD_FORCES), label="force"),
                                 n, k)
        if draw(st.booleans()):
            kw["tangent"] = make_tangent(draw.pick(st.sampled_from(GOOD_TANGENTS), st.sampled_from(BAD_TANGENTS),
                                                   label="tangent"), n, k)
        kw["uses_velocity"] = draw(st.booleans())
        kw["uses_time"] = draw(st.booleans())
    if draw.chance(70):
        kw["effects"] = [effect(draw, dofs) for _ in range(draw(st.integers(0, 4)))]
    model = nvib.Model(mass(draw, n), **kw)

    scheme = make_scheme(draw, scheme_class)
    dt = draw.pick(st.floats(1e-4, 0.2), st.sampled_from([0.0, -1e-3, math.nan, "0.1", 1e-300]), label="dt")
    nsteps = draw(st.integers(1, 400), label="nsteps")
    t0 = draw(st.one_of(st.just(0.0), st.floats(-10, 10)), label="t0")
    t_end = t0 + dt * nsteps if isinstance(dt, float) and math.isfinite(dt) and dt > 1e-6 else t0 + 1.0
    t_end = draw.pick(st.just(t_end), st.sampled_from([t0, t0 - 1.0, math.nan, math.inf, "1"]), label="t_end")
    opts = dict(dt=dt, t_end=t_end, t0=t0, throw=draw(st.booleans()))
    if draw(st.booleans()):
        opts["save_every"] = draw.pick(st.integers(1, 50), st.sampled_from([0, -2, 2.5, "3"]), label="save_every")
    if draw.chance(25):
        opts["dofs"] = draw.pick(st.lists(st.sampled_from(dofs + list(range(n))), min_size=1, max_size=3),
                                 st.sampled_from([["zz"], [9], [-1], [1.5]]), label="dofs")
    if draw.chance(25):
        opts["max_displacement"] = draw.pick(st.sampled_from([1e-3, 1.0, 1e6, math.inf]),
                                             st.sampled_from([-1.0, 0.0, math.nan, "big"]), label="max_displacement")
    if draw.chance(25):
        opts["energy"] = True
    if draw.chance(15):
        opts["u0"] = draw.pick(good_vectors(n), bad_vectors(n), label="solve u0")
    if draw.chance(5):
        def progress(i, total):
            raise CallbackBoom("progress")
        opts["progress"] = progress
    if draw.chance(20):  # step by step instead of solve()
        stepper = nvib.Stepper(model, scheme, dt)
        stepper.step(draw(st.integers(1, 50)))
        if draw(st.booleans()):
            x = stepper.state()
            stepper.set_state(draw.pick(st.sampled_from([x, 2.0 * x]),
                                        st.sampled_from([x[:-1], x * math.nan, "x", x.reshape(1, -1)])))
        res = stepper.integrate(stepper.t + 0.05, throw=opts["throw"])
    else:
        res = nvib.solve(model, scheme, **opts)
    return check_result(res)


@settings(FUZZ, max_examples=500)
@given(data=st.data())
def test_fuzz_models_and_runs(scheme_class, data):
    try:
        outcome = exercise(data, scheme_class)
    except (ValueError, TypeError, CallbackBoom, *RUN_ERRORS) as exc:
        outcome = category(exc)
    event(outcome)


# --------------------------------------------------------------------------- scheme constructors
BAD_VALUES = st.one_of(BAD_REALS, st.sampled_from(["bogus", 2**70, -3, 0, 1001, 1.5, 2.0, -0.5, b"newton"]))


def constructors(cls) -> list:
    """(callable, its parameters) for the class and each of its named constructors, from the declaration."""
    params = {p["name"]: p for p in cls.parameters()}
    newton = [p for p in params.values() if p["kind"] == "newton"]
    shortcut = [{"name": "iteration", "kind": "choice", "default": "newton",
                 "range": next(q["range"] for q in nvib.Newton.parameters() if q["name"] == "iteration")}] if newton else []
    out = [(cls, list(params.values()) + shortcut)]
    for f in cls.factories():
        real = {"name": f["parameter"], "kind": "real", "default": 0.0, "range": (-1.0, 1.0, False, False)}
        out.append((getattr(cls, f["method"]), [real] + newton + shortcut))
    return out


@settings(FUZZ, max_examples=150)
@given(data=st.data())
def test_fuzz_scheme_constructors(scheme_class, data):
    draw = Draw(data)
    make, params = draw(st.sampled_from(constructors(scheme_class)), label="constructor")
    chosen = draw(st.lists(st.sampled_from(params), max_size=len(params), unique_by=lambda p: p["name"])) \
        if params else []  # a scheme may have no parameters
    kwargs = {p["name"]: draw.pick(valid_value(p), BAD_VALUES) for p in chosen}
    if draw.chance(draw.bad_percent):
        kwargs[draw(st.sampled_from(["foo", "eta", "beta", "alpha", "max_iter"]))] = draw(st.floats(0, 1))
    args = []
    if draw.chance(2 * draw.bad_percent):  # positional arguments, possibly too many or given twice
        args = draw(st.lists(st.one_of(st.floats(0, 1), BAD_VALUES), min_size=1, max_size=3))
    try:
        scheme = make(*args, **kwargs)
    except (ValueError, TypeError) as exc:
        event(category(exc))
        return
    event("constructed")
    assert type(scheme) is scheme_class
    if make is scheme_class and not args:  # what was accepted is what the scheme holds
        for k, v in kwargs.items():
            assert getattr(scheme, k) == v, (k, v)
    assert eval(repr(scheme), vars(nvib)) == scheme


# --------------------------------------------------------------------------- scene files
GOOD_SCENE = """[scene]
name = "fuzz"
t_end = 0.05
dt = 0.001
[dofs]
names = ["a", "b"]
mass = [1.0, 2.0]
[initial]
u = [0.1, 0.0]
v = { b = 1.0 }
[[effect]]
type = "spring"
measure = { a = 1.0 }
k = 100.0
[[effect]]
type = "hardening_spring"
measure = { b = 1.0, a = -1.0 }
k0 = 50.0
a = 10.0
[[effect]]
type = "constant_force"
name = "gravity"
measure = { b = 1.0 }
value = 5.0
""".splitlines()
SCENE_LINES = [
    '[scene]', 'name = "x"', 't_end = 1.0', 'dt = 0.01', 'dt = "fast"', 'dt = -1.0', 'plot_dof = "a"',
    'plot_dof = "zz"', 'bogus = 1', '[dofs]', 'names = ["a", "b"]', 'names = ["a"]', 'names = "a"',
    'names = ["a", "a"]', 'mass = [1.0, 2.0]', 'mass = [1.0, -2.0]', 'mass = [[1.0, 0.0], [0.0, 1.0]]',
    'mass = [[1.0, 2.0], [2.0, 1.0]]', 'mass = ["x", 1.0]', 'mass = [[1.0], [2.0, 3.0]]', '[initial]',
    'u = [0.1, 0.0]', 'u = "static_equilibrium"', 'u = "static"', 'v = { a = 1.0 }', 'v = { q = 1.0 }',
    'v = { a = "x" }', 'u = [1.0]', 'u = 3', 'u = ["x", 1]', '[[effect]]', 'type = "spring"',
    'type = "hertz_contact"', 'type = "constant_force"', 'type = "nope"', 'measure = { a = 1.0 }',
    'measure = { b = 1.0, a = -1.0 }', 'measure = { q = 1.0 }', 'measure = 3', 'k = 100.0', 'k = "stiff"',
    'G = 1e-7', 'value = 5.0', 'name = "g"', 'c = 1.0', 'signal = { kind = "table", t = [0.0, 1.0], values = [1.0] }',
    '[effect]', 'x = = 1', '[[effect', 'names = [', '"unterminated', 'mass = nan', 'k = inf', 'k0 = 1e308',
]


@settings(FUZZ, max_examples=400)
@given(data=st.data())
def test_fuzz_scene_files(data, tmp_path_factory):
    lines = list(GOOD_SCENE)
    draw = Draw(data)  # a clean example loads the good scene with its solvable variations
    if draw.bad_percent == 0:
        lines[lines.index("k = 100.0")] = f"k = {draw(st.floats(0, 1e4))!r}"
        lines[lines.index("value = 5.0")] = f"value = {draw(st.floats(-100, 100))!r}"
        if draw(st.booleans()):
            lines[lines.index("u = [0.1, 0.0]")] = 'u = "static_equilibrium"'
    for _ in range(draw(st.integers(1, 3), label="mutations") if draw.bad_percent else 0):
        where = data.draw(st.integers(0, len(lines)))
        how = data.draw(st.sampled_from(["insert", "replace", "delete"]))
        if how == "delete" and where < len(lines):
            del lines[where]
        elif how == "replace" and where < len(lines):
            lines[where] = data.draw(st.sampled_from(SCENE_LINES))
        else:
            lines.insert(where, data.draw(st.sampled_from(SCENE_LINES)))
    path = tmp_path_factory.mktemp("scene") / "fuzz.toml"
    path.write_text("\n".join(lines) + "\n")
    try:
        model = nvib.load_scene(str(path))
        res = nvib.solve(model, nvib.CEMDTS(), dt=model.scene["dt"] or 1e-3, t_end=model.scene["t_end"] or 0.05,
                         throw=False)
    except (ValueError, TypeError) as exc:
        event(category(exc))
        assert isinstance(exc, nvib.SceneError) and str(exc).startswith(str(path)), f"{type(exc).__name__}: {exc}"
        return
    event(check_result(res))


def test_fuzz_checks_are_strict():
    """The checks above fail on what they must fail on."""
    with pytest.raises(AssertionError):
        category(RuntimeError("x"))
    with pytest.raises(AssertionError):
        category(ValueError("incompatible constructor arguments"))
    assert category(ValueError("dt: must be > 0")) == "ValueError"
    assert category(TypeError("force returned None at t = 0")) == "TypeError"
    assert category(CallbackBoom("anything")) == "callback's own exception"
    assert category(ValueError("u0, v0: the initial acceleration is not finite")) == "ValueError"
    with pytest.raises(AssertionError):  # NumPy's own message names nothing
        category(ValueError("could not convert string to float: 'a'"))
    with pytest.raises(AssertionError):  # .argument disagrees with the message
        bad = nvib.ArgumentError("dt: must be > 0")
        bad.argument = "t_end"
        category(bad)
