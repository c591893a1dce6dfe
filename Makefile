# The front door: a thin layer over CMake. Every target installs what is missing first.
BUILD      ?= build
FUZZ_BUILD ?= build-fuzz
JOBS       ?= $(shell nproc)
FUZZ_SECONDS ?= 20
CMAKE_ARGS ?=
LAUNCHER   := $(if $(shell command -v ccache 2>/dev/null),-DCMAKE_CXX_COMPILER_LAUNCHER=ccache,)

.PHONY: deps deps-bench build test unit fuzz up bench clean format

deps:
	@scripts/install-deps.sh test

deps-bench:
	@scripts/install-deps.sh bench

$(BUILD)/build.ninja:
	cmake -S . -B $(BUILD) -G Ninja -DCMAKE_BUILD_TYPE=Release $(LAUNCHER) $(CMAKE_ARGS)

build: deps $(BUILD)/build.ninja
	cmake --build $(BUILD) -j $(JOBS)

# Every test: the GoogleTest suites through ctest, then each fuzz target briefly.
test: build
	cd $(BUILD) && ctest -j $(JOBS) --output-on-failure --timeout 900
	$(MAKE) fuzz

unit: build
	cd $(BUILD) && ctest -j $(JOBS) --output-on-failure -LE slow

fuzz: deps
	CC=clang CXX=clang++ cmake -S . -B $(FUZZ_BUILD) -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
	  -DCMAKE_CXX_FLAGS="-fsanitize=fuzzer-no-link,address,undefined" \
	  -DMESHFLOW_BUILD_TESTS=OFF -DMESHFLOW_BUILD_FUZZERS=ON $(LAUNCHER)
	cmake --build $(FUZZ_BUILD) -j $(JOBS) --target meshflow_fuzzers
	@# Seed the correction and part fuzzers with real files made by the tool itself.
	@mkdir -p $(FUZZ_BUILD)/tests/fuzz/corpus-work/correction $(FUZZ_BUILD)/tests/fuzz/corpus-work/part
	@if [ -x $(BUILD)/meshflow ]; then \
	  $(BUILD)/meshflow op LaplacianSmoothing tests/fuzz/corpus/off/coff.off -o $(FUZZ_BUILD)/seed.ply \
	    --correction $(FUZZ_BUILD)/tests/fuzz/corpus-work/correction/seed-ls.mfc >/dev/null 2>&1 || true; \
	  $(BUILD)/meshflow op FillHoles ../shared/data/meshes/defects/triangular_hole.off -o $(FUZZ_BUILD)/seed.ply \
	    --correction $(FUZZ_BUILD)/tests/fuzz/corpus-work/correction/seed-fh.mfc >/dev/null 2>&1 || true; \
	  $(BUILD)/meshflow partition ../shared/data/meshes/defects/triangular_hole.off --vertices-per-part 1000 \
	    --parts-dir $(FUZZ_BUILD)/tests/fuzz/corpus-work/part >/dev/null 2>&1 || true; \
	fi
	@# Regression: an empty part with its quadric flag set (once crashed fuzz_part's round trip).
	@printf 'MFPART2\n%016d\001' 0 | tr 0 '\000' > $(FUZZ_BUILD)/tests/fuzz/corpus-work/part/regression-empty-quadric-flag
	@# A Rem file seed: parts 0 -> 1, two merges (5 -> 7, then 7 -> 9).
	@mkdir -p $(FUZZ_BUILD)/tests/fuzz/corpus-work/rem
	@printf 'MFREM01\n\000\000\000\000\001\000\000\000\002\000\000\000\000\000\000\000\005\000\000\000\000\000\000\000\007\000\000\000\000\000\000\000\007\000\000\000\000\000\000\000\011\000\000\000\000\000\000\000' \
	  > $(FUZZ_BUILD)/tests/fuzz/corpus-work/rem/seed-two-merges
	tests/fuzz/run.sh $(FUZZ_BUILD)/tests/fuzz $(FUZZ_SECONDS)

up: build
	scripts/up.sh $(BUILD)/meshflow

bench: deps-bench $(BUILD)/build.ninja
	cmake -S . -B $(BUILD) -DMESHFLOW_BUILD_BENCHMARKS=ON
	cmake --build $(BUILD) -j $(JOBS)
	bench/run.sh $(BUILD)/meshflow

format:
	git ls-files '*.h' '*.cpp' | xargs clang-format -i

clean:
	rm -rf $(BUILD) $(FUZZ_BUILD)
