"""Type stub of the dynamap module (pybind11, python/src/module.cpp)."""

from typing import Any, Mapping, Optional, Sequence, Union

import numpy as np
import numpy.typing as npt

_Scalar = Union[str, int, float, bool]
_Pose = npt.NDArray[np.float64]  # shape (4, 4), camera-to-world

class ConfigError(ValueError):
    """Unknown configuration key, bad value or unreadable file (message names file/line/key)."""

class MapFileError(ValueError):
    """A saved map that is missing, corrupt or mismatched (message names file and field)."""

class TrackResult:
    """Outcome of System.track() for one frame."""

    @property
    def timestamp_s(self) -> float: ...
    @property
    def pose(self) -> _Pose:
        """4x4 float64 camera-to-world pose (the last known one when lost)."""
    @property
    def status(self) -> str:
        """'tracked', 'relocalized' or 'lost'."""
    @property
    def mask(self) -> npt.NDArray[np.uint8]:
        """HxW dynamic mask, 255 = moving."""
    @property
    def is_keyframe(self) -> bool: ...

class System:
    """Tracking + motion-area removal + dense mapping of one RGB-D sequence.

    Not thread-safe: call its methods from one thread at a time.
    """

    def __init__(
        self,
        config: Optional[str] = None,
        overrides: Optional[Mapping[str, Union[_Scalar, Sequence[_Scalar]]]] = None,
        load_map: Optional[str] = None,
    ) -> None:
        """Raises ConfigError for an unknown key or bad value, RuntimeError for an unknown
        backend or missing detector files."""
    def track(
        self,
        bgr: npt.NDArray[np.uint8],
        depth: Union[npt.NDArray[np.uint16], npt.NDArray[np.float32]],
        timestamp_s: float,
    ) -> TrackResult:
        """bgr HxWx3 uint8 (BGR); depth HxW uint16 (camera.depth_scale units per metre) or
        float32 metres. Raises ValueError for a wrong dtype or shape."""
    def trajectory(self) -> list[tuple[float, _Pose]]: ...
    def keyframes(self) -> list[tuple[float, _Pose]]: ...
    def frame_statuses(self) -> list[str]: ...
    def save_trajectory(self, path: str) -> None:
        """TUM format, as `dynamap run` writes OUT/trajectory.txt."""
    def finish(self) -> None: ...
    def export_map(self, directory: str) -> None: ...
    def save_map(self, directory: str) -> None:
        """finish(), then what System(load_map=directory) needs to start in this map."""
    def export_map_snapshot(self, directory: str) -> None:
        """The map as it is now, during the run, without finishing."""
    @property
    def counts(self) -> dict[str, Any]: ...
