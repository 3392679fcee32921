//! Mosaics read as one sketch: a glob of tiles on one grid (`sketch.path = "tiles/*.hgt"`) and
//! GDAL's VRT mosaic (`gdalbuildvrt`), the two ways users hold SRTM and Copernicus downloads.
//!
//! Rules:
//! - Glob tiles are placed by their georeference: every tile must share the first one's cell
//!   size and units, and its nodes must fall on the first one's grid (within 1/1000 of a cell).
//!   Tiles may overlap (SRTM's share their edge rows); a later tile's valid cells win. Cells no
//!   tile covers are nodata, filled like any other.
//! - A VRT is read as GDAL reads it for the sources GDAL's own tools write: `SimpleSource` and
//!   `ComplexSource` of band 1, placed by `SrcRect` and `DstRect`, a source's `NODATA` skipped, its
//!   `ScaleOffset`/`ScaleRatio` applied, later sources over earlier ones. A source whose two rects
//!   differ in size would need resampling and is refused, as are other source kinds and pixel
//!   functions, by name. Sources are any sketch format, nested VRTs included (to a depth of 4).
//! - The mosaic's size is checked against the cell limit before it is allocated.

use super::RawGrid;
use super::georef::{Georef, Units};
use crate::error::{Error, Result, Role};
use std::path::{Path, PathBuf};

/// Nested VRTs deeper than this are refused (a VRT naming itself would recurse forever).
const MAX_DEPTH: usize = 4;
/// A VRT is XML of a few kilobytes per source; larger is not one we read.
const MAX_VRT_BYTES: u64 = 64 << 20;

/// Whether `path` is a glob pattern rather than a file name.
pub fn is_glob(path: &Path) -> bool {
    path.to_str()
        .is_some_and(|s| s.contains(['*', '?', '[']) && !path.exists())
}

/// The tiles a glob names, sorted so the result does not depend on the directory's order.
pub fn read_glob(pattern: &Path, read: impl Fn(&Path) -> Result<RawGrid>) -> Result<RawGrid> {
    let grids = list_glob(pattern)?
        .into_iter()
        .map(|t| read(&t).map(|g| (t, g)))
        .collect::<Result<Vec<_>>>()?;
    mosaic(pattern, &grids)
}

/// The files a glob names, sorted so the mosaic does not depend on the directory's order; at
/// least one.
pub fn list_glob(pattern: &Path) -> Result<Vec<PathBuf>> {
    let bad = |reason: String| Error::sketch(pattern, reason);
    let text = pattern
        .to_str()
        .ok_or_else(|| bad("pattern is not UTF-8".into()))?;
    let paths = glob::glob(text).map_err(|e| bad(format!("bad glob pattern: {e}")))?;
    let mut tiles: Vec<PathBuf> = paths
        .collect::<std::result::Result<_, _>>()
        .map_err(|e| bad(format!("cannot list the tiles: {e}")))?;
    tiles.sort();
    if tiles.is_empty() {
        return Err(bad("no file matches the pattern".into()));
    }
    Ok(tiles)
}

/// Where each tile of a glob mosaic lies on the first tile's grid: the rules of this module's
/// doc, told from the tiles' sizes and georeferences alone, so that `terrain tiles` can place
/// tiles it streams one at a time.
#[derive(Clone, Debug, PartialEq)]
pub struct Placement {
    pub width: usize,
    pub height: usize,
    /// Each tile's south-west node, in nodes from the mosaic's south-west node.
    pub offsets: Vec<(usize, usize)>,
    pub georef: Georef,
}

/// One tile as [`place`] sees it: its file, georeference and size.
pub struct TileExtent<'a> {
    pub path: &'a Path,
    pub georef: Option<Georef>,
    pub width: usize,
    pub height: usize,
}

/// Places georeferenced tiles on the first tile's grid (`pattern` names the mosaic in messages).
pub fn place(pattern: &Path, tiles: &[TileExtent]) -> Result<Placement> {
    let georef_of = |t: &TileExtent| -> Result<Georef> {
        t.georef.ok_or_else(|| {
            Error::sketch(
                t.path,
                "mosaic tile has no georeference (world file, GeoTIFF tags or a tile name)",
            )
        })
    };
    let Some(first) = tiles.first() else {
        return Err(Error::sketch(pattern, "no file matches the pattern"));
    };
    let base = georef_of(first)?;
    let (mut west, mut south) = (f64::INFINITY, f64::INFINITY);
    let (mut east, mut north) = (f64::NEG_INFINITY, f64::NEG_INFINITY);
    let mut nodes = Vec::with_capacity(tiles.len());
    let same = |a: f64, b: f64| (a - b).abs() <= 1e-9 * a.abs().max(b.abs());
    for t in tiles {
        let r = georef_of(t)?;
        if r.units != base.units || !same(r.cell_x, base.cell_x) || !same(r.cell_y, base.cell_y) {
            return Err(Error::sketch(
                t.path,
                format!(
                    "mosaic tile has cells of {} × {} {:?}; the first tile's are {} × {} {:?}",
                    r.cell_x, r.cell_y, r.units, base.cell_x, base.cell_y, base.units
                ),
            ));
        }
        let (fi, fj) = (
            (r.west - base.west) / base.cell_x,
            (r.south - base.south) / base.cell_y,
        );
        let (i, j) = (fi.round(), fj.round());
        if (fi - i).abs() > 1e-3 || (fj - j).abs() > 1e-3 || !(i.abs() < 1e9 && j.abs() < 1e9) {
            return Err(Error::sketch(
                t.path,
                "mosaic tile's nodes are off the first tile's grid",
            ));
        }
        nodes.push((i as i64, j as i64));
        west = west.min(i);
        south = south.min(j);
        east = east.max(i + t.width as f64 - 1.0);
        north = north.max(j + t.height as f64 - 1.0);
    }
    let (width, height) = RawGrid::check_size_unlimited(
        pattern,
        (east - west) as i64 + 1,
        (north - south) as i64 + 1,
    )?;
    let offsets = nodes
        .into_iter()
        .map(|(i, j)| ((i - west as i64) as usize, (j - south as i64) as usize))
        .collect();
    let georef = Georef {
        west: base.west + west * base.cell_x,
        south: base.south + south * base.cell_y,
        ..base
    };
    Ok(Placement {
        width,
        height,
        offsets,
        georef,
    })
}

/// Places georeferenced tiles on the first tile's grid.
fn mosaic(pattern: &Path, grids: &[(PathBuf, RawGrid)]) -> Result<RawGrid> {
    let extents: Vec<TileExtent> = grids
        .iter()
        .map(|(path, g)| TileExtent {
            path,
            georef: g.georef,
            width: g.width,
            height: g.height,
        })
        .collect();
    let placed = place(pattern, &extents)?;
    let (w, h) = RawGrid::check_size(pattern, placed.width as i64, placed.height as i64)?;
    let mut data = vec![f32::NAN; w * h];
    for ((_, g), &(x0, y0)) in grids.iter().zip(&placed.offsets) {
        for r in 0..g.height {
            let src = &g.data[r * g.width..(r + 1) * g.width];
            let dst = &mut data[(y0 + r) * w + x0..(y0 + r) * w + x0 + g.width];
            for (d, s) in dst.iter_mut().zip(src) {
                if s.is_finite() {
                    *d = *s;
                }
            }
        }
    }
    Ok(RawGrid::georeferenced(w, h, data, placed.georef))
}

/// Reads a GDAL VRT mosaic.
pub fn read_vrt(
    path: &Path,
    depth: usize,
    read: impl Fn(&Path, usize) -> Result<RawGrid>,
) -> Result<RawGrid> {
    let len = std::fs::metadata(path)
        .map_err(|e| Error::io(Role::Sketch, path, e))?
        .len();
    if len > MAX_VRT_BYTES {
        return Err(Error::sketch(
            path,
            format!("VRT is {len} bytes; larger than {MAX_VRT_BYTES} is not a mosaic"),
        ));
    }
    let bytes = std::fs::read(path).map_err(|e| Error::io(Role::Sketch, path, e))?;
    parse_vrt(path, &bytes, depth, read)
}

pub fn parse_vrt(
    path: &Path,
    bytes: &[u8],
    depth: usize,
    read: impl Fn(&Path, usize) -> Result<RawGrid>,
) -> Result<RawGrid> {
    let plan = vrt_plan(path, bytes, depth, true)?;
    let (w, h) = (plan.width, plan.height);
    let mut data = vec![f32::NAN; w * h];
    for source in &plan.sources {
        let src = read(&source.path, depth + 1)?;
        let (s, d) = source.rects(path, src.width, src.height)?;
        // Rows counted from the north in the VRT, from the south in our grids.
        for r in 0..s[3] {
            let (sy, dy) = (s[1] + r, d[1] + r);
            if !(0..src.height as i64).contains(&sy) || !(0..h as i64).contains(&dy) {
                continue;
            }
            let src_row = (src.height as i64 - 1 - sy) as usize * src.width;
            let dst_row = (h as i64 - 1 - dy) as usize * w;
            for c in 0..s[2] {
                let (sx, dx) = (s[0] + c, d[0] + c);
                if !(0..src.width as i64).contains(&sx) || !(0..w as i64).contains(&dx) {
                    continue;
                }
                if let Some(v) = source.value(src.data[src_row + sx as usize]) {
                    data[dst_row + dx as usize] = v;
                }
            }
        }
    }
    plan.band_nodata_to_nan(&mut data);
    Ok(RawGrid::new(w, h, data, plan.georef))
}

/// A VRT's band 1 as [`parse_vrt`] reads it, its sources not yet opened: what `terrain tiles`
/// needs to read a VRT band by band.
#[derive(Clone, Debug)]
pub struct VrtPlan {
    pub width: usize,
    pub height: usize,
    pub sources: Vec<VrtSource>,
    /// The band's `NoDataValue`, applied after the sources are placed.
    pub band_nodata: Option<f64>,
    pub georef: Option<Georef>,
}

/// One `SimpleSource` or `ComplexSource`.
#[derive(Clone, Debug)]
pub struct VrtSource {
    pub path: PathBuf,
    /// `SrcRect` and `DstRect` (xOff, yOff from the north, xSize, ySize); absent: the source's
    /// whole grid.
    src_rect: Option<[i64; 4]>,
    dst_rect: Option<[i64; 4]>,
    nodata: Option<f64>,
    scale: f64,
    offset: f64,
}

impl VrtSource {
    /// The source and destination rects for a source of `width` × `height`; refused where they
    /// differ in size (resampling).
    pub fn rects(&self, vrt: &Path, width: usize, height: usize) -> Result<([i64; 4], [i64; 4])> {
        let full = [0, 0, width as i64, height as i64];
        let (s, d) = (self.src_rect.unwrap_or(full), self.dst_rect.unwrap_or(full));
        if s[2] != d[2] || s[3] != d[3] {
            return Err(Error::sketch(
                vrt,
                format!(
                    "VRT source {} is resampled ({}×{} to {}×{}); only same-size sources are read",
                    self.path.display(),
                    s[2],
                    s[3],
                    d[2],
                    d[3]
                ),
            ));
        }
        Ok((s, d))
    }

    /// What a source's cell puts in the mosaic: nothing for its nodata or a non-finite cell, else
    /// the cell scaled and offset.
    pub fn value(&self, v: f32) -> Option<f32> {
        if !v.is_finite() || self.nodata.is_some_and(|nd| v as f64 == nd) {
            return None;
        }
        Some((v as f64 * self.scale + self.offset) as f32)
    }
}

impl VrtPlan {
    /// The band's nodata cells made NaN.
    pub fn band_nodata_to_nan(&self, data: &mut [f32]) {
        if let Some(nd) = self.band_nodata {
            for v in data {
                if *v as f64 == nd || *v == nd as f32 {
                    *v = f32::NAN;
                }
            }
        }
    }
}

/// Reads a VRT file's plan (its XML alone).
pub fn read_vrt_plan(path: &Path) -> Result<VrtPlan> {
    let len = std::fs::metadata(path)
        .map_err(|e| Error::io(Role::Sketch, path, e))?
        .len();
    if len > MAX_VRT_BYTES {
        return Err(Error::sketch(
            path,
            format!("VRT is {len} bytes; larger than {MAX_VRT_BYTES} is not a mosaic"),
        ));
    }
    let bytes = std::fs::read(path).map_err(|e| Error::io(Role::Sketch, path, e))?;
    vrt_plan(path, &bytes, 0, false)
}

/// Parses a VRT's XML: its size (within the cell limit when `whole`, else any up to 2^31 a
/// side), band 1's sources and its georeference.
fn vrt_plan(path: &Path, bytes: &[u8], depth: usize, whole: bool) -> Result<VrtPlan> {
    let bad = |reason: String| Error::sketch(path, format!("VRT {reason}"));
    if depth >= MAX_DEPTH {
        return Err(bad(format!("nests more than {MAX_DEPTH} deep")));
    }
    let text = std::str::from_utf8(bytes).map_err(|_| bad("is not UTF-8 text".into()))?;
    let doc = roxmltree::Document::parse(text).map_err(|e| bad(format!("is not XML: {e}")))?;
    let root = doc.root_element();
    if root.tag_name().name() != "VRTDataset" {
        return Err(bad(format!(
            "root is <{}>, not <VRTDataset>",
            root.tag_name().name()
        )));
    }
    let int_attr = |node: roxmltree::Node, name: &str| -> Result<i64> {
        let v = node
            .attribute(name)
            .ok_or_else(|| bad(format!("<{}> lacks {name}", node.tag_name().name())))?;
        // GDAL writes rects as integers, sometimes with a fractional zero.
        let f: f64 = v
            .parse()
            .map_err(|_| bad(format!("{name}=\"{v}\" is not a number")))?;
        if f.fract() != 0.0 || f.abs() > 1e12 {
            return Err(bad(format!("{name}=\"{v}\" is not a whole number")));
        }
        Ok(f as i64)
    };
    let (x, y) = (
        int_attr(root, "rasterXSize")?,
        int_attr(root, "rasterYSize")?,
    );
    let (w, h) = match whole {
        true => RawGrid::check_size(path, x, y)?,
        false => RawGrid::check_size_unlimited(path, x, y)?,
    };
    let number = |node: roxmltree::Node| -> Result<f64> {
        let t = node.text().unwrap_or("").trim();
        t.parse().map_err(|_| {
            bad(format!(
                "<{}> `{t}` is not a number",
                node.tag_name().name()
            ))
        })
    };
    let band = root
        .children()
        .filter(|c| c.has_tag_name("VRTRasterBand"))
        .find(|b| b.attribute("band").is_none_or(|n| n == "1"))
        .ok_or_else(|| bad("has no <VRTRasterBand band=\"1\">".into()))?;
    if band.attribute("subClass").is_some() {
        return Err(bad(format!(
            "band is a {}; pixel functions and derived bands are not read",
            band.attribute("subClass").unwrap_or_default()
        )));
    }
    let band_nodata = child(band, "NoDataValue").map(number).transpose()?;
    let dir = path.parent().unwrap_or(Path::new("."));
    let mut sources = Vec::new();
    for source in band.children().filter(|c| c.is_element()) {
        let kind = source.tag_name().name();
        match kind {
            "SimpleSource" | "ComplexSource" => {}
            "AveragedSource" | "KernelFilteredSource" => {
                return Err(bad(format!("<{kind}> would resample; it is not read")));
            }
            _ => continue,
        }
        let file = child(source, "SourceFilename")
            .and_then(|n| n.text().map(|t| (n, t.trim())))
            .ok_or_else(|| bad(format!("<{kind}> lacks <SourceFilename>")))?;
        let relative = file.0.attribute("relativeToVRT") == Some("1");
        let src_path = if relative {
            dir.join(file.1)
        } else {
            PathBuf::from(file.1)
        };
        if let Some(b) = child(source, "SourceBand") {
            let n = number(b)?;
            if n != 1.0 {
                return Err(bad(format!(
                    "source {} band {n}: only band 1 of a source is read",
                    src_path.display()
                )));
            }
        }
        let rect = |name: &str| -> Result<Option<[i64; 4]>> {
            child(source, name)
                .map(|n| {
                    Ok([
                        int_attr(n, "xOff")?,
                        int_attr(n, "yOff")?,
                        int_attr(n, "xSize")?,
                        int_attr(n, "ySize")?,
                    ])
                })
                .transpose()
        };
        sources.push(VrtSource {
            src_rect: rect("SrcRect")?,
            dst_rect: rect("DstRect")?,
            nodata: child(source, "NODATA").map(number).transpose()?,
            scale: child(source, "ScaleRatio")
                .map(number)
                .transpose()?
                .unwrap_or(1.0),
            offset: child(source, "ScaleOffset")
                .map(number)
                .transpose()?
                .unwrap_or(0.0),
            path: src_path,
        });
    }
    let srs = child(root, "SRS").and_then(|n| n.text());
    let units = srs.map_or(Units::Unknown, wkt_units);
    let gt = child(root, "GeoTransform")
        .and_then(|n| n.text())
        .map(|t| {
            t.split(',')
                .map(|v| v.trim().parse::<f64>())
                .collect::<std::result::Result<Vec<f64>, _>>()
        })
        .transpose()
        .map_err(|_| bad("<GeoTransform> is not six numbers".into()))?;
    let georef = match gt {
        Some(gt) => {
            let gt: [f64; 6] = gt
                .try_into()
                .map_err(|_| bad("<GeoTransform> is not six numbers".into()))?;
            let g = Georef::from_geotransform(gt, h, units)
                .ok_or_else(|| bad("<GeoTransform> is rotated or not north-up".into()))?;
            Some(Georef {
                epsg: srs.and_then(super::georef::wkt_epsg),
                ..g
            })
        }
        None => None,
    };
    Ok(VrtPlan {
        width: w,
        height: h,
        sources,
        band_nodata,
        georef,
    })
}

/// The first child element of `node` named `name`.
fn child<'a, 'i>(node: roxmltree::Node<'a, 'i>, name: &str) -> Option<roxmltree::Node<'a, 'i>> {
    node.children().find(|c| c.has_tag_name(name))
}

/// Units of a WKT coordinate system: geographic, or the projected one's linear unit.
fn wkt_units(wkt: &str) -> Units {
    let t = wkt.trim_start().to_ascii_uppercase();
    if t.starts_with("GEOGCS") || t.starts_with("GEOGCRS") || t.starts_with("GEODCRS") {
        return Units::Degrees;
    }
    // The projected system's own unit is its last UNIT/LENGTHUNIT (the datum's come first).
    let last = t.rfind("UNIT[").map(|k| &t[k..]).unwrap_or("");
    if last.contains("US SURVEY FOOT") || last.contains("FOOT_US") {
        Units::Linear(super::georef::US_SURVEY_FOOT_M)
    } else if last.contains("FOOT") || last.contains("FEET") {
        Units::Linear(super::georef::FOOT_M)
    } else {
        Units::Linear(1.0)
    }
}
