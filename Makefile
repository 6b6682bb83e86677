# sphfmu — build, demo, tests, benchmarks. See README.md.
SHELL := /bin/bash
CARGO ?= cargo
PYTHON ?= python3
VENV := target/venv
VPY := $(VENV)/bin/python
BIN := target/release/sphfmu

.PHONY: all build demo test test-rust test-python venv bench bench-peer verify clean

all: build

build:
	$(CARGO) build --release

# Main job (until the FMU lands): run the Sod shock tube and plot it against the exact
# Riemann solution -> target/demo/profile.png
demo: build
	$(BIN) run models/sod.toml --out target/demo

# Every test: Rust unit/integration tests, then the Python tests in a venv made here.
test: test-rust test-python

test-rust:
	$(CARGO) test --release

$(VENV)/.installed: tests/fmpy/requirements.txt
	$(PYTHON) -m venv $(VENV)
	$(VPY) -m pip install --quiet --upgrade pip
	$(VPY) -m pip install --quiet -r tests/fmpy/requirements.txt
	touch $@

venv: $(VENV)/.installed

test-python: build venv
	$(VPY) -m pytest tests/fmpy -q

# Throughput table (particle-updates/s, pair interactions/s), 2D and 3D periodic boxes.
bench: build
	$(BIN) bench --sizes 10000,100000,1000000 --dims 2,3 --steps 5 --json target/bench.json

# Side-by-side with PySPH on the 2D Noh problem (installs PySPH into target/peer-venv).
bench-peer: build
	tools/bench_peer.sh

# Heavy verification runs: the ignored tests (the paper-resolution hydrostatic square) and
# the CRKSPH paper's Noh and Sedov with each of its schemes (tools/verify_schemes.sh).
verify: build
	$(CARGO) test --release -- --ignored --nocapture
	mkdir -p target/verify && tools/verify_schemes.sh | tee target/verify/table.md

clean:
	$(CARGO) clean
