//! The CPU twin of the GEOMIPMAP vertex shader's geomorphing (tests hold the two together).

#![cfg(test)]

use super::{BlockGpu, Grid};
use glam::DVec3;

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
