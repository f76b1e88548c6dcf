#!/usr/bin/env bash
# Builds and installs the `vlf` Python package into a virtual environment of its own, with what
# its tests compare against, and runs the tests. Fails if anything fails.
#
#   crates/vlf-python/run-tests.sh [pytest arguments]
#
# The environment (default `target/pyvenv`, or $VLF_PY_VENV) is created with `python3 -m venv`
# (or $PYTHON) on first use and reused after. It gets numpy, pytest, trimesh and embreex from
# PyPI, and Open3D if it installs for this Python (set VLF_PY_OPEN3D=0 to skip it; its tests are
# then skipped). The package is installed the way a user installs it, `pip install
# crates/vlf-python` (maturin builds the extension with cargo, in the release profile, as a user's
# install does; $VLF_PY_PROFILE picks another, such as `dev`).
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
venv="${VLF_PY_VENV:-$root/target/pyvenv}"
python="${PYTHON:-python3}"
profile="${VLF_PY_PROFILE:-release}"

if [ ! -x "$venv/bin/python" ]; then
    echo "python: creating the virtual environment $venv"
    "$python" -m venv "$venv"
fi
pip=("$venv/bin/python" -m pip --disable-pip-version-check)
"${pip[@]}" install -q --upgrade pip
"${pip[@]}" install -q maturin pytest numpy trimesh rtree
"${pip[@]}" install -q embreex || echo "python: embreex did not install; trimesh's Embree comparisons are skipped"
if [ "${VLF_PY_OPEN3D:-1}" != 0 ]; then
    "${pip[@]}" install -q open3d || echo "python: open3d did not install; its comparisons are skipped"
    # Open3D's wheel links system libraries a minimal machine may lack (libusb first of all). As
    # root with apt, install them; otherwise, or if it still does not import, remove it, so that
    # its comparisons are skipped instead of failing on the import.
    o3d_imports() { "$venv/bin/python" -c "import open3d" >/dev/null 2>&1; }
    if "${pip[@]}" show -q open3d >/dev/null 2>&1 && ! o3d_imports; then
        if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null; then
            echo "python: open3d does not import; installing the system libraries it links"
            apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq \
                libusb-1.0-0 libgomp1 libgl1 >/dev/null || true
        fi
        if ! o3d_imports; then
            echo "python: open3d does not import here ($("$venv/bin/python" -c "import open3d" 2>&1 | tail -n 1)); its comparisons are skipped"
            "${pip[@]}" uninstall -q -y open3d
        fi
    fi
fi

echo "python: building and installing crates/vlf-python (cargo profile $profile)"
MATURIN_PEP517_ARGS="--profile $profile" "${pip[@]}" install -q --force-reinstall --no-deps "$here"

# From the tests' directory, so that `import vlf` finds the installed package, not the sources.
cd "$here/tests"
exec "$venv/bin/python" -m pytest -q -p no:cacheprovider -p no:dash "$@"
