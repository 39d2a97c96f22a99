# Sourced by the set-up scripts: sets PY to an interpreter of Python 3.12 or newer.
# Order: $PYTHON if set; python3.13, python3.12, python3 on PATH; then pyenv's installed
# versions (pyenv's shims answer only for the global version). Fails with a message naming
# what was found when none is 3.12+.
fbs_py_ok() { "$1" -c 'import sys; sys.exit(sys.version_info < (3, 12))' >/dev/null 2>&1; }
fbs_find_python() {
    local c
    if [ -n "${PYTHON:-}" ]; then
        if fbs_py_ok "$PYTHON"; then PY=$PYTHON; return 0; fi
        echo "PYTHON=$PYTHON is not Python 3.12 or newer" >&2
        return 1
    fi
    for c in python3.13 python3.12 python3; do
        if command -v "$c" >/dev/null 2>&1 && fbs_py_ok "$c"; then PY=$(command -v "$c"); return 0; fi
    done
    for c in "${PYENV_ROOT:-$HOME/.pyenv}"/versions/3.1[2-9]*/bin/python3; do
        if [ -x "$c" ] && fbs_py_ok "$c"; then PY=$c; return 0; fi
    done
    echo "tire-fbs needs Python 3.12 or newer; found: $(python3 --version 2>&1)." >&2
    echo "Install python3.12 (or set PYTHON=/path/to/python3.12) and run this again." >&2
    return 1
}
fbs_find_python
# A .venv made by an older interpreter is made again (the project needs 3.12+).
if [ -x .venv/bin/python ] && ! fbs_py_ok .venv/bin/python; then
    echo "== .venv has $(.venv/bin/python --version 2>&1): making it again with $("$PY" --version)"
    rm -rf .venv
fi
