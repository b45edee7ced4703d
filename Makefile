# Two entry points: `make reproduce` (the paper's report) and `make test`.
# Both create the virtual environment and install the package on a fresh machine.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed
OUT ?= report

.PHONY: reproduce test bench clean chromium

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[test,dask]'
	# numba's cache, built once here: the first command after install is as fast as the second
	$(BIN)/python -m empact.nonlinear._compile
	touch $(STAMP)

reproduce: $(STAMP)
	MPLBACKEND=Agg $(BIN)/empact reproduce --out $(OUT) --force

# The report test renders the page in headless Chromium (Debian's package; needs root or sudo).
chromium:
	@command -v chromium >/dev/null 2>&1 || command -v chromium-browser >/dev/null 2>&1 || \
	  { echo "installing chromium (apt-get) for the report's browser test"; \
	    (apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium) \
	    >/dev/null || { echo "error: could not install chromium; install it and rerun"; exit 1; }; }

test: $(STAMP) chromium
	MPLBACKEND=Agg $(BIN)/python -m pytest -q

bench: $(STAMP)
	$(BIN)/python -m pip install --quiet -e '.[bench]' || echo "scikit-sundae not installed: bench_integrators skips CVODE"
	for f in bench/bench_*.py; do MPLBACKEND=Agg $(BIN)/python $$f || exit 1; done

clean:
	rm -rf $(VENV) $(OUT) build src/*.egg-info .pytest_cache
