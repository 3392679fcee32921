//! `terrain tiles`: converts a sketch (a file, or a glob of tiles) into a tile pyramid with
//! bounded memory, resumably.
//!
//! Rules:
//! - Memory is bounded by the largest single source file plus two bands of level 0's width: level 0
//!   is cut band by band (one tile row and its borders) from the sources, which are first copied
//!   one at a time into raw scratch files that a band reads by rows; level l is cut band by band from
//!   the rows of level l−1's tiles. A 32,768-node-wide sketch holds about 100 MB of bands.
//! - Nodata is filled within each band by the atlas's rule ([`crate::sketch::fill`]): a hole that a
//!   band does not close from its own rows is closed from those, not from rows further away, so a
//!   holed sketch's tiled fill can differ from the whole-grid one near bands' edges. A sketch with
//!   no nodata converts bit for bit.
//! - Resuming: every tile and scratch file is written under a temporary name and renamed; a band
//!   whose tiles are all whole is skipped. `build.json` records the sources (path, size, mtime)
//!   and options; a folder built from anything else is refused rather than mixed.
//! - The scratch folder `.build` is removed once `pyramid.toml` is written.

use super::codec::{HEADER_BYTES, TileHeader, encode_tile};
use super::{BORDER, FORMAT, META, Meta, MetaGeoref, SIDE, TILE, level_sizes, tile_path};
use crate::error::{Error, Result, Role};
use crate::io::write_atomic;
use crate::sketch::georef::{Georef, Units};
use crate::sketch::mosaic::{self, TileExtent};
use crate::sketch::{LoadOptions, fill, read_grid, scale_heights};
use serde::{Deserialize, Serialize};
use std::os::unix::fs::FileExt;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// What the command asked for beyond the source.
#[derive(Clone, Debug, Default)]
pub struct BuildOptions {
    /// The scene's sketch keys that a file may not say (spacing, height scale and range).
    pub load: LoadOptions,
    /// Threads that encode a band's tiles (0: all cores).
    pub threads: usize,
}

/// Removes the temporary files (`.NAME.PID.tmp`) a killed build left half written under `dir`,
/// so a resumed build leaves the folder as a fresh one would.
fn remove_temporaries(dir: &Path) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for e in entries.flatten() {
        let (path, name) = (e.path(), e.file_name());
        let name = name.to_string_lossy();
        // Not through a link: only what this folder holds.
        if e.file_type().is_ok_and(|t| t.is_dir()) {
            remove_temporaries(&path);
        } else if name.starts_with('.') && name.ends_with(".tmp") {
            let _ = std::fs::remove_file(&path);
        }
    }
}

/// What a build did, for the command's report.
#[derive(Clone, Debug, Serialize)]
pub struct BuildSummary {
    pub width: usize,
    pub height: usize,
    pub levels: usize,
    pub tiles: usize,
    /// Tiles this run encoded; the others were whole from an earlier, interrupted run.
    pub tiles_written: usize,
    pub sources: usize,
    /// Bytes of the finished pyramid's files.
    pub disk_bytes: u64,
    pub seconds: f64,
}

/// `build.json`: what a pyramid folder is being built from.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
struct Plan {
    format: String,
    sources: Vec<SourceStamp>,
    spacing_m: Option<f64>,
    height_scale: Option<f64>,
    height_range_m: Option<[f64; 2]>,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
struct SourceStamp {
    path: String,
    bytes: u64,
    mtime_ns: u128,
}

/// A source copied to scratch: `src-K.f32` (row-major f32, row 0 south) and `src-K.json`.
#[derive(Clone, Debug, Serialize, Deserialize)]
struct Scratch {
    width: usize,
    height: usize,
    dx: f64,
    dy: f64,
    georef: Option<MetaGeoref>,
}

/// Converts `src` into a pyramid in `out` (created, or resumed where a run stopped).
pub fn build(src: &Path, out: &Path, opts: &BuildOptions) -> Result<BuildSummary> {
    let start = Instant::now();
    if super::is_pyramid(src) {
        return Err(Error::sketch(src, "is a tile pyramid already"));
    }
    let sources = if mosaic::is_glob(src) {
        mosaic::list_glob(src)?
    } else {
        vec![src.to_path_buf()]
    };
    let plan = Plan {
        format: FORMAT.into(),
        sources: sources.iter().map(|p| stamp(p)).collect::<Result<_>>()?,
        spacing_m: opts.load.spacing_m,
        height_scale: opts.load.height_scale,
        height_range_m: opts.load.height_range_m,
    };
    start_or_resume(out, &plan)?;
    if super::is_pyramid(out) {
        // Whole already: nothing to read or write.
        let meta = super::Pyramid::open(out)?.meta;
        return Ok(BuildSummary {
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
    let scratch = copy_sources(&sources, &scratch_dir, &opts.load)?;
    let (width, height, dx, dy, offsets, georef) = place(src, &sources, &scratch, &opts.load)?;
    let levels = level_sizes(width, height);
    let mut meta = Meta {
        format: FORMAT.into(),
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
                    level0_band(&meta, ty, &scratch_dir, &scratch, &offsets)?
                } else {
                    coarser_band(out, &meta, l, ty)?
                };
                write_band(out, &meta, l, ty, r0, &band, w, &missing, threads)?;
                written += missing.len();
            }
            progress.advance(tx_count as f64, &format!("level {l}, row {ty}"));
        }
    }
    progress.finish();
    finish_meta(out, &mut meta)?;
    write_atomic(&out.join(META), toml_text(&meta)?.as_bytes())?;
    let _ = std::fs::remove_dir_all(&scratch_dir);
    Ok(BuildSummary {
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

fn stamp(path: &Path) -> Result<SourceStamp> {
    let m = std::fs::metadata(path).map_err(|e| Error::io(Role::Sketch, path, e))?;
    let mtime_ns = m
        .modified()
        .ok()
        .and_then(|t| t.duration_since(std::time::UNIX_EPOCH).ok())
        .map_or(0, |d| d.as_nanos());
    Ok(SourceStamp {
        path: std::fs::canonicalize(path)
            .unwrap_or_else(|_| path.to_path_buf())
            .display()
            .to_string(),
        bytes: m.len(),
        mtime_ns,
    })
}

/// Creates `out` with its `build.json`, or checks that the one there is this build's.
fn start_or_resume(out: &Path, plan: &Plan) -> Result<()> {
    let recorded = out.join("build.json");
    match std::fs::read(&recorded) {
        Ok(bytes) => {
            let theirs: Plan = serde_json::from_slice(&bytes)
                .map_err(|e| Error::decode(Role::OutputFolder, &recorded, "a build record", e))?;
            if &theirs != plan {
                return Err(Error::file(
                    Role::OutputFolder,
                    out,
                    "holds a pyramid of other sources or options (build.json); remove it or \
                     choose another --out-dir",
                ));
            }
            Ok(())
        }
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            let occupied = std::fs::read_dir(out).is_ok_and(|mut d| d.next().is_some());
            if occupied {
                return Err(Error::file(
                    Role::OutputFolder,
                    out,
                    "is not empty and holds no build.json: not a pyramid to resume",
                ));
            }
            let json =
                serde_json::to_vec_pretty(plan).map_err(|e| Error::encode("build record", e))?;
            write_atomic(&recorded, &json)
        }
        Err(e) => Err(Error::io(Role::OutputFolder, &recorded, e)),
    }
}

/// Copies each source into scratch (one in memory at a time), or reads back what a run before
/// copied.
fn copy_sources(sources: &[PathBuf], dir: &Path, load: &LoadOptions) -> Result<Vec<Scratch>> {
    let mut progress = crate::progress::start("reading sources", Some(sources.len() as f64));
    let mut out = Vec::with_capacity(sources.len());
    for (k, path) in sources.iter().enumerate() {
        let info = dir.join(format!("src-{k}.json"));
        let done = std::fs::read(&info)
            .ok()
            .and_then(|b| serde_json::from_slice::<Scratch>(&b).ok());
        let scratch = match done {
            Some(s) => s,
            None => {
                let mut raw = read_grid(path, load)?;
                scale_heights(&mut raw.data, load).map_err(|e| match e {
                    Error::Value { reason, .. } => Error::sketch(path, reason),
                    e => e,
                })?;
                let mut bytes = Vec::with_capacity(raw.data.len() * 4);
                for h in &raw.data {
                    bytes.extend_from_slice(&h.to_le_bytes());
                }
                write_quietly(&dir.join(format!("src-{k}.f32")), &bytes)?;
                let s = Scratch {
                    width: raw.width,
                    height: raw.height,
                    dx: raw.dx,
                    dy: raw.dy,
                    georef: raw.georef.map(meta_georef),
                };
                let json =
                    serde_json::to_vec(&s).map_err(|e| Error::encode("scratch record", e))?;
                write_quietly(&info, &json)?;
                s
            }
        };
        out.push(scratch);
        progress.advance(1.0, &path.display().to_string());
    }
    progress.finish();
    Ok(out)
}

type Placed = (usize, usize, f64, f64, Vec<(usize, usize)>, Option<Georef>);

/// The mosaic's size, spacing and each source's offset, as [`crate::sketch`] places a glob.
fn place(
    src: &Path,
    sources: &[PathBuf],
    scratch: &[Scratch],
    load: &LoadOptions,
) -> Result<Placed> {
    let (width, height, offsets, georef, (dx, dy)) = if sources.len() == 1 {
        let s = &scratch[0];
        (
            s.width,
            s.height,
            vec![(0, 0)],
            s.georef.as_ref().map(georef_of),
            (s.dx, s.dy),
        )
    } else {
        let extents: Vec<TileExtent> = sources
            .iter()
            .zip(scratch)
            .map(|(path, s)| TileExtent {
                path,
                georef: s.georef.as_ref().map(georef_of),
                width: s.width,
                height: s.height,
            })
            .collect();
        let p = mosaic::place(src, &extents)?;
        // Resolved at the mosaic's size, as the in-memory mosaic's RawGrid::georeferenced does.
        let georef = p.georef.resolved(p.width, p.height);
        let spacing = georef.spacing_m(p.width, p.height);
        (p.width, p.height, p.offsets, Some(georef), spacing)
    };
    let (dx, dy) = load.spacing_m.map_or((dx, dy), |s| (s, s));
    if !(dx.is_finite() && dy.is_finite() && dx > 0.0 && dy > 0.0) {
        return Err(Error::sketch(
            src,
            format!("grid spacing {dx} × {dy} m is not positive and finite; set --spacing-m"),
        ));
    }
    Ok((width, height, dx, dy, offsets, georef))
}

/// Level 0's rows `ty·TILE − BORDER .. (ty+1)·TILE + BORDER` (clamped), filled: (first row, rows).
fn level0_band(
    meta: &Meta,
    ty: usize,
    dir: &Path,
    scratch: &[Scratch],
    offsets: &[(usize, usize)],
) -> Result<(usize, Vec<f32>)> {
    let (w, h) = (meta.width, meta.height);
    let (r0, r1) = band_rows(ty, h);
    let mut band = vec![f32::NAN; w * (r1 - r0)];
    let mut row = Vec::new();
    for (k, (s, &(x0, y0))) in scratch.iter().zip(offsets).enumerate() {
        let (lo, hi) = (r0.max(y0), r1.min(y0 + s.height));
        if lo >= hi {
            continue;
        }
        let path = dir.join(format!("src-{k}.f32"));
        let file = std::fs::File::open(&path).map_err(|e| Error::io(Role::Sketch, &path, e))?;
        row.resize(s.width * 4, 0u8);
        for r in lo..hi {
            file.read_exact_at(&mut row, ((r - y0) * s.width * 4) as u64)
                .map_err(|e| Error::io(Role::Sketch, &path, e))?;
            let dst = &mut band[(r - r0) * w + x0..(r - r0) * w + x0 + s.width];
            for (d, b) in dst.iter_mut().zip(row.chunks_exact(4)) {
                let v = f32::from_le_bytes(b.try_into().expect("4 bytes"));
                if v.is_finite() {
                    *d = v;
                }
            }
        }
    }
    Ok((r0, band))
}

/// Level l's rows of band `ty`, each the box average of two rows of level l−1 read from its tiles.
fn coarser_band(out: &Path, meta: &Meta, l: usize, ty: usize) -> Result<(usize, Vec<f32>)> {
    let [w, h] = meta.levels[l];
    let [fw, _] = meta.levels[l - 1];
    let (r0, r1) = band_rows(ty, h);
    let fine = read_rows(out, meta, l - 1, 2 * r0, 2 * r1)?;
    let mut band = Vec::with_capacity(w * (r1 - r0));
    for j in 0..r1 - r0 {
        for i in 0..w {
            let at = |x: usize, y: usize| fine[y * fw + x];
            let (x, y) = (2 * i, 2 * j);
            // The atlas's order of additions, so both pyramids agree bit for bit.
            band.push(0.25 * (at(x, y) + at(x + 1, y) + at(x, y + 1) + at(x + 1, y + 1)));
        }
    }
    Ok((r0, band))
}

/// Rows `r0..r1` of level `l`, whole width, from the interiors of its tiles.
pub(super) fn read_rows(
    out: &Path,
    meta: &Meta,
    l: usize,
    r0: usize,
    r1: usize,
) -> Result<Vec<f32>> {
    let [w, _] = meta.levels[l];
    let (tiles_x, _) = meta.tiles(l);
    let (t, b, side) = (meta.tile, meta.border, meta.tile + 2 * meta.border);
    let mut rows = vec![0f32; w * (r1 - r0)];
    for ty in r0 / t..=(r1 - 1) / t {
        for tx in 0..tiles_x {
            let heights = super::read::read_tile_file(&tile_path(out, l, tx, ty), side)?;
            let (lo, hi) = (r0.max(ty * t), r1.min(ty * t + t));
            let cols = t.min(w - tx * t);
            for r in lo..hi {
                let src = &heights[(r - ty * t + b) * side + b..][..cols];
                rows[(r - r0) * w + tx * t..][..cols].copy_from_slice(src);
            }
        }
    }
    Ok(rows)
}

/// The rows a band of tile row `ty` holds, clamped to a level of `h` rows.
fn band_rows(ty: usize, h: usize) -> (usize, usize) {
    let r0 = (ty * TILE).saturating_sub(BORDER);
    let r1 = ((ty + 1) * TILE + BORDER).min(h);
    (r0, r1)
}

/// Fills the band's nodata (level 0) and writes its `missing` tiles, encoded on `threads` threads.
#[allow(clippy::too_many_arguments)]
fn write_band(
    out: &Path,
    meta: &Meta,
    l: usize,
    ty: usize,
    r0: usize,
    band: &[f32],
    w: usize,
    missing: &[usize],
    threads: usize,
) -> Result<()> {
    let rows = band.len() / w;
    let mut filled;
    let mut nodata_mask = Vec::new();
    let band = if band.iter().any(|h| !h.is_finite()) {
        nodata_mask = band.iter().map(|h| !h.is_finite()).collect();
        filled = band.to_vec();
        fill::fill_nodata(&mut filled, w, rows);
        &filled[..]
    } else {
        band
    };
    let [_, h] = meta.levels[l];
    let dir = tile_path(out, l, 0, ty);
    let dir = dir.parent().expect("a tile has a folder");
    std::fs::create_dir_all(dir).map_err(|e| Error::io(Role::OutputFolder, dir, e))?;
    let chunk = missing.len().div_ceil(threads.max(1));
    std::thread::scope(|scope| {
        let jobs: Vec<_> = missing
            .chunks(chunk.max(1))
            .map(|txs| {
                let mask = &nodata_mask;
                scope.spawn(move || -> Result<()> {
                    let mut tile = vec![0f32; SIDE * SIDE];
                    for &tx in txs {
                        let (mut lo, mut hi, mut nodata) = (f32::INFINITY, f32::NEG_INFINITY, 0u32);
                        for j in 0..SIDE {
                            let gy = (ty * TILE + j).saturating_sub(BORDER).min(h - 1);
                            for i in 0..SIDE {
                                let gx = (tx * TILE + i).saturating_sub(BORDER).min(w - 1);
                                let k = (gy - r0) * w + gx;
                                let v = band[k];
                                tile[j * SIDE + i] = v;
                                let inside = (BORDER..BORDER + TILE).contains(&i)
                                    && (BORDER..BORDER + TILE).contains(&j)
                                    && tx * TILE + i - BORDER < w
                                    && ty * TILE + j - BORDER < h;
                                if inside {
                                    lo = lo.min(v);
                                    hi = hi.max(v);
                                    nodata += mask.get(k).copied().unwrap_or(false) as u32;
                                }
                            }
                        }
                        let bytes = encode_tile(&tile, SIDE, lo, hi, nodata);
                        write_quietly(&tile_path(out, l, tx, ty), &bytes)?;
                    }
                    Ok(())
                })
            })
            .collect();
        jobs.into_iter()
            .try_for_each(|j| j.join().expect("a tile encoder does not panic"))
    })
}

/// Whether a tile file is there and as long as its header says (a run killed mid-write leaves
/// only temporary names, but a disk that lost power may keep a short file).
fn tile_is_whole(path: &Path) -> bool {
    let Ok(file) = std::fs::File::open(path) else {
        return false;
    };
    let mut head = [0u8; HEADER_BYTES];
    if file.read_exact_at(&mut head, 0).is_err() {
        return false;
    }
    let len = file.metadata().map_or(0, |m| m.len());
    TileHeader::parse(path, &head).is_ok_and(|h| len == (HEADER_BYTES + h.payload) as u64)
}

/// Writes under a temporary name and renames; no fsync (tiles are many, and a killed process
/// loses nothing the kernel holds; a power loss is what [`tile_is_whole`] checks for).
fn write_quietly(path: &Path, bytes: &[u8]) -> Result<()> {
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir).map_err(|e| Error::io(Role::OutputFolder, dir, e))?;
    }
    let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("tile");
    let tmp = path.with_file_name(format!(".{name}.{}.tmp", std::process::id()));
    std::fs::write(&tmp, bytes)
        .and_then(|()| std::fs::rename(&tmp, path))
        .map_err(|e| {
            let _ = std::fs::remove_file(&tmp);
            Error::io(Role::Output, path, e)
        })
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
        let west_tile = super::read::read_tile_file(&tile_path(out, 0, 0, ty), SIDE)?;
        let east_tile = match tx_n {
            1 => west_tile.clone(),
            _ => super::read::read_tile_file(&tile_path(out, 0, tx_n - 1, ty), SIDE)?,
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

fn meta_georef(g: Georef) -> MetaGeoref {
    MetaGeoref {
        units: match g.units {
            Units::Degrees => "degrees".into(),
            Units::Linear(m) => format!("{m}"),
            Units::Unknown => "unknown".into(),
        },
        west: g.west,
        south: g.south,
        cell_x: g.cell_x,
        cell_y: g.cell_y,
        epsg: g.epsg,
    }
}

/// The inverse of `meta_georef`.
pub fn georef_of(m: &MetaGeoref) -> Georef {
    Georef {
        west: m.west,
        south: m.south,
        cell_x: m.cell_x,
        cell_y: m.cell_y,
        units: match m.units.as_str() {
            "degrees" => Units::Degrees,
            "unknown" => Units::Unknown,
            s => s.parse().map_or(Units::Unknown, Units::Linear),
        },
        epsg: m.epsg,
    }
}

fn folder_bytes(dir: &Path) -> u64 {
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
