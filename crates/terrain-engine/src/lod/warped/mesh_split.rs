//! Mesh split (`shaders/mesh_split.wgsl`): the warped mesh's index buffer, each cell split into
//! two triangles along the diagonal that lies nearer the surface. [`split_cpu`] is its CPU twin.
//!
//! Rules:
//! - A cell's corners are a = (s, t), b = (s+1, t), c = (s+1, t+1), d = (s, t+1). Split along
//!   a–c, the surface at the cell's centre is drawn at `(z_a + z_c)/2`; along b–d, at
//!   `(z_b + z_d)/2`. `warp_zoom.wgsl` evaluates the detailed surface at the mean of the corners
//!   (at the spacing of the cell's longest side, so with the octaves its corners carry), and the
//!   cell takes b–d where that midpoint lies strictly nearer it than a–c's.
//! - Only where both triangles of b–d, (a, b, d) and (b, c, d), are counter-clockwise in (x, y):
//!   the warp's guard (`stage::warp`) keeps every cell's a–c triangles so, and a cell that is not
//!   convex would fold along b–d. Ties and such cells keep a–c, the fixed split.
//! - The triangles are written in the fixed split's order, six indices a cell, row by row, so the
//!   draw is the same call; with `warp.triangulation = "fixed"` neither the centres nor this
//!   pass run, and the indices are [`crate::gpu::terrain::quad_indices`].
//!
//! Why: the mesh is a piecewise-linear interpolant of the surface, and on a cell the error of
//! either split is largest about its diagonal's midpoint, which is where the two differ. The
//! centre is evaluated, one more height per vertex in warp & zoom, the pass's main cost: an
//! estimate from the 4×4 vertices around the cell (no new height) cannot see the octaves finer
//! than the mesh (docs/decisions.md, “Mesh split along the nearer diagonal”). GeoMipMap keeps its
//! fixed split: its blocks' triangles are the ones its δ was computed for. A cell's six indices
//! are stored from one array, not one by one.

use crate::error::Result;
use crate::gpu::alloc::Alloc;
use crate::gpu::bindings::{Binding, bind_group, buffer, layout};
use crate::gpu::pipeline::{compute_pipeline, dispatch_grid};
use crate::gpu::shaders::Key;
use wgpu::ShaderStages as S;

/// The pass's shader, `shaders/mesh_split.wgsl`.
pub const SHADER: crate::gpu::pipeline::Shader = shader!("mesh_split", BINDINGS);

/// `shaders/mesh_split.wgsl`'s bindings.
pub const BINDINGS: &[Binding] = &[
    Binding::frame(S::COMPUTE),
    Binding::storage(3, "detailed", S::COMPUTE),
    Binding::storage(4, "centres", S::COMPUTE),
    Binding::storage_rw(5, "indices", S::COMPUTE),
];

pub struct MeshSplitPass {
    pipeline: wgpu::ComputePipeline,
    bind_group: wgpu::BindGroup,
    mesh: u32,
}

impl MeshSplitPass {
    /// The pass's name: its timer key, its `passes_ms` key, its WGSL file.
    pub const NAME: &'static str = SHADER.name;

    /// The pass from `detailed` and `centres` (warp & zoom's) to `indices` (the terrain pass's
    /// index buffer, with STORAGE use), for meshes of up to `mesh`².
    pub fn new(
        device: &Alloc,
        frame: &wgpu::Buffer,
        detailed: &wgpu::Buffer,
        centres: &wgpu::Buffer,
        indices: &wgpu::Buffer,
        mesh: u32,
    ) -> Result<MeshSplitPass> {
        let (name, key) = (Self::NAME, Key::NONE);
        let layout = layout(device, name, BINDINGS, 0, key);
        let pipeline = compute_pipeline(device, &SHADER, key, &layout)?;
        let resources = [
            ("frame", buffer(frame)),
            ("detailed", buffer(detailed)),
            ("centres", buffer(centres)),
            ("indices", buffer(indices)),
        ];
        let bind_group = bind_group(device, name, &layout, BINDINGS, 0, key, &resources)?;
        Ok(MeshSplitPass {
            pipeline,
            bind_group,
            mesh,
        })
    }

    /// Records the pass for a `mesh`² geometry image (at most the size it was built for; the
    /// frame's uniforms must say the same `mesh`).
    pub fn record(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        mesh: u32,
        probe: crate::gpu::counters::Probe,
    ) {
        let (p, b) = (&self.pipeline, &self.bind_group);
        let cells = mesh.min(self.mesh).saturating_sub(1);
        dispatch_grid(encoder, Self::NAME, p, b, [cells; 2], probe);
    }
}

#[cfg(test)]
fn ccw(a: [f32; 4], b: [f32; 4], c: [f32; 4]) -> bool {
    let (u, v) = ([b[0] - a[0], b[1] - a[1]], [c[0] - a[0], c[1] - a[1]]);
    u[0] * v[1] - u[1] * v[0] > 0.0
}

#[cfg(test)]
/// The CPU twin of one invocation of `mesh_split.wgsl`: the six indices of cell (s, t) of a
/// `mesh`² `detailed` geometry image whose cell centres' heights are `centres`.
pub fn split_cpu(detailed: &[[f32; 4]], centres: &[f32], mesh: u32, s: u32, t: u32) -> [u32; 6] {
    let a = t * mesh + s;
    let (b, c, d) = (a + 1, a + mesh + 1, a + mesh);
    let [pa, pb, pc, pd] = [a, b, c, d].map(|v| detailed[v as usize]);
    let z = centres[a as usize];
    let along = (z - 0.5 * (pa[2] + pc[2])).abs();
    let across = (z - 0.5 * (pb[2] + pd[2])).abs();
    if across < along && ccw(pa, pb, pd) && ccw(pb, pc, pd) {
        [a, b, d, b, c, d]
    } else {
        [a, b, c, a, c, d]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 2×2-vertex mesh (one cell) with heights `z` at a, b, c, d and corners at `xy`.
    fn cell(xy: [[f32; 2]; 4], z: [f32; 4]) -> Vec<[f32; 4]> {
        // Row-major: a = (0, 0), b = (1, 0), d = (0, 1), c = (1, 1).
        let v = |k: usize| [xy[k][0], xy[k][1], z[k], 0.0];
        vec![v(0), v(1), v(3), v(2)]
    }

    const SQUARE: [[f32; 2]; 4] = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
    /// b–d's triangles, (a, b, d) and (b, c, d), in a 2² mesh (a 0, b 1, d 2, c 3).
    const ACROSS: [u32; 6] = [0, 1, 2, 1, 3, 2];

    /// The fixed split: `quad_indices`, which a fixed triangulation draws.
    fn fixed() -> Vec<u32> {
        crate::gpu::terrain::quad_indices(2)
    }

    #[test]
    fn a_ridge_along_a_diagonal_is_kept_by_the_split_along_it() {
        // A ridge along b–d: b and d high, a and c low; the centre lies on the ridge.
        let mesh = cell(SQUARE, [0.0, 10.0, 0.0, 10.0]);
        assert_eq!(split_cpu(&mesh, &[10.0, 0.0, 0.0, 0.0], 2, 0, 0), ACROSS);
        // The same heights with the centre in the valley: a–c draws it.
        assert_eq!(
            split_cpu(&mesh, &[0.0, 0.0, 0.0, 0.0], 2, 0, 0).to_vec(),
            fixed()
        );
        // A tie keeps the fixed split.
        assert_eq!(
            split_cpu(&mesh, &[5.0, 0.0, 0.0, 0.0], 2, 0, 0).to_vec(),
            fixed()
        );
    }

    #[test]
    fn a_cell_that_would_fold_along_the_other_diagonal_keeps_the_fixed_split() {
        // A reflex corner at a (pushed in toward c) or at c (pushed in toward a): split along
        // a–c, both triangles are counter-clockwise; along b–d, (a, b, d) or (b, c, d) turns
        // clockwise.
        let at_a = [[0.8, 0.8], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
        let at_c = [[0.0, 0.0], [1.0, 0.0], [0.2, 0.2], [0.0, 1.0]];
        for (xy, folds) in [(at_a, [0, 1, 2]), (at_c, [1, 3, 2])] {
            let mesh = cell(xy, [0.0, 10.0, 0.0, 10.0]);
            assert!(ccw(mesh[0], mesh[1], mesh[3]) && ccw(mesh[0], mesh[3], mesh[2]));
            assert!(!ccw(mesh[folds[0]], mesh[folds[1]], mesh[folds[2]]));
            // The ridge along b–d would take b–d on a convex cell.
            let cut = split_cpu(&mesh, &[10.0, 0.0, 0.0, 0.0], 2, 0, 0);
            assert_eq!(cut.to_vec(), fixed(), "{xy:?}");
        }
    }
}
