//! Which blocks a frame draws and at which level: frustum culling of each block's box (widened by
//! the detail's vertical reach), then the coarsest level whose `D_l` the block's distance exceeds,
//! then each edge's governing level and morph range as the GPU reads them.

use super::{Blocks, Grid, MORPH_START, Templates};
use crate::camera::{Camera, Plane};
use glam::{DVec2, DVec3};

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
