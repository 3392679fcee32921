#!/usr/bin/env bash
# Writes tests/data/planet/global-64x32.tif: a 64 × 32 global grid (5.625° cells, EPSG:4326,
# Float32, north row first as GDAL writes it) of h = 3000·cos(lat)·sin(2·lon) + 1000·sin(3·lat)
# − 500 at the cells' centres, for tests/planet.rs; and global-1024x512.tif, the same plus
# 400·sin(40·lon)·sin(37·lat) (relief that only the finest levels hold), Int16 and DEFLATE, for a
# planet streamed from a tile pyramid of several tiles a level (tests/tiles.rs). Needs GDAL
# (Debian's gdal-bin) and numpy.
set -euo pipefail
cd "$(dirname "$0")/.."
out=tests/data/planet
mkdir -p "$out"
tmp=$(mktemp -d)
for size in 64x32 1024x512; do
python3 - "$tmp/g.asc" "$size" <<'PY'
import sys
import numpy as np
w, h = (int(v) for v in sys.argv[2].split("x"))
lon = (np.arange(w) + 0.5) / w * 360 - 180
lat = 90 - (np.arange(h) + 0.5) / h * 180
L, A = np.meshgrid(np.radians(lon), np.radians(lat))
z = 3000 * np.cos(A) * np.sin(2 * L) + 1000 * np.sin(3 * A) - 500
if w > 64:
    z += 400 * np.sin(40 * L) * np.sin(37 * A)
with open(sys.argv[1], "w") as f:
    f.write(f"ncols {w}\nnrows {h}\nxllcorner -180\nyllcorner -90\ncellsize {360 / w}\nNODATA_value -9999\n")
    for row in z:
        f.write(" ".join(f"{v:.1f}" for v in row) + "\n")
PY
if [ "$size" = 64x32 ]; then
  gdal_translate -q -of GTiff -a_srs EPSG:4326 -ot Float32 "$tmp/g.asc" "$out/global-$size.tif"
else
  gdal_translate -q -of GTiff -a_srs EPSG:4326 -ot Int16 -co COMPRESS=DEFLATE -co PREDICTOR=2 \
    "$tmp/g.asc" "$out/global-$size.tif"
fi
echo "wrote $out/global-$size.tif"
done
rm -rf "$tmp" "$out"/*.aux.xml
