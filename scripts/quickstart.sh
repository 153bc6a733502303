#!/usr/bin/env bash
# README command 1: install dependencies, build, and run dynamap on the bundled sequences:
#   1. the real TUM fr3 teddy sequence (200 frames) -> runs/teddy/: trajectory, dense map,
#      ATE/RPE, report.html;
#   2. teddy_dyn_dev, the same sequence with people walking through it -> runs/teddy_dyn_dev/:
#      the same, plus the map's precision / completeness / ghost ratio against the reference
#      clouds and the keyframe masks against the ground-truth masks.
# Extra arguments go to both runs (e.g. --set mapping.backend=vdb_tsdf).
set -euo pipefail
cd "$(dirname "$0")/.."
DATA=${DATA:-../shared/data}
bash scripts/install_deps.sh
bash scripts/build.sh
./build/bin/dynamap run --sequence "$DATA/tum/rgbd_dataset_freiburg3_teddy" --out runs/teddy "$@"
# Without ../shared the first run has already explained where to get the data and failed.
./build/bin/dynamap run --sequence "$DATA/dynamic/teddy_dyn_dev" --out runs/teddy_dyn_dev "$@"
