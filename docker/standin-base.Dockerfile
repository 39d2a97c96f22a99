# Stand-in for the official `python:3.12-slim-bookworm` image, for machines that cannot pull
# from a container registry (used by scripts/docker_proof.sh; never needed where the official
# image can be pulled). Its base is a Debian bookworm minbase root file system made with
# debootstrap and loaded with `docker import`; Debian bookworm ships Python 3.11 only, so the
# interpreter is the host's own CPython 3.12 build for bookworm (its prefix copied into the
# build context as python/ by scripts/docker_proof.sh), installed in /usr/local as in the
# official image, with the shared libraries its standard modules link to.
ARG MINBASE=local/debian:bookworm-minbase
FROM ${MINBASE}
RUN apt-get update \
    && DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends \
        ca-certificates libbz2-1.0 libexpat1 libffi8 libgdbm6 liblzma5 libncursesw6 \
        libreadline8 libsqlite3-0 libssl3 libuuid1 netbase tzdata zlib1g \
    && rm -rf /var/lib/apt/lists/*
COPY python/ /usr/local/
RUN echo /usr/local/lib > /etc/ld.so.conf.d/usr-local-python.conf && ldconfig \
    && ln -sf python3.12 /usr/local/bin/python3 && ln -sf python3 /usr/local/bin/python \
    && python3 -c "import bz2, ctypes, hashlib, lzma, sqlite3, ssl, venv, zlib, sys; print(sys.version)"
CMD ["python3"]
