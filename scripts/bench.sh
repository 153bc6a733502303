#!/usr/bin/env bash
# The benchmark suite: runs dynamap on the sequences in ../shared/data (tracking with and
# without motion-area removal, the removal ablations, every mapping backend from ground-truth
# poses and masks) and the mapping component benchmark, then writes the generated section of
# BENCHMARKS.md (machine, date, command, tables). Offline mode: every frame, as fast as possible.
# usage: [REPEATS=3] scripts/bench.sh   (about 8 minutes on 2 cores with REPEATS=3)
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/build.sh >/dev/null
# The Open3D peer (ScalableTSDFVolume, RGB-D odometry) is measured when python3-open3d is there;
# install it when we can (root + apt), otherwise the tables say it is missing.
if ! /usr/bin/python3 -c 'import open3d' >/dev/null 2>&1 && [ "$(id -u)" = 0 ] &&
  command -v apt-get >/dev/null 2>&1; then
  apt-get install -y -qq --no-install-recommends python3-open3d >/dev/null 2>&1 ||
    { apt-get update -qq && apt-get install -y -qq --no-install-recommends python3-open3d >/dev/null; } ||
    echo "bench: could not install python3-open3d; Open3D columns will say so" >&2
fi
OUT=${OUT:-runs/bench}
DATA=../shared/data
TEDDY=$DATA/tum/rgbd_dataset_freiburg3_teddy
DYN=$DATA/dynamic/teddy_dyn_dev
rm -rf "$OUT" && mkdir -p "$OUT"

run() {  # run <folder name: sequence__label> <sequence dir> [dynamap run options]
  local name=$1 seq=$2
  shift 2
  echo "bench: $name" >&2
  ./build/bin/dynamap run --sequence "$seq" --out "$OUT/$name" --quiet "$@" >"$OUT/$name.log" 2>&1 ||
    echo "bench: $name exited with $? (see $OUT/$name.log)" >&2
}

TSDF=(--set mapping.backend=vdb_tsdf --set mapping.params.vdb_tsdf.voxel_size_m=0.02)
for mode in off both; do run "teddy__$mode" "$TEDDY" --set dynamic.mode=$mode "${TSDF[@]}"; done
for mode in off geometry detector both; do
  run "teddy_dyn_dev__$mode" "$DYN" --set dynamic.mode=$mode "${TSDF[@]}"
done
# Crowded scenes (issue 15): the semi-synthetic crowd and the real Bonn crowd slice (its own
# camera), removal off / on, and the paper's epipolar check beside the default PnP reprojection.
CROWD=$DATA/dynamic/teddy_dyn_crowd_dev
BONN=(--config config/bonn.yaml)
for mode in off both; do run "teddy_dyn_crowd_dev__$mode" "$CROWD" --set dynamic.mode=$mode "${TSDF[@]}"; done
run "teddy_dyn_crowd_dev__both-epipolar" "$CROWD" --set dynamic.geometric_check=epipolar "${TSDF[@]}"
for mode in off detector both; do
  run "rgbd_bonn_crowd_400_499__$mode" "$DATA/bonn/rgbd_bonn_crowd_400_499" "${BONN[@]}" \
    --set dynamic.mode=$mode "${TSDF[@]}"
done
run "rgbd_bonn_crowd_400_499__both-epipolar" "$DATA/bonn/rgbd_bonn_crowd_400_499" "${BONN[@]}" \
  --set dynamic.geometric_check=epipolar "${TSDF[@]}"
# Real time: frames at their own timestamps, the newest frame wins.
run "teddy_dyn_dev__realtime" "$DYN" --realtime "${TSDF[@]}"
# Ablation of the mapping side's free-space check (README, Mapping backends).
NOFS=(--set mapping.free_space_check=false)
run "teddy_dyn_dev__both-nofreespace" "$DYN" --set dynamic.mode=both "${TSDF[@]}" "${NOFS[@]}"
# Offline runs are deterministic (tracking.ba_lockstep, dynamic.detector_lockstep), so repeats
# check that and show the spread of the timings: REPEATS runs, summarised as median and range.
for i in $(seq 2 "${REPEATS:-3}"); do
  for mode in off both; do run "teddy__${mode}_r$i" "$TEDDY" --set dynamic.mode=$mode "${TSDF[@]}"; done
  run "teddy_dyn_dev__both_r$i" "$DYN" --set dynamic.mode=both "${TSDF[@]}"
  for mode in off both; do
    run "teddy_dyn_crowd_dev__${mode}_r$i" "$CROWD" --set dynamic.mode=$mode "${TSDF[@]}"
  done
  run "teddy_dyn_dev__both-nofreespace_r$i" "$DYN" --set dynamic.mode=both "${TSDF[@]}" "${NOFS[@]}"
done
for backend in points pcl_voxel vdb_tsdf octomap; do
  run "teddy_dyn_dev__gt-poses-masks_$backend" "$DYN" --poses "$DYN/groundtruth.txt" \
    --masks "$DYN/mask" --set mapping.backend=$backend
done

# Peer tracker on the same frames: Open3D's frame-to-frame RGB-D odometry (colour and hybrid terms).
if /usr/bin/python3 -c 'import open3d' >/dev/null 2>&1; then
  mkdir -p "$OUT/peers"
  for spec in "teddy:$TEDDY:color" "teddy:$TEDDY:hybrid" "teddy_dyn_dev:$DYN:color"; do
    IFS=: read -r name seq term <<<"$spec"
    stem="$OUT/peers/${name}__open3d_$term"
    echo "bench: $name open3d odometry ($term)" >&2
    { OMP_NUM_THREADS=2 /usr/bin/python3 scripts/o3d_odometry_bench.py "$seq" "$term" "$stem.txt" >"$stem.timing.json" &&
      ./build/bin/dynamap evaluate --gt "$seq/groundtruth.txt" --est "$stem.txt" --json >"$stem.eval.json"; } 2>"$stem.log" ||
      echo "bench: open3d odometry on $name ($term) failed (see $stem.log)" >&2
  done
fi

cmake --build build -j2 --target dynamap_map_bench >/dev/null
./build/bin/dynamap_map_bench --data "$DYN" --open3d --out "$OUT/map_bench" >"$OUT/map_bench.md" 2>"$OUT/map_bench.log" ||
  echo "bench: map bench failed (see $OUT/map_bench.log)" >&2
# OctoMap against plain insertPointCloud of the full cloud (stride 1: every static pixel, as
# `dynamap run` maps by default), the comparison the mapping issue names.
./build/bin/dynamap_map_bench --data "$DYN" --stride 1 --only octomap_5cm --out "$OUT/map_bench_full" \
  >"$OUT/map_bench_full.md" 2>"$OUT/map_bench_full.log" ||
  echo "bench: full-cloud map bench failed (see $OUT/map_bench_full.log)" >&2

{
  echo "<!-- bench:begin (generated by scripts/bench.sh; do not edit by hand) -->"
  echo "Generated $(date -u '+%Y-%m-%d %H:%M UTC') on $(nproc) cores," \
    "$(lscpu | sed -n 's/^Model name: *//p' | head -n 1), $(free -g | awk '/Mem:/{print $2}') GiB," \
    "commit $(git rev-parse --short HEAD 2>/dev/null || echo unknown). Command: \`bash scripts/bench.sh\`."
  echo
  echo "### dynamap run (offline, every frame)"
  echo
  python3 scripts/bench_tables.py "$OUT"
  echo
  echo "### Mapping backends on teddy_dyn_dev, ground-truth poses and masks (dynamap_map_bench)"
  echo
  cat "$OUT/map_bench.md"
  echo
  echo "Full clouds (every static pixel, \`--stride 1\`), OctoMap only:"
  echo
  grep -E '^(\||octomap)' "$OUT/map_bench_full.md" || echo "(failed: see $OUT/map_bench_full.log)"
  echo "<!-- bench:end -->"
} >"$OUT/generated.md"

# Replace the generated section of BENCHMARKS.md (or append it).
python3 - "$OUT/generated.md" <<'PY'
import re, sys
gen = open(sys.argv[1]).read()
try:
    text = open("BENCHMARKS.md").read()
except OSError:
    text = "# Benchmarks\n\n"
pattern = re.compile(r"<!-- bench:begin.*?<!-- bench:end -->\n?", re.S)
text = pattern.sub(lambda _: gen, text) if pattern.search(text) else text.rstrip() + "\n\n" + gen
open("BENCHMARKS.md", "w").write(text)
PY
echo "bench: wrote BENCHMARKS.md (runs in $OUT)" >&2
