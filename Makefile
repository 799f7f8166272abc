# pluecker developer entry points. Everything goes into ./.venv; nothing is installed globally.
#   make test    build the extension, run the Rust and Python tests (property tests: the hypothesis
#                profile "ci"; PLUECKER_HYPOTHESIS=nightly make test-python for the deep run; their
#                examples come from one seed, printed on the "property tests: ... seed" line at the end
#                of the run: the UTC date unless PLUECKER_HYPOTHESIS_SEED=<seed> replays a run or
#                =random draws a fresh one)
#   make lint    cargo fmt --check, clippy on every target with warnings as errors, rustdoc with warnings as errors,
#                ruff on the Python package, the stubs checked against the built module (mypy's stubtest)
#   make demo    reproduce both papers' experiments into results/phong-horaud-1995 and results/josephson-kahl-2008
#   make bench   compare against OpenCV, PoseLib and pycolmap, then run the criterion benchmarks
#   make mutants mutation-test the proof code (.cargo/mutants.toml); SHARD=k/n runs round-robin shard k of n
# Idempotent: the virtualenv is made once, the extension rebuilt only when a Rust source changes.

PYTHON ?= python3
PYTEST_WORKERS ?= 2
VENV := .venv
BIN := $(VENV)/bin
DEPS_STAMP := $(VENV)/.deps-stamp
DEVELOP_STAMP := $(VENV)/.develop-stamp
RUST_SOURCES := $(shell find crates -name '*.rs' -o -name Cargo.toml) Cargo.toml $(wildcard Cargo.lock)

# Cargo and maturin configure PyO3 for the same interpreter, with the environment signature maturin
# sets (cpython-3.11-64bit), so `cargo test` and `maturin develop` do not rebuild each other's PyO3.
export PYO3_PYTHON := $(CURDIR)/$(BIN)/python
export PYO3_ENVIRONMENT_SIGNATURE := $(shell $(PYTHON) -c 'import struct, sys; print(f"{sys.implementation.name}-{sys.version_info[0]}.{sys.version_info[1]}-{struct.calcsize(chr(80)) * 8}bit")')

.PHONY: setup develop test test-rust test-python lint demo bench mutants clean

setup: develop

.venv: $(DEPS_STAMP)

$(DEPS_STAMP): Makefile
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet "maturin>=1.5,<2" "numpy>=1.22" "tqdm>=4.60" "matplotlib>=3.7" "pytest>=7" "pytest-xdist>=3.5" "hypothesis>=6.100" "ruff>=0.6" "mypy>=1.18" "pycolmap>=3.11" "dask[distributed]>=2024.1" "pyarrow>=14"
	touch $@

# Rebuilds the extension when a Rust source, a manifest or pyproject.toml is newer than the last build,
# or when the built module is missing from python/pluecker/. maturin passes every dependency, the
# optional extras' too, to `pip install`, which then prints "Ignoring <package>: markers 'extra == ...'
# don't match your environment" for each; PIP_QUIET=1 leaves out these information lines and keeps
# pip's warnings and errors. The development build has the test hooks that tests/ calls (cargo feature
# `test-hooks`; inert until a test calls one), and demo, bench and lint use that same build rather than
# rebuild; the wheel (`pip install .`, `maturin build`) has none.
develop: $(DEPS_STAMP)
	@ls python/pluecker/_core*.so >/dev/null 2>&1 || rm -f $(DEVELOP_STAMP)
	@$(MAKE) --no-print-directory $(DEVELOP_STAMP)

$(DEVELOP_STAMP): $(DEPS_STAMP) $(RUST_SOURCES) pyproject.toml
	PIP_QUIET=1 VIRTUAL_ENV=$(CURDIR)/$(VENV) $(BIN)/maturin develop --release --features test-hooks --quiet
	touch $@

test: test-rust test-python

# The unit, integration and doc tests (`--tests`: the targets with test = true, so not the extension's
# lib, which `--lib` would build as an empty test harness, nor crates/pluecker-bench, whose criterion
# is then not built at all; its doc tests, none, would build it: excluded). The examples are not built here (a plain
# `cargo test` builds the six in release: about a sixth of a cold test build); `make lint`'s
# clippy --all-targets type-checks them, and `.ci/rust_newcomer.sh` builds and runs the README's example.
test-rust: develop
	cargo test --workspace --release --tests
	cargo test --workspace --exclude pluecker-bench --release --doc

# The Python tests run in PYTEST_WORKERS processes (pytest-xdist; 0 runs them in this one). Each test is
# independent of the others' order and process, and the property tests' seed is the same in every worker.
test-python: develop
	$(BIN)/python -m pytest -q -n $(PYTEST_WORKERS) tests

# Format, lints and docs, warnings as errors. Clippy's one crate-level allow is the NaN guard
# `!(x > 0.0)` (lib.rs). The docs check covers the core crate only: rustdoc (1.95 and nightly) stops with
# an internal compiler error on a malformed intra-doc link in numpy 0.23.0's own docs
# (`[ToPyArray::to_pyarray`]` in src/convert.rs) as soon as a crate that uses numpy is documented; with that
# link fixed, `-p pluecker-py` passes too. Add `-p pluecker-py` here once numpy is upgraded past it.
lint: $(DEPS_STAMP)
	@echo "== format: cargo fmt --check"
	cargo fmt --all -- --check
	@echo "== lints: cargo clippy on every target, warnings as errors"
	cargo clippy --all-targets -p pluecker -p pluecker-py -p pluecker-bench -- -D warnings
	@echo "== lints: the extension with its test hooks (cargo feature test-hooks, as make develop builds it)"
	cargo clippy --all-targets -p pluecker-py --features test-hooks -- -D warnings
	@echo "== lints: the development tools of crates/pluecker-bench/benches (bench = false: not in --all-targets)"
	cargo clippy -p pluecker-bench --bench global_pose --bench profile_pose --bench lines_and_quadrics -- -D warnings
	@echo "== docs: cargo doc, warnings as errors"
	RUSTDOCFLAGS="-D warnings" cargo doc --no-deps -p pluecker
	@echo "== python: ruff check"
	$(BIN)/ruff check python/pluecker
	@echo "== stubs: _core.pyi against the built module (mypy stubtest; PyO3 classes are all disjoint bases)"
	$(MAKE) --no-print-directory develop
	$(BIN)/python -m pluecker._stubgen --check
	$(BIN)/python -m mypy.stubtest pluecker._core --ignore-disjoint-bases --allowlist python/stubtest-allowlist.txt

demo: develop
	$(BIN)/pluecker reproduce phong-horaud-1995 --out results/phong-horaud-1995
	$(BIN)/pluecker reproduce josephson-kahl-2008 --out results/josephson-kahl-2008

bench: develop
	$(BIN)/python -m pip install --quiet opencv-python-headless poselib pycolmap cvxpnpl
	$(BIN)/python bench/compare_pose.py
	$(BIN)/python bench/compare_triangulation.py
	$(BIN)/python bench/compare_robust_pose.py
	$(BIN)/python bench/compare_global_pose.py
	cargo bench -p pluecker-bench --bench pose
	cargo bench -p pluecker-bench --bench triangulation

# About 9,000 mutants: a whole run takes days on two cores, so it is split into shards, e.g.
# `make mutants SHARD=0/100` (a 1 % sample, round-robin over every file). Results in mutants.out/.
CARGO_MUTANTS_VERSION := 27.1.0
mutants: develop
	@cargo mutants --version 2>/dev/null | grep -q $(CARGO_MUTANTS_VERSION) || cargo install --locked cargo-mutants@$(CARGO_MUTANTS_VERSION)
	cargo mutants $(if $(SHARD),--shard $(SHARD) --sharding round-robin) --output .

clean:
	rm -rf $(VENV) python/pluecker/_core*.so
