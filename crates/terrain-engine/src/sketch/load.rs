//! Reading a sketch: what the scene says of a file ([`LoadOptions`]), the grid a reader makes
//! ([`RawGrid`]), the dispatch by format, and the atlas made of it (scale, nodata fill, pyramid).
//!
//! Rule: the file's name alone picks its reader ([`Format::of`], the one place that knows the
//! extensions); guesses the library takes on trust come back as [`warnings`] after a read succeeds, never
//! printed.

use super::georef::Georef;
pub use super::grid::{Extent, LoadOptions, RawGrid, limit_cells, max_cells};
use super::{
    Atlas, Level, MAX_HEIGHT_M, asc, build_pyramid, fill, geotiff, hgt, mosaic, png, synthetic, xyz,
};
use crate::error::{Error, Result};
use glam::DVec2;
use std::path::Path;

/// Reads a sketch file, or a glob of tiles, as the grid its format holds: the scene's overrides,
/// the nodata fill and the pyramid come after ([`Atlas::from_raw`]).
pub fn read_grid(path: &Path, opts: &LoadOptions) -> Result<RawGrid> {
    read_at_depth(path, opts, 0)
}

/// A sketch file's format, told by its name: the one place that knows the extensions.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Format {
    Asc,
    Hgt,
    HgtZip,
    Png,
    Tiff,
    Vrt,
    Xyz,
}

impl Format {
    fn of(path: &Path) -> Result<Format> {
        let name = path
            .file_name()
            .and_then(|n| n.to_str())
            .map(|n| n.to_ascii_lowercase())
            .unwrap_or_default();
        if name.ends_with(".hgt.zip") {
            return Ok(Format::HgtZip);
        }
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(|e| e.to_ascii_lowercase())
            .unwrap_or_default();
        let why = match ext.as_str() {
            "asc" | "grd" => return Ok(Format::Asc),
            "hgt" => return Ok(Format::Hgt),
            "png" => return Ok(Format::Png),
            "tif" | "tiff" => return Ok(Format::Tiff),
            "vrt" => return Ok(Format::Vrt),
            "xyz" | "csv" | "txt" => return Ok(Format::Xyz),
            "toml" => "a scene file, not a height map: give it to `terrain render`".to_string(),
            "" if path.is_dir() => {
                "is a folder without pyramid.toml, not a tile pyramid (`terrain tiles` writes one)"
                    .to_string()
            }
            "" => "no extension to tell its format".to_string(),
            other => format!("unknown sketch format `.{other}`"),
        };
        Err(Error::sketch(path, format!("{why}; a sketch is {FORMATS}")))
    }
}

/// `depth`: how many mosaics enclose this file (a VRT may name VRTs).
fn read_at_depth(path: &Path, opts: &LoadOptions, depth: usize) -> Result<RawGrid> {
    if crate::sketch::tiles::is_pyramid(path) {
        return crate::sketch::tiles::read::raw_grid(path, opts);
    }
    if mosaic::is_glob(path) {
        return mosaic::read_glob(path, |tile| read_at_depth(tile, opts, depth + 1));
    }
    let spacing_given = opts.spacing_m.is_some();
    match Format::of(path)? {
        Format::Asc => asc::read(path),
        Format::Hgt => hgt::read_file(path, spacing_given),
        Format::HgtZip => hgt::read_zip_file(path, spacing_given),
        Format::Png => png::read_file(path, opts),
        Format::Tiff => geotiff::read_file(path),
        Format::Vrt => mosaic::read_vrt(path, depth, |src, d| read_at_depth(src, opts, d)),
        Format::Xyz => xyz::read(path),
    }
}

/// A relief more than this many times the sketch's horizontal extent is no landscape's (the
/// steepest mountains rise about their own width): a unit mistaken, most likely.
const TALL_RELIEF: f64 = 3.0;

/// What a successful read of the sketch at `path` with `opts` took on trust where neither the
/// file nor the options say, one line each for the program to show (the library prints
/// nothing): the cell size of a file without a georeference (1 m), a PNG's height units, or,
/// where nothing was guessed, a relief too tall for the sketch's extent. One cause is said
/// once: a guessed unit explains the tall relief it makes, so the relief is not said again.
/// Called after the read, never before: a file that fails to read gets its error alone.
pub fn warnings(path: &Path, opts: &LoadOptions, extent: &Extent) -> Vec<String> {
    match guessed_units(path, opts, extent.georeferenced) {
        Some(line) => vec![line],
        None => tall_relief(path, extent).into_iter().collect(),
    }
}

/// The line for the units a read guessed, if it guessed any.
fn guessed_units(path: &Path, opts: &LoadOptions, georeferenced: bool) -> Option<String> {
    // A pyramid records the spacing it was converted with; `terrain tiles` warned then.
    if crate::sketch::tiles::is_pyramid(path) {
        return None;
    }
    let spaced = georeferenced || opts.spacing_m.is_some();
    if !mosaic::is_glob(path) && matches!(Format::of(path), Ok(Format::Png)) {
        return png::units_warning(path, opts, spaced);
    }
    (!spaced).then(|| {
        format!(
            "sketch {}: the file has no georeference, so its cells are taken as 1 m; \
             sketch.spacing_m gives their size",
            path.display()
        )
    })
}

/// The line for a relief more than [`TALL_RELIEF`] times the sketch's larger side.
fn tall_relief(path: &Path, e: &Extent) -> Option<String> {
    let side = ((e.width.max(1) - 1) as f64 * e.dx).max((e.height.max(1) - 1) as f64 * e.dy);
    let relief = e.max_m - e.min_m;
    if !(side > 0.0 && relief > TALL_RELIEF * side) {
        return None;
    }
    Some(format!(
        "sketch {}: its relief ({relief:.0} m) is {:.0} times its extent ({side:.0} m): cells in \
         degrees or heights in feet read as metres? sketch.spacing_m gives the cells' size in \
         metres, sketch.height_scale the heights' unit",
        path.display(),
        relief / side
    ))
}

/// Parses a sketch held in memory, the format told by `name`'s extension, as [`read_grid`] would
/// read the file (a VRT's sources and a PNG's world file are still read from disk, beside
/// `name`). For the fuzz harness and for callers that hold the bytes already.
pub fn parse_grid(name: &Path, bytes: &[u8], opts: &LoadOptions) -> Result<RawGrid> {
    let spacing_given = opts.spacing_m.is_some();
    match Format::of(name)? {
        Format::Asc => asc::parse_bytes(name, bytes),
        Format::Hgt => hgt::parse(name, bytes, spacing_given),
        Format::HgtZip => hgt::parse_zip(name, std::io::Cursor::new(bytes), spacing_given),
        Format::Png => png::parse(name, bytes, opts, None),
        Format::Tiff => geotiff::read(name, std::io::Cursor::new(bytes)),
        Format::Vrt => mosaic::parse_vrt(name, bytes, 0, |src, d| read_at_depth(src, opts, d)),
        Format::Xyz => xyz::parse_bytes(name, bytes),
    }
}

/// Sketch files above this size report their reading as progress (about 2 s for an ASCII grid).
const LARGE_FILE_BYTES: u64 = 64 << 20;

/// The sketch formats by extension, for messages.
const FORMATS: &str = ".asc/.grd (ESRI ASCII), .hgt/.hgt.zip (SRTM), .png (with a .pgw world file), \
     .tif/.tiff (GeoTIFF), .vrt (GDAL mosaic), .xyz/.csv/.txt, a glob of tiles (tiles/*.hgt), \
     or a tile pyramid's folder (`terrain tiles`)";

impl Atlas {
    /// What reading this sketch found, for [`warnings`].
    pub fn extent(&self) -> Extent {
        Extent {
            width: self.width(),
            height: self.height(),
            dx: self.dx,
            dy: self.dy,
            min_m: self.min_m as f64,
            max_m: self.max_m as f64,
            georeferenced: self.georef.is_some(),
        }
    }

    /// Reads a sketch file, choosing the reader by its extension.
    pub fn load(path: &Path, opts: &LoadOptions) -> Result<Atlas> {
        // A large sketch takes seconds to parse and fill: say so while it does.
        let step = std::fs::metadata(path)
            .is_ok_and(|m| m.len() > LARGE_FILE_BYTES)
            .then(|| crate::progress::start(&format!("reading sketch {}", path.display()), None));
        let atlas = Atlas::load_quietly(path, opts);
        if let Some(s) = step {
            s.finish();
        }
        atlas
    }

    fn load_quietly(path: &Path, opts: &LoadOptions) -> Result<Atlas> {
        if crate::sketch::tiles::is_pyramid(path) {
            return super::streamed::streamed_atlas(path, opts);
        }
        let raw = read_grid(path, opts)?;
        Atlas::from_raw(raw, opts).map_err(|e| match e {
            Error::Value { reason, .. } => Error::sketch(path, reason),
            e => e,
        })
    }

    /// Reads a sketch held in memory (a browser's fetch, an archive's entry), the format told by
    /// `name`'s extension, as [`Atlas::load`] reads the file: no file system is touched but for
    /// a VRT's sources and a PNG's world file beside `name`.
    ///
    /// ```
    /// use terrain::sketch::{Atlas, LoadOptions};
    ///
    /// let grid = b"ncols 3\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 30\n1 2 3\n4 5 6\n";
    /// let atlas = Atlas::from_bytes("hills.asc".as_ref(), grid, &LoadOptions::default())?;
    /// assert_eq!((atlas.width(), atlas.height(), atlas.dx), (3, 2, 30.0));
    /// # Ok::<(), terrain::Error>(())
    /// ```
    pub fn from_bytes(name: &Path, bytes: &[u8], opts: &LoadOptions) -> Result<Atlas> {
        let raw = parse_grid(name, bytes, opts)?;
        Atlas::from_raw(raw, opts).map_err(|e| match e {
            Error::Value { reason, .. } => Error::sketch(name, reason),
            e => e,
        })
    }

    /// The atlas of a grid a reader (or a program) made: fills nodata, applies the scene's
    /// overrides and builds the pyramid.
    pub fn from_raw(mut raw: RawGrid, opts: &LoadOptions) -> Result<Atlas> {
        if let Some(s) = opts.spacing_m {
            raw.dx = s;
            raw.dy = s;
        }
        if !(raw.dx.is_finite() && raw.dy.is_finite() && raw.dx > 0.0 && raw.dy > 0.0) {
            return Err(Error::value(
                "sketch.spacing_m",
                format!(
                    "grid spacing {} × {} m is not positive and finite",
                    raw.dx, raw.dy
                ),
            ));
        }
        scale_heights(&mut raw.data, opts)?;
        let nodata = fill::fill_nodata(&mut raw.data, raw.width, raw.height);
        let mut min_m = f32::INFINITY;
        let mut max_m = f32::NEG_INFINITY;
        for &h in &raw.data {
            min_m = min_m.min(h);
            max_m = max_m.max(h);
        }
        let base = Level {
            width: raw.width,
            height: raw.height,
            data: raw.data,
        };
        let edge_mean_m = base.edge_mean();
        Ok(Atlas {
            dx: raw.dx,
            dy: raw.dy,
            origin: opts.origin_m.unwrap_or(DVec2::ZERO),
            nodata,
            min_m,
            max_m,
            edge_mean_m,
            water_m: 0.0,
            levels: build_pyramid(base),
            georef: raw.georef,
            resident_from: 0,
            pyramid: None,
            relief_m: None,
        })
    }
}

/// Applies `sketch.height_scale` and takes heights beyond ±[`MAX_HEIGHT_M`] as nodata (NaN); more
/// than 1 % of them beyond is a unit error and refused.
pub fn scale_heights(data: &mut [f32], opts: &LoadOptions) -> Result<()> {
    scale_cells(data, opts)?.check(data.len(), opts)
}

/// Heights that [`scale_cells`] found beyond ±[`MAX_HEIGHT_M`] and made nodata: how many, and
/// the largest magnitude among them.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Beyond {
    /// Heights made nodata.
    pub cells: usize,
    /// The largest magnitude among them, metres after `sketch.height_scale`.
    pub largest_m: f64,
}

impl Beyond {
    /// Counts `other`'s cells too (another band of the same grid).
    pub fn add(&mut self, other: Beyond) {
        self.cells += other.cells;
        self.largest_m = self.largest_m.max(other.largest_m);
    }

    /// [`scale_heights`]'s refusal for a grid of `total` cells: a few such cells are damage or an
    /// undeclared nodata; more than 1 % are heights in another unit.
    pub fn check(&self, total: usize, opts: &LoadOptions) -> Result<()> {
        if self.cells * 100 <= total {
            return Ok(());
        }
        let scale = opts.height_scale.unwrap_or(1.0);
        Err(Error::value(
            "sketch.height_scale",
            format!(
                "{} of {total} heights lie beyond ±1000 km (up to {:.3e} m after height_scale {scale}): \
                 set sketch.height_scale to their unit in metres (0.001 for millimetres)",
                self.cells, self.largest_m
            ),
        ))
    }
}

/// [`scale_heights`] cell by cell, without its refusal: each height scaled, those beyond
/// ±1000 km made nodata and counted, so a grid read in bands ([`crate::sketch::tiles`]) scales each band
/// as the whole grid would and checks the sum at the end.
pub(crate) fn scale_cells(data: &mut [f32], opts: &LoadOptions) -> Result<Beyond> {
    let scale = opts.height_scale.unwrap_or(1.0);
    if !(scale.is_finite() && scale > 0.0) {
        return Err(Error::value(
            "sketch.height_scale",
            format!("height scale {scale} is not positive and finite"),
        ));
    }
    let mut beyond = Beyond::default();
    for h in data.iter_mut() {
        let v = *h as f64 * scale;
        *h = if v.abs() <= MAX_HEIGHT_M {
            v as f32
        } else {
            if v.is_finite() {
                beyond.cells += 1;
                beyond.largest_m = beyond.largest_m.max(v.abs());
            }
            f32::NAN
        };
    }
    Ok(beyond)
}

/// What a sketch file says of itself before its cells are read: size, spacing (after
/// `sketch.spacing_m`) and georeference.
#[derive(Clone, Debug, PartialEq)]
pub struct GridHeader {
    /// Nodes along x (east).
    pub width: usize,
    /// Nodes along y (north).
    pub height: usize,
    /// Grid spacing along x, metres.
    pub dx: f64,
    /// Grid spacing along y, metres.
    pub dy: f64,
    /// Where the file puts its south-west node, when it says.
    pub georef: Option<Georef>,
}

/// The header of a sketch whose size its header states and whose cells can be read in bands
/// (a GeoTIFF), read without a cell; `None` for any other format or a glob. For `terrain info`
/// on a file larger than memory.
pub fn read_header(path: &Path, opts: &LoadOptions) -> Result<Option<GridHeader>> {
    if mosaic::is_glob(path) || !matches!(Format::of(path), Ok(Format::Tiff)) {
        return Ok(None);
    }
    let tiff = geotiff::open(path)?;
    let (width, height) = (tiff.width, tiff.height);
    let grid = RawGrid::new(width, height, Vec::new(), tiff.georef);
    let (dx, dy) = opts.spacing_m.map_or((grid.dx, grid.dy), |s| (s, s));
    Ok(Some(GridHeader {
        width,
        height,
        dx,
        dy,
        georef: grid.georef,
    }))
}

impl Atlas {
    /// A synthetic sketch (see `sketch::synthetic::NAMES`), `size`² nodes.
    pub fn synthetic(name: &str, size: usize, opts: &LoadOptions) -> Result<Atlas> {
        if !(2..=4097).contains(&size) {
            return Err(Error::value(
                "sketch.size",
                format!("synthetic size {size} is outside 2..=4097"),
            ));
        }
        let spacing = opts.spacing_m.unwrap_or(synthetic::DEFAULT_SPACING_M);
        Atlas::from_raw(synthetic::generate(name, size, spacing)?, opts)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn heights_beyond_a_thousand_kilometres_are_filled_as_nodata() {
        let mut data = vec![10.0; 400];
        data[7] = -3.4e38;
        data[99] = 1.0e30;
        data[0] = 20.0;
        let raw = RawGrid::new(20, 20, data, None);
        let a = Atlas::from_raw(raw, &LoadOptions::default()).unwrap();
        assert_eq!(a.nodata, 2);
        assert!(
            a.min_m >= 10.0 && a.max_m <= 20.0,
            "{} {}",
            a.min_m,
            a.max_m
        );
        // Many such heights are another unit: refused, naming the key that fixes it.
        let mm = RawGrid::new(2, 2, vec![1.2e6, 1.3e6, 1.1e6, 2.0e6], None);
        let err = Atlas::from_raw(mm.clone(), &LoadOptions::default())
            .unwrap_err()
            .to_string();
        assert!(err.starts_with("sketch.height_scale: 4 of 4"), "{err}");
        let opts = LoadOptions {
            height_scale: Some(0.001),
            ..LoadOptions::default()
        };
        let a = Atlas::from_raw(mm, &opts).unwrap();
        assert_eq!((a.nodata, a.min_m, a.max_m), (0, 1100.0, 2000.0));
    }
}
