//! `terrain tiles`: converts a sketch (a file, or a glob of tiles) or an image into a tile
//! pyramid ([`crate::sketch::tiles`]) with bounded memory, resumably. Apart from the pyramids it
//! writes: the readers (`tiles`, the streamed atlas) never reach the converter, which reads its
//! sources through the sketch's loaders.
//!
//! Rules:
//! - Memory is bounded by a few bands of level 0's width, whatever the sketch's height: level 0 is
//!   cut band by band (one tile row and its borders). A single GeoTIFF, and the GeoTIFFs under a
//!   VRT, are read window by window: a band decodes the strips or tiles under its rows alone
//!   (`level0`). Other sources, and every tile of a glob, are first copied one at a time into raw
//!   scratch files that a band reads by rows (a GeoTIFF tile band by band, any other file whole);
//!   level l is cut band by band from the rows of level l−1's tiles. A 32,768-node-wide sketch
//!   holds about 100 MB of bands. The cell limit ([`crate::sketch::max_cells`]) bounds a band
//!   and a GeoTIFF's chunk row, not the sketch; a text grid (ESRI ASCII, XYZ) above 256 MiB is
//!   refused with the `gdal_translate` command that makes it a tiled GeoTIFF.
//! - A cloud-optimised GeoTIFF's overviews are ignored: every coarser level is the 2×2 average
//!   of the one below, so the pyramid is the atlas's whatever resampling made the overviews
//!   (docs/decisions.md, “Single files read window by window”).
//! - Nodata is filled within each band by the atlas's rule (`sketch::fill`): a hole that a
//!   band does not close from its own rows is closed from those, not from rows further away, so a
//!   holed sketch's tiled fill can differ from the whole-grid one near bands' edges. A sketch with
//!   no nodata converts bit for bit.
//! - Resuming: every tile and scratch file is written under a temporary name and renamed; a band
//!   whose tiles are all whole is skipped. `build.json` records the sources (path, size, mtime)
//!   and options; a folder built from anything else is refused rather than mixed.
//! - The scratch folder `.build` is removed once `pyramid.toml` is written.

mod bands;
mod image;
mod level0;
pub(super) mod resume;
mod scratch;

use crate::error::{Error, Result, Role};
use crate::io::write_atomic;
use crate::sketch::load::LoadOptions;
use crate::sketch::mosaic;
use crate::sketch::tiles::codec::{HEADER_BYTES, TileHeader};
use crate::sketch::tiles::read::read_rows;
use crate::sketch::tiles::{self, BORDER, FORMAT, META, Meta, SIDE, TILE, level_sizes, tile_path};
pub(in crate::sketch::convert) use bands::band_rows;
use bands::{coarser_band, write_band};
pub(in crate::sketch::convert) use level0::is_tiff;
use resume::{Plan, remove_temporaries, stamp, start_or_resume, tile_is_whole};
pub(in crate::sketch::convert) use scratch::meta_georef;
use serde::Serialize;
use std::os::unix::fs::FileExt;
use std::path::Path;
use std::time::Instant;

/// Converts `src` into a pyramid in `out` (created, or resumed where a run stopped).
///
/// `src` is any sketch file or a quoted glob of tiles on one grid; a scene whose `sketch.path`
/// names `out` then streams it. A GeoTIFF of 8-bit RGB or RGBA pixels (or grey ones, with
/// [`BuildOptions::image`]) is an image: its pyramid ([`tiles::image`]) is for `surface.image`.
///
/// ```no_run
/// use std::path::Path;
/// use terrain_engine::sketch::convert::{self, BuildOptions};
///
/// let summary = convert::build(
///     Path::new("dem/*.hgt"),
///     Path::new("dem-pyramid"),
///     &BuildOptions { threads: 0, ..Default::default() },
/// )?;
/// println!("{} levels, {} tiles", summary.levels, summary.tiles);
/// # Ok::<(), terrain_engine::Error>(())
/// ```
pub fn build(src: &Path, out: &Path, opts: &BuildOptions) -> Result<BuildSummary> {
    if tiles::is_pyramid(src) {
        return Err(Error::sketch(src, "is a tile pyramid already"));
    }
    match is_image(src, opts.image) {
        true => image::build(src, out, opts),
        false => heights(src, out, opts),
    }
}

/// What the command asked for beyond the source.
#[derive(Clone, Debug, Default)]
pub struct BuildOptions {
    /// The scene's sketch keys that a file may not say (spacing, height scale and range).
    pub load: LoadOptions,
    /// Threads that encode a band's tiles (0: all cores).
    pub threads: usize,
    /// Converts an 8-bit grey GeoTIFF as an image, not as heights (RGB and RGBA ones are
    /// images whatever this says).
    pub image: bool,
}

/// What a build did, for the command's report.
#[derive(Clone, Debug, Serialize)]
pub struct BuildSummary {
    /// What the pyramid holds: `heights` or `image`.
    pub kind: tiles::Kind,
    /// Level 0's nodes (an image's pixels) per row.
    pub width: usize,
    /// Level 0's rows.
    pub height: usize,
    /// Mip levels, level 0 included.
    pub levels: usize,
    /// Tiles of every level.
    pub tiles: usize,
    /// Tiles this run encoded; the others were whole from an earlier, interrupted run.
    pub tiles_written: usize,
    /// Source files read (one, or the tiles a glob matched).
    pub sources: usize,
    /// Bytes of the finished pyramid's files.
    pub disk_bytes: u64,
    /// Wall time of the build, seconds.
    pub seconds: f64,
}

/// Converts the height map `src` into a pyramid in `out`: [`build`] for heights.
pub(super) fn heights(src: &Path, out: &Path, opts: &BuildOptions) -> Result<BuildSummary> {
    let start = Instant::now();
    let sources = if mosaic::is_glob(src) {
        mosaic::list_glob(src)?
    } else {
        vec![src.to_path_buf()]
    };
    let plan = Plan {
        format: FORMAT.into(),
        kind: tiles::Kind::Heights,
        sources: sources.iter().map(|p| stamp(p)).collect::<Result<_>>()?,
        spacing_m: opts.load.spacing_m,
        height_scale: opts.load.height_scale,
        height_range_m: opts.load.height_range_m,
    };
    start_or_resume(out, &plan)?;
    if tiles::is_pyramid(out) {
        // Whole already: nothing to read or write.
        let meta = tiles::Pyramid::open(out)?.meta;
        return Ok(BuildSummary {
            kind: tiles::Kind::Heights,
            width: meta.width,
            height: meta.height,
            levels: meta.levels.len(),
            tiles: meta.tile_count(),
            tiles_written: 0,
            sources: sources.len(),
            disk_bytes: folder_bytes(out),
            seconds: start.elapsed().as_secs_f64(),
        });
    }
    let scratch_dir = out.join(".build");
    let ((width, height, dx, dy, _, georef), mut level0) =
        level0::open(src, &sources, &scratch_dir, &opts.load)?;
    check_band(src, width)?;
    let levels = level_sizes(width, height);
    let mut meta = Meta {
        format: FORMAT.into(),
        kind: tiles::Kind::Heights,
        source: src.display().to_string(),
        width,
        height,
        dx_m: dx,
        dy_m: dy,
        tile: TILE,
        border: BORDER,
        levels,
        min_m: 0.0,
        max_m: 0.0,
        edge_mean_m: 0.0,
        nodata: 0,
        georef: georef.map(meta_georef),
    };
    let threads = match opts.threads {
        0 => std::thread::available_parallelism().map_or(1, |n| n.get()),
        n => n,
    };
    remove_temporaries(out);
    let mut progress = crate::progress::start("tiles", Some(meta.tile_count() as f64));
    let mut written = 0;
    for l in 0..meta.levels.len() {
        let (_, bands) = meta.tiles(l);
        for ty in 0..bands {
            let [w, _] = meta.levels[l];
            let (tx_count, _) = meta.tiles(l);
            let missing: Vec<usize> = (0..tx_count)
                .filter(|&tx| !tile_is_whole(&tile_path(out, l, tx, ty)))
                .collect();
            if !missing.is_empty() {
                let (r0, band) = if l == 0 {
                    let rows = bands::band_rows(ty, height);
                    let own = (ty * TILE, ((ty + 1) * TILE).min(height));
                    let next = own.1.saturating_sub(BORDER);
                    (rows.0, level0.band(width, rows, own, next)?)
                } else {
                    coarser_band(out, &meta, l, ty)?
                };
                write_band(out, &meta, l, ty, r0, &band, w, &missing, threads)?;
                written += missing.len();
            }
            progress.advance(tx_count as f64, &format!("level {l}, row {ty}"));
        }
        if l == 0 {
            let beyond = level0
                .scale
                .as_ref()
                .map(|load| level0.beyond.check(width * height, load));
            if let Some(Err(e)) = beyond {
                // A run again must find the level missing and refuse again, not finish it.
                let _ = std::fs::remove_dir_all(out.join("L0"));
                return Err(match e {
                    Error::Value { reason, .. } => Error::sketch(src, reason),
                    e => e,
                });
            }
        }
    }
    progress.finish();
    finish_meta(out, &mut meta)?;
    write_atomic(&out.join(META), toml_text(&meta)?.as_bytes())?;
    let _ = std::fs::remove_dir_all(&scratch_dir);
    Ok(BuildSummary {
        kind: tiles::Kind::Heights,
        width,
        height,
        levels: meta.levels.len(),
        tiles: meta.tile_count(),
        tiles_written: written,
        sources: sources.len(),
        disk_bytes: folder_bytes(out),
        seconds: start.elapsed().as_secs_f64(),
    })
}

/// Whether `src` is converted as an image: a single GeoTIFF whose pixels are 8-bit RGB or RGBA
/// (a height map has one sample), or anything when `asked` (whose reading then says what it is
/// not). 8-bit grey is heights unless asked: a DEM may be stored in bytes.
pub(super) fn is_image(src: &Path, asked: bool) -> bool {
    use crate::surface::tiff::{Samples, samples_of};
    let rgb = || matches!(samples_of(src), Some(Samples::Rgb | Samples::Rgba));
    asked || (!mosaic::is_glob(src) && is_tiff(src) && rgb())
}

/// Refuses a sketch whose bands (a tile row and its borders, at level 0's width) would hold more
/// than the cell limit at once: the limit bounds what is held, not the sketch.
fn check_band(src: &Path, width: usize) -> Result<()> {
    let cells = width * (TILE + 2 * BORDER);
    let limit = crate::sketch::load::max_cells();
    if cells > limit {
        return Err(Error::sketch(
            src,
            format!(
                "a band of {width}×{} nodes is more than the {limit} cells held at once",
                TILE + 2 * BORDER
            ),
        ));
    }
    Ok(())
}

/// The level-0 statistics from the tiles: range and nodata from their headers, the edge mean
/// from the edge tiles (the atlas's formula).
fn finish_meta(out: &Path, meta: &mut Meta) -> Result<()> {
    let (tx_n, ty_n) = meta.tiles(0);
    let (mut lo, mut hi, mut nodata) = (f32::INFINITY, f32::NEG_INFINITY, 0u64);
    for ty in 0..ty_n {
        for tx in 0..tx_n {
            let path = tile_path(out, 0, tx, ty);
            let file = std::fs::File::open(&path).map_err(|e| Error::io(Role::Sketch, &path, e))?;
            let mut head = [0u8; HEADER_BYTES];
            file.read_exact_at(&mut head, 0)
                .map_err(|e| Error::io(Role::Sketch, &path, e))?;
            let h = TileHeader::parse(&path, &head)?;
            lo = lo.min(h.min_m);
            hi = hi.max(h.max_m);
            nodata += h.nodata as u64;
        }
    }
    let (w, h) = (meta.width, meta.height);
    let bottom = read_rows(out, meta, 0, 0, 1)?;
    let top = read_rows(out, meta, 0, h - 1, h)?;
    let rows: f64 = (0..w).map(|i| bottom[i] as f64 + top[i] as f64).sum();
    let mut cols = 0.0f64;
    let east = BORDER + (w - 1 - (tx_n - 1) * TILE);
    for ty in 0..ty_n {
        let west_tile = tiles::read::read_tile_file(&tile_path(out, 0, 0, ty), SIDE)?;
        let east_tile = match tx_n {
            1 => west_tile.clone(),
            _ => tiles::read::read_tile_file(&tile_path(out, 0, tx_n - 1, ty), SIDE)?,
        };
        for j in 0..TILE {
            if (1..h - 1).contains(&(ty * TILE + j)) {
                let row = (j + BORDER) * SIDE;
                cols += west_tile[row + BORDER] as f64 + east_tile[row + east] as f64;
            }
        }
    }
    let sum = rows + cols;
    meta.min_m = lo;
    meta.max_m = hi;
    meta.nodata = nodata;
    meta.edge_mean_m = (sum / (2 * w + 2 * (h - 2)) as f64) as f32;
    Ok(())
}

fn toml_text(meta: &Meta) -> Result<String> {
    toml::to_string(meta).map_err(|e| Error::encode("pyramid.toml", e))
}

pub(in crate::sketch::convert) fn folder_bytes(dir: &Path) -> u64 {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return 0;
    };
    entries
        .flatten()
        .map(|e| match e.file_type() {
            Ok(t) if t.is_dir() => folder_bytes(&e.path()),
            Ok(_) => e.metadata().map_or(0, |m| m.len()),
            Err(_) => 0,
        })
        .sum()
}
