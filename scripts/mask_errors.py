#!/usr/bin/python3
"""Where a run's keyframe masks go wrong, against a semi-synthetic sequence's ground-truth masks.

usage: scripts/mask_errors.py SEQ RUN [--per-keyframe] [--picture OUT.jpg]
  SEQ: the sequence folder (mask/<stamp>.png: 255 moving person, 128 standing person, 0 scene)
  RUN: a `dynamap run ... --save-masks` output folder (masks/<stamp>.png, 255 = masked)

Prints the pooled IoU / recall / precision / standing share (as `dynamap run` computes them),
the same with the masks eroded by 1-3 px (what the masks' margins cost), and the false-positive
pixels split by what they are: the standing person, or scene pixels at a given distance from the
nearest moving-person pixel (beyond 30 px, with and without depth). --picture writes the six
keyframes with the most false positives beyond 30 px: green masked mover, red masked scene or
standing person, blue missed mover, yellow outline the standing person.
"""
import os
import sys

import cv2
import numpy as np

from tum_lists import read_list


def stamps_to_files(seq, listing):
    return dict(read_list(seq, listing))


def nearest(table, t):
    return table[min(table, key=lambda k: abs(k - t))]


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    seq, run = sys.argv[1], sys.argv[2]
    per_keyframe = "--per-keyframe" in sys.argv
    depths = stamps_to_files(seq, "depth.txt")
    names = sorted(os.listdir(os.path.join(run, "masks")))
    frames = []
    for name in names:
        pred = cv2.imread(os.path.join(run, "masks", name), cv2.IMREAD_GRAYSCALE) > 127
        gt = cv2.imread(os.path.join(seq, "mask", name), cv2.IMREAD_GRAYSCALE)
        depth = cv2.imread(os.path.join(seq, nearest(depths, float(name[:-4]))), cv2.IMREAD_UNCHANGED)
        frames.append((name[:-4], pred, gt == 255, gt == 128, depth))

    for r in (0, 1, 2, 3):
        tp = fp = fn = st = stm = 0
        ious = []
        for stamp, pred, moving, standing, _ in frames:
            p = pred
            if r:
                kernel = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * r + 1, 2 * r + 1))
                p = cv2.erode(pred.astype(np.uint8), kernel) > 0
            a, b, c = (p & moving).sum(), (p & ~moving).sum(), (~p & moving).sum()
            if moving.any():
                ious.append(a / max(1, (p | moving).sum()))
            tp, fp, fn = tp + a, fp + b, fn + c
            st, stm = st + standing.sum(), stm + (p & standing).sum()
            if per_keyframe and r == 0:
                print("%s IoU %.3f recall %.3f precision %.3f standing %d of %d" %
                      (stamp, ious[-1] if moving.any() else 0, a / max(1, moving.sum()),
                       a / max(1, p.sum()), (p & standing).sum(), standing.sum()))
        print("eroded %d px: IoU %.3f recall %.3f precision %.3f standing masked %.1f %%" %
              (r, np.mean(ious), tp / max(1, tp + fn), tp / max(1, tp + fp), 100 * stm / max(1, st)))

    bins = ["the standing person", "<= 3 px from a moving person", "4-10 px", "11-30 px",
            "> 30 px, no depth", "> 30 px"]
    counts = np.zeros(len(bins))
    tp = 0
    for _, pred, moving, standing, depth in frames:
        fp = pred & ~moving
        dist = cv2.distanceTransform((~moving).astype(np.uint8), cv2.DIST_L2, 3)
        scene = fp & ~standing
        counts += [(fp & standing).sum(), (scene & (dist <= 3)).sum(),
                   (scene & (dist > 3) & (dist <= 10)).sum(), (scene & (dist > 10) & (dist <= 30)).sum(),
                   (scene & (dist > 30) & (depth == 0)).sum(), (scene & (dist > 30) & (depth > 0)).sum()]
        tp += (pred & moving).sum()
    total = counts.sum()
    print("false positives: %d pixels (precision %.3f)" % (total, tp / max(1, tp + total)))
    for name, c in zip(bins, counts):
        print("  %-30s %9d %5.1f %%  precision without them %.3f" %
              (name, c, 100 * c / max(1, total), tp / max(1, tp + total - c)))
    if "--picture" in sys.argv:
        picture(seq, frames, sys.argv[sys.argv.index("--picture") + 1])


def picture(seq, frames, out):
    rgbs = stamps_to_files(seq, "rgb.txt")
    far = []
    for stamp, pred, moving, standing, _ in frames:
        dist = cv2.distanceTransform((~moving).astype(np.uint8), cv2.DIST_L2, 3)
        far.append(((pred & ~moving & ~standing & (dist > 30)).sum(), stamp, pred, moving, standing))
    far.sort(key=lambda f: -f[0])
    tiles = []
    for n, stamp, pred, moving, standing in far[:6]:
        img = cv2.imread(os.path.join(seq, nearest(rgbs, float(stamp))))
        for sel, colour in ((pred & moving, (0, 127, 0)), (pred & ~moving, (0, 0, 127)),
                            (~pred & moving, (127, 0, 0))):
            img[sel] = (0.5 * img[sel] + colour).astype(np.uint8)
        outline, _ = cv2.findContours(standing.astype(np.uint8), cv2.RETR_EXTERNAL,
                                      cv2.CHAIN_APPROX_SIMPLE)
        cv2.drawContours(img, outline, -1, (0, 255, 255), 2)
        cv2.putText(img, "%s: %d px beyond 30 px" % (stamp, n), (8, 24), 0, 0.7, (255, 255, 255), 2)
        tiles.append(cv2.resize(img, (480, 360)))
    while len(tiles) % 3:
        tiles.append(np.zeros_like(tiles[0]))
    rows = [np.hstack(tiles[i:i + 3]) for i in range(0, len(tiles), 3)]
    cv2.imwrite(out, np.vstack(rows), [cv2.IMWRITE_JPEG_QUALITY, 80])


if __name__ == "__main__":
    main()
