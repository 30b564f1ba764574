"""Record and compare trajectories across a change of nvib: the check that a refactor keeps results.

    python tools/trajectories.py record DIR     # run every case, save DIR/<case>.npz
    python tools/trajectories.py compare DIR    # run again, compare with DIR

Explicit schemes (and PIM) must reproduce the recorded trajectories bit for bit; the
implicit ones within 1e-12 of each history's peak. The cases cover the built-in scenes
under every scheme and Newton mode, effect arrays (uniform and per-effect parameters,
sparse tangents), single effects of every measure storage (one DOF, a difference, two
coefficients, a sparse list, a dense row, dense loads), Python laws and a force callable,
with the energy accounting where the model has it. Only the cases that run on both
versions are compared (a case the recorded version could not run is listed, not failed).
"""

from __future__ import annotations

import argparse
import os
import sys
import traceback

import numpy as np

import nvib

IMPLICIT = {"newmark", "galpha"}


def schemes():
    """(label, scheme) pairs: every scheme, the Newton modes, PIM's variants."""
    out = [("lcdm", nvib.CentralDifference()), ("lcdm_half", nvib.CentralDifference(velocity="half_step")),
           ("cemdts", nvib.CEMDTS()), ("zhai", nvib.Zhai()), ("pim", nvib.PreciseIntegration())]
    for mode in ("newton", "modified", "initial", "incremental", "one_iteration"):
        out.append((f"newmark_{mode}", nvib.Newmark(newton=nvib.Newton(iteration=mode))))
    out.append(("galpha", nvib.GeneralizedAlpha()))
    out.append(("hht", nvib.GeneralizedAlpha.hht(-0.1)))
    out.append(("galpha_rho05_fd", nvib.GeneralizedAlpha.from_rho_inf(0.5, newton=nvib.Newton(jacobian="finite_difference"))))
    return out


def chain(n: int, velocity: bool):
    """A chain of n masses with effect arrays: linear springs to the ground, hardening springs between
    neighbours with per-effect parameters, cubic springs, (power) dampers, a harmonic force."""
    i = np.arange(n)
    k0 = 1e4 * (1.0 + 0.1 * np.sin(i))
    effects = [
        {"type": "spring", "i": i, "k": 2e3},
        {"type": "hardening_spring", "i": i[1:], "j": i[:-1], "k0": k0[1:], "a": 5.0},
        {"type": "cubic_spring", "i": i[::3], "k3": 1e5},
        {"type": "harmonic_force", "measure": {0: 1.0}, "amplitude": 50.0, "omega": 7.0},
    ]
    if velocity:
        effects.append({"type": "damper", "i": i[1:], "j": i[:-1], "c": 3.0})
        effects.append({"type": "power_damper", "i": i[::2], "c": 2.0, "p": 1.5})
    u0 = 0.01 * np.sin(np.linspace(0, 3, n))
    return nvib.Model(np.full(n, 1.5), effects=effects, u0=u0, name=f"chain{n}")


def storages():
    """Single effects of every measure storage and dense loads, one Hertz contact with a table signal."""
    n = 8
    effects = [
        {"type": "hardening_spring", "measure": {0: 1.0}, "k0": 400.0, "a": 3.0},
        {"type": "hardening_spring", "measure": {1: 1.0, 0: -1.0}, "k0": 300.0, "a": 2.0},
        {"type": "cubic_spring", "measure": {2: 2.0, 1: -0.5}, "k3": 900.0},
        {"type": "spring", "measure": {3: 1.0, 2: -1.0}, "k": 250.0},
        {"type": "pendulum_gravity", "measure": {4: 1.0, 3: -0.3, 5: 0.2}, "m": 1.0, "g": 9.81, "l": 2.0},
        {"type": "power_damper", "measure": {5: 1.0, 4: -1.0}, "c": 4.0, "p": 0.7},
        {"type": "damper", "measure": {6: 1.0}, "c": 1.0},
        {"type": "hardening_spring", "measure": {k: 0.3 + 0.1 * k for k in range(n)}, "k0": 80.0, "a": 1.0},
        {"type": "hertz_contact", "measure": {7: 1.0, 6: -1.0}, "G": 1e-3, "contacts": 2.0,
         "irregularity": {"kind": "table", "t": [0.0, 0.2, 0.5, 1.0], "values": [0.0, 1e-3, -2e-3, 0.0]}},
        {"type": "spring", "measure": {7: 1.0}, "k": 500.0},
        {"type": "spring", "measure": {6: 1.0, 5: -1.0}, "k": 200.0},
        {"type": "constant_force", "measure": {7: 1.0}, "value": 3.0},
        {"type": "harmonic_force", "measure": {2: 1.0, 3: 0.5}, "amplitude": 2.0, "omega": 5.0, "phase": 0.3},
        {"type": "ground_acceleration", "signal": {"kind": "sine", "amplitude": 1.0, "omega": 4.0}},
    ]
    u0 = 0.05 * np.cos(np.arange(n))
    return nvib.Model(np.linspace(1.0, 2.0, n), effects=effects, u0=u0, name="storages")


def python_laws():
    """A Python law on a measure, with its tangent, beside built-in effects; and a force callable."""
    effects = [
        {"type": "spring", "measure": {0: 1.0}, "k": 100.0},
        {"type": "callable", "measure": {1: 1.0, 0: -1.0}, "law": lambda d, dd, t: 50.0 * d + 20.0 * d ** 3,
         "tangent": lambda d, dd, t: (50.0 + 60.0 * d ** 2, 0.0), "uses_velocity": False, "uses_time": False},
        {"type": "damper", "measure": {1: 1.0}, "c": 0.5},
    ]
    return nvib.Model([1.0, 2.0], effects=effects, u0=[0.3, -0.2], name="python_laws")


def force_callable():
    K = np.array([[200.0, -100.0], [-100.0, 100.0]])
    return nvib.Model([1.0, 1.0], K=K, force=lambda u, v, t: np.array([10.0 * u[0] ** 3, 0.2 * v[1] - np.sin(3 * t)]),
                      u0=[0.1, 0.0], name="force_callable")


def cases():
    """(name, model, dt, t_end, energy) for every case."""
    out = []
    for scene in nvib.scene_names():
        model = nvib.load_scene(scene)
        dt = model.scene["dt"]
        t_end = min(model.scene["t_end"], 3000 * dt)
        out.append((scene, model, dt, t_end, model.accounts_energy if hasattr(model, "accounts_energy") else True))
    out.append(("chain40", chain(40, True), 2e-3, 1.0, True))
    out.append(("chain200", chain(200, False), 1e-3, 0.5, True))
    out.append(("storages", storages(), 1e-3, 1.0, True))
    out.append(("python_laws", python_laws(), 2e-3, 2.0, False))
    out.append(("force_callable", force_callable(), 2e-3, 2.0, False))
    return out


def run_all(only=None):
    results = {}
    for name, model, dt, t_end, energy in cases():
        for label, scheme in schemes():
            key = f"{name}__{label}"
            if only and not any(o in key for o in only):
                continue
            if label.startswith("pim") and model.n > 60:
                continue
            try:
                res = nvib.solve(model, scheme, dt=dt, t_end=t_end, energy=energy and _accounts(model), throw=False)
            except Exception as exc:  # recorded as such: a case a version cannot run
                results[key] = {"error": f"{type(exc).__name__}: {exc}"}
                continue
            rec = {"t": res.t, "u": res.u, "v": res.v, "a": res.a, "status": str(res.status),
                   "nfe": res.stats.num_force_evals, "nit": res.stats.num_newton_iters}
            if res.energy is not None:
                rec["energy"] = np.column_stack([res.energy.kinetic, res.energy.potential, res.energy.work_in,
                                                 res.energy.dissipated, res.energy.balance_error])
            results[key] = rec
    return results


def _accounts(model) -> bool:
    return bool(model._core.accounts_energy)


def record(folder: str, only=None) -> None:
    os.makedirs(folder, exist_ok=True)
    for key, rec in run_all(only).items():
        np.savez(os.path.join(folder, key + ".npz"), **{k: np.asarray(v) for k, v in rec.items()})
    print(f"recorded {len(os.listdir(folder))} cases in {folder}")


def compare(folder: str, only=None) -> int:
    bad, same, close, missing = [], 0, 0, []
    for key, rec in run_all(only).items():
        path = os.path.join(folder, key + ".npz")
        if not os.path.exists(path):
            missing.append(key)
            continue
        old = dict(np.load(path, allow_pickle=False))
        if "error" in old or "error" in rec:
            if "error" in old and "error" in rec:
                same += 1
            elif "error" in old:
                missing.append(f"{key} (the recorded version failed: {old['error']})")
            else:
                bad.append(f"{key}: now fails: {rec['error']}")
            continue
        implicit = any(key.split("__")[1].startswith(s) for s in ("newmark", "galpha", "hht"))
        problems = []
        for field in ("t", "u", "v", "a", "energy"):
            if field not in old and field not in rec:
                continue
            if (field in old) != (field in rec):
                problems.append(f"{field} present in only one version")
                continue
            a, b = np.asarray(old[field]), np.asarray(rec[field])
            if a.shape != b.shape:
                problems.append(f"{field} shape {a.shape} -> {b.shape}")
                continue
            if np.array_equal(a, b):
                continue
            scale = max(np.max(np.abs(a)) if a.size else 0.0, 1e-300)
            err = np.max(np.abs(a - b)) / scale
            if implicit and err <= 1e-12:
                close += 1
                continue
            problems.append(f"{field} differs by {err:.3g} of its peak")
        if str(old["status"]) != rec["status"]:
            problems.append(f"status {old['status']} -> {rec['status']}")
        if problems:
            bad.append(f"{key}: " + "; ".join(problems))
        else:
            same += 1
    print(f"{same} cases agree ({close} implicit fields within 1e-12, the rest bit for bit)")
    for m in missing:
        print("  not compared:", m)
    for b in bad:
        print("  DIFFERENT:", b)
    return 1 if bad else 0


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("action", choices=("record", "compare"))
    p.add_argument("folder")
    p.add_argument("--only", nargs="*", help="only cases whose name contains one of these")
    a = p.parse_args(argv)
    try:
        if a.action == "record":
            record(a.folder, a.only)
            return 0
        return compare(a.folder, a.only)
    except Exception:
        traceback.print_exc()
        return 2


if __name__ == "__main__":
    sys.exit(main())
