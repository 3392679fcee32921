//! Level 0's sources, read band by band: a GeoTIFF (alone or under a VRT) window by window from
//! its own strips or tiles, anything else from a raw scratch copy.
//!
//! Rules:
//! - A single GeoTIFF is a mosaic of its own chunks: a band decodes only the chunk rows under
//!   its rows, and keeps the decoded rows the next band asks for, so each chunk is decoded once. What is held at once is a band, one
//!   chunk row and one decoded chunk, whatever the file's size; a chunk row beyond the cell limit
//!   ([`crate::sketch::max_cells`]) is refused with the command that rewrites the file tiled.
//! - A VRT's sources are placed as [`crate::sketch::mosaic::parse_vrt`] places them (later over
//!   earlier, a source's nodata skipped, its scale and offset applied, then the band's nodata),
//!   each band from the GeoTIFF sources' windows and the other sources' scratch copies.
//! - `sketch.height_scale` applies to each band as [`crate::sketch::scale_heights`] to the
//!   whole grid, cell by cell; its refusal (more than 1 % beyond ±1000 km) is checked on the sum
//!   over level 0, before the coarser levels.
//! - A cloud-optimised GeoTIFF's overviews are not read: every coarser level is averaged from
//!   level 0, so the pyramid does not depend on the resampling GDAL chose for them.
//!
//! Rejected alternative: a single GeoTIFF copied into a raw scratch file first, as a glob's tiles
//! are. Its windows are already addressable by row, and the copy is a second level 0 on disk
//! (16 GiB of f32 for a 65,536² file) written and read once more
//! (docs/decisions.md, “Single files read window by window”).

use super::scratch::{Placed, Scratch, copy_source, copy_sources, place, spacing};
use crate::error::{Error, Result, Role};
use crate::sketch::geotiff::{Windows as TiffWindows, open as open_tiff};
use crate::sketch::load::{Beyond, LoadOptions, RawGrid, scale_cells};
use crate::sketch::mosaic::{self, VrtSource};
use std::fs::File;
use std::io::BufReader;
use std::os::unix::fs::FileExt;
use std::path::{Path, PathBuf};

/// Whether `path` names a GeoTIFF (by its extension, as the readers tell formats).
pub(in crate::sketch::convert) fn is_tiff(path: &Path) -> bool {
    has_extension(path, &["tif", "tiff"])
}

fn has_extension(path: &Path, names: &[&str]) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| names.contains(&e.to_ascii_lowercase().as_str()))
}

/// Opens level 0's sources: a single GeoTIFF or a VRT read in bands, anything else copied to
/// scratch under `dir` first. Returns the sketch's size, spacing and georeference with them.
pub(super) fn open(
    src: &Path,
    sources: &[PathBuf],
    dir: &Path,
    load: &LoadOptions,
) -> Result<(Placed, Level0)> {
    let single = sources.len() == 1 && !mosaic::is_glob(src);
    if single && is_tiff(src) {
        let tiff = open_tiff(src)?;
        let (w, h) = (tiff.width, tiff.height);
        let grid = RawGrid::new(w, h, Vec::new(), tiff.georef);
        let (dx, dy) = spacing(src, (grid.dx, grid.dy), load)?;
        let part = Part::placed(Grid::Tiff(Box::new(tiff)), h, (0, 0));
        return Ok((
            (w, h, dx, dy, vec![(0, 0)], grid.georef),
            banded(vec![part], None, load),
        ));
    }
    if single && has_extension(src, &["vrt"]) {
        let plan = mosaic::read_vrt_plan(src)?;
        let (w, h) = (plan.width, plan.height);
        let mut parts = Vec::with_capacity(plan.sources.len());
        for (k, source) in plan.sources.iter().enumerate() {
            let (grid, sw, sh) = if is_tiff(&source.path) {
                let tiff = open_tiff(&source.path)?;
                let (sw, sh) = (tiff.width, tiff.height);
                (Grid::Tiff(Box::new(tiff)), sw, sh)
            } else {
                let s = copy_source(k, &source.path, dir, load, false)?;
                let path = dir.join(format!("src-{k}.f32"));
                (Grid::raw(path, &s), s.width, s.height)
            };
            let rects = source.rects(src, sw, sh)?;
            parts.push(Part::of_vrt(grid, sh, rects, (w, h), source.clone()));
        }
        let grid = RawGrid::new(w, h, Vec::new(), plan.georef);
        let (dx, dy) = spacing(src, (grid.dx, grid.dy), load)?;
        let level0 = banded(parts, plan.band_nodata, load);
        return Ok(((w, h, dx, dy, Vec::new(), grid.georef), level0));
    }
    let scratch = copy_sources(sources, dir, load)?;
    let placed = place(src, sources, &scratch, load)?;
    let parts = scratch
        .iter()
        .zip(&placed.4)
        .enumerate()
        .map(|(k, (s, &at))| {
            let path = dir.join(format!("src-{k}.f32"));
            Part::placed(Grid::raw(path, s), s.height, at)
        })
        .collect();
    let level0 = Level0 {
        parts,
        band_nodata: None,
        scale: None,
        beyond: Beyond::default(),
    };
    Ok((placed, level0))
}

/// Sources read in bands whose heights are scaled band by band.
fn banded(parts: Vec<Part>, band_nodata: Option<f64>, load: &LoadOptions) -> Level0 {
    Level0 {
        parts,
        band_nodata,
        scale: Some(load.clone()),
        beyond: Beyond::default(),
    }
}

/// A source grid read by rows.
pub(super) enum Grid {
    /// A GeoTIFF read window by window.
    Tiff(Box<TiffWindows<BufReader<File>>>),
    /// A raw f32 scratch file (row-major, row 0 south).
    Raw { path: PathBuf, width: usize },
}

impl Grid {
    pub(super) fn raw(path: PathBuf, s: &Scratch) -> Grid {
        Grid::Raw {
            path,
            width: s.width,
        }
    }

    fn width(&self) -> usize {
        match self {
            Grid::Tiff(t) => t.width,
            Grid::Raw { width, .. } => *width,
        }
    }

    /// Rows `lo..hi` from the south into `out`; `next` is the first row the next band asks for.
    fn rows_into(&mut self, lo: usize, hi: usize, next: usize, out: &mut [f32]) -> Result<()> {
        match self {
            Grid::Tiff(t) => t.rows_into(lo, hi, next, out),
            Grid::Raw { path, width } => {
                let path: &Path = path;
                let file = File::open(path).map_err(|e| Error::io(Role::Sketch, path, e))?;
                let mut bytes = vec![0u8; *width * (hi - lo) * 4];
                file.read_exact_at(&mut bytes, (lo * *width * 4) as u64)
                    .map_err(|e| Error::io(Role::Sketch, path, e))?;
                for (d, b) in out.iter_mut().zip(bytes.chunks_exact(4)) {
                    *d = f32::from_le_bytes(b.try_into().expect("4 bytes"));
                }
                Ok(())
            }
        }
    }
}

/// One source on level 0: its grid, the cells of it that land on the sketch, and where.
pub(super) struct Part {
    pub(super) grid: Grid,
    /// The source's columns `[0]..[1]` and rows `[2]..[3]` (from the south) that lie on the sketch.
    pub(super) clip: [usize; 4],
    /// Added to a source cell's column and row to give the sketch's.
    pub(super) shift: (i64, i64),
    /// A VRT source's nodata, scale and offset; `None`: the cell as it is (a glob's tile).
    pub(super) vrt: Option<VrtSource>,
}

impl Part {
    /// A source of `height` rows whose south-west node lies at (x0, y0) on the sketch.
    pub(super) fn placed(grid: Grid, height: usize, (x0, y0): (usize, usize)) -> Part {
        let width = grid.width();
        Part {
            grid,
            clip: [0, width, 0, height],
            shift: (x0 as i64, y0 as i64),
            vrt: None,
        }
    }

    /// A VRT source with rects `s` and `d` (offsets from the north) of a source of `height`
    /// rows on a VRT of `w` × `h`.
    pub(super) fn of_vrt(
        grid: Grid,
        height: usize,
        (s, d): ([i64; 4], [i64; 4]),
        (w, h): (usize, usize),
        source: VrtSource,
    ) -> Part {
        let (sw, sh) = (grid.width() as i64, height as i64);
        let (ox, oy) = (d[0] - s[0], (h as i64 - d[1]) - (sh - s[1]));
        // The source's rect, within the source and landing within the VRT.
        let x0 = s[0].max(0).max(-ox);
        let x1 = (s[0] + s[2]).min(sw).min(w as i64 - ox);
        let y0 = (sh - s[1] - s[3]).max(0).max(-oy);
        let y1 = (sh - s[1]).min(sh).min(h as i64 - oy);
        let clip = if x0 < x1 && y0 < y1 {
            [x0 as usize, x1 as usize, y0 as usize, y1 as usize]
        } else {
            [0; 4]
        };
        Part {
            grid,
            clip,
            shift: (ox, oy),
            vrt: Some(source),
        }
    }
}

/// Level 0's sources and what is applied to a band of them.
pub(super) struct Level0 {
    pub(super) parts: Vec<Part>,
    /// A VRT band's nodata.
    pub(super) band_nodata: Option<f64>,
    /// `sketch.height_scale`, applied per band (sources whose scratch copies are scaled already
    /// have `None`).
    pub(super) scale: Option<LoadOptions>,
    /// Heights found beyond ±1000 km in the bands' own rows so far.
    pub(super) beyond: Beyond,
}

impl Level0 {
    /// Rows `r0..r1` of a sketch `w` wide, the rows `own` among them counted for the height
    /// check (bands overlap by their borders); `next` is the first row of the band after it.
    pub(super) fn band(
        &mut self,
        w: usize,
        (r0, r1): (usize, usize),
        own: (usize, usize),
        next: usize,
    ) -> Result<Vec<f32>> {
        let mut band = vec![f32::NAN; w * (r1 - r0)];
        let mut rows = Vec::new();
        let single = self.parts.len() == 1;
        for part in &mut self.parts {
            let [x0, x1, y0, y1] = part.clip;
            let (ox, oy) = part.shift;
            let lo = (r0 as i64 - oy).max(y0 as i64);
            let hi = (r1 as i64 - oy).min(y1 as i64);
            if lo >= hi || x0 >= x1 {
                continue;
            }
            let (lo, hi) = (lo as usize, hi as usize);
            let next = (next as i64 - oy).max(0) as usize;
            let sw = part.grid.width();
            let whole = part.vrt.is_none() && (x0, x1, ox, sw) == (0, w, 0, w);
            if whole && single {
                // A single source as wide as the sketch: its rows are the band's.
                let at = (lo as i64 + oy) as usize - r0;
                part.grid
                    .rows_into(lo, hi, next, &mut band[at * w..(at + hi - lo) * w])?;
                continue;
            }
            rows.resize(sw * (hi - lo), 0.0);
            part.grid.rows_into(lo, hi, next, &mut rows)?;
            for r in lo..hi {
                let dst = ((r as i64 + oy) as usize - r0) * w;
                let src = &rows[(r - lo) * sw..(r - lo + 1) * sw];
                let dst = &mut band[dst..dst + w];
                for x in x0..x1 {
                    let v = src[x];
                    let d = &mut dst[(x as i64 + ox) as usize];
                    match &part.vrt {
                        None if v.is_finite() => *d = v,
                        None => {}
                        Some(s) => {
                            if let Some(v) = s.value(v) {
                                *d = v;
                            }
                        }
                    }
                }
            }
        }
        if let Some(nd) = self.band_nodata {
            for v in &mut band {
                if *v as f64 == nd || *v == nd as f32 {
                    *v = f32::NAN;
                }
            }
        }
        if let Some(load) = &self.scale {
            let (a, b) = ((own.0 - r0) * w, (own.1 - r0) * w);
            scale_cells(&mut band[..a], load)?;
            self.beyond.add(scale_cells(&mut band[a..b], load)?);
            scale_cells(&mut band[b..], load)?;
        }
        Ok(band)
    }
}
