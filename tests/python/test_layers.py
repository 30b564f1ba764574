"""The C++ headers in layers (cpp/include/nvib/nvib.hpp): each folder includes only itself and the
folders above it, so that no include cycle can form and a newcomer finds each layer of the design
in a folder of its own."""

from __future__ import annotations

import os
import re

import pytest

ROOT = os.path.join(os.path.dirname(__file__), "..", "..", "cpp", "include", "nvib")
LAYERS = ["base", "linalg", "model", "effects", "newton", "schemes", "solve"]  # top to bottom


def headers():
    out = []
    for folder, _, files in os.walk(ROOT):
        out += [os.path.join(folder, f) for f in files if f.endswith(".hpp")]
    return sorted(out)


def layer_of(path: str) -> str:
    rel = os.path.relpath(os.path.normpath(path), os.path.normpath(ROOT))
    return rel.split(os.sep)[0]


def test_every_header_sits_in_a_layer():
    for h in headers():
        rel = os.path.relpath(h, ROOT)
        assert rel == "nvib.hpp" or layer_of(h) in LAYERS, f"{rel} is outside the layers {LAYERS}"


@pytest.mark.parametrize("header", headers(), ids=lambda h: os.path.relpath(h, ROOT))
def test_includes_go_up_the_layers(header):
    if os.path.relpath(header, ROOT) == "nvib.hpp":
        return
    mine = LAYERS.index(layer_of(header))
    with open(header, encoding="utf-8") as fh:
        for name in re.findall(r'^#include "([^"]+)"', fh.read(), flags=re.M):
            target = os.path.normpath(os.path.join(os.path.dirname(header), name))
            assert os.path.exists(target), f"{name} does not exist"
            theirs = LAYERS.index(layer_of(target))
            assert theirs <= mine, (f"{os.path.relpath(header, ROOT)} ({LAYERS[mine]}) includes {name} "
                                    f"({LAYERS[theirs]}), a layer below it")
