#!/bin/bash
# Issue 47's long-run bench: teddy, teddy_dyn_crowd_dev and the Bonn slice, each once and played
# 10 times forward and backward, with the default backend and each of the four; then, with
# TEN_MINUTES=1, teddy played 90 times (~18 000 frames, 10 minutes of camera) with the default
# backend; with SPANS=1, the crowd over six spans of its frames (its mask gap's spread).
# Tables (markdown) in $OUT/x10/long.md, $OUT/x90/long.md and $OUT/spans/long.md.
#
#   bash scripts/bench_long.sh                 # ~40 min on 2 cores
#   TEN_MINUTES=1 bash scripts/bench_long.sh   # + ~15 min
#   SPANS=1 bash scripts/bench_long.sh         # + ~10 min
#   DYNAMAP=/tmp/frozen/bin/dynamap OUT=/tmp/bl bash scripts/bench_long.sh --set key=value
#
# Extra arguments go to scripts/bench_long.py (e.g. --cases teddy, --set section.key=value).
set -euo pipefail
cd "$(dirname "$0")/.."
DYNAMAP=${DYNAMAP:-build/bin/dynamap}
OUT=${OUT:-/tmp/bench_long}
python3 scripts/bench_long.py --dynamap "$DYNAMAP" --out "$OUT/x10" --passes 10 \
  --backends default,points,vdb_tsdf,octomap "$@"
if [ "${TEN_MINUTES:-0}" = 1 ]; then
  python3 scripts/bench_long.py --dynamap "$DYNAMAP" --out "$OUT/x90" --passes 90 --cases teddy
fi
if [ "${SPANS:-0}" = 1 ]; then
  python3 scripts/bench_long.py --dynamap "$DYNAMAP" --out "$OUT/spans" --cases crowd \
    --spans 0-199,0-185,5-193,10-199,20-179,30-199
fi
