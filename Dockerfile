# tire-fbs dashboard: `panel serve` of app/main.py, one Bokeh session per browser tab.
# Deployment guide, environment variables and the offline build: docs/deployment.md.
#
#   docker build -t tire-fbs .
#   docker run --rm -p 5006:5006 tire-fbs          # then open http://localhost:5006/
#
# Offline / air-gapped build (no package index reachable from the build):
#   scripts/make_wheelhouse.sh && docker build --build-arg WHEELHOUSE=wheelhouse -t tire-fbs .
#
# Only Dockerfile instructions of the classic builder are used, so it builds with BuildKit and
# with DOCKER_BUILDKIT=0 alike.

ARG PYTHON_IMAGE=python:3.12-slim-bookworm

# ---- build stage: a virtual environment with the project and its dependencies ---------------
FROM ${PYTHON_IMAGE} AS build
# Directory (inside the build context) holding wheels for an offline install. When it holds
# wheels, pip installs with `--no-index --find-links` from it and nothing else.
ARG WHEELHOUSE=docker/no-wheelhouse
# Extra requirements installed next to the project, e.g. "cryptography" for encrypted OAuth
# cookies (PANEL_OAUTH_ENCRYPTION). From the wheelhouse too in an offline build.
ARG EXTRA_PACKAGES=""
ENV PIP_DISABLE_PIP_VERSION_CHECK=1 PIP_NO_CACHE_DIR=1 PYTHONDONTWRITEBYTECODE=1
RUN python3 -m venv /opt/venv
COPY ${WHEELHOUSE}/ /wheelhouse/
# With wheels in the wheelhouse, pip of this venv is configured to use nothing else.
RUN if ls /wheelhouse/*.whl >/dev/null 2>&1; then \
        printf '[global]\nno-index = true\nfind-links = /wheelhouse\n' > /opt/venv/pip.conf; \
        echo "offline install from the wheelhouse ($(ls /wheelhouse/*.whl | wc -l) wheels)"; \
    elif [ "$WHEELHOUSE" != docker/no-wheelhouse ]; then \
        echo "WHEELHOUSE=$WHEELHOUSE holds no wheels (make it with scripts/make_wheelhouse.sh)"; \
        exit 1; \
    else \
        echo "online install from pip's configured index"; \
    fi
# Dependencies first (from pyproject.toml alone: this layer is reused while they do not
# change), then the project itself.
COPY pyproject.toml /src/
RUN touch /src/README.md \
    && /opt/venv/bin/python -m pip install --no-compile /src ${EXTRA_PACKAGES} \
    && /opt/venv/bin/python -m compileall -q -j 0 /opt/venv/lib >/dev/null
COPY README.md* /src/
COPY fbs_core/ /src/fbs_core/
COPY app/ /src/app/
COPY data/ /src/data/
COPY docker/prepare.py /src/docker/prepare.py
RUN /opt/venv/bin/python -m pip install --no-deps --force-reinstall /src \
    && /opt/venv/bin/python /src/docker/prepare.py data /src/data \
    && rm -f /opt/venv/pip.conf

# ---- runtime stage -------------------------------------------------------------------------
FROM ${PYTHON_IMAGE}
LABEL org.opencontainers.image.title="tire-fbs dashboard" \
      org.opencontainers.image.description="Frequency Based Substructuring of a rolling tire and a chassis: Panel dashboard" \
      org.opencontainers.image.licenses="BSD-3-Clause"
RUN useradd --system --create-home --home-dir /home/fbs --uid 10001 --user-group fbs
# The projects' data directory (FBS_DATA_DIR, docs/projects.md): owned by fbs so that a named
# volume mounted on it (docker run -v tire-fbs-data:/data) starts writable by the server.
RUN mkdir -p /data && chown fbs:fbs /data
COPY --from=build /opt/venv /opt/venv
COPY docker/entrypoint.py docker/fbs_server.py docker/fbs_auth.py docker/page_gate.py \
     docker/conn_limits.py docker/page_limits.py docker/server_private.py docker/prepare.py \
     /opt/fbs/
ENV PATH=/opt/venv/bin:$PATH \
    PYTHONUNBUFFERED=1 \
    NUMBA_CACHE_DIR=/home/fbs/.cache/numba \
    BOKEH_ALLOW_WS_ORIGIN=localhost:5006,127.0.0.1:5006 \
    FBS_NUM_THREADS=4
USER fbs
WORKDIR /home/fbs
# Compile the numba kernels into NUMBA_CACHE_DIR now, not in the first user's session.
RUN python /opt/fbs/prepare.py warmup
EXPOSE 5006
HEALTHCHECK --interval=10s --timeout=5s --start-period=30s --retries=3 \
    CMD ["/opt/venv/bin/python", "/opt/fbs/entrypoint.py", "--healthcheck"]
ENTRYPOINT ["/opt/venv/bin/python", "/opt/fbs/entrypoint.py"]
CMD []
