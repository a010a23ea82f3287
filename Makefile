# Batch pipeline: every stage is a file target, so Make reruns only what a change touches.
#   make all                          every stage and the report for the cases in CASES
#   make all CASE=cases/rv40e-81.toml one case
#   make test                         the test suite (what CI runs)
#   make bench                        benchmarks -> $(BUILD)/bench.json
# `all`, `test` and `bench` create .venv and install the pinned dependencies when missing.
# Stage graph per case:  geometry -> mesh -> fem -> {matrix, hysteresis, fourbar, tolerance, diagnosis} -> report

PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed
BUILD ?= build
CASES ?= rv40e-81 rv40e-105 rv160n-81
ifdef CASE
CASES := $(basename $(notdir $(CASE)))
endif
MEASURED ?= ../shared/measured
SAMPLES ?= 4000
SCHEDULER ?=
Q ?=
RUN := $(PY) -m pipeline
SCHED := $(if $(SCHEDULER),--scheduler $(SCHEDULER),)
export MPLBACKEND := Agg
export PYVISTA_OFF_SCREEN := true

.PHONY: all test bench clean install report $(addprefix stage-,geometry mesh fem matrix hysteresis fourbar tolerance diagnosis)
.DELETE_ON_ERROR:
.SECONDARY:

all: report
	@echo "make all: reports in $(foreach c,$(CASES),$(BUILD)/$(c)/report/index.html)"

install: $(STAMP)
$(STAMP): pyproject.toml
	test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install -q --upgrade pip
	$(PY) -m pip install -q -e '.[test]'
	touch $@

# Sources each stage depends on (a change in a stage's code reruns it and what follows).
SRC_geometry := $(wildcard geometry/*.py pipeline/cmd_geometry.py)
SRC_mesh := $(SRC_geometry) $(wildcard fem/mesh.py fem/shaft.py pipeline/cmd_fem.py)
SRC_fem := $(SRC_geometry) $(wildcard fem/*.py pipeline/cmd_fem.py)
SRC_dynamics := $(wildcard dynamics/*.py pipeline/cmd_dynamics.py pipeline/sweep.py)
SRC_fourbar := $(wildcard dynamics/fourbar.py dynamics/tolerance.py pipeline/cmd_fourbar.py pipeline/sweep.py)
SRC_diagnosis := $(wildcard pipeline/diagnosis/*.py pipeline/cmd_diagnose.py pipeline/records.py)

stage-geometry: $(foreach c,$(CASES),$(BUILD)/$(c)/geometry/profile.csv)
$(BUILD)/%/geometry/profile.csv: cases/%.toml $(SRC_geometry) | $(STAMP)
	$(RUN) geometry --case $< --out $(BUILD)/$*/geometry $(Q)

# The crankshaft tet mesh is made once (fTetWild is not run-to-run reproducible) and reused.
stage-mesh: $(foreach c,$(CASES),$(BUILD)/$(c)/mesh/crankshaft_mesh.npz)
$(BUILD)/%/mesh/crankshaft_mesh.npz: cases/%.toml $(BUILD)/%/geometry/profile.csv $(SRC_mesh) | $(STAMP)
	$(RUN) mesh --case $< --out $(BUILD)/$*/mesh $(Q)

stage-fem: $(foreach c,$(CASES),$(BUILD)/$(c)/fem/stiffness.json)
$(BUILD)/%/fem/stiffness.json: cases/%.toml $(BUILD)/%/mesh/crankshaft_mesh.npz $(SRC_fem) | $(STAMP)
	$(RUN) fem --case $< --mesh $(BUILD)/$*/mesh --out $(BUILD)/$*/fem $(Q)

STIFF = --stiffness $(BUILD)/$*/fem/stiffness.json

stage-matrix: $(foreach c,$(CASES),$(BUILD)/$(c)/matrix/te_std.csv)
$(BUILD)/%/matrix/te_std.csv: cases/%.toml $(BUILD)/%/fem/stiffness.json $(SRC_dynamics) | $(STAMP)
	$(RUN) matrix --case $< $(STIFF) --out $(BUILD)/$*/matrix $(SCHED) $(Q)

stage-hysteresis: $(foreach c,$(CASES),$(BUILD)/$(c)/hysteresis/hysteresis.json)
$(BUILD)/%/hysteresis/hysteresis.json: cases/%.toml $(BUILD)/%/fem/stiffness.json $(SRC_dynamics) | $(STAMP)
	$(RUN) hysteresis --case $< $(STIFF) --out $(BUILD)/$*/hysteresis $(Q)

stage-fourbar: $(foreach c,$(CASES),$(BUILD)/$(c)/fourbar/comparison.md)
$(BUILD)/%/fourbar/comparison.md: cases/%.toml $(BUILD)/%/fem/stiffness.json $(SRC_fourbar) $(SRC_dynamics) | $(STAMP)
	$(RUN) fourbar --case $< $(STIFF) --out $(BUILD)/$*/fourbar $(Q)

stage-tolerance: $(foreach c,$(CASES),$(BUILD)/$(c)/tolerance/summary.json)
$(BUILD)/%/tolerance/summary.json: cases/%.toml $(BUILD)/%/fem/stiffness.json $(SRC_fourbar) | $(STAMP)
	$(RUN) tolerance --case $< $(STIFF) --samples $(SAMPLES) --out $(BUILD)/$*/tolerance $(SCHED) $(Q)

# Diagnosis runs where bench records exist for the case: the real RV-160N records (read in place,
# never copied); the RV-40E cases have none shipped.
RECORDS_rv160n-81 = $(wildcard $(MEASURED)/rv160n_*.csv)
stage-diagnosis: $(foreach c,$(CASES),$(if $(RECORDS_$(c)),$(BUILD)/$(c)/diagnosis/diagnosis.json))
$(BUILD)/%/diagnosis/diagnosis.json: cases/%.toml $(BUILD)/%/fem/stiffness.json $(SRC_diagnosis) $(SRC_dynamics) | $(STAMP)
	$(RUN) diagnose --case $< $(STIFF) --measured $(RECORDS_$*) --out $(BUILD)/$*/diagnosis $(Q)

# Paper 001's no-load bench case (RV-40E, i = 81) as a worked example of the coaxiality diagnosis.
$(BUILD)/%/diagnosis/paper001.json: cases/%.toml $(BUILD)/%/fem/stiffness.json $(SRC_diagnosis) $(SRC_dynamics) | $(STAMP)
	$(RUN) paper001 --case $< $(STIFF) --out $(BUILD)/$*/diagnosis $(Q)

STAGES = geometry/profile.csv mesh/crankshaft_mesh.npz fem/stiffness.json matrix/te_std.csv hysteresis/hysteresis.json \
         fourbar/comparison.md tolerance/summary.json
report: $(foreach c,$(CASES),$(BUILD)/$(c)/report/index.html)
.SECONDEXPANSION:
$(BUILD)/%/report/index.html: cases/%.toml $$(addprefix $(BUILD)/%/,$(STAGES)) \
        $$(if $$(RECORDS_$$*),$(BUILD)/%/diagnosis/diagnosis.json) \
        $$(if $$(filter rv40e-81,$$*),$(BUILD)/%/diagnosis/paper001.json) pipeline/report.py | $(STAMP)
	$(RUN) report --case $< --build $(BUILD) $(Q)

test: $(STAMP)
	$(PY) -m pytest -q -p no:cacheprovider

bench: $(STAMP)
	$(PY) bench/run_all.py --out $(BUILD)/bench.json

clean:
	rm -rf $(BUILD)
