#!/usr/bin/python3
"""How well a sequence's depth is registered to its colour, with and without undistortion.

  scripts/depth_colour_alignment.py SEQ --config CONFIG.yaml --distortion k1,k2,p1,p2

For every colour frame (and the depth frame nearest in time): the median and the mean (of
those within 5 px) distance from each depth discontinuity pixel (the near side of a jump of
more than 10 cm) to the nearest colour edge (Canny), in rings around the principal point,
for the images as they are, both undistorted with the same maps (what the reader does when the
camera has distortion), and colour alone undistorted. Depth registered to the raw colour image
lines up best as it is and with both undistorted; depth registered to an undistorted one, with
colour alone undistorted. Also prints how far the distortion moves pixels in each ring.
"""
import argparse

import cv2
import numpy as np
import yaml

from tum_lists import read_list  # the scripts' one reader of rgb.txt / depth.txt

RINGS = [(0, 150), (150, 250), (250, 330), (330, 400)]
JUMP_M = 0.10


def camera_of(config_path):
    with open(config_path) as f:
        cam = yaml.safe_load(f)["camera"]
    K = np.array([[cam["fx"], 0, cam["cx"]], [0, cam["fy"], cam["cy"]], [0, 0, 1]], float)
    return K, (int(cam.get("width", 640)), int(cam.get("height", 480))), float(cam.get("depth_scale", 5000))


def depth_discontinuities(depth_m):
    """The near side of every jump of more than JUMP_M between 4-neighbours with readings."""
    z = depth_m
    edges = np.zeros(z.shape, bool)
    right, left = z[:, 1:], z[:, :-1]
    jump = (np.abs(right - left) > JUMP_M) & (right > 0) & (left > 0)
    edges[:, 1:] |= jump & (right < left)
    edges[:, :-1] |= jump & (left < right)
    below, above = z[1:, :], z[:-1, :]
    jump = (np.abs(below - above) > JUMP_M) & (below > 0) & (above > 0)
    edges[1:, :] |= jump & (below < above)
    edges[:-1, :] |= jump & (above < below)
    return edges


def edge_distances(gray, depth_m, ring_masks):
    colour_edges = cv2.Canny(cv2.GaussianBlur(gray, (5, 5), 1.2), 40, 100)
    dist = cv2.distanceTransform((colour_edges == 0).astype(np.uint8), cv2.DIST_L2, 5)
    near = depth_discontinuities(depth_m)
    return [dist[near & ring].tolist() for ring in ring_masks]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("sequence")
    ap.add_argument("--config", required=True, help="a dynamap config with a camera: section")
    ap.add_argument("--distortion", required=True, help="k1,k2,p1,p2")
    args = ap.parse_args()
    K, size, depth_scale = camera_of(args.config)
    D = np.array([float(v) for v in args.distortion.split(",")] + [0.0])
    map_x, map_y = cv2.initUndistortRectifyMap(K, D, None, K, size, cv2.CV_32FC1)
    yy, xx = np.mgrid[0:size[1], 0:size[0]]
    radius = np.hypot(xx - K[0, 2], yy - K[1, 2])
    rings = [(radius >= a) & (radius < b) for a, b in RINGS]
    moved = np.hypot(map_x - xx, map_y - yy)
    print("rings (px from the principal point):", RINGS)
    print("%-12s %s" % ("moved by", " ".join("max %.2f median %.2f" % (moved[r].max(), np.median(moved[r])) for r in rings)))
    rgb = read_list(args.sequence, "rgb.txt")
    depth = read_list(args.sequence, "depth.txt")
    depth_t = np.array([t for t, _ in depth])
    found = {name: [[] for _ in RINGS] for name in ("as is", "both", "colour only")}
    for stamp, name in rgb:
        nearest = depth[int(np.argmin(np.abs(depth_t - stamp)))][1]
        gray = cv2.imread(args.sequence + "/" + name, cv2.IMREAD_GRAYSCALE)
        raw = cv2.imread(args.sequence + "/" + nearest, cv2.IMREAD_UNCHANGED)
        if gray is None or raw is None:
            raise SystemExit("cannot read %s or %s" % (name, nearest))
        gray_u = cv2.remap(gray, map_x, map_y, cv2.INTER_LINEAR)
        raw_u = cv2.remap(raw, map_x, map_y, cv2.INTER_NEAREST)
        for variant, (g, d) in {"as is": (gray, raw), "both": (gray_u, raw_u),
                                "colour only": (gray_u, raw)}.items():
            for k, values in enumerate(edge_distances(g, d.astype(np.float32) / depth_scale, rings)):
                found[variant][k].extend(values)
    for variant, per_ring in found.items():
        cells = []
        for values in per_ring:
            near = [v for v in values if v <= 5.0]
            cells.append("median %.2f mean(<=5) %.2f n %d" % (np.median(values), np.mean(near), len(values)))
        print("%-12s %s" % (variant, " | ".join(cells)))


if __name__ == "__main__":
    main()
