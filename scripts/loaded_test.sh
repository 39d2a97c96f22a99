#!/usr/bin/env bash
# Run a test command while other processes keep every core busy (issue 16: the suite must
# pass on a loaded machine; its waits are conditions, never fixed sleeps).
#
#   scripts/loaded_test.sh [-n BUSY] [COMMAND ...]
#
# Starts BUSY busy-loop processes (default: the number of cores, `nproc`), runs COMMAND
# (default: the browser tests and the app tests with the project's .venv), stops the busy
# processes (also on Ctrl-C or failure) and exits with COMMAND's status.
set -euo pipefail
cd "$(dirname "$0")/.."

busy=$(nproc)
if [[ "${1:-}" == "-n" ]]; then
    busy=$2
    shift 2
fi
if [[ $# -eq 0 ]]; then
    set -- .venv/bin/python -m pytest -q -p no:cacheprovider tests/browser tests/test_app_*.py
fi

pids=()
stop_busy() {
    for pid in "${pids[@]}"; do
        kill "$pid" 2>/dev/null || true
    done
    for pid in "${pids[@]}"; do
        wait "$pid" 2>/dev/null || true
    done
}
trap stop_busy EXIT

for _ in $(seq "$busy"); do
    python3 -c 'while True: pass' &
    pids+=("$!")
done
echo "loaded_test: $busy busy-loop process(es) (${pids[*]}) on $(nproc) core(s); running: $*"
status=0
"$@" || status=$?
echo "loaded_test: exit status $status"
exit "$status"
