//! Stitching templates: triangles in block-local vertex numbers, built once per block size — an
//! interior per level and, per side, a strip per (level, neighbour level) that zips the shared
//! edge to the coarser neighbour's vertices, so no T-junction opens.
//!
//! Rejected alternative: one index buffer per (level, four neighbour levels): 2,275 buffers of up
//! to 6k indices. Interior plus four edge strips needs 6 + 84 small templates.

use super::{BlockGpu, Grid};

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
