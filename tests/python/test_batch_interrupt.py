"""Ctrl-C stops a batch within a second on every path (serial, threads, processes, Dask): the runs
under way stop at their next poll and hand back their partial histories, the runs not started are
cancelled, and the KeyboardInterrupt carries the Batch of what was done. No worker process outlives
the call, nor its caller when the caller is killed. Each case runs in a child process that the test
signals, as a terminal would."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time

import pytest

from _batch_interrupt_child import alive, descendants

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc; POSIX signals")

CHILD = os.path.join(os.path.dirname(os.path.abspath(__file__)), "_batch_interrupt_child.py")
LIMIT = 2.0  # s from the signal to the exception


def start(path: str, runs: int = 40):
    p = subprocess.Popen([sys.executable, CHILD, path, str(runs)], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                         text=True, preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    line = p.stdout.readline().split()
    if not line or line[0] != "started":
        p.kill()
        raise AssertionError(f"the child did not start: {line} {p.stderr.read()[-3000:]}")
    return p


def interrupt(p, after: float) -> tuple[dict, float, set[int]]:
    time.sleep(after)
    workers = descendants(p.pid)
    sent = time.clock_gettime(time.CLOCK_MONOTONIC)
    p.send_signal(signal.SIGINT)
    try:
        out, err = p.communicate(timeout=120)
    except subprocess.TimeoutExpired:
        p.kill()
        raise AssertionError("the batch did not stop within 120 s of Ctrl-C")
    assert p.returncode == 0, err[-3000:]
    assert "Traceback" not in err, err[-3000:]
    r = json.loads(out.strip().splitlines()[-1])
    return r, sent, workers


def check_interrupted(r: dict, sent: float, runs: int = 40) -> None:
    assert r["outcome"] == "interrupted", r
    assert r["caught"] - sent < LIMIT, f"{r['caught'] - sent:.2f} s from the signal to the exception"
    # the Batch of what was done: one entry per run, the runs under way partial, the rest never started
    assert r["runs"] == runs and r["labels"] == runs
    assert r["partial"], r  # the runs under way were stopped part-way and handed back
    assert all(0 < s < 10**8 for s in r["partial_steps"]), r["partial_steps"]
    assert r["not_run"] >= runs - 2 - r["finished"] - len(r["partial"]) and r["not_run"] > 0, r
    assert "not run" in r["message"] and "exc.result" in r["message"]


@pytest.mark.parametrize("path", ["serial", "threads"])
def test_ctrl_c_stops_a_batch_of_cpp_runs(path):
    p = start(path)
    r, sent, _ = interrupt(p, 1.0)
    check_interrupted(r, sent)
    if path == "threads":
        assert len(r["partial"]) == 2, r  # both threads' runs were stopped, not left to finish


def test_ctrl_c_stops_a_batch_in_processes_and_no_worker_survives():
    p = start("processes")
    r, sent, workers = interrupt(p, 2.0)
    check_interrupted(r, sent)
    assert len(workers) >= 2, workers  # the pool's processes were there when the signal came
    deadline = time.monotonic() + 5.0
    while any(alive(w) for w in workers) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert not any(alive(w) for w in workers), [w for w in workers if alive(w)]


def test_workers_die_with_a_killed_caller():
    p = start("processes")
    time.sleep(2.0)
    workers = descendants(p.pid)
    assert len(workers) >= 2, workers
    p.kill()  # SIGKILL: the caller cannot clean up
    p.communicate(timeout=30)
    deadline = time.monotonic() + 5.0
    while any(alive(w) for w in workers) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert not any(alive(w) for w in workers), [w for w in workers if alive(w)]


def test_ctrl_c_stops_a_batch_on_dask():
    pytest.importorskip("distributed")
    p = start("dask")
    r, sent, _ = interrupt(p, 3.0)
    check_interrupted(r, sent)
