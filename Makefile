# icewall: every target does its own set-up (creates .venv and installs) on a fresh machine.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed
DECK ?= decks/cf4.yaml

# the converged scheme with the readings its runs in docs/solver.md use (items 18, 22)
NEWTON := --set analysis.scheme=newton --set materials.concrete.mode_rule_band=0.1 \
	--set materials.concrete.post_peak_strength=peak

.PHONY: run test test-platforms lint stability validate compare convergence convergence-newton cylinder bench schema clean

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)

$(STAMP): $(BIN)/python pyproject.toml
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e ".[dev]"
	touch $(STAMP)

RUN_FIELDS ?= [displacement, stress, strain, state]

run: $(STAMP)  ## run the CF-4 deck (or DECK=...), storing the state fields the crack plots need
	$(BIN)/icewall run $(DECK) --set 'outputs.fields=$(RUN_FIELDS)'

# the default suite in two worker processes (CI has 2 cores), each test file on one worker so
# that a file's shared runs (module fixtures) are made once; TEST_WORKERS=0 runs it in-process
TEST_WORKERS ?= 2

test: $(STAMP)  ## the default test suite (fast; no long validation runs)
	$(BIN)/python -m pytest -q -m "not slow" -n $(TEST_WORKERS) --dist loadfile

test-platforms: $(STAMP)  ## the numerical test folders under every OpenBLAS kernel this CPU runs (by hand, before a numerical change lands; not part of `make test`)
	$(BIN)/python tools/test_platforms.py

lint: $(STAMP)
	$(BIN)/ruff check icewall tests benchmarks tools

stability: $(STAMP)  ## the stability suite: stiff and extreme cases, each run twice (minutes)
	$(BIN)/python -m pytest -q -m stability tests/stability

ANALYSED := cf4 cf5 cf8 cf13 tf1 tf2 tf4 vtt3
BLIND := cf6 cf7 cf14 tf3 tf5 tf6 tf7 vtt1 vtt2 vtt4

validate: $(STAMP)  ## all specimen decks at full resolution, 3 round-off realizations each (long)
	$(BIN)/icewall sweep $(foreach d,$(ANALYSED) $(BLIND),decks/$(d).yaml) --realizations 3 \
	    --set 'outputs.fields=[]' -o results/validation

compare: $(STAMP)  ## CI variants of the analysed decks (to just past their peaks) against the stored baseline
	$(BIN)/python -m icewall.analysis.ci_gate -o results/compare

$(VENV)/.plot: $(STAMP)
	$(BIN)/python -m pip install --quiet -e ".[dev,plot]"
	touch $(VENV)/.plot

convergence: $(VENV)/.plot  ## CF-4 and TF-1 over a discretisation ladder (long): results/convergence
	$(BIN)/icewall convergence decks/cf4.yaml -j 2 -o results/convergence/cf4
	$(BIN)/icewall convergence decks/tf1.yaml -j 2 -o results/convergence/tf1

NEWTON_LADDER := --ladder docs/convergence/newton_ladder.yaml

convergence-newton: $(VENV)/.plot  ## the Newton scheme's own error (step, tolerances) on CF-4 and TF-1 (long)
	$(BIN)/icewall convergence decks/cf4.yaml $(NEWTON_LADDER) $(NEWTON) \
		--set loads.control.target=10.5 -j 2 -o results/convergence-newton/cf4
	$(BIN)/icewall convergence decks/tf1.yaml $(NEWTON_LADDER) $(NEWTON) \
		--set loads.control.target=8 -j 2 -o results/convergence-newton/tf1

cylinder: $(STAMP)  ## thesis Appendix A: 24 axisymmetric cylinders, fit of alpha_c, n (long)
	$(BIN)/python -m icewall.analysis.cylinder -j 2 -o results/cylinder

PEERS_VENV ?= $(HOME)/.cache/bench-peers-venv

bench: $(STAMP)  ## benchmarks, outside the test suite; tables printed, CSV in benchmarks/out
	$(BIN)/python benchmarks/bench_concrete.py
	$(BIN)/python benchmarks/bench_iteration.py
	$(BIN)/python benchmarks/bench_iteration.py --name iteration_newton --backends superlu:COLAMD \
	    $(NEWTON) --set 'outputs.fields=[]' --set loads.control.target=7.5
	$(BIN)/python benchmarks/bench_scaling.py --backends superlu superlu:COLAMD
	ICEWALL_SPARSE_SOLVER=auto ICEWALL_SUPERLU_ORDERING=COLAMD $(BIN)/python \
	    benchmarks/bench_scaling.py --backends superlu:COLAMD --csv scaling_fast.csv
	$(BIN)/python benchmarks/bench_backends.py capture --name cf4_50mm --deck decks/cf4.yaml \
	    --set analysis.scheme=newton --set analysis.tolerance_load=0.0001 \
	    --set analysis.tolerance_displacement=0.0001 --set analysis.max_iterations=40 \
	    --set 'outputs.fields=[]' --set loads.control.target=4 --every 6 --max 12
	MKL_NUM_THREADS=1 $(BIN)/python benchmarks/bench_backends.py time --repeats 5
	test -x $(PEERS_VENV)/bin/python || bash ../shared/bench-peers/setup_venv.sh $(PEERS_VENV)
	$(BIN)/python benchmarks/bench_peers.py --peers-python $(PEERS_VENV)/bin/python

schema: $(STAMP)  ## regenerate the published JSON Schema of the deck format
	$(BIN)/icewall schema -o docs/deck.schema.json

clean:
	rm -rf $(VENV) results .pytest_cache .ruff_cache
