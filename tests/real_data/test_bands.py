"""The band logic of bands.py: limits from samples, violations, reading a run's outputs."""
import json
import os
import sys

import pytest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import bands  # noqa: E402


def test_limit_lies_on_the_worse_side_at_three_sd_and_never_inside_the_samples():
    samples = [1.0, 1.2, 1.1, 0.9, 1.0, 1.3]
    upper = bands.band_of(samples, higher_is_better=False)
    assert set(upper) == {"max"}
    assert upper["max"] > max(samples)
    lower = bands.band_of([0.8, 0.8, 0.8], higher_is_better=True)
    assert lower == {"min": 0.8}  # no spread: the worst sample is the limit


def test_a_worse_metric_fails_a_better_one_passes_a_missing_one_fails():
    limits = {"ate_cm": {"max": 1.5}, "mask_iou": {"min": 0.7}, "map_precision": {"min": 0.9}}
    bad = bands.violations({"ate_cm": 1.6, "mask_iou": 0.95}, limits)
    assert sorted(b[0] for b in bad) == ["ate_cm", "map_precision"]
    assert bands.violations({"ate_cm": 0.2, "mask_iou": 0.99, "map_precision": 1.0}, limits) == []


def test_reads_ate_in_cm_masks_map_and_frame_states(tmp_path):
    (tmp_path / "metrics.json").write_text(json.dumps({
        "ate": {"rmse_m": 0.0123}, "masks": {"mean_iou": 0.7, "pixel_recall": 0.9},
        "map": {"precision": 0.95, "ghost_ratio": 0.001}}))
    (tmp_path / "frames.txt").write_text("# t status\n1.0 tracked\n2.0 lost\n3.0 relocalized\n"
                                         "4.0 lost\n5.0 depth\n6.0 depth\n7.0 depth\n")
    values = bands.read_metrics(str(tmp_path))
    assert abs(values["ate_cm"] - 1.23) < 1e-9
    assert values["lost_frames"] == 2 and values["relocalized_frames"] == 1
    assert values["posed_by_depth_frames"] == 3
    assert values["mask_iou"] == 0.7 and values["map_ghost_ratio"] == 0.001
    assert "mask_precision" not in values


def test_every_case_has_bands_for_ate():
    recorded = bands.load_bands()["cases"]
    for case in bands.CASES:
        assert "ate_cm" in recorded.get(case, {}), case


def test_sweep_starts_are_a_range_or_a_list_and_anything_else_is_one_clear_error():
    assert bands.parse_starts("0-11") == list(range(12))
    assert bands.parse_starts("3") == [3]
    assert bands.parse_starts("0,3,7") == [0, 3, 7]
    with pytest.raises(SystemExit, match="--starts 'a-b'"):
        bands.parse_starts("a-b")
