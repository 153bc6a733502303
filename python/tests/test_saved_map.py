"""Save and reload from Python: System.save_map(dir), then System(load_map=dir) starts in that
map (poses in its frame) and a bad map raises MapFileError naming the file and the field."""
import numpy as np
import pytest

import dynamap
from run_tum import tum_frames
from test_system import FAST, load

FRAMES = 40


def test_reload_poses_in_the_saved_frame(teddy, tmp_path):
    frames = [load(e) for e in tum_frames(teddy)[:FRAMES]]
    first = dynamap.System(overrides=FAST)
    for t, bgr, depth in frames:
        first.track(bgr, depth, t)
    first.save_map(str(tmp_path / "saved"))
    assert (tmp_path / "saved" / "map.sqlite").is_file()
    saved_poses = {round(t, 6): pose for t, pose in first.trajectory()}
    saved_keyframes = first.counts["keyframes"]
    saved_elements = first.counts["map_elements"]

    # The same frames backward, 100 s later: poses of the same images in run 1's frame.
    second = dynamap.System(overrides=FAST, load_map=str(tmp_path / "saved"))
    for t, bgr, depth in reversed(frames):
        second.track(bgr, depth, t + 100.0)
    second.finish()
    counts = second.counts
    assert counts["loaded_keyframes"] == saved_keyframes
    assert counts["loaded_map_elements"] >= 0.98 * saved_elements  # the saved voxels, re-placed
    assert counts["lost"] <= 2  # relocalized within the first frames, then tracked
    errors = [np.linalg.norm(pose[:3, 3] - saved_poses[round(t - 100.0, 6)][:3, 3])
              for t, pose in second.trajectory()]
    assert len(errors) >= FRAMES - 2
    assert max(errors) < 0.02, max(errors)  # run 1 and 2 on the same images, no alignment
    assert counts["keyframes"] <= saved_keyframes // 2 + 1  # the saved keyframes are reused


def test_bad_map_raises_map_file_error(teddy, tmp_path):
    with pytest.raises(dynamap.MapFileError, match="map.sqlite: no such map file"):
        dynamap.System(overrides=FAST, load_map=str(tmp_path))
    t, bgr, depth = load(tum_frames(teddy)[0])
    system = dynamap.System(overrides=FAST)
    system.track(bgr, depth, t)
    system.save_map(str(tmp_path / "one_frame"))
    other_camera = dict(FAST, **{"camera.preset": "freiburg1"})
    with pytest.raises(dynamap.MapFileError, match=r"map.sqlite: meta.camera.fx: the map was made"):
        dynamap.System(overrides=other_camera, load_map=str(tmp_path / "one_frame"))
    assert issubclass(dynamap.MapFileError, ValueError)
