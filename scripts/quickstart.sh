#!/usr/bin/env bash
# README command 1: install dependencies, build, and run dynamap on the bundled real TUM
# sequence (fr3 teddy, 200 frames): trajectory, dense map, metrics, plots in runs/teddy/.
set -euo pipefail
cd "$(dirname "$0")/.."
SEQUENCE=${SEQUENCE:-../shared/data/tum/rgbd_dataset_freiburg3_teddy}
OUT=${OUT:-runs/teddy}
bash scripts/install_deps.sh
bash scripts/build.sh
exec ./build/bin/dynamap run --sequence "$SEQUENCE" --out "$OUT" "$@"
