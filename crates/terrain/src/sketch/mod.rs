//! The sketch atlas: the whole height map in main memory, in metres, with a mip pyramid.
//!
//! Rules:
//! - Row 0 is the southern edge; texel (i, j) is the grid node at `origin + (i·dx, j·dy)`.
//! - Every height is finite and within ±[`MAX_HEIGHT_M`]: nodata, NaN and heights beyond it are
//!   filled from valid neighbours by the loader ([`fill`]) and counted in [`Atlas::nodata`], never
//!   passed on.
//! - Level l of the pyramid is a 2×2 box average of level l−1 (sizes halved rounding down, as
//!   texture mips are), so a level-l texel's centre lies at level-0 coordinate `2^l·i + (2^l − 1)/2`.
//!   Sampling between levels is trilinear on the CPU, bicubic per level on the GPU.
//!
//! Rejected alternative: resampling the sketch map straight from level 0 with a wide filter. At
//! 50 km up a 128² sketch map spans thousands of atlas texels each; a per-frame wide filter would cost
//! milliseconds, the pyramid costs one build at load time (a third more memory).

mod asc;
pub mod cubic;
pub mod fill;
pub mod georef;
mod geotiff;
mod hgt;
pub mod mosaic;
mod png;
pub mod synthetic;
mod xyz;

pub use png::parse_world_file;

use crate::error::{Error, Result};
use georef::Georef;
use glam::DVec2;
use std::path::Path;

/// Mean Earth radius (IUGG), for converting geographic cells to metres at their mid latitude.
pub const EARTH_RADIUS_M: f64 = 6_371_008.8;
/// Larger grids are refused rather than allocated: 2^28 cells is 1 GiB of f32 before the pyramid.
pub const MAX_CELLS: usize = 1 << 28;

/// Heights beyond ±1000 km (after `sketch.height_scale`) are no terrain's (the Earth's relief
/// spans 20 km), and squared or summed in f32 downstream they would overflow. Up to 1 % of a
/// sketch's cells beyond it are taken as nodata and filled (a Float64 file damaged into 1e180 m, a
/// float DEM whose −3.4e38 nodata its header does not declare; GDAL reads them as values); more
/// are heights in another unit, and the sketch is refused with a hint to set the scale.
pub const MAX_HEIGHT_M: f64 = 1.0e6;

/// The cell limit in force: [`MAX_CELLS`] unless [`limit_cells`] lowered it.
static CELL_LIMIT: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(MAX_CELLS);

/// Lowers the largest grid any reader allocates, for the whole process: for a fuzz harness or a
/// service that must bound its memory below the default (values above [`MAX_CELLS`] are clamped).
pub fn limit_cells(cells: usize) {
    CELL_LIMIT.store(cells.min(MAX_CELLS), std::sync::atomic::Ordering::Relaxed);
}

/// The largest grid a reader allocates now.
pub fn max_cells() -> usize {
    CELL_LIMIT.load(std::sync::atomic::Ordering::Relaxed)
}

/// One level of the pyramid: a row-major grid of finite heights.
#[derive(Clone, Debug)]
pub struct Level {
    pub width: usize,
    pub height: usize,
    pub data: Vec<f32>,
}

/// The side of the window a level not in memory is measured on for
/// [`Atlas::level_curvature`]: 512², whose stride (2) visits as many texels as on a level held
/// whole.
pub const CURVATURE_WINDOW: usize = 512;

#[derive(Clone, Debug)]
pub struct Atlas {
    /// Grid spacing in metres along x (east) and y (north).
    pub dx: f64,
    pub dy: f64,
    /// World position of the south-west node.
    pub origin: DVec2,
    /// Cells that held nodata or NaN in the file and were filled.
    pub nodata: usize,
    pub min_m: f32,
    pub max_m: f32,
    /// The mean height of the edge nodes: where a plain beyond the sketch lies.
    pub edge_mean_m: f32,
    /// The water's surface: ground below it lies under flat water (`sketch.water_level_m`).
    pub water_m: f32,
    /// `levels[0]` is the atlas itself.
    pub levels: Vec<Level>,
    /// Where the file put its south-west node, in the file's coordinate system (not the world's:
    /// the world is `origin`-based metres), when the file says.
    pub georef: Option<Georef>,
    /// Levels finer than this are not held in memory (their `data` is empty): a tile pyramid
    /// streamed to the GPU through the tile cache keeps only its coarse levels here, and the CPU
    /// reads the finest of those. 0 for a sketch read whole.
    pub resident_from: usize,
    /// The tile pyramid the sketch streams from, when it is one.
    pub pyramid: Option<crate::tiles::Pyramid>,
    /// [`Atlas::finest_relief`] measured when the finest levels were read, for a streamed sketch.
    pub relief_m: Option<[f64; 2]>,
}

/// What a file does not say about itself, from the scene.
#[derive(Clone, Debug, Default)]
pub struct LoadOptions {
    pub spacing_m: Option<f64>,
    pub origin_m: Option<DVec2>,
    pub height_scale: Option<f64>,
    /// For 8/16-bit images: the heights that pixel values 0 and the maximum stand for.
    pub height_range_m: Option<[f64; 2]>,
    /// A streamed tile pyramid: bytes of its coarse levels to hold in memory (`stream.cpu_mb`).
    pub stream_cpu_bytes: Option<u64>,
}

/// A grid as a format reader produces it, before filling and the pyramid.
#[derive(Clone, Debug)]
pub struct RawGrid {
    pub width: usize,
    pub height: usize,
    pub dx: f64,
    pub dy: f64,
    /// Row-major, row 0 south. Non-finite values are nodata.
    pub data: Vec<f32>,
    /// Where the nodes lie in the file's coordinate system, when the file says (mosaics need it).
    pub georef: Option<Georef>,
}

impl RawGrid {
    /// A grid placed by its georeference when it has one; without, its cells are 1 m until the
    /// scene's `sketch.spacing_m` says otherwise.
    pub fn new(width: usize, height: usize, data: Vec<f32>, georef: Option<Georef>) -> RawGrid {
        match georef {
            Some(g) => RawGrid::georeferenced(width, height, data, g),
            None => RawGrid {
                width,
                height,
                dx: 1.0,
                dy: 1.0,
                data,
                georef: None,
            },
        }
    }

    /// A grid whose spacing follows from its georeference.
    pub fn georeferenced(width: usize, height: usize, data: Vec<f32>, georef: Georef) -> RawGrid {
        let georef = georef.resolved(width, height);
        let (dx, dy) = georef.spacing_m(width, height);
        RawGrid {
            width,
            height,
            dx,
            dy,
            data,
            georef: Some(georef),
        }
    }

    /// Checks the size against the limits before a reader allocates.
    pub fn check_size(path: &Path, width: i64, height: i64) -> Result<(usize, usize)> {
        if width < 2 || height < 2 {
            RawGrid::check_size_unlimited(path, width, height)?;
        }
        let cells = (width as u128) * (height as u128);
        let limit = max_cells();
        if cells > limit as u128 {
            return Err(Error::sketch(
                path,
                format!("grid is {width}×{height}, more than the {limit} cells supported"),
            ));
        }
        Ok((width as usize, height as usize))
    }

    /// Checks that a grid has at least 2×2 nodes and at most 2^31 along a side, whatever the cell
    /// limit: for grids that are streamed rather than allocated (`terrain tiles`).
    pub fn check_size_unlimited(path: &Path, width: i64, height: i64) -> Result<(usize, usize)> {
        if width < 2 || height < 2 {
            return Err(Error::sketch(
                path,
                format!("grid is {width}×{height}; a sketch needs at least 2×2 cells"),
            ));
        }
        if width.max(height) > i32::MAX as i64 {
            return Err(Error::sketch(
                path,
                format!("grid is {width}×{height}; a side longer than 2^31 nodes is no sketch's"),
            ));
        }
        Ok((width as usize, height as usize))
    }
}

pub use georef::degrees_to_metres;

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
    if crate::tiles::is_pyramid(path) {
        return crate::tiles::read::raw_grid(path, opts);
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

/// What reading the sketch at `path` with `opts` would take on trust where neither the file nor
/// the options say (a PNG's units), one line each for the program to show: the library prints
/// nothing. Cheap (a PNG's header); empty where nothing is guessed or the file cannot be read.
pub fn warnings(path: &Path, opts: &LoadOptions) -> Vec<String> {
    match Format::of(path) {
        Ok(Format::Png) if !mosaic::is_glob(path) => {
            png::units_warning(path, opts).into_iter().collect()
        }
        _ => Vec::new(),
    }
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
        if crate::tiles::is_pyramid(path) {
            return crate::tiles::read::streamed_atlas(path, opts);
        }
        let raw = read_grid(path, opts)?;
        Atlas::from_raw(raw, opts).map_err(|e| match e {
            Error::Value { reason, .. } => Error::sketch(path, reason),
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

    pub fn width(&self) -> usize {
        self.levels[0].width
    }

    /// The sketch's relief in its two finest bands, metres: the spread of what level 0 adds to
    /// level 1 of the pyramid (wavelengths of 2–4 cells), and of what level 1 adds to level 2
    /// (4–8 cells). The spread is robust, 1.4826 × the median absolute value (the standard
    /// deviation where the band is normal), so a few cliffs or filled voids do not stand for the
    /// whole sketch: on the bundled DEM the RMS is within 5 % of
    /// it, but on the synthetic cliff (a plain with one step) the RMS is 14 m where the plain has
    /// none. At most about 256² texels are
    /// visited, so a sketch of any size costs the same.
    pub fn finest_relief(&self) -> [f64; 2] {
        if let Some(r) = self.relief_m {
            return r;
        }
        let band = |l: usize| -> f64 {
            if l + 1 >= self.levels.len() {
                return 0.0;
            }
            let level = &self.levels[l];
            let stride = (level.width.max(level.height) / 256).max(1);
            let s = (1u64 << l) as f64;
            let mut values = Vec::new();
            for j in (0..level.height).step_by(stride) {
                for i in (0..level.width).step_by(stride) {
                    // Level l's texel (i, j) in level-0 texel units, where sample_texel works.
                    let (u, v) = ((i as f64 + 0.5) * s - 0.5, (j as f64 + 0.5) * s - 0.5);
                    let fine = level.data[j * level.width + i] as f64;
                    let coarse = self.sample_texel(u, v, (l + 1) as f64) as f64;
                    values.push((fine - coarse).abs());
                }
            }
            if values.is_empty() {
                return 0.0;
            }
            let mid = values.len() / 2;
            let (_, median, _) = values.select_nth_unstable_by(mid, f64::total_cmp);
            1.4826 * *median
        };
        [band(0), band(1)]
    }
    /// The mean curvature of each pyramid level, 1/m: the largest of its second differences
    /// (|h_xx|, |h_yy|, |h_xy|, the heights raised to `water_m`) at its own spacing, as the
    /// importance's geometric-error term takes them from the sketch map, averaged over the level.
    /// A level not held in memory (a streamed pyramid's finest) is measured on its central
    /// window of at most [`CURVATURE_WINDOW`]² texels, read from its tiles (NaN where they cannot
    /// be read): counting only the levels in memory gave a sketch larger than memory, seen from
    /// high up, less of the error term than the same sketch held whole (jacksboro-high over its
    /// pyramid with `stream.cpu_mb = 0.1`, levels 0 and 1 on disk: warped needed 0.963×
    /// GeoMipMap's triangles, 0.916× with the windows, 0.921× with the pyramid all in memory;
    /// `terrain compare S --out-dir D --modes warped,geomipmap --repeat 1 --path-frames 0`,
    /// `summary.md`'s geometric mean). Every k-th texel of a
    /// level is visited, k its larger side ÷ 256 rounded down (fewer than 512² texels), so a
    /// sketch of any size costs about the same.
    ///
    /// Natural terrain is rough at every scale: on the bundled DEM the mean doubles with each
    /// finer level (0.56·10⁻³ at 320 m, 1.1·10⁻³ at 160 m, 2.0·10⁻³ at 80 m), so a sketch map
    /// coarser than the atlas sees a fraction of the curvature its samples meet.
    pub fn level_curvature(&self, water_m: f32) -> Vec<f64> {
        self.levels
            .iter()
            .enumerate()
            .map(|(l, level)| {
                let scale = (1u64 << l) as f64;
                let (dx, dy) = (self.dx * scale, self.dy * scale);
                match self.tiled_window(l) {
                    Some(window) => window.mean_curvature(dx, dy, water_m),
                    None => level.mean_curvature(dx, dy, water_m),
                }
            })
            .collect()
    }

    /// Level `l`'s central window of at most [`CURVATURE_WINDOW`]² texels from the tiles, where
    /// the level is not in memory but a pyramid holds it; None otherwise or where a tile cannot
    /// be read.
    fn tiled_window(&self, l: usize) -> Option<Level> {
        let pyramid = self
            .pyramid
            .as_ref()
            .filter(|_| self.levels[l].data.is_empty())?;
        pyramid.central_window(l, CURVATURE_WINDOW).ok()
    }

    pub fn height(&self) -> usize {
        self.levels[0].height
    }
    /// Bytes of heights in the whole pyramid held in memory (what the GPU holds of a whole atlas).
    pub fn bytes(&self) -> u64 {
        self.levels.iter().map(|l| l.data.len() as u64 * 4).sum()
    }

    /// `d_atlas`: the smaller grid spacing, the scale of octave 1.
    pub fn d_atlas(&self) -> f64 {
        self.dx.min(self.dy)
    }
    /// World position of the north-east node.
    pub fn max_corner(&self) -> DVec2 {
        self.origin
            + DVec2::new(
                (self.width() - 1) as f64 * self.dx,
                (self.height() - 1) as f64 * self.dy,
            )
    }

    /// Height at level-0 texel (u, v), bilinear on level 0, clamped to the edge: from memory, or
    /// for a streamed sketch from the tile that holds it. A point query, for the ground under a
    /// camera: a check on the coarse levels held in memory would let a camera sink under a peak
    /// they smooth away. Errors only where a tile cannot be read.
    pub fn ground_texel(&self, u: f64, v: f64) -> Result<f32> {
        match &self.pyramid {
            Some(p) if self.resident_from > 0 => p.bilinear(0, u, v),
            _ => Ok(self.levels[0].bilinear(u, v)),
        }
    }

    /// Height at a position given in level-0 texel units, at mip level `lod` (fractional ≥ 0 is
    /// trilinear; below 0 is level 0), clamped to the edge.
    pub fn sample_texel(&self, u: f64, v: f64, lod: f64) -> f32 {
        let lod = lod.clamp(self.resident_from as f64, (self.levels.len() - 1) as f64);
        let l0 = lod.floor() as usize;
        let t = (lod - l0 as f64) as f32;
        let a = self.levels[l0].bilinear_at_level(u, v, l0);
        if t == 0.0 || l0 + 1 >= self.levels.len() {
            return a;
        }
        let b = self.levels[l0 + 1].bilinear_at_level(u, v, l0 + 1);
        a + (b - a) * t
    }
}

impl Level {
    /// The mean height of the edge nodes.
    fn edge_mean(&self) -> f32 {
        let (w, h) = (self.width, self.height);
        let at = |i: usize, j: usize| self.data[j * w + i] as f64;
        let rows: f64 = (0..w).map(|i| at(i, 0) + at(i, h - 1)).sum();
        let cols: f64 = (1..h - 1).map(|j| at(0, j) + at(w - 1, j)).sum();
        ((rows + cols) / (2 * w + 2 * (h - 2)) as f64) as f32
    }

    /// [`Atlas::level_curvature`] of this level, of spacing `dx` × `dy`: NaN without data or
    /// without an interior texel.
    fn mean_curvature(&self, dx: f64, dy: f64, water_m: f32) -> f64 {
        let (w, h) = (self.width, self.height);
        if self.data.len() != w * h || w < 3 || h < 3 {
            return f64::NAN;
        }
        let at = |i: usize, j: usize| f64::from(self.data[j * w + i].max(water_m));
        let stride = (w.max(h) / 256).max(1);
        let (mut sum, mut count) = (0.0, 0usize);
        for j in (1..h - 1).step_by(stride) {
            for i in (1..w - 1).step_by(stride) {
                let c = at(i, j);
                let hxx = (at(i + 1, j) - 2.0 * c + at(i - 1, j)) / (dx * dx);
                let hyy = (at(i, j + 1) - 2.0 * c + at(i, j - 1)) / (dy * dy);
                let hxy = (at(i + 1, j + 1) - at(i - 1, j + 1) - at(i + 1, j - 1)
                    + at(i - 1, j - 1))
                    / (4.0 * dx * dy);
                sum += hxx.abs().max(hyy.abs()).max(hxy.abs());
                count += 1;
            }
        }
        sum / count as f64
    }

    /// Bilinear sample at level-0 texel coordinates (u, v), this being level `l`.
    fn bilinear_at_level(&self, u: f64, v: f64, l: usize) -> f32 {
        let s = (1u64 << l) as f64;
        let off = (s - 1.0) * 0.5;
        self.bilinear((u - off) / s, (v - off) / s)
    }

    /// Bilinear sample at this level's texel coordinates, clamped to the edge.
    pub fn bilinear(&self, u: f64, v: f64) -> f32 {
        let ((i, j), f) = bilinear_cell(u, v, self.width, self.height);
        let w = self.width;
        let r0 = &self.data[j * w + i..j * w + i + 2];
        let r1 = &self.data[(j + 1) * w + i..(j + 1) * w + i + 2];
        bilinear_blend([[r0[0], r0[1]], [r1[0], r1[1]]], f)
    }
}

/// The cell of a `width` × `height` grid (at least 2 × 2) a bilinear sample at (u, v) reads,
/// clamped to the edge: its south-west node and the fractions across it. With
/// [`bilinear_blend`], the one rule of every bilinear read of heights on the CPU, in memory or
/// from a pyramid's tiles (`tiles::Pyramid::bilinear`), so they agree bit for bit.
pub fn bilinear_cell(u: f64, v: f64, width: usize, height: usize) -> ((usize, usize), [f32; 2]) {
    let u = u.clamp(0.0, (width - 1) as f64);
    let v = v.clamp(0.0, (height - 1) as f64);
    let i = (u.floor() as usize).min(width - 2);
    let j = (v.floor() as usize).min(height - 2);
    ((i, j), [(u - i as f64) as f32, (v - j as f64) as f32])
}

/// A cell's corners `z[row][column]` (row 0 south) blended at fractions `f`.
pub fn bilinear_blend(z: [[f32; 2]; 2], f: [f32; 2]) -> f32 {
    let a = z[0][0] + (z[0][1] - z[0][0]) * f[0];
    let b = z[1][0] + (z[1][1] - z[1][0]) * f[0];
    a + (b - a) * f[1]
}

/// Applies `sketch.height_scale` and takes heights beyond ±[`MAX_HEIGHT_M`] as nodata (NaN); more
/// than 1 % of them beyond is a unit error and refused.
pub fn scale_heights(data: &mut [f32], opts: &LoadOptions) -> Result<()> {
    let scale = opts.height_scale.unwrap_or(1.0);
    if !(scale.is_finite() && scale > 0.0) {
        return Err(Error::value(
            "sketch.height_scale",
            format!("height scale {scale} is not positive and finite"),
        ));
    }
    let (mut beyond, mut largest) = (0usize, 0.0f64);
    for h in data.iter_mut() {
        let v = *h as f64 * scale;
        *h = if v.abs() <= MAX_HEIGHT_M {
            v as f32
        } else {
            if v.is_finite() {
                beyond += 1;
                largest = largest.max(v.abs());
            }
            f32::NAN
        };
    }
    // A few such cells are damage or an undeclared nodata; many are heights in another unit.
    if beyond * 100 > data.len() {
        return Err(Error::value(
            "sketch.height_scale",
            format!(
                "{beyond} of {} heights lie beyond ±1000 km (up to {largest:.3e} m after height_scale {scale}): \
                     set sketch.height_scale to their unit in metres (0.001 for millimetres)",
                data.len()
            ),
        ));
    }
    Ok(())
}

/// Halves (rounding down, as texture mip levels do, so the GPU holds the same pyramid) while the
/// next level keeps 2 texels on its shorter side; an odd level's last row or column is dropped.
pub(crate) fn build_pyramid(base: Level) -> Vec<Level> {
    let mut levels = vec![base];
    loop {
        let prev = levels.last().expect("pyramid has a base");
        let (w, h) = (prev.width / 2, prev.height / 2);
        if w.min(h) < 2 {
            break;
        }
        let mut data = Vec::with_capacity(w * h);
        for j in 0..h {
            for i in 0..w {
                let at = |x: usize, y: usize| prev.data[y * prev.width + x];
                let (x, y) = (2 * i, 2 * j);
                data.push(0.25 * (at(x, y) + at(x + 1, y) + at(x, y + 1) + at(x + 1, y + 1)));
            }
        }
        levels.push(Level {
            width: w,
            height: h,
            data,
        });
    }
    levels
}

impl Atlas {
    /// A synthetic sketch (see [`synthetic::NAMES`]), `size`² nodes.
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

    fn ramp(w: usize, h: usize) -> Atlas {
        let data = (0..w * h).map(|k| (k % w) as f32).collect();
        let raw = RawGrid {
            width: w,
            height: h,
            dx: 10.0,
            dy: 10.0,
            data,
            georef: None,
        };
        Atlas::from_raw(raw, &LoadOptions::default()).unwrap()
    }

    /// A paraboloid h = a·x² + b·y² has second differences 2a and 2b at every level (a box
    /// filter adds a constant to a quadratic), so each level's mean is the larger, 2b, in 1/m;
    /// a plane has none; water above the ground flattens it; a level not in memory is NaN.
    #[test]
    fn level_curvature_is_the_mean_second_difference_of_each_level() {
        let (w, h, d) = (300, 260, 20.0);
        let (a, b) = (1e-4f64, 3e-4f64);
        let grid = |f: &dyn Fn(f64, f64) -> f64| {
            let data = (0..w * h)
                .map(|k| f((k % w) as f64 * d, (k / w) as f64 * d) as f32)
                .collect();
            let raw = RawGrid {
                width: w,
                height: h,
                dx: d,
                dy: d,
                data,
                georef: None,
            };
            Atlas::from_raw(raw, &LoadOptions::default()).unwrap()
        };
        let bowl = grid(&|x, y| a * (x - 3000.0).powi(2) + b * (y - 2600.0).powi(2));
        let c = bowl.level_curvature(f32::NEG_INFINITY);
        assert_eq!(c.len(), bowl.levels.len());
        for (l, &v) in c.iter().enumerate().take(c.len() - 1) {
            assert!((v - 2.0 * b).abs() < 0.02 * 2.0 * b, "level {l}: {v}");
        }
        let plane = grid(&|x, y| 0.3 * x - 0.1 * y + 50.0);
        assert!(plane.level_curvature(f32::NEG_INFINITY)[0].abs() < 1e-7);
        assert!(bowl.level_curvature(1e9)[0] == 0.0, "under water");
        let mut streamed = bowl.clone();
        streamed.levels[0].data.clear();
        let c = streamed.level_curvature(f32::NEG_INFINITY);
        assert!(c[0].is_nan() && (c[1] - 2.0 * b).abs() < 0.02 * 2.0 * b);
    }

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

    #[test]
    fn pyramid_keeps_a_linear_ramp_in_place_at_every_level() {
        // A ramp h = u must sample as u at every level, or the level offsets are wrong.
        let a = ramp(64, 64);
        for lod in [0.0, 1.0, 2.5, 4.0] {
            let h = a.sample_texel(20.0, 30.0, lod);
            assert!((h - 20.0).abs() < 1e-4, "lod {lod}: {h}");
        }
    }
}
