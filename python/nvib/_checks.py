"""Argument checks shared by the public entry points: every error names the
argument, in its message ("dt: must be > 0, got -1") and in ``.argument``."""

from __future__ import annotations

import errno
import math
import numbers
import os
import stat

import numpy as np

from ._core import ArgumentError, ArgumentTypeError


def value_error(name: str, what: str) -> ArgumentError:
    """ArgumentError (a ValueError) "<name>: <what>" with .argument = name."""
    exc = ArgumentError(f"{name}: {what}")
    exc.argument, exc.reason = name, what
    return exc


def type_error(name: str, what: str) -> ArgumentTypeError:
    """ArgumentTypeError (a TypeError) "<name>: <what>" with .argument = name."""
    exc = ArgumentTypeError(f"{name}: {what}")
    exc.argument, exc.reason = name, what
    return exc


def suggestion(key: str, valid) -> str:
    """The words " (did you mean 'scale'?)" when a valid name is close to ``key`` (a misspelling), else ""."""
    import difflib

    close = difflib.get_close_matches(str(key), sorted(valid), n=1)
    return f" (did you mean {close[0]!r}?)" if close else ""


def unknown_keys(where: str, spec: dict, valid, what: str) -> None:
    """Refuse a key of ``spec`` that is not in ``valid``: ArgumentError naming "<where>.<key>", the close valid
    name if there is one, and the valid keys."""
    for key in spec:
        if key not in valid:
            raise value_error(f"{where}.{key}", f"unknown key for {what}{suggestion(key, valid)} (expected "
                                                f"{', '.join(sorted(valid))})")


def real(name: str, x, *, positive: bool = False) -> float:
    if isinstance(x, bool) or not isinstance(x, numbers.Real):
        raise type_error(name, f"expected a real number, got {type(x).__name__}")
    try:
        x = float(x)
    except OverflowError:  # an integer too large for a double
        raise value_error(name, "must be finite, got an integer too large for a double") from None
    if not math.isfinite(x):
        raise value_error(name, f"must be finite, got {x}")
    if positive and x <= 0.0:
        raise value_error(name, f"must be > 0, got {x}")
    return x


def number(name: str, x) -> float:
    """A real number converted to a float, its value unchecked: for the values the C++ core checks itself
    (a time step, a time), so that each check and its message live in one place."""
    if isinstance(x, bool) or not isinstance(x, numbers.Real):
        raise type_error(name, f"expected a real number, got {type(x).__name__}")
    try:
        return float(x)
    except OverflowError:  # an integer too large for a double
        raise value_error(name, "must be finite, got an integer too large for a double") from None


def integer(name: str, x, *, minimum: int | None = None, maximum: int | None = 2**63 - 1) -> int:
    """An integer (not a bool) in [minimum, maximum]; the default maximum is the C++ core's 64-bit limit
    (None: no bound, for callers that check their own range)."""
    if isinstance(x, bool) or not isinstance(x, numbers.Integral):
        raise type_error(name, f"expected an integer, got {type(x).__name__}")
    x = int(x)
    if minimum is not None and x < minimum:
        raise value_error(name, f"must be >= {minimum}, got {x}")
    if maximum is not None and x > maximum:
        raise value_error(name, f"must be <= {maximum}, got {x}")
    return x


def samples(t_name: str, y_name: str, t, y, *, nonfinite: str) -> tuple[np.ndarray, np.ndarray]:
    """Sample times (1-D, at least two, strictly increasing) and as many values, all finite (a table
    signal, a ground-motion record); ``nonfinite`` names the argument a NaN or Inf is blamed on."""
    t = real_array(t_name, t)
    y = real_array(y_name, y)
    if t.ndim != 1 or t.size < 2:
        raise value_error(t_name, "expected at least two sample times")
    if y.shape != t.shape:
        raise value_error(y_name, f"expected {t.size} values (as many as t), got shape {y.shape}")
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(y))):
        raise value_error(nonfinite, "the samples contain NaN or Inf")
    if np.any(np.diff(t) <= 0):
        raise value_error(t_name, "times must increase strictly")
    return t, y


def boolean(name: str, x) -> bool:
    """True or False only (a string such as "False" is not read as a truth value)."""
    if not isinstance(x, (bool, np.bool_)):
        raise type_error(name, f"expected True or False, got {x!r}")
    return bool(x)


def real_array(name: str, x) -> np.ndarray:
    """x as a float array; complex, boolean, string or object entries raise TypeError naming the argument
    (NumPy would drop an imaginary part with only a warning, or parse strings)."""
    try:
        a = np.asarray(x)
    except (TypeError, ValueError) as exc:  # a ragged nested list
        raise value_error(name, f"expected a regular array of real numbers ({exc})") from None
    if a.dtype.kind in "iuf":
        return a.astype(float, copy=False)
    if a.dtype.kind == "O":  # mixed entries: each must be a real number (not a string, a Decimal, a bool, None)
        for x in a.flat:
            if isinstance(x, (bool, np.bool_)) or not isinstance(x, numbers.Real):
                raise type_error(name, f"expected real numbers, got an entry {x!r} of type {type(x).__name__}")
        try:
            return a.astype(float)
        except (TypeError, ValueError, OverflowError) as exc:
            raise type_error(name, f"expected real numbers ({exc})") from None
    raise type_error(name, f"expected real numbers, got an array of dtype {a.dtype}")


def vector(name: str, x, n: int) -> np.ndarray:
    a = real_array(name, x)
    if a.ndim == 0 and n == 1:
        a = a.reshape(1)
    if a.shape != (n,):
        raise value_error(name, f"expected shape ({n},), got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise value_error(name, "contains NaN or Inf")
    return np.ascontiguousarray(a)


def matrix(name: str, x, n: int) -> np.ndarray:
    a = real_array(name, x)
    if a.ndim == 0 and n == 1:
        a = a.reshape(1, 1)
    if a.shape != (n, n):
        raise value_error(name, f"expected shape ({n}, {n}), got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise value_error(name, "contains NaN or Inf")
    return np.ascontiguousarray(a)


def is_sparse(x) -> bool:
    """A scipy.sparse matrix or array (scipy is imported only when one is given)."""
    return type(x).__module__.startswith("scipy.sparse")


def sparse_matrix(name: str, x, n: int | None = None):
    """x as a scipy.sparse CSC matrix of float64: square (n x n if n is given), finite."""
    from scipy import sparse

    if x.ndim != 2 or x.shape[0] != x.shape[1] or (n is not None and x.shape[0] != n):
        want = f"({n}, {n})" if n is not None else "a square matrix"
        raise value_error(name, f"expected shape {want}, got {x.shape}")
    if x.dtype.kind not in "iuf":
        raise type_error(name, f"expected real numbers, got a sparse matrix of dtype {x.dtype}")
    a = sparse.csc_matrix(x, dtype=float)
    a.sum_duplicates()
    if not np.all(np.isfinite(a.data)):
        raise value_error(name, "contains NaN or Inf")
    return a


def linear_part(name: str, x, n: int):
    """K or C: None (absent), a dense (n, n) array or a scipy.sparse matrix; a scipy.sparse CSC matrix for the
    core (None: an empty one)."""
    from scipy import sparse

    if x is None:
        return sparse.csc_matrix((0, 0))
    if is_sparse(x):
        return sparse_matrix(name, x, n)
    return sparse.csc_matrix(matrix(name, x, n))


def input_file_problem(path: str, kind: str, *, streams: bool = False) -> str | None:
    """Why ``path`` cannot be read as a ``kind`` ("record file"), or None when it can: missing, a symbolic
    link to nothing or a loop of them, a folder, a device (/dev/zero would be read for ever), or a pipe or
    socket unless ``streams`` (a record may come from a pipe, ``<(gunzip -c rec.txt.gz)``)."""
    try:
        st = os.stat(path)
    except FileNotFoundError:
        return f"a symbolic link to {os.readlink(path)!r}, which does not exist" if os.path.islink(path) \
            else "no such file"
    except OSError as exc:
        if exc.errno == errno.ELOOP:
            return "a loop of symbolic links"
        return f"cannot be read: {exc.strerror or exc}"
    if stat.S_ISDIR(st.st_mode):
        return f"is a folder, not a {kind}"
    if stat.S_ISCHR(st.st_mode) or stat.S_ISBLK(st.st_mode):
        return f"is a device, not a {kind}"
    if not stat.S_ISREG(st.st_mode) and not streams:
        return f"is a pipe or socket, not a {kind}"
    return None
