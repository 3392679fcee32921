"""Procedural terrain snapshots and their ground truth, rendered on the GPU.

``terrain`` renders a height map (the *sketch*) with procedural detail added at render time,
by geometry image warping (Dachsbacher & Stamminger, *Rendering Procedural Terrain by Geometry
Image Warping*, 2004). A :class:`Renderer` keeps one device and its pipelines across calls;
:meth:`Renderer.render` returns the picture and, beside it, depth, distance, world positions,
latitude and longitude and normals as NumPy arrays.

>>> import terrain
>>> scene = terrain.Scene.load("sketches/jacksboro.toml")          # doctest: +SKIP
>>> renderer = terrain.Renderer(scene, size=256)                    # doctest: +SKIP
>>> out = renderer.render(outputs=["rgb", "depth"])                 # doctest: +SKIP
>>> out["rgb"].shape, out["depth"].dtype                            # doctest: +SKIP
((256, 256, 3), dtype('float32'))
"""

import os as _os
import tempfile as _tempfile

# Mesa's Vulkan device-select layer connects to a Wayland display whenever an adapter is
# requested; where XDG_RUNTIME_DIR is unset or empty (a container, a CI job, ssh) libwayland then
# prints an error about a display nobody asked for. Pointing it at the temporary folder makes the
# probe fail quietly, as the `terrain` command does; a real Wayland session always sets it.
if not _os.environ.get("XDG_RUNTIME_DIR") and "WAYLAND_DISPLAY" not in _os.environ:
    _os.environ["XDG_RUNTIME_DIR"] = _tempfile.gettempdir()

from ._terrain import (  # noqa: E402
    Camera,
    Error,
    Renderer,
    SURFACE_CLASSES,
    Scene,
    devices_opened,
    random_cameras,
)

__all__ = [
    "Camera",
    "Error",
    "Renderer",
    "SURFACE_CLASSES",
    "Scene",
    "devices_opened",
    "random_cameras",
]
