#!/usr/bin/env python3
"""Writes a synthetic mosaic tile by tile, never whole: N×N 16-bit PNG tiles of T² nodes with
world files (.pgw), on one 30 m grid in metres, for `terrain tiles`' bounded-memory figures.

Usage: make-large-mosaic.py OUT_DIR [TILES_PER_SIDE=32] [TILE=1024]
(32 × 1024 = 32,768² nodes; about 2.4 GB of PNG.) Heights: a sum of rotated ridged waves over
the whole mosaic (continuous across tiles), about 30..6600 m quantised to 0.1 m (convert with --height-scale 0.1).
Needs numpy and Pillow."""
import math, os, sys
import numpy as np
from PIL import Image

out = sys.argv[1]
n = int(sys.argv[2]) if len(sys.argv) > 2 else 32
t = int(sys.argv[3]) if len(sys.argv) > 3 else 1024
cell, west, north = 30.0, 500000.0, 4_500_000.0
os.makedirs(out, exist_ok=True)
rng = np.random.default_rng(7)
waves = [(rng.uniform(0, math.pi), 2 * math.pi / (40000 / 1.9 ** k), rng.uniform(0, 6.3),
          1400 / 1.75 ** k) for k in range(12)]
for ty in range(n):
    for tx in range(n):
        name = os.path.join(out, f"r{ty:03d}_c{tx:03d}")
        if os.path.exists(name + ".png"):
            continue
        # Row 0 of the image is north; tile row 0 is the mosaic's north edge.
        y = (ty * t + np.arange(t, dtype=np.float64))[:, None] * cell
        x = (tx * t + np.arange(t, dtype=np.float64))[None, :] * cell
        h = np.full((t, t), 3300.0)
        for a, f, p, amp in waves:
            u = (x * math.cos(a) + y * math.sin(a)) * f + p
            h += amp * (1 - 2 * np.abs(np.sin(u)))
        q = np.clip(h / 0.1, 0, 65535).astype(np.uint16)
        Image.fromarray(q).save(name + ".tmp.png")
        os.replace(name + ".tmp.png", name + ".png")
        with open(name + ".pgw", "w") as f:
            f.write(f"{cell}\n0\n0\n{-cell}\n{west + tx * t * cell}\n{north - ty * t * cell}\n")
