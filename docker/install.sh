#!/bin/sh
# Install rnsca with the service extra into a new virtual environment, remove what the
# service does not need at run time, and compile the kernels into Numba's cache. The
# Dockerfile runs this; so does the test that checks the image's steps without a Docker
# engine (tests/service/test_docker.py).
#   docker/install.sh VENV SOURCE     (NUMBA_CACHE_DIR says where the cache goes)
# RNSCA_EXTRAS (default: service) names the extras; the Dask profile of compose.yml builds
# with service,dask (dask scheduler, dask worker, rnsca batch).
set -eu
venv="$1"
source="$2"
extras="${RNSCA_EXTRAS:-service}"
here="$(dirname "$0")"
python3 -m venv "$venv"
"$venv/bin/pip" install --no-cache-dir --disable-pip-version-check --quiet \
    "$source[$extras]"
# Installers, tests, headers, pyarrow's unused components, debug symbols (docker/slim.py).
"$venv/bin/python" "$here/slim.py" files "$venv"
# Compile the kernels once, here, so that no container pays for it at start.
"$venv/bin/rnsca" warm-up
# The service's image: start the service, ask each endpoint, keep the bytecode it read
# (its own warm-up adds its kernels to the cache on the way). Not for other extras: the
# Dask image also runs dask's commands, which would lose theirs.
if [ "$extras" = service ]; then
    "$venv/bin/python" "$here/slim.py" bytecode "$venv"
fi
