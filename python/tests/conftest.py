"""Paths for the Python tests: set by ctest (python/CMakeLists.txt), with in-tree fallbacks."""
import os
import pathlib
import sys

import pytest

SOURCE_DIR = pathlib.Path(os.environ.get("DYNAMAP_SOURCE_DIR", pathlib.Path(__file__).parents[2]))
SHARED_DIR = pathlib.Path(os.environ.get("DYNAMAP_SHARED_DIR", SOURCE_DIR.parent / "shared"))
CLI = pathlib.Path(os.environ.get("DYNAMAP_CLI", SOURCE_DIR / "build/bin/dynamap"))
TEDDY = SHARED_DIR / "data/tum/rgbd_dataset_freiburg3_teddy"
CONFIG = SOURCE_DIR / "config/default.yaml"

sys.path.insert(0, str(SOURCE_DIR / "examples"))  # run_tum.tum_frames


@pytest.fixture
def teddy():
    if not (TEDDY / "rgb.txt").exists():
        pytest.skip(f"TUM teddy not found: {TEDDY}")
    return TEDDY
