# Two commands on a fresh machine (each makes .venv by itself):
#   make run    open the explorer on the embedded synthetic talker
#   make test   lint (ruff), type-check the engine (mypy), then run the whole test suite (GUI tests on the
#               virtual X server pytest-xvfb starts: install the xvfb package)
#   make docs   build the guide and the API reference into docs/_build/html (warnings are errors)
PY      ?= python3
VENV    := .venv
BIN     := $(VENV)/bin
STAMP   := $(VENV)/.installed

.PHONY: run test docs venv bench clean

$(STAMP): pyproject.toml
	test -x $(BIN)/python || $(PY) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[test,docs,scale,video,parquet]'
	touch $(STAMP)

venv: $(STAMP)

run: $(STAMP)
	$(BIN)/lipspace explore

test: $(STAMP)
	$(BIN)/ruff check .
	$(BIN)/python -m mypy
	$(BIN)/python -m pytest -q $(PYTEST_ARGS)

docs: $(STAMP)
	rm -rf docs/generated
	$(BIN)/python -m sphinx -b html -q -W --keep-going docs docs/_build/html
	@echo "docs: docs/_build/html/index.html"

bench: $(STAMP)
	for b in benchmarks/bench_*.py; do $(BIN)/python $$b || exit 1; done
	$(BIN)/python tools/benchmark_table.py

clean:
	rm -rf $(VENV) .pytest_cache .mypy_cache
