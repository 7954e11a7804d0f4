# fsrlab: every target sets up what it needs on a fresh machine.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed-stamp
REPORT ?= report

.PHONY: venv sysdeps demo test bench firmware clean

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

demo: venv
	$(BIN)/fsrlab paper --out $(REPORT)

test: venv sysdeps firmware
	$(BIN)/python -m pytest

bench: venv sysdeps firmware
	$(BIN)/python benchmarks/run.py

clean:
	rm -rf $(VENV) $(REPORT) build firmware/build .pytest_cache .hypothesis
