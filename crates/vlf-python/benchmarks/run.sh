#!/usr/bin/env bash
# The Python benchmarks of docs/benchmarks/python.md: installs the package and the contestants
# (trimesh with embreex, Open3D) in the test environment (crates/vlf-python/run-tests.sh makes it),
# then prints the tables.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../../.." && pwd)"
venv="${VLF_PY_VENV:-$root/target/pyvenv}"
if [ ! -x "$venv/bin/python" ]; then
    python3 -m venv "$venv"
fi
"$venv/bin/python" -m pip install -q --disable-pip-version-check maturin numpy trimesh embreex open3d
"$venv/bin/python" -m pip install -q --disable-pip-version-check --force-reinstall --no-deps "$here/.."
cd "$root"
exec "$venv/bin/python" "$here/bench.py"
