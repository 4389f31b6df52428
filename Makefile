# roomlight: `make demo` runs the main job on built-in defaults, `make test` runs the test suite.
# Both bootstrap what they need (libLLVM for Mitsuba's CPU backend, .venv, torch, the package).

PYTHON ?= $(shell command -v python3.11 || command -v python3)
VENV   := .venv
PY     := $(VENV)/bin/python
# The CPU build of torch where no NVIDIA GPU is visible (on these machines 2.13.0 is a local CPU wheel).
TORCH_SPEC ?= $(shell if command -v nvidia-smi >/dev/null 2>&1 && nvidia-smi -L >/dev/null 2>&1; then echo "torch"; else echo "torch==2.13.0"; fi)
STAMP  := $(VENV)/.roomlight-installed

.PHONY: all setup web blender demo test test-fast bench clean info

all: test

setup: $(STAMP) web

# three.js (npm, pinned) for `roomlight view`, Chromium for the browser tests; checked on every run
web:
	@scripts/ensure_web.sh

# Blender as a Python module in .venv-blender (bpy pins numpy 1.x) for the Blender export test
blender:
	@scripts/ensure_blender.sh

$(STAMP): pyproject.toml scripts/ensure_llvm.sh
	@scripts/ensure_llvm.sh
	@test -x $(PY) || $(PYTHON) -m venv $(VENV)
	@$(PY) -m pip install -q --upgrade pip
	@$(PY) -c "import torch" 2>/dev/null || $(PY) -m pip install -q "$(TORCH_SPEC)"
	@$(PY) -m pip install -q -e ".[test,denoise,export,dask,prepare]"
	@touch $(STAMP)

info: $(STAMP)
	@$(VENV)/bin/roomlight info

demo: $(STAMP)
	@$(VENV)/bin/roomlight demo

# The suite runs on one worker process per core (at most 4; pytest-xdist): most tests keep to one
# thread, so two workers on two cores finish in about 0.8x the time of one (docs/results.md).
PYTEST := $(PY) -m pytest -q -n auto --maxprocesses 4

test: $(STAMP) web blender
	@$(PYTEST)

test-fast: $(STAMP) web
	@$(PYTEST) -m "not slow"

bench: $(STAMP)
	@for b in benchmarks/bench_*.py; do $(PY) $$b || exit 1; done

clean:
	rm -rf $(VENV) .venv-blender build src/*.egg-info .pytest_cache roomlight-demo
