#!/usr/bin/python3
"""Long runs against their single pass (issue 47): keyframes, peak memory, ATE, finish time,
frames/s, masks and map, for sequences played N times forward and backward by
../shared/tools/make_long.py.

Usage: bench_long.py [--dynamap BIN] [--out DIR] [--cases a,b] [--backends b1,b2] [--passes N]
                      [--spans A-B,C-D]
Prints a markdown table (one row per case and backend: the single pass, the long run and their
ratios, and the keyframes each pass of the long run added: where the growth is) and writes it
to OUT/long.md. The long sequences are made under /tmp on first use. --spans plays frames A..B
of each case instead of the whole source (the single pass A..B, the long run A..B, B..A, ...):
variants of one sequence, whose spread tells how far one run's ratios and mask gap are noise; a
second table gives each case's mean, smallest and largest over the spans.
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


def played_sequence(name, passes, span=None):
    """Frames span = (first, last) of the case (None: all) played `passes` times (forward,
    backward, ...), made once under /tmp; the whole source itself for one pass of all."""
    src, frames, _ = CASES[name]
    if span is None and passes == 1:
        return src
    first, last = span if span is not None else (0, frames - 1)
    tag = "" if span is None else f"_{first}_{last}"
    out = f"/tmp/{name}{tag}_x{passes}"
    if not os.path.isfile(os.path.join(out, "rgb.txt")):
        ends = [str(first if i % 2 == 0 else last) for i in range(passes + 1)]
        subprocess.run(["/usr/bin/python3", f"{SHARED}/tools/make_long.py", src, out,
                        ",".join(ends)], check=True, stdout=subprocess.DEVNULL)
    return out


def parse_spans(text):
    """'A-B,C-D' -> [(A, B), (C, D)]; empty -> [None] (the whole source)."""
    if not text:
        return [None]
    spans = []
    for item in text.split(","):
        first, _, last = item.partition("-")
        if not (first.isdigit() and last.isdigit() and int(first) < int(last)):
            sys.exit(f"bench_long.py: --spans: '{item}' is not FIRST-LAST (frames, FIRST < LAST)")
        spans.append((int(first), int(last)))
    return spans


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


def spread(values, digits, signed=False):
    """'mean (min, max)' of the values that are there."""
    v = [x for x in values if x is not None]
    if not v:
        return "–"
    f = f"{{:{'+' if signed else ''}.{digits}f}}"
    return f"{f.format(sum(v) / len(v))} ({f.format(min(v))}, {f.format(max(v))})"


def summary(pairs):
    """One row per case and backend over its spans: the long run against its single pass."""
    lines = ["| case | backend | spans | mask IoU long - single | keyframes (x) | ATE (x) | "
             "peak memory (x) |", "|---" * 7 + "|"]
    for (case, backend), runs in pairs.items():
        gap = [m["iou"] - o["iou"] if None not in (m["iou"], o["iou"]) else None for o, m in runs]
        ratios = {k: [m[k] / o[k] if m[k] is not None and o[k] else None for o, m in runs]
                  for k in ("kf", "ate", "mem")}
        lines.append(f"| {case} | {backend} | {len(runs)} | {spread(gap, 3, True)} | "
                     f"{spread(ratios['kf'], 2)} | {spread(ratios['ate'], 2)} | "
                     f"{spread(ratios['mem'], 2)} |")
    return lines


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--dynamap", default=os.path.join(ROOT, "build/bin/dynamap"))
    ap.add_argument("--out", default="/tmp/bench_long")
    ap.add_argument("--cases", default="teddy,crowd,bonn")
    ap.add_argument("--backends", default="default")
    ap.add_argument("--passes", type=int, default=10)
    ap.add_argument("--set", action="append", default=[], help="extra section.key=value")
    ap.add_argument("--spans", default="", help="FIRST-LAST,...: variants (frames of the case)")
    a = ap.parse_args()
    spans = parse_spans(a.spans)
    os.makedirs(a.out, exist_ok=True)
    header = ("| case | backend | frames 1 / N | keyframes (x) | peak MiB (x) | ATE cm (x) | "
              "finish s | frames/s | mask IoU | map precision | ghost | new keyframes per pass |\n" +
              "|---" * 12 + "|")
    lines, pairs = [header], {}
    for case, span in ((c, s) for c in a.cases.split(",") for s in spans):
        _, _, options = CASES[case]
        name = case if span is None else f"{case} {span[0]}-{span[1]}"
        seq_one = played_sequence(case, 1, span)
        seq_long = played_sequence(case, a.passes, span)
        starts = pass_starts(seq_long)
        for backend in a.backends.split(","):
            opts = list(options)
            if backend != "default":
                opts += ["--set", f"mapping.backend={backend}"]
            for kv in a.set:
                opts += ["--set", kv]
            folder = f"{a.out}/{name.replace(' ', '_')}__{backend}"
            one = run(a.dynamap, seq_one, folder + "__x1", opts)
            many = run(a.dynamap, seq_long, f"{folder}__x{a.passes}", opts)
            many["per_pass"] = keyframes_per_pass(f"{folder}__x{a.passes}", starts)
            pairs.setdefault((case, backend), []).append((one, many))
            lines.append(row(name, backend, one, many))
            print(lines[-1], flush=True)
    if len(spans) > 1:
        lines += [""] + summary(pairs)
    with open(os.path.join(a.out, "long.md"), "w") as f:
        f.write("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    sys.exit(main())
