#!/usr/bin/env bash
# Writes the sketch-format fixtures in tests/data/formats/ with GDAL (Debian's gdal-bin, 3.6), and
# tests/data/formats/gdal.json: what GDAL reports for each file (size, geotransform, nodata,
# statistics, sample values). The files are committed; run this again only to change them.
#
#   sudo apt-get install gdal-bin && scripts/make-format-fixtures.sh
#
# The source is a 37 × 29 crop of the bundled Jacksboro DEM with three cells set to nodata: odd
# sizes, so strips and tiles end part-filled.
set -euo pipefail
cd "$(dirname "$0")/.."
out=tests/data/formats
rm -rf "$out" && mkdir -p "$out"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
gdal_version=$(gdalinfo --version)

python3 - "$tmp/src.asc" <<'PY'
import sys
lines = open("sketches/jacksboro_fault_dem.asc").read().split("\n")
head = {l.split()[0].lower(): float(l.split()[1]) for l in lines[:6]}
rows = [l.split() for l in lines[6:] if l.strip()]
r0, c0, h, w = 100, 200, 29, 37
cell = head["cellsize"]
nrows = int(head["nrows"])
grid = [row[c0:c0 + w] for row in rows[r0:r0 + h]]
for (r, c) in [(3, 4), (17, 30), (28, 0)]:
    grid[r][c] = "-32768"
with open(sys.argv[1], "w") as f:
    f.write(f"ncols {w}\nnrows {h}\n")
    f.write(f"xllcorner {head['xllcorner'] + c0 * cell:.10f}\n")
    f.write(f"yllcorner {head['yllcorner'] + (nrows - r0 - h) * cell:.10f}\n")
    f.write(f"cellsize {cell}\nNODATA_value -32768\n")
    for row in grid:
        f.write(" ".join(row) + "\n")
PY
src="$tmp/src.asc"
t() { gdal_translate -q "$@"; }

# One source per sample type, nodata kept where the type can hold it.
t -a_srs EPSG:4326 -ot Int16 "$src" "$tmp/Int16.tif"
t -ot Byte -scale 300 1000 1 250 -a_nodata 0 "$tmp/Int16.tif" "$tmp/Byte.tif"
# GDAL 3.6 has no Int8 type: it writes signed bytes from Byte values, so 128–255 read as −128…−1.
t -ot Byte -scale 300 1000 60 200 -a_nodata 0 -co PIXELTYPE=SIGNEDBYTE "$tmp/Int16.tif" "$tmp/Int8.tif"
t -ot UInt16 -scale 300 1000 1000 65000 -a_nodata 0 "$tmp/Int16.tif" "$tmp/UInt16.tif"
t -ot UInt32 -scale 300 1000 100000 4000000000 -a_nodata 0 "$tmp/Int16.tif" "$tmp/UInt32.tif"
t -ot Int32 -scale 300 1000 -2000000000 2000000000 -a_nodata -2147483648 "$tmp/Int16.tif" "$tmp/Int32.tif"
t -ot UInt64 -scale 300 1000 100000 9000000000000 -a_nodata 0 "$tmp/Int16.tif" "$tmp/UInt64.tif"
t -ot Int64 -scale 300 1000 -9000000000000 9000000000000 -a_nodata -9999 "$tmp/Int16.tif" "$tmp/Int64.tif"
t -ot Float32 -scale 300 1000 300.25 1000.75 -a_nodata -9999 "$tmp/Int16.tif" "$tmp/Float32.tif"
t -ot Float64 -scale 300 1000 300.125 1000.5 -a_nodata -9999 "$tmp/Int16.tif" "$tmp/Float64.tif"
types="Byte Int8 UInt16 Int16 UInt32 Int32 UInt64 Int64 Float32 Float64"

pred() { case $1 in Float*) echo 3 ;; *) echo 2 ;; esac; }
signed() { [ "$1" = Int8 ] && echo "-co PIXELTYPE=SIGNEDBYTE" || true; }
for ty in $types; do
  s="$tmp/$ty.tif"; p=$(pred "$ty"); sg=$(signed "$ty")
  t $sg -co COMPRESS=NONE "$s" "$out/strip-none-$ty.tif"
  t $sg -co COMPRESS=NONE -co BLOCKYSIZE=5 "$s" "$out/strip5-none-$ty.tif"
  t $sg -co COMPRESS=LZW -co PREDICTOR=$p -co BLOCKYSIZE=7 "$s" "$out/strip7-lzw-pred$p-$ty.tif"
  t $sg -co COMPRESS=LZW -co TILED=YES -co BLOCKXSIZE=32 -co BLOCKYSIZE=32 "$s" "$out/tile32-lzw-$ty.tif"
  t $sg -co COMPRESS=LZW -co PREDICTOR=$p -co TILED=YES -co BLOCKXSIZE=32 -co BLOCKYSIZE=32 "$s" "$out/tile32-lzw-pred$p-$ty.tif"
  t $sg -co COMPRESS=DEFLATE -co PREDICTOR=$p -co TILED=YES -co BLOCKXSIZE=16 -co BLOCKYSIZE=16 "$s" "$out/tile16-deflate-pred$p-$ty.tif"
  t $sg -co COMPRESS=ZSTD -co PREDICTOR=$p "$s" "$out/strip-zstd-pred$p-$ty.tif"
  t $sg -co COMPRESS=PACKBITS "$s" "$out/strip-packbits-$ty.tif"
  # GDAL 3.6 reads its own big-endian files with predictor 3 back as garbage (gdal_translate to
  # AAIGrid shows values of 1e-140 to 1e229), so big-endian floats go without a predictor.
  bp=$p; [ "$p" = 3 ] && bp=1
  t $sg -co COMPRESS=LZW -co PREDICTOR=$bp -co ENDIANNESS=BIG "$s" "$out/bigendian-lzw-pred$bp-$ty.tif"
  t $sg -co BIGTIFF=YES -co COMPRESS=ZSTD -co TILED=YES -co BLOCKXSIZE=16 -co BLOCKYSIZE=16 "$s" "$out/bigtiff-tile16-zstd-$ty.tif"
done
# LZW tiles narrower than their tile width whose stream ends on the last row's padding: tiff 0.11.3
# failed these with "no lzw end code found" (fixed in vendor/tiff, patches/tiff-0.11.3.patch).
for ty in Int16 Float64; do
  t -a_srs EPSG:4326 -srcwin 0 0 51 40 -ot $ty -co COMPRESS=LZW -co TILED=YES -co BLOCKXSIZE=32 \
    -co BLOCKYSIZE=32 sketches/jacksboro_fault_dem.asc "$out/narrow-tiles-lzw-${ty,,}.tif"
done
# Cloud-optimised: tiles and overviews, the full resolution read.
t -of COG -co BLOCKSIZE=16 -co COMPRESS=DEFLATE -co OVERVIEWS=FORCE_USE_EXISTING "$tmp/Int16.tif" "$out/cog-Int16.tif" 2>/dev/null \
  || t -of COG -co BLOCKSIZE=16 -co COMPRESS=DEFLATE "$tmp/Int16.tif" "$out/cog-Int16.tif"
t -of COG -co BLOCKSIZE=16 -co COMPRESS=LZW -co PREDICTOR=YES "$tmp/Float32.tif" "$out/cog-Float32.tif"
# Refused by name.
t -co COMPRESS=JPEG "$tmp/Byte.tif" "$out/refused-jpeg-Byte.tif"
t -co COMPRESS=LERC "$tmp/Float32.tif" "$out/refused-lerc-Float32.tif"
# Coordinate systems and registration: projected in metres, projected in US survey feet,
# pixel-is-point.
gdalwarp -q -t_srs EPSG:32616 -tr 80 80 -r near -ot Float32 "$tmp/Int16.tif" "$out/utm-metres-Float32.tif"
gdalwarp -q -t_srs EPSG:2274 -tr 250 250 -r near -ot Float32 "$tmp/Int16.tif" "$out/stateplane-feet-Float32.tif"
t -mo AREA_OR_POINT=Point "$tmp/Int16.tif" "$out/point-Int16.tif"

# Mosaics: the Int16 source cut into four uneven tiles, as a VRT and as a glob.
mkdir -p "$out/tiles"
t -srcwin 0 0 20 12 "$tmp/Int16.tif" "$out/tiles/t-nw.tif"
t -srcwin 20 0 17 12 -co COMPRESS=LZW "$tmp/Int16.tif" "$out/tiles/t-ne.tif"
t -srcwin 0 12 20 17 -co COMPRESS=DEFLATE "$tmp/Int16.tif" "$out/tiles/t-sw.tif"
t -srcwin 20 12 17 17 -co TILED=YES -co BLOCKXSIZE=16 -co BLOCKYSIZE=16 "$tmp/Int16.tif" "$out/tiles/t-se.tif"
(cd "$out" && gdalbuildvrt -q mosaic.vrt tiles/t-*.tif)

# The other formats.
t -of AAIGrid "$tmp/Int16.tif" "$out/grid.asc"
t -of XYZ -co ADD_HEADER_LINE=YES "$tmp/Float32.tif" "$out/grid.xyz"
t -of PNG -ot UInt16 -co WORLDFILE=YES "$tmp/UInt16.tif" "$out/grid.png"
[ -f "$out/grid.wld" ] && mv "$out/grid.wld" "$out/grid.pgw"
rm -f "$out"/*.aux.xml "$out"/*.prj
# SRTM 3″: a 1201² tile named for its south-west corner, zipped as USGS ships them.
t -of SRTMHGT -r bilinear -outsize 1201 1201 -a_ullr -84 37 -83 36 "$tmp/Int16.tif" "$tmp/N36W084.hgt"
# A fixed timestamp, so the zip is the same bytes every time.
(cd "$tmp" && python3 -c "
import zipfile
info = zipfile.ZipInfo('N36W084.hgt', date_time=(2000, 1, 1, 0, 0, 0))
info.compress_type = zipfile.ZIP_DEFLATED
with zipfile.ZipFile('N36W084.hgt.zip', 'w') as z:
    z.writestr(info, open('N36W084.hgt', 'rb').read())
")
cp "$tmp/N36W084.hgt.zip" "$out/"
cp "$tmp/N36W084.hgt" "$tmp/hgt-copy.hgt"

# What GDAL reports for each file.
python3 - "$out" "$gdal_version" "$tmp/N36W084.hgt" <<'PY'
import json, os, subprocess, sys
out, version, hgt = sys.argv[1], sys.argv[2], sys.argv[3]
files = sorted(f for f in os.listdir(out) if f.endswith((".tif", ".vrt", ".asc", ".xyz", ".png", ".zip")))
report = {"gdal": version, "files": {}}
for f in files:
    path = hgt if f.endswith(".hgt.zip") else os.path.join(out, f)
    if f.endswith(".vrt"):
        # gdalinfo -stats on a VRT combines its sources' statistics (and writes them into the
        # VRT): read its pixels into a plain GeoTIFF instead.
        subprocess.run(["gdal_translate", "-q", path, "/tmp/vrt-pixels.tif"], check=True)
        path = "/tmp/vrt-pixels.tif"
    try:
        info = json.loads(subprocess.run(["gdalinfo", "-json", "-stats", path], capture_output=True, check=True, text=True).stdout)
    except subprocess.CalledProcessError as e:
        report["files"][f] = {"gdal_error": e.stderr.strip().splitlines()[-1] if e.stderr.strip() else "failed"}
        continue
    band = info["bands"][0]
    w, h = info["size"]
    samples = []
    for (x, y) in [(0, 0), (w - 1, h - 1), (w // 2, h // 3), (4, 3), (30, 17), (0, h - 1)]:
        if x >= w or y >= h:
            continue
        v = subprocess.run(["gdallocationinfo", "-valonly", path, str(x), str(y)], capture_output=True, text=True).stdout.strip()
        samples.append([x, y, float(v)])
    md = band.get("metadata", {}).get("", {})
    report["files"][f] = {
        "size": [w, h],
        "type": band["type"],
        "geotransform": info.get("geoTransform"),
        "area_or_point": info.get("metadata", {}).get("", {}).get("AREA_OR_POINT"),
        "nodata": band.get("noDataValue"),
        "min": float(md["STATISTICS_MINIMUM"]),
        "max": float(md["STATISTICS_MAXIMUM"]),
        "mean": float(md["STATISTICS_MEAN"]),
        "valid_percent": float(md.get("STATISTICS_VALID_PERCENT", 100)),
        "samples_col_row_from_north": samples,
    }
    if "coordinateSystem" in info:
        wkt = info["coordinateSystem"]["wkt"]
        report["files"][f]["crs"] = "geographic" if wkt.startswith("GEOGCRS") else ("feet" if "foot" in wkt.split("LENGTHUNIT")[-1] else "metres")
json.dump(report, open(os.path.join(out, "gdal.json"), "w"), indent=1, sort_keys=True)
PY
rm -f "$out"/*.aux.xml "$out"/tiles/*.aux.xml
echo "wrote $(ls "$out" | wc -l) files in $out"
