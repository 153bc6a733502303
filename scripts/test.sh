#!/usr/bin/env bash
# README command 2: install what is missing, build, run the test suite:
#   1. every ctest test of the Release build (unit, threaded, timing, simd, real_data);
#   2. the sanitizer runs (scripts/sanitize.sh), SANITIZERS="tsan" by default: the threaded
#      tests under ThreadSanitizer, built without the fast paths (the portable code);
#      TSAN_TESTS=short (default here) leaves out the threaded_long ones (whole runs whose
#      threads the shorter tests run too; scripts/sanitize.sh tsan alone runs every one).
#      SANITIZERS="asan tsan" adds the whole suite under ASan + UBSan with the fuzzers' smoke
#      run (FUZZ_SECONDS, default 10, each): about 25 minutes more on 2 cores.
# CI (.ci/run) runs exactly this: ~20 minutes on 2 cores from a fresh clone (BENCHMARKS.md#ci).
# Locally, SANITIZERS= (empty) skips 2.
set -euo pipefail
cd "$(dirname "$0")/.."
START=$SECONDS
stage() { echo "test.sh: $1 done at $((SECONDS - START)) s"; }
bash scripts/install_deps.sh
bash scripts/build.sh
stage "install + build"
(cd "${BUILD_DIR:-build}" && ctest --output-on-failure -j"${JOBS:-2}" --timeout 900)
stage "tests"
for s in ${SANITIZERS-tsan}; do
  TSAN_TESTS=${TSAN_TESTS:-short} bash scripts/sanitize.sh "$s"
  stage "$s"
done
echo "test.sh: all passed in $((SECONDS - START)) s"
