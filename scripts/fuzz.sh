#!/usr/bin/env bash
# Builds the libFuzzer targets (clang, ASan + UBSan, libraries with coverage instrumentation)
# into build-fuzz (FUZZ_BUILD_DIR) and runs each one for N seconds (default 10; e.g. 600 for a
# long run; scripts/sanitize.sh asan smoke-runs them in build-asan instead), TEST_JOBS (default 2)
# at a time, niced (each target keeps a core for its N seconds).
#   scripts/fuzz.sh [seconds-per-target]
# Seeds: fuzz/corpus/<target>/ (read only); new inputs: build-fuzz/fuzz/corpus/<target>/.
# A crash leaves build-fuzz/fuzz/<target>-crash-* and makes the script fail; turn it into a
# regression test (tests/io/fuzz_regression_test.cpp) before fixing.
set -euo pipefail
cd "$(dirname "$0")/.."
SECONDS_PER_TARGET=${1:-10}
BUILD_DIR=${BUILD_DIR:-${FUZZ_BUILD_DIR:-build-fuzz}}
source scripts/clang_setup.sh  # clang, GENERATOR, LINES_ONLY
cmake -S . -B "$BUILD_DIR" "${GENERATOR[@]}" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  "-DCMAKE_C_FLAGS_RELWITHDEBINFO=$LINES_ONLY" "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=$LINES_ONLY" \
  -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ -DDYNAMAP_SANITIZE=ON -DDYNAMAP_FUZZ=ON \
  -DDYNAMAP_FUZZ_SECONDS="$SECONDS_PER_TARGET" >/dev/null
nice -n 19 cmake --build "$BUILD_DIR" -j"${JOBS:-2}" --target dynamap_fuzzers
cd "$BUILD_DIR"
nice -n 19 ctest -L fuzz --output-on-failure -j"${TEST_JOBS:-2}"
