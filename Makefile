# The two commands of the README:
#   make run   installs what is missing, builds, and runs the main job on the embedded default
#   make test  installs what is missing, builds, and runs the whole test suite (CI calls this)
BUILD_DIR ?= build
JOBS ?= $(shell nproc)
OUT ?= out

.PHONY: deps configure build test run clean

deps:
	@bash scripts/install_deps.sh

configure: deps
	@cmake -S . -B $(BUILD_DIR) -DCMAKE_BUILD_TYPE=Release

build: configure
	@cmake --build $(BUILD_DIR) -j $(JOBS)

test: build
	@cd $(BUILD_DIR) && ctest --output-on-failure -j $(JOBS)

run: build
	@bash scripts/run_default.sh $(BUILD_DIR) $(OUT)

clean:
	rm -rf $(BUILD_DIR)
