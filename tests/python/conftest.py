"""Fixtures shared by the tests: the scheme registry, as the C++ core declares it
(see _registry.py for the schemes and variants that "every scheme" tests run)."""

from __future__ import annotations

import pytest

import nvib


@pytest.fixture(params=list(nvib.schemes()))
def scheme_key(request) -> str:
    """Each command-line key of the registry (cpp/include/nvib/schemes/all.hpp), in order."""
    return request.param


@pytest.fixture
def scheme_class(scheme_key):
    """Each scheme class of the registry."""
    return nvib.schemes()[scheme_key]
