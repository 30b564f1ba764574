"""Generated scenes for work at scale (the built-in TOML scenes sit beside this file).

``chain(n)``: a shear chain of n storeys, the paper's building (Yang et al.
2017, section 5.1) stretched to any height: storey masses, hardening storey
springs f = k0 (1 + a d^2) d and linear dampers on the drifts, a harmonic
ground acceleration. Its iteration matrix is tridiagonal.

``lattice(nx, ny)``: a 2-D mass-spring lattice, one out-of-plane DOF per
node, each node tied to its right and upper neighbours by a linear spring and
a cubic one and to the ground by a soft spring, with dampers on the ties, under
a ground acceleration. Its iteration matrix has bandwidth nx: a sparse
factorisation fills in, unlike the chain's.

Both are built from effect arrays (one entry per law), so 10^6 DOFs build in
about a second; DOF names are x1..xn (chain) and n<ix>_<iy> (lattice), made on demand
(nvib._names), not stored.
SI units: kg, N/m, N s/m, m/s^2.
"""

from __future__ import annotations

import math

import numpy as np

from .. import _checks
from .._model import Model
from .._names import GridNames, NumberedNames

__all__ = ["chain", "lattice"]


def _count(name: str, value, minimum: int = 1) -> int:
    return _checks.integer(name, value, minimum=minimum)


def _ground(amplitude: float, omega: float) -> dict:
    return {"type": "ground_acceleration", "name": "ground",
            "signal": {"kind": "sine", "amplitude": amplitude, "omega": omega}}


def chain(n: int, *, mass: float = 1e5, k0: float = 1e8, a: float = 10.0, damping_ratio: float = 0.02,
          ag_amplitude: float = 10.0, ag_omega: float = math.pi, t_end: float = 10.0, dt: float | None = None) -> Model:
    """A shear chain of n storeys under a_g = ag_amplitude sin(ag_omega t), from rest.

    Every storey has mass ``mass`` [kg], a hardening spring k0 (1 + a d^2) d [N] and a damper
    c = 2 damping_ratio sqrt(k0 mass) [N s/m] on its drift d (storey 1 against the ground). With the
    defaults n = 6 is the paper's building plus 2 % damping. ``model.scene`` holds t_end and dt
    (default: a fifth of the central-difference limit at the linear stiffness, 2 sqrt(m / (4 k0)))."""
    n = _count("n", n)
    for name, value in (("mass", mass), ("k0", k0)):
        _checks.real(name, value, positive=True)
    for name, value in (("a", a), ("damping_ratio", damping_ratio), ("ag_amplitude", ag_amplitude),
                        ("ag_omega", ag_omega)):
        _checks.real(name, value)
    c = 2.0 * damping_ratio * math.sqrt(k0 * mass)
    idx = np.arange(n, dtype=np.int32)
    effects = [
        {"type": "hardening_spring", "name": "storeys", "i": idx, "j": idx - 1, "k0": k0, "a": a},
        _ground(ag_amplitude, ag_omega),
    ]
    if c > 0.0:
        effects.insert(1, {"type": "damper", "name": "dampers", "i": idx, "j": idx - 1, "c": c})
    dt = 0.2 * math.sqrt(mass / k0) if dt is None else _checks.real("dt", dt, positive=True)
    t_end = _checks.real("t_end", t_end, positive=True)
    model = Model(np.full(n, float(mass)), effects=effects, dofs=NumberedNames("x", n, start=1), name=f"chain({n})")
    model.scene = _scene(f"chain({n})", f"Shear chain of {n} storeys, a_g = {ag_amplitude:g} sin({ag_omega:g} t)",
                         dt, t_end, "x1")
    return model


def lattice(nx: int, ny: int, *, mass: float = 1.0, k: float = 1e4, k3: float = 1e8, k_ground: float = 1e2,
            damping_ratio: float = 0.01, ag_amplitude: float = 1.0, ag_omega: float = 20.0, t_end: float = 1.0,
            dt: float | None = None) -> Model:
    """An nx x ny lattice: node (ix, iy) moves out of plane; ties to (ix+1, iy) and (ix, iy+1) are a linear
    spring k [N/m], a cubic spring k3 d^3 [N] and a damper c = 2 damping_ratio sqrt(k mass); every node
    has a ground spring k_ground; a_g = ag_amplitude sin(ag_omega t) on every node. DOF (ix, iy) is number
    ix + nx iy. ``model.scene`` holds t_end and dt (default: a fifth of 2 / omega_max at the linear
    stiffness, omega_max^2 = (8 k + k_ground) / mass)."""
    nx, ny = _count("nx", nx), _count("ny", ny)
    for name, value in (("mass", mass), ("k", k)):
        _checks.real(name, value, positive=True)
    for name, value in (("k3", k3), ("k_ground", k_ground), ("damping_ratio", damping_ratio),
                        ("ag_amplitude", ag_amplitude), ("ag_omega", ag_omega)):
        _checks.real(name, value)
    ix, iy = np.meshgrid(np.arange(nx), np.arange(ny), indexing="xy")
    node = (ix + nx * iy).astype(np.int32).ravel()
    right = node[(ix < nx - 1).ravel()]
    up = node[(iy < ny - 1).ravel()]
    i = np.concatenate([right, up]).astype(np.int32)
    j = np.concatenate([right + 1, up + nx]).astype(np.int32)
    c = 2.0 * damping_ratio * math.sqrt(k * mass)
    effects = [
        {"type": "spring", "name": "ties", "i": i, "j": j, "k": k},
        {"type": "cubic_spring", "name": "ties_cubic", "i": i, "j": j, "k3": k3},
        _ground(ag_amplitude, ag_omega),
    ]
    if k_ground > 0.0:
        effects.append({"type": "spring", "name": "ground_springs", "i": node, "k": k_ground})
    if c > 0.0:
        effects.append({"type": "damper", "name": "dampers", "i": i, "j": j, "c": c})
    n = nx * ny
    omega_max = math.sqrt((8.0 * k + max(k_ground, 0.0)) / mass)
    dt = 0.2 * 2.0 / omega_max if dt is None else _checks.real("dt", dt, positive=True)
    t_end = _checks.real("t_end", t_end, positive=True)
    model = Model(np.full(n, float(mass)), effects=effects, dofs=GridNames("n", nx, ny), name=f"lattice({nx}x{ny})")
    model.scene = _scene(f"lattice({nx}x{ny})", f"Mass-spring lattice {nx} x {ny}, cubic ties, "
                         f"a_g = {ag_amplitude:g} sin({ag_omega:g} t)", dt, t_end, model.dofs[n // 2])
    return model


def _scene(name: str, title: str, dt: float, t_end: float, plot_dof: str) -> dict:
    return {"name": name, "title": title, "source": "generated (nvib.scenes)", "dt": dt, "t_end": t_end,
            "plot_dof": plot_dof, "path": None, "initial_u": "given", "notes": []}
