"""The schemes as Python classes: each is its C++ parameter struct (nvib._core)
with a constructor that checks argument names and types first, so that every
error names the argument ("foo: unknown parameter of CEMDTS (expected eta)",
"eta: expected a real number, got str") instead of pybind11's generic
"incompatible constructor arguments". Ranges are checked by the C++
constructors, which name the parameter and the condition."""

from __future__ import annotations

import functools
import inspect

from . import _checks, _core

_NEWTON_DEFAULTS = dict(iteration="newton", max_iter=20, rtol=1e-10, atol=1e-12, jacobian="analytic")


def _explain(owner: str, sig: inspect.Signature, args: tuple, kwargs: dict) -> str:
    """Why args/kwargs do not fit sig, naming the argument."""
    params = list(sig.parameters.values())[1:]  # without self / cls
    names = [p.name for p in params]
    expected = ", ".join(names) or "no parameters"
    for key in kwargs:
        if key not in names:
            return f"{key}: unknown parameter of {owner} (expected {expected})"
    positional = [p.name for p in params if p.kind is p.POSITIONAL_OR_KEYWORD]
    if len(args) > len(positional):
        keyword_only = [p.name for p in params if p.kind is p.KEYWORD_ONLY]
        extra = f"; {', '.join(keyword_only)} must be given by name" if keyword_only else ""
        return (f"{owner}: takes at most {len(positional)} positional argument"
                f"{'' if len(positional) == 1 else 's'} ({', '.join(positional) or 'none'}), "
                f"got {len(args)}{extra}")
    for name in positional[:len(args)]:
        if name in kwargs:
            return f"{name}: given twice (by position and by name) to {owner}"
    for p in params:
        if p.default is p.empty and p.name not in kwargs and p.name not in positional[:len(args)]:
            return f"{p.name}: missing (required by {owner})"
    return f"{owner}: arguments do not match {sig}"


def _named_errors(owner: str):
    """Binds the arguments to the signature first; a mismatch raises TypeError naming the argument."""

    def decorate(func):
        sig = inspect.signature(func)

        @functools.wraps(func)
        def wrapper(first, *args, **kwargs):
            try:
                sig.bind(first, *args, **kwargs)
            except TypeError:
                raise TypeError(_explain(owner, sig, args, kwargs)) from None
            return func(first, *args, **kwargs)

        return wrapper

    return decorate


def _choice(name: str, value, options: tuple[str, ...]) -> str:
    if not isinstance(value, str):
        raise TypeError(f"{name}: expected one of {', '.join(repr(o) for o in options)}, "
                        f"got {type(value).__name__}")
    return value  # the C++ constructor rejects an unknown string, naming the argument


def _cint(name: str, x) -> int:
    """An integer that fits the C++ int it is passed to (the range itself is checked there)."""
    x = _checks.integer(name, x)
    if not -2**31 <= x < 2**31:
        raise ValueError(f"{name}: out of range, got {x}")
    return x


def _newton(iteration, max_iter, rtol, atol, jacobian) -> dict:
    return dict(iteration=_choice("iteration", iteration, ("newton", "modified", "none")),
                max_iter=_cint("max_iter", max_iter),
                rtol=_checks.real("rtol", rtol), atol=_checks.real("atol", atol),
                jacobian=_choice("jacobian", jacobian, ("analytic", "finite_difference")))


class CentralDifference(_core.CentralDifference):
    __doc__ = _core.CentralDifference.__doc__

    @_named_errors("CentralDifference")
    def __init__(self, *, velocity: str = "synchronized"):
        super().__init__(velocity=_choice("velocity", velocity, ("synchronized", "half_step")))


class Zhai(_core.Zhai):
    __doc__ = _core.Zhai.__doc__

    @_named_errors("Zhai")
    def __init__(self, psi: float = 0.5, phi: float = 0.5):
        super().__init__(_checks.real("psi", psi), _checks.real("phi", phi))


class CEMDTS(_core.CEMDTS):
    __doc__ = _core.CEMDTS.__doc__

    @_named_errors("CEMDTS")
    def __init__(self, eta: float = 0.45):
        super().__init__(_checks.real("eta", eta))


class Newmark(_core.Newmark):
    __doc__ = _core.Newmark.__doc__

    @_named_errors("Newmark")
    def __init__(self, beta: float = 0.25, gamma: float = 0.5, *, iteration: str = "newton", max_iter: int = 20,
                 rtol: float = 1e-10, atol: float = 1e-12, jacobian: str = "analytic"):
        super().__init__(_checks.real("beta", beta), _checks.real("gamma", gamma),
                         **_newton(iteration, max_iter, rtol, atol, jacobian))


class GeneralizedAlpha(_core.GeneralizedAlpha):
    __doc__ = _core.GeneralizedAlpha.__doc__

    @_named_errors("GeneralizedAlpha")
    def __init__(self, alpha_m: float = 0.5, alpha_f: float = 0.5, beta: float = 0.25, gamma: float = 0.5, *,
                 iteration: str = "newton", max_iter: int = 20, rtol: float = 1e-10, atol: float = 1e-12,
                 jacobian: str = "analytic"):
        super().__init__(_checks.real("alpha_m", alpha_m), _checks.real("alpha_f", alpha_f),
                         _checks.real("beta", beta), _checks.real("gamma", gamma),
                         **_newton(iteration, max_iter, rtol, atol, jacobian))

    @classmethod
    def _like(cls, core, newton: dict) -> "GeneralizedAlpha":
        # the C++ factory computed (and validated) the four parameters; rebuild them as this class
        return cls(core.alpha_m, core.alpha_f, core.beta, core.gamma, **newton)

    @classmethod
    @_named_errors("GeneralizedAlpha.from_rho_inf")
    def from_rho_inf(cls, rho_inf: float, *, iteration: str = "newton", max_iter: int = 20, rtol: float = 1e-10,
                     atol: float = 1e-12, jacobian: str = "analytic") -> "GeneralizedAlpha":
        """Chung-Hulbert parameters from the spectral radius at infinity rho_inf in [0, 1]."""
        kw = _newton(iteration, max_iter, rtol, atol, jacobian)
        return cls._like(_core.GeneralizedAlpha.from_rho_inf(_checks.real("rho_inf", rho_inf), **kw), kw)

    @classmethod
    @_named_errors("GeneralizedAlpha.hht")
    def hht(cls, alpha: float, *, iteration: str = "newton", max_iter: int = 20, rtol: float = 1e-10,
            atol: float = 1e-12, jacobian: str = "analytic") -> "GeneralizedAlpha":
        """Hilber-Hughes-Taylor with their alpha in [-1/3, 0]."""
        kw = _newton(iteration, max_iter, rtol, atol, jacobian)
        return cls._like(_core.GeneralizedAlpha.hht(_checks.real("alpha", alpha), **kw), kw)

    @classmethod
    @_named_errors("GeneralizedAlpha.wbz")
    def wbz(cls, alpha: float, *, iteration: str = "newton", max_iter: int = 20, rtol: float = 1e-10,
            atol: float = 1e-12, jacobian: str = "analytic") -> "GeneralizedAlpha":
        """Wood-Bossak-Zienkiewicz with alpha in [-1, 0]."""
        kw = _newton(iteration, max_iter, rtol, atol, jacobian)
        return cls._like(_core.GeneralizedAlpha.wbz(_checks.real("alpha", alpha), **kw), kw)


class PreciseIntegration(_core.PreciseIntegration):
    __doc__ = _core.PreciseIntegration.__doc__

    @_named_errors("PreciseIntegration")
    def __init__(self, *, squarings: int = 20, order: int = 2, corrections: int = 1):
        super().__init__(squarings=_cint("squarings", squarings), order=_cint("order", order),
                         corrections=_cint("corrections", corrections))


SCHEMES = (CentralDifference, Zhai, CEMDTS, Newmark, GeneralizedAlpha, PreciseIntegration)
