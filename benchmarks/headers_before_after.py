"""The building scene's explicit steps through nvib's C++ headers at two revisions, beside the hand-written loop:
did a change of the headers make a step slower?

    python benchmarks/headers_before_after.py --before REV [--after WORKTREE] [--rounds 7]
                                              [--out benchmarks/results/headers_before_after.md]

Compiles benchmarks/cpp/building_nvib.cpp against the headers of git revision REV (extracted with
``git archive``) and against the working tree's, and benchmarks/cpp/building_loop.cpp (the
hand-written loop), all with g++ -std=c++17 -O3 -DNDEBUG; runs the three programs in turn, ROUNDS
rounds of 10 runs each (dt = 1e-4 s, 10 s: 100,000 steps, save_every 10 and 1), and prints the best
time of each with the ratios nvib / hand-written before and after (the hand-written loop's "best"
column, its output buffer reused). The functor rows of building_nvib (the hand-written force inside
nvib's loop) are left out: they do not go through the effects.
"""

from __future__ import annotations

import argparse
import collections
import datetime
import json
import os
import platform
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.path.insert(0, HERE)


def eigen_include() -> str:
    from building import eigen_include as find  # the same lookup as the building benchmark

    return find()


def compile_program(src: str, out: str, includes: list[str]) -> None:
    cmd = ["g++", "-std=c++17", "-O3", "-DNDEBUG", *[f"-I{i}" for i in includes], src, "-o", out]
    subprocess.run(cmd, check=True)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--before", required=True, help="git revision whose headers are 'before'")
    ap.add_argument("--rounds", type=int, default=7)
    ap.add_argument("--out", default=os.path.join(HERE, "results", "headers_before_after.md"))
    args = ap.parse_args(argv)
    eigen = eigen_include()
    with tempfile.TemporaryDirectory() as tmp:
        old = os.path.join(tmp, "old")
        os.makedirs(old)
        archive = subprocess.run(["git", "-C", ROOT, "archive", args.before, "cpp/include", "benchmarks/cpp"],
                                 check=True, capture_output=True).stdout
        subprocess.run(["tar", "-x", "-C", old], input=archive, check=True)
        exes = {"hand": os.path.join(tmp, "loop"), "before": os.path.join(tmp, "nvib_before"),
                "after": os.path.join(tmp, "nvib_after")}
        compile_program(os.path.join(HERE, "cpp", "building_loop.cpp"), exes["hand"], [os.path.join(HERE, "cpp")])
        compile_program(os.path.join(old, "benchmarks", "cpp", "building_nvib.cpp"), exes["before"],
                        [os.path.join(old, "cpp", "include"), eigen, os.path.join(old, "benchmarks", "cpp")])
        compile_program(os.path.join(HERE, "cpp", "building_nvib.cpp"), exes["after"],
                        [os.path.join(ROOT, "cpp", "include"), eigen, os.path.join(HERE, "cpp")])
        best = collections.defaultdict(lambda: float("inf"))
        for _ in range(args.rounds):
            for name, exe in exes.items():
                out = subprocess.run([exe, "1e-4", "10", "10", "0.45", "10", "1"], capture_output=True, text=True,
                                     check=True).stdout
                for line in out.splitlines():
                    row = json.loads(line)
                    if not row["scheme"].endswith("functor"):
                        key = (name, row["scheme"], row["save_every"])
                        best[key] = min(best[key], row["best"])
    rev = subprocess.run(["git", "-C", ROOT, "rev-parse", "--short", args.before], capture_output=True,
                         text=True).stdout.strip()
    head = subprocess.run(["git", "-C", ROOT, "describe", "--always", "--dirty"], capture_output=True,
                          text=True).stdout.strip()
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    lines = [f"# The building's explicit steps: nvib's headers at {rev} and at {head}, against the hand-written loop",
             "",
             f"- date: {datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC; {platform.processor() or platform.machine()}, "
             f"{os.cpu_count()} CPUs; 1-minute load average {load:.2f} at the end",
             "- g++ -std=c++17 -O3 -DNDEBUG; benchmarks/cpp/building_nvib.cpp (the scene `building` from effects) and "
             "benchmarks/cpp/building_loop.cpp (the hand-written loop, its output reused)",
             f"- dt = 1e-4 s, 10 s = 100,000 steps; best of {args.rounds} rounds x 10 runs, the programs in turn",
             "",
             "| scheme | save_every | hand-written [ms] | nvib before [ms] | nvib after [ms] | before / hand | after / hand |",
             "|---|---:|---:|---:|---:|---:|---:|"]
    for scheme in ("cd", "cemdts", "zhai"):
        for k in (10, 1):
            h, b, a = (best[(n, scheme, k)] for n in ("hand", "before", "after"))
            lines.append(f"| {scheme} | {k} | {h * 1e3:.2f} | {b * 1e3:.2f} | {a * 1e3:.2f} | {b / h:.2f} | {a / h:.2f} |")
    text = "\n".join(lines) + "\n"
    print(text)
    with open(args.out, "w", encoding="utf-8") as fh:
        fh.write(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
