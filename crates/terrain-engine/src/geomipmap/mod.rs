//! GeoMipMapping (de Boer) over a baked grid: the baseline the warped mode is measured against.
//!
//! Rules:
//! - The baked grid holds the terrain function (sketch plus octaves up to K) at spacing
//!   `d_atlas / 2^K`, `c·B + 1` vertices a side for blocks of `c` cells (`geomipmap.block` − 1:
//!   16, 32, 64 or 128); block (bx, by) owns vertices `[c·bx, c·bx + c] × [c·by, c·by + c]`
//!   (neighbours share their edge).
//! - Level l draws every `2^l`-th vertex (l = 0..log2 c). δ_l is the largest vertical distance between
//!   a level-0 vertex and the level-l surface (cells split along (i, j)–(i+s, j+s), as drawn), raised
//!   to at least twice δ_{l−1}; `D_l = δ_l · f_px / τ` (de Boer's equations 1–2). The doubling
//!   over-estimates errors (τ still holds) and gives every level a distance range to morph over.
//! - A visible block takes the coarsest level with `D_l ≤ d`. `d` is the distance from the eye to
//!   the block's box (de Boer's horizontal-camera simplification) or, with `exact`, the box's
//!   least depth along the view axis over the secant of the half-diagonal field of view, which
//!   bounds every projected error by τ.
//! - Stitching: a block whose neighbour is coarser draws the shared edge with the neighbour's
//!   vertices only, as a zipper between the edge and the first inner row; templates per
//!   (level, neighbour level) are built once. A finer neighbour stitches itself, so no T-junction.
//! - Geomorphing (Wagner): a vertex that level l+1 drops moves toward the midpoint of its two
//!   level-(l+1) neighbours as its own distance goes from `start = D_l + the block's diameter` to
//!   `end = D_{l+1}`: unmorphed when the block arrives at level l, fully morphed when it leaves.
//!   Where D_{l+1} − D_l is shorter than a block, there is no room, and the morph is a step. Edge vertices use parameters shared by both blocks of the edge (the
//!   coarser one's, or the smaller of two equal ones), so the border follows the coarser neighbour.
//!
//! The jobs, one module each: the grid, its blocks and δ (here); culling and level choice
//! (`select`); stitching templates (`templates`); the CPU twin of the morphing vertex shader
//! (`morph`).

mod morph;
mod select;
mod templates;

#[cfg(test)]
pub use morph::morphed_height;
#[cfg(test)]
pub use select::choose_level;
pub use select::{BlockGpu, LodParams, Selection};
pub use templates::Templates;

use glam::{DVec2, DVec3};

/// Where in [D_l, D_{l+1}] the morph toward level l+1 begins.
pub const MORPH_START: f64 = 0.7;
#[cfg(test)]
/// Cells per block side by default (blocks of 33 vertices); 16, 32, 64 and 128 are allowed.
pub const DEFAULT_CELLS: usize = 32;
/// Levels of the largest block (128 cells: levels 0..=7).
pub const MAX_LEVELS: usize = 8;

/// The baked grid's heights and where it lies.
#[derive(Clone, Debug)]
pub struct Grid {
    /// Vertices per side: cells·blocks + 1.
    pub n: usize,
    /// Cells per block side (a power of two, 16..=128).
    pub cells: usize,
    pub spacing: f64,
    /// World position of vertex (0, 0).
    pub origin: DVec2,
    /// The baked heights, row by row; empty for a grid over a tile pyramid, whose vertices are
    /// read on the GPU (so [`Grid::z`] and what reads it are for baked grids). Shared with the
    /// bake, which renderers of one terrain share.
    pub heights: std::sync::Arc<[f32]>,
}

impl Grid {
    pub fn blocks_per_side(&self) -> usize {
        (self.n - 1) / self.cells
    }
    /// Levels per block: 0 (every vertex) to log2(cells) (the corners only).
    pub fn levels(&self) -> usize {
        self.cells.trailing_zeros() as usize + 1
    }
    /// Bits of the block-local vertex number in an index; the block's slot takes the rest.
    pub fn slot_shift(&self) -> u32 {
        let side = (self.cells + 1) as u32;
        32 - (side * side - 1).leading_zeros()
    }
    pub fn z(&self, i: usize, j: usize) -> f32 {
        self.heights[j * self.n + i]
    }
    pub fn world(&self, i: usize, j: usize) -> DVec3 {
        (self.origin + DVec2::new(i as f64, j as f64) * self.spacing).extend(self.z(i, j) as f64)
    }
    /// Height of the level-`l` surface at vertex (i, j) (not morphed).
    pub fn level_height(&self, i: usize, j: usize, l: usize) -> f32 {
        level_height(|i, j| self.z(i, j), self.n - 1, i, j, l)
    }
}

/// Height of the level-`l` surface at vertex (i, j) of a grid whose last vertex is `last` and
/// whose heights `z` gives: the level's cells split along (i, j)–(i+s, j+s), as drawn.
pub fn level_height(
    z: impl Fn(usize, usize) -> f32,
    last: usize,
    i: usize,
    j: usize,
    l: usize,
) -> f32 {
    let s = 1 << l;
    let (ci, cj) = ((i / s) * s, (j / s) * s);
    let (fx, fy) = ((i - ci) as f32 / s as f32, (j - cj) as f32 / s as f32);
    if fx == 0.0 && fy == 0.0 {
        return z(i, j);
    }
    let (i1, j1) = ((ci + s).min(last), (cj + s).min(last));
    let (z00, z11) = (z(ci, cj), z(i1, j1));
    if fx >= fy {
        let z10 = z(i1, cj);
        z00 + fx * (z10 - z00) + fy * (z11 - z10)
    } else {
        let z01 = z(ci, j1);
        z00 + fy * (z01 - z00) + fx * (z11 - z01)
    }
}

/// δ per level and the height range of one block of `cells` cells and `levels` levels, from its
/// vertices' heights `z(i, j)`, (i, j) in 0..=cells (level cells never cross a block's edge:
/// blocks start at multiples of `cells`, a multiple of every level's step).
pub fn block_stats(
    cells: usize,
    levels: usize,
    z: impl Fn(usize, usize) -> f32,
) -> ([f32; MAX_LEVELS], (f32, f32)) {
    let mut delta = [0.0f32; MAX_LEVELS];
    let mut range = (f32::INFINITY, f32::NEG_INFINITY);
    for j in 0..=cells {
        for i in 0..=cells {
            let h = z(i, j);
            range = (range.0.min(h), range.1.max(h));
            for (l, d) in delta.iter_mut().enumerate().take(levels).skip(1) {
                *d = d.max((h - level_height(&z, cells, i, j, l)).abs());
            }
        }
    }
    // At least double per level (an over-estimate, so τ still holds): each level then spans a
    // distance range at least as long as the one before, room to morph in.
    for l in 2..levels {
        delta[l] = delta[l].max(2.0 * delta[l - 1]);
    }
    (delta, range)
}

/// Per block: δ per level and the box of its vertices.
#[derive(Clone, Debug)]
pub struct Blocks {
    pub per_side: usize,
    pub cells: usize,
    pub levels: usize,
    /// Grid spacing, metres (for the blocks' diameters).
    pub spacing: f64,
    pub delta: Vec<[f32; MAX_LEVELS]>,
    pub z_range: Vec<(f32, f32)>,
    /// Quadtree over blocks: levels of boxes, coarsest last.
    tree: Vec<Vec<(f32, f32)>>,
}

impl Blocks {
    pub fn new(grid: &Grid) -> Blocks {
        let b = grid.blocks_per_side();
        let (c, levels) = (grid.cells, grid.levels());
        let (delta, z_range) = (0..b * b)
            .map(|k| {
                let (x0, y0) = ((k % b) * c, (k / b) * c);
                block_stats(c, levels, |i, j| grid.z(x0 + i, y0 + j))
            })
            .unzip();
        Blocks::from_stats(b, c, grid.spacing, delta, z_range)
    }

    /// Blocks of `cells` cells, `per_side` a side, from each block's δ and height range
    /// ([`block_stats`]), row by row: builds the culling quadtree.
    pub fn from_stats(
        per_side: usize,
        cells: usize,
        spacing: f64,
        delta: Vec<[f32; MAX_LEVELS]>,
        z_range: Vec<(f32, f32)>,
    ) -> Blocks {
        let (b, c, levels) = (per_side, cells, cells.trailing_zeros() as usize + 1);
        let mut tree = vec![z_range.clone()];
        let mut side = b;
        while side > 1 {
            let prev = tree.last().expect("tree has a base");
            let next_side = side.div_ceil(2);
            let mut level = vec![(f32::INFINITY, f32::NEG_INFINITY); next_side * next_side];
            for y in 0..side {
                for x in 0..side {
                    let (lo, hi) = prev[y * side + x];
                    let p = &mut level[(y / 2) * next_side + x / 2];
                    *p = (p.0.min(lo), p.1.max(hi));
                }
            }
            tree.push(level);
            side = next_side;
        }
        Blocks {
            per_side: b,
            cells: c,
            levels,
            spacing,
            delta,
            z_range,
            tree,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn templates_cover_each_block_exactly_once_for_every_size_and_neighbour_level() {
        for c in [16, 32, 64, 128] {
            let grid = Grid {
                n: c + 1,
                cells: c,
                spacing: 1.0,
                origin: DVec2::ZERO,
                heights: vec![0.0; (c + 1) * (c + 1)].into(),
            };
            let t = Templates::new(&grid);
            let levels = grid.levels();
            for l in 0..levels {
                for nl in l..levels {
                    let g = BlockGpu {
                        level: l as u32,
                        side_level: [nl as u32; 4],
                        ..Default::default()
                    };
                    let mut idx = Vec::new();
                    t.append(&[g], &mut idx);
                    let area: f64 = idx
                        .chunks_exact(3)
                        .map(|tri| {
                            let p: Vec<(f64, f64)> = tri
                                .iter()
                                .map(|&v| {
                                    ((v as usize % (c + 1)) as f64, (v as usize / (c + 1)) as f64)
                                })
                                .collect();
                            let a = 0.5
                                * ((p[1].0 - p[0].0) * (p[2].1 - p[0].1)
                                    - (p[2].0 - p[0].0) * (p[1].1 - p[0].1));
                            assert!(
                                a > 0.0,
                                "{c} cells, level {l}/{nl}: triangle {tri:?} not counter-clockwise"
                            );
                            a
                        })
                        .sum();
                    assert!(
                        (area - (c * c) as f64).abs() < 1e-9,
                        "{c} cells, level {l} beside {nl}: area {area}"
                    );
                }
            }
            assert!(((c + 1) * (c + 1)) as u32 <= 1 << grid.slot_shift());
        }
    }
}
