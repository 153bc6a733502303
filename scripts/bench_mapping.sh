#!/bin/sh
# Mapping benchmark (BENCHMARKS.md): every backend on teddy_dyn_dev with ground-truth poses and
# masks, plus plain OctoMap, one-shot VoxelGrid and (if python3-open3d is installed) Open3D.
# usage: scripts/bench_mapping.sh [build-dir] [extra dynamap_map_bench options]
set -e
build=${1:-build}
[ $# -gt 0 ] && shift
cmake --build "$build" -j2 --target dynamap_map_bench
exec "$build/bin/dynamap_map_bench" --open3d --out /tmp/dynamap_map_bench "$@"
