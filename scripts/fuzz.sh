#!/usr/bin/env bash
# Builds the libFuzzer targets (clang, ASan + UBSan, libraries with coverage instrumentation)
# into build-fuzz (FUZZ_BUILD_DIR) and runs each one for
# N seconds (default 10: the CI smoke run; e.g. 600 for a long run), TEST_JOBS (default 2) at
# a time, niced (each target keeps a core for its N seconds).
#   scripts/fuzz.sh [seconds-per-target]
# Seeds: fuzz/corpus/<target>/ (read only); new inputs: build-fuzz/fuzz/corpus/<target>/.
# A crash leaves build-fuzz/fuzz/<target>-crash-* and makes the script fail; turn it into a
# regression test (tests/io/fuzz_regression_test.cpp) before fixing.
set -euo pipefail
cd "$(dirname "$0")/.."
SECONDS_PER_TARGET=${1:-10}
BUILD_DIR=${BUILD_DIR:-${FUZZ_BUILD_DIR:-build-fuzz}}
# clang and its sanitizer/libFuzzer runtimes (Debian: clang, libclang-rt-dev); other deps come
# from scripts/install_deps.sh.
if ! command -v clang++ >/dev/null 2>&1 || ! ls /usr/lib/llvm-*/lib/clang/*/lib/linux/libclang_rt.fuzzer-x86_64.a >/dev/null 2>&1; then
  if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
    apt-get update -qq && apt-get install -y -qq --no-install-recommends clang libclang-rt-dev >/dev/null
  else
    echo "$(basename "$0"): needs clang and libclang-rt-dev (apt-get install clang libclang-rt-dev)" >&2
    exit 1
  fi
fi
GENERATOR=()
if command -v ninja >/dev/null 2>&1; then GENERATOR=(-G Ninja); fi
LINES_ONLY="-O2 -gline-tables-only -DNDEBUG"  # as scripts/sanitize.sh
cmake -S . -B "$BUILD_DIR" "${GENERATOR[@]}" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  "-DCMAKE_C_FLAGS_RELWITHDEBINFO=$LINES_ONLY" "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=$LINES_ONLY" \
  -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ -DDYNAMAP_SANITIZE=ON -DDYNAMAP_FUZZ=ON \
  -DDYNAMAP_FUZZ_SECONDS="$SECONDS_PER_TARGET" >/dev/null
nice -n 19 cmake --build "$BUILD_DIR" -j"${JOBS:-2}" --target dynamap_fuzzers
cd "$BUILD_DIR"
nice -n 19 ctest -L fuzz --output-on-failure -j"${TEST_JOBS:-2}"
