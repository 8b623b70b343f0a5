# The whole set-up is `make run` or `make test`; both create .venv if missing.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: install run test lint bench clean

install: $(STAMP)

$(STAMP): pyproject.toml
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e ".[dev]"
	touch $(STAMP)

run: install
	$(BIN)/cell run tasks/bins.yaml

lint: install
	$(BIN)/ruff check cell tests examples
	$(BIN)/ruff format --check cell tests examples
	$(BIN)/mypy cell

test: lint
	$(BIN)/python -m pytest -q -p no:cacheprovider tests

bench: install
	$(BIN)/cell bench

clean:
	rm -rf $(VENV) build *.egg-info
