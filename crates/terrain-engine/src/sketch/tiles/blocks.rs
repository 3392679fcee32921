//! GeoMipMap's per-block figures for a tile pyramid: each block's δ per level and height range,
//! measured once on level 0's tiles and kept beside them, so a streamed GeoMipMap chooses levels
//! for blocks whose heights were never in memory.
//!
//! Rules:
//! - The grid is GeoMipMap's at k = 0: spacing d = min(dx, dy), vertex (i, j) the bake's
//!   Catmull-Rom sample of level 0 at texel coordinates (i·d/dx, j·d/dy), taps clamped to the
//!   level, and never below the water's surface (`sketch.water_level_m`). A vertex past the
//!   sketch's last node lies on its edge, as the bake draws it. δ and the range follow
//!   [`crate::geomipmap::block_stats`], the rule the baked grid's blocks use, so both paths
//!   choose the same levels.
//! - Square cells, with blocks that divide the tile: every vertex is a node
//!   (min(i, W−1), min(j, H−1)), and a block lies inside one level-0 tile and its border, so
//!   each tile is read once.
//! - Otherwise a block row's vertices are sampled from the texel rows under it, read as a
//!   window (each tile then about tile·dy / (block·d) times).
//! - Either way on as many threads as the machine has.
//! - The figures are read back from `geomipmap-<block>.bin` in the pyramid folder whenever it is
//!   there and `pyramid.toml` and the water's level are unchanged. They are written there
//!   (atomically) only when the program asks ([`set_keep_figures`]; the `terrain` binary does):
//!   the library writes no file it was not asked to. A folder that cannot be written costs the
//!   measurement on every run, with a note.
//!
//! Rejected alternatives:
//! - Measuring δ in `terrain tiles` for every block size. The sizes a scene may ask for (17 to
//!   129 vertices) would cost four passes for the one a user flies, and a pyramid made before
//!   GeoMipMap could stream would have none.
//! - Asking for the file through an argument of `Renderer::new`: the measurement runs under
//!   every caller that builds a renderer from a scene, and whether a program may write into its
//!   sketch's folder is the program's choice, made once, like its logger.

use super::{META, Pyramid};
use crate::error::{Error, Result, Role};
use crate::geomipmap::{MAX_LEVELS, block_stats};
use std::hash::{Hash, Hasher};
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};

/// δ per level and the height range of every block, row by row.
#[derive(Clone, Debug, PartialEq)]
pub struct BlockStats {
    pub per_side: usize,
    pub cells: usize,
    pub delta: Vec<[f32; MAX_LEVELS]>,
    pub z_range: Vec<(f32, f32)>,
}

// Version 3: vertices past the edge on it (figures kept by version 2 are measured anew).
const MAGIC: &[u8; 8] = b"TGMMB\x003\n";

static KEEP: AtomicBool = AtomicBool::new(false);

/// Whether figures measured from now on are kept in their pyramid's folder for the next run
/// (off until a program turns it on).
pub fn set_keep_figures(keep: bool) {
    KEEP.store(keep, Ordering::Relaxed);
}

/// The figures of `per_side`² blocks of `cells` cells over `pyramid`'s level 0 with the water's
/// surface at `water` metres: from the folder's file when it matches, else measured (with
/// progress) and, when [`set_keep_figures`] asked, kept there.
pub fn block_stats_of(
    pyramid: &Pyramid,
    cells: usize,
    per_side: usize,
    water: f32,
) -> Result<BlockStats> {
    let path = cache_path(pyramid, cells);
    let key = meta_key(pyramid, water)?;
    if let Some(stats) = std::fs::read(&path)
        .ok()
        .and_then(|b| decode(&b, key, cells, per_side))
    {
        return Ok(stats);
    }
    let stats = measure(pyramid, cells, per_side, water)?;
    if KEEP.load(Ordering::Relaxed)
        && let Err(e) = crate::io::write_atomic(&path, &encode(&stats, key))
    {
        log::info!("GeoMipMap's block figures are measured again next run: {e}");
    }
    Ok(stats)
}

fn cache_path(pyramid: &Pyramid, cells: usize) -> PathBuf {
    pyramid.dir.join(format!("geomipmap-{}.bin", cells + 1))
}

/// A hash of `pyramid.toml` and the water's level: a pyramid converted again, or other water
/// (the grid's vertices stand on it), invalidates the figures. The standard library's hasher may
/// change between Rust releases; a new toolchain then measures once more.
fn meta_key(pyramid: &Pyramid, water: f32) -> Result<u64> {
    let path = pyramid.dir.join(META);
    let text = std::fs::read(&path).map_err(|e| Error::io(Role::Sketch, &path, e))?;
    let mut h = std::hash::DefaultHasher::new();
    text.hash(&mut h);
    water.to_bits().hash(&mut h);
    Ok(h.finish())
}

/// One block's δ per level and height range.
type Stats = ([f32; MAX_LEVELS], (f32, f32));

/// The grid's blocks of `cells` cells over `pyramid`'s level 0, `per_side` a side.
struct Layout<'a> {
    pyramid: &'a Pyramid,
    cells: usize,
    per_side: usize,
    /// The water's surface, which the grid's vertices never go below (as the bake's).
    water: f32,
}

impl Layout<'_> {
    /// The tile (along one axis) holding block `b`'s south-west vertex, clamped into a level
    /// whose last node is `last`.
    fn tile_of(&self, b: usize, last: usize) -> usize {
        (b * self.cells).min(last) / self.pyramid.meta.tile
    }

    /// The blocks of rows `rows` lying in tile (tx, ty), measured on that tile and its border.
    fn measure_tile(&self, tx: usize, ty: usize, rows: &[usize]) -> Result<Vec<(usize, Stats)>> {
        let m = &self.pyramid.meta;
        let (t, border, side) = (m.tile, m.border, self.pyramid.side());
        let [w, h] = m.levels[0];
        let levels = self.cells.trailing_zeros() as usize + 1;
        let heights = self.pyramid.tile(0, tx, ty)?;
        // Past the level's edge a vertex takes the edge node, as the GPU's clamped reads do.
        let z = |gi: usize, gj: usize| {
            let (i, j) = (gi.min(w - 1), gj.min(h - 1));
            heights[(j + border - ty * t) * side + i + border - tx * t].max(self.water)
        };
        let mut out = Vec::new();
        for &r in rows {
            for bx in (0..self.per_side).filter(|&b| self.tile_of(b, w - 1) == tx) {
                let (x0, y0) = (bx * self.cells, r * self.cells);
                let stats = block_stats(self.cells, levels, |i, j| z(x0 + i, y0 + j));
                out.push((r * self.per_side + bx, stats));
            }
        }
        Ok(out)
    }

    /// Tile row `ty`'s blocks of rows `rows`, its tiles split among `threads`.
    fn measure_row(
        &self,
        ty: usize,
        rows: &[usize],
        threads: usize,
    ) -> Result<Vec<(usize, Stats)>> {
        let (tiles_x, _) = self.pyramid.meta.tiles(0);
        let chunk = tiles_x.div_ceil(threads).max(1);
        let parts: Vec<_> = (0..tiles_x)
            .step_by(chunk)
            .map(|tx0| tx0..(tx0 + chunk).min(tiles_x))
            .collect();
        on_threads(parts, |tx| self.measure_tile(tx, ty, rows))
    }
}

/// Grid vertex heights sampled between nodes (cells that are not square), or from windows
/// (blocks that straddle tiles).
struct Strips<'a> {
    pyramid: &'a Pyramid,
    cells: usize,
    per_side: usize,
    /// Texel coordinates per metre of grid, as the bake's f32 `1 / dx`, `1 / dy`.
    inv: [f32; 2],
    /// The grid's spacing, metres.
    d: f64,
    water: f32,
    /// Each grid column's taps and weights along x, the same for every row.
    cols: Vec<([usize; 4], [f32; 4])>,
}

impl Strips<'_> {
    /// The Catmull-Rom taps and weights at grid index `i` along an axis of `len` nodes.
    fn taps(&self, i: usize, axis: usize, len: usize) -> ([usize; 4], [f32; 4]) {
        // Past the sketch's last node the bake draws the vertex on the edge (`on_sketch_edge` in
        // shaders/shared/frame.wgsl): the edge's f32 coordinate, as the shader computes it.
        let x = ((i as f64 * self.d) as f32).min((len - 1) as f32 / self.inv[axis]);
        let u = x * self.inv[axis];
        let f = u.floor();
        let at = |k: i64| (f as i64 - 1 + k).clamp(0, len as i64 - 1) as usize;
        (
            [at(0), at(1), at(2), at(3)],
            crate::sketch::cubic::catmull_rom(u - f),
        )
    }

    /// Block row `r`'s blocks, from the texel rows under its vertices.
    fn measure_row(&self, r: usize) -> Result<Vec<(usize, Stats)>> {
        let [w, h] = self.pyramid.meta.levels[0];
        let (c, n) = (self.cells, self.cells * self.per_side + 1);
        let rows: Vec<_> = (r * c..=r * c + c).map(|j| self.taps(j, 1, h)).collect();
        let y0 = rows[0].0[0];
        let y1 = rows[c].0[3];
        let texels = self.pyramid.window(0, 0, y0, w, y1 - y0 + 1)?;
        let mut strip = vec![0f32; (c + 1) * n];
        for (jj, (ty, wy)) in rows.iter().enumerate() {
            for (i, (tx, wx)) in self.cols.iter().enumerate() {
                let mut z = 0.0;
                for (y, wyb) in ty.iter().zip(wy) {
                    let row = &texels[(y - y0) * w..];
                    let line: f32 = tx.iter().zip(wx).map(|(&x, wxa)| wxa * row[x]).sum();
                    z += wyb * line;
                }
                strip[jj * n + i] = z.max(self.water);
            }
        }
        let levels = c.trailing_zeros() as usize + 1;
        Ok((0..self.per_side)
            .map(|bx| {
                let z = |i: usize, j: usize| strip[j * n + bx * c + i];
                (r * self.per_side + bx, block_stats(c, levels, z))
            })
            .collect())
    }

    /// Block rows `rows`, split among `threads`.
    fn measure_rows(
        &self,
        rows: std::ops::Range<usize>,
        threads: usize,
    ) -> Result<Vec<(usize, Stats)>> {
        let parts: Vec<_> = (0..threads)
            .map(|t| rows.clone().skip(t).step_by(threads))
            .collect();
        on_threads(parts, |r| self.measure_row(r))
    }
}

/// `each` over every index of every part, a thread per part, the results gathered.
fn on_threads<P, F>(parts: Vec<P>, each: F) -> Result<Vec<(usize, Stats)>>
where
    P: IntoIterator<Item = usize> + Send,
    F: Fn(usize) -> Result<Vec<(usize, Stats)>> + Sync,
{
    let each = &each;
    let results: Vec<Result<Vec<(usize, Stats)>>> = std::thread::scope(|s| {
        let handles: Vec<_> = parts
            .into_iter()
            .map(|part| {
                s.spawn(move || {
                    let mut out = Vec::new();
                    for k in part {
                        out.extend(each(k)?);
                    }
                    Ok(out)
                })
            })
            .collect();
        handles
            .into_iter()
            .map(|h| h.join().expect("a measuring thread does not panic"))
            .collect()
    });
    let mut all = Vec::new();
    for r in results {
        all.extend(r?);
    }
    Ok(all)
}

/// Measures every block on level 0's tiles.
pub fn measure(pyramid: &Pyramid, cells: usize, per_side: usize, water: f32) -> Result<BlockStats> {
    let m = &pyramid.meta;
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let mut stats = BlockStats {
        per_side,
        cells,
        delta: vec![[0.0f32; MAX_LEVELS]; per_side * per_side],
        z_range: vec![(0.0f32, 0.0f32); per_side * per_side],
    };
    let mut keep = |all: Vec<(usize, Stats)>| {
        for (k, (d, r)) in all {
            stats.delta[k] = d;
            stats.z_range[k] = r;
        }
    };
    // Between nodes, or blocks that straddle tiles: sampled from texel windows.
    if m.dx_m != m.dy_m || !m.tile.is_multiple_of(cells) {
        let mut strips = Strips {
            pyramid,
            cells,
            per_side,
            inv: [(1.0 / m.dx_m) as f32, (1.0 / m.dy_m) as f32],
            d: m.dx_m.min(m.dy_m),
            water,
            cols: Vec::new(),
        };
        strips.cols = (0..cells * per_side + 1)
            .map(|i| strips.taps(i, 0, m.levels[0][0]))
            .collect();
        let mut progress = crate::progress::start("GeoMipMap blocks", Some(per_side as f64));
        let batch = 16 * threads;
        for first in (0..per_side).step_by(batch) {
            let rows = first..(first + batch).min(per_side);
            keep(strips.measure_rows(rows.clone(), threads)?);
            progress.advance(rows.len() as f64, &format!("block row {}", rows.end - 1));
        }
        progress.finish();
    } else {
        let layout = Layout {
            pyramid,
            cells,
            per_side,
            water,
        };
        let last_row = m.levels[0][1] - 1;
        let (_, tiles_y) = m.tiles(0);
        let mut progress = crate::progress::start("GeoMipMap blocks", Some(tiles_y as f64));
        let mut next = 0;
        for ty in 0..tiles_y {
            let rows: Vec<usize> = (next..per_side)
                .take_while(|&r| layout.tile_of(r, last_row) == ty)
                .collect();
            next += rows.len();
            keep(layout.measure_row(ty, &rows, threads)?);
            progress.advance(1.0, &format!("tile row {ty}"));
        }
        progress.finish();
    }
    Ok(stats)
}

fn encode(s: &BlockStats, key: u64) -> Vec<u8> {
    let mut b = Vec::with_capacity(32 + s.delta.len() * (MAX_LEVELS + 2) * 4);
    b.extend_from_slice(MAGIC);
    b.extend_from_slice(&key.to_le_bytes());
    b.extend_from_slice(&(s.cells as u64).to_le_bytes());
    b.extend_from_slice(&(s.per_side as u64).to_le_bytes());
    for (d, r) in s.delta.iter().zip(&s.z_range) {
        for v in d.iter().chain([&r.0, &r.1]) {
            b.extend_from_slice(&v.to_le_bytes());
        }
    }
    b
}

/// The figures in `bytes` if they are whole and for this pyramid, cell count and grid.
fn decode(bytes: &[u8], key: u64, cells: usize, per_side: usize) -> Option<BlockStats> {
    let word = |i: usize| u64::from_le_bytes(bytes[8 + 8 * i..16 + 8 * i].try_into().unwrap());
    let n = per_side * per_side;
    let record = (MAX_LEVELS + 2) * 4;
    if bytes.len() != 32 + n * record
        || &bytes[..8] != MAGIC
        || word(0) != key
        || word(1) != cells as u64
        || word(2) != per_side as u64
    {
        return None;
    }
    let mut delta = Vec::with_capacity(n);
    let mut z_range = Vec::with_capacity(n);
    for rec in bytes[32..].chunks_exact(record) {
        let v: Vec<f32> = rec
            .chunks_exact(4)
            .map(|c| f32::from_le_bytes(c.try_into().unwrap()))
            .collect();
        if v.iter().any(|x| !x.is_finite()) {
            return None;
        }
        delta.push(v[..MAX_LEVELS].try_into().unwrap());
        z_range.push((v[MAX_LEVELS], v[MAX_LEVELS + 1]));
    }
    Some(BlockStats {
        per_side,
        cells,
        delta,
        z_range,
    })
}
