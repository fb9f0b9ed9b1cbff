# The two commands of the README:
#   make run   installs what is missing, builds the dala tool, runs the main job (scripts/run_default.sh)
#   make test  installs what is missing (and the test-only packages: test-deps), builds, and runs
#              the whole test suite (CI calls this)
BUILD_DIR ?= build
JOBS ?= $(shell nproc)
OUT ?= out

.PHONY: deps test-deps configure build build-tool test run clean

deps:
	@bash scripts/install_deps.sh

# Test-only packages (a local Slurm for the bench job array test), not needed by make run.
test-deps:
	@bash scripts/install_deps.sh --test

configure: deps
	@cmake -S . -B $(BUILD_DIR) -DCMAKE_BUILD_TYPE=Release

build: configure
	@cmake --build $(BUILD_DIR) -j $(JOBS)

# make run needs only the command-line tool, not the tests and benchmarks.
build-tool: configure
	@cmake --build $(BUILD_DIR) -j $(JOBS) --target dala

# After the suite: docs/reliability.md's table of end-to-end bounds must be the tests' bounds.
test: build test-deps
	@cd $(BUILD_DIR) && ctest --output-on-failure -j $(JOBS)
	@python3 scripts/e2e_bounds_table.py --check docs/reliability.md $(BUILD_DIR)/Testing/Temporary/LastTest.log

run: build-tool
	@bash scripts/run_default.sh $(BUILD_DIR) $(OUT)

clean:
	rm -rf $(BUILD_DIR)
