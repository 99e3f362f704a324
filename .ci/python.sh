#!/usr/bin/env bash
# Python bindings: builds the `fathom` wheel (maturin, abi3) into a fresh virtual
# environment and runs the pytest suite in python/tests against it (the tests also
# run the real `fathom` binary, built here first).
#
# Needs only a Rust toolchain and CPython >= 3.9 with pip (and the venv module, or
# virtualenv from PyPI when the interpreter lacks it); PyPI must be reachable unless
# PIP_FIND_LINKS points at wheels of maturin, pytest, numpy and filterpy.
# Called from .ci/run after the Rust tests; runnable on its own: bash .ci/python.sh
set -euo pipefail
cd "$(dirname "$0")/.."

PYTHON="${PYTHON:-python3}"
ROOT="$(pwd)"
VENV="$(realpath -m "${FATHOM_PY_VENV:-target/python-venv}")"
TARGET_DIR="$(realpath -m "${CARGO_TARGET_DIR:-target}")"

echo "== python: $("$PYTHON" --version 2>&1)"
"$PYTHON" - <<'PY'
import sys
if sys.version_info < (3, 9):
    sys.exit(f"fathom's Python bindings need CPython >= 3.9, found {sys.version.split()[0]}")
PY

echo "== python: virtual environment ${VENV}"
rm -rf "${VENV}"
if ! "$PYTHON" -m venv "${VENV}" 2>/dev/null; then
  # Debian's python3 without python3-venv: ensurepip is missing; use virtualenv.
  echo "python -m venv is unavailable; using virtualenv from PyPI"
  rm -rf "${VENV}"
  "$PYTHON" -m pip install --quiet --user virtualenv \
    || "$PYTHON" -m pip install --quiet --user --break-system-packages virtualenv
  "$PYTHON" -m virtualenv --quiet "${VENV}"
fi
PY="${VENV}/bin/python"
# the maturin build backend runs the `maturin` executable of the environment
export PATH="${VENV}/bin:${PATH}"
"$PY" -m pip install --quiet --upgrade pip
"$PY" -m pip install --quiet maturin pytest numpy filterpy

echo "== python: the fathom binary the tests compare against"
cargo build --release --quiet -p fathom-cli --bin fathom
export FATHOM_BIN="${TARGET_DIR}/release/fathom"
test -x "${FATHOM_BIN}"

echo "== python: build and install the wheel (pip install ./python)"
# --no-build-isolation: use the maturin installed above (pip would otherwise fetch
# it again into an isolated build environment).
"$PY" -m pip install --no-build-isolation ./python

echo "== python: pytest"
# from the repository root: no `fathom` Python package there, so the import finds the
# installed wheel
"$PY" -c "import fathom; print('fathom', fathom.__version__, 'from', fathom.__file__)"
"$PY" -m pytest -q -p no:cacheprovider python/tests
echo "python done"
