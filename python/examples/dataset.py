"""A PyTorch-style dataset of (rgb, depth) pairs from random cameras over a sketch.

It is a plain class with ``__len__`` and ``__getitem__``, which is all ``torch.utils.data``
asks of a map-style dataset, so the package needs no PyTorch; with PyTorch installed:

    from torch.utils.data import DataLoader
    loader = DataLoader(TerrainDataset("sketches/jacksboro.toml", 1000), batch_size=8,
                        num_workers=2)

Each worker process renders with a renderer of its own, made on first use (a device is not
shared across processes). Item i is always the same view: the i-th random camera of the seed.

Run it to see a few pairs:  python python/examples/dataset.py sketches/jacksboro.toml
"""

import sys

import numpy as np

import terrain


class TerrainDataset:
    """(rgb, depth) pairs: rgb float32 (3, H, W) in 0…1, depth float32 (1, H, W) in metres with
    the sky at `sky_m`."""

    def __init__(self, scene_path, count, size=256, seed=0, sky_m=1e5):
        self.scene = terrain.Scene.load(scene_path)
        self.cameras = terrain.random_cameras(self.scene, count, seed=seed)
        self.size = size
        self.sky_m = sky_m
        self._renderer = None

    def __len__(self):
        return len(self.cameras)

    def __getitem__(self, i):
        if self._renderer is None:
            self._renderer = terrain.Renderer(self.scene, size=self.size)
        out = self._renderer.render(camera=self.cameras[i], outputs=["rgb", "depth"])
        rgb = out["rgb"].astype(np.float32).transpose(2, 0, 1) / 255.0
        depth = np.where(np.isinf(out["depth"]), self.sky_m, out["depth"])[None]
        return rgb, depth.astype(np.float32)

    def __getstate__(self):
        # Worker processes get the cameras, not the device.
        state = self.__dict__.copy()
        state["_renderer"] = None
        state["scene"] = str(self.scene.path)
        return state

    def __setstate__(self, state):
        state["scene"] = terrain.Scene.load(state["scene"])
        self.__dict__.update(state)


if __name__ == "__main__":
    data = TerrainDataset(sys.argv[1] if len(sys.argv) > 1 else "sketches/jacksboro.toml", 4,
                          size=128)
    for k in range(len(data)):
        rgb, depth = data[k]
        ground = depth < data.sky_m
        print(f"item {k}: rgb {rgb.shape} {rgb.dtype}, depth {depth.shape}, "
              f"ground {ground.mean():.0%}, nearest {depth.min():.0f} m")
