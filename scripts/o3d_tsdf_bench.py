#!/usr/bin/python3
"""Open3D ScalableTSDFVolume on the frames dynamap_map_bench lists (same depth filtering:
mask dilation, depth range, depth edges). Prints "median_integrate_ms <x>" and writes the mesh.

usage: o3d_tsdf_bench.py FRAMES VOXEL TRUNC DEPTH_MIN DEPTH_MAX DILATE_PX EDGE_M OUT_MESH
FRAMES lines: rgb depth mask T_W_C (16 numbers, row-major)."""
import sys
import time

import cv2
import numpy as np
import open3d as o3d


def static_depth(depth_png, mask_png, zmin, zmax, dilate_px, edge_m):
    d = cv2.imread(depth_png, cv2.IMREAD_UNCHANGED).astype(np.float32) / 5000.0
    m = cv2.imread(mask_png, cv2.IMREAD_GRAYSCALE) == 255
    if dilate_px > 0:
        k = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * dilate_px + 1, 2 * dilate_px + 1))
        m = cv2.dilate(m.astype(np.uint8), k) > 0
    keep = (d >= zmin) & (d <= zmax) & ~m
    if edge_m > 0:
        p = np.pad(d, 1)
        c = p[1:-1, 1:-1]
        for n in (p[:-2, 1:-1], p[2:, 1:-1], p[1:-1, :-2], p[1:-1, 2:]):
            keep &= ~((n > 0) & (np.abs(n - c) > edge_m))
    return np.where(keep, d, 0.0).astype(np.float32)


def main():
    frames, voxel, trunc, zmin, zmax, dil, edge, out = sys.argv[1:9]
    voxel, trunc, zmin, zmax, edge = map(float, (voxel, trunc, zmin, zmax, edge))
    intr = o3d.camera.PinholeCameraIntrinsic(640, 480, 535.4, 539.2, 320.1, 247.6)
    vol = o3d.pipelines.integration.ScalableTSDFVolume(
        voxel_length=voxel, sdf_trunc=trunc,
        color_type=o3d.pipelines.integration.TSDFVolumeColorType.RGB8)
    times = []
    for line in open(frames):
        f = line.split()
        rgb = cv2.cvtColor(cv2.imread(f[0]), cv2.COLOR_BGR2RGB)
        d = static_depth(f[1], f[2], zmin, zmax, int(dil), edge)
        T = np.array([float(x) for x in f[3:19]]).reshape(4, 4)
        rgbd = o3d.geometry.RGBDImage.create_from_color_and_depth(
            o3d.geometry.Image(rgb), o3d.geometry.Image(d), depth_scale=1.0, depth_trunc=zmax,
            convert_rgb_to_intensity=False)
        t0 = time.perf_counter()
        vol.integrate(rgbd, intr, np.linalg.inv(T))
        times.append((time.perf_counter() - t0) * 1000.0)
    mesh = vol.extract_triangle_mesh()
    o3d.io.write_triangle_mesh(out, mesh)
    print("median_integrate_ms %.3f" % float(np.median(times)))


if __name__ == "__main__":
    main()
