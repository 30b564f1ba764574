"""Where a Newton iteration's time goes on the six-storey building: instruction counts (callgrind).

Counts instructions instead of timing them (a shared machine's clock moves by 10-20 % from run to
run; the instruction count of a run does not): nvib's Newmark + full Newton through the headers
(benchmarks/cpp/building_nvib.cpp, `--only=newmark`) and the hand-written Newton loop with a
tridiagonal solve (benchmarks/cpp/building_newton_loop.cpp), both built with the Release flags plus
-g, run for dt = 1e-4 s to 0.5 s (5,000 steps) under `valgrind --tool=callgrind`. Reports the
instructions per Newton iteration of each and nvib's functions by their own instructions (the
program's start and the libraries' loading subtracted with a run of zero steps).

    python benchmarks/profile_building.py        # writes benchmarks/results/profile_building.md

Needs valgrind (callgrind_annotate); without it the script says so and stops.
"""

from __future__ import annotations

import argparse
import datetime
import os
import re
import shutil
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from building import CXXFLAGS, ROOT, cpu_name, eigen_include, git_revision  # noqa: E402

DT, T_END = 1e-4, 0.5


def compile_all(tmp: str, cxx: str) -> dict:
    out = {}
    for name, extra in (("building_newton_loop", []),
                        ("building_nvib", ["-I", os.path.join(ROOT, "cpp", "include"), "-I", eigen_include()])):
        exe = os.path.join(tmp, name)
        subprocess.run([cxx, *CXXFLAGS, "-g", *extra, os.path.join(HERE, "cpp", name + ".cpp"), "-o", exe], check=True)
        out[name] = exe
    return out


def callgrind(args: list[str], tmp: str, tag: str, inclusive: bool = False) -> tuple[int, str, str]:
    """(total instructions, callgrind_annotate's report (by own or inclusive cost), the program's stdout)."""
    out = os.path.join(tmp, f"cg.{tag}")
    p = subprocess.run(["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}", *args],
                       capture_output=True, text=True, check=True)
    m = re.search(r"refs:\s+([\d,]+)", p.stderr)
    total = int(m.group(1).replace(",", ""))
    ann = subprocess.run(["callgrind_annotate", f"--inclusive={'yes' if inclusive else 'no'}", out], capture_output=True, text=True, check=True).stdout
    return total, ann, p.stdout


def top_functions(annotate: str, count: int) -> list[tuple[int, str]]:
    rows = []
    for line in annotate.splitlines():
        m = re.match(r"\s*([\d,]+) \([ \d.]+%\)\s+(.*)$", line)
        if not m or "PROGRAM TOTALS" in line:
            continue
        rows.append((int(m.group(1).replace(",", "")), m.group(2)))
    return rows[:count]


def short(name: str) -> str:
    """A function's file and name, without template arguments and paths."""
    file, _, fn = name.partition(":")
    file = os.path.relpath(file, ROOT) if file.startswith(ROOT) else os.path.basename(file)
    fn = re.sub(r"\s*\[.*\]$", "", fn)
    for _ in range(6):
        fn = re.sub(r"<[^<>]*>", "", fn)
    fn = re.sub(r"\(.*", "", fn)
    return f"`{fn}` ({file})"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cxx", default=os.environ.get("CXX", "g++"))
    ap.add_argument("--out", default=os.path.join(HERE, "results", "profile_building.md"))
    args = ap.parse_args()
    if shutil.which("valgrind") is None or shutil.which("callgrind_annotate") is None:
        raise SystemExit("valgrind is not installed: no profile")
    with tempfile.TemporaryDirectory() as tmp:
        exe = compile_all(tmp, args.cxx)
        steps = round(T_END / DT)
        # nvib: one run of `steps` steps, less a run of zero steps (start-up, loading, model building)
        nvib_args = [exe["building_nvib"], repr(DT), "{t}", "1", "0.45", "10", "--implicit", "--only=newmark"]
        full, ann, out = callgrind([a.format(t=repr(T_END)) for a in nvib_args], tmp, "nvib")
        base, _, out0 = callgrind([a.format(t=repr(DT)) for a in nvib_args], tmp, "nvib0")
        iters = int(re.search(r'"newton_iters": (\d+)', out).group(1))
        iters0 = int(re.search(r'"newton_iters": (\d+)', out0).group(1))
        # bench() runs `repeats` (here 1) solves, no warm-up
        per_it_nvib = (full - base) / (iters - iters0)
        # the loop: four variants (Newmark and generalized-alpha, dense LU and tridiagonal), each a
        # warm-up and one repeat; the tridiagonal ones' run<true>, with what it calls (inclusive)
        loop_full, loop_ann, loop_out = callgrind([exe["building_newton_loop"], repr(DT), repr(T_END), "1", "10"], tmp, "loop",
                                                  inclusive=True)
        nvib_top = top_functions(ann, 14)
    loop_rows = top_functions(loop_ann, 60)
    tri = max(n for n, name in loop_rows if "run<true>" in name)  # inclusive: with what it calls
    loop_iters = [int(x) for x in re.findall(r'"newton_iters": (\d+)', loop_out)]
    loop_tri_iters = sum(loop_iters[1::2]) * 2 if len(loop_iters) >= 4 else None
    lines = ["# Where the Newton iteration's time goes: the building, nvib against the hand-written loop", "",
             f"Written by `benchmarks/profile_building.py`. {datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC; "
             f"{cpu_name()}; git {git_revision()}; `{args.cxx} {' '.join(CXXFLAGS)} -g`; valgrind callgrind "
             "(instructions executed, the same on any run of the program).", "",
             f"Scene `building` (6 DOFs, hardening storey springs, ground acceleration), Newmark (average acceleration) + "
             f"full Newton, dt = {DT} s, {steps:,} steps.", ""]
    lines += ["| program | Newton iterations (one run) | instructions per iteration |", "|---|---:|---:|",
              f"| nvib (headers, `nvib::solve`) | {iters:,} | {per_it_nvib:.0f} |"]
    if loop_tri_iters:
        per_it_loop = tri / loop_tri_iters
        lines.append(f"| hand-written loop, tridiagonal solve (`run<true>`) | {loop_iters[1]:,} | {per_it_loop:.0f} |")
        lines += ["", f"nvib / loop: **{per_it_nvib / per_it_loop:.2f}x** the instructions per iteration. Instructions "
                  "are not time: the same two programs' times per iteration are in `implicit.md` (there the ratio is "
                  "smaller: nvib's extra instructions are bookkeeping that runs beside the loop's chain of dependent "
                  "floating-point operations, the factorisation's and the substitutions')."]
    lines += ["", "nvib's functions by their own instructions over the run (start-up included; each function's "
              "inlined callees are counted in it):", "",
              "| instructions | share of the run | function (file) |", "|---:|---:|---|"]
    for n, name in nvib_top:
        lines.append(f"| {n:,} | {100 * n / full:.1f} % | {short(name)} |")
    text = "\n".join(lines) + "\n"
    with open(args.out, "w") as f:
        f.write(text)
    print(text)


if __name__ == "__main__":
    main()
