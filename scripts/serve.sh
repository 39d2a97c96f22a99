#!/usr/bin/env bash
# Start the dashboard on the shipped reference data (the README's "start the dashboard on a
# fresh machine" command). Creates .venv if missing, installs the project if fbs_core is not
# importable, then runs `panel serve app/main.py` through the container's entrypoint
# (docker/entrypoint.py: cheap /liveness, throttled logins, prompt exit on Ctrl-C) and prints
# the URL. The FBS_* variables of docs/deployment.md apply (e.g. FBS_BASIC_AUTH for a login).
#
# Environment: PORT (5006), ADDRESS (localhost; 0.0.0.0 to listen on all interfaces),
# NUM_THREADS (4: one session's long computation does not block the others),
# PYTHON (python3), SHOW=1 to open a browser (only where there is a display), WS_MAX_MB
# (200: largest websocket message, i.e. upload, in MB).
# Serving to other machines: ADDRESS=0.0.0.0 and BOKEH_ALLOW_WS_ORIGIN=<host>:<port> (the
# address the browsers use), or pass --allow-websocket-origin <host>:<port>.
# Extra arguments are passed to `panel serve`.
set -euo pipefail
cd "$(dirname "$0")/.."

PY=${PYTHON:-python3}
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
echo "== dashboard: http://${HOST}:${PORT}/main   (Ctrl-C stops it)"

SHOW_ARG=()
if [ "${SHOW:-0}" = 1 ] && { [ -n "${DISPLAY:-}" ] || [ "$(uname)" = Darwin ]; }; then
  SHOW_ARG=(--show)
fi
# --warm runs the page once at start-up: the reference models are loaded, the compiled
# kernels and the truncation maps cached, so the first visitor sees plots within seconds.
echo "== warming up (reference models, truncation maps, default scatter band) ..."
# uploads travel base64-encoded in one websocket message: 200 MB carries files up to
# 150 MB, so a file above fbs_core's 100 MiB limit is refused with a message (Bokeh's
# default of 20 MB would close the connection on files above 15 MB)
WS_MAX_MB=${WS_MAX_MB:-200}
FBS_APP=app/main.py FBS_PORT=$PORT FBS_ADDRESS=$ADDRESS FBS_NUM_THREADS=$NUM_THREADS \
  FBS_WEBSOCKET_MAX_MESSAGE_MB=$WS_MAX_MB \
  exec .venv/bin/python docker/entrypoint.py --warm "${SHOW_ARG[@]}" "$@"
