# beatsync: the two commands are `make reproduce` and `make test`.
# Both set up .venv from the committed lock (uv.lock) with Python 3.11 first;
# nothing else needs to be installed by hand. `make lock` refreshes the lock.

PYTHON     ?= python3.11
VENV       ?= .venv
BIN         = $(VENV)/bin
STAMP       = $(VENV)/.installed
# uv itself is pinned and installed into .uv/ with pip (the only unpinned step is pip).
UV_VERSION  = 0.13.8
UV_DIR      = .uv
UV          = $(UV_DIR)/bin/uv
EXTRAS     ?= --extra test --extra dev --extra peers
# `make lab`, `make docs` and `make test-browser` add these (one set for the three, so
# that going from one to another does not re-sync .venv)
SITE_EXTRAS = --extra lab --extra docs --extra browser
# the site's build (docs/_build keeps the doctrees, so that a rebuild reads only what
# changed); warnings are errors
SPHINXOPTS ?= -W --keep-going
# Debian's chromium, driven by playwright in the browser tests (never a browser of its own)
CHROMIUM   ?= /usr/bin/chromium
PARAMS     ?= params/paper.yaml
# Pass e.g. PYTEST_ARGS="-x -q" to change pytest's options.
PYTEST_ARGS ?= -q
# Tests run on every CPU (pytest-xdist); --dist loadscope keeps a notebook's cells
# (and a module's tests) on one worker. XDIST= runs them in one process.
XDIST      ?= -n auto --dist loadscope
NBVAL       = -p no:cacheprovider --nbval --nbval-sanitize-with notebooks/nbval_sanitize.cfg
# the Examples of the package's docstrings run as tests too
DOCTEST     = --doctest-modules src/beatsync

# uv never downloads a Python of its own: the machine's Python 3.11 is used.
export UV_PYTHON_DOWNLOADS = never
export UV_PROJECT_ENVIRONMENT = $(VENV)

.PHONY: setup lock reproduce test test-unit test-notebooks test-browser bench notebooks lint lab docs clean help FORCE

help:
	@echo "make reproduce   set up .venv from uv.lock and run the whole study into results/"
	@echo "make test        set up .venv from uv.lock and run unit tests + nbval on the notebooks"
	@echo "make lock        re-resolve the newest allowed versions into uv.lock (and environment.yml)"
	@echo "make bench       run the benchmarks into benchmarks/RESULTS.md"
	@echo "make notebooks   re-execute the committed notebooks (params/ci.yaml) and the tutorials"
	@echo "make lint        ruff on src/ tests/ tests_browser/ benchmarks/ and the site's Python"
	@echo "make lab         install the lab extra from uv.lock and open JupyterLab at notebooks/"
	@echo "make docs        build the static site into docs/_build/html (open docs/_build/html/index.html)"
	@echo "make test-browser  build the site, then test it and JupyterLab in headless Chromium"

$(UV):
	@$(PYTHON) -c 'import sys; assert sys.version_info[:2] == (3, 11), "beatsync is locked for Python 3.11, found " + sys.version' 
	$(PYTHON) -m venv $(UV_DIR)
	$(UV_DIR)/bin/python -m pip install --quiet --disable-pip-version-check "uv==$(UV_VERSION)"

# --locked: refuse a uv.lock that does not match pyproject.toml (run `make lock`).
# --compile-bytecode: every process of the tests and the study would otherwise parse
# scipy, pandas and matplotlib from source again where bytecode is not written
# (PYTHONDONTWRITEBYTECODE, read-only installs): 9 s instead of 3 s per import.
# Then librosa's numba functions are compiled into their on-disk cache by one process:
# the parallel test workers and notebook kernels compiling them at once can pair cache
# files written by different processes and crash (numba issue 10128; beatsync.other_trackers.prepare).
# The stamp holds the extras it was installed with: other extras (`make setup EXTRAS=...`,
# `make lab`) sync .venv again.
ifneq ($(strip $(file < $(STAMP))),$(strip $(EXTRAS)))
$(STAMP): FORCE
endif
$(STAMP): uv.lock pyproject.toml | $(UV)
	$(UV) sync --locked --compile-bytecode --python $(PYTHON) $(EXTRAS)
	$(BIN)/python -c "from beatsync import other_trackers; other_trackers.prepare('librosa')"
	@echo '$(strip $(EXTRAS))' > $(STAMP)

setup: $(STAMP)

lock: | $(UV)
	$(UV) lock --upgrade --python $(PYTHON)
	$(UV) run --no-project --python $(PYTHON) python scripts/environment_from_lock.py

reproduce: setup
	$(BIN)/beatsync reproduce --params $(PARAMS) --output results/notebooks

# The unit tests and nbval in one run, so that both CPUs stay busy to the end.
# nbval re-executes every committed notebook and compares its text outputs;
# cells tagged nbval-ignore-output (timings) are run but not compared.
test: setup
	$(BIN)/beatsync reproduce --params params/ci.yaml --check
	$(BIN)/python -m pytest $(PYTEST_ARGS) $(XDIST) $(NBVAL) $(DOCTEST) tests notebooks

test-unit: setup
	$(BIN)/python -m pytest $(PYTEST_ARGS) $(XDIST) $(DOCTEST) tests

test-notebooks: setup
	$(BIN)/beatsync reproduce --params params/ci.yaml --check
	$(BIN)/python -m pytest $(PYTEST_ARGS) $(XDIST) $(NBVAL) notebooks

bench: setup
	$(BIN)/python benchmarks/run_all.py

notebooks: setup
	$(BIN)/beatsync reproduce --params params/ci.yaml --in-place
	for nb in notebooks/tutorials/[0-9]*.ipynb; do \
	    $(BIN)/papermill -k python3 --cwd notebooks/tutorials "$$nb" "$$nb" || exit 1; \
	done

# JupyterLab at notebooks/ (the tutorials are in notebooks/tutorials/); ipywidgets 8
# brings the lab extension its sliders need.
lab:
	@$(MAKE) --no-print-directory setup EXTRAS="$(EXTRAS) $(SITE_EXTRAS)"
	$(BIN)/jupyter lab --ServerApp.root_dir=notebooks $(if $(filter 0,$(shell id -u)),--allow-root)

# The site (docs/conf.py says how the notebooks get in); the committed notebooks' outputs
# are shown as they are, never executed here.
docs:
	@$(MAKE) --no-print-directory setup EXTRAS="$(EXTRAS) $(SITE_EXTRAS)"
	$(BIN)/sphinx-build -M html docs docs/_build $(SPHINXOPTS)

# Every page of the site and a widget in JupyterLab, in headless Chromium (.ci/run
# installs Debian's chromium where it is missing).
test-browser: docs
	BEATSYNC_CHROMIUM=$(CHROMIUM) $(BIN)/python -m pytest $(PYTEST_ARGS) -p no:cacheprovider -n 0 tests_browser

FORCE:

lint: setup
	$(BIN)/ruff check src tests tests_browser benchmarks docs/_ext docs/conf.py

clean:
	rm -rf $(VENV) $(UV_DIR) .pytest_cache results/ci docs/_build docs/notebooks
