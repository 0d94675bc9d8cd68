# Every target creates .venv on first use; nothing relies on packages installed by hand.
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed

.PHONY: test bench lint clean

$(STAMP): pyproject.toml
	test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e '.[dev,bench]'
	touch $(STAMP)

lint: $(STAMP)
	$(VENV)/bin/ruff check .

# Lint, the whole suite (doctests included), then the kernel unit tests once more in
# pure Python (NUMBA_DISABLE_JIT=1) so every kernel line also runs uncompiled.
test: $(STAMP) lint
	$(PY) -m pytest -n 2 -q
	NUMBA_DISABLE_JIT=1 $(PY) -m pytest -n 2 -q tests/unit -k "not slow"

bench: $(STAMP)
	$(PY) -m benchmarks.run

clean:
	rm -rf $(VENV) .pytest_cache .hypothesis .ruff_cache
