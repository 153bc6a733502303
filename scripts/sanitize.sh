#!/usr/bin/env bash
# Runs the test suite under sanitizers (clang):
#   asan: everything under AddressSanitizer + UndefinedBehaviorSanitizer, in build-asan
#   tsan: the threaded tests (tracking BA and loop threads, mapping worker, visibility pass,
#         detector worker, CLI runs) under ThreadSanitizer, in build-tsan, with
#         scripts/tsan.supp
#   scripts/sanitize.sh [asan|tsan|all]   (default all)
# Env: ASAN_BUILD_DIR, TSAN_BUILD_DIR, TSAN_TESTS (all, the default, or short), JOBS (compile
# jobs, default 2), TEST_JOBS (tests run at once, default 2: half the wall time of one at a
# time on 2 cores; it also lets a signal land on another thread, which is how TSan found the
# interrupt flag's race), CTEST_ARGS (extra).
# By ctest label (tests/CMakeLists.txt): ASan runs every test but the fuzz, timing (wall-clock
# bounds a 2-10x sanitizer slowdown breaks) and real_data ones (whole runs, measured in the
# Release build). TSan runs the threaded tests but the timing ones; TSAN_TESTS=short (CI's,
# scripts/test.sh) leaves out the threaded_long ones too. Both builds leave the fast paths out
# (-DDYNAMAP_FAST_PATHS=OFF): the portable code is built and tested in every CI run. TSan is
# not combined with UBSan: UBSan's checks call pipe() (IsAccessibleMemoryRange), which TSan
# reports as races on every std::async. CTEST_ARGS adds ctest arguments.
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$(pwd)
WHAT=${1:-all}
source scripts/clang_setup.sh  # clang, GENERATOR, LINES_ONLY
# Unity builds, as the Release build (CMakeLists.txt).
CLANG=(-DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=RelWithDebInfo
  "-DCMAKE_C_FLAGS_RELWITHDEBINFO=$LINES_ONLY" "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=$LINES_ONLY"
  -DCMAKE_UNITY_BUILD=ON)

run_asan() {
  local dir=${ASAN_BUILD_DIR:-build-asan}
  # The fuzzers are built here too (DYNAMAP_FUZZ=ON) for the smoke run, FUZZ_SECONDS (default 10)
  # each, 0 for none; DYNAMAP_FUZZ_COVERAGE=OFF: only the harnesses carry libFuzzer's coverage
  # instrumentation. On the libraries it made this suite 3x slower (two tracking tests 65.7 s ->
  # 20.9 s without); scripts/fuzz.sh keeps a coverage-guided build (build-fuzz) for long runs.
  local fuzz_seconds=${FUZZ_SECONDS:-10} fuzzers=()
  if [ "$fuzz_seconds" != 0 ]; then fuzzers=(dynamap_fuzzers); fi
  cmake -S . -B "$dir" "${GENERATOR[@]}" "${CLANG[@]}" -DDYNAMAP_SANITIZE=ON -DDYNAMAP_FUZZ=ON \
    -DDYNAMAP_FUZZ_COVERAGE=OFF -DDYNAMAP_FUZZ_SECONDS="$fuzz_seconds" \
    -DDYNAMAP_FAST_PATHS=OFF >/dev/null
  nice -n 19 cmake --build "$dir" -j"${JOBS:-2}" --target dynamap dynamap_backends \
    dynamap_io_tests dynamap_eval_tests dynamap_tracking_tests dynamap_dynamic_tests \
    dynamap_mapping_tests dynamap_cli_tests dynamap_system_tests dynamap_loop_tests "${fuzzers[@]}"
  if [ "$fuzz_seconds" != 0 ]; then
    # Each fuzzer from the seeds in fuzz/corpus for fuzz_seconds, as scripts/fuzz.sh runs them.
    nice -n 19 ctest --test-dir "$dir" -L fuzz --output-on-failure -j"${TEST_JOBS:-2}"
  fi
  # detect_leaks: OpenCV/TBB/OpenVDB keep process-lifetime caches; leaks are checked too, with
  # the third-party ones listed in scripts/lsan.supp.
  # alloc_dealloc_mismatch=0: Debian's PCL is built as C++14, where Eigen gives PointCloud a
  # class operator new/delete (malloc/free); our C++17 plugins use aligned global new, and
  # shared_ptr<PointCloud> disposal resolves to libpcl's C++14 instantiation -> "operator new vs
  # free" in pcl_voxel's exportMap. Benign with glibc; every other ASan check stays on.
  # --repeat until-pass:2: LeakSanitizer's tracer itself sometimes crashes at process exit ("Tracer
  # caught signal 11 ... LeakSanitizer has encountered a fatal error") after a test has passed
  # (seen on SyntheticTracking.AMapStartsOnUnconfirmed..., 1 of 3 runs, 2026-11-25); a real
  # failure fails twice.
  ASAN_OPTIONS=detect_stack_use_after_return=1:check_initialization_order=1:alloc_dealloc_mismatch=0 \
  LSAN_OPTIONS=suppressions=$ROOT/scripts/lsan.supp:print_suppressions=0 \
  UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
    nice -n 19 ctest --test-dir "$dir" -LE 'fuzz|timing|real_data' \
      --output-on-failure -j"${TEST_JOBS:-2}" --repeat until-pass:2 ${CTEST_ARGS:-}
}

run_tsan() {
  local dir=${TSAN_BUILD_DIR:-build-tsan}
  # -O1 (TSan's documented minimum): compiles in 270 s instead of 287 s on 2 cores, and the 93
  # short threaded tests ran in 208 s, as fast as at -O2 (220 s), 2026-12-02.
  local o1="${LINES_ONLY/-O2/-O1}"
  cmake -S . -B "$dir" "${GENERATOR[@]}" "${CLANG[@]}" -DDYNAMAP_TSAN=ON \
    "-DCMAKE_C_FLAGS_RELWITHDEBINFO=$o1" "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=$o1" \
    -DDYNAMAP_FAST_PATHS=OFF >/dev/null
  # Also for the build: gtest_discover_tests runs the test programs.
  export TSAN_OPTIONS="suppressions=$ROOT/scripts/tsan.supp:halt_on_error=1:second_deadlock_stack=1"
  export OMP_NUM_THREADS=1 OPENCV_FOR_THREADS_NUM=1
  nice -n 19 cmake --build "$dir" -j"${JOBS:-2}" --target dynamap dynamap_backends \
    dynamap_tracking_tests dynamap_mapping_tests dynamap_cli_tests dynamap_dynamic_tests \
    dynamap_system_tests dynamap_loop_tests
  # OMP_NUM_THREADS=1 / OPENCV_FOR_THREADS_NUM=1: Ceres (OpenMP) and OpenCV (TBB) run their
  # loops on the calling thread, so TSan sees no uninstrumented pool; see scripts/tsan.supp.
  local label=threaded  # a regular expression: threaded and threaded_long
  if [ "${TSAN_TESTS:-all}" = short ]; then label='^threaded$'; fi
  nice -n 19 ctest --test-dir "$dir" -L "$label" -LE timing --output-on-failure \
      -j"${TEST_JOBS:-2}" ${CTEST_ARGS:-}
}

case "$WHAT" in
  asan) run_asan ;;
  tsan) run_tsan ;;
  all) run_asan && run_tsan ;;
  *) echo "usage: scripts/sanitize.sh [asan|tsan|all]" >&2; exit 2 ;;
esac
