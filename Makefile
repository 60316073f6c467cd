# keygrid — the two commands users need, plus a few for developers.
#   make demo   install dependencies, build Release, run the demo job
#   make test   install dependencies, build, run the test suite (ctest)
#   make fuzz   fuzz the input parsers (libFuzzer, FUZZ_SECONDS per parser)
# Build trees: build/ (Release), build-asan/ (ASan + UBSan).
BUILD_DIR ?= build
ASAN_DIR  ?= build-asan
JOBS      ?= 2
CMAKE_ARGS ?=

.PHONY: all deps configure build test demo sanitize test-sanitize fuzz ini-reference clean

all: build

deps:
	bash scripts/install-deps.sh

configure: deps
	cmake -S . -B $(BUILD_DIR) -DCMAKE_BUILD_TYPE=Release $(CMAKE_ARGS)

build: configure
	cmake --build $(BUILD_DIR) -j$(JOBS)

test: build
	ctest --test-dir $(BUILD_DIR) --output-on-failure -j$(JOBS)

demo: build
	bash scripts/demo.sh $(BUILD_DIR)

# Sanitizer configuration: the whole test suite under AddressSanitizer + UBSan (-O1; -g1 keeps
# file:line in stack traces with a far smaller build tree than -g).
sanitize: deps
	cmake -S . -B $(ASAN_DIR) -DCMAKE_BUILD_TYPE=RelWithDebInfo -DKEYGRID_SANITIZE=ON \
	  -DKEYGRID_BUILD_BENCHMARKS=OFF -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1" $(CMAKE_ARGS)
	cmake --build $(ASAN_DIR) -j$(JOBS)

test-sanitize: sanitize
	ASAN_OPTIONS=detect_leaks=0:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
	  ctest --test-dir $(ASAN_DIR) --output-on-failure -j$(JOBS)

# Coverage-guided fuzzing of the input parsers (rawlog, TUM lists, INI, PNG) with libFuzzer:
# FUZZ_SECONDS per parser; exits non-zero on any crash (tests/fuzz/run.sh).
FUZZ_SECONDS ?= 60
fuzz: deps
	bash tests/fuzz/run.sh --seconds $(FUZZ_SECONDS)

# doc/ini-reference.md from the options structs (checked by the test IniReference.MatchesCommittedFile).
ini-reference: configure
	cmake --build $(BUILD_DIR) -j$(JOBS) --target keygrid-slam
	$(BUILD_DIR)/bin/keygrid-slam --ini-reference > doc/ini-reference.md.tmp
	mv doc/ini-reference.md.tmp doc/ini-reference.md

clean:
	rm -rf $(BUILD_DIR) $(ASAN_DIR)
