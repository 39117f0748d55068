# mjmaze: `make run` runs the main job, `make test` runs the tests; both set
# up everything they need first (Debian GL packages, a virtualenv, the package).
SHELL := /bin/bash
PYTHON ?= python3
VENV ?= .venv
PY := $(VENV)/bin/python
# EGL (default) for headless rendering; OSMesa (the fallback) where the
# distribution still ships it (newer Mesa releases dropped libosmesa6).
GL_PACKAGES := libegl1 libgl1 libgl1-mesa-dri libegl-mesa0 libglx-mesa0
OPTIONAL_GL_PACKAGES := libosmesa6
# For the test of the play window under a real X display (skipped without them).
TEST_PACKAGES := xvfb xdotool
# Installed only when no torch is there yet: install your own (a CUDA build,
# say) into .venv first to train on a GPU.
TORCH ?= torch==2.13.0
# PyPI's Linux torch brings triton (torch 2.13.0 pins triton 3.7.1), and a
# triton loaded after Mesa's LLVM once crashed every training script
# (mjmaze/llvm_clash.py). `make test` adds it where torch came without it (this
# box's CPU wheel), so the tests run as users install; `TRITON=` skips it.
TRITON ?= triton==3.7.1
# Where pip looks for torch; empty = PyPI (whose Linux torch is the multi-GB
# CUDA build). Without an NVIDIA GPU: TORCH_INDEX=https://download.pytorch.org/whl/cpu
TORCH_INDEX ?=
# The main job (mjmaze.train.first_run): A2C on Labyrinth 5x5 with the paper's
# configuration, then a greedy evaluation beside a random policy, a learning
# curve and a video. Its measured time and success: docs/learning.md, "The main job".
RUN_STEPS ?= 1100000
RUN_ARGS ?=

.PHONY: run test test-fast bench setup system-deps test-deps clean

run: system-deps $(VENV)/.stamp-torch $(VENV)/.stamp-train,viz
	$(PY) -m mjmaze.train.first_run --total-steps $(RUN_STEPS) $(RUN_ARGS)

test: system-deps test-deps $(VENV)/.stamp-torch $(VENV)/.stamp-triton $(VENV)/.stamp-train,dev
	$(PY) -m pytest -q

# The tests that take seconds, not minutes: no training, Warp, Ray or X display
# (pytest markers in pyproject.toml). `make test` runs everything.
FAST := not slow and not warp and not ray and not display
test-fast: system-deps $(VENV)/.stamp-torch $(VENV)/.stamp-train,dev
	$(PY) -m pytest -q -m "$(FAST)"

# docs/speed.md's CPU figures, with the flags they were measured with (the bench
# extra brings ViZDoom and numba, Doom's compiled light); run with nothing else on
# the cores. Training's figure needs torch: bench/train_speed.py (docs/speed.md).
bench: system-deps $(VENV)/.stamp-bench
	$(PY) bench/multiproc.py --rounds 3 --seconds 4 --no-scaling --no-draw
	$(PY) bench/multiproc.py --rounds 3 --seconds 4 --no-scaling --no-draw --scenario two_colour
	$(PY) bench/speed.py --rounds 4 --steps 3000

setup: system-deps $(VENV)/.stamp-torch $(VENV)/.stamp-all

system-deps:
	@if ! command -v dpkg >/dev/null; then \
	  echo "Not a Debian system: install EGL or OSMesa yourself ($(GL_PACKAGES))."; exit 0; fi; \
	missing=$$(for p in $(GL_PACKAGES); do dpkg -s $$p >/dev/null 2>&1 || echo $$p; done); \
	optional=$$(for p in $(OPTIONAL_GL_PACKAGES); do dpkg -s $$p >/dev/null 2>&1 || echo $$p; done); \
	if [ -z "$$missing$$optional" ]; then exit 0; fi; \
	if [ "$$(id -u)" != 0 ]; then \
	  if [ -n "$$missing" ]; then echo "Missing GL packages; run: sudo apt-get install $$missing"; exit 1; fi; \
	  exit 0; fi; \
	apt-get update -qq; \
	if [ -n "$$missing" ]; then echo "Installing GL packages: $$missing"; \
	  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends $$missing >/dev/null || exit 1; fi; \
	for p in $$optional; do \
	  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends $$p >/dev/null 2>&1 \
	    || echo "$$p is not available here: rendering uses EGL only"; done

test-deps:
	@command -v dpkg >/dev/null || exit 0; \
	missing=$$(for p in $(TEST_PACKAGES); do dpkg -s $$p >/dev/null 2>&1 || echo $$p; done); \
	if [ -z "$$missing" ]; then exit 0; fi; \
	if [ "$$(id -u)" != 0 ]; then echo "Without $$missing the play-window test is skipped (sudo apt-get install $$missing)"; exit 0; fi; \
	apt-get update -qq; DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends $$missing >/dev/null 2>&1 \
	  || echo "Could not install $$missing: the play-window test is skipped"

$(VENV)/bin/python:
	@$(PYTHON) -c 'import sys; sys.exit(sys.version_info < (3, 10))' || { echo "mjmaze needs Python >= 3.10"; exit 1; }
	@# Debian and Ubuntu ship venv's pip (ensurepip) apart, in python3-venv.
	@if ! $(PYTHON) -c 'import ensurepip' 2>/dev/null; then \
	  if [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null; then \
	    echo "Installing python3-venv"; apt-get update -qq; \
	    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends python3-venv >/dev/null || exit 1; \
	  else echo "$(PYTHON) cannot make a virtualenv: run sudo apt-get install python3-venv"; exit 1; fi; fi
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install -q --upgrade pip

$(VENV)/.stamp-torch: | $(VENV)/bin/python
	$(PY) -c 'import torch' 2>/dev/null || $(PY) -m pip install -q $(if $(TORCH_INDEX),--index-url $(TORCH_INDEX)) "$(TORCH)"
	@touch $@

$(VENV)/.stamp-triton: $(VENV)/.stamp-torch
	@if [ -n "$(TRITON)" ] && [ "$$(uname -s)" = Linux ] && \
	  ! $(PY) -c 'import importlib.util, sys; sys.exit(importlib.util.find_spec("triton") is None)'; then \
	  echo "Installing $(TRITON), as PyPI's torch would"; $(PY) -m pip install -q "$(TRITON)"; fi
	@touch $@

# On every editable install of a package that maps folders (train/ as mjmaze.train),
# setuptools warns that folders named like the package may shadow it: information,
# and noise in `make run`'s output. Its warnings are UserWarnings; errors still fail.
$(VENV)/.stamp-%: pyproject.toml | $(VENV)/bin/python
	PYTHONWARNINGS=ignore::UserWarning $(PY) -m pip install -q -e ".[$*]"
	@touch $@

clean:
	rm -rf $(VENV) *.egg-info .pytest_cache
