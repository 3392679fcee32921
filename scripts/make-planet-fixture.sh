#!/usr/bin/env bash
# Writes tests/data/planet/global-64x32.tif: a 64 × 32 global grid (5.625° cells, EPSG:4326,
# Float32, north row first as GDAL writes it) of h = 3000·cos(lat)·sin(2·lon) + 1000·sin(3·lat)
# − 500 at the cells' centres, for tests/planet.rs. Needs GDAL (Debian's gdal-bin) and numpy.
set -euo pipefail
cd "$(dirname "$0")/.."
out=tests/data/planet
mkdir -p "$out"
tmp=$(mktemp -d)
python3 - "$tmp/g.asc" <<'PY'
import sys
import numpy as np
w, h = 64, 32
lon = (np.arange(w) + 0.5) / w * 360 - 180
lat = 90 - (np.arange(h) + 0.5) / h * 180
L, A = np.meshgrid(np.radians(lon), np.radians(lat))
z = 3000 * np.cos(A) * np.sin(2 * L) + 1000 * np.sin(3 * A) - 500
with open(sys.argv[1], "w") as f:
    f.write(f"ncols {w}\nnrows {h}\nxllcorner -180\nyllcorner -90\ncellsize 5.625\nNODATA_value -9999\n")
    for row in z:
        f.write(" ".join(f"{v:.1f}" for v in row) + "\n")
PY
gdal_translate -q -of GTiff -a_srs EPSG:4326 -ot Float32 "$tmp/g.asc" "$out/global-64x32.tif"
rm -rf "$tmp" "$out"/*.aux.xml
echo "wrote $out/global-64x32.tif"
