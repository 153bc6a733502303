#!/usr/bin/env bash
# README command 2: install what is missing, build, run the whole test suite:
#   1. the unit, integration and fault tests (ctest, Release build);
#   2. a smoke fuzz run: every libFuzzer target for FUZZ_SECONDS (default 10) seconds from the
#      seeded corpus in fuzz/corpus (clang, ASan + UBSan; scripts/fuzz.sh);
#   3. the sanitizer runs (scripts/sanitize.sh): SANITIZERS="tsan asan" by default, i.e. the
#      threaded tests under ThreadSanitizer and the whole suite under ASan + UBSan.
# CI (.ci/run) runs exactly this. Locally, SANITIZERS= (empty) and FUZZ_SECONDS=0 skip 2 and 3.
set -euo pipefail
cd "$(dirname "$0")/.."
START=$SECONDS
stage() { echo "test.sh: $1 done at $((SECONDS - START)) s"; }
bash scripts/install_deps.sh
bash scripts/build.sh
stage "install + build"
(cd "${BUILD_DIR:-build}" && ctest --output-on-failure -j"${JOBS:-2}" --timeout 900)
stage "tests"
if [ "${FUZZ_SECONDS:-10}" != 0 ]; then
  bash scripts/fuzz.sh "${FUZZ_SECONDS:-10}"
  stage "smoke fuzz"
fi
for s in ${SANITIZERS-tsan asan}; do
  bash scripts/sanitize.sh "$s"
  stage "$s"
done
echo "test.sh: all passed in $((SECONDS - START)) s"
