# Batch pipeline: every stage is a file target, so Make reruns only what a change touches.
#   make all                          all cases in CASES (default: the three shipped cases)
#   make all CASE=cases/rv40e-81.toml one case
#   make test                         the test suite (what CI runs)
#   make bench                        benchmarks -> build/bench.json
# Both `all` and `test` create .venv and install the pinned dependencies when missing.

PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed
CASES ?= rv40e-81 rv40e-105 rv160n-81
ifdef CASE
CASES := $(basename $(notdir $(CASE)))
endif
MEASURED ?= ../shared/measured
QUIET ?=
export MPLBACKEND := Agg
export PYVISTA_OFF_SCREEN := true

.PHONY: all test bench clean install geometry
.DELETE_ON_ERROR:
.SECONDARY:

all: geometry
	@echo "make all: geometry stage done for: $(CASES) (later stages are not built yet)"

install: $(STAMP)
$(STAMP): pyproject.toml
	test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install -q --upgrade pip
	$(PY) -m pip install -q -e '.[test]'
	touch $@

GEOMETRY_SRC := $(wildcard geometry/*.py) pipeline/cmd_geometry.py

geometry: $(foreach c,$(CASES),build/$(c)/geometry/profile.csv)
build/%/geometry/profile.csv: cases/%.toml $(GEOMETRY_SRC) | $(STAMP)
	$(PY) -m pipeline geometry --case $< --out build/$*/geometry $(QUIET)

test: $(STAMP)
	$(PY) -m pytest -q -p no:cacheprovider

clean:
	rm -rf build
