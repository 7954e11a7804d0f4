# fsrlab: every target sets up what it needs on a fresh machine.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed-stamp
REPORT ?= report
DEMO   ?= demo

.PHONY: venv sysdeps demo test bench firmware clean live-screenshot

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

# The measurement chain on the virtual bench (record, calibrate, apply, hysteresis), then the
# paper's reproduction report. The recordings run in real time: about 20 s.
demo: venv
	@mkdir -p $(DEMO)
	$(BIN)/fsrlab acquire --virtual --profile triangle --duration 8.5s --seed 1 --out $(DEMO)/calibration-run.csv --overwrite --quiet
	$(BIN)/fsrlab acquire --virtual --profile sine --duration 8.5s --seed 2 --out $(DEMO)/test-run.csv --overwrite --quiet
	$(BIN)/fsrlab calibrate $(DEMO)/calibration-run.csv --compensate -o $(DEMO)/calibration.json
	$(BIN)/fsrlab apply $(DEMO)/calibration.json $(DEMO)/test-run.csv -o $(DEMO)/test-estimate.csv --overwrite
	$(BIN)/fsrlab hysteresis $(DEMO)/test-run.csv --quantity frequency_hz
	$(BIN)/fsrlab hysteresis $(DEMO)/test-estimate.csv --quantity stress_pa_estimate
	$(BIN)/fsrlab paper --out $(REPORT)

test: venv sysdeps firmware
	$(BIN)/python -m pytest

bench: venv sysdeps firmware
	$(BIN)/python -m pip install -q -e '.[dev,bench]'
	$(BIN)/python benchmarks/run.py

# docs/live.png: the live page on the virtual bench, as a real headless Chromium renders it.
live-screenshot: venv sysdeps
	$(BIN)/python scripts/live_screenshot.py

clean:
	rm -rf $(VENV) $(REPORT) $(DEMO) build firmware/build .pytest_cache .hypothesis
