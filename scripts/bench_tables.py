#!/usr/bin/python3
"""Markdown tables from dynamap run folders (metrics.json, timings.json, run.json).

Usage: bench_tables.py RUNS_DIR   (each sub-folder is one `dynamap run --out` folder, named
<sequence>__<label>). Standard library only.
"""
import json
import math
import os
import re
import statistics
import sys


def load(path):
    try:
        with open(path) as f:
            return json.load(f)
    except (OSError, ValueError):
        return {}


def fmt(v, scale=1.0, digits=3):
    if v is None or (isinstance(v, float) and math.isnan(v)):
        return "–"
    return f"{v * scale:.{digits}f}"


def main(runs_dir):
    rows = []
    for name in sorted(os.listdir(runs_dir)):
        d = os.path.join(runs_dir, name)
        if not os.path.isdir(d) or "__" not in name:
            continue
        seq, label = name.split("__", 1)
        m, t, r = (load(os.path.join(d, f)) for f in ("metrics.json", "timings.json", "run.json"))
        stages = t.get("stages", {})
        c = r.get("counts", {})
        rows.append({
            "seq": seq, "label": label, "status": r.get("status", "?"),
            "frames": c.get("frames_read"),
            "tracked": sum(c.get(k, 0) for k in ("tracked", "relocalized", "posed_by_depth")),
            "kf": c.get("keyframes"),
            "ate_cm": m.get("ate", {}).get("rmse_m"), "rpe_t": m.get("rpe", {}).get("trans_rmse_m"),
            "rpe_r": m.get("rpe", {}).get("rot_rmse_deg"),
            "iou": m.get("masks", {}).get("mean_iou"),
            "standing": m.get("masks", {}).get("standing_masked_share"),
            "fps": t.get("frames_per_s"), "track_ms": t.get("tracking_median_ms"),
            "track_p95": t.get("tracking_p95_ms"),
            "det_ms": stages.get("detector", {}).get("median_ms"),
            "map_ms": stages.get("mapping_integrate", {}).get("median_ms"),
            "mem": t.get("peak_memory_mib"),
            "prec": m.get("map", {}).get("precision"), "comp": m.get("map", {}).get("completeness"),
            "ghost": m.get("map", {}).get("ghost_ratio"),
            "mode": r.get("mode"), "skipped_rt": c.get("skipped_realtime"),
            "det_skipped": stages.get("detector_skipped", {}).get("count", 0),
            "det_runs": stages.get("detector", {}).get("count", 0),
            "lag_p95": stages.get("realtime_lag", {}).get("p95_ms"),
            "lag_max": stages.get("realtime_lag", {}).get("max_ms"),
        })
    print("| sequence | run | status | frames (tracked) | keyframes | ATE RMSE cm | RPE 1 s cm / deg "
          "| mask IoU | standing masked | frames/s | tracking median / p95 ms | detector ms "
          "| map integrate ms | precision / completeness / ghost | peak MiB |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for x in rows:
        print(f"| {x['seq']} | {x['label']} | {x['status']} | {x['frames']} ({x['tracked']}) | {x['kf']} "
              f"| {fmt(x['ate_cm'], 100, 2)} | {fmt(x['rpe_t'], 100, 2)} / {fmt(x['rpe_r'], 1, 2)} "
              f"| {fmt(x['iou'], 1, 3)} | {fmt(x['standing'], 100, 1)} % | {fmt(x['fps'], 1, 1)} "
              f"| {fmt(x['track_ms'], 1, 1)} / {fmt(x['track_p95'], 1, 1)} | {fmt(x['det_ms'], 1, 1)} "
              f"| {fmt(x['map_ms'], 1, 1)} | {fmt(x['prec'])} / {fmt(x['comp'])} / {fmt(x['ghost'], 1, 4)} "
              f"| {fmt(x['mem'], 1, 0)} |")
    repeats(rows)
    realtime(rows)
    peers(rows, runs_dir)


def realtime(rows):
    """--realtime runs: frames arrive at their timestamps (30 Hz); what was skipped, how late."""
    rt = [x for x in rows if x["mode"] == "realtime"]
    if not rt:
        return
    print()
    print("`--realtime` (frames arrive at the sequence's own timestamps, ~30 Hz; the detector "
          "takes a frame only when idle, the newest frame wins):")
    print()
    print("| sequence | run | frames | frames skipped by tracking | detections skipped (share of "
          "frames) | detector runs | tracking lag p95 / max ms | ATE RMSE cm |")
    print("|---|---|---|---|---|---|---|---|")
    for x in rt:
        share = x["det_skipped"] / x["frames"] if x["frames"] else None
        print(f"| {x['seq']} | {x['label']} | {x['frames']} | {x['skipped_rt']} "
              f"| {x['det_skipped']} ({fmt(share, 100, 1)} %) | {x['det_runs']} "
              f"| {fmt(x['lag_p95'], 1, 0)} / {fmt(x['lag_max'], 1, 0)} | {fmt(x['ate_cm'], 100, 2)} |")


def repeats(rows):
    """Median and range of ATE (and mask IoU) over a run and its repeats (<label>_r<i>)."""
    groups = {}
    for x in rows:
        m = re.match(r"^(.*)_r\d+$", x["label"])
        key = (x["seq"], m.group(1) if m else x["label"])
        groups.setdefault(key, []).append(x)
    groups = {k: v for k, v in groups.items() if len(v) > 1}
    if not groups:
        return
    print()
    print("Repeated runs (same command; offline runs are deterministic, so accuracy repeats and "
          "only the timings differ):")
    print()
    print("| sequence | run | runs | ATE RMSE cm median (min–max) | mask IoU median "
          "| standing masked median (max) | map precision / completeness / ghost median "
          "| ghost max | frames/s median | tracking median ms (median of runs) |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for (seq, label), xs in sorted(groups.items()):
        col = lambda k: [x[k] for x in xs if x[k] is not None]
        med = lambda v, s, d: fmt(statistics.median(v), s, d) if v else "–"
        top = lambda v, s, d: fmt(max(v), s, d) if v else "–"
        ate, st, ghost = col("ate_cm"), col("standing"), col("ghost")
        rng = f"({fmt(min(ate), 100, 2)}–{fmt(max(ate), 100, 2)})" if ate else ""
        print(f"| {seq} | {label} | {len(xs)} | {med(ate, 100, 2)} {rng} "
              f"| {med(col('iou'), 1, 3)} | {med(st, 100, 1)} % ({top(st, 100, 1)} %) "
              f"| {med(col('prec'), 1, 3)} / {med(col('comp'), 1, 3)} / {med(ghost, 100, 2)} % "
              f"| {top(ghost, 100, 2)} % | {med(col('fps'), 1, 1)} | {med(col('track_ms'), 1, 1)} |")


def peers(rows, runs_dir):
    """Open3D RGB-D odometry on the same frames (RUNS_DIR/peers, written by scripts/bench.sh)."""
    d = os.path.join(runs_dir, "peers")
    if not os.path.isdir(d):
        return
    print()
    print("Peer on the same frames in the same run: Open3D frame-to-frame RGB-D odometry "
          "(python3-open3d, `scripts/o3d_odometry_bench.py`), against dynamap's medians over the "
          "repeated `both` runs above:")
    print()
    print("| sequence | tracker | ATE RMSE cm | failed frames | ms per frame (median) "
          "| dynamap ATE cm | peer ATE / dynamap ATE | peer ms / dynamap tracking ms |")
    print("|---|---|---|---|---|---|---|---|")
    for name in sorted(os.listdir(d)):
        if not name.endswith(".eval.json"):
            continue
        stem = name[: -len(".eval.json")]
        seq, label = stem.split("__", 1)
        ev, tm = load(os.path.join(d, name)), load(os.path.join(d, stem + ".timing.json"))
        ate, ms = ev.get("ate", {}).get("rmse_m"), tm.get("ms_per_frame_median")
        ours = [x for x in rows if x["seq"] == seq and re.match(r"^both(_r\d+)?$", x["label"])]
        our_ate = [x["ate_cm"] for x in ours if x["ate_cm"] is not None]
        our_ms = [x["track_ms"] for x in ours if x["track_ms"] is not None]
        oa = statistics.median(our_ate) if our_ate else None
        om = statistics.median(our_ms) if our_ms else None
        ratio = lambda a, b: f"{a / b:.1f} x" if a is not None and b else "–"
        print(f"| {seq} | {label} | {fmt(ate, 100, 2)} | {tm.get('failed', '–')} "
              f"| {fmt(ms, 1, 0)} | {fmt(oa, 100, 2)} | {ratio(ate, oa)} | {ratio(ms, om)} |")


if __name__ == "__main__":
    main(sys.argv[1])
