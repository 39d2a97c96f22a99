#!/usr/bin/env bash
# End-to-end proof that the Docker deployment works (CI runs it; docs/deployment.md).
#
#  1. installs docker.io and debootstrap with apt-get when missing (needs root), and
#     chromium for the browser test;
#  2. starts dockerd in the background when no daemon answers;
#  3. makes sure the base image python:3.12-slim-bookworm exists: pulled when a registry is
#     reachable, else a local stand-in (Debian bookworm minbase made with debootstrap,
#     `docker import`, the host's CPython 3.12 in /usr/local: docker/standin-base.Dockerfile);
#  4. makes the wheelhouse on the host (scripts/make_wheelhouse.sh) and builds the image with
#     the offline build path (--build-arg WHEELHOUSE=wheelhouse: pip uses no index);
#  5. runs the container on a loopback port, waits for Docker to report it healthy, checks
#     that the app document can be created (/liveness?endpoint=/main) and runs the browser
#     smoke test (docker/smoke_test.py: page renders, a slider change updates a plot);
#  6. runs a second container with basic authentication on (FBS_BASIC_AUTH): without
#     credentials only the login form, after logging in the same smoke test passes; the
#     cookie secret and the password appear neither in `docker top` nor in the environment
#     of the server process, and `docker stop` ends the container within its grace period;
#  7. stops everything it started, by container ID and PID (dockerd only if it started it),
#     also on failure or interruption, and prints the timings.
#
# Environment: FBS_IMAGE (image tag, default tire-fbs:proof), FBS_PROOF_CPUS (docker run
# --cpus, default 2), FBS_PROOF_HEALTH_TIMEOUT (s, default 180), FBS_PROOF_STANDIN
# (auto: pull, else stand-in | always | never), FBS_PROOF_KEEP_IMAGE (1 keeps the built
# image, default 1: later runs reuse its layers).
set -euo pipefail
cd "$(dirname "$0")/.."
repo=$(pwd)

image=${FBS_IMAGE:-tire-fbs:proof}
cpus=${FBS_PROOF_CPUS:-$(( $(nproc) < 2 ? $(nproc) : 2 ))}
health_timeout=${FBS_PROOF_HEALTH_TIMEOUT:-180}
standin=${FBS_PROOF_STANDIN:-auto}
base_image=python:3.12-slim-bookworm
export DOCKER_BUILDKIT=0   # the classic builder: no buildx plugin needed, same Dockerfile
export PATH="$PATH:/usr/local/sbin:/usr/sbin:/sbin"   # dockerd, debootstrap
if [[ -x .venv/bin/python ]]; then PY=$repo/.venv/bin/python; else PY=python3; fi

work=$(mktemp -d /tmp/docker-proof.XXXXXX)
containers=()
dockerd_pid=""
timings=()
t_start=$SECONDS

log() { printf '[docker-proof %4ds] %s\n' "$((SECONDS - t_start))" "$*"; }
fail() { log "FAILED: $*"; exit 1; }
timed() {  # timed "label" cmd...: run, record the duration
    local label=$1 t=$SECONDS
    shift
    "$@"
    timings+=("$(printf '%-44s %5d s' "$label" "$((SECONDS - t))")")
}

cleanup() {
    local rc=$?
    trap - EXIT INT TERM
    set +e
    for cid in "${containers[@]}"; do
        if [[ $rc -ne 0 ]]; then
            log "logs of container ${cid:0:12}:"
            docker logs --tail 40 "$cid" 2>&1 | sed 's/^/    /'
        fi
        docker rm -f "$cid" >/dev/null 2>&1 && log "removed container ${cid:0:12}"
    done
    if [[ "${FBS_PROOF_KEEP_IMAGE:-1}" != 1 ]]; then docker rmi "$image" >/dev/null 2>&1; fi
    if [[ -n "$dockerd_pid" ]]; then
        kill "$dockerd_pid" 2>/dev/null
        for _ in $(seq 1 30); do kill -0 "$dockerd_pid" 2>/dev/null || break; sleep 1; done
        kill -0 "$dockerd_pid" 2>/dev/null && kill -9 "$dockerd_pid"
        log "stopped dockerd (pid $dockerd_pid)"
    fi
    rm -rf "$work"
    echo "---- docker proof timings ----"
    printf '%s\n' "${timings[@]}"
    printf '%-44s %5d s\n' "total" "$((SECONDS - t_start))"
    if [[ $rc -eq 0 ]]; then echo "docker proof: OK"; else echo "docker proof: FAILED (exit $rc)"; fi
    exit "$rc"
}
trap cleanup EXIT
trap 'exit 130' INT TERM

install_tools() {
    local pkgs=()
    command -v dockerd >/dev/null || pkgs+=(docker.io)
    command -v docker >/dev/null || pkgs+=(docker.io)
    command -v debootstrap >/dev/null || pkgs+=(debootstrap)
    [[ -x /usr/bin/chromium ]] || pkgs+=(chromium)
    if [[ ${#pkgs[@]} -gt 0 ]]; then
        [[ $(id -u) -eq 0 ]] || fail "need root to install: ${pkgs[*]}"
        log "apt-get install ${pkgs[*]}"
        apt-get update -qq
        DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "${pkgs[@]}" >/dev/null
    fi
    "$PY" -c "import playwright" 2>/dev/null \
        || fail "playwright is not installed for $PY (pip install -e '.[test]')"
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

build_standin() {
    log "building the stand-in base image $base_image (debootstrap bookworm minbase)"
    [[ $(id -u) -eq 0 ]] || fail "debootstrap needs root"
    debootstrap --variant=minbase bookworm "$work/rootfs" >"$work/debootstrap.log" 2>&1 \
        || { tail -20 "$work/debootstrap.log"; fail "debootstrap failed"; }
    tar -C "$work/rootfs" -c . | docker import - local/debian:bookworm-minbase >/dev/null
    rm -rf "$work/rootfs"
    # the interpreter: the host's CPython 3.12 (the prefix behind the project's venv), without
    # its test suite and installed packages
    local prefix
    prefix=$("$PY" -c 'import sys; assert sys.version_info[:2] == (3, 12), sys.version; print(sys.base_prefix)') \
        || fail "the stand-in needs the host's Python 3.12 ($PY is $("$PY" --version 2>&1))"
    mkdir -p "$work/standin/python"
    tar -C "$prefix" -c --exclude=lib/python3.12/test --exclude='lib/python3.12/site-packages/*' \
        --exclude='__pycache__' bin include lib share 2>/dev/null | tar -C "$work/standin/python" -x
    docker build --force-rm -q -t "$base_image" -f docker/standin-base.Dockerfile "$work/standin" \
        >"$work/standin.log" 2>&1 || { tail -20 "$work/standin.log"; fail "stand-in build failed"; }
    rm -rf "$work/standin"
}

ensure_base() {
    if docker image inspect "$base_image" >/dev/null 2>&1; then
        log "base image $base_image present"
        return
    fi
    if [[ "$standin" != always ]] && timeout 120 docker pull "$base_image" >/dev/null 2>&1; then
        log "pulled $base_image"
        return
    fi
    [[ "$standin" != never ]] || fail "cannot pull $base_image and FBS_PROOF_STANDIN=never"
    build_standin
}

build_image() {
    scripts/make_wheelhouse.sh wheelhouse 2> >(grep -v "is ignored" >&2)
    log "docker build -t $image --build-arg WHEELHOUSE=wheelhouse ."
    docker build --force-rm --build-arg WHEELHOUSE=wheelhouse -t "$image" . \
        >"$work/build.log" 2>&1 || { tail -40 "$work/build.log"; fail "docker build failed"; }
    # (a build served from the layer cache prints none of these lines: not an error)
    { grep -E "^(offline install|online install|reference|warm-up)" "$work/build.log" || true; } \
        | sed "s/^/    /"
    log "image size: $(docker image inspect -f '{{.Size}}' "$image" | awk '{printf "%.0f MB", $1/1e6}')"
}

free_port() {
    "$PY" -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])'
}

run_container() {  # run_container PORT [docker run options...]: echo the container ID
    local port=$1
    shift
    docker run -d --cpus "$cpus" -p "127.0.0.1:$port:5006" \
        -e "BOKEH_ALLOW_WS_ORIGIN=127.0.0.1:$port" "$@" "$image"
}

wait_healthy() {  # wait_healthy CID
    local cid=$1 status
    for _ in $(seq 1 "$health_timeout"); do
        status=$(docker inspect -f '{{.State.Status}} {{.State.Health.Status}}' "$cid")
        case "$status" in
            "running healthy") log "container ${cid:0:12} healthy"; return ;;
            *unhealthy* | exited* | dead*) fail "container ${cid:0:12}: $status" ;;
        esac
        sleep 1
    done
    fail "container ${cid:0:12} not healthy after ${health_timeout} s ($status)"
}

check_app_document() {  # the app script builds a document without error
    "$PY" scripts/wait_app_document.py "$1"
}

proof_open() {
    local port cid
    port=$(free_port)
    cid=$(run_container "$port")
    containers+=("$cid")
    log "container ${cid:0:12} on 127.0.0.1:$port (--cpus $cpus)"
    timed "start -> healthy (no auth)" wait_healthy "$cid"
    timed "app document (/liveness?endpoint=/main)" check_app_document "$port"
    timed "browser smoke test (no auth)" "$PY" docker/smoke_test.py "http://127.0.0.1:$port/"
    timed "docker stop after use (no auth)" stop_promptly "$cid"
}

check_no_secrets() {  # check_no_secrets CID SECRET...: not in docker top, not in PID 1's env
    local cid=$1 s
    shift
    local top env
    top=$(docker top "$cid" -eo pid,args)
    env=$(docker exec "$cid" cat /proc/1/environ | tr '\0' '\n')
    for s in "$@"; do
        if grep -qF -- "$s" <<<"$top"; then fail "a secret is visible in docker top"; fi
        if grep -qF -- "$s" <<<"$env"; then fail "a secret is in the server's environment"; fi
    done
    log "no secret in docker top or /proc/1/environ:"
    sed 's/^/    /' <<<"$top"
}

stop_promptly() {  # stop_promptly CID: docker stop must not need its kill after 10 s
    local cid=$1 t0=$SECONDS
    docker stop -t 10 "$cid" >/dev/null
    local took=$((SECONDS - t0)) code
    code=$(docker inspect -f '{{.State.ExitCode}}' "$cid")
    log "stopped container ${cid:0:12} in ${took} s (exit code $code)"
    if ((took >= 10)) || [[ "$code" == 137 ]]; then fail "the server did not end on SIGTERM"; fi
}

proof_auth() {
    local port cid password secret
    port=$(free_port)
    password=$("$PY" -c 'import secrets; print(secrets.token_urlsafe(12))')
    secret=$("$PY" -c 'import secrets; print(secrets.token_urlsafe(32))')
    cid=$(run_container "$port" -e "FBS_BASIC_AUTH=reviewer:$password" \
        -e "FBS_COOKIE_SECRET=$secret")
    containers+=("$cid")
    log "container ${cid:0:12} with basic auth on 127.0.0.1:$port"
    timed "start -> healthy (basic auth)" wait_healthy "$cid"
    timed "browser smoke test (login first)" "$PY" docker/smoke_test.py \
        "http://127.0.0.1:$port/" --expect-login --user reviewer "--password=$password"
    check_no_secrets "$cid" "$password" "$secret"
    timed "docker stop after use (basic auth)" stop_promptly "$cid"
}

timed "install tools (apt-get when missing)" install_tools
timed "Docker daemon" start_dockerd
timed "base image $base_image" ensure_base
timed "wheelhouse + docker build" build_image
proof_open
proof_auth
log "all checks passed"
