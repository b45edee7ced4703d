# Two entry points: `make reproduce` (the paper's report) and `make test`.
# Both create the virtual environment and install the package on a fresh machine.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed
OUT ?= report
DOCS_OUT ?= docs/_build/html

.PHONY: reproduce test test-fast lint typecheck docs docs-check bench clean chromium

# The install must build without a warning (a deprecated pyproject key is next year's broken
# build): the backend's output is kept and searched. The only lines let through are pip's
# notes on this machine's index configuration ("Location '...' is ignored"), which are not
# the project's.
$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install -e '.[test,dask,lint,docs,fmi]' > $(VENV)/install.log 2>&1 \
	  || { cat $(VENV)/install.log; exit 1; }
	@if grep -iE "warning|deprecat|!!" $(VENV)/install.log \
	     | grep -vE "^WARNING: Location '[^']*' is ignored"; then \
	   echo "error: pip install printed the warnings above ($(VENV)/install.log)"; exit 1; fi
	@grep -E "^Successfully installed" $(VENV)/install.log
	# numba's cache, built once here: the first command after install is as fast as the second
	$(BIN)/python -m empact._compile
	touch $(STAMP)

reproduce: $(STAMP)
	MPLBACKEND=Agg $(BIN)/empact reproduce --out $(OUT) --force

# The report test renders the page in headless Chromium (Debian's package; needs root or sudo).
chromium:
	@command -v chromium >/dev/null 2>&1 || command -v chromium-browser >/dev/null 2>&1 || \
	  { echo "installing chromium (apt-get) for the report's browser test"; \
	    (apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium) \
	    >/dev/null || { echo "error: could not install chromium; install it and rerun"; exit 1; }; }

# ruff: pyflakes, pycodestyle errors and import order (configured in pyproject.toml)
lint: $(STAMP)
	$(BIN)/ruff check src tests bench examples docs

# mypy over the package (configured in pyproject.toml; every ignore there says why); run by
# .ci/run (a cold run takes about a minute, so make test leaves it to CI and to you)
typecheck: $(STAMP)
	$(BIN)/mypy

# The whole suite (CI runs it): the fast tier and the slow tests (marker slow).
test: $(STAMP) chromium lint
	MPLBACKEND=Agg $(BIN)/python -m pytest -q

# The fast tier while editing: every test but the end-to-end ones (the full report, the
# README tour, a real Ctrl-C, Dask clusters) and the slow ones (tests/conftest.py marks them slow).
test-fast: $(STAMP)
	MPLBACKEND=Agg $(BIN)/python -m pytest -q -m "not docs_site and not slow"

# The Sphinx site with its gallery (examples/plot_*.py are run); warnings are errors.
docs: $(STAMP)
	rm -rf $(DOCS_OUT) docs/api/generated docs/gallery
	MPLBACKEND=Agg $(BIN)/sphinx-build -W --keep-going -q -b html docs $(DOCS_OUT)
	@echo "docs: $(DOCS_OUT)/index.html"

# The built site in headless Chromium: links, anchors, images (.ci/run runs it after docs)
docs-check: docs chromium
	MPLBACKEND=Agg $(BIN)/python -m pytest -q -m docs_site tests/test_docs_site.py

bench: $(STAMP)
	$(BIN)/python -m pip install --quiet -e '.[bench]' || echo "scikit-sundae not installed: bench_integrators skips CVODE"
	for f in bench/bench_*.py; do MPLBACKEND=Agg $(BIN)/python $$f || exit 1; done

clean:
	rm -rf $(VENV) $(OUT) build src/*.egg-info .pytest_cache .mypy_cache docs/_build docs/api docs/gallery
