# icewall: every target does its own set-up (creates .venv and installs) on a fresh machine.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed
DECK ?= decks/cf4.yaml

.PHONY: run test lint validate bench schema clean

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)

$(STAMP): $(BIN)/python pyproject.toml
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e ".[dev]"
	touch $(STAMP)

run: $(STAMP)  ## run the CF-4 deck (or DECK=...)
	$(BIN)/icewall run $(DECK)

test: $(STAMP)  ## the default test suite (fast; no long validation runs)
	$(BIN)/python -m pytest -q -m "not slow"

lint: $(STAMP)
	$(BIN)/ruff check icewall tests benchmarks

validate: $(STAMP)  ## long validation runs (marked slow)
	$(BIN)/python -m pytest -q -m slow

bench: $(STAMP)  ## benchmarks, outside the test suite
	$(BIN)/python benchmarks/bench_concrete.py

schema: $(STAMP)  ## regenerate the published JSON Schema of the deck format
	$(BIN)/icewall schema -o docs/deck.schema.json

clean:
	rm -rf $(VENV) results .pytest_cache .ruff_cache
