#!/usr/bin/python3
"""Markdown tables from dynamap run folders (metrics.json, timings.json, run.json).

Usage: bench_tables.py RUNS_DIR   (each sub-folder is one `dynamap run --out` folder, named
<sequence>__<label>). Standard library only.
"""
import json
import math
import os
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
            "frames": c.get("frames_read"), "tracked": c.get("tracked", 0) + c.get("relocalized", 0),
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


if __name__ == "__main__":
    main(sys.argv[1])
