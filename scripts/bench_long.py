#!/usr/bin/python3
"""Long runs against their single pass (issue 47): keyframes, peak memory, ATE, finish time,
frames/s, masks and map, for sequences played N times forward and backward by
../shared/tools/make_long.py.

Usage: bench_long.py [--dynamap BIN] [--out DIR] [--cases a,b] [--backends b1,b2] [--passes N]
Prints a markdown table (one row per case and backend: the single pass, the long run and their
ratios, and the keyframes each pass of the long run added: where the growth is) and writes it
to OUT/long.md. The long sequences are made under /tmp on first use.
Standard library only (make_long.py needs Debian's numpy).
"""
import argparse
import bisect
import os
import subprocess
import sys

from bench_tables import load  # one reader of the run folders' JSON files

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
SHARED = os.path.join(os.path.dirname(ROOT), "shared")
DATA = os.path.join(SHARED, "data")

# name -> (source folder, frames in one pass, extra run options)
CASES = {
    "teddy": (f"{DATA}/tum/rgbd_dataset_freiburg3_teddy", 200, []),
    "crowd": (f"{DATA}/dynamic/teddy_dyn_crowd_dev", 200, []),
    "dyn": (f"{DATA}/dynamic/teddy_dyn_dev", 200, []),
    "bonn": (f"{DATA}/bonn/rgbd_bonn_crowd_400_499", 100, ["--config", "config/bonn.yaml"]),
}


def long_sequence(name, passes):
    """The sequence played `passes` times (forward, backward, ...), made once under /tmp."""
    src, frames, _ = CASES[name]
    out = f"/tmp/{name}_x{passes}"
    if not os.path.isfile(os.path.join(out, "rgb.txt")):
        ends = [str(0 if i % 2 == 0 else frames - 1) for i in range(passes + 1)]
        subprocess.run(["/usr/bin/python3", f"{SHARED}/tools/make_long.py", src, out,
                        ",".join(ends)], check=True, stdout=subprocess.DEVNULL)
    return out


def tum_rows(path):
    """The fields of each line of a TUM-format list (rgb.txt, keyframes.txt), comments skipped."""
    with open(path) as f:
        return [line.split() for line in f if line.strip() and line[0] != "#"]


def pass_starts(seq):
    """The timestamps at which each pass of a make_long.py sequence starts: where the source
    frames its images link to turn from forward to backward or back."""
    rows = tum_rows(os.path.join(seq, "rgb.txt"))
    stamps = [float(r[0]) for r in rows]
    source = [float(os.path.splitext(os.path.basename(os.readlink(os.path.join(seq, r[1]))))[0])
              for r in rows]
    starts, direction = [stamps[0]], 0.0
    for i in range(1, len(source)):
        step = source[i] - source[i - 1]
        if step * direction < 0:
            starts.append(stamps[i - 1])
        if step != 0:
            direction = step
    return starts


def keyframes_per_pass(out, starts):
    """How many keyframes the run made in each pass (a list as long as `starts`)."""
    counts = [0] * len(starts)
    kf_file = os.path.join(out, "keyframes.txt")
    for r in tum_rows(kf_file) if os.path.isfile(kf_file) else []:
        counts[max(0, bisect.bisect_right(starts, float(r[0])) - 1)] += 1
    return counts


def run(dynamap, seq, out, options):
    cmd = [dynamap, "run", "--sequence", seq, "--out", out, "--quiet"] + options
    # The binary's own libraries, not those its RUNPATH names (a frozen copy of a build).
    env = dict(os.environ, LD_LIBRARY_PATH=os.path.join(os.path.dirname(dynamap), "..", "lib"))
    with open(out + ".log", "w") as log:
        rc = subprocess.run(cmd, cwd=ROOT, stdout=log, stderr=subprocess.STDOUT,
                            env=env).returncode
    m, t, r = (load(os.path.join(out, f)) for f in ("metrics.json", "timings.json", "run.json"))
    masks, mp = m.get("masks", {}), m.get("map", {})
    return {
        "rc": rc, "frames": r.get("counts", {}).get("frames_read"),
        "kf": r.get("counts", {}).get("keyframes"),
        "mem": t.get("peak_memory_mib"), "ate": m.get("ate", {}).get("rmse_m"),
        "finish": t.get("finish_s"), "fps": t.get("frames_per_s"),
        "iou": masks.get("mean_iou"), "precision": mp.get("precision"),
        "ghost": mp.get("ghost_ratio"),
    }


def fmt(v, digits=2, scale=1.0):
    return "–" if v is None else f"{v * scale:.{digits}f}"


def ratio(a, b):
    return "–" if a is None or b in (None, 0) else f"{a / b:.2f}"


def row(case, backend, one, many):
    cells = [case, backend, f"{one['frames']} / {many['frames']}",
             f"{one['kf']} / {many['kf']} ({ratio(many['kf'], one['kf'])})",
             f"{fmt(one['mem'], 0)} / {fmt(many['mem'], 0)} ({ratio(many['mem'], one['mem'])})",
             f"{fmt(one['ate'], 2, 100)} / {fmt(many['ate'], 2, 100)} "
             f"({ratio(many['ate'], one['ate'])})",
             f"{fmt(one['finish'])} / {fmt(many['finish'])}",
             f"{fmt(one['fps'], 1)} / {fmt(many['fps'], 1)}",
             f"{fmt(one['iou'], 3)} / {fmt(many['iou'], 3)}",
             f"{fmt(one['precision'], 3)} / {fmt(many['precision'], 3)}",
             f"{fmt(one['ghost'], 3)} / {fmt(many['ghost'], 3)}",
             ", ".join(str(n) for n in many["per_pass"])]
    return "| " + " | ".join(cells) + " |"


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--dynamap", default=os.path.join(ROOT, "build/bin/dynamap"))
    ap.add_argument("--out", default="/tmp/bench_long")
    ap.add_argument("--cases", default="teddy,crowd,bonn")
    ap.add_argument("--backends", default="default")
    ap.add_argument("--passes", type=int, default=10)
    ap.add_argument("--set", action="append", default=[], help="extra section.key=value")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    header = ("| case | backend | frames 1 / N | keyframes (x) | peak MiB (x) | ATE cm (x) | "
              "finish s | frames/s | mask IoU | map precision | ghost | new keyframes per pass |\n" +
              "|---" * 12 + "|")
    lines = [header]
    for case in a.cases.split(","):
        src, _, options = CASES[case]
        seq_long = long_sequence(case, a.passes)
        starts = pass_starts(seq_long)
        for backend in a.backends.split(","):
            opts = list(options)
            if backend != "default":
                opts += ["--set", f"mapping.backend={backend}"]
            for kv in a.set:
                opts += ["--set", kv]
            one = run(a.dynamap, src, f"{a.out}/{case}__{backend}__x1", opts)
            out_long = f"{a.out}/{case}__{backend}__x{a.passes}"
            many = run(a.dynamap, seq_long, out_long, opts)
            many["per_pass"] = keyframes_per_pass(out_long, starts)
            lines.append(row(case, backend, one, many))
            print(lines[-1], flush=True)
    with open(os.path.join(a.out, "long.md"), "w") as f:
        f.write("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    sys.exit(main())
