#!/usr/bin/env python3
"""Frame-to-frame camera motion of tracked runs against the ground truth.

For each run (a `dynamap run` output folder), prints per frame the difference between the
estimated relative motion (frame k-1 -> k) and the ground truth's, as a rotation angle (deg) and a
translation (cm); these differences do not depend on how the trajectories are aligned. Two runs
of the same frames (e.g. the clean TUM sequence and a semi-synthetic one made from it) that
differ from the ground truth by the same amounts at the same frames point at the ground truth,
not at the tracking. With --masks SEQ the share of the standing person (mask value 128) that each
keyframe mask of the first run (RUN/masks, `--save-masks`) covers is added.

usage: scripts/motion_vs_gt.py GROUNDTRUTH RUN [RUN ...] [--masks SEQ] [--png OUT.png]
"""
import argparse
import os
import sys

import cv2
import numpy as np


def load_tum(path):
    try:
        rows = [l.split() for l in open(path) if l.strip() and not l.startswith("#")]
        table = np.array([[float(x) for x in r[:8]] for r in rows])
    except (OSError, ValueError) as e:
        sys.exit("motion_vs_gt.py: %s: %s" % (path, e))
    if table.ndim != 2 or table.shape[1] != 8 or len(table) < 2:
        sys.exit("motion_vs_gt.py: %s: expected two or more 'stamp tx ty tz qx qy qz qw' lines" % path)
    return table


def pose(row):
    x, y, z, w = row[4:8]
    n = np.sqrt(x * x + y * y + z * z + w * w)
    x, y, z, w = x / n, y / n, z / n, w / n
    m = np.eye(4)
    m[:3, :3] = [[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                 [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                 [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]]
    m[:3, 3] = row[1:4]
    return m


def nearest(gt, t):
    i = int(np.clip(np.searchsorted(gt[:, 0], t), 1, len(gt) - 1))
    return gt[i] if abs(gt[i, 0] - t) < abs(gt[i - 1, 0] - t) else gt[i - 1]


def motion_diffs(gt, est):
    """{stamp: (rotation diff deg, translation diff cm)} for consecutive estimated frames."""
    out = {}
    for k in range(1, len(est)):
        a = np.linalg.inv(pose(est[k - 1])) @ pose(est[k])
        b = np.linalg.inv(pose(nearest(gt, est[k - 1, 0]))) @ pose(nearest(gt, est[k, 0]))
        d = np.linalg.inv(a) @ b
        angle = np.degrees(np.arccos(np.clip((np.trace(d[:3, :3]) - 1) / 2, -1, 1)))
        out[round(est[k, 0], 3)] = (angle, 100 * np.linalg.norm(d[:3, 3]))
    return out


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
    legend = [(l, c) for l, _, c in series] + ([("standing person masked (share)", (200, 200, 200))]
                                                 if bars else [])
    for i, (label, colour) in enumerate(legend):
        cv2.rectangle(img, (left + 10, top + 2 + 18 * i), (left + 24, top + 12 + 18 * i), colour, -1)
        cv2.putText(img, label, (left + 30, top + 12 + 18 * i), 0, 0.45, (0, 0, 0), 1, cv2.LINE_AA)
    cv2.putText(img, "rotation of each frame-to-frame motion minus the ground truth's [deg]; "
                "time [s]", (left, h - 12), 0, 0.45, (0, 0, 0), 1, cv2.LINE_AA)
    cv2.imwrite(path, img)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("groundtruth")
    ap.add_argument("runs", nargs="+")
    ap.add_argument("--masks", help="sequence folder with mask/ (standing person = 128)")
    ap.add_argument("--png")
    args = ap.parse_args()
    gt = load_tum(args.groundtruth)
    diffs = [motion_diffs(gt, load_tum(os.path.join(r, "trajectory.txt"))) for r in args.runs]
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
