//! Reading a tile pyramid: its `pyramid.toml`, single tiles and windows, whole levels, and the
//! streamed sketch a scene gets from it.
//!
//! Rules:
//! - A scene whose `sketch.path` names a pyramid folder gets a streamed atlas
//!   (`sketch::streamed`) over a [`Pyramid`]: the pyramid's true geometry, its coarse levels in
//!   memory within `stream.cpu_mb`, the finer ones left to the tile cache ([`super::cache`]).
//! - A pyramid inside a mosaic is read as a grid ([`raw_grid`]): level 0 when it fits the cell
//!   limit ([`crate::sketch::max_cells`]); otherwise the finest level that fits stands in, with its
//!   spacing, and a note on stderr says which. The stand-in's nodes lie where that level's
//!   centres do: `(2^l − 1)/2` level-0 cells north-east of level 0's south-west node; its
//!   georeference says so.
//! - Every tile is checked as it is read: its header, length, checksum and side; a missing tile is
//!   an error naming it.

use super::codec::decode_tile;
use super::{FORMAT, Kind, META, Meta, level_sizes, tile_path};
use crate::error::{Error, Result, Role};
use crate::sketch::grid::{LoadOptions, RawGrid, max_cells};
use crate::sketch::pyramid::{Level, bilinear_blend, bilinear_cell};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

/// Tiles the point queries ([`Pyramid::bilinear`]) keep decoded. The ground under a moving
/// camera stays in one tile for 256 nodes (7.7 km at 30 m), and a sample reads a single tile, so
/// a few suffice: reading and decoding a tile costs thousands of queries on a kept one
/// (docs/decisions.md, “Recent tiles kept decoded”).
const RECENT_TILES: usize = 4;

/// A decoded tile of level `.0`, column `.1`, row `.2`.
type Recent = Vec<((usize, usize, usize), Arc<Vec<f32>>)>;

/// An opened pyramid folder.
#[derive(Clone, Debug)]
pub struct Pyramid {
    /// The pyramid's folder, holding `pyramid.toml` and the tiles.
    pub dir: PathBuf,
    /// Its `pyramid.toml`.
    pub meta: Meta,
    /// The tiles point queries read last, most recent first (shared by clones).
    recent: Arc<Mutex<Recent>>,
}

impl Pyramid {
    /// Reads and checks `DIR/pyramid.toml`.
    pub fn open(dir: &Path) -> Result<Pyramid> {
        let path = dir.join(META);
        let kind = super::kind_of(&path, Role::Sketch)?;
        if kind != Kind::Heights {
            return Err(Error::sketch(
                &path,
                format!(
                    "the pyramid holds {} (kind = \"image\"), not heights: give it as \
                     surface.image, and sketch.path a height map",
                    kind.noun()
                ),
            ));
        }
        let text = std::fs::read_to_string(&path).map_err(|e| Error::io(Role::Sketch, &path, e))?;
        let meta: Meta = toml::from_str(&text)
            .map_err(|e| Error::decode(Role::Sketch, &path, "a pyramid.toml", e))?;
        let bad = |why: String| Error::sketch(&path, why);
        if meta.format != FORMAT {
            return Err(bad(format!(
                "format is {:?}; this terrain reads {FORMAT:?}: convert the source again",
                meta.format
            )));
        }
        if meta.width < 2 || meta.height < 2 || meta.levels != level_sizes(meta.width, meta.height)
        {
            return Err(bad(format!(
                "levels do not follow from a {}×{} grid",
                meta.width, meta.height
            )));
        }
        // A border of two nodes lets a sample read one tile: a bilinear one here, a bicubic one
        // (floor − 1 to floor + 2, half a texel off on an ancestor level) on the GPU.
        if !(16..=4096).contains(&meta.tile) || !(2..=8).contains(&meta.border) {
            return Err(bad(format!(
                "tile {} with border {} is not a layout this terrain writes",
                meta.tile, meta.border
            )));
        }
        let spacing_ok = |d: f64| d.is_finite() && d > 0.0;
        if !(spacing_ok(meta.dx_m) && spacing_ok(meta.dy_m)) {
            return Err(bad(format!(
                "spacing {} × {} m is not positive and finite",
                meta.dx_m, meta.dy_m
            )));
        }
        if !(meta.min_m.is_finite() && meta.max_m.is_finite() && meta.min_m <= meta.max_m) {
            return Err(bad("height range is not finite".into()));
        }
        Ok(Pyramid {
            dir: dir.to_path_buf(),
            meta,
            recent: Arc::default(),
        })
    }

    /// Stored nodes per tile side.
    pub fn side(&self) -> usize {
        self.meta.tile + 2 * self.meta.border
    }

    /// Tile (tx, ty) of level `l`, border included, row-major, row 0 south.
    pub fn tile(&self, l: usize, tx: usize, ty: usize) -> Result<Vec<f32>> {
        read_tile_file(&tile_path(&self.dir, l, tx, ty), self.side())
    }

    /// Level `l` whole, from its tiles' interiors.
    pub fn level(&self, l: usize) -> Result<Level> {
        let [width, height] = self.meta.levels[l];
        let data = read_rows(&self.dir, &self.meta, l, 0, height)?;
        Ok(Level {
            width,
            height,
            data,
        })
    }

    /// Level `l`'s central window of at most `side`² nodes, as a level of its own: what a
    /// measurement of a level too large for memory reads (the relief, the curvature).
    pub fn central_window(&self, l: usize, side: usize) -> Result<Level> {
        let [w, h] = self.meta.levels[l];
        let (ww, wh) = (w.min(side), h.min(side));
        let data = self.window(l, (w - ww) / 2, (h - wh) / 2, ww, wh)?;
        Ok(Level {
            width: ww,
            height: wh,
            data,
        })
    }

    /// Nodes `x0 .. x0 + w` × `y0 .. y0 + h` of level `l` (inside the level), row-major, from the
    /// interiors of the tiles that hold them.
    pub fn window(&self, l: usize, x0: usize, y0: usize, w: usize, h: usize) -> Result<Vec<f32>> {
        let (t, b, side) = (self.meta.tile, self.meta.border, self.side());
        let mut out = vec![0f32; w * h];
        for ty in y0 / t..=(y0 + h - 1) / t {
            for tx in x0 / t..=(x0 + w - 1) / t {
                let heights = self.tile(l, tx, ty)?;
                let (c0, c1) = (x0.max(tx * t), (x0 + w).min(tx * t + t));
                for r in y0.max(ty * t)..(y0 + h).min(ty * t + t) {
                    let src = &heights[(r - ty * t + b) * side + b + c0 - tx * t..][..c1 - c0];
                    out[(r - y0) * w + c0 - x0..][..c1 - c0].copy_from_slice(src);
                }
            }
        }
        Ok(out)
    }

    /// Height at level `l`'s node coordinates (x, y), bilinear, clamped to the level: the nodes
    /// come from the one tile holding (x, y) (its border holds the next node), and the rule is
    /// `Level::bilinear`'s (`sketch::bilinear_cell`), so it equals the level held in
    /// memory bit for bit.
    pub fn bilinear(&self, l: usize, x: f64, y: f64) -> Result<f32> {
        let [w, h] = self.meta.levels[l];
        let (t, b, side) = (self.meta.tile, self.meta.border, self.side());
        let ((i, j), f) = bilinear_cell(x, y, w, h);
        let (tx, ty) = (i / t, j / t);
        let heights = self.recent_tile(l, tx, ty)?;
        let at = |i: usize, j: usize| heights[(j - ty * t + b) * side + i - tx * t + b];
        let z = [[at(i, j), at(i + 1, j)], [at(i, j + 1), at(i + 1, j + 1)]];
        Ok(bilinear_blend(z, f))
    }

    /// Node (i, j) of level `l` (inside the level), from the recent tiles.
    pub fn node(&self, l: usize, i: usize, j: usize) -> Result<f32> {
        let (t, b, side) = (self.meta.tile, self.meta.border, self.side());
        let (tx, ty) = (i / t, j / t);
        let heights = self.recent_tile(l, tx, ty)?;
        Ok(heights[(j - ty * t + b) * side + i - tx * t + b])
    }

    /// Tile (tx, ty) of level `l` from the recent tiles, or read and kept there.
    fn recent_tile(&self, l: usize, tx: usize, ty: usize) -> Result<Arc<Vec<f32>>> {
        let key = (l, tx, ty);
        // A poisoned lock only means another query panicked; the tiles it holds are whole.
        let mut recent = self.recent.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(k) = recent.iter().position(|(k, _)| *k == key) {
            let hit = recent.remove(k);
            recent.insert(0, hit.clone());
            return Ok(hit.1);
        }
        let heights = Arc::new(self.tile(l, tx, ty)?);
        recent.truncate(RECENT_TILES - 1);
        recent.insert(0, (key, heights.clone()));
        Ok(heights)
    }

    /// The finest level with at most `cells` nodes.
    pub fn finest_fitting(&self, cells: usize) -> usize {
        self.meta
            .levels
            .iter()
            .position(|[w, h]| (*w as u128) * (*h as u128) <= cells as u128)
            .unwrap_or(self.meta.levels.len() - 1)
    }
}

/// A tile file's heights, checked to hold `side`² of them.
pub fn read_tile_file(path: &Path, side: usize) -> Result<Vec<f32>> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(Role::Sketch, path, e))?;
    let (header, heights) = decode_tile(path, &bytes)?;
    if header.side != side {
        return Err(Error::sketch(
            path,
            format!("tile is {}² nodes; its pyramid's are {side}²", header.side),
        ));
    }
    Ok(heights)
}

/// A pyramid as a sketch grid: level 0, or the finest level that fits the cell limit.
pub fn raw_grid(dir: &Path, _opts: &LoadOptions) -> Result<RawGrid> {
    raw_grid_within(dir, max_cells())
}

/// A pyramid as a sketch grid of at most `cells` nodes (its level 0 when that fits).
pub fn raw_grid_within(dir: &Path, cells: usize) -> Result<RawGrid> {
    let pyramid = Pyramid::open(dir)?;
    let l = pyramid.finest_fitting(cells);
    let level = pyramid.level(l)?;
    let m = &pyramid.meta;
    let scale = (1u64 << l) as f64;
    if l > 0 {
        log::info!(
            "sketch {}: {}×{} nodes exceed the in-memory limit of {} cells; level {l} \
             ({}×{}, {:.3} m spacing) stands in",
            dir.display(),
            m.width,
            m.height,
            cells,
            level.width,
            level.height,
            m.dx_m * scale
        );
    }
    let georef = m.georef.as_ref().map(|g| {
        let g = g.georef();
        let shift = (scale - 1.0) * 0.5;
        crate::sketch::georef::Georef {
            west: g.west + shift * g.cell_x,
            south: g.south + shift * g.cell_y,
            cell_x: g.cell_x * scale,
            cell_y: g.cell_y * scale,
            ..g
        }
    });
    Ok(RawGrid {
        width: level.width,
        height: level.height,
        dx: m.dx_m * scale,
        dy: m.dy_m * scale,
        data: level.data,
        georef,
    })
}

/// Rows `r0..r1` of level `l`, whole width, from the interiors of its tiles.
pub(crate) fn read_rows(
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
            let heights = read_tile_file(&tile_path(out, l, tx, ty), side)?;
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
