#!/usr/bin/env bash
# README command 2: install what is missing, build, run the whole test suite:
#   1. the unit, integration and fault tests (ctest, Release build);
#   2. the sanitizer runs (scripts/sanitize.sh): SANITIZERS="asan tsan" by default, i.e. the
#      whole suite under ASan + UBSan and the threaded tests under ThreadSanitizer;
#   3. a smoke fuzz run: every libFuzzer target for FUZZ_SECONDS (default 10) seconds from the
#      seeded corpus in fuzz/corpus, ASan + UBSan: built and run in the asan stage (its build
#      holds the fuzzers); without that stage, scripts/fuzz.sh's own build (build-fuzz).
# CI (.ci/run) runs exactly this. Locally, SANITIZERS= (empty) and FUZZ_SECONDS=0 skip 2 and 3.
set -euo pipefail
cd "$(dirname "$0")/.."
START=$SECONDS
stage() { echo "test.sh: $1 done at $((SECONDS - START)) s"; }
bash scripts/install_deps.sh
# The test suites as unity builds (cmake/DynamapUnity.cmake); the libraries one file at a time.
bash scripts/build.sh -DDYNAMAP_UNITY_TESTS=ON
stage "install + build"
(cd "${BUILD_DIR:-build}" && ctest --output-on-failure -j"${JOBS:-2}" --timeout 900)
stage "tests"
SANITIZERS=${SANITIZERS-asan tsan}
if [ "${FUZZ_SECONDS:-10}" != 0 ] && [[ " $SANITIZERS " != *" asan "* ]]; then
  bash scripts/fuzz.sh "${FUZZ_SECONDS:-10}"
  stage "smoke fuzz"
fi
for s in $SANITIZERS; do
  FUZZ_SECONDS=${FUZZ_SECONDS:-10} bash scripts/sanitize.sh "$s"
  stage "$s"
done
echo "test.sh: all passed in $((SECONDS - START)) s"
