#!/usr/bin/env bash
# Make a wheelhouse for the offline Docker build (docs/deployment.md, "Offline build").
#
# Run on a host that can reach the package index (directly or through the proxy configured in
# pip's own settings); the image is then built with
#   docker build --build-arg WHEELHOUSE=wheelhouse -t tire-fbs .
# and pip inside the build never contacts an index (`--no-index --find-links`).
#
# The wheels are chosen for the image's interpreter, not the host's: CPython 3.12 on
# glibc Linux (the official python:3.12-slim-bookworm image), binary wheels only, so the
# host may run another Python version. Versions are pinned to the host environment's
# (`pip freeze` of $PYTHON) when that has the packages, so the image runs what was tested.
#
# Usage: scripts/make_wheelhouse.sh [OUTDIR]      (default OUTDIR: wheelhouse)
# Environment: PYTHON (default .venv/bin/python, else python3), WHEELHOUSE_PY (3.12),
#   WHEELHOUSE_ARCH (uname -m), WHEELHOUSE_PIN (1: pin to $PYTHON's versions; 0: newest),
#   WHEELHOUSE_EXTRA (extra requirements, space separated, e.g. "cryptography" for OAuth).
set -euo pipefail
cd "$(dirname "$0")/.."

out=${1:-wheelhouse}
if [[ -z "${PYTHON:-}" ]]; then
    if [[ -x .venv/bin/python ]]; then PYTHON=.venv/bin/python; else PYTHON=python3; fi
fi
py=${WHEELHOUSE_PY:-3.12}
arch=${WHEELHOUSE_ARCH:-$(uname -m)}
pin=${WHEELHOUSE_PIN:-1}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

# Runtime dependencies and the build backend, read from pyproject.toml.
"$PYTHON" - > "$tmp/requirements.txt" <<'PY'
import tomllib

with open("pyproject.toml", "rb") as f:
    meta = tomllib.load(f)
for req in meta["project"]["dependencies"] + meta["build-system"]["requires"] + ["wheel"]:
    print(req)
PY
for extra in ${WHEELHOUSE_EXTRA:-}; do echo "$extra" >> "$tmp/requirements.txt"; done

constraint_args=()
if [[ "$pin" == 1 ]]; then
    "$PYTHON" -m pip freeze --exclude-editable 2>/dev/null \
        | grep -E '^[A-Za-z0-9_.-]+==' > "$tmp/constraints.txt" || true
    if [[ -s "$tmp/constraints.txt" ]]; then
        constraint_args=(--constraint "$tmp/constraints.txt")
    fi
fi

# Bookworm has glibc 2.36: accept every manylinux tag up to that (pip does not widen them).
platform_args=(--platform "manylinux2014_${arch}" --platform "manylinux2010_${arch}")
for minor in $(seq 36 -1 5); do platform_args+=(--platform "manylinux_2_${minor}_${arch}"); done

mkdir -p "$out"
start=$(date +%s)
"$PYTHON" -m pip download --quiet --dest "$out" \
    --only-binary=:all: --implementation cp --python-version "$py" \
    "${platform_args[@]}" \
    "${constraint_args[@]}" --requirement "$tmp/requirements.txt"
echo "wheelhouse: $(ls "$out"/*.whl | wc -l) wheels in $out ($(du -sh "$out" | cut -f1)," \
     "$(( $(date +%s) - start )) s; pinned=$pin, python $py, $arch)"
