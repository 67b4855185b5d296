# beatsync: the two commands are `make reproduce` and `make test`.
# Both create .venv (Python >= 3.11) and install the package with pinned-range
# dependencies first; nothing else needs to be installed by hand.

PYTHON ?= python3
VENV   ?= .venv
BIN     = $(VENV)/bin
STAMP   = $(VENV)/.installed
PARAMS ?= params/paper.yaml
# Pass e.g. PYTEST_ARGS="-x -q" to change pytest's options.
PYTEST_ARGS ?= -q

.PHONY: setup reproduce test test-unit test-notebooks bench notebooks lint clean help

help:
	@echo "make reproduce   set up .venv and run the whole study into results/"
	@echo "make test        set up .venv and run unit tests + nbval on the notebooks"
	@echo "make bench       run the benchmarks into benchmarks/RESULTS.md"
	@echo "make notebooks   re-execute the committed notebooks with params/ci.yaml"
	@echo "make lint        ruff on src/ tests/ benchmarks/"

$(STAMP): pyproject.toml
	@$(PYTHON) -c 'import sys; assert sys.version_info >= (3, 11), "beatsync needs Python >= 3.11, found " + sys.version' 
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e ".[test,dev]"
	@touch $(STAMP)

setup: $(STAMP)

reproduce: setup
	$(BIN)/beatsync reproduce --params $(PARAMS) --output results/notebooks

test: setup test-unit test-notebooks

test-unit: setup
	$(BIN)/python -m pytest $(PYTEST_ARGS) tests

# nbval re-executes every committed notebook and compares its text outputs;
# cells tagged nbval-ignore-output (timings) are run but not compared.
test-notebooks: setup
	$(BIN)/beatsync reproduce --params params/ci.yaml --check
	$(BIN)/python -m pytest $(PYTEST_ARGS) -p no:cacheprovider --nbval \
	    --nbval-sanitize-with notebooks/nbval_sanitize.cfg notebooks

bench: setup
	$(BIN)/python benchmarks/run_all.py

notebooks: setup
	$(BIN)/beatsync reproduce --params params/ci.yaml --in-place

lint: setup
	$(BIN)/ruff check src tests benchmarks

clean:
	rm -rf $(VENV) .pytest_cache results/ci
