# Every target creates .venv on first use; nothing relies on packages installed by hand.
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed
SERVE_STAMP := $(VENV)/.installed-service
HOST ?= 127.0.0.1
PORT ?= 8000

.PHONY: serve test check bench paper compare soak lint fuzz clean proto

# The client SDK (clients/python, package rnsca-client) is installed beside rnsca so that
# `make test` tests it against live servers.
$(STAMP): pyproject.toml clients/python/pyproject.toml
	test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e '.[dev,bench,service,opencl]' -e clients/python
	# The ICD file for Intel's CPU OpenCL driver (the dev extra): its wheel's own names a
	# conda path. rnsca.backends.opencl points OCL_ICD_VENDORS here (unless it is set).
	if [ -e $(VENV)/lib/libintelocl.so ]; then mkdir -p $(VENV)/opencl-vendors && \
	  echo "$(abspath $(VENV))/lib/libintelocl.so" > $(VENV)/opencl-vendors/intel-cpu.icd; fi
	touch $(STAMP)

# The service needs only the `service` extra (a full dev install also satisfies it); the
# SDK is installed beside it with GeoPandas (its `geopandas` extra), so the README's client
# examples, GeoDataFrames included, run in the same .venv.
$(SERVE_STAMP): pyproject.toml clients/python/pyproject.toml
	test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e '.[service]' -e 'clients/python[geopandas]'
	touch $(SERVE_STAMP)

# The HTTP service on http://$(HOST):$(PORT) (docs at /docs); Ctrl-C stops it gracefully.
serve: $(SERVE_STAMP)
	$(VENV)/bin/rnsca serve --host $(HOST) --port $(PORT)

# The MVT message's descriptor set (rnsca/tiles/vector_tile.desc) from its .proto, by
# protoc (grpcio-tools, the dev extra); rnsca.tiles.vector_tile loads it.
proto: $(STAMP)
	$(PY) -m grpc_tools.protoc -I rnsca/tiles --descriptor_set_out=rnsca/tiles/vector_tile.desc \
	  rnsca/tiles/vector_tile.proto

# Ruff (style, NumPy docstrings, return types of public functions), the layer rules
# (import-linter: [tool.importlinter] in pyproject.toml) and the type checker (mypy:
# [tool.mypy], rnsca outside its kernels, and the service).
lint: $(STAMP)
	$(VENV)/bin/ruff check .
	$(VENV)/bin/lint-imports
	$(VENV)/bin/mypy

# The quick check before a commit: lint, then the unit tests (compiled; not the slow ones).
check: $(STAMP) lint
	$(PY) -m pytest -n 2 -q tests/unit -k "not slow"

# Lint, the whole suite (doctests and the service's live-server tests included), then the
# kernel unit tests once more in pure Python (NUMBA_DISABLE_JIT=1) so every kernel line
# also runs uncompiled.
test: $(STAMP) lint
	$(PY) -m pytest -n 2 -q
	NUMBA_DISABLE_JIT=1 $(PY) -m pytest -n 2 -q tests/unit -k "not slow"

# Coverage-guided fuzzing (atheris) of the SVG path reader, the SVG document reader, the
# GeoJSON reader with its MessagePack decoder, and the binary segment endpoint, each for
# FUZZ_SECONDS in its own process with Numba's bounds checks on (fuzz/README.md). Exits
# non-zero on any crash, hang (over 1 s per input) or disagreement with a reference.
FUZZ_SECONDS ?= 600
fuzz: $(STAMP)
	$(PY) -m fuzz.run --seconds $(FUZZ_SECONDS)

bench: $(STAMP)
	$(PY) -m benchmarks.run

# The paper's claims, reproduced (benchmarks/README.md): RNSCA against Cohen-Sutherland at
# the Table 2 sizes up to 10M, fragments decided early, intersections per method. Also part
# of `make bench`; MAX_SIZE=1000000 caps the workloads.
paper: $(STAMP)
	$(PY) -m benchmarks.paper $(if $(MAX_SIZE),--max-size $(MAX_SIZE))

# Before/after a change: the benchmark workloads on BASE (another checkout, e.g. a
# `git worktree add ../base <revision>`) and on this one, interleaved in one run.
compare: $(STAMP)
	@test -n "$(BASE)" || { echo "usage: make compare BASE=../base"; exit 2; }
	$(PY) -m benchmarks.compare --base $(BASE)

# Soak (issue 16; not in CI, not in `make bench`): MINUTES minutes of mixed load with wrk
# on loopback against `rnsca serve --workers 2`, RSS and p99 per minute; fails if either
# grows over 10% after the first 5 minutes (benchmarks/README.md).
MINUTES ?= 30
soak: $(STAMP)
	$(PY) -m benchmarks.soak --minutes $(MINUTES)

clean:
	rm -rf $(VENV) .fuzz .pytest_cache .hypothesis .ruff_cache .mypy_cache .import_linter_cache
