"""Argument checks shared by the public entry points: every error names the argument."""

from __future__ import annotations

import math
import numbers

import numpy as np


def real(name: str, x, *, positive: bool = False) -> float:
    if isinstance(x, bool) or not isinstance(x, numbers.Real):
        raise TypeError(f"{name}: expected a real number, got {type(x).__name__}")
    x = float(x)
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


def vector(name: str, x, n: int) -> np.ndarray:
    try:
        a = np.asarray(x, dtype=float)
    except (TypeError, ValueError) as exc:
        raise TypeError(f"{name}: expected an array of {n} real numbers ({exc})") from None
    if a.ndim == 0 and n == 1:
        a = a.reshape(1)
    if a.shape != (n,):
        raise ValueError(f"{name}: expected shape ({n},), got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name}: contains NaN or Inf")
    return np.ascontiguousarray(a)


def matrix(name: str, x, n: int) -> np.ndarray:
    try:
        a = np.asarray(x, dtype=float)
    except (TypeError, ValueError) as exc:
        raise TypeError(f"{name}: expected a ({n}, {n}) matrix of real numbers ({exc})") from None
    if a.ndim == 0 and n == 1:
        a = a.reshape(1, 1)
    if a.shape != (n, n):
        raise ValueError(f"{name}: expected shape ({n}, {n}), got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name}: contains NaN or Inf")
    return np.ascontiguousarray(a)
