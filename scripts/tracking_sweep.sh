#!/usr/bin/env bash
# Judges a tracking change on more than one run of each sequence: every bundled sequence is cut
# into variants (start frame x frame stride), each variant is tracked with the same build and
# config, and the ATE of each is printed, with the crowd/clean and dyn/clean ratios per variant
# and the means over all variants. Sequences: clean teddy, teddy_dyn_dev, teddy_dyn_crowd_dev
# and the real Bonn crowd slice (its own camera: config/bonn.yaml). For the semi-synthetic
# sequences (ground-truth masks and reference clouds) the means of the keyframe-mask and map
# metrics over the variants follow: the masks' IoU, pixel recall and precision, the share of the
# standing person masked, the map's precision, completeness, ghost ratio and ghost fragments.
# Offline runs are deterministic, but any change to tracking moves a single run's ATE by up to
# ~0.3 cm (several cm on Bonn); the variants show whether a change helps in general.
# usage: scripts/tracking_sweep.sh [--set key=value ...]   (12 variants; ~12 minutes on 2 cores)
# BIN=DIR/bin/dynamap runs a frozen copy of a build (bin/ and lib/ copied side by side), so that
# rebuilding the tree during a sweep changes nothing; without BIN the tree is built and used.
set -euo pipefail
cd "$(dirname "$0")/.."
if [ -n "${BIN:-}" ]; then
  export LD_LIBRARY_PATH="$(dirname "$(dirname "$BIN")")/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
else
  bash scripts/build.sh >/dev/null
  BIN=./build/bin/dynamap
fi
DATA=${DATA:-../shared/data}
OUT=${OUT:-runs/sweep}
STARTS=${STARTS:-"0 10 20 30 40 50"}
STRIDES=${STRIDES:-"1 2"}
SEQS=${SEQS:-"teddy:tum/rgbd_dataset_freiburg3_teddy dyn:dynamic/teddy_dyn_dev crowd:dynamic/teddy_dyn_crowd_dev bonn:bonn/rgbd_bonn_crowd_400_499"}
rm -rf "$OUT" && mkdir -p "$OUT"

subset() {  # subset <source dir> <dest dir> <start> <stride>: frame lists cut, files linked
  local src=$1 dst=$2 start=$3 stride=$4 f
  mkdir -p "$dst"
  for f in rgb depth mask depth.txt mask.txt groundtruth.txt reference_static.ply reference_dynamic.ply; do
    [ -e "$src/$f" ] && ln -s "$(realpath "$src/$f")" "$dst/$f"
  done
  # Colour frames are cut; every depth frame stays listed so each keeps its associated depth.
  awk -v s="$start" -v k="$stride" '/^#/ {print; next} {if (n >= s && (n - s) % k == 0) print; n++}' \
    "$src/rgb.txt" >"$dst/rgb.txt"
}

ate_cm() {  # ate_cm <seq> <run>
  "$BIN" evaluate --gt "$1/groundtruth.txt" --est "$2/trajectory.txt" --json |
    /usr/bin/python3 -c 'import json,sys; print("%.3f" % (100 * json.load(sys.stdin)["ate"]["rmse_m"]))'
}

names=()
for spec in $SEQS; do names+=("${spec%%:*}"); done
printf '%-6s %-6s' start stride; printf ' %9s' "${names[@]}"; echo
declare -A sum=()
n=0
for start in $STARTS; do
  for stride in $STRIDES; do
    printf '%-6s %-6s' "$start" "$stride"
    for spec in $SEQS; do
      name=${spec%%:*}
      cfg=()
      [ "$name" = bonn ] && cfg=(--config config/bonn.yaml)
      seq="$OUT/seq_${name}_${start}_${stride}"
      subset "$DATA/${spec#*:}" "$seq" "$start" "$stride"
      run="$OUT/run_${name}_${start}_${stride}"
      "$BIN" run --sequence "$seq" --out "$run" --quiet "${cfg[@]}" "$@" >"$run.log" 2>&1 ||
        echo "sweep: $run failed" >&2
      a=$(ate_cm "$seq" "$run")
      printf ' %9s' "$a"
      sum[$name]=$(echo "${sum[$name]:-0} + $a" | bc -l)
    done
    echo
    n=$((n + 1))
  done
done
printf '%-13s' "mean"
for name in "${names[@]}"; do printf ' %9.3f' "$(echo "${sum[$name]} / $n" | bc -l)"; done
echo
for name in "${names[@]}"; do
  [ "$name" = teddy ] || [ -z "${sum[teddy]:-}" ] && continue
  printf 'mean %s / mean teddy: %.2f\n' "$name" "$(echo "${sum[$name]} / ${sum[teddy]}" | bc -l)"
done
# Masks and map over the variants (the sequences with ground-truth masks and reference clouds).
/usr/bin/python3 - "$OUT" "${names[@]}" <<'PY'
import glob, json, sys
out, names = sys.argv[1], sys.argv[2:]
keys = [("masks", "mean_iou", "IoU"), ("masks", "pixel_recall", "recall"),
        ("masks", "pixel_precision", "precision"), ("masks", "standing_masked_share", "standing"),
        ("map", "precision", "map_prec"), ("map", "completeness", "map_comp"),
        ("map", "ghost_ratio", "ghost_%"), ("map", "ghost_fragments", "fragments")]
print("%-9s %3s" % ("masks", "n") + "".join(" %9s" % k[2] for k in keys))
def show(label, rows):
    if rows:
        means = [sum(c) / len(rows) for c in zip(*rows)]
        print("%-9s %3d" % (label, len(rows)) + "".join(" %9.3f" % v for v in means))
for name in names:
    rows, by_stride = [], {}
    for path in sorted(glob.glob("%s/run_%s_*/metrics.json" % (out, name))):
        m = json.load(open(path))
        if "masks" in m and "map" in m:
            row = [m[a][b] * (100 if b == "ghost_ratio" else 1) for a, b, _ in keys]
            rows.append(row)
            by_stride.setdefault(path.split("/")[-2].split("_")[-1], []).append(row)
    show(name, rows)
    # Per stride as well: a stride of 2 doubles every motion between frames (and the ground
    # truth's jitter, with which the semi-synthetic people are drawn).
    for stride in sorted(by_stride, key=int) if len(by_stride) > 1 else []:
        show("%s/%s" % (name, stride), by_stride[stride])
PY
