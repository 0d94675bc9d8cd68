# A stand-in for python:3.11-slim (CI only, where no registry of images is reachable):
# Debian bookworm's python3 (3.11) with venv (which brings pip into each virtual environment),
# as `python` and `python3`, and the
# CA certificates of the machine that builds it (its egress proxy's), so pip works.
FROM debian:bookworm-slim
COPY certificates/ /usr/local/share/ca-certificates/
# hadolint ignore=DL3008
RUN apt-get update \
    && apt-get install -y --no-install-recommends ca-certificates python3 python3-venv \
        python-is-python3 \
    && update-ca-certificates \
    && rm -rf /var/lib/apt/lists/*
ENV LANG=C.UTF-8
CMD ["python3"]
