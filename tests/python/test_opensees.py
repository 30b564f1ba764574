"""nvib against OpenSees on the building scene (benchmarks/opensees_building.py).

The script builds the building in OpenSeesPy (ElasticPowerFunc storey springs
f = k0 d + k0 a d^3, UniformExcitation with a Trig series a_g = 10 sin(pi t),
Newton, NormUnbalance max-norm 1e-6 N, BandGeneral) and integrates it to 2 s at
dt = 1e-4 with the same schemes as nvib: Newmark(1/4, 1/2); HHTGeneralized
(alpha_I = alpha_F = 1/2, beta = 1/4, gamma = 1/2), which is nvib's
GeneralizedAlpha() (OpenSees' own GeneralizedAlpha integrator does not
converge here, see the script); OpenSees HHT(0.9), which is nvib's
GeneralizedAlpha(alpha_m=0, alpha_f=0.1, beta=0.3025, gamma=0.6).

Both solve the same discrete equations with the same predictor (constant
displacement), so they differ only where the Newton iteration stops and in
round-off. The convergence tests differ: OpenSees stops when the max-norm of
the unbalanced force is below 1e-6 N (absolute); nvib when it is below
rtol = 1e-10 times the step's largest inertia/force term plus atol = 1e-12, or
when a negligible increment no longer lowers it and it is within its
round-off. The residuals also round differently: OpenSees updates the
acceleration by increments (a += c3 du) and its residual bottoms out near
1e-9 N; nvib recomputes a = c0 (u1 - u_n - h v_n) - ..., whose cancellation
leaves a residual floor near 1e-3 N, above its tolerance (about 2.5e-5 N), so
most of its steps end through the stall check after a third iteration, where
OpenSees stops after two. The final displacements then differ at the level
of accumulated round-off (a few 1e-12 m on about 1e-2 m), the same size as
nvib's own change when its rtol goes from 1e-10 to 1e-12 (7e-12 m).

Skips when openseespylinux is not installed. OpenSees runs in a subprocess
started with the LD_LIBRARY_PATH that the script's opensees_env() gives.
"""

from __future__ import annotations

import importlib.util
import json
import os
import subprocess
import sys

import numpy as np
import pytest

import nvib

pytestmark = pytest.mark.skipif(
    importlib.util.find_spec("openseespylinux") is None, reason="openseespy (openseespylinux) is not installed"
)

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SCRIPT = os.path.join(ROOT, "benchmarks", "opensees_building.py")
DT = 1e-4
T_END = 2.0


def _script_module():
    spec = importlib.util.spec_from_file_location("_opensees_building", SCRIPT)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)  # imports no OpenSees: that happens inside run()
    return mod


NVIB_SCHEMES = {
    "newmark": nvib.Newmark(),
    "galpha": nvib.GeneralizedAlpha(),
    "hht": nvib.GeneralizedAlpha(alpha_m=0.0, alpha_f=0.1, beta=0.3025, gamma=0.6),
}

# max |u_opensees - u_nvib| over the six floors at t = 2 s; measured (relative
# to max |u| = 9.6e-3 m) and bound (under 10x the measurement)
U_BOUND = {
    "newmark": 3e-11,  # measured 3.58e-12 m (3.7e-10 relative)
    "galpha": 1.5e-11,  # measured 1.82e-12 m (1.9e-10 relative)
    "hht": 1.2e-11,  # measured 1.36e-12 m (1.4e-10 relative)
}


@pytest.fixture(scope="module")
def opensees():
    env = _script_module().opensees_env()
    if env is None:
        pytest.skip("openseespy (openseespylinux) is not installed")
    proc = subprocess.run(
        [sys.executable, SCRIPT, "--json", "--t-end", str(T_END), "--dt", str(DT), "--repeats", "1",
         "--schemes", ",".join(NVIB_SCHEMES)],
        env=env, capture_output=True, text=True, timeout=60,
    )
    assert proc.returncode == 0, proc.stderr[-2000:]
    rows = [json.loads(line) for line in proc.stdout.splitlines() if line.startswith("{")]
    return {r["scheme"]: r for r in rows if "scheme" in r}


@pytest.fixture(scope="module")
def building():
    return nvib.load_scene("building")


@pytest.mark.parametrize("scheme", list(NVIB_SCHEMES))
def test_final_displacements_agree(opensees, building, scheme):
    r = opensees[scheme]
    assert r["steps"] == round(T_END / DT)
    assert abs(r["t_final"] - T_END) < 1e-9  # OpenSees sums dt: 2 -+ 2e-12 here
    res = nvib.solve(building, NVIB_SCHEMES[scheme], dt=DT, t_end=T_END, save_every=10**9)
    assert res.t[-1] == pytest.approx(T_END)
    u_nvib = np.asarray(res.u[-1])
    u_ops = np.asarray(r["u"])
    du = np.max(np.abs(u_ops - u_nvib))
    assert np.max(np.abs(u_nvib)) > 5e-3  # the comparison is not between two near-zero states
    assert du <= U_BOUND[scheme], (scheme, du)
    # the untimed per-step run (for the iteration count) ends in the same state
    assert r["loop_vs_one_call_max_du"] == 0.0


@pytest.mark.parametrize("scheme", list(NVIB_SCHEMES))
def test_newton_iterations(opensees, building, scheme):
    """Measured at 2 s: OpenSees 1.98 per step (all three schemes), nvib 2.75 to 2.85.

    nvib needs more: its third iteration mostly confirms a residual stalled at
    its round-off floor (see the module docstring). Asserted: both at least one
    per step, OpenSees at most 2.2 per step, OpenSees not above nvib (5 %
    slack), nvib at most 1.6x OpenSees (measured 1.39 to 1.44).
    """
    r = opensees[scheme]
    steps = r["steps"]
    ops_iters = r["iterations"]
    res = nvib.solve(building, NVIB_SCHEMES[scheme], dt=DT, t_end=T_END, save_every=10**9)
    nvib_iters = res.stats.num_newton_iters
    assert steps <= ops_iters <= 2.2 * steps
    assert steps <= nvib_iters
    assert ops_iters <= 1.05 * nvib_iters
    assert nvib_iters <= 1.6 * ops_iters
