"""Argument checks shared by the public entry points: every error names the argument."""

from __future__ import annotations

import math
import numbers

import numpy as np


def real(name: str, x, *, positive: bool = False) -> float:
    if isinstance(x, bool) or not isinstance(x, numbers.Real):
        raise TypeError(f"{name}: expected a real number, got {type(x).__name__}")
    try:
        x = float(x)
    except OverflowError:  # an integer too large for a double
        raise ValueError(f"{name}: must be finite, got an integer too large for a double") from None
    if not math.isfinite(x):
        raise ValueError(f"{name}: must be finite, got {x}")
    if positive and x <= 0.0:
        raise ValueError(f"{name}: must be > 0, got {x}")
    return x


def integer(name: str, x, *, minimum: int | None = None) -> int:
    if isinstance(x, bool) or not isinstance(x, numbers.Integral):
        raise TypeError(f"{name}: expected an integer, got {type(x).__name__}")
    x = int(x)
    if minimum is not None and x < minimum:
        raise ValueError(f"{name}: must be >= {minimum}, got {x}")
    return x


def real_array(name: str, x) -> np.ndarray:
    """x as a float array; complex, boolean, string or object entries raise TypeError naming the argument
    (NumPy would drop an imaginary part with only a warning, or parse strings)."""
    try:
        a = np.asarray(x)
    except (TypeError, ValueError) as exc:  # a ragged nested list
        raise ValueError(f"{name}: expected a regular array of real numbers ({exc})") from None
    if a.dtype.kind in "iuf":
        return a.astype(float, copy=False)
    if a.dtype.kind == "O":
        try:
            return a.astype(float)
        except (TypeError, ValueError, OverflowError) as exc:
            raise TypeError(f"{name}: expected real numbers ({exc})") from None
    raise TypeError(f"{name}: expected real numbers, got an array of dtype {a.dtype}")


def vector(name: str, x, n: int) -> np.ndarray:
    a = real_array(name, x)
    if a.ndim == 0 and n == 1:
        a = a.reshape(1)
    if a.shape != (n,):
        raise ValueError(f"{name}: expected shape ({n},), got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name}: contains NaN or Inf")
    return np.ascontiguousarray(a)


def matrix(name: str, x, n: int) -> np.ndarray:
    a = real_array(name, x)
    if a.ndim == 0 and n == 1:
        a = a.reshape(1, 1)
    if a.shape != (n, n):
        raise ValueError(f"{name}: expected shape ({n}, {n}), got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name}: contains NaN or Inf")
    return np.ascontiguousarray(a)
