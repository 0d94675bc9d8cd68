# rnsca HTTP service. Build: docker build -t rnsca . ; run: docker run -p 8000:8000 rnsca
# Settings come from RNSCA_* variables (see README.md, "HTTP service").

ARG PYTHON_VERSION=3.11

FROM python:${PYTHON_VERSION}-slim AS build
# Numba's OpenMP threading layer (thread-safe for concurrent requests) needs libgomp.
# hadolint ignore=DL3008
RUN apt-get update \
    && apt-get install -y --no-install-recommends libgomp1 \
    && rm -rf /var/lib/apt/lists/*
ENV NUMBA_CACHE_DIR=/var/cache/numba
# The extras installed (docker/install.sh): service,dask for the Dask profile of compose.yml.
ARG RNSCA_EXTRAS=service
WORKDIR /src
COPY pyproject.toml README.md ./
COPY docker/install.sh docker/install.sh
COPY rnsca rnsca
COPY service service
RUN docker/install.sh /opt/venv /src

FROM python:${PYTHON_VERSION}-slim AS runtime
# hadolint ignore=DL3008
RUN apt-get update \
    && apt-get install -y --no-install-recommends libgomp1 \
    && rm -rf /var/lib/apt/lists/* \
    && useradd --system --uid 10001 --no-create-home --shell /usr/sbin/nologin rnsca
COPY --from=build /opt/venv /opt/venv
COPY --from=build --chown=rnsca:rnsca /var/cache/numba /var/cache/numba
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
# uvicorn via `python -m service`: settings from the environment; SIGTERM drains requests.
CMD ["python", "-m", "service"]
