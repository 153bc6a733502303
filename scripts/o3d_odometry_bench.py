#!/usr/bin/python3
"""Peer for the tracking benchmark: Open3D's frame-to-frame RGB-D odometry on a TUM sequence.

usage: o3d_odometry_bench.py SEQUENCE_DIR TERM OUT_TRAJECTORY [MAX_FRAMES]
  TERM: color (photometric term) or hybrid (photometric + geometric)
Writes the chained camera-to-world poses in TUM format and prints one JSON line:
{"term", "frames", "failed", "ms_per_frame_median", "ms_per_frame_mean"}.
Colour and depth are paired by nearest timestamp within 0.02 s, as dynamap does; freiburg3
intrinsics, 5000 depth units per metre, depth cut at 4 m (dynamap's mapping range).
Needs Debian's python3-open3d; run with /usr/bin/python3.
"""
import json
import statistics
import sys
import time

import numpy as np
import open3d as o3d

from tum_lists import read_list

FX, FY, CX, CY = 535.4, 539.2, 320.1, 247.6


def associate(rgb, depth, max_diff=0.02):
    pairs, j = [], 0
    for t, name in rgb:
        while j + 1 < len(depth) and abs(depth[j + 1][0] - t) <= abs(depth[j][0] - t):
            j += 1
        if depth and abs(depth[j][0] - t) <= max_diff:
            pairs.append((t, name, depth[j][1]))
    return pairs


def quaternion(r):
    w = np.sqrt(max(0.0, 1.0 + r[0, 0] + r[1, 1] + r[2, 2])) / 2.0
    x = np.sqrt(max(0.0, 1.0 + r[0, 0] - r[1, 1] - r[2, 2])) / 2.0
    y = np.sqrt(max(0.0, 1.0 - r[0, 0] + r[1, 1] - r[2, 2])) / 2.0
    z = np.sqrt(max(0.0, 1.0 - r[0, 0] - r[1, 1] + r[2, 2])) / 2.0
    x = np.copysign(x, r[2, 1] - r[1, 2])
    y = np.copysign(y, r[0, 2] - r[2, 0])
    z = np.copysign(z, r[1, 0] - r[0, 1])
    q = np.array([x, y, z, w])
    return q / np.linalg.norm(q)


def main():
    if len(sys.argv) < 4 or sys.argv[2] not in ("color", "hybrid"):
        sys.exit(__doc__)
    seq, term, out = sys.argv[1], sys.argv[2], sys.argv[3]
    limit = int(sys.argv[4]) if len(sys.argv) > 4 else None
    frames = associate(read_list(seq, "rgb.txt"), read_list(seq, "depth.txt"))[:limit]
    intr = o3d.camera.PinholeCameraIntrinsic(640, 480, FX, FY, CX, CY)
    jac = (o3d.pipelines.odometry.RGBDOdometryJacobianFromColorTerm() if term == "color" else
           o3d.pipelines.odometry.RGBDOdometryJacobianFromHybridTerm())
    option = o3d.pipelines.odometry.OdometryOption()

    def load(f):
        return o3d.geometry.RGBDImage.create_from_color_and_depth(
            o3d.io.read_image(seq + "/" + f[1]), o3d.io.read_image(seq + "/" + f[2]),
            depth_scale=5000.0, depth_trunc=4.0, convert_rgb_to_intensity=True)

    pose, poses, times, failed = np.eye(4), [np.eye(4)], [], 0
    prev = load(frames[0])
    for f in frames[1:]:
        cur = load(f)
        start = time.perf_counter()
        ok, t_prev_cur, _ = o3d.pipelines.odometry.compute_rgbd_odometry(
            cur, prev, intr, np.eye(4), jac, option)
        times.append(1000.0 * (time.perf_counter() - start))
        if not ok:
            failed += 1
            t_prev_cur = np.eye(4)
        pose = pose @ t_prev_cur
        poses.append(pose.copy())
        prev = cur
    with open(out, "w") as f:
        for (t, _, _), p in zip(frames, poses):
            q = quaternion(p[:3, :3])
            f.write("%.6f %.6f %.6f %.6f %.6f %.6f %.6f %.6f\n" % (t, *p[:3, 3], *q))
    print(json.dumps({"term": term, "frames": len(frames), "failed": failed,
                      "ms_per_frame_median": statistics.median(times),
                      "ms_per_frame_mean": statistics.mean(times)}))


if __name__ == "__main__":
    main()
