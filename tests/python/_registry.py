"""The schemes that tests run "every scheme" with, taken from the registry, never
from a list of a test's own: ``scheme_variants()`` gives each registry scheme
with its defaults and the settings of VARIANTS (by registry key; a new scheme
without an entry runs with its defaults); ``with_newton`` changes the Newton
options of an implicit scheme. The fixtures ``scheme_key`` and
``scheme_class`` are in conftest.py."""

from __future__ import annotations

import nvib

# Settings beyond each scheme's defaults, by registry key: {id: constructor keywords, or
# (named constructor, its argument, keywords)}.
VARIANTS = {
    "lcdm": {"half_step": dict(velocity="half_step")},
    "zhai": {"0.6": dict(psi=0.6, phi=0.6)},
    "newmark": {"one_iteration": dict(iteration="one_iteration")},
    "galpha": {"rho0.8-modified": ("from_rho_inf", 0.8, dict(iteration="modified"))},
    "pim": {"interpolation1": dict(interpolation=1)},
}


def make_variant(cls, spec):
    if isinstance(spec, tuple):
        method, arg, kwargs = spec
        return getattr(cls, method)(arg, **kwargs)
    return cls(**spec)


def scheme_variants(*, explicit: bool | None = None) -> dict:
    """{id: scheme} for every registry scheme (id = its class name) and its VARIANTS (id = "Class-variant"),
    in registry order; ``explicit`` keeps only the explicit (True) or implicit (False) ones."""
    out = {}
    for key, cls in nvib.schemes().items():
        if explicit is not None and cls.is_explicit != explicit:
            continue
        out[cls.__name__] = cls()
        for vid, spec in VARIANTS.get(key, {}).items():
            out[f"{cls.__name__}-{vid}"] = make_variant(cls, spec)
    return out


def is_implicit(scheme) -> bool:
    return not type(scheme).is_explicit


def with_newton(scheme, **options):
    """The same scheme with its Newton options changed (``mode``, ``max_iter``, ``rtol``, ``atol``,
    ``jacobian``); an explicit scheme is returned as it is."""
    if not is_implicit(scheme):
        return scheme
    cls = type(scheme)
    kwargs = {p["name"]: getattr(scheme, p["name"]) for p in cls.parameters()}
    current = {p["name"]: getattr(scheme.newton, p["name"]) for p in nvib.Newton.parameters()}
    kwargs["newton"] = nvib.Newton(**{**current, **options})
    return cls(**kwargs)
