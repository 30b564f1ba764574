"""A child process for the Ctrl-C tests and benchmark of solve_many: starts a batch far too long to
finish on the path named by argv[1] (serial, threads, processes, dask), prints "started" with its pid
and is sent SIGINT (or killed) by its parent. Prints one JSON line: when the KeyboardInterrupt reached
Python code (the monotonic clock the parent shares) and what its ``result`` (a Batch) holds. Also
the parent's helpers that find the batch's worker processes and tell whether they still run."""

from __future__ import annotations

import json
import os
import sys
import time

import nvib


def hardening_python(u, v, t):  # module level: it pickles, for the process path
    return 100.0 * (1.0 + 30.0 * u * u) * u


def descendants(pid: int) -> set[int]:
    """The processes below pid (from /proc/*/task/*/children; Linux)."""
    out, todo = set(), [pid]
    while todo:
        p = todo.pop()
        try:
            tasks = os.listdir(f"/proc/{p}/task")
        except FileNotFoundError:
            continue
        for tid in tasks:
            try:
                with open(f"/proc/{p}/task/{tid}/children", encoding="utf-8") as fh:
                    kids = [int(x) for x in fh.read().split()]
            except (FileNotFoundError, ProcessLookupError):
                continue
            for k in kids:
                if k not in out:
                    out.add(k)
                    todo.append(k)
    return out


def alive(pid: int) -> bool:
    """pid is a process that has not ended (a zombie has)."""
    try:
        with open(f"/proc/{pid}/stat", encoding="utf-8") as fh:
            state = fh.read().rsplit(")", 1)[1].split()[0]
    except (FileNotFoundError, ProcessLookupError):
        return False
    return state != "Z"


def main() -> int:
    path = sys.argv[1]
    runs = int(sys.argv[2]) if len(sys.argv) > 2 else 40
    kw = dict(dt=1e-4, t_end=1e4, save_every=10**5, progress=False)  # 1e8 steps a run: minutes each
    if path == "processes":
        models = [nvib.Model([1.0], u0=[1.0 + 0.01 * k], uses_velocity=False, uses_time=False,
                             force=hardening_python) for k in range(runs)]
        kw.update(processes=True, threads=2)
    else:
        building = nvib.load_scene("building")
        models = [building] * runs
        if path == "threads":
            kw.update(threads=2)
        elif path == "serial":
            kw.update(threads=1)
    client = None
    if path == "dask":
        from distributed import Client, LocalCluster

        cluster = LocalCluster(n_workers=1, threads_per_worker=2, processes=False, dashboard_address=None)
        client = Client(cluster)
        kw.update(client=client)
    print("started", os.getpid(), flush=True)
    out = {"path": path}
    try:
        nvib.solve_many(models, nvib.CentralDifference(), **kw)
        out["outcome"] = "returned"
    except KeyboardInterrupt as exc:
        out["caught"] = time.clock_gettime(time.CLOCK_MONOTONIC)
        out["outcome"] = "interrupted"
        out["message"] = str(exc)
        batch = getattr(exc, "result", None)
        if batch is not None:
            out["runs"] = len(batch)
            out["not_run"] = sum(r is None for r in batch)
            out["partial"] = [k for k, r in enumerate(batch)
                              if r is not None and r.status == nvib.Status.interrupted]
            out["partial_steps"] = [int(batch[k].stats.num_steps) for k in out["partial"]]
            out["finished"] = sum(r is not None and r.status == nvib.Status.success for r in batch)
            out["labels"] = len(batch.labels)
    if client is not None:
        client.close()
    print(json.dumps(out), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
