"""Generated finite-element models like the ones structural engineers bring (numpy and scipy only).

Each generator returns the stiffness K and the consistent mass M (scipy.sparse CSC, the supports
removed) and what a run needs; ``make(name)`` adds the rest and returns a ``Case``:

* Rayleigh damping C = alpha M + beta K of 2 % on modes 1 and 5 (``eigsh`` with sigma = 0);
* a ground acceleration a_g(t) = A sin(omega_1 t) along one direction, acting as P = -M r a_g;
* 4-8 hardening springs to ground, f = k0 (d + a d^3), on DOFs where they matter (the top of a wall,
  a block or a frame in the direction of the ground motion; the bearings of a rotor); k0 is a
  fraction of the stiffness of the structure there, 1 / (K^-1)_ii, and a = 1 / d0^2 with d0 the
  spring's displacement in the initial state, so that the cubic term equals the linear one at the
  start;
* an initial displacement u0: the static deflection under the ground motion's direction,
  K^-1 M r, scaled to a drift of about 1/200 of the height (a nonlinear state from the first step
  on, so that a short run measures the nonlinear iteration, not a linear start from rest), v0 = 0;
* omega_1 (the first circular frequency), omega_max of the model with its springs stiffened to
  twice the initial spring displacement (for the explicit step), and the ratios of its largest to
  smallest diagonal stiffness and mass (what makes round-off and convergence tests hard).

Models (``MODELS``): plane-stress walls of 4-node quadrilaterals (2 DOFs a node), 3-D blocks of
8-node hexahedra (3 DOFs a node), 3-D frame buildings of Euler-Bernoulli beam-columns (6 DOFs a
node, consistent beam mass plus the floor slabs' mass on the translations; one in mm-tonne-N units,
one with a penalty diaphragm) and slender rotors of beam elements on bearings, 800 to 15,000 DOFs,
and a 29,376-DOF hexahedral block.

    python benchmarks/fe_models.py            # lists the models and their properties (builds each)
"""

from __future__ import annotations

import argparse
import dataclasses
import itertools
import math
import sys
import time

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

# ---------------------------------------------------------------- elements

_G2 = np.array([-1.0, 1.0]) / np.sqrt(3.0)
_HEX = np.array([[-1, -1, -1], [1, -1, -1], [1, 1, -1], [-1, 1, -1],
                 [-1, -1, 1], [1, -1, 1], [1, 1, 1], [-1, 1, 1]], dtype=float)
_QUAD = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]], dtype=float)


def hexahedron(size, E: float, nu: float, rho: float) -> tuple[np.ndarray, np.ndarray]:
    """Stiffness and consistent mass (24 x 24) of a trilinear brick of edges ``size`` (2x2x2 Gauss,
    isotropic linear elasticity); DOFs (ux, uy, uz) of its 8 corners in ``_HEX`` order."""
    lam = E * nu / ((1 + nu) * (1 - 2 * nu))
    mu = E / (2 * (1 + nu))
    D = np.zeros((6, 6))
    D[:3, :3] = lam
    D[np.arange(3), np.arange(3)] += 2 * mu
    D[np.arange(3, 6), np.arange(3, 6)] = mu
    half = np.asarray(size, dtype=float) / 2
    det = float(np.prod(half))
    Ke, Me = np.zeros((24, 24)), np.zeros((24, 24))
    for p in itertools.product(_G2, _G2, _G2):
        p = np.asarray(p)
        N = np.prod(1 + _HEX * p, axis=1) / 8
        dN = np.empty((8, 3))
        for a in range(3):
            o = [b for b in range(3) if b != a]
            dN[:, a] = _HEX[:, a] * np.prod(1 + _HEX[:, o] * p[o], axis=1) / 8 / half[a]
        B = np.zeros((6, 24))
        for i in range(8):
            bx, by, bz = dN[i]
            B[:, 3 * i:3 * i + 3] = [[bx, 0, 0], [0, by, 0], [0, 0, bz], [by, bx, 0], [0, bz, by], [bz, 0, bx]]
        Ke += B.T @ D @ B * det
        Nm = np.kron(N, np.eye(3))
        Me += rho * Nm.T @ Nm * det
    return Ke, Me


def quadrilateral(size, E: float, nu: float, rho: float, thickness: float) -> tuple[np.ndarray, np.ndarray]:
    """Stiffness and consistent mass (8 x 8) of a bilinear plane-stress rectangle of edges ``size``
    (2x2 Gauss); DOFs (ux, uy) of its 4 corners counter-clockwise from (-1, -1)."""
    D = E / (1 - nu**2) * np.array([[1, nu, 0], [nu, 1, 0], [0, 0, (1 - nu) / 2]])
    half = np.asarray(size, dtype=float) / 2
    det = float(np.prod(half)) * thickness
    Ke, Me = np.zeros((8, 8)), np.zeros((8, 8))
    for p in itertools.product(_G2, _G2):
        p = np.asarray(p)
        N = np.prod(1 + _QUAD * p, axis=1) / 4
        dN = np.empty((4, 2))
        dN[:, 0] = _QUAD[:, 0] * (1 + _QUAD[:, 1] * p[1]) / 4 / half[0]
        dN[:, 1] = _QUAD[:, 1] * (1 + _QUAD[:, 0] * p[0]) / 4 / half[1]
        B = np.zeros((3, 8))
        for i in range(4):
            bx, by = dN[i]
            B[:, 2 * i:2 * i + 2] = [[bx, 0], [0, by], [by, bx]]
        Ke += B.T @ D @ B * det
        Nm = np.kron(N, np.eye(2))
        Me += rho * Nm.T @ Nm * det
    return Ke, Me


def beam(x1, x2, E: float, G: float, A: float, Iy: float, Iz: float, J: float, rho: float,
         up=(0.0, 0.0, 1.0), mass: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """Euler-Bernoulli 3-D beam-column from x1 to x2: stiffness and consistent mass (12 x 12) in
    global coordinates, DOFs (ux, uy, uz, rx, ry, rz) of each end. Local axes: e1 along the member,
    e2 = up x e1, e3 = e1 x e2 (for a horizontal member e3 is vertical; a vertical member takes
    up = global X). Iy bends in the e1-e3 plane (about e2), Iz in the e1-e2 plane. The mass is
    Przemieniecki's consistent one: translations (cubic Hermite), axial and torsional (linear, the
    polar inertia rho J), without the sections' rotary inertia in bending."""
    x1, x2 = np.asarray(x1, float), np.asarray(x2, float)
    e1 = x2 - x1
    L = float(np.linalg.norm(e1))
    e1 /= L
    up = np.asarray(up, float)
    if abs(e1 @ up) > 0.99:
        up = np.array([1.0, 0.0, 0.0])
    e2 = np.cross(up, e1)
    e2 /= np.linalg.norm(e2)
    e3 = np.cross(e1, e2)
    lam = np.vstack([e1, e2, e3])
    T = np.kron(np.eye(4), lam)

    def bending(EI):  # (w1, th1, w2, th2) with th = dw/dx
        return EI / L**3 * np.array([[12, 6 * L, -12, 6 * L], [6 * L, 4 * L**2, -6 * L, 2 * L**2],
                                     [-12, -6 * L, 12, -6 * L], [6 * L, 2 * L**2, -6 * L, 4 * L**2]])

    def bending_mass(m):
        return m * L / 420 * np.array([[156, 22 * L, 54, -13 * L], [22 * L, 4 * L**2, 13 * L, -3 * L**2],
                                       [54, 13 * L, 156, -22 * L], [-13 * L, -3 * L**2, -22 * L, 4 * L**2]])

    flip = np.diag([1.0, -1.0, 1.0, -1.0])  # in the e1-e3 plane the rotation about e2 is -dw/dx
    k, m = np.zeros((12, 12)), np.zeros((12, 12))
    ax, tor = [0, 6], [3, 9]
    k[np.ix_(ax, ax)] = E * A / L * np.array([[1, -1], [-1, 1]])
    k[np.ix_(tor, tor)] = G * J / L * np.array([[1, -1], [-1, 1]])
    yz, zy = [1, 5, 7, 11], [2, 4, 8, 10]
    k[np.ix_(yz, yz)] = bending(E * Iz)
    k[np.ix_(zy, zy)] = flip @ bending(E * Iy) @ flip
    if mass:
        m[np.ix_(ax, ax)] = rho * A * L / 6 * np.array([[2, 1], [1, 2]])
        m[np.ix_(tor, tor)] = rho * (Iy + Iz) * L / 6 * np.array([[2, 1], [1, 2]])
        m[np.ix_(yz, yz)] = bending_mass(rho * A)
        m[np.ix_(zy, zy)] = flip @ bending_mass(rho * A) @ flip
    return T.T @ k @ T, T.T @ m @ T


# ---------------------------------------------------------------- assembly

def _assemble(dofs: np.ndarray, Ke, Me, n: int) -> tuple[sp.csc_matrix, sp.csc_matrix]:
    """K, M from identical element matrices (Ke, Me) on the rows of ``dofs`` (elements x DOFs each)."""
    ne, nd = dofs.shape
    r = np.repeat(dofs, nd, axis=1).ravel()
    c = np.tile(dofs, (1, nd)).ravel()
    K = sp.csc_matrix((np.tile(Ke.ravel(), ne), (r, c)), shape=(n, n))
    M = sp.csc_matrix((np.tile(Me.ravel(), ne), (r, c)), shape=(n, n))
    return K, M


def _restrict(K, M, free):
    K = K[free][:, free]
    M = M[free][:, free]
    return ((K + K.T) / 2).tocsc(), ((M + M.T) / 2).tocsc()


def wall(nx: int, ny: int, width: float = 8.0, height: float = 24.0, thickness: float = 0.3,
         E: float = 3e10, nu: float = 0.2, rho: float = 2500.0):
    """A plane-stress concrete wall of nx x ny bilinear quadrilaterals, clamped at its base; 2 DOFs
    (ux, uy) a node, node (i, j) at x = i width / nx, y = j height / ny. Returns K, M, the free DOFs'
    (node, component) and the node coordinates."""
    Ke, Me = quadrilateral((width / nx, height / ny), E, nu, rho, thickness)
    node = np.arange((nx + 1) * (ny + 1)).reshape(ny + 1, nx + 1)
    j, i = np.meshgrid(np.arange(ny), np.arange(nx), indexing="ij")
    corners = np.stack([node[j, i], node[j, i + 1], node[j + 1, i + 1], node[j + 1, i]], axis=-1).reshape(-1, 4)
    dofs = (2 * corners[:, :, None] + np.arange(2)).reshape(-1, 8)
    n_all = 2 * node.size
    K, M = _assemble(dofs, Ke, Me, n_all)
    free = np.arange(2 * (nx + 1), n_all)
    K, M = _restrict(K, M, free)
    xy = np.stack(np.meshgrid(np.linspace(0, width, nx + 1), np.linspace(0, height, ny + 1)), -1).reshape(-1, 2)
    return K, M, free // 2, free % 2, xy


def block(nx: int, ny: int, nz: int, size=(1.0, 1.0, 1.0), E: float = 3e10, nu: float = 0.2, rho: float = 2500.0):
    """An nx x ny x nz block of bricks, the nodes at z = 0 clamped; 3 DOFs (ux, uy, uz) a node."""
    Ke, Me = hexahedron(size, E, nu, rho)
    node = np.arange((nx + 1) * (ny + 1) * (nz + 1)).reshape(nz + 1, ny + 1, nx + 1)
    k, j, i = np.meshgrid(np.arange(nz), np.arange(ny), np.arange(nx), indexing="ij")
    corners = np.stack([node[k, j, i], node[k, j, i + 1], node[k, j + 1, i + 1], node[k, j + 1, i],
                        node[k + 1, j, i], node[k + 1, j, i + 1], node[k + 1, j + 1, i + 1],
                        node[k + 1, j + 1, i]], axis=-1).reshape(-1, 8)
    dofs = (3 * corners[:, :, None] + np.arange(3)).reshape(-1, 24)
    n_all = 3 * node.size
    K, M = _assemble(dofs, Ke, Me, n_all)
    free = np.arange(3 * (nx + 1) * (ny + 1), n_all)
    K, M = _restrict(K, M, free)
    g = np.meshgrid(np.arange(nx + 1) * size[0], np.arange(ny + 1) * size[1], np.arange(nz + 1) * size[2],
                    indexing="ij")
    xyz = np.stack([a.transpose(2, 1, 0).ravel() for a in g], -1)
    return K, M, free // 3, free % 3, xyz


class _Beams:
    """Nodes and 6-DOF beam elements, assembled element by element."""

    def __init__(self):
        self.xyz: list = []
        self.key: dict = {}
        self.rows, self.cols, self.kv, self.mv = [], [], [], []
        self.lumped: dict = {}  # (node, component) -> added mass or rotary inertia

    def node(self, x) -> int:
        k = tuple(np.round(np.asarray(x, float), 9))
        if k not in self.key:
            self.key[k] = len(self.xyz)
            self.xyz.append(np.asarray(x, float))
        return self.key[k]

    def element(self, a: int, b: int, **section):
        Ke, Me = beam(self.xyz[a], self.xyz[b], **section)
        d = np.r_[6 * a + np.arange(6), 6 * b + np.arange(6)]
        self.rows.append(np.repeat(d, 12))
        self.cols.append(np.tile(d, 12))
        self.kv.append(Ke.ravel())
        self.mv.append(Me.ravel())

    def line(self, x1, x2, parts: int, **section) -> list[int]:
        """A member from x1 to x2 in ``parts`` elements; its node numbers."""
        x1, x2 = np.asarray(x1, float), np.asarray(x2, float)
        nodes = [self.node(x1 + (x2 - x1) * s / parts) for s in range(parts + 1)]
        for a, b in zip(nodes[:-1], nodes[1:]):
            self.element(a, b, **section)
        return nodes

    def add_mass(self, node: int, comp: int, value: float):
        self.lumped[(node, comp)] = self.lumped.get((node, comp), 0.0) + value

    def matrices(self):
        n = 6 * len(self.xyz)
        r, c = np.concatenate(self.rows), np.concatenate(self.cols)
        K = sp.csc_matrix((np.concatenate(self.kv), (r, c)), shape=(n, n))
        M = sp.csc_matrix((np.concatenate(self.mv), (r, c)), shape=(n, n))
        if self.lumped:
            idx = np.array([6 * a + b for a, b in self.lumped])
            M = M + sp.csc_matrix((np.array(list(self.lumped.values())), (idx, idx)), shape=(n, n))
        return K, M


def _rect(b: float, h: float) -> dict:
    """Section of a b x h rectangle (h along e3): A, Iy (about e2, strong for h > b), Iz, J (Saint-Venant)."""
    lo, hi = min(b, h), max(b, h)
    J = lo**3 * hi * (1 / 3 - 0.21 * lo / hi * (1 - lo**4 / (12 * hi**4)))
    return dict(A=b * h, Iy=b * h**3 / 12, Iz=h * b**3 / 12, J=J)


def frame(bays_x: int, bays_y: int, storeys: int, bay: float = 6.0, storey: float = 3.5, col_parts: int = 1,
          beam_parts: int = 2, slab: float = 700.0, E: float = 3e10, nu: float = 0.2, rho: float = 2500.0,
          diaphragm_penalty: float = 0.0):
    """A 3-D reinforced-concrete frame building: columns (0.6 x 0.6 m at the bottom third, 0.5 x 0.5 m
    above) on a bays_x x bays_y grid, clamped at the ground, floors of beams (0.3 x 0.6 m) in both
    directions, each column in ``col_parts`` and each beam in ``beam_parts`` elements; 6 DOFs a node.
    The floor slabs' mass (``slab`` kg/m^2) is added to the three translations of the floor's grid
    nodes (their tributary areas), none to their rotations: a floor node's translational mass is
    10^4 kg while a rotation's inertia is that of the beam and column elements alone (10 to 10^3
    kg m^2), and its axial column stiffness (EA/L ~ 3e9 N/m) is 10^2 times its bending stiffness.
    ``diaphragm_penalty`` > 0 adds the rigid diaphragm as engineers often do by penalty: massless
    diagonal bars in every bay of every floor, axial stiffness that factor times a beam's.
    SI units (m, kg, s, N). Returns K, M, the free DOFs' (node, component), the node coordinates."""
    G = E / (2 * (1 + nu))
    fb = _Beams()
    col_low, col_high, bm = _rect(0.6, 0.6), _rect(0.5, 0.5), _rect(0.3, 0.6)
    grid = {}
    for i, j, k in itertools.product(range(bays_x + 1), range(bays_y + 1), range(storeys + 1)):
        grid[i, j, k] = fb.node((i * bay, j * bay, k * storey))
    for i, j, k in itertools.product(range(bays_x + 1), range(bays_y + 1), range(storeys)):
        sec = col_low if k < max(1, storeys // 3) else col_high
        fb.line(fb.xyz[grid[i, j, k]], fb.xyz[grid[i, j, k + 1]], col_parts, E=E, G=G, rho=rho, **sec)
    for k in range(1, storeys + 1):
        for i, j in itertools.product(range(bays_x), range(bays_y + 1)):
            fb.line(fb.xyz[grid[i, j, k]], fb.xyz[grid[i + 1, j, k]], beam_parts, E=E, G=G, rho=rho, **bm)
        for i, j in itertools.product(range(bays_x + 1), range(bays_y)):
            fb.line(fb.xyz[grid[i, j, k]], fb.xyz[grid[i, j + 1, k]], beam_parts, E=E, G=G, rho=rho, **bm)
        for i, j in itertools.product(range(bays_x + 1), range(bays_y + 1)):
            area = bay * bay * (1.0 if 0 < i < bays_x else 0.5) * (1.0 if 0 < j < bays_y else 0.5)
            for comp in range(3):
                fb.add_mass(grid[i, j, k], comp, slab * area)
        if diaphragm_penalty > 0:
            bar = dict(E=E * diaphragm_penalty, G=G, rho=0.0, A=bm["A"], Iy=1e-12, Iz=1e-12, J=1e-12, mass=False)
            for i, j in itertools.product(range(bays_x), range(bays_y)):
                fb.element(grid[i, j, k], grid[i + 1, j + 1, k], **bar)
                fb.element(grid[i + 1, j, k], grid[i, j + 1, k], **bar)
    K, M = fb.matrices()
    xyz = np.array(fb.xyz)
    ground = np.flatnonzero(np.abs(xyz[:, 2]) < 1e-9)
    fixed = (6 * ground[:, None] + np.arange(6)).ravel()
    free = np.setdiff1d(np.arange(K.shape[0]), fixed)
    K, M = _restrict(K, M, free)
    return K, M, free // 6, free % 6, xyz


def to_mm(K, M, comp):
    """The same model in the units of many exported models, mm, tonne, s, N (N mm for moments):
    u' = 1000 u on translations, K' = 1e3 S K S and M' = 1e3 S M S with S = diag(1e-3 on
    translations, 1 on rotations): translational stiffness / 1000, rotational x 1000, translational
    mass / 1000 (kg -> t), rotary inertia x 1000 (kg m^2 -> t mm^2)."""
    s = np.where(comp < 3, 1e-3, 1.0)
    S = sp.diags(s)
    return (1e3 * S @ K @ S).tocsc(), (1e3 * S @ M @ S).tocsc()


def rotor(elements: int, length: float = 8.0, E: float = 2.1e11, nu: float = 0.3, rho: float = 7850.0,
          bearing_k: float = 5e8):
    """A slender stepped steel rotor along x of ``elements`` beam elements (6 DOFs a node), 0.20 m in
    diameter with a 0.30 m middle third, carrying three disks (600 kg, polar inertia 60 kg m^2,
    diametral 30 kg m^2, lumped at their nodes) on four bearings (springs of ``bearing_k`` N/m to
    ground laterally, y and z), with an axial thrust spring at the first bearing and a torsional
    spring (the coupling) at the drive end. Fine elements (length / elements; 6 to 32 mm in ``MODELS``):
    a rotation's diagonal stiffness and inertia are 10^-4 to 10^-6 of a translation's (measured in
    fe_newton.py's models table), the disks' inertias sit among them, and omega_max / omega_1 reaches
    10^5 to 10^6: the hard case of beam models. Returns K, M, the free DOFs' (node, component),
    the node coordinates and the bearing nodes."""
    G = E / (2 * (1 + nu))
    fb = _Beams()
    xs = np.linspace(0.0, length, elements + 1)
    nodes = [fb.node((x, 0.0, 0.0)) for x in xs]
    for a, b in zip(nodes[:-1], nodes[1:]):
        xm = 0.5 * (xs[a] + xs[b])
        d = 0.30 if length / 3 <= xm <= 2 * length / 3 else 0.20
        A, I = math.pi * d**2 / 4, math.pi * d**4 / 64
        fb.element(a, b, E=E, G=G, rho=rho, A=A, Iy=I, Iz=I, J=2 * I)
    for frac in (0.25, 0.5, 0.75):
        k = nodes[int(round(frac * elements))]
        for comp, value in ((0, 600.0), (1, 600.0), (2, 600.0), (3, 60.0), (4, 30.0), (5, 30.0)):
            fb.add_mass(k, comp, value)
    K, M = fb.matrices()
    n = K.shape[0]
    bearings = [nodes[int(round(f * elements))] for f in (0.04, 0.36, 0.64, 0.96)]
    extra = {}
    for b in bearings:
        extra[6 * b + 1] = extra[6 * b + 2] = bearing_k
    extra[6 * bearings[0]] = bearing_k  # thrust
    extra[6 * nodes[0] + 3] = 1e7  # coupling, N m / rad
    idx = np.array(list(extra))
    K = (K + sp.csc_matrix((np.array(list(extra.values())), (idx, idx)), shape=(n, n))).tocsc()
    K, M = ((K + K.T) / 2).tocsc(), ((M + M.T) / 2).tocsc()
    free = np.arange(n)
    return K, M, free // 6, free % 6, np.array(fb.xyz), bearings


# ---------------------------------------------------------------- cases

@dataclasses.dataclass
class Case:
    name: str
    kind: str
    hard: str                 # what makes it hard, in words
    K: sp.csc_matrix
    M: sp.csc_matrix
    C: sp.csc_matrix
    node: np.ndarray          # each DOF's node
    comp: np.ndarray          # each DOF's component (0-2 translations, 3-5 rotations)
    r: np.ndarray             # influence vector of the ground motion (1 on its direction's translations)
    springs: np.ndarray       # DOFs of the hardening springs to ground
    k0: np.ndarray
    a: np.ndarray
    u0: np.ndarray
    v0: np.ndarray
    omega: np.ndarray         # the lowest five circular frequencies of the linear model [rad/s]
    omega_max: float          # highest, springs stiffened to 2 d0 (for the explicit step)
    ground_amplitude: float   # A of a_g = A sin(omega_1 t)
    units: str
    build_time: float = 0.0
    alpha: float = 0.0        # C = alpha M + beta K
    beta: float = 0.0

    @property
    def n(self) -> int:
        return self.K.shape[0]

    @property
    def omega1(self) -> float:
        return float(self.omega[0])

    @property
    def T1(self) -> float:
        return 2 * math.pi / self.omega1

    @property
    def rayleigh(self) -> tuple[float, float]:
        return rayleigh_coefficients(0.02, self.omega[0], self.omega[4])

    def ground(self, t):
        return self.ground_amplitude * np.sin(self.omega1 * np.asarray(t, float))

    def explicit_dt(self, safety: float = 0.8) -> float:
        """``safety`` times the central-difference limit at omega_max with its Rayleigh damping
        ratio xi: 2 (sqrt(1 + 4 xi^2) - 2 xi) / omega_max (the damping force takes the predicted
        velocity v + dt a; stiffness-proportional damping makes the top mode heavily damped and
        shrinks the limit, to about 1 / (2 xi omega_max))."""
        al, be = self.rayleigh
        w = self.omega_max
        xi = al / (2 * w) + be * w / 2
        return safety * 2 / (w * (math.hypot(1.0, 2 * xi) + 2 * xi))

    def diagonal_ratios(self) -> tuple[float, float]:
        """max / min of the diagonal of K and of M (the spread of the DOFs' scales)."""
        k, m = np.abs(self.K.diagonal()), np.abs(self.M.diagonal())
        return float(k.max() / k.min()), float(m.max() / m.min())


def factorize(A):
    """A sparse LU of a symmetric positive definite matrix the way that suits it in SciPy: SuperLU in
    symmetric mode, minimum degree on A^T + A, no pivoting (splu's defaults, COLAMD with partial
    pivoting, fill a 15,840-DOF frame's factors to 25x the nonzeros and take 200x as long)."""
    return spla.splu(A.tocsc(), permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                     options=dict(SymmetricMode=True))


def rayleigh_coefficients(zeta: float, w1: float, w2: float) -> tuple[float, float]:
    return 2 * zeta * w1 * w2 / (w1 + w2), 2 * zeta / (w1 + w2)


def _finish(name, kind, hard, K, M, node, comp, direction, spring_dofs, drift_height, units="m",
            k_fraction=0.5, length_scale=1.0) -> Case:
    n = K.shape[0]
    lu = factorize(K)
    OPinv = spla.LinearOperator((n, n), matvec=lu.solve, dtype=float)
    # ARPACK from a fixed start vector: without one it starts from a random vector, and the frequencies, the
    # damping, u0 and the explicit step of a model moved in their last digits from one make() to the next
    # (two runs of one build on "the same" model then differed by up to 1e-5 after 300 explicit steps)
    start = np.random.default_rng(20261208).standard_normal(n)
    w2 = spla.eigsh(K, k=5, M=M, sigma=0, which="LM", OPinv=OPinv, return_eigenvectors=False, v0=start)
    omega = np.sqrt(np.sort(np.abs(w2)))
    al, be = rayleigh_coefficients(0.02, omega[0], omega[4])
    C = (al * M + be * K).tocsc()
    r = np.zeros(n)
    for c, weight in (direction.items() if isinstance(direction, dict) else [(direction, 1.0)]):
        r[comp == c] = weight
    static = lu.solve(M @ r)
    trans = comp < 3
    u0 = static * (drift_height / 200.0 * length_scale / np.max(np.abs(static[trans])))
    springs = np.asarray(spring_dofs, dtype=int)
    flex = np.array([lu.solve(np.eye(1, n, int(i)).ravel())[int(i)] for i in springs])
    k0 = k_fraction / flex
    d0 = np.abs(u0[springs])
    a = 1.0 / d0**2
    # the top of the spectrum with the springs stiffened to twice their initial displacement
    Kt = (K + sp.csc_matrix((k0 * (1 + 3 * a * (2 * d0) ** 2), (springs, springs)), shape=(n, n))).tocsc()
    Mlu = factorize(M)
    op = spla.LinearOperator((n, n), matvec=lambda x: Mlu.solve(Kt @ x), dtype=float)
    w_top = spla.eigs(op, k=1, which="LM", return_eigenvectors=False, tol=1e-4, maxiter=20000, v0=start)
    omega_max = 1.01 * math.sqrt(abs(complex(w_top[0])))  # the margin covers the tolerance
    A = 0.1 * np.max(np.abs(u0)) / np.max(np.abs(static)) * 1.0
    return Case(name, kind, hard, K.tocsc(), M.tocsc(), C, node, comp, r, springs, k0, a, u0, np.zeros(n),
                omega, omega_max, float(A), units, alpha=al, beta=be)


def _wall(nx, ny):
    K, M, node, comp, xy = wall(nx, ny)
    top = np.flatnonzero((node >= ny * (nx + 1)) & (comp == 0))
    springs = top[np.linspace(0, top.size - 1, 4).round().astype(int)]
    return _finish(f"wall {nx}x{ny}", "plane-stress wall, Q4",
                   f"8 x 24 m wall, 0.3 m thick, {8 / nx:.2g} x {24 / ny:.2g} m elements (aspect "
                   f"{max(8 / nx, 24 / ny) / min(8 / nx, 24 / ny):.2g}); 4 springs on the top's x DOFs",
                   K, M, node, comp, 0, springs, 24.0)


def _block(nx, ny, nz, size=(1.0, 1.0, 1.0), label=None):
    K, M, node, comp, xyz = block(nx, ny, nz, size)
    top_nodes = np.arange(nz * (ny + 1) * (nx + 1), (nz + 1) * (ny + 1) * (nx + 1))
    top = np.flatnonzero(np.isin(node, top_nodes) & (comp == 0))
    springs = top[np.linspace(0, top.size - 1, 6).round().astype(int)]
    dims = f"{nx * size[0]:g} x {ny * size[1]:g} x {nz * size[2]:g} m"
    aspect = max(size) / min(size)
    return _finish(label or f"block {nx}x{ny}x{nz}", "3-D block, H8",
                   f"{dims}, bricks {size[0]:g} x {size[1]:g} x {size[2]:g} m (aspect {aspect:g}); a 3-D mesh's "
                   "factors fill in (the cost of every factorisation); 6 springs on the top's x DOFs",
                   K, M, node, comp, 0, springs, nz * size[2])


def _rotation_ratios(case: Case) -> str:
    """The spread between rotations and translations of a beam model, measured: median diagonal
    stiffness and mass of the rotations over those of the translations."""
    rot, tr = case.comp >= 3, case.comp < 3
    k, m = np.abs(case.K.diagonal()), np.abs(case.M.diagonal())
    return (f"rotation / translation median diagonal: stiffness {np.median(k[rot]) / np.median(k[tr]):.1e}, "
            f"mass {np.median(m[rot]) / np.median(m[tr]):.1e}")


def case_to_mm(case: Case) -> Case:
    """The same case in mm, tonne, s, N (``to_mm``): the state, the springs on translations and the
    ground acceleration scaled with it; the frequencies are the same."""
    K, M = to_mm(case.K, case.M, case.comp)
    C = to_mm(case.C, case.M, case.comp)[0]
    s = np.where(case.comp < 3, 1e3, 1.0)  # u' = s u
    sk = s[case.springs]
    return dataclasses.replace(case, K=K, M=M, C=C, u0=case.u0 * s, v0=case.v0 * s, k0=case.k0 / sk,
                               a=case.a / sk**2, ground_amplitude=case.ground_amplitude * 1e3, units="mm")


def _frame(bx, by, s, units="m", penalty=0.0, col_parts=1, beam_parts=2, label=None):
    K, M, node, comp, xyz = frame(bx, by, s, col_parts=col_parts, beam_parts=beam_parts, diaphragm_penalty=penalty)
    height = s * 3.5
    width_x, width_y = bx * 6.0, by * 6.0

    def corners(z):
        level = np.flatnonzero(np.abs(xyz[:, 2] - z) < 1e-9)
        return [i for i in level if xyz[i, 0] in (0.0, width_x) and xyz[i, 1] in (0.0, width_y)]

    x_dof = {int(node[d]): d for d in np.flatnonzero(comp == 0)}
    springs = [x_dof[int(i)] for i in corners(height) + corners(3.5 * (s // 2))[:2]]
    hard = (f"{bx} x {by} bays, {s} storeys, columns in {col_parts} and beams in {beam_parts} elements, "
            "slab mass on the translations only")
    if penalty:
        hard += f", penalty diaphragm (bars of {penalty:g} x a beam's EA)"
    case = _finish("", "3-D frame, beams", "", K, M, node, comp, 0, springs, height)
    if units == "mm":
        case = case_to_mm(case)
        hard += ", in mm, t, N"
    case.name = label or f"frame {bx}x{by}x{s}" + (" mm" if units == "mm" else "") + (" diaphragm" if penalty else "")
    case.hard = hard + "; " + _rotation_ratios(case) + "; 6 springs on x at the roof and mid-height corners"
    return case


def _rotor(elements):
    K, M, node, comp, xyz, bearings = rotor(elements)
    springs = []
    for b in bearings:
        springs += [6 * b + 1, 6 * b + 2]
    case = _finish(f"rotor {elements}", "rotor, beams on bearings", "", K, M, node, comp, {1: 1.0, 2: 0.6},
                   springs, 0.2, k_fraction=0.3)
    case.hard = (f"8 m stepped shaft in {elements} elements ({8000 / elements:.2g} mm), 3 disks, 4 bearings; "
                 + _rotation_ratios(case) + "; 8 hardening springs at the bearings (y, z); ground motion along "
                 "y and 0.6 of it along z")
    return case


MODELS = {
    "wall 20x20": lambda: _wall(20, 20),
    "wall 40x60": lambda: _wall(40, 60),
    "wall 60x120": lambda: _wall(60, 120),
    "column 2x2x40": lambda: _block(2, 2, 40, (0.2, 0.2, 1.0), "column 2x2x40"),
    "block 8x8x10": lambda: _block(8, 8, 10),
    "block 12x12x12": lambda: _block(12, 12, 12),
    "block 16x16x16": lambda: _block(16, 16, 16),
    "frame 3x3x8": lambda: _frame(3, 3, 8, beam_parts=1),
    "frame 4x4x12": lambda: _frame(4, 4, 12),
    "frame 4x4x12 diaphragm": lambda: _frame(4, 4, 12, penalty=1e3),
    "frame 5x5x20 mm": lambda: _frame(5, 5, 20, units="mm", col_parts=2),
    "rotor 250": lambda: _rotor(250),
    "rotor 1315": lambda: _rotor(1315),
    "block 23x23x17": lambda: _block(23, 23, 17),
}
"""Every model by name: a dozen from 800 to 15,000 DOFs and a 29,376-DOF block."""

QUICK = ["wall 20x20", "column 2x2x40", "frame 3x3x8", "rotor 250"]


def make(name: str) -> Case:
    t0 = time.perf_counter()
    case = MODELS[name]()
    case.build_time = time.perf_counter() - t0
    return case


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("models", nargs="*", help="model names (default: all); see the list with --list")
    ap.add_argument("--list", action="store_true", help="list the model names and exit")
    args = ap.parse_args(argv)
    if args.list:
        print("\n".join(MODELS))
        return 0
    names = args.models or list(MODELS)
    print("| model | DOFs | nnz(K) | T1 [s] | omega_max/omega_1 | diag K max/min | diag M max/min | build [s] |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|")
    for name in names:
        c = make(name)
        kr, mr = c.diagonal_ratios()
        print(f"| {name} | {c.n} | {c.K.nnz} | {c.T1:.4g} | {c.omega_max / c.omega1:.3g} | {kr:.2g} | {mr:.2g} | "
              f"{c.build_time:.2f} |", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
