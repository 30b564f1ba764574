"""Compiled laws: a force law compiled elsewhere (a Numba ``cfunc``, a ``scipy.LowLevelCallable``, a ctypes
function pointer, or a bare address) is called from C++ like a built-in law, with the GIL released.

Its C signature (``LAW_SIGNATURE`` in Numba's notation)::

    int law(const double* params, const double* state, double d, double dd, double t,
            double* out, double* trial_state)

``params``: the effect's ``params`` (up to 8); ``state``: its committed internal variables (NULL without
memory); it writes f, df/dd and df/dd' to out[0..2] and, with memory, the internal variables after
(d, d', t) to ``trial_state``, changing nothing else, and returns 0 (anything else stops the run with an
error giving the code and the point). As an effect::

    {"type": "compiled", "measure": {...} (or "i"/"j" for an array), "law": f, "params": [k, fy],
     "state": [0.0, 0.0] (with memory: the initial internal variables, up to 8), "uses_time": False}

In an array each entry of ``params`` (and of ``state``) may be one value or one per effect.
"""

from __future__ import annotations

import ctypes

import numpy as np

from . import _checks

__all__ = ["LAW_SIGNATURE", "MAX_PARAMS", "MAX_STATE", "address_of", "lower"]

LAW_SIGNATURE = ("int32(CPointer(float64), CPointer(float64), float64, float64, float64, CPointer(float64), "
                 "CPointer(float64))")
MAX_PARAMS = 8
MAX_STATE = 8
_KEYS = ("type", "law", "params", "state", "uses_time", "measure", "i", "j", "name", "note")
_CTYPES_SIGNATURE = (ctypes.c_int, ctypes.POINTER(ctypes.c_double), ctypes.POINTER(ctypes.c_double), ctypes.c_double,
                     ctypes.c_double, ctypes.c_double, ctypes.POINTER(ctypes.c_double),
                     ctypes.POINTER(ctypes.c_double))


def address_of(where: str, law) -> int:
    """The address of a compiled law: a Numba cfunc (its signature checked), a scipy.LowLevelCallable, a
    ctypes function pointer or an int."""
    if isinstance(law, (int, np.integer)) and not isinstance(law, bool):
        address = int(law)
    elif hasattr(law, "address") and hasattr(law, "_sig"):  # numba.core.ccallback.CFunc
        from numba.core import sigutils  # a cfunc was made: Numba is there

        args, ret = sigutils.normalize_signature(LAW_SIGNATURE)
        if tuple(law._sig.args) != tuple(args) or law._sig.return_type != ret:
            raise _checks.type_error(where, f"the cfunc's signature is {law._sig}; a law needs "
                                            f"nvib.LAW_SIGNATURE = {LAW_SIGNATURE}")
        address = int(law.address)
    elif type(law).__name__ == "LowLevelCallable":
        capsule = law.function
        get_name = ctypes.pythonapi.PyCapsule_GetName
        get_name.restype, get_name.argtypes = ctypes.c_char_p, [ctypes.py_object]
        get_pointer = ctypes.pythonapi.PyCapsule_GetPointer
        get_pointer.restype, get_pointer.argtypes = ctypes.c_void_p, [ctypes.py_object, ctypes.c_char_p]
        address = int(get_pointer(capsule, get_name(capsule)) or 0)
    elif isinstance(law, ctypes._CFuncPtr):
        address = int(ctypes.cast(law, ctypes.c_void_p).value or 0)
    else:
        import importlib.util

        how = ("compile it with numba.cfunc(nvib.LAW_SIGNATURE)" if importlib.util.find_spec("numba") else
               'compile it with Numba (pip install "nvib[numba]"), numba.cfunc(nvib.LAW_SIGNATURE)')
        raise _checks.type_error(where, "expected a compiled function: a Numba cfunc of nvib.LAW_SIGNATURE, a "
                                        "scipy.LowLevelCallable, a ctypes function pointer or its address (an int); "
                                        f"got {type(law).__name__}: {how}, or give it as a 'callable' effect")
    if not 0 < address < 2 ** 53:
        raise _checks.value_error(where, f"not a function's address: {address}")
    return address


class _Recompiled:
    """A Numba cfunc on its way to another process: its Python function (pickled by value), compiled again
    there (a cfunc's machine code does not pickle)."""

    def __init__(self, pyfunc):
        self.pyfunc = pyfunc

    def __reduce__(self):
        import cloudpickle

        return (_recompile, (cloudpickle.dumps(self.pyfunc),))


def _recompile(payload: bytes):
    import pickle

    import numba

    return numba.cfunc(LAW_SIGNATURE)(pickle.loads(payload))


def travelling(effects):
    """The effects as they travel to another process: each compiled law a Numba cfunc gives as its Python
    function, compiled again there; one given by its address (a ctypes pointer, a LowLevelCallable, an int)
    refused, naming it (its code is in this process only)."""
    out = []
    for i, e in enumerate(effects or []):
        if isinstance(e, dict) and e.get("type") == "compiled" and "law" in e:
            law = e["law"]
            if hasattr(law, "_pyfunc") and hasattr(law, "_sig"):
                e = {**e, "law": _Recompiled(law._pyfunc)}
            else:
                raise _checks.type_error(f"effects[{i}].law", "a compiled law given by its address cannot go to "
                                                              "another process (its code is in this one): give "
                                                              "the Numba cfunc, compiled again there from its "
                                                              "Python function, or run on threads (threads=, "
                                                              "processes=False)")
        out.append(e)
    return out


def ctypes_law(fn):
    """A ctypes function pointer of the law's signature calling the Python function ``fn(params, state, d,
    dd, t, out, trial_state)`` (pointers as ctypes arrays): the contract without a compiler, to test a law
    (each call takes the GIL: slower than a Python law, not faster)."""
    return ctypes.CFUNCTYPE(*_CTYPES_SIGNATURE)(fn)


def lower(where: str, spec: dict) -> dict:
    """The built-in effect ("compiled" or "compiled_state") that runs the compiled law of ``spec``."""
    for key in spec:
        if key not in _KEYS:
            raise _checks.value_error(f"{where}.{key}", "unknown key of a compiled effect (expected "
                                                        f"{', '.join(k for k in _KEYS if k != 'type')})")
    if "law" not in spec:
        raise _checks.value_error(f"{where}.law", "missing: the compiled function (a Numba cfunc of "
                                                  "nvib.LAW_SIGNATURE, a LowLevelCallable, a ctypes pointer)")
    out = {k: spec[k] for k in ("measure", "i", "j", "name", "note") if k in spec}
    out["address"] = float(address_of(f"{where}.law", spec["law"]))
    uses_time = spec.get("uses_time", True)
    if not isinstance(uses_time, (bool, np.bool_)):
        raise _checks.type_error(f"{where}.uses_time", f"expected True or False, got {uses_time!r}")
    out["uses_time"] = 1.0 if uses_time else 0.0
    params = spec.get("params", [])
    if isinstance(params, (str, bytes, dict)) or not hasattr(params, "__len__"):
        raise _checks.type_error(f"{where}.params", "expected a list of parameters (each one value, or one per "
                                                    "effect of an array)")
    if len(params) > MAX_PARAMS:
        raise _checks.value_error(f"{where}.params", f"at most {MAX_PARAMS} parameters, got {len(params)}")
    for k, p in enumerate(params):
        out[f"p{k}"] = p
    state = spec.get("state")
    if state is None:
        out["type"] = "compiled"
        return out
    if isinstance(state, (str, bytes, dict)) or not hasattr(state, "__len__"):
        raise _checks.type_error(f"{where}.state", "expected the initial internal variables, a list")
    if not 1 <= len(state) <= MAX_STATE:
        raise _checks.value_error(f"{where}.state", f"expected 1 to {MAX_STATE} internal variables, got {len(state)}")
    out["type"] = "compiled_state"
    out["state_size"] = float(len(state))
    for k, s in enumerate(state):
        out[f"s{k}"] = s
    return out
