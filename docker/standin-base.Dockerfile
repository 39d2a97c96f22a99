# Stand-in for the official `python:3.11-slim-bookworm` image, for machines that cannot pull
# from a container registry (used by scripts/docker_proof.sh; never needed where the official
# image can be pulled). Its base is a Debian bookworm minbase root file system made with
# debootstrap and loaded with `docker import` (see scripts/docker_proof.sh). Debian bookworm's
# python3 is 3.11, the same minor version as the official image, so wheels built for one run
# on the other. Python lives in /usr here and in /usr/local in the official image: the
# project's Dockerfile only relies on `python3 -m venv`, which works on both.
ARG MINBASE=local/debian:bookworm-minbase
FROM ${MINBASE}
RUN apt-get update \
    && DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends \
        python3 python3-venv \
    && rm -rf /var/lib/apt/lists/*
CMD ["python3"]
