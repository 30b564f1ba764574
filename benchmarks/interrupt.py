"""How fast Ctrl-C stops a run, and what it hands back.

Each case runs in a fresh Python subprocess that starts a run far too long to
finish, prints a line when the run is under way (from its first progress
call), and is sent SIGINT a moment later. The child times, on its own clock,
the interval from the signal's arrival (a SIGINT handler that records the
time and then raises KeyboardInterrupt as Python's own does) to the moment
the KeyboardInterrupt reaches Python code again, and reports the partial
history the exception carries (`exc.result`).

Cases:
  * hardening oscillator, built-in effect (C++ only: the GIL is released), CentralDifference;
  * the same law as a Python force (the GIL is kept; the signal lands between callbacks);
  * a 160,000-DOF lattice with Newmark and Newton: steps of about a second each
    (two sparse factorisations), where the poll sits at every factorisation;
  * PIM's set-up on a 400-DOF chain (dense 2^N squarings of an 800 x 800 matrix).

Batches (``solve_many`` of 40 runs far too long to finish, 2 workers; the child is
tests/python/_batch_interrupt_child.py): serially, on threads (the building, C++ only), in
processes (a Python force) and on a Dask LocalCluster (threads, in the caller's process). The
latency is from the signal to the KeyboardInterrupt out of ``solve_many``; the table says what its
``exc.result`` held and, for processes, whether a worker outlived the call.

    python benchmarks/interrupt.py [--repeats 3] [--out benchmarks/results/interrupt.md]
"""

from __future__ import annotations

import argparse
import json
import os
import signal
import subprocess
import sys
import textwrap
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from building import cpu_name, git_revision, write_report  # noqa: E402

CHILD = textwrap.dedent("""
    import json, signal, sys, time
    import numpy as np
    import nvib

    case = sys.argv[1]
    arrived = []

    def handler(signum, frame):
        arrived.append(time.clock_gettime(time.CLOCK_MONOTONIC))
        raise KeyboardInterrupt

    signal.signal(signal.SIGINT, handler)
    started = [False]

    def progress(step, n):
        if not started[0]:
            started[0] = True
            print("started", flush=True)

    hardening = [{"type": "hardening_spring", "measure": {"x": 1.0}, "k0": 100.0, "a": 30.0}]
    if case == "cpp":
        model, scheme = nvib.Model([1.0], effects=hardening, dofs=["x"], u0=[1.5]), nvib.CentralDifference()
        kw = dict(dt=1e-4, t_end=1e6, save_every=10_000)
    elif case == "python":
        model = nvib.Model([1.0], u0=[1.5], uses_velocity=False, uses_time=False,
                           force=lambda u, v, t: 100.0 * (1.0 + 30.0 * u * u) * u)
        scheme, kw = nvib.CentralDifference(), dict(dt=1e-4, t_end=1e6, save_every=10_000)
    elif case == "lattice":
        model = nvib.scenes.lattice(400, 400)
        scheme = nvib.Newmark()
        kw = dict(dt=1e-3, t_end=1e3, save_every=1, u0=np.full(model.n, 1e-3), dofs=[0])
    else:  # pim set-up
        model = nvib.scenes.chain(400)
        scheme, kw = nvib.PreciseIntegration(squarings=60), dict(dt=1e-3, t_end=1e3, save_every=1000)
        print("started", flush=True)  # the set-up has no progress call: the signal comes during it
    t0 = time.perf_counter()
    out = {"case": case, "n": model.n}
    try:
        nvib.solve(model, scheme, progress=progress, **kw)
        out["outcome"] = "finished (not interrupted)"
    except KeyboardInterrupt as exc:
        out["caught"] = time.clock_gettime(time.CLOCK_MONOTONIC)
        out["handler"] = arrived[0] if arrived else float("nan")
        res = getattr(exc, "result", None)
        if res is not None:
            out["steps_done"] = int(res.stats.num_steps)
            out["saved"] = len(res.t)
            out["status"] = res.status.name
            out["t_saved"] = float(res.t[-1]) if len(res.t) else None
        out["outcome"] = "interrupted"
    out["run_s"] = time.perf_counter() - t0
    print(json.dumps(out), flush=True)
""")

CASES = {
    "cpp": "hardening oscillator, built-in effect (C++ only), CentralDifference",
    "python": "hardening oscillator, Python force, CentralDifference",
    "lattice": "lattice 400 x 400 (160,000 DOFs), Newmark + Newton, ~1 s per step",
    "pim": "chain of 400 DOFs, PIM set-up (2^60 squarings of an 800 x 800 matrix)",
}
DELAY = {"cpp": 0.5, "python": 0.5, "lattice": 1.5, "pim": 1.0}  # s after the run is under way


def signal_child(argv: list[str], label: str, delay: float) -> tuple[dict, float, set[int]]:
    """Starts a child, waits for its "started" line and ``delay`` more, sends SIGINT and reads the
    JSON line it prints last: (that line, when the signal was sent, the child's processes then)."""
    p = subprocess.Popen([sys.executable, *argv], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                         preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    line = p.stdout.readline()
    if not line.startswith("started"):
        p.kill()
        raise RuntimeError(f"{label}: the child did not start: {line!r} {p.stderr.read()[-2000:]}")
    time.sleep(delay)
    workers = descendants(p.pid)
    sent = time.clock_gettime(time.CLOCK_MONOTONIC)
    p.send_signal(signal.SIGINT)
    out, err = p.communicate(timeout=600)
    if p.returncode != 0:
        raise RuntimeError(f"{label}: exit {p.returncode}: {err[-2000:]}")
    return json.loads(out.strip().splitlines()[-1]), sent, workers


def run_case(case: str) -> dict:
    r, sent, _ = signal_child(["-c", CHILD, case], case, DELAY[case])
    if "caught" in r:
        r["latency_s"] = r["caught"] - sent
        r["poll_s"] = r["handler"] - sent
    return r


BATCH_CHILD = os.path.join(os.path.dirname(HERE), "tests", "python", "_batch_interrupt_child.py")
sys.path.insert(0, os.path.dirname(BATCH_CHILD))
from _batch_interrupt_child import alive, descendants  # noqa: E402
BATCH_CASES = {
    "serial": "40 building runs, one at a time (threads=1)",
    "threads": "40 building runs on 2 threads",
    "processes": "40 runs of a Python force on 2 processes",
    "dask": "40 building runs on a Dask LocalCluster (1 worker, 2 threads)",
}
BATCH_DELAY = {"serial": 1.0, "threads": 1.0, "processes": 2.0, "dask": 3.0}  # s after "started"


def run_batch_case(case: str) -> dict:
    r, sent, workers = signal_child([BATCH_CHILD, case, "40"], f"batch {case}", BATCH_DELAY[case])
    if "caught" in r:
        r["latency_s"] = r["caught"] - sent
    time.sleep(1.0)
    r["workers"] = len(workers)
    r["survivors"] = sum(alive(w) for w in workers)
    return r


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--cases", nargs="+", default=list(CASES), choices=list(CASES))
    ap.add_argument("--batches", nargs="*", default=list(BATCH_CASES), choices=list(BATCH_CASES))
    ap.add_argument("--out", default=os.path.join(HERE, "results", "interrupt.md"))
    args = ap.parse_args()
    if args.repeats < 1:
        ap.error("--repeats: must be >= 1")
    import nvib

    rows = []
    for case in args.cases:
        runs = [run_case(case) for _ in range(args.repeats)]
        rows.append((case, runs))
        print(f"{case}: " + ", ".join(f"{r.get('latency_s', float('nan')) * 1e3:.1f} ms" for r in runs),
              file=sys.stderr)
    batch_rows = []
    for case in args.batches:
        if case == "dask":
            try:
                import distributed  # noqa: F401
            except ImportError:
                print("dask: distributed is not installed, skipped", file=sys.stderr)
                continue
        runs = [run_batch_case(case) for _ in range(args.repeats)]
        batch_rows.append((case, runs))
        print(f"batch {case}: " + ", ".join(f"{r.get('latency_s', float('nan')) * 1e3:.0f} ms" for r in runs),
              file=sys.stderr)
    lines = ["# Ctrl-C: how fast a run stops, and what it hands back", "",
             f"- date: {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}",
             f"- CPU: {cpu_name()}, {os.cpu_count()} logical CPUs; load average at start {os.getloadavg()[0]:.2f}",
             f"- nvib {nvib.__version__} (git {git_revision()}); Python {sys.version.split()[0]}",
             f"- command: `python benchmarks/interrupt.py --repeats {args.repeats}`", "",
             "Latency: from the parent's `send_signal(SIGINT)` to the KeyboardInterrupt caught around "
             "`nvib.solve` in the child, on the monotonic clock both share (each run a fresh subprocess, the "
             "signal sent a moment after the run is under way); in brackets, the part until nvib's poll ran "
             "the child's signal handler. The partial history is the one the exception carries as "
             "`exc.result`.", "",
             "| case | DOFs | latency [ms] (until the poll), each run | steps done before it | states handed back "
             "| status |",
             "|---|---:|---|---|---|---|"]
    for case, runs in rows:
        lat = ", ".join(f"{r['latency_s'] * 1e3:.1f} ({r['poll_s'] * 1e3:.1f})" if "latency_s" in r else r["outcome"]
                        for r in runs)
        steps = ", ".join(f"{r['steps_done']:,}" if "steps_done" in r else "–" for r in runs)
        saved = ", ".join(str(r["saved"]) if "saved" in r else "none (before the first step)" for r in runs)
        status = ", ".join(sorted({r.get("status", "–") for r in runs}))
        lines.append(f"| {CASES[case]} | {runs[0]['n']:,} | {lat} | {steps} | {saved} | {status} |")
    lines += ["", "The C++ loop polls for signals on a clock (SolveOptions::observe_period, 50 ms by default, "
              "is the longest interval) and at every factorisation and PIM squaring; with a Python force the "
              "interpreter raises at its next "
              "bytecode, inside the force callback. A run stopped during PIM's set-up hands back no "
              "history (no step was taken)."]
    if batch_rows:
        lines += ["", "## Batches", "",
                  "`solve_many` of 40 runs far too long to finish, SIGINT a moment after the batch is under way; "
                  "latency from the signal to the KeyboardInterrupt out of `solve_many`. Its `exc.result` is the "
                  "Batch of what was done: runs finished, runs stopped part-way (Status.interrupted, their "
                  "partial histories) and runs never started (None). *Workers left*: the batch's worker "
                  "processes still running a second after the call returned.", "",
                  "| batch | latency [ms], each run | finished | stopped part-way | not run | workers left |",
                  "|---|---|---|---|---|---|"]
        for case, runs in batch_rows:
            lat = ", ".join(f"{r['latency_s'] * 1e3:.0f}" if "latency_s" in r else r["outcome"] for r in runs)
            fin = ", ".join(str(r.get("finished", "–")) for r in runs)
            part = ", ".join(str(len(r.get("partial", []))) for r in runs)
            notrun = ", ".join(str(r.get("not_run", "–")) for r in runs)
            left = ", ".join(f"{r['survivors']} of {r['workers']}" if r["workers"] else "–" for r in runs)
            lines.append(f"| {BATCH_CASES[case]} | {lat} | {fin} | {part} | {notrun} | {left} |")
        lines += ["", "Before this measurement's change, threads went on until every run had finished (67 s "
                  "after the signal on 40 building runs, once returning normally with the interrupt lost) and "
                  "processes waited 48-78 s the same way: the C++ poll's `PyErr_CheckSignals()` does nothing "
                  "outside the main thread. Now the main thread sets a stop token that every run's poll reads "
                  "(threads, Dask through a Dask Event), and worker processes turn SIGINT into their own token."]
    write_report(args.out, lines)
    return 0


if __name__ == "__main__":
    sys.exit(main())
