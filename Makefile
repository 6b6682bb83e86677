# sphfmu — build, demo, tests, benchmarks. See README.md.
SHELL := /bin/bash
CARGO ?= cargo
PYTHON ?= python3
VENV := target/venv
VPY := $(VENV)/bin/python
BIN := target/release/sphfmu

.PHONY: all build fmu demo test test-rust test-python test-import libclang openmpi venv bench bench-peer verify clean

# Every build has the `mpi` feature (`mpirun -n R sphfmu run`), so that build, test and fmu
# share one compiled tree (a feature set of its own would rebuild the solver and the FMU).
# The FMU library does not link Open MPI (only the sphfmu binary calls it); the sphfmu binary
# needs Open MPI's runtime, which `openmpi` installs with the headers the build probes.
FEATURES := --features sphfmu/mpi

all: build

# Always the whole workspace, as `cargo test --workspace` builds it: cargo unifies features
# over the packages it builds, and a root-only build would resolve serde, syn, memchr ... with
# other features and compile the dependency tree a second time (minutes on 2 cores).
build: openmpi libclang
	$(CARGO) build --release --workspace $(FEATURES)

# The FMUs: target/fmu/sphfmu.fmu (FMI 3.0) and sphfmu-fmi2.fmu (FMI 2.0) for the demo's
# free piston, and the same pair for the hydrostatic tank under target/fmu/closed-tank2d/, the
# channel between two pressure ports under target/fmu/channel-ports2d/ and the sloshing tank
# under target/fmu/slosh2d/, and the 3D box driven in six degrees of freedom under
# target/fmu/box3d/ (orientation as a quaternion) and target/fmu/box3d-matrix/ (as Modelica's
# R.T), and the light piston under a water column (strong coupling) under
# target/fmu/added-mass2d/, the tuned liquid damper under target/fmu/tld2d/ and the pitched 3D
# tank under target/fmu/pitch3d/ (the tests use them all; `make verify` the last two). `make fmu FMU_CASE=models/x.toml` also
# packages x under target/fmu/<its case name>/ and leaves the others alone. `cargo build
# --workspace` also builds the zenoh node sphfmu-serve (`sphfmu serve`).
DEMO_CASE := models/free-piston2d.toml
FMU_CASE ?=
FMU_LIB := target/release/libsphfmu_fmu.so
PACKAGE := target/release/sphfmu-package --lib $(FMU_LIB) --models models
fmu: openmpi libclang
	$(CARGO) build --release --workspace $(FEATURES)
	$(PACKAGE) --case $(DEMO_CASE) --out target/fmu
	$(PACKAGE) --case models/closed-tank2d.toml --out target/fmu/closed-tank2d
	$(PACKAGE) --case models/channel-ports2d.toml --out target/fmu/channel-ports2d
	$(PACKAGE) --case models/slosh2d.toml --out target/fmu/slosh2d
	$(PACKAGE) --case models/box3d.toml --out target/fmu/box3d
	$(PACKAGE) --case models/box3d.toml --set 'body.0.orientation="matrix"' --out target/fmu/box3d-matrix
	$(PACKAGE) --case models/added-mass2d.toml --out target/fmu/added-mass2d
	$(PACKAGE) --case models/tld2d.toml --out target/fmu/tld2d
	$(PACKAGE) --case models/pitch3d.toml --out target/fmu/pitch3d
	$(if $(FMU_CASE),$(PACKAGE) --case $(FMU_CASE))

# Main job: build the FMU and co-simulate a free piston on a gas spring with a Python master
# (fmpy) -> target/demo/free_piston.png, and the period against the gas-spring theory.
demo: fmu venv
	$(VPY) tools/free_piston.py --fmu target/fmu/sphfmu.fmu --out target/demo

# Every test: Rust unit/integration tests (library and FMU crate), the FMU packages, then the
# Python tests (fmpy as the master) in a venv made here.
test: test-rust test-python test-import

test-rust: openmpi libclang
	$(CARGO) test --release --workspace $(FEATURES)

$(VENV)/.installed: tests/fmpy/requirements.txt
	$(PYTHON) -m venv $(VENV)
	$(VPY) -m pip install --quiet --upgrade pip
	$(VPY) -m pip install --quiet -r tests/fmpy/requirements.txt
	touch $@

venv: $(VENV)/.installed

test-python: build fmu venv
	$(VPY) -m pytest tests/fmpy -q

# A second master besides fmpy: rust-fmi's importer steps both packaged FMUs
# (fmu/import-test, its own workspace: fmi-sys runs bindgen, which needs libclang).
test-import: fmu libclang
	cd fmu/import-test && CARGO_TARGET_DIR=$(CURDIR)/target/import-test $(CARGO) test --release

# libclang for bindgen (rsmpi's mpi-sys, rust-fmi's fmi-sys): Debian's libclang-dev, installed
# when what bindgen loads is missing (tools/ensure_libclang.sh says what it looks for and why a
# glob is not enough).
libclang:
	tools/ensure_libclang.sh

# Open MPI for the mpi feature (rsmpi probes mpicc; the tests start ranks with mpirun):
# Debian's libopenmpi-dev and openmpi-bin, installed when missing (tools/ensure_openmpi.sh).
openmpi:
	tools/ensure_openmpi.sh

# Throughput table (particle-updates/s, pair interactions/s, the force loop's own rate and
# the neighbour share), 2D and 3D periodic boxes, each size timed over at least 1e7
# particle-updates over the same 5 steps of a fresh box (200 times over for 1e4 particles, twice
# for 1e6); the 1e6 3D box on 2 ranks x 1 thread
# (mpirun; bytes per step, exchange share, halo size; docs/scaling.md); live coupling on loopback (round trips with
# the zenoh node, publishing's cost per doStep); the side-by-side with PySPH (bench-peer); then
# every performance goal with its figure, baseline, target and pass/short
# (tools/bench_goals.py -> target/bench-goals.md). About 25 minutes on 2 cores, plus PySPH's
# install the first time.
bench: build fmu venv
	$(BIN) bench --sizes 10000,100000,1000000 --dims 2,3 --steps 5 --min-updates 10000000 --json target/bench.json
	OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 mpirun --oversubscribe -n 2 \
	  $(BIN) bench --sizes 1000000 --dims 3 --steps 5 --min-updates 10000000 --threads 1 --json target/bench-mpi.json
	$(VPY) tools/bench_zenoh.py --json target/bench-zenoh.json
	tools/bench_peer.sh --rounds 3
	$(VPY) tools/bench_goals.py

# Side-by-side with PySPH on the 2D Noh problem (installs PySPH into target/peer-venv).
bench-peer: build
	tools/bench_peer.sh

# The verification suite: every headline claim of the three papers (models/verify/suite.toml)
# run with every scheme it compares, judged against the paper's figure, reported in
# docs/verification/README.md with its PNGs (tools/verify.py; VERIFY_ARGS="--only ID,..." for a
# part). Then the remaining ignored tests (paper-resolution Sedov and Noh, the kernel choice)
# and the long co-simulations (pytest marker `verify`: the tuned liquid damper, the 3D tank in
# pitch).
VERIFY_ARGS ?=
verify: build fmu venv
	$(VPY) tools/verify.py --jobs 2 $(VERIFY_ARGS)
	$(CARGO) test --release $(FEATURES) -- --ignored --nocapture
	SPHFMU_VERIFY=1 $(VPY) -m pytest tests/fmpy -q -s -m verify

clean:
	$(CARGO) clean
