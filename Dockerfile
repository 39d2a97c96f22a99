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

ARG PYTHON_IMAGE=python:3.11-slim-bookworm

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
COPY pyproject.toml README.md* /src/
COPY fbs_core/ /src/fbs_core/
COPY app/ /src/app/
RUN set -eu; \
    if ls /wheelhouse/*.whl >/dev/null 2>&1; then \
        echo "offline install from the wheelhouse ($(ls /wheelhouse/*.whl | wc -l) wheels)"; \
        set -- --no-index --find-links /wheelhouse; \
    else \
        echo "online install from pip's configured index"; \
        set --; \
    fi; \
    /opt/venv/bin/python -m pip install "$@" /src ${EXTRA_PACKAGES}; \
    /opt/venv/bin/python -c "import app.main, fbs_core; print('installed', fbs_core.__name__)"

# ---- runtime stage -------------------------------------------------------------------------
FROM ${PYTHON_IMAGE}
LABEL org.opencontainers.image.title="tire-fbs dashboard" \
      org.opencontainers.image.description="Frequency Based Substructuring of a rolling tire and a chassis: Panel dashboard" \
      org.opencontainers.image.licenses="BSD-3-Clause"
RUN useradd --system --create-home --home-dir /home/fbs --uid 10001 --user-group fbs
COPY --from=build /opt/venv /opt/venv
COPY docker/entrypoint.py /opt/fbs/entrypoint.py
ENV PATH=/opt/venv/bin:$PATH \
    PYTHONUNBUFFERED=1 \
    NUMBA_CACHE_DIR=/home/fbs/.cache/numba \
    BOKEH_ALLOW_WS_ORIGIN=localhost:5006,127.0.0.1:5006 \
    FBS_NUM_THREADS=4
USER fbs
WORKDIR /home/fbs
EXPOSE 5006
HEALTHCHECK --interval=10s --timeout=5s --start-period=30s --retries=3 \
    CMD ["/opt/venv/bin/python", "/opt/fbs/entrypoint.py", "--healthcheck"]
ENTRYPOINT ["/opt/venv/bin/python", "/opt/fbs/entrypoint.py"]
CMD []
