"""DOF names made on demand: a model of 10^6 DOFs need not hold 10^6 strings (about 100 bytes
each in Python and C++). A generated sequence behaves like the list of its names: indexing,
iteration, len, ``in``, ``index``, comparison with a list."""

from __future__ import annotations

import re
from collections.abc import Sequence


class GeneratedNames(Sequence):
    """Names ``name(k)`` for k = 0..n-1, with ``number(name)`` their inverse (None if not one of them)."""

    def __init__(self, n: int):
        self._n = int(n)

    def name(self, k: int) -> str:  # pragma: no cover - subclasses
        raise NotImplementedError

    def number(self, name: str) -> int | None:  # pragma: no cover - subclasses
        raise NotImplementedError

    def __len__(self) -> int:
        return self._n

    def __getitem__(self, k):
        if isinstance(k, slice):
            return [self.name(i) for i in range(*k.indices(self._n))]
        k = int(k)
        if k < 0:
            k += self._n
        if not 0 <= k < self._n:
            raise IndexError(f"DOF {k} is out of range for {self._n} DOFs")
        return self.name(k)

    def __contains__(self, name) -> bool:
        return isinstance(name, str) and self.number(name) is not None

    def index(self, name, start: int = 0, stop: int | None = None) -> int:
        k = self.number(name) if isinstance(name, str) else None
        if k is None or k < start or (stop is not None and k >= stop):
            raise ValueError(f"{name!r} is not a DOF name")
        return k

    def __eq__(self, other) -> bool:
        if isinstance(other, GeneratedNames):
            return type(self) is type(other) and self.__dict__ == other.__dict__
        if isinstance(other, (list, tuple)):
            return len(other) == self._n and all(a == b for a, b in zip(self, other))
        return NotImplemented

    def __hash__(self):
        return hash((type(self).__name__, tuple(sorted(self.__dict__.items()))))

    def __reduce__(self):
        return type(self), self._args()

    def _args(self) -> tuple:  # pragma: no cover - subclasses
        raise NotImplementedError


class NumberedNames(GeneratedNames):
    """prefix + str(start + k): u0, u1, ... or x1, x2, ..."""

    def __init__(self, prefix: str, n: int, start: int = 0):
        super().__init__(n)
        self.prefix, self.start = str(prefix), int(start)
        self._pattern = re.compile(re.escape(self.prefix) + r"(0|[1-9][0-9]*)\Z")

    def name(self, k: int) -> str:
        return f"{self.prefix}{self.start + k}"

    def number(self, name: str) -> int | None:
        m = self._pattern.match(name)
        if m is None:
            return None
        k = int(m.group(1)) - self.start
        return k if 0 <= k < self._n else None

    def _args(self) -> tuple:
        return self.prefix, self._n, self.start

    def __repr__(self) -> str:
        return f"NumberedNames({self.prefix!r}, {self._n}, start={self.start})"


class GridNames(GeneratedNames):
    """prefix + f"{ix}_{iy}" for node ix + nx iy of an nx x ny grid."""

    def __init__(self, prefix: str, nx: int, ny: int):
        super().__init__(int(nx) * int(ny))
        self.prefix, self.nx, self.ny = str(prefix), int(nx), int(ny)
        self._pattern = re.compile(re.escape(self.prefix) + r"(0|[1-9][0-9]*)_(0|[1-9][0-9]*)\Z")

    def name(self, k: int) -> str:
        return f"{self.prefix}{k % self.nx}_{k // self.nx}"

    def number(self, name: str) -> int | None:
        m = self._pattern.match(name)
        if m is None:
            return None
        ix, iy = int(m.group(1)), int(m.group(2))
        return ix + self.nx * iy if ix < self.nx and iy < self.ny else None

    def _args(self) -> tuple:
        return self.prefix, self.nx, self.ny

    def __repr__(self) -> str:
        return f"GridNames({self.prefix!r}, {self.nx}, {self.ny})"
