# fsrlab: every target sets up what it needs on a fresh machine.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed-stamp
REPORT ?= report
DEMO   ?= demo

.PHONY: venv sysdeps demo lint test bench firmware clean live-screenshot docs

venv: $(STAMP)

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install -q --upgrade pip
	$(BIN)/python -m pip install -q -e '.[dev]'
	touch $(STAMP)

sysdeps:
	@bash scripts/install-sysdeps.sh

firmware: sysdeps
	@if [ -f firmware/Makefile ]; then $(MAKE) -C firmware; fi

# The measurement chain on a virtual bench (spring cycles and dead weights recorded, calibration,
# compensation, the measurement report), then the paper's reproduction report: fsrlab demo (the bench faster than real time, --speed max).
demo: venv
	@$(MAKE) -s -C firmware >/dev/null 2>&1 || echo "firmware and twin not built (make sysdeps installs the tools): the demo uses the Python virtual device"
	$(BIN)/fsrlab demo --out $(DEMO)

# ruff with the configuration in pyproject.toml ([tool.ruff]: pyflakes, pycodestyle, bugbear, import order,
# pyupgrade, McCabe complexity at most 15) over the package, its tests, the benchmarks and the scripts.
lint: venv
	$(BIN)/ruff check src tests benchmarks scripts

test: venv lint sysdeps firmware
	$(BIN)/python -m pytest

bench: venv sysdeps firmware
	$(BIN)/python -m pip install -q -e '.[dev,bench]'
	$(BIN)/python benchmarks/run.py

# The manual (Sphinx: user guide, CLI and API reference, the gallery of examples/plot_*.py) into docs/_build/html,
# every warning an error. The pages Sphinx generates (API, CLI, gallery) are made again each time.
DOCS_STAMP := $(VENV)/.docs-stamp

$(DOCS_STAMP): $(STAMP)
	$(BIN)/python -m pip install -q -e '.[dev,docs]'
	touch $(DOCS_STAMP)

docs: $(DOCS_STAMP)
	rm -rf docs/generated docs/auto_examples
	$(BIN)/sphinx-build -W --keep-going -q -b html docs docs/_build/html
	@echo "docs/_build/html/index.html"

# docs/live.png: the live page on the virtual bench, as a real headless Chromium renders it.
live-screenshot: venv sysdeps
	$(BIN)/python scripts/live_screenshot.py

clean:
	rm -rf $(VENV) $(REPORT) $(DEMO) build firmware/build .pytest_cache .hypothesis
