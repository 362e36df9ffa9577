# snapmorph — `make` lists the targets. Every target sets up .venv by itself on first use.
PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed-stamp
JOBS   ?=
MAPS_FLAGS ?=

.DEFAULT_GOAL := help
.PHONY: help venv test test-fast test-durations bench maps maps-ci maps-polygons maps-accuracy check-maps figures fuzz test-nojit clean

help:  ## list the targets
	@echo "snapmorph make targets:"
	@grep -E '^[a-zA-Z_-]+:.*## ' $(MAKEFILE_LIST) | sed -E 's/:.*## /\t/' | awk -F'\t' '{printf "  %-12s %s\n", $$1, $$2}'

$(STAMP): pyproject.toml
	@test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install -q --upgrade pip
	$(PY) -m pip install -q -e ".[dev]"
	$(PY) -m snapmorph.units.warmup
	$(PY) -m snapmorph unit --L 100 --h 20 --t 0.5 --w 5 --b 5 > /dev/null
	@touch $(STAMP)

venv: $(STAMP)  ## create .venv, install the project and warm numba's cache (done automatically by every target)

test: $(STAMP)  ## run the whole test suite (slow tests included)
	$(PY) -m pytest -q --durations=15

test-fast: $(STAMP)  ## run the tests not marked slow (measured >= 2 s: tests/durations.json)
	$(PY) -m pytest -q -m "not slow"

test-durations: $(STAMP)  ## run the whole suite and write each test's time into tests/durations.json
	$(PY) -m pytest -q --durations=15 --record-durations tests/durations.json

bench: $(STAMP)  ## print speed figures (solver, unit, pipeline)
	$(PY) bench/run.py

maps: $(STAMP)  ## build the default design map into maps/data/ (7452 points, ~1 min on 2 idle cores; no-op when up to date; MAPS_FLAGS=--force rebuilds)
	$(PY) -m snapmorph maps build --grid default --out maps/data/default.nc $(if $(JOBS),--workers $(JOBS),) $(MAPS_FLAGS)

maps-ci: $(STAMP)  ## build the small CI grid into maps/data/ci.nc (no-op when up to date)
	$(PY) -m snapmorph maps build --grid ci --out maps/data/ci.nc $(MAPS_FLAGS)

maps-polygons: $(STAMP)  ## build the small maps of the 2-D units on a triangle, square and hexagon into maps/data/unit2d-*-small.nc (~1 min on one core; no-op when up to date)
	$(PY) -m snapmorph maps build --kind unit2d_triangle --grid small --out maps/data/unit2d-triangle-small.nc $(MAPS_FLAGS)
	$(PY) -m snapmorph maps build --kind unit2d --grid small --out maps/data/unit2d-square-small.nc $(MAPS_FLAGS)
	$(PY) -m snapmorph maps build --kind unit2d_hexagon --grid small --out maps/data/unit2d-hexagon-small.nc $(MAPS_FLAGS)

check-maps: $(STAMP)  ## recompute the CI grid and compare it with the committed snapshot
	$(PY) -m snapmorph maps check --grid ci --against maps/data/ci.nc

maps-accuracy: $(STAMP)  ## interpolated map values against direct simulation at random off-grid points
	$(PY) -m snapmorph.pipeline.accuracy --map maps/data/default.nc --n 50

figures: $(STAMP)  ## write the paper's figures into figures/ with a gallery page figures/index.md
	$(PY) -m snapmorph figures --out figures

fuzz: $(STAMP)  ## 1,000 random unit geometries over the valid domain at 101 and 201 nodes (no hang, bistable = stable, no NaN, no monostable cut path, no flag flip)
	$(PY) tests/units/fuzz_units.py --n 1000 --nodes 101 --compare 201 --time-limit 20 --every 25 --failures build/fuzz_failures.json

test-nojit: $(STAMP)  ## run the kernel tests as plain Python (NUMBA_DISABLE_JIT=1), for debugging
	NUMBA_DISABLE_JIT=1 $(PY) -m pytest -q tests/solver/test_energies.py tests/solver/test_banded.py

clean:  ## remove caches (keeps .venv)
	find . -name __pycache__ -type d -prune -exec rm -rf {} +
	rm -rf .pytest_cache build *.egg-info
