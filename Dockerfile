# rnsca HTTP service. Build: docker build -t rnsca . ; run: docker run -p 8000:8000 rnsca
# Settings come from RNSCA_* variables (see README.md, "HTTP service"); docker/README.md
# says how to run it read-only and behind a proxy (docker/compose.yml).

ARG PYTHON_VERSION=3.11

FROM python:${PYTHON_VERSION}-slim AS build
# Numba's OpenMP threading layer (thread-safe for concurrent requests) needs libgomp;
# binutils strips the debug symbols of the environment's shared objects (docker/slim.py).
# hadolint ignore=DL3008
RUN apt-get update \
    && apt-get install -y --no-install-recommends libgomp1 binutils \
    && rm -rf /var/lib/apt/lists/*
ENV NUMBA_CACHE_DIR=/var/cache/numba
# The extras installed (docker/install.sh): service,dask for the Dask profile of compose.yml.
ARG RNSCA_EXTRAS=service
WORKDIR /src
COPY pyproject.toml README.md ./
COPY docker/install.sh docker/slim.py docker/
COPY rnsca rnsca
COPY service service
RUN docker/install.sh /opt/venv /src

FROM python:${PYTHON_VERSION}-slim AS runtime
# The user and its group are both 10001, named rnsca (-l: no sparse lastlog entry).
# hadolint ignore=DL3008
RUN apt-get update \
    && apt-get install -y --no-install-recommends libgomp1 \
    && rm -rf /var/lib/apt/lists/* \
    && groupadd --system --gid 10001 rnsca \
    && useradd --system --no-log-init --uid 10001 --gid 10001 --no-create-home \
        --home-dir /nonexistent --shell /usr/sbin/nologin rnsca
COPY --from=build /opt/venv /opt/venv
COPY --from=build --chown=10001:10001 /var/cache/numba /var/cache/numba
COPY docker/entrypoint.sh /usr/local/bin/rnsca-entrypoint
ENV PATH=/opt/venv/bin:$PATH \
    NUMBA_CACHE_DIR=/var/cache/numba \
    PYTHONUNBUFFERED=1 \
    RNSCA_HOST=0.0.0.0 \
    RNSCA_PORT=8000
USER 10001:10001
WORKDIR /tmp
EXPOSE 8000
HEALTHCHECK --interval=15s --timeout=5s --start-period=60s --retries=3 \
    CMD ["python", "-m", "service.healthcheck"]
# A read-only root gets a writable view of the Numba cache in /tmp (docker/entrypoint.sh).
ENTRYPOINT ["rnsca-entrypoint"]
# uvicorn via `python -m service`: settings from the environment; SIGTERM drains requests.
CMD ["python", "-m", "service"]
