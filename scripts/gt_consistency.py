#!/usr/bin/python3
"""Which frame-to-frame motion do the images agree with: the ground truth's or a run's?

For each pair of consecutive frames of a run (its trajectory.txt), ORB features of the two colour
images are matched (cross-checked); features on people (the sequence's mask/ value != 0, when it
has masks) and without depth (0.3-4 m) in the first frame are left out. Each remaining feature is
lifted with the first frame's depth and projected into the second frame with (a) the ground
truth's two poses (interpolated at the frame times: positions linearly, rotations by slerp) and
(b) the run's two poses. The median distance to the matched feature (matches farther than 15 px
under both are dropped as mismatches) says how well each relative motion explains the static
scene. Sensor and feature noise give ~1 px; a pair where the ground truth needs several pixels
more than the run is one where the ground truth disagrees with the images. In the semi-synthetic
sequences people are drawn with the ground-truth poses, so there a person standing still moves
against the real scene by that much.

usage: scripts/gt_consistency.py SEQ RUN [--png OUT.png] [--limit PX]
--png draws both per pair over time, with grey bars for the share of the standing person that the
run's keyframe masks cover (RUN/masks from `dynamap run --save-masks`, SEQ/mask value 128). Prints per pair: stamp of the second frame, features used, median px under the ground truth and
under the run; then the means and the pairs above --limit (2.5 px) for each.
"""
import argparse
import functools
import os
import sys

import cv2
import numpy as np

from motion_vs_gt import draw_legend, standing_share
from tum_lists import read_list

ORB = cv2.ORB_create(1500)


def read_poses(path):
    rows = [l.split() for l in open(path) if l.strip() and not l.startswith("#")]
    return np.array([[float(v) for v in r[:8]] for r in rows])


def quat_to_rot(q):
    x, y, z, w = q / np.linalg.norm(q)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def slerp(qa, qb, s):
    dot = float(np.dot(qa, qb))
    if dot < 0.0:
        qb, dot = -qb, -dot
    if dot > 0.9995:
        q = qa + s * (qb - qa)
        return q / np.linalg.norm(q)
    theta = np.arccos(dot)
    return (np.sin((1 - s) * theta) * qa + np.sin(s * theta) * qb) / np.sin(theta)


def gt_pose(gt, t):
    """(R, p) camera-to-world at time t, or None outside the ground truth."""
    i = int(np.searchsorted(gt[:, 0], t))
    if i == 0 or i >= len(gt):
        return None
    a, b = gt[i - 1], gt[i]
    s = (t - a[0]) / (b[0] - a[0])
    return quat_to_rot(slerp(a[4:8], b[4:8], s)), a[1:4] * (1 - s) + b[1:4] * s


def listing(seq, name):
    return [(t, os.path.join(seq, f)) for t, f in read_list(seq, name)]


def nearest(items, t, max_dt=0.02):
    best = min(items, key=lambda it: abs(it[0] - t))
    return best[1] if abs(best[0] - t) <= max_dt else None


@functools.lru_cache(maxsize=2)
def features(rgb):
    """ORB keypoints and descriptors of a colour image: each frame is the second of one pair and
    the first of the next."""
    return ORB.detectAndCompute(cv2.imread(rgb, cv2.IMREAD_GRAYSCALE), None)


@functools.lru_cache(maxsize=2)
def person_mask(seq, t):
    """The sequence's mask of the frame with stamp t (!= 0: a person), or None."""
    path = os.path.join(seq, "mask", "%.6f.png" % t)
    return cv2.imread(path, cv2.IMREAD_GRAYSCALE) if os.path.exists(path) else None


def static_matches(seq, rgb_a, rgb_b, depth_a, t_a, t_b, K):
    """Matches of frame a and b off people and with depth in a: a's points lifted (3 x n), b's
    pixels (n x 2)."""
    depth = cv2.imread(depth_a, cv2.IMREAD_UNCHANGED).astype(np.float64) / 5000.0
    (ka, da), (kb, db) = features(rgb_a), features(rgb_b)
    if da is None or db is None:
        return None
    m = cv2.BFMatcher(cv2.NORM_HAMMING, crossCheck=True).match(da, db)
    pa = np.array([ka[x.queryIdx].pt for x in m]).reshape(-1, 2)
    pb = np.array([kb[x.trainIdx].pt for x in m]).reshape(-1, 2)
    ua, ub = pa.astype(int), pb.astype(int)
    z = depth[ua[:, 1], ua[:, 0]]
    keep = (z > 0.3) & (z < 4.0)
    ma, mb = person_mask(seq, t_a), person_mask(seq, t_b)
    if ma is not None and mb is not None:
        keep &= (ma[ua[:, 1], ua[:, 0]] == 0) & (mb[ub[:, 1], ub[:, 0]] == 0)
    pa, pb, z = pa[keep], pb[keep], z[keep]
    x_a = np.linalg.inv(K) @ np.vstack([pa.T, np.ones(len(pa))]) * z
    return x_a, pb


def reprojection(x_a, pb, pose_a, pose_b, K):
    (ra, ta), (rb, tb) = pose_a, pose_b
    x_b = rb.T @ (ra @ x_a + (ta - tb)[:, None])
    u = K @ x_b
    return np.linalg.norm((u[:2] / u[2]).T - pb, axis=1)


def plot(path, rows, limit, bars):
    w, h, left, top = 1000, 340, 50, 30
    img = np.full((h, w, 3), 255, np.uint8)
    t0, t1, ymax = rows[0][0], rows[-1][0], 8.0

    def xy(t, v):
        return (int(left + (t - t0) / max(t1 - t0, 1e-9) * (w - left - 20)),
                int(h - 40 - min(v, ymax) / ymax * (h - 40 - top)))

    for t, share in bars.items():  # grey bars: the standing person's masked share, 0..1 = 0..8
        if t0 <= t <= t1:
            x0, y0 = xy(t, share * ymax)
            cv2.rectangle(img, (x0 - 3, y0), (x0 + 3, h - 40), (210, 210, 210), -1)
    for v in range(0, int(ymax) + 1, 2):
        cv2.line(img, xy(t0, v), xy(t1, v), (230, 230, 230), 1)
        cv2.putText(img, "%d" % v, (15, xy(t0, v)[1] + 4), 0, 0.4, (0, 0, 0), 1)
    cv2.line(img, xy(t0, limit), xy(t1, limit), (160, 160, 160), 1)
    for t in np.arange(0.0, t1 - t0 + 1e-9, 1.0):
        cv2.putText(img, "%.0f" % t, (xy(t0 + t, 0)[0] - 4, h - 26), 0, 0.4, (0, 0, 0), 1)
    series = [("ground truth's motion", 2, (0, 0, 220)), ("the run's motion", 3, (200, 80, 0))]
    for label, col, colour in series:
        pts = np.array([xy(r[0], r[col]) for r in rows], np.int32)
        cv2.polylines(img, [pts], False, colour, 1, cv2.LINE_AA)
    draw_legend(img, [(label, colour) for label, _, colour in series] +
                ([("standing person masked (share of him, keyframes)", (210, 210, 210))]
                 if bars else []), left, top)
    cv2.putText(img, "median reprojection error of static features between consecutive frames "
                "[px]; time [s]", (left, h - 12), 0, 0.45, (0, 0, 0), 1, cv2.LINE_AA)
    cv2.imwrite(path, img)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("seq")
    ap.add_argument("run")
    ap.add_argument("--png")
    ap.add_argument("--limit", type=float, default=2.5)
    ap.add_argument("--intrinsics", default="535.4,539.2,320.1,247.6", help="fx,fy,cx,cy")
    args = ap.parse_args()
    fx, fy, cx, cy = (float(v) for v in args.intrinsics.split(","))
    K = np.array([[fx, 0, cx], [0, fy, cy], [0, 0, 1]])
    gt = read_poses(os.path.join(args.seq, "groundtruth.txt"))
    est = read_poses(os.path.join(args.run, "trajectory.txt"))
    rgb, depth = listing(args.seq, "rgb.txt"), listing(args.seq, "depth.txt")
    rows = []
    for a, b in zip(est[:-1], est[1:]):
        ga, gb = gt_pose(gt, a[0]), gt_pose(gt, b[0])
        rgb_a, rgb_b, depth_a = nearest(rgb, a[0], 1e-4), nearest(rgb, b[0], 1e-4), nearest(depth, a[0])
        if ga is None or gb is None or None in (rgb_a, rgb_b, depth_a):
            continue
        found = static_matches(args.seq, rgb_a, rgb_b, depth_a, a[0], b[0], K)
        if found is None or found[1].shape[0] < 20:
            continue
        x_a, pb = found
        e_gt = reprojection(x_a, pb, ga, gb, K)
        e_run = reprojection(x_a, pb, (quat_to_rot(a[4:8]), a[1:4]), (quat_to_rot(b[4:8]), b[1:4]),
                             K)
        use = np.minimum(e_gt, e_run) < 15.0
        if use.sum() < 20:
            continue
        rows.append((b[0], int(use.sum()), float(np.median(e_gt[use])), float(np.median(e_run[use]))))
        print("%.6f %4d %6.2f %6.2f" % rows[-1])
    if not rows:
        sys.exit("gt_consistency.py: no frame pair with ground truth and enough static features")
    r = np.array([row[2:] for row in rows])
    print("# %d pairs: mean of the medians, ground truth %.2f px, run %.2f px; pairs above %.1f px:"
          " ground truth %d, run %d" % (len(rows), r[:, 0].mean(), r[:, 1].mean(), args.limit,
                                        int((r[:, 0] > args.limit).sum()),
                                        int((r[:, 1] > args.limit).sum())))
    if args.png:
        plot(args.png, rows, args.limit, standing_share(args.seq, args.run))


if __name__ == "__main__":
    main()
