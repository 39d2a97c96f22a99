#!/usr/bin/env bash
# Install everything the project needs on a fresh machine, then run lint and the whole
# test suite. Usage: bash scripts/test.sh [extra pytest arguments]
set -euo pipefail
cd "$(dirname "$0")/.."

# Debian's chromium drives the real-browser tests (playwright cannot download its own here).
if ! command -v chromium >/dev/null 2>&1 && [ ! -x /usr/bin/chromium ]; then
  if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
    echo "== installing chromium (apt)"
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium chromium-driver >/dev/null
  else
    echo "== no system chromium: trying 'playwright install chromium' after the Python install"
    NEED_PW_BROWSER=1
  fi
fi

. scripts/find_python.sh
if [ ! -x .venv/bin/python ]; then
  echo "== creating .venv"
  "$PY" -m venv .venv
fi
echo "== installing the project and its test dependencies"
.venv/bin/python -m pip install -q --upgrade pip
.venv/bin/python -m pip install -q -e ".[test]"
if [ "${NEED_PW_BROWSER:-0}" = 1 ]; then .venv/bin/playwright install chromium; fi

# One BLAS thread per process: the tests' many small dense solves gain nothing from
# threading, and on 2 cores with numba kernels beside them threads only oversubscribe.
export OPENBLAS_NUM_THREADS="${OPENBLAS_NUM_THREADS:-1}" OMP_NUM_THREADS="${OMP_NUM_THREADS:-1}"

echo "== ruff"
.venv/bin/ruff check .
.venv/bin/ruff format --check .
echo "== mypy (strict on fbs_core, lighter on app; see [tool.mypy] in pyproject.toml)"
.venv/bin/python -m mypy
echo "== pytest"
exec .venv/bin/python -m pytest "$@"
