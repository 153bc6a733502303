"""Per-frame time of the Python path (examples/run_tum.py's loop: cv2.imread + System.track,
then export_map) vs `dynamap run` (its timings.json wall_time_s: image loading, tracking,
finish and map export) on the same sequence, interleaved REPEATS times in one run.
    PYTHONPATH=build/python /usr/bin/python3 scripts/python_overhead.py [SEQUENCE] [REPEATS]
Both exclude start-up (detector and plugin loading) and the CLI's report writing."""
import json, pathlib, statistics, subprocess, sys, tempfile, time

import cv2
import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "examples"))
import dynamap  # noqa: E402
from run_tum import tum_frames  # noqa: E402

sequence = sys.argv[1] if len(sys.argv) > 1 else str(ROOT.parent / "shared/data/tum/rgbd_dataset_freiburg3_teddy")
repeats = int(sys.argv[2]) if len(sys.argv) > 2 else 3
config = str(ROOT / "config/default.yaml")
cli_ms, py_ms = [], []
for _ in range(repeats):
    with tempfile.TemporaryDirectory() as out:
        subprocess.run([str(ROOT / "build/bin/dynamap"), "run", "--sequence", sequence, "--out", out,
                        "--config", config, "--quiet"], check=True, stdout=subprocess.DEVNULL)
        timings = json.loads((pathlib.Path(out) / "timings.json").read_text())
        cli_ms.append(1000.0 * timings["wall_time_s"] / timings["frames"])
        system = dynamap.System(config)
        frames = tum_frames(sequence)
        start = time.perf_counter()
        for t, rgb_path, depth_path in frames:
            bgr = cv2.imread(rgb_path, cv2.IMREAD_COLOR)
            depth = (cv2.imread(depth_path, cv2.IMREAD_UNCHANGED) if depth_path
                     else np.zeros(bgr.shape[:2], np.uint16))
            system.track(bgr, depth, t)
        system.export_map(out + "/py_map")
        py_ms.append(1000.0 * (time.perf_counter() - start) / len(frames))
        del system
cli, py = statistics.median(cli_ms), statistics.median(py_ms)
print(f"frames: {len(frames)}, repeats: {repeats} (interleaved)")
print(f"CLI    ms/frame: median {cli:.1f}  runs {', '.join(f'{v:.1f}' for v in cli_ms)}")
print(f"Python ms/frame: median {py:.1f}  runs {', '.join(f'{v:.1f}' for v in py_ms)}")
print(f"Python / CLI: {py / cli:.3f} ({py - cli:+.1f} ms/frame)")
