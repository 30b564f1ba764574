"""Sparse symmetric factorisation of the iteration matrix S = K + (4/dt^2) M + (2/dt) C of finite-element
models: nvib's supernodal Cholesky (``SupernodalCholesky<false>`` LL^T and ``<true>`` LDL^T,
cpp/include/nvib/linalg/supernodal_cholesky.hpp) against nvib's simplicial ``OrderedCholesky`` (AMD,
then Eigen's simplicial LDL^T / LL^T) and SciPy's ``splu`` (SuperLU, default options).

Models (assembled here with scipy.sparse; the 3-D block is tests/python/_fe_mesh.py's, copied):
  * 3-D elastic blocks of trilinear hexahedra (8 nodes, 2 x 2 x 2 Gauss points, E = 3e10, nu = 0.2,
    rho = 2500, 1 m bricks, 3 DOFs a node, clamped at z = 0, consistent mass): block(6, 6, 6)
    (882 DOFs), block(16, 16, 12) (10,404) and block(23, 23, 17) (29,376, the case of the issue);
  * 2-D plane-stress squares of bilinear quadrilaterals (4 nodes, 2 x 2 Gauss points, same
    material, thickness 1, 2 DOFs a node, clamped at y = 0, consistent mass): 22 x 22 (1,012 DOFs),
    70 x 70 (9,940), 223 x 223 (99,904);
  * a chain of 10^5 two-node bars (axial, consistent mass), clamped at one end (tridiagonal S).
S = K + (4/dt^2) M + (2/dt) C, the matrix Newmark's trapezoidal rule (and Newton on it) factorises,
with C Rayleigh damping of 2 % on modes 1 and 3 and dt = T1 / 50 (the first three modes from
scipy.sparse.linalg.eigsh, shift-invert).

Each matrix goes to the C++ program benchmarks/cpp/factorize.cpp as a Matrix Market file (its lower
triangle), built with nvib's Release flags (-std=c++17 -O3 -DNDEBUG, no -march=native). Times are the
best over --repeats runs (the machine is shared and timings are noisy), of analyse, factorise and one
solve (best of 5 per run); a simplicial factorisation over --budget seconds is run once. SciPy:
splu(S) (the factorisation, its ordering included) and one solve, best of the same repeats.
"factor + 20 solves" = factorise + 20 x solve (plus analyse for nvib: a new S each time, as SciPy's).
GFlop/s = the flop count of the numeric factorisation (sum over L's stored columns of entries^2,
the supernodal one counting its explicit zeros) / factorise time.

    python benchmarks/factorize.py [--repeats 3] [--quick] [--out benchmarks/results/factorize.md]
"""

from __future__ import annotations

import argparse
import datetime
import itertools
import json
import os
import platform
import shutil
import subprocess
import sys
import tempfile
import time

import numpy as np
import scipy
import scipy.io
import scipy.sparse as sp
import scipy.sparse.linalg as spla

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
CXXFLAGS = ["-std=c++17", "-O3", "-DNDEBUG"]
SOLVES = 20
E, NU, RHO = 3e10, 0.2, 2500.0


# ---- models ------------------------------------------------------------------------------------
_G = np.array([-1.0, 1.0]) / np.sqrt(3.0)
_HEX = np.array([[-1, -1, -1], [1, -1, -1], [1, 1, -1], [-1, 1, -1],
                 [-1, -1, 1], [1, -1, 1], [1, 1, 1], [-1, 1, 1]], dtype=float)
_QUAD = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]], dtype=float)


def hexahedron(size=(1.0, 1.0, 1.0), E=E, nu=NU, rho=RHO):
    """Stiffness and consistent mass (24 x 24) of a trilinear brick (as tests/python/_fe_mesh.py)."""
    lam, mu = E * nu / ((1 + nu) * (1 - 2 * nu)), E / (2 * (1 + nu))
    D = np.zeros((6, 6))
    D[:3, :3] = lam
    D[np.arange(3), np.arange(3)] += 2 * mu
    D[np.arange(3, 6), np.arange(3, 6)] = mu
    half = np.asarray(size, dtype=float) / 2
    det = float(np.prod(half))
    Ke, Me = np.zeros((24, 24)), np.zeros((24, 24))
    for xi, eta, zeta in itertools.product(_G, _G, _G):
        p = np.array([xi, eta, zeta])
        N = np.prod(1 + _HEX * p, axis=1) / 8
        dN = np.empty((8, 3))
        for a in range(3):
            others = [b for b in range(3) if b != a]
            dN[:, a] = _HEX[:, a] * np.prod(1 + _HEX[:, others] * p[others], axis=1) / 8 / half[a]
        B = np.zeros((6, 24))
        for i in range(8):
            bx, by, bz = dN[i]
            B[:, 3 * i:3 * i + 3] = [[bx, 0, 0], [0, by, 0], [0, 0, bz], [by, bx, 0], [0, bz, by], [bz, 0, bx]]
        Ke += B.T @ D @ B * det
        Nm = np.kron(N, np.eye(3))
        Me += rho * Nm.T @ Nm * det
    return Ke, Me


def quadrilateral(size=(1.0, 1.0), E=E, nu=NU, rho=RHO):
    """Plane-stress stiffness and consistent mass (8 x 8) of a bilinear square, thickness 1."""
    D = E / (1 - nu**2) * np.array([[1, nu, 0], [nu, 1, 0], [0, 0, (1 - nu) / 2]])
    half = np.asarray(size, dtype=float) / 2
    det = float(np.prod(half))
    Ke, Me = np.zeros((8, 8)), np.zeros((8, 8))
    for xi, eta in itertools.product(_G, _G):
        p = np.array([xi, eta])
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


def assemble(elements: np.ndarray, Ke: np.ndarray, Me: np.ndarray, n_all: int, free: np.ndarray):
    """K, M (CSC) from each element's DOF list, restricted to the free DOFs."""
    ne, k = elements.shape
    r = np.repeat(elements, k, axis=1).ravel()
    c = np.tile(elements, (1, k)).ravel()
    K = sp.csc_matrix((np.tile(Ke.ravel(), ne), (r, c)), shape=(n_all, n_all))
    M = sp.csc_matrix((np.tile(Me.ravel(), ne), (r, c)), shape=(n_all, n_all))
    K, M = K[free][:, free], M[free][:, free]
    return ((K + K.T) / 2).tocsc(), ((M + M.T) / 2).tocsc()


def block(nx: int, ny: int, nz: int):
    """K, M of an nx x ny x nz block of bricks, the nodes at z = 0 clamped (tests/python/_fe_mesh.py)."""
    Ke, Me = hexahedron()
    node = np.arange((nx + 1) * (ny + 1) * (nz + 1)).reshape(nz + 1, ny + 1, nx + 1)
    k, j, i = (a.ravel() for a in np.meshgrid(np.arange(nz), np.arange(ny), np.arange(nx), indexing="ij"))
    corners = np.stack([node[k, j, i], node[k, j, i + 1], node[k, j + 1, i + 1], node[k, j + 1, i],
                        node[k + 1, j, i], node[k + 1, j, i + 1], node[k + 1, j + 1, i + 1], node[k + 1, j + 1, i]], 1)
    dofs = (3 * corners[:, :, None] + np.arange(3)).reshape(len(k), 24)
    n_all = 3 * node.size
    return assemble(dofs, Ke, Me, n_all, np.arange(3 * (nx + 1) * (ny + 1), n_all))


def plate(nx: int, ny: int):
    """K, M of an nx x ny square of plane-stress quadrilaterals, the nodes at y = 0 clamped."""
    Ke, Me = quadrilateral()
    node = np.arange((nx + 1) * (ny + 1)).reshape(ny + 1, nx + 1)
    j, i = (a.ravel() for a in np.meshgrid(np.arange(ny), np.arange(nx), indexing="ij"))
    corners = np.stack([node[j, i], node[j, i + 1], node[j + 1, i + 1], node[j + 1, i]], 1)
    dofs = (2 * corners[:, :, None] + np.arange(2)).reshape(len(j), 8)
    n_all = 2 * node.size
    return assemble(dofs, Ke, Me, n_all, np.arange(2 * (nx + 1), n_all))


def chain(n: int):
    """K, M of n two-node bars (E A = E, L = 1, consistent mass), node 0 clamped: n DOFs."""
    Ke = E * np.array([[1.0, -1.0], [-1.0, 1.0]])
    Me = RHO / 6 * np.array([[2.0, 1.0], [1.0, 2.0]])
    dofs = np.stack([np.arange(n), np.arange(1, n + 1)], 1)
    return assemble(dofs, Ke, Me, n + 1, np.arange(1, n + 1))


def iteration_matrix(K, M):
    """S = K + (4/dt^2) M + (2/dt) C: C Rayleigh, 2 % on modes 1 and 3; dt = T1 / 50."""
    w = np.sqrt(np.sort(np.abs(spla.eigsh(K, k=3, M=M, sigma=0, which="LM", return_eigenvectors=False))))
    zeta = 0.02
    a, b = 2 * zeta * w[0] * w[2] / (w[0] + w[2]), 2 * zeta / (w[0] + w[2])
    dt = 2 * np.pi / w[0] / 50
    C = a * M + b * K
    S = (K + 4 / dt**2 * M + 2 / dt * C).tocsc()
    S.sort_indices()
    return S, dt


CASES = [  # (label, builder, quick)
    ("chain 10^5 (1-D bars)", lambda: chain(100_000), True),
    ("2-D quads 22 x 22", lambda: plate(22, 22), True),
    ("2-D quads 70 x 70", lambda: plate(70, 70), True),
    ("2-D quads 223 x 223", lambda: plate(223, 223), False),
    ("3-D hexahedra 6 x 6 x 6", lambda: block(6, 6, 6), True),
    ("3-D hexahedra 16 x 16 x 12", lambda: block(16, 16, 12), True),
    ("3-D hexahedra 23 x 23 x 17", lambda: block(23, 23, 17), False),
]


# ---- timing ------------------------------------------------------------------------------------
def eigen_include() -> str:
    try:
        import cmeel
        path = os.path.join(os.path.dirname(cmeel.__path__[0]), "cmeel.prefix", "include", "eigen3")
        if os.path.isfile(os.path.join(path, "Eigen", "Dense")):
            return path
    except ImportError:
        pass
    for path in ("/usr/include/eigen3", "/usr/local/include/eigen3"):
        if os.path.isfile(os.path.join(path, "Eigen", "Dense")):
            return path
    raise SystemExit("Eigen headers not found (pip install cmeel-eigen, or install libeigen3-dev)")


def compile_program(tmp: str, cxx: str) -> str:
    exe = os.path.join(tmp, "factorize")
    cmd = [cxx, *CXXFLAGS, "-I", os.path.join(ROOT, "cpp", "include"), "-I", eigen_include(),
           os.path.join(HERE, "cpp", "factorize.cpp"), "-o", exe]
    subprocess.run(cmd, check=True)
    return exe


def run_cpp(exe: str, path: str, repeats: int, budget: float) -> list[dict]:
    out = subprocess.run([exe, path, "--repeats", str(repeats), "--budget", str(budget)],
                         check=True, capture_output=True, text=True).stdout
    return [json.loads(line) for line in out.splitlines() if line.startswith("{")]


def time_scipy(S, repeats: int) -> dict:
    n = S.shape[0]
    b = np.sin(0.37 * np.arange(n) + 1.0)
    t_f = t_s = np.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        lu = spla.splu(S)
        t_f = min(t_f, time.perf_counter() - t0)
        for _ in range(5):
            t0 = time.perf_counter()
            x = lu.solve(b)
            t_s = min(t_s, time.perf_counter() - t0)
    res = np.linalg.norm(S @ x - b) / (spla.norm(S) * np.linalg.norm(x))
    return {"method": "scipy_splu", "n": n, "ok": True, "analyze": 0.0, "factorize": t_f, "solve": t_s, "ordering": "COLAMD",
            "residual": res, "nnz_l": int(lu.L.nnz + lu.U.nnz), "flops": 0.0}


# ---- report ------------------------------------------------------------------------------------
LABEL = {"simplicial_ldlt": "simplicial LDLᵀ (`OrderedCholesky<true>`)",
         "simplicial_llt": "simplicial LLᵀ (`OrderedCholesky<false>`)",
         "supernodal_llt_amd": "supernodal LLᵀ, AMD forced (the simplicial one's order)",
         "supernodal_llt": "supernodal LLᵀ (`SupernodalCholesky<false>`)",
         "supernodal_ldlt": "supernodal LDLᵀ (`SupernodalCholesky<true>`)",
         "scipy_splu": "SciPy `splu` (SuperLU, L + U)"}


def cpu_name() -> str:
    try:
        with open("/proc/cpuinfo") as fh:
            for line in fh:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown"


def fmt_t(t: float) -> str:
    return f"{t:.3g}" if t >= 1e-3 else f"{t:.2e}"


def table(rows: list[tuple[str, dict, list[dict]]]) -> list[str]:
    out = ["| model | n | nnz(tril S) | method | ordering (supernodes) | nnz(L) | GFlop | analyse [s] | factorise [s] | "
           "GFlop/s | solve [ms] | factor + 20 solves [s] | factorise: speed-up vs simplicial LDLᵀ | "
           "factor + 20 solves: speed-up vs SciPy | residual |",
           "|---|---:|---:|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for label, info, results in rows:
        by = {r["method"]: r for r in results}
        simp = by.get("simplicial_ldlt")
        scipy_total = None
        if "scipy_splu" in by:
            s = by["scipy_splu"]
            scipy_total = s["factorize"] + SOLVES * s["solve"]
        for r in results:
            m = r["method"]
            total = r["analyze"] + r["factorize"] + SOLVES * r["solve"]
            gf = r.get("flops", 0.0)
            speed = f"{simp['factorize'] / r['factorize']:.1f}x" if simp and m != "scipy_splu" else "–"
            vs_scipy = f"{scipy_total / total:.2f}x" if scipy_total else "–"
            sn = (f"{r['ordering']} ({r['supernodes']:,})" if r.get("supernodes") else
                  "COLAMD" if m == "scipy_splu" else r.get("ordering", "AMD"))
            out.append(
                f"| {label} | {info['n']:,} | {info['nnz']:,} | {LABEL[m]} | {sn} | {r['nnz_l']:,} | "
                f"{gf / 1e9:.3g} | {fmt_t(r['analyze']) if m != 'scipy_splu' else '(in factorise)'} | "
                f"{fmt_t(r['factorize'])} | {gf / r['factorize'] / 1e9:.2f} | {r['solve'] * 1e3:.3g} | "
                f"{total:.3g} | {speed} | {vs_scipy} | {r['residual']:.1e} |"
                if gf else
                f"| {label} | {info['n']:,} | {info['nnz']:,} | {LABEL[m]} | {sn} | {r['nnz_l']:,} | – | "
                f"{fmt_t(r['analyze']) if m != 'scipy_splu' else '(in factorise)'} | {fmt_t(r['factorize'])} | – | "
                f"{r['solve'] * 1e3:.3g} | {total:.3g} | {speed} | {vs_scipy} | {r['residual']:.1e} |")
    return out


def summary(rows: list[tuple[str, dict, list[dict]]]) -> list[str]:
    """The targets, read on the largest 3-D block."""
    big = [r for r in rows if r[0].startswith("3-D") and r[1]["n"] > 20_000]
    if not big:
        return []
    label, info, results = big[-1]
    by = {r["method"]: r for r in results}
    simp, sn, sd, sc = (by.get(k) for k in ("simplicial_ldlt", "supernodal_llt", "supernodal_ldlt", "scipy_splu"))
    if not (simp and sn and sd and sc):
        return []

    def total(r: dict) -> float:
        return r["analyze"] + r["factorize"] + SOLVES * r["solve"]

    return [
        f"On the {label} block ({info['n']:,} DOFs):",
        "",
        f"- factorise, supernodal LLᵀ against the simplicial LDLᵀ: {simp['factorize'] / sn['factorize']:.1f}x "
        f"(LDLᵀ: {simp['factorize'] / sd['factorize']:.1f}x); target >= 5x, goal >= 15x",
        f"- factor + {SOLVES} solves against SciPy's splu + {SOLVES} solves: LLᵀ {total(sc) / total(sn):.1f}x, "
        f"LDLᵀ {total(sc) / total(sd):.1f}x; target >= 2x",
        f"- one solve: LLᵀ {sn['solve'] * 1e3:.3g} ms, LDLᵀ {sd['solve'] * 1e3:.3g} ms against the simplicial "
        f"{simp['solve'] * 1e3:.3g} ms; target: no slower",
        f"- the flop count: {simp['flops'] / sn['flops']:.1f}x fewer than the simplicial factorisation's (its AMD "
        f"order), {sn['ordering']} chosen by the analysis"
        + (f"; with AMD forced (the same flops as the simplicial one) the supernodal LLᵀ factorises "
           f"{simp['factorize'] / by['supernodal_llt_amd']['factorize']:.1f}x faster: the dense kernels' share"
           if "supernodal_llt_amd" in by else ""),
        "",
    ]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--repeats", type=int, default=3, help="runs of each method; the best is reported (default 3)")
    ap.add_argument("--budget", type=float, default=20.0,
                    help="a method whose factorisation takes longer (s) is run once (default 20)")
    ap.add_argument("--quick", action="store_true", help="skip the largest models (2-D 10^5, 3-D 29,376)")
    ap.add_argument("--keep", metavar="DIR", help="keep the Matrix Market files in DIR")
    ap.add_argument("--out", default=os.path.join(HERE, "results", "factorize.md"), help="the markdown report")
    ap.add_argument("--cxx", default=os.environ.get("CXX", "g++"))
    args = ap.parse_args()
    if args.repeats < 1:
        ap.error("--repeats must be >= 1")
    load = os.getloadavg()[0]
    started = datetime.datetime.now().astimezone()
    tmp = tempfile.mkdtemp(prefix="nvib-factorize-")
    mdir = args.keep or tmp
    os.makedirs(mdir, exist_ok=True)
    try:
        exe = compile_program(tmp, args.cxx)
        rows = []
        for label, build, quick in CASES:
            if args.quick and not quick:
                continue
            K, M = build()
            S, dt = iteration_matrix(K, M)
            path = os.path.join(mdir, label.split(" (")[0].replace(" ", "_").replace("^", "") + ".mtx")
            scipy.io.mmwrite(path, sp.tril(S).tocoo(), symmetry="symmetric")
            info = {"n": S.shape[0], "nnz": int(sp.tril(S).nnz), "dt": dt}
            print(f"{label}: n = {info['n']}, nnz(tril S) = {info['nnz']}, dt = {dt:.3g} s", file=sys.stderr)
            results = run_cpp(exe, path, args.repeats, args.budget)
            results.append(time_scipy(S, args.repeats))
            for r in results:
                print(f"  {r['method']:16s} analyse {r['analyze']:.3g} s, factorise {r['factorize']:.3g} s, "
                      f"solve {r['solve'] * 1e3:.3g} ms, nnz(L) {r['nnz_l']:,}, residual {r['residual']:.1e}",
                      file=sys.stderr)
            rows.append((label, info, results))
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    try:
        gxx = subprocess.run([args.cxx, "--version"], capture_output=True, text=True).stdout.splitlines()[0]
    except (OSError, IndexError):
        gxx = args.cxx
    lines = [
        "# Sparse Cholesky: supernodal against simplicial and SciPy's SuperLU",
        "",
        f"- date: {started.strftime('%Y-%m-%d %H:%M %Z')}",
        f"- CPU: {cpu_name()}, {os.cpu_count()} logical CPUs; {platform.system()} {platform.release()}; "
        f"1-minute load average at start {load:.2f}",
        f"- compiler: {gxx}; `benchmarks/cpp/factorize.cpp` built with `{' '.join(CXXFLAGS)}` (nvib's Release "
        "flags, no `-march=native`), one thread",
        f"- Python {platform.python_version()}, NumPy {np.__version__}, SciPy {scipy.__version__}",
        f"- times: best of {args.repeats} runs (the machine is shared: timings are noisy), one solve the best of 5 "
        f"in each run; a simplicial factorisation over {args.budget:g} s is run once",
        "- S = K + (4/dt²) M + (2/dt) C, C Rayleigh (2 % on modes 1 and 3), dt = T1 / 50; nvib reads its lower "
        "triangle; SciPy factorises the whole S with `splu(S)` (default options: COLAMD, partial pivoting "
        "threshold 1)",
        "- GFlop: the flop count of the numeric factorisation, Σ over the stored columns of L of (entries)² "
        "(the supernodal one counts its explicit zeros); nnz(L) of SciPy is nnz(L) + nnz(U)",
        f"- factor + {SOLVES} solves: analyse + factorise + {SOLVES} x solve (SciPy: splu + {SOLVES} x solve)",
        "- residual: |S x − b| / (|S|_F |x|)",
        "",
    ]
    lines += summary(rows)
    lines += table(rows)
    lines.append("")
    text = "\n".join(lines)
    print(text)
    if args.out:
        os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
        with open(args.out, "w") as fh:
            fh.write(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
