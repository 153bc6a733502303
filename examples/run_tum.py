"""Runs dynamap on a TUM RGB-D folder through the Python module (build/python on PYTHONPATH):
    python3 examples/run_tum.py SEQUENCE_DIR OUT_DIR [section.key=value ...]
Writes OUT_DIR/trajectory.txt (as `dynamap run` does) and the map in OUT_DIR/map."""
import bisect, pathlib, sys
import cv2, numpy as np
import dynamap


def tum_frames(folder, max_diff_s=0.02):
    """[(timestamp, colour path, depth path or None)], associated as `dynamap run` does."""
    def read(name):
        rows = [l.split() for l in open(f"{folder}/{name}") if l.strip() and not l.startswith("#")]
        return {float(r[0]): f"{folder}/{r[1]}" for r in rows}
    rgb, depth = read("rgb.txt"), read("depth.txt")
    ds = sorted(depth)
    near = lambda a: ds[bisect.bisect_left(ds, a - max_diff_s):bisect.bisect_right(ds, a + max_diff_s)]
    pairs, used = {}, set()  # TUM associate.py: closest pairs first, each stamp used once
    for _, a, b in sorted((abs(a - b), a, b) for a in rgb for b in near(a) if abs(a - b) < max_diff_s):
        if a not in pairs and b not in used:
            pairs[a] = b; used.add(b)
    return [(t, rgb[t], depth[pairs[t]] if t in pairs else None) for t in sorted(rgb)]


if __name__ == "__main__":
    folder, out = sys.argv[1], pathlib.Path(sys.argv[2])
    overrides = dict(arg.split("=", 1) for arg in sys.argv[3:])
    limit = int(overrides.get("dataset.max_frames", 0)) or None
    system = dynamap.System(str(pathlib.Path(__file__).resolve().parents[1] / "config/default.yaml"), overrides)
    for t, rgb_path, depth_path in tum_frames(folder)[:limit]:
        bgr = cv2.imread(rgb_path, cv2.IMREAD_COLOR)
        depth = cv2.imread(depth_path, cv2.IMREAD_UNCHANGED) if depth_path else np.zeros(bgr.shape[:2], np.uint16)
        result = system.track(bgr, depth, t)  # result.pose (4x4), result.status, result.mask (HxW)
    system.export_map(str(out / "map"))
    system.save_trajectory(str(out / "trajectory.txt"))
    print(system.counts)
