"""The Python path equals `dynamap run` on teddy; bad input raises clear errors."""
import subprocess

import cv2
import numpy as np
import pytest

import dynamap
from conftest import CLI, CONFIG
from run_tum import tum_frames

FRAMES = 40
FAST = {"dynamic.mode": "off", "mapping.backend": "points"}  # no detector: quick error tests


def load(entry):
    t, rgb_path, depth_path = entry
    bgr = cv2.imread(rgb_path, cv2.IMREAD_COLOR)
    if depth_path is None:
        return t, bgr, np.zeros(bgr.shape[:2], np.uint16)
    return t, bgr, cv2.imread(depth_path, cv2.IMREAD_UNCHANGED)


def test_trajectory_equals_cli(teddy, tmp_path):
    cli_out = tmp_path / "cli"
    subprocess.run([str(CLI), "run", "--sequence", str(teddy), "--out", str(cli_out), "--quiet",
                    "--config", str(CONFIG), "--set", f"dataset.max_frames={FRAMES}"],
                   check=True, stdout=subprocess.DEVNULL)
    system = dynamap.System(str(CONFIG))
    results = [system.track(bgr, depth, t) for t, bgr, depth in map(load, tum_frames(teddy)[:FRAMES])]
    system.export_map(str(tmp_path / "map"))
    system.save_trajectory(str(tmp_path / "trajectory.txt"))

    assert (tmp_path / "trajectory.txt").read_text() == (cli_out / "trajectory.txt").read_text()
    trajectory = system.trajectory()
    assert len(trajectory) == FRAMES
    np.testing.assert_allclose(trajectory[0][1], np.eye(4), atol=1e-12)
    assert all(np.isfinite(pose).all() for _, pose in trajectory)
    cli = np.loadtxt(cli_out / "trajectory.txt")
    np.testing.assert_allclose([t for t, _ in trajectory], cli[:, 0], atol=1e-6)
    np.testing.assert_allclose([p[:3, 3] for _, p in trajectory], cli[:, 1:4], rtol=1e-8, atol=1e-9)
    cli_statuses = [line.split()[1] for line in (cli_out / "frames.txt").read_text().splitlines()[1:]]
    assert system.frame_statuses() == cli_statuses
    assert any(r.is_keyframe for r in results) and any(r.mask.any() for r in results)
    for r in results:
        assert r.pose.shape == (4, 4) and r.pose.dtype == np.float64
        assert r.mask.shape == (480, 640) and r.mask.dtype == np.uint8
        assert set(np.unique(r.mask)) <= {0, 255}
    assert any((tmp_path / "map").iterdir())


def test_float_metres_depth_matches_uint16(teddy):
    frames = [load(e) for e in tum_frames(teddy)[:8]]
    a, b = dynamap.System(overrides=FAST), dynamap.System(overrides=FAST)
    for t, bgr, depth in frames:
        pa = a.track(bgr, depth, t).pose
        # The same metres as cv::Mat::convertTo(CV_32F, 1.0 / 5000) computes (a float product
        # with the float scale); a division differs in the last bit on 30 % of the values, and
        # the tracker's RANSAC decisions may amplify that to millimetres.
        metres = depth.astype(np.float32) * np.float32(1.0 / 5000.0)
        pb = b.track(bgr, metres, t).pose
        np.testing.assert_allclose(pa, pb, atol=1e-5)
    assert a.counts["frames"] == 8


@pytest.mark.parametrize("bgr, depth, message", [
    (np.zeros((480, 640, 3), np.uint16), np.zeros((480, 640), np.uint16), "dtype uint8"),
    (np.zeros((480, 640), np.uint8), np.zeros((480, 640), np.uint16), "shape (H, W, 3)"),
    (np.zeros((480, 640, 4), np.uint8), np.zeros((480, 640), np.uint16), "got (480, 640, 4)"),
    (np.zeros((480, 640, 3), np.uint8), np.zeros((480, 640), np.float64), "dtype uint16"),
    (np.zeros((480, 640, 3), np.uint8), np.zeros((480, 640, 1), np.uint16), "shape (H, W)"),
    (np.zeros((480, 640, 3), np.uint8), np.zeros((240, 320), np.uint16),
     "depth image is 320x240 but colour image is 640x480"),
])
def test_bad_images_raise_value_error(bgr, depth, message):
    system = dynamap.System(overrides=FAST)
    with pytest.raises(ValueError) as error:
        system.track(bgr, depth, 0.0)
    assert message in str(error.value)
    assert system.counts["frames"] == 0


def test_unknown_key_raises_the_cli_message(tmp_path):
    with pytest.raises(dynamap.ConfigError) as error:
        dynamap.System(overrides={"tracking.no_such_key": 3})
    assert "tracking.no_such_key" in str(error.value)
    assert isinstance(error.value, ValueError)
    cli = subprocess.run([str(CLI), "run", "--sequence", str(tmp_path), "--out", str(tmp_path / "o"),
                          "--set", "tracking.no_such_key=3"], capture_output=True, text=True)
    assert cli.returncode != 0
    assert str(error.value) in cli.stderr


def test_bad_value_and_missing_file_raise_config_error(tmp_path):
    with pytest.raises(dynamap.ConfigError, match="tracking.lk_levels"):
        dynamap.System(overrides={"tracking.lk_levels": "many"})
    with pytest.raises(dynamap.ConfigError, match="nope.yaml"):
        dynamap.System(str(tmp_path / "nope.yaml"))
    with pytest.raises(ValueError, match="override values"):
        dynamap.System(overrides={"tracking.lk_levels": object()})


def test_unknown_backend_lists_known_ones():
    with pytest.raises(RuntimeError, match="pcl_voxel"):
        dynamap.System(overrides={"mapping.backend": "no_such_backend", "dynamic.mode": "off"})


def test_track_after_finish_raises():
    system = dynamap.System(overrides=FAST)
    system.finish()
    with pytest.raises(RuntimeError, match="after finish"):
        system.track(np.zeros((480, 640, 3), np.uint8), np.zeros((480, 640), np.uint16), 0.0)
    assert system.trajectory() == []


def test_docstrings():
    assert "BGR" in dynamap.System.track.__doc__
    assert "ConfigError" in dynamap.System.__init__.__doc__


def ply_vertices(path):
    """The vertex count in a PLY header."""
    with open(path, "rb") as f:
        for line in f:
            if line.startswith(b"element vertex"):
                return int(line.split()[2])
            if line.strip() == b"end_header":
                break
    return 0


def test_map_snapshot_before_finish(teddy, tmp_path):
    """The map exists while the camera runs: a snapshot mid-run holds keyframes and points."""
    system = dynamap.System(overrides=FAST)
    frames = tum_frames(teddy)[:60]
    for t, bgr, depth in map(load, frames):
        system.track(bgr, depth, t)
    system.export_map_snapshot(str(tmp_path / "mid"))
    mid_keyframes = system.counts["mapped_keyframes"]
    mid_points = ply_vertices(tmp_path / "mid" / "cloud.ply")
    assert mid_keyframes > 0 and mid_points > 0
    assert system.counts["map_elements"] == mid_points
    system.finish()
    assert system.counts["mapped_keyframes"] >= mid_keyframes
