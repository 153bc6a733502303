#!/usr/bin/env bash
# Configures and builds dynamap (Release by default) into ./build.
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD_DIR=${BUILD_DIR:-build}
GENERATOR=()
if command -v ninja >/dev/null 2>&1; then GENERATOR=(-G Ninja); fi
# Configured when there is no build system yet, also after a configure that failed (e.g. a
# dependency was missing): its cache is dropped (it may name another generator).
if [ ! -f "$BUILD_DIR/build.ninja" ] && [ ! -f "$BUILD_DIR/Makefile" ]; then
  rm -f "$BUILD_DIR/CMakeCache.txt"
  cmake -S . -B "$BUILD_DIR" "${GENERATOR[@]}" -DCMAKE_BUILD_TYPE="${BUILD_TYPE:-Release}" "$@"
fi
cmake --build "$BUILD_DIR" -j"${JOBS:-2}"
