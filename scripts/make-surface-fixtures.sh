#!/usr/bin/env bash
# Writes the surface and relief fixtures in tests/data/surface/ with GDAL (Debian's gdal-bin):
#
# - coast-4326.tif: a coast with bathymetry, EPSG:4326, 120 × 91 cells of 1/30°, heights
#   −1437…2205 m (Vancouver Island and the Strait of Georgia: matplotlib's `topobathy.npz`
#   sample, fetched from the matplotlib wheel on PyPI); coast-plain.tif: the same heights in a
#   TIFF without any georeference.
# - jacksboro-utm.tif: the bundled Jacksboro DEM warped to UTM 17N (EPSG:32617), 120 m cells.
# - ramp.txt: gdaldem's documented example ramp at the DEM's heights; jacksboro-ramp.tif:
#   `gdaldem color-relief` of jacksboro-utm.tif with it, on the DEM's own grid.
# - ortho-4326.tif: that image warped to EPSG:4326 (RGBA), and ortho-west.png/.pgw: its west
#   half as a PNG with a world file, for imagery draped over jacksboro-utm.tif.
# - ortho.jpg/.jgw: jacksboro-ramp.tif as a JPEG with a world file.
# - ortho-fine.tif: the middle 4,096 m of jacksboro-ramp.tif at 4 m pixels (1024², bilinear),
#   tiled 256² with DEFLATE: finer than a drape over the whole DEM can hold, for image pyramids.
#
# The files are committed; run this again only to change them:
#
#   sudo apt-get install gdal-bin && scripts/make-surface-fixtures.sh
set -euo pipefail
export GDAL_PAM_ENABLED=NO
cd "$(dirname "$0")/.."
out=tests/data/surface
rm -rf "$out" && mkdir -p "$out"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

python3 -m pip download -q --no-deps --only-binary=:all: -d "$tmp" matplotlib==3.11.2
python3 - "$tmp" <<'PY'
import glob, io, sys, zipfile
tmp = sys.argv[1]
wheel = zipfile.ZipFile(glob.glob(f"{tmp}/matplotlib-*.whl")[0])
data = wheel.read("matplotlib/mpl-data/sample_data/topobathy.npz")
# The .npz is a zip of .npy arrays: read them without numpy.
arrays = {}
with zipfile.ZipFile(io.BytesIO(data)) as z:
    for name in z.namelist():
        raw = z.read(name)
        header_len = int.from_bytes(raw[8:10], "little")
        header = raw[10:10 + header_len].decode()
        shape = tuple(int(v) for v in header.split("'shape': (")[1].split(")")[0].split(",") if v.strip())
        import array
        a = array.array("f")
        a.frombytes(raw[10 + header_len:])
        arrays[name[:-4]] = (shape, a)
(rows, cols), topo = arrays["topo"]
lon = arrays["longitude"][1]
lat = arrays["latitude"][1]
cell = (lon[-1] - lon[0]) / (cols - 1)
# Node-registered in the sample; as an ESRI grid of cells centred on the nodes.
west = lon[0] - 360.0 - cell / 2
south = lat[0] - cell / 2
north_first = lat[0] > lat[-1]
with open(f"{tmp}/coast.asc", "w") as f:
    f.write(f"ncols {cols}\nnrows {rows}\nxllcorner {west:.10f}\nyllcorner {min(lat[0], lat[-1]) - cell / 2:.10f}\n")
    f.write(f"cellsize {cell:.10f}\n")
    order = range(rows) if north_first else range(rows - 1, -1, -1)
    for r in order:
        f.write(" ".join(f"{topo[r * cols + c]:.1f}" for c in range(cols)) + "\n")
PY
gdal_translate -q -of GTiff -a_srs EPSG:4326 -ot Float32 "$tmp/coast.asc" "$out/coast-4326.tif"
gdal_translate -q -of GTiff -ot Float32 -co PROFILE=BASELINE "$tmp/coast.asc" "$out/coast-plain.tif"

gdal_translate -q -a_srs EPSG:4326 sketches/jacksboro_fault_dem.asc "$tmp/jacksboro.tif"
gdalwarp -q -t_srs EPSG:32617 -tr 120 120 -r bilinear -ot Float32 "$tmp/jacksboro.tif" "$out/jacksboro-utm.tif"

cat > "$out/ramp.txt" <<'RAMP'
# gdaldem's documented example ramp, its heights scaled to the DEM's 248-1069 m: metres, a
# percentage, a colour name, and each kind of separator.
1000 white
900 235:220:175
50%	190 185 135
400,240,250,150
250 50 180 50
nv 0 0 0 0
RAMP
gdaldem color-relief -q "$out/jacksboro-utm.tif" "$out/ramp.txt" "$out/jacksboro-ramp.tif"
# An orthophoto stand-in in another coordinate system than the DEM: gdaldem's image of the DEM
# (with -alpha, its nodata transparent) warped to EPSG:4326, an RGBA GeoTIFF whose alpha is 0
# beyond the DEM's data; and a PNG of it
# with a world file (no coordinate system: read in the sketch's own), clipped to the DEM's west
# half so that the procedural surface shows east of it.
gdaldem color-relief -q -alpha "$out/jacksboro-utm.tif" "$out/ramp.txt" "$tmp/ramp-alpha.tif"
gdalwarp -q -t_srs EPSG:4326 -dstalpha -r bilinear -co COMPRESS=DEFLATE "$tmp/ramp-alpha.tif" "$out/ortho-4326.tif"
gdal_translate -q -of PNG -srcwin 0 0 130 273 "$out/jacksboro-ramp.tif" "$out/ortho-west.png"
gdal_translate -q -of GTiff -srcwin 0 0 130 273 "$out/jacksboro-ramp.tif" "$tmp/west.tif"
python3 - "$tmp/west.tif" "$out/ortho-west.pgw" <<'PY'
import subprocess, sys, json
info = json.loads(subprocess.check_output(["gdalinfo", "-json", sys.argv[1]]))
x0, dx, _, y0, _, dy = info["geoTransform"]
with open(sys.argv[2], "w") as f:
    f.write(f"{dx}\n0\n0\n{dy}\n{x0 + dx / 2}\n{y0 + dy / 2}\n")
PY
# The same image with no georeference at all, which cannot be placed.
gdal_translate -q -of GTiff -co PROFILE=BASELINE -outsize 64 64 "$out/jacksboro-ramp.tif" "$out/ortho-plain.tif"
# The JPEG driver writes its world file as .wld; .jgw is the name most orthophotos come with.
gdal_translate -q -of JPEG -co WORLDFILE=YES -co QUALITY=90 "$out/jacksboro-ramp.tif" "$out/ortho.jpg"
mv "$out/ortho.wld" "$out/ortho.jgw"
gdal_translate -q -projwin 207567 4056348 211663 4052252 -outsize 1024 1024 -r bilinear \
  -co TILED=YES -co COMPRESS=DEFLATE -co PREDICTOR=2 "$out/jacksboro-ramp.tif" "$out/ortho-fine.tif"
rm -f "$out"/*.aux.xml
gdalinfo --version > "$out/GDAL_VERSION"
