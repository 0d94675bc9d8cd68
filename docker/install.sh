#!/bin/sh
# Install rnsca with the service extra into a new virtual environment, then compile the
# kernels into Numba's cache. The Dockerfile runs this; so does the test that checks the
# image's steps without a Docker engine (tests/service/test_docker.py).
#   docker/install.sh VENV SOURCE     (NUMBA_CACHE_DIR says where the cache goes)
# RNSCA_EXTRAS (default: service) names the extras; the Dask profile of compose.yml builds
# with service,dask (dask scheduler, dask worker, rnsca batch).
set -eu
venv="$1"
source="$2"
python3 -m venv "$venv"
"$venv/bin/pip" install --no-cache-dir --disable-pip-version-check --quiet \
    "$source[${RNSCA_EXTRAS:-service}]"
# Compile the kernels once, here, so that no container pays for it at start.
"$venv/bin/rnsca" warm-up
