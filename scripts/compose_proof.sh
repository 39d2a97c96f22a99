#!/usr/bin/env bash
# End-to-end proof of the compose deployment (docker/compose.yaml): the dashboard, a Dask
# scheduler and two Dask workers from the project's image. CI runs it after
# scripts/docker_proof.sh (which builds and keeps the image).
#
#  1. installs docker.io and a compose tool with apt-get when missing (needs root): the
#     `docker compose` plugin when present, else `docker-compose` (Debian's package);
#  2. starts dockerd in the background when no daemon answers;
#  3. uses the image $FBS_IMAGE (default tire-fbs:proof); when it is missing, builds it
#     with scripts/docker_proof.sh (which also runs the single-container proof);
#  4. `up -d` of docker/compose.yaml under a project name of its own; waits for the
#     scheduler to see both workers and for the dashboard to be healthy, and checks that
#     the dashboard's app document builds (/liveness?endpoint=/main on the host port);
#  5. from the dashboard container (FBS_DASK_SCHEDULER points at the scheduler): runs a
#     campaign of one scatter case in 8 blocks on the cluster, checks that every block was
#     computed on a worker and that the band equals fbs_core.scatter_band with the case's
#     seed to 1e-12; runs campaigns/example.toml (mounted read-only) and lists its cases;
#     runs a corridor study (a [variants] table of 8 variants of a small tire: one task per
#     rebuilt tire) on the cluster and checks that every task ran on a worker and that its
#     responses equal fbs_core.variants.run_variants of the case's seed in the container;
#     checks that TLS is in force: the scheduler refuses a plain tcp:// client and a TLS
#     client without a certificate, and the dashboard refuses a plain remote scheduler;
#  6. `down` of the project and stops dockerd if it started it, also on failure or
#     interruption, and prints the timings.
#
# Environment: FBS_IMAGE (default tire-fbs:proof), FBS_PROOF_HEALTH_TIMEOUT (s, default 180).
set -euo pipefail
cd "$(dirname "$0")/.."

image=${FBS_IMAGE:-tire-fbs:proof}
health_timeout=${FBS_PROOF_HEALTH_TIMEOUT:-180}
project="fbsproof$$"
export PATH="$PATH:/usr/local/sbin:/usr/sbin:/sbin"
if [[ -x .venv/bin/python ]]; then PY=$(pwd)/.venv/bin/python; else PY=python3; fi

work=$(mktemp -d /tmp/compose-proof.XXXXXX)
dockerd_pid=""
compose=()
up=0
timings=()
t_start=$SECONDS

log() { printf '[compose-proof %4ds] %s\n' "$((SECONDS - t_start))" "$*"; }
fail() { log "FAILED: $*"; exit 1; }
timed() {
    local label=$1 t=$SECONDS
    shift
    "$@"
    timings+=("$(printf '%-52s %5d s' "$label" "$((SECONDS - t))")")
}
dc() { FBS_IMAGE="$image" FBS_PORT="$port" "${compose[@]}" -p "$project" -f docker/compose.yaml "$@"; }

cleanup() {
    local rc=$?
    trap - EXIT INT TERM
    set +e
    if [[ $up -eq 1 ]]; then
        if [[ $rc -ne 0 ]]; then
            log "logs of the services:"
            dc logs --no-color --tail 30 2>&1 | sed 's/^/    /'
        fi
        dc down --volumes --remove-orphans -t 10 >/dev/null 2>&1 && log "removed project $project (and its volume dask-tls)"
    fi
    if [[ -n "$dockerd_pid" ]]; then
        kill "$dockerd_pid" 2>/dev/null
        for _ in $(seq 1 30); do kill -0 "$dockerd_pid" 2>/dev/null || break; sleep 1; done
        kill -0 "$dockerd_pid" 2>/dev/null && kill -9 "$dockerd_pid"
        log "stopped dockerd (pid $dockerd_pid)"
    fi
    rm -rf "$work"
    echo "---- compose proof timings ----"
    printf '%s\n' "${timings[@]}"
    printf '%-52s %5d s\n' "total" "$((SECONDS - t_start))"
    if [[ $rc -eq 0 ]]; then echo "compose proof: OK"; else echo "compose proof: FAILED (exit $rc)"; fi
    exit "$rc"
}
trap cleanup EXIT
trap 'exit 130' INT TERM

install_tools() {
    local pkgs=()
    command -v dockerd >/dev/null || pkgs+=(docker.io)
    command -v docker >/dev/null || pkgs+=(docker.io)
    if ! docker compose version >/dev/null 2>&1 && ! command -v docker-compose >/dev/null; then
        pkgs+=(docker-compose)
    fi
    if [[ ${#pkgs[@]} -gt 0 ]]; then
        [[ $(id -u) -eq 0 ]] || fail "need root to install: ${pkgs[*]}"
        log "apt-get install ${pkgs[*]}"
        apt-get update -qq
        DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "${pkgs[@]}" >/dev/null
    fi
    if docker compose version >/dev/null 2>&1; then
        compose=(docker compose)
    else
        compose=(docker-compose)
    fi
    log "compose tool: ${compose[*]} ($("${compose[@]}" version 2>/dev/null | head -1))"
}

start_dockerd() {
    if docker info >/dev/null 2>&1; then
        log "using the running Docker daemon"
        return
    fi
    [[ $(id -u) -eq 0 ]] || fail "no Docker daemon answers and not root to start one"
    log "starting dockerd"
    dockerd >"$work/dockerd.log" 2>&1 &
    dockerd_pid=$!
    for _ in $(seq 1 60); do
        docker info >/dev/null 2>&1 && { log "dockerd ready (pid $dockerd_pid)"; return; }
        kill -0 "$dockerd_pid" 2>/dev/null || break
        sleep 1
    done
    tail -20 "$work/dockerd.log"
    fail "dockerd did not become ready"
}

ensure_image() {
    if docker image inspect "$image" >/dev/null 2>&1; then
        log "image $image present"
        return
    fi
    log "image $image missing: building it with scripts/docker_proof.sh"
    FBS_IMAGE="$image" FBS_PROOF_KEEP_IMAGE=1 bash scripts/docker_proof.sh
}

free_port() {
    "$PY" -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])'
}

compose_up() {
    dc up -d >"$work/up.log" 2>&1 || { cat "$work/up.log"; fail "compose up failed"; }
    up=1
    log "project $project up: $(dc ps --services 2>/dev/null | tr '\n' ' ')"
}

wait_cluster() {  # the scheduler sees both workers (asked from the dashboard container)
    dc exec -T dashboard python - <<'PY'
import os, time
from fbs_core.campaign.security import connect
c = connect(os.environ["FBS_DASK_SCHEDULER"], "120s")
c.wait_for_workers(2, timeout=180)
w = c.scheduler_info()["workers"]
print("    scheduler", c.scheduler.address, "workers:", sorted(v["name"] for v in w.values()))
c.close()
PY
}

wait_dashboard() {
    local cid status
    cid=$(dc ps -q dashboard)
    for _ in $(seq 1 "$health_timeout"); do
        status=$(docker inspect -f '{{.State.Status}} {{.State.Health.Status}}' "$cid")
        case "$status" in
            "running healthy") log "dashboard ${cid:0:12} healthy"; break ;;
            exited* | dead*) fail "dashboard: $status" ;;
        esac
        sleep 1
    done
    [[ "$status" == "running healthy" ]] || fail "dashboard not healthy after ${health_timeout} s"
    "$PY" scripts/wait_app_document.py "$port"
}

smoke_campaign() {  # one case in 8 blocks on the cluster; the band as scatter_band's
    dc exec -T dashboard sh -c 'cat > /tmp/smoke.toml' <<'TOML'
[campaign]
name = "compose-smoke"
seed = 11
output = "/tmp/smoke.h5"
[scatter]
harmonics = [1]
noise = [0.1]
targets = ["both"]
frequency_dependent = [true]
rounds = 400
[execution]
task_round_lines = 4000
TOML
    dc exec -T dashboard python -m fbs_core.campaign run /tmp/smoke.toml --quiet \
        | sed 's/^/    /'
    dc exec -T dashboard python - <<'PY'
import os
import h5py, numpy as np
import fbs_core
from fbs_core.campaign import open_campaign
from fbs_core.campaign.security import connect
res = open_campaign("/tmp/smoke.h5")
(case,) = res.cases
assert case.complete, case
c = connect(os.environ["FBS_DASK_SCHEDULER"], "60s")
workers = set(c.scheduler_info()["workers"])
c.close()
with h5py.File("/tmp/smoke.h5") as h:
    blocks = list(h["cases"][case.name]["blocks"].values())
    used = [str(b.attrs["worker"]) for b in blocks]
    secs = [float(b.attrs["seconds"]) for b in blocks]
assert len(used) == 8 and set(used) <= workers, (used, workers)
band = res.band(case.name)
direct = fbs_core.scatter_band(1, 0.1, "both", 400, True, seed=int(case.settings["seed"]))
for k in ("lower", "upper", "percentiles"):
    np.testing.assert_allclose(getattr(band, k), getattr(direct, k), rtol=1e-12, atol=0)
assert np.array_equal(band.argmax_round, direct.argmax_round)
print(f"    8 blocks on {len(set(used))} of {len(workers)} workers (task compute time "
      f"{min(secs):.2f}-{max(secs):.2f} s); band == scatter_band (1e-12)")
PY
}

example_campaign() {
    dc exec -T dashboard python -m fbs_core.campaign run /campaigns/example.toml \
        --output /tmp/example.h5 --quiet | grep -E "^(complete|campaign)" | sed 's/^/    /'
    local summary
    summary=$(dc exec -T dashboard python -m fbs_core.campaign summary /tmp/example.h5)
    [[ "$summary" == *"16 of 16 cases complete"* ]] || fail "example campaign incomplete"
}

variants_campaign() {  # a corridor study on the cluster == the same study in-process
    dc exec -T dashboard sh -c 'cat > /tmp/variants.toml' <<'TOML'
[campaign]
name = "compose-variants"
seed = 32
output = "/tmp/variants.h5"
[variants]
name = "smoke"
parameters = ["inflation_pressure", "tread_mass", "body_bushing_stiffness"]
design = "sobol"
n = 8
harmonics = [4]
speeds = [20.0, 40.0, 60.0, 80.0, 100.0, 120.0]
[variants.tire]
orders = [6, 3, 4, 3, -1, -1, -1, -1]
slip_zones = 1
TOML
    dc exec -T dashboard python -m fbs_core.campaign run /tmp/variants.toml --quiet \
        | sed 's/^/    /'
    dc exec -T dashboard python - <<'PY'
import os
import h5py, numpy as np
import fbs_core.variants as fv
from fbs_core.campaign import load_campaign, open_campaign
from fbs_core.campaign.security import connect
(case,) = load_campaign("/tmp/variants.toml").variants_cases
res = open_campaign("/tmp/variants.h5")
study = res.variants(case.name)
c = connect(os.environ["FBS_DASK_SCHEDULER"], "60s")
workers = set(c.scheduler_info()["workers"])
c.close()
with h5py.File("/tmp/variants.h5") as h:
    g = h["cases"][case.name]
    units = [g["nominal"], *g["tires"].values()]
    used = [str(u.attrs["worker"]) for u in units]
    assert g.attrs["seed"] == str(case.seed)
assert len(used) == 9 and set(used) <= workers, (used, workers)
ref = fv.run_variants(case.sample(), case.variant_settings())
a, b = study.responses[4], ref.responses[4]
np.testing.assert_allclose(a, b, rtol=1e-6, atol=1e-9 * np.abs(b).max())
print(f"    9 tasks (8 tires + nominal) on {len(set(used))} of {len(workers)} workers; "
      f"responses == run_variants (1e-6); corridor width up to "
      f"{study.corridor(4).width_db.max():.1f} dB")
PY
}

tls_in_force() {  # plain and certificate-less clients refused; the dashboard refuses plain
    dc exec -T dashboard python - <<'PY'
import os, socket, ssl
from distributed import Client
addr = os.environ["FBS_DASK_SCHEDULER"]
assert addr.startswith("tls://"), addr
plain = addr.replace("tls://", "tcp://")
try:
    Client(plain, timeout="10s").close()
    raise SystemExit(f"a plain client joined {plain}")
except (OSError, TimeoutError) as e:
    print(f"    plain {plain}: refused ({type(e).__name__})")
ctx = ssl.create_default_context(cafile=os.environ["FBS_DASK_TLS_DIR"] + "/ca.pem")
ctx.check_hostname = False
try:
    with socket.create_connection(("scheduler", 8786), 10) as raw, ctx.wrap_socket(raw) as t:
        t.settimeout(10)
        t.sendall(b"\0" * 16)
        assert t.recv(1) == b"", "the scheduler kept a client without a certificate"
except (ssl.SSLError, ConnectionError) as e:
    pass
print("    TLS client without a certificate: refused")
from fbs_core.campaign.security import InsecureScheduler, security_for
try:
    security_for(plain, {})
    raise SystemExit("plain tcp to the scheduler was allowed")
except InsecureScheduler:
    print("    the dashboard refuses plain tcp://scheduler:8786 (FBS_DASK_ALLOW_PLAIN unset)")
PY
}

timed "install tools (apt-get when missing)" install_tools
timed "Docker daemon" start_dockerd
timed "image $image" ensure_image
port=$(free_port)
timed "compose up" compose_up
timed "scheduler sees 2 workers (TLS)" wait_cluster
timed "TLS in force: plain and certificate-less clients refused" tls_in_force
timed "dashboard healthy + app document" wait_dashboard
timed "campaign in 8 blocks on the cluster == scatter_band" smoke_campaign
timed "campaigns/example.toml on the cluster" example_campaign
timed "corridor study ([variants]) on the cluster == in-process" variants_campaign
log "all checks passed"
