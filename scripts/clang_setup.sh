# Sourced by scripts/sanitize.sh and scripts/fuzz.sh: clang and its sanitizer/libFuzzer runtimes
# (Debian: clang, libclang-rt-dev; other deps come from scripts/install_deps.sh), then
# GENERATOR (Ninja where installed) and LINES_ONLY, the flags of both builds: line tables only
# (file:line in every sanitizer report, no variable info): the libraries compile in 53 s instead
# of 65 s (TSan, 2 cores).
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
LINES_ONLY="-O2 -gline-tables-only -DNDEBUG"
