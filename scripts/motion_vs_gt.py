#!/usr/bin/env python3
"""Frame-to-frame camera motion of tracked runs against the ground truth.

For each run (a `dynamap run` output folder), prints per frame the difference between the
estimated relative motion (frame k-1 -> k) and the ground truth's, as a rotation angle (deg) and a
translation (cm): the TUM RPE with a delta of one frame, per pair (`dynamap evaluate --rpe-delta 1
--rpe-unit f --rpe-pairs`); it does not depend on how the trajectories are aligned. Two runs
of the same frames (e.g. the clean TUM sequence and a semi-synthetic one made from it) that
differ from the ground truth by the same amounts at the same frames point at the ground truth,
not at the tracking. With --masks SEQ the share of the standing person (mask value 128) that each
keyframe mask of the first run (RUN/masks, `--save-masks`) covers is added.

usage: scripts/motion_vs_gt.py GROUNDTRUTH RUN [RUN ...] [--masks SEQ] [--png OUT.png]
       [--dynamap build/bin/dynamap]
"""
import argparse
import os
import subprocess
import sys
import tempfile

import cv2
import numpy as np


def motion_diffs(dynamap, groundtruth, run):
    """{stamp of the later frame: (rotation diff deg, translation diff cm)}, from the project's
    RPE (one frame apart, every pair)."""
    with tempfile.TemporaryDirectory() as tmp:
        pairs = os.path.join(tmp, "pairs.txt")
        cmd = [dynamap, "evaluate", "--gt", groundtruth, "--est", os.path.join(run, "trajectory.txt"),
               "--rpe-delta", "1", "--rpe-unit", "f", "--rpe-pairs", pairs]
        done = subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        if done.returncode != 0:
            sys.exit("motion_vs_gt.py: %s" % (done.stderr.strip() or " ".join(cmd)))
        rows = [l.split() for l in open(pairs) if l.strip() and not l.startswith("#")]
    return {round(float(t), 3): (float(rot), 100 * float(trans)) for t, trans, rot in rows}


def standing_share(seq, run):
    """{stamp: share of the standing person's pixels under the keyframe mask}."""
    out = {}
    folder = os.path.join(run, "masks")
    for name in sorted(os.listdir(folder)) if os.path.isdir(folder) else []:
        gt = cv2.imread(os.path.join(seq, "mask", name), cv2.IMREAD_GRAYSCALE)
        mask = cv2.imread(os.path.join(folder, name), cv2.IMREAD_GRAYSCALE)
        if gt is None or mask is None or not (gt == 128).any():
            continue
        out[round(float(name[:-4]), 3)] = float(((gt == 128) & (mask > 0)).sum() / (gt == 128).sum())
    return out


def draw_legend(img, entries, left, top):
    """(label, BGR colour) entries, one a line, top left of the plot area."""
    for i, (label, colour) in enumerate(entries):
        cv2.rectangle(img, (left + 10, top + 2 + 18 * i), (left + 24, top + 12 + 18 * i), colour, -1)
        cv2.putText(img, label, (left + 30, top + 12 + 18 * i), 0, 0.45, (0, 0, 0), 1, cv2.LINE_AA)


def plot(path, t0, series, bars):
    w, h, left, top = 1000, 360, 60, 30
    img = np.full((h, w, 3), 255, np.uint8)
    t1 = max(max(s) for _, s, _ in series)
    ymax = 1.5

    def xy(t, v):
        return (int(left + (t - t0) / (t1 - t0) * (w - left - 20)),
                int(h - 40 - min(v, ymax) / ymax * (h - 40 - top)))

    for t, share in bars.items():  # standing person masked: grey bars, 0..1 on the same axis
        x0, y0 = xy(t, share * ymax)
        cv2.rectangle(img, (x0 - 3, y0), (x0 + 3, h - 40), (200, 200, 200), -1)
    for v in np.arange(0, ymax + 1e-9, 0.5):
        cv2.line(img, xy(t0, v), xy(t1, v), (230, 230, 230), 1)
        cv2.putText(img, "%.1f" % v, (10, xy(t0, v)[1] + 4), 0, 0.4, (0, 0, 0), 1)
    for t in np.arange(0, t1 + 1e-9, 1.0):
        cv2.putText(img, "%.0f" % t, (xy(t, 0)[0] - 4, h - 26), 0, 0.4, (0, 0, 0), 1)
    for label, s, colour in series:
        pts = [xy(t, s[t][0]) for t in sorted(s)]
        cv2.polylines(img, [np.array(pts, np.int32)], False, colour, 1, cv2.LINE_AA)
    draw_legend(img, [(l, c) for l, _, c in series] +
                ([("standing person masked (share)", (200, 200, 200))] if bars else []), left, top)
    cv2.putText(img, "rotation of each frame-to-frame motion minus the ground truth's [deg]; "
                "time [s]", (left, h - 12), 0, 0.45, (0, 0, 0), 1, cv2.LINE_AA)
    cv2.imwrite(path, img)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("groundtruth")
    ap.add_argument("runs", nargs="+")
    ap.add_argument("--masks", help="sequence folder with mask/ (standing person = 128)")
    ap.add_argument("--png")
    ap.add_argument("--dynamap", default=os.path.join(os.path.dirname(__file__), "..", "build",
                                                      "bin", "dynamap"))
    args = ap.parse_args()
    diffs = [motion_diffs(args.dynamap, args.groundtruth, r) for r in args.runs]
    bars = standing_share(args.masks, args.runs[0]) if args.masks else {}
    stamps = sorted(set.intersection(*(set(d) for d in diffs)))
    print("stamp " + " ".join("rot_deg%d trans_cm%d" % (i, i) for i in range(len(diffs))) +
          (" standing_masked" if bars else ""))
    for t in stamps:
        row = " ".join("%.2f %.2f" % d[t] for d in diffs)
        print("%.3f %s%s" % (t, row, " %.2f" % bars[t] if t in bars else ""))
    rot = np.array([[d[t][0] for t in stamps] for d in diffs])
    for i in range(len(diffs)):
        print("# run %d: median %.2f deg, frames > 0.5 deg: %d of %d" %
              (i, np.median(rot[i]), int((rot[i] > 0.5).sum()), len(stamps)), file=sys.stderr)
    if len(diffs) > 1:
        print("# correlation of runs 0 and 1 per frame: %.2f" % np.corrcoef(rot[0], rot[1])[0, 1],
              file=sys.stderr)
    if args.png:
        colours = [(200, 80, 0), (0, 0, 220), (0, 150, 0)]
        t0 = min(stamps)
        series = [(os.path.basename(os.path.normpath(r)), {t - t0: d[t] for t in d}, colours[i % 3])
                  for i, (r, d) in enumerate(zip(args.runs, diffs))]
        plot(args.png, 0.0, series, {t - t0: v for t, v in bars.items()})


if __name__ == "__main__":
    main()
