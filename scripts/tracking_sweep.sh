#!/usr/bin/env bash
# Judges a tracking change on more than one run of each sequence: every bundled sequence is cut
# into variants (start frame x frame stride), each variant is tracked with the same build and
# config, and the ATE of each is printed with the dyn/clean ratio per variant and over all.
# Offline runs are deterministic, but any change to tracking moves a single run's ATE by up to
# ~0.2 cm; the variants show whether a change helps in general or only on one run.
# usage: scripts/tracking_sweep.sh [--set key=value ...]   (12 variants, about 3 minutes on 2 cores)
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/build.sh >/dev/null
DATA=../shared/data
OUT=${OUT:-runs/sweep}
STARTS=${STARTS:-"0 10 20 30 40 50"}
STRIDES=${STRIDES:-"1 2"}
rm -rf "$OUT" && mkdir -p "$OUT"

subset() {  # subset <source dir> <dest dir> <start> <stride>: frame lists cut, files linked
  local src=$1 dst=$2 start=$3 stride=$4 f
  mkdir -p "$dst"
  for f in rgb depth mask depth.txt groundtruth.txt; do
    [ -e "$src/$f" ] && ln -s "$(realpath "$src/$f")" "$dst/$f"
  done
  # Colour frames are cut; every depth frame stays listed so each keeps its associated depth.
  awk -v s="$start" -v k="$stride" '/^#/ {print; next} {if (n >= s && (n - s) % k == 0) print; n++}' \
    "$src/rgb.txt" >"$dst/rgb.txt"
}

printf '%-8s %-7s %10s %10s %7s\n' start stride teddy_cm dyn_cm ratio
sum_c=0 sum_d=0
for start in $STARTS; do
  for stride in $STRIDES; do
    declare -A ate=()
    for spec in teddy:tum/rgbd_dataset_freiburg3_teddy dyn:dynamic/teddy_dyn_dev; do
      name=${spec%%:*}
      seq="$OUT/seq_${name}_${start}_${stride}"
      subset "$DATA/${spec#*:}" "$seq" "$start" "$stride"
      run="$OUT/run_${name}_${start}_${stride}"
      ./build/bin/dynamap run --sequence "$seq" --out "$run" --quiet "$@" >"$run.log" 2>&1 || echo "sweep: $run failed" >&2
      ate[$name]=$(./build/bin/dynamap evaluate --gt "$seq/groundtruth.txt" \
        --est "$run/trajectory.txt" --json | /usr/bin/python3 -c \
        'import json,sys; print("%.3f" % (100 * json.load(sys.stdin)["ate"]["rmse_m"]))')
    done
    printf '%-8s %-7s %10s %10s %7.2f\n' "$start" "$stride" "${ate[teddy]}" "${ate[dyn]}" \
      "$(echo "${ate[dyn]} / ${ate[teddy]}" | bc -l)"
    sum_c=$(echo "$sum_c + ${ate[teddy]}" | bc -l)
    sum_d=$(echo "$sum_d + ${ate[dyn]}" | bc -l)
  done
done
printf 'mean     all     %10.3f %10.3f %7.2f\n' "$(echo "$sum_c / $(($(wc -w <<<"$STARTS") * $(wc -w <<<"$STRIDES")))" | bc -l)" \
  "$(echo "$sum_d / $(($(wc -w <<<"$STARTS") * $(wc -w <<<"$STRIDES")))" | bc -l)" \
  "$(echo "$sum_d / $sum_c" | bc -l)"
