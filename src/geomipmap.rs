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
//! Rejected alternative: one index buffer per (level, four neighbour levels): 2,275 buffers of up
//! to 6k indices. Interior plus four edge strips needs 6 + 84 small templates.

use crate::camera::{Camera, Plane};
use glam::{DVec2, DVec3};

/// Where in [D_l, D_{l+1}] the morph toward level l+1 begins.
pub const MORPH_START: f64 = 0.7;
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
    pub heights: Vec<f32>,
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
        let s = 1 << l;
        let (ci, cj) = ((i / s) * s, (j / s) * s);
        let (fx, fy) = ((i - ci) as f32 / s as f32, (j - cj) as f32 / s as f32);
        if fx == 0.0 && fy == 0.0 {
            return self.z(i, j);
        }
        let (i1, j1) = ((ci + s).min(self.n - 1), (cj + s).min(self.n - 1));
        let (z00, z11) = (self.z(ci, cj), self.z(i1, j1));
        if fx >= fy {
            let z10 = self.z(i1, cj);
            z00 + fx * (z10 - z00) + fy * (z11 - z10)
        } else {
            let z01 = self.z(ci, j1);
            z00 + fy * (z01 - z00) + fx * (z11 - z01)
        }
    }
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
        let mut delta = vec![[0.0f32; MAX_LEVELS]; b * b];
        let mut z_range = vec![(f32::INFINITY, f32::NEG_INFINITY); b * b];
        for by in 0..b {
            for bx in 0..b {
                let k = by * b + bx;
                for j in by * c..=by * c + c {
                    for i in bx * c..=bx * c + c {
                        let z = grid.z(i, j);
                        z_range[k].0 = z_range[k].0.min(z);
                        z_range[k].1 = z_range[k].1.max(z);
                        for (l, d) in delta[k].iter_mut().enumerate().take(levels).skip(1) {
                            *d = d.max((z - grid.level_height(i, j, l)).abs());
                        }
                    }
                }
                // At least double per level (an over-estimate, so τ still holds): each level then
                // spans a distance range at least as long as the one before, room to morph in.
                for l in 2..levels {
                    delta[k][l] = delta[k][l].max(2.0 * delta[k][l - 1]);
                }
            }
        }
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
            spacing: grid.spacing,
            delta,
            z_range,
            tree,
        }
    }
}

/// How levels are chosen.
#[derive(Clone, Copy, Debug)]
pub struct LodParams {
    /// τ, pixels.
    pub tau: f64,
    /// Least depth along the view axis (τ guaranteed) instead of de Boer's distance.
    pub exact: bool,
    pub morph: bool,
    /// Vertical reach of detail not in the grid, widening the boxes (metres).
    pub reach_m: f64,
}

/// A visible block as the GPU sees it (`shaders/terrain.wgsl`'s `Block`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
pub struct BlockGpu {
    pub origin: [u32; 2],
    pub level: u32,
    pub pad: u32,
    /// The level governing each edge's vertices: S, E, N, W.
    pub side_level: [u32; 4],
    /// Own morph range: start, end (metres of eye distance); the interior's morph factor; pad.
    pub morph: [f32; 4],
    pub side_start: [f32; 4],
    pub side_end: [f32; 4],
}

/// The blocks drawn this frame.
#[derive(Clone, Debug, Default)]
pub struct Selection {
    /// Level per block; `u8::MAX` when culled.
    pub level: Vec<u8>,
    pub visible: Vec<usize>,
    pub gpu: Vec<BlockGpu>,
    /// The distance each block's level was chosen by (empty when levels were set by hand).
    pub distance: Vec<f64>,
}

/// Distance used for block `k`'s level: to its box, or its least depth along the view axis.
fn block_distance(grid: &Grid, blocks: &Blocks, k: usize, cam: &Camera, p: &LodParams) -> f64 {
    let (lo, hi) = box_of(grid, blocks, k, p.reach_m);
    if p.exact {
        // A vertical error δ at depth z shows at most f_px·δ·sec(half-diagonal fov)/z pixels
        // anywhere in the image (its shift along the view axis moves off-axis points too), so
        // the least depth over the box's corners, divided by that secant, bounds every error.
        let secant = (1.0 + cam.tan_half_x().powi(2) + cam.tan_half_y().powi(2)).sqrt();
        let mut least = f64::INFINITY;
        for c in 0..8 {
            let q = DVec3::new(
                if c & 1 == 0 { lo.x } else { hi.x },
                if c & 2 == 0 { lo.y } else { hi.y },
                if c & 4 == 0 { lo.z } else { hi.z },
            );
            least = least.min((q - cam.eye).dot(cam.forward));
        }
        least / secant
    } else {
        (cam.eye.clamp(lo, hi) - cam.eye).length()
    }
}

fn box_of(grid: &Grid, blocks: &Blocks, k: usize, reach: f64) -> (DVec3, DVec3) {
    let (bx, by) = (k % blocks.per_side, k / blocks.per_side);
    let z = blocks.z_range[k];
    let size = blocks.cells as f64 * grid.spacing;
    let lo = grid.origin + DVec2::new(bx as f64, by as f64) * size;
    (
        lo.extend(z.0 as f64 - reach),
        (lo + DVec2::splat(size)).extend(z.1 as f64 + reach),
    )
}

fn box_visible(planes: &[Plane; 5], lo: DVec3, hi: DVec3) -> bool {
    planes.iter().all(|pl| {
        let p = DVec3::new(
            if pl.n.x >= 0.0 { hi.x } else { lo.x },
            if pl.n.y >= 0.0 { hi.y } else { lo.y },
            if pl.n.z >= 0.0 { hi.z } else { lo.z },
        );
        pl.distance(p) >= 0.0
    })
}

/// `D_l` of block `k`.
pub fn d_of(blocks: &Blocks, k: usize, l: usize, f_px: f64, tau: f64) -> f64 {
    blocks.delta[k][l] as f64 * f_px / tau
}

/// The coarsest level whose D is within `d`.
pub fn choose_level(blocks: &Blocks, k: usize, d: f64, f_px: f64, tau: f64) -> usize {
    (0..blocks.levels)
        .rev()
        .find(|&l| d_of(blocks, k, l, f_px, tau) <= d)
        .unwrap_or(0)
}

impl Selection {
    /// Culls with the quadtree, chooses levels, and fills the GPU's block records.
    pub fn select(&mut self, grid: &Grid, blocks: &Blocks, cam: &Camera, p: &LodParams) {
        let b = blocks.per_side;
        self.level.clear();
        self.level.resize(b * b, u8::MAX);
        self.visible.clear();
        let planes = cam.planes();
        let top = blocks.tree.len() - 1;
        let mut stack = vec![(top, 0usize, 0usize)];
        while let Some((depth, x, y)) = stack.pop() {
            let side = tree_side(b, depth);
            if x >= side || y >= side {
                continue;
            }
            let span = 1usize << depth;
            let z = blocks.tree[depth][y * side + x];
            let size = (span * blocks.cells) as f64 * grid.spacing;
            let lo = grid.origin + DVec2::new(x as f64, y as f64) * size;
            let (blo, bhi) = (
                lo.extend(z.0 as f64 - p.reach_m),
                (lo + DVec2::splat(size)).extend(z.1 as f64 + p.reach_m),
            );
            if !box_visible(&planes, blo, bhi) {
                continue;
            }
            if depth == 0 {
                self.visible.push(y * b + x);
            } else {
                for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                    stack.push((depth - 1, 2 * x + dx, 2 * y + dy));
                }
            }
        }
        self.visible.sort_unstable();
        let f_px = cam.f_px();
        self.distance.clear();
        self.distance.resize(b * b, 0.0);
        for &k in &self.visible {
            let d = block_distance(grid, blocks, k, cam, p);
            self.distance[k] = d;
            self.level[k] = choose_level(blocks, k, d, f_px, p.tau) as u8;
        }
        self.fill_gpu(blocks, f_px, p);
    }

    /// Every block at one level, none culled (brute force when `level` is 0).
    pub fn all_at(&mut self, grid: &Grid, blocks: &Blocks, level: u8) {
        let b = grid.blocks_per_side();
        self.level = vec![level; b * b];
        self.visible = (0..b * b).collect();
        self.distance.clear();
        let p = LodParams {
            tau: 1.0,
            exact: false,
            morph: false,
            reach_m: 0.0,
        };
        self.fill_gpu(blocks, 1.0, &p);
    }

    /// Re-derives the GPU records after `level` was set (tests force level patterns this way).
    pub fn fill_gpu(&mut self, blocks: &Blocks, f_px: f64, p: &LodParams) {
        let b = blocks.per_side;
        // Morph over the last part of each level's range only: a morphing vertex adds up to its
        // share of the next level's error, so the less terrain is mid-morph, the closer the image
        // stays to the chosen level's.
        let range = |k: usize, l: usize| -> (f32, f32) {
            if !p.morph || l + 1 >= blocks.levels {
                return (f32::MAX, f32::MAX);
            }
            let lo = d_of(blocks, k, l, f_px, p.tau);
            let hi = d_of(blocks, k, l + 1, f_px, p.tau);
            ((lo + MORPH_START * (hi - lo)) as f32, hi as f32)
        };
        // The interior's morph follows the distance that chose the level: 0 on arrival at
        // level l (d = D_l), 1 on leaving it (d = D_{l+1}).
        let block_morph = |k: usize, (lo, hi): (f32, f32)| -> f32 {
            match self.distance.get(k) {
                Some(&d) if hi > lo && hi < f32::MAX => {
                    ((d as f32 - lo) / (hi - lo)).clamp(0.0, 1.0)
                }
                _ => 0.0,
            }
        };
        self.gpu.clear();
        for &k in &self.visible {
            let (bx, by) = (k % b, k / b);
            let l = self.level[k] as usize;
            let own = range(k, l);
            let mut rec = BlockGpu {
                origin: [(bx * blocks.cells) as u32, (by * blocks.cells) as u32],
                level: l as u32,
                morph: [own.0, own.1, block_morph(k, own), 0.0],
                ..Default::default()
            };
            let neighbours = [
                (by > 0).then(|| k - b),
                (bx + 1 < b).then(|| k + 1),
                (by + 1 < b).then(|| k + b),
                (bx > 0).then(|| k - 1),
            ];
            for (side, nb) in neighbours.into_iter().enumerate() {
                let (sl, (s0, s1)) = match nb.map(|n| (n, self.level[n])) {
                    Some((n, nl)) if nl != u8::MAX && nl as usize > l => {
                        (nl as usize, range(n, nl as usize))
                    }
                    Some((n, nl)) if nl as usize == l => {
                        let other = range(n, l);
                        (l, (own.0.min(other.0), own.1.min(other.1)))
                    }
                    _ => (l, own),
                };
                rec.side_level[side] = sl as u32;
                rec.side_start[side] = s0;
                rec.side_end[side] = s1;
            }
            self.gpu.push(rec);
        }
    }

    pub fn triangles(&self, templates: &Templates) -> usize {
        self.gpu.iter().map(|g| templates.count(g)).sum::<usize>() / 3
    }
}

fn tree_side(b: usize, depth: usize) -> usize {
    let mut side = b;
    for _ in 0..depth {
        side = side.div_ceil(2);
    }
    side
}

/// Triangle templates in block-local vertex numbers (j·(cells+1) + i), built once per block size.
pub struct Templates {
    cells: usize,
    shift: u32,
    interior: Vec<Vec<u32>>,
    /// `strip[side][level][neighbour level]`.
    strip: Vec<Vec<Vec<Vec<u32>>>>,
}

impl Templates {
    pub fn new(grid: &Grid) -> Templates {
        let (c, levels) = (grid.cells, grid.levels());
        let interior = (0..levels).map(|l| interior_template(l, c)).collect();
        let strip = (0..4)
            .map(|side| {
                (0..levels)
                    .map(|l| {
                        (0..levels)
                            .map(|nl| strip_template(side, l, nl.max(l), c))
                            .collect()
                    })
                    .collect()
            })
            .collect();
        Templates {
            cells: c,
            shift: grid.slot_shift(),
            interior,
            strip,
        }
    }

    pub fn cells(&self) -> usize {
        self.cells
    }

    fn parts<'a>(&'a self, g: &BlockGpu) -> impl Iterator<Item = &'a Vec<u32>> + 'a {
        let l = g.level as usize;
        let sides = g.side_level;
        std::iter::once(&self.interior[l])
            .chain((0..4).map(move |s| &self.strip[s][l][sides[s] as usize]))
    }

    pub fn count(&self, g: &BlockGpu) -> usize {
        self.parts(g).map(Vec::len).sum()
    }

    /// Appends the indices of `blocks` (slot = position in the slice) to `out`.
    pub fn append(&self, blocks: &[BlockGpu], out: &mut Vec<u32>) {
        out.clear();
        for (slot, g) in blocks.iter().enumerate() {
            let high = (slot as u32) << self.shift;
            for part in self.parts(g) {
                out.extend(part.iter().map(|&v| v | high));
            }
        }
    }
}

fn local(i: usize, j: usize, c: usize) -> u32 {
    (j * (c + 1) + i) as u32
}

fn interior_template(l: usize, c: usize) -> Vec<u32> {
    let s = 1 << l;
    let mut v = Vec::new();
    if s == c {
        // One cell, no inner ring: two triangles over the corners.
        let (a, b, cc, d) = (
            local(0, 0, c),
            local(c, 0, c),
            local(c, c, c),
            local(0, c, c),
        );
        v.extend_from_slice(&[a, b, cc, a, cc, d]);
        return v;
    }
    let mut j = s;
    while j + s <= c - s {
        let mut i = s;
        while i + s <= c - s {
            let (a, b) = (local(i, j, c), local(i + s, j, c));
            let (cc, d) = (local(i + s, j + s, c), local(i, j + s, c));
            v.extend_from_slice(&[a, b, cc, a, cc, d]);
            i += s;
        }
        j += s;
    }
    v
}

/// (a, b) in the south strip's frame to block-local (i, j) for side 0..4 (S, E, N, W): each side
/// is the south one turned 90° counter-clockwise, which keeps triangles counter-clockwise.
fn rotate(side: usize, a: usize, b: usize, c: usize) -> (usize, usize) {
    match side {
        0 => (a, b),
        1 => (c - b, a),
        2 => (c - a, c - b),
        _ => (b, c - a),
    }
}

/// The trapezoid between a block's edge (drawn at level `outer_l`) and its first inner row (at
/// `l`), zipped: each step advances whichever polyline's next vertex comes first.
fn strip_template(side: usize, l: usize, outer_l: usize, c: usize) -> Vec<u32> {
    let (s, big) = (1usize << l, 1usize << outer_l);
    if s == c {
        return Vec::new(); // the coarsest level is one cell, drawn by its interior template
    }
    let outer: Vec<usize> = (0..=c).step_by(big).collect();
    let inner: Vec<usize> = (s..=c - s).step_by(s).collect();
    let at = |a: usize, b: usize| {
        let (i, j) = rotate(side, a, b, c);
        local(i, j, c)
    };
    let (mut o, mut q) = (0, 0);
    let mut v = Vec::new();
    while o + 1 < outer.len() || q + 1 < inner.len() {
        let advance_outer =
            q + 1 == inner.len() || (o + 1 < outer.len() && outer[o + 1] <= inner[q + 1]);
        if advance_outer {
            v.extend_from_slice(&[at(outer[o], 0), at(outer[o + 1], 0), at(inner[q], s)]);
            o += 1;
        } else {
            v.extend_from_slice(&[at(outer[o], 0), at(inner[q + 1], s), at(inner[q], s)]);
            q += 1;
        }
    }
    v
}

/// The CPU twin of the GEOMIPMAP vertex shader: the morphed height of block-local vertex
/// (i, j) of `g` seen from `eye` (world), and the morph factor.
pub fn morphed_height(grid: &Grid, g: &BlockGpu, i: usize, j: usize, eye: DVec3) -> (f32, f32) {
    let (gi, gj) = (g.origin[0] as usize + i, g.origin[1] as usize + j);
    let z = grid.z(gi, gj);
    let c = grid.cells;
    let side = if j == 0 {
        Some(0)
    } else if i == c {
        Some(1)
    } else if j == c {
        Some(2)
    } else if i == 0 {
        Some(3)
    } else {
        None
    };
    let (mut level, mut start, mut end) = (g.level as usize, g.morph[0], g.morph[1]);
    if let Some(k) = side {
        level = g.side_level[k] as usize;
        start = g.side_start[k];
        end = g.side_end[k];
    }
    let (s, s2) = (1usize << level, 2usize << level);
    if level + 1 >= grid.levels() || (gi % s2 == 0 && gj % s2 == 0) {
        return (z, 0.0);
    }
    let dx = if gi % s2 != 0 { s } else { 0 };
    let dy = if gj % s2 != 0 { s } else { 0 };
    if gi < dx || gj < dy || gi + dx >= grid.n || gj + dy >= grid.n {
        // Not a vertex this level draws (stitching leaves it out): no morph.
        return (z, 0.0);
    }
    let coarse = 0.5 * (grid.z(gi - dx, gj - dy) + grid.z(gi + dx, gj + dy));
    // Inside: the block's factor; on an edge: the vertex's own distance over the edge's range.
    let m = match side {
        None => g.morph[2],
        Some(_) if end > start => {
            let d = (grid.world(gi, gj) - eye).length() as f32;
            ((d - start) / (end - start)).clamp(0.0, 1.0)
        }
        Some(_) => 0.0,
    };
    (z + (coarse - z) * m, m)
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
                heights: vec![0.0; (c + 1) * (c + 1)],
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
