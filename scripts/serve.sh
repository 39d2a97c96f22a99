#!/usr/bin/env bash
# Start the dashboard on the shipped reference data (the README's "start the dashboard on a
# fresh machine" command). Creates .venv if missing, installs the project if fbs_core is not
# importable, then runs `panel serve app/main.py` through the container's entrypoint
# (docker/entrypoint.py: cheap /liveness, throttled logins, prompt exit on Ctrl-C) and prints
# the URL. The FBS_* variables of docs/deployment.md apply (e.g. FBS_BASIC_AUTH for a login).
#
# Environment: PORT (5006), ADDRESS (localhost; 0.0.0.0 to listen on all interfaces),
# NUM_THREADS (4: one session's long computation does not block the others),
# PYTHON (an interpreter of Python 3.12+; found on PATH or among pyenv's versions), SHOW=1 to open a browser (only where there is a display), WS_MAX_MB
# (200: largest websocket message, i.e. upload, in MB).
# Serving to other machines: ADDRESS=0.0.0.0 and BOKEH_ALLOW_WS_ORIGIN=<host>:<port> (the
# address the browsers use), or pass --allow-websocket-origin <host>:<port>.
# Extra arguments are passed to `panel serve`.
set -euo pipefail
cd "$(dirname "$0")/.."

. scripts/find_python.sh
PORT=${PORT:-5006}
ADDRESS=${ADDRESS:-localhost}
NUM_THREADS=${NUM_THREADS:-4}

if [ ! -x .venv/bin/python ]; then
  echo "== creating .venv"
  "$PY" -m venv .venv
fi
if ! .venv/bin/python -c "import fbs_core, panel, bokeh, pyuff" >/dev/null 2>&1; then
  echo "== installing the project into .venv"
  .venv/bin/python -m pip install -q --upgrade pip
  .venv/bin/python -m pip install -q -e .
fi

HOST=$ADDRESS
if [ "$HOST" = "0.0.0.0" ]; then HOST=localhost; fi

SHOW_ARG=()
if [ "${SHOW:-0}" = 1 ] && { [ -n "${DISPLAY:-}" ] || [ "$(uname)" = Darwin ]; }; then
  SHOW_ARG=(--show)
fi
# The server listens within seconds; right after, it builds one page on a thread of its own
# (docker/fbs_server.py: the app's proof, which loads the reference models, compiles the
# kernels and caches the first page's results), so the first visitor need not wait for a
# warm-up before the port opens (issue 33; Panel's --warm ran it before listening: 23.6 s).
# uploads travel base64-encoded in one websocket message: 200 MB carries files up to
# 150 MB, so a file above fbs_core's 100 MiB limit is refused with a message (Bokeh's
# default of 20 MB would close the connection on files above 15 MB)
WS_MAX_MB=${WS_MAX_MB:-135}
FBS_APP=app/main.py FBS_PORT=$PORT FBS_ADDRESS=$ADDRESS FBS_NUM_THREADS=$NUM_THREADS \
  FBS_WEBSOCKET_MAX_MESSAGE_MB=$WS_MAX_MB \
  .venv/bin/python docker/entrypoint.py "${SHOW_ARG[@]}" "$@" &
SERVER=$!
# Ctrl-C reaches the server too (same process group); a TERM sent to this script is passed on
trap 'kill -TERM "$SERVER" 2>/dev/null; wait "$SERVER"; exit 143' TERM
# the URL once the app is proved (/liveness 200: the server's own page of it built and
# loaded, within a few seconds of the port opening); a page opened earlier goes first, the
# proof steps aside until it is shown (docker/page_gate.py)
until .venv/bin/python -c 'import sys, urllib.request
urllib.request.urlopen(f"http://{sys.argv[1]}:{sys.argv[2]}/liveness?endpoint=/main", timeout=2)' \
  "$HOST" "$PORT" 2>/dev/null; do
  if ! kill -0 "$SERVER" 2>/dev/null; then
    wait "$SERVER"
    exit $?
  fi
  sleep 0.5
done
echo "== dashboard ready: http://${HOST}:${PORT}/main   (Ctrl-C stops it)"
wait "$SERVER"
