# Two commands: `make demo` and `make test` (and `make docs`). Each creates .venv on first use.
PYTHON ?= python3.11
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: demo test test-fast docs lint bench clean

$(STAMP): pyproject.toml paper/pyproject.toml constraints.txt
	@test -x $(BIN)/python || $(PYTHON) -m venv $(VENV) || python3 -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -c constraints.txt -e '.[test,paper,docs]' -e ./paper
	@touch $(STAMP)

demo: $(STAMP)
	MPLBACKEND=Agg $(BIN)/discrepancy reproduce all --out out/

# Two workers (the machines have 2 cores); a module's tests stay on one worker, so its
# expensive fixtures (a whole campaign, a simulated recording) are computed once; the ten
# slowest tests are listed at the end. One BLAS thread per worker: with a thread per core
# each, BLAS threads spin waiting on each other (the prediction-error quick run alone took
# 17.3 s of CPU against 13.2 s; the whole suite 697 s against 680 s).
THREADS := OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 MKL_NUM_THREADS=1
test: $(STAMP)
	MPLBACKEND=Agg $(THREADS) $(BIN)/python -m pytest -q -n 2 --dist loadscope --durations=10

# The inner loop: everything but the end-to-end tests marked slow (`make test` runs those too).
test-fast: $(STAMP)
	MPLBACKEND=Agg $(THREADS) $(BIN)/python -m pytest -q -n 2 --dist loadscope -m "not slow"

# The site in docs/_build/html: API pages from the docstrings, the gallery (examples/) run,
# warnings are errors; then every public name and internal link is checked.
docs: $(STAMP)
	MPLBACKEND=Agg $(BIN)/sphinx-build -W --keep-going -b html docs docs/_build/html
	$(BIN)/python docs/check_api.py docs/_build/html

lint: $(STAMP)
	$(BIN)/ruff check src tests benchmarks paper docs examples

bench: $(STAMP)
	$(BIN)/python benchmarks/run_all.py

clean:
	rm -rf $(VENV) out docs/_build docs/api docs/auto_examples
