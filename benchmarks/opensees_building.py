"""OpenSees alone on nvib's "building" scene: the OpenSees-only mode of benchmarks/opensees.py.

Kept for benchmarks/implicit.py, which runs this file and reads its JSON lines;
the model, the schemes and OpenSees' conventions are described in
benchmarks/opensees.py. The same command line as

    python benchmarks/opensees.py --opensees-only --json ...

with the NormUnbalance test (max-norm of the unbalanced force <= 1e-6 N) by
default, as the OpenSees rows of benchmarks/results/implicit.md were measured:

    python benchmarks/opensees_building.py --json [--dt 1e-4] [--t-end 10] [--repeats 3]
                                                  [--schemes newmark,galpha,hht] [--test unbalance]
                                                  [--history] [--check] [--no-iterations]

As a module it gives opensees_env(), run(), check_inputs() of benchmarks/opensees.py.
"""

from __future__ import annotations

import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from opensees import (SCHEMES, TESTS, check_inputs, opensees_env, opensees_lib_dir,  # noqa: E402,F401
                      opensees_only_main, run)

__all__ = ["SCHEMES", "TESTS", "check_inputs", "opensees_env", "opensees_lib_dir", "opensees_only_main", "run"]

if __name__ == "__main__":
    sys.exit(opensees_only_main(sys.argv[1:], default_test="unbalance"))
