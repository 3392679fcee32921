"""Type stubs of terrain's native module (python/src/lib.rs)."""

from os import PathLike
from typing import Dict, List, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

_Path = Union[str, PathLike]

SURFACE_CLASSES: List[str]
"""The surface classes' names by index ("sky", "water", "meadow", …): the legend of "surface"."""

class Error(Exception):
    """A scene, sketch, camera or device the renderer cannot use; its message is one line."""

class Scene:
    """A scene: the sketch (height map), its detail, light and camera (docs/scene.md)."""

    @staticmethod
    def load(path: _Path, overrides: Sequence[str] = ...) -> "Scene":
        """Reads a scene file (.toml) or a sketch with every default; `overrides` are
        `key=value` strings as `--set` takes them."""
    @staticmethod
    def from_sketch(path: _Path, overrides: Sequence[str] = ...) -> "Scene":
        """A sketch (height map: GeoTIFF, .asc, .hgt, PNG, …) as a scene with every default."""
    @property
    def path(self) -> str: ...
    @property
    def size(self) -> Tuple[int, int]:
        """The default camera's image size, (width, height)."""

class Camera:
    """Where a camera stands and looks: `position` and `look_at` (world metres), or a place by
    `map_xy`, or `lat_deg` and `lon_deg`, with `altitude_m`, aimed by `heading_deg` and
    `pitch_deg`."""

    position: Optional[Tuple[float, float, float]]
    look_at: Optional[Tuple[float, float, float]]
    map_xy: Optional[Tuple[float, float]]
    lat_deg: Optional[float]
    lon_deg: Optional[float]
    altitude_m: Optional[float]
    heading_deg: Optional[float]
    pitch_deg: Optional[float]
    fov_y_deg: Optional[float]
    def __init__(
        self,
        *,
        position: Optional[Sequence[float]] = None,
        look_at: Optional[Sequence[float]] = None,
        map_xy: Optional[Sequence[float]] = None,
        lat_deg: Optional[float] = None,
        lon_deg: Optional[float] = None,
        altitude_m: Optional[float] = None,
        heading_deg: Optional[float] = None,
        pitch_deg: Optional[float] = None,
        fov_y_deg: Optional[float] = None,
    ) -> None: ...

class Renderer:
    """A renderer of one scene at one image size and mode, on a device of its own kept across
    calls."""

    def __init__(
        self,
        scene: Scene,
        size: Union[int, Tuple[int, int], None] = None,
        mode: Optional[str] = None,
    ) -> None: ...
    def render(
        self, camera: Optional[Camera] = None, outputs: Sequence[str] = ("rgb",)
    ) -> Dict[str, npt.NDArray[np.generic]]:
        """The view from `camera` (default the scene's): a dict of the `outputs` asked for
        ("rgb" uint8 (H, W, 3); "depth", "distance" float32 (H, W); "positions" float64
        (H, W, 4); "latlon" float64 (H, W, 2); "normals" float32 (H, W, 3); "surface" uint8
        (H, W), indices into SURFACE_CLASSES) and the camera's
        "K" (3×3), "world_to_camera" and "camera_to_world" (4×4, OpenCV's axes)."""
    def height_at(self, x: float, y: float) -> Optional[float]:
        """The terrain's height at world point (x, y), metres; None where nothing is drawn."""
    @property
    def size(self) -> Tuple[int, int]: ...
    @property
    def mode(self) -> str: ...
    @property
    def adapter(self) -> str: ...

def random_cameras(scene: Scene, n: int, seed: int = 0) -> List[Camera]:
    """`n` random cameras over the sketch: a jobs file's `[random]` with that seed, in order."""

def devices_opened() -> int:
    """Devices this process's renderers have opened."""
