//! Warp & zoom (`shaders/warp_zoom.wgsl`): Φ upsampled to the mesh, heights from the atlas at Φ,
//! split octaves, displacement up to them; for an adaptive triangulation (`lod::warped::mesh_split`),
//! also each cell's centre height. [`vertex_cpu`] and [`centre_cpu`] are its CPU twins, used by
//! the tests to hold the GPU to the CPU stage's definitions.

use super::alloc::{Alloc, Buffer};
use super::bindings::{Binding, bind_group, buffer, layout};
use super::pipeline::{compute_pipeline, dispatch_grid};
use super::shaders::Key;
use super::stream::AtlasBinding;
#[cfg(test)]
use super::uniforms::FrameUniforms;
#[cfg(test)]
use crate::detail::{OctaveFrame, gradient_noise};
use crate::error::Result;
#[cfg(test)]
use crate::sketch::Atlas;
#[cfg(test)]
use crate::sketch::cubic::catmull_rom;
#[cfg(test)]
use glam::{IVec2, Vec2, Vec3};
use wgpu::ShaderStages as S;

/// The pass's shader, `shaders/warp_zoom.wgsl`.
pub const SHADER: crate::gpu::pipeline::Shader = shader!("warp_zoom", BINDINGS);

/// `shaders/warp_zoom.wgsl`'s bindings.
pub const BINDINGS: &[Binding] = &[
    Binding::frame(S::COMPUTE),
    Binding::atlas(S::COMPUTE),
    Binding::wanted(S::COMPUTE),
    Binding::work(S::COMPUTE),
    Binding::storage(2, "phi", S::COMPUTE),
    Binding::storage_rw(3, "detailed", S::COMPUTE),
    Binding::storage_rw(4, "centres", S::COMPUTE).when(|k| k.contains(Key::CENTRES)),
];

pub struct WarpZoomPass {
    pipeline: wgpu::ComputePipeline,
    bind_group: wgpu::BindGroup,
    /// Φ, n² vec2 f32, written each frame.
    pub phi: Buffer,
    /// The detailed geometry image, mesh² vec4 (x, y, z, split octave).
    pub detailed: Buffer,
    /// Each cell's centre height, mesh² f32 (cell (s, t) at s + t·mesh; the last row and column
    /// unused), when built with centres.
    pub centres: Option<Buffer>,
    mesh: u32,
}

impl WarpZoomPass {
    /// The pass's name: its timer key, its `passes_ms` key, its WGSL file.
    pub const NAME: &'static str = SHADER.name;

    pub fn new(
        device: &Alloc,
        frame: &wgpu::Buffer,
        atlas: &AtlasBinding,
        n: u32,
        mesh: u32,
        key: Key,
    ) -> Result<WarpZoomPass> {
        let centres = key.contains(Key::CENTRES);
        let name = Self::NAME;
        let layout = layout(device, name, BINDINGS, 0, key);
        let pipeline = compute_pipeline(device, &SHADER, key, &layout)?;
        let phi = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("phi"),
            size: (n * n) as u64 * 8,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let detailed = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("detailed geometry image"),
            size: (mesh * mesh) as u64 * 16,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let centres = centres.then(|| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("cell centres"),
                size: (mesh * mesh) as u64 * 4,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            })
        });
        let mut resources = atlas.resources();
        resources.extend([
            ("frame", buffer(frame)),
            ("phi", buffer(&phi)),
            ("detailed", buffer(&detailed)),
        ]);
        resources.extend(centres.iter().map(|c| ("centres", buffer(c))));
        let bind_group = bind_group(device, name, &layout, BINDINGS, 0, key, &resources)?;
        Ok(WarpZoomPass {
            pipeline,
            bind_group,
            phi,
            detailed,
            centres,
            mesh,
        })
    }

    /// Records the pass for a `mesh`² geometry image (at most the size it was built for; the
    /// frame's uniforms must say the same `mesh`).
    pub fn record(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        mesh: u32,
        probe: super::counters::Probe,
    ) {
        let (p, b) = (&self.pipeline, &self.bind_group);
        let m = mesh.min(self.mesh);
        dispatch_grid(encoder, Self::NAME, p, b, [m; 2], probe);
    }
}

#[cfg(test)]
/// Φ at warp coordinates (bilinear), metres from the frame origin (`phi_at` in the shader).
fn phi_at(f: &FrameUniforms, phi: &[[f32; 2]], st: Vec2) -> Vec2 {
    let n = f.mesh.n;
    let c = st.clamp(Vec2::ZERO, Vec2::splat((n - 1) as f32));
    let i = c.as_uvec2().min(glam::UVec2::splat(n - 2));
    let fr = c - i.as_vec2();
    let at = |x: u32, y: u32| Vec2::from(phi[(y * n + x) as usize]);
    let (p00, p10) = (at(i.x, i.y), at(i.x + 1, i.y));
    let (p01, p11) = (at(i.x, i.y + 1), at(i.x + 1, i.y + 1));
    let q = p00.lerp(p10, fr.x).lerp(p01.lerp(p11, fr.x), fr.y);
    let (s, t) = (Vec2::from(f.mesh.phi_s), Vec2::from(f.mesh.phi_t));
    s * q.x + t * q.y + Vec2::from(f.mesh.phi_offset)
}

#[cfg(test)]
fn mesh_xy(f: &FrameUniforms, phi: &[[f32; 2]], ij: IVec2) -> Vec2 {
    let m = f.mesh.mesh as i32;
    let c = ij.clamp(IVec2::ZERO, IVec2::splat(m - 1));
    phi_at(
        f,
        phi,
        c.as_vec2() * ((f.mesh.n - 1) as f32 / (f.mesh.mesh - 1) as f32),
    )
}

#[cfg(test)]
/// `drawn_xy` in the shader: a vertex past the sketch's edge is drawn on it (`on_sketch_edge` in
/// `shaders/shared/frame.wgsl`), unless the region is turned.
fn drawn_xy(f: &FrameUniforms, p: Vec2) -> Vec2 {
    if f.mesh.phi_s[1] != 0.0 {
        return p;
    }
    let (lo, hi) = sketch_rect(f);
    p.clamp(lo, hi)
}

#[cfg(test)]
/// The sketch's rectangle, metres from the frame origin (`sketch_lo` and `sketch_hi` in
/// `shaders/shared/frame.wgsl`).
pub fn sketch_rect(f: &FrameUniforms) -> (Vec2, Vec2) {
    let lo = -Vec2::from(f.atlas.offset);
    let nodes = glam::UVec2::new(f.atlas.level[0][0], f.atlas.level[0][1]) - glam::UVec2::ONE;
    (lo, lo + nodes.as_vec2() / Vec2::from(f.atlas.inv_spacing))
}

#[cfg(test)]
/// `atlas_level` in the shader: bicubic height on level l at level-0 texel coordinates.
fn atlas_level(atlas: &Atlas, uv: Vec2, l: usize) -> f32 {
    let level = &atlas.levels[l];
    let s = (1u32 << l) as f32;
    let x = (uv - Vec2::splat((s - 1.0) * 0.5)) / s;
    let i = x.floor();
    let fr = x - i;
    let (wx, wy) = (catmull_rom(fr.x), catmull_rom(fr.y));
    let mut h = 0.0;
    for (b, wyb) in wy.iter().enumerate() {
        let y = (i.y as i32 - 1 + b as i32).clamp(0, level.height as i32 - 1) as usize;
        let mut row = 0.0;
        for (a, wxa) in wx.iter().enumerate() {
            let xx = (i.x as i32 - 1 + a as i32).clamp(0, level.width as i32 - 1) as usize;
            row += wxa * level.data[y * level.width + xx];
        }
        h += wyb * row;
    }
    h
}

#[cfg(test)]
fn atlas_height(f: &FrameUniforms, atlas: &Atlas, local: Vec2, spacing: f32) -> f32 {
    let uv = (local + Vec2::from(f.atlas.offset)) * Vec2::from(f.atlas.inv_spacing);
    let lod = (spacing.max(1e-6) / f.atlas.d_atlas)
        .log2()
        .clamp(0.0, (f.atlas.levels - 1) as f32);
    let l0 = lod as u32;
    let t = lod - l0 as f32;
    let a = atlas_level(atlas, uv, l0 as usize);
    if t <= 0.0 || l0 + 1 >= f.atlas.levels {
        return a;
    }
    a + (atlas_level(atlas, uv, l0 as usize + 1) - a) * t
}

#[cfg(test)]
fn octave_local(o: &super::uniforms::OctaveGpu, local: Vec2) -> f32 {
    let frame = OctaveFrame {
        lattice: IVec2::from(o.lattice),
        phase: Vec2::from(o.phase),
        scale: o.scale,
        weight: o.weight,
        seed: o.seed,
    };
    let q = local * frame.scale + frame.phase;
    let c = q.floor();
    gradient_noise(frame.lattice + c.as_ivec2(), q - c, frame.seed).0
}

#[cfg(test)]
/// The spacing whose pyramid level the sketch is sampled at, for a vertex whose sketch octave is
/// `o` ([`sketch_octave_in_view`]): level −o, clamped to the pyramid.
pub fn sketch_spacing(d_atlas: f32, o: f32) -> f32 {
    d_atlas * (-o).exp2()
}

#[cfg(test)]
/// The octave whose pyramid level a vertex at `p` reads the sketch at, for a split octave `o`
/// before its stop at the pixel octave: with a camera, the pixel octave `log2(d_atlas /
/// footprint)` (`pixel_octave`), so that each vertex lies on the surface the picture is
/// compared with, at the reference's level there or finer (the footprint is taken at the nearest
/// height the sketch can have, never farther than the reference's hit); a bake has no camera and
/// reads level −o.
///
/// Rejected (docs/decisions.md, “Sketch level at the pixel octave”):
/// - the vertex's own spacing: every vertex sits on the sketch smoothed over its cell, below each
///   ridge the mesh could draw;
/// - level −o (the split octave's level): more triangles for the same error from high up;
/// - the finest level (no prefilter at all): a tile pyramid then streams its finest tiles under
///   every vertex, where at the pixel octave it streams the tiles the shading of distant ground
///   reads (`shaders/terrain.wgsl`, `shading_normal`) anyway.
pub fn sketch_octave_in_view(f: &FrameUniforms, p: Vec2, o: f32) -> f32 {
    pixel_octave(f, p).unwrap_or(o)
}

#[cfg(test)]
/// The pixel octave at `p`, `log2(d_atlas / footprint)`, the footprint taken at the nearest
/// height the sketch can have under `p` (the eye's, below the sketch's highest); none without a
/// camera (`pixel_scale` 0, a bake).
fn pixel_octave(f: &FrameUniforms, p: Vec2) -> Option<f32> {
    if f.camera.pixel_scale <= 0.0 {
        return None;
    }
    let eye = Vec3::from(f.camera.eye);
    let nearest = p.extend(eye.z.min(f.atlas.max_m));
    let footprint = nearest.distance(eye) * f.camera.pixel_scale;
    Some((f.atlas.d_atlas / footprint.max(1e-6)).log2())
}

#[cfg(test)]
/// The split octave of a vertex at `p` (frame metres) whose mesh gives `o`: no finer than the
/// pixel octave there (`pixel_octave`), as the reference's surface holds no octave finer than
/// its pixel. A mesh finer than the pixels (far ground, a dense mesh from high up) otherwise
/// carries octaves the reference does not draw, and its normals alias them (docs/decisions.md,
/// “Split octave stops at the pixel octave”). Taking the footprint at the nearest height
/// the sketch can have keeps the stop from binding more than it should, and reads the sketch once,
/// at its final level: a streamed pyramid marks every tile it reads as wanted. A bake has no
/// camera and no stop.
pub fn split_octave_in_view(f: &FrameUniforms, p: Vec2, o: f32) -> f32 {
    pixel_octave(f, p).map_or(o, |px| o.min(px))
}

#[cfg(test)]
/// `detailed_at` in the shader: the detailed surface's height at `p` for a mesh spacing of
/// `d_max` metres there, and its split octave.
fn detailed_at(f: &FrameUniforms, atlas: &Atlas, detail: bool, p: Vec2, d_max: f32) -> (f32, f32) {
    let o_mesh = (f.atlas.d_atlas / d_max.max(1e-6)).log2() - f.detail.bias;
    let o = split_octave_in_view(f, p, o_mesh);
    let o_sketch = sketch_octave_in_view(f, p, o_mesh);
    let mut z = atlas_height(f, atlas, p, sketch_spacing(f.atlas.d_atlas, o_sketch));
    if detail {
        let last = f.detail.octaves.min(o.ceil().max(0.0) as u32);
        let mut octaves = 0.0;
        for k in 1..=last {
            let g = (o - k as f32 + 1.0).clamp(0.0, 1.0);
            let oct = &f.detail.octave[(k - 1) as usize];
            octaves += oct.weight * g * octave_local(oct, p);
        }
        let (water, band) = (f.atlas.water_m as f64, f.detail.shore_m as f64);
        z += crate::detail::shore(z as f64, water, band) as f32 * octaves;
    }
    (z.max(f.atlas.water_m), o)
}

#[cfg(test)]
/// The CPU twin of one invocation of `warp_zoom.wgsl`: vertex `ij` of the detailed geometry image.
pub fn vertex_cpu(
    f: &FrameUniforms,
    phi: &[[f32; 2]],
    atlas: &Atlas,
    detail: bool,
    ij: IVec2,
) -> [f32; 4] {
    let p = mesh_xy(f, phi, ij);
    let d = |o: IVec2| p.distance(mesh_xy(f, phi, ij + o));
    let d_max = d(IVec2::X)
        .max(d(-IVec2::X))
        .max(d(IVec2::Y).max(d(-IVec2::Y)));
    let drawn = drawn_xy(f, p);
    let (z, o) = detailed_at(f, atlas, detail, drawn, d_max);
    [drawn.x, drawn.y, z, o]
}

#[cfg(test)]
/// The CPU twin of `warp_zoom.wgsl`'s centres: the height at the mean of cell `ij`'s corners
/// (from vertex `ij` to `ij + (1, 1)`), at the spacing of its longest side.
pub fn centre_cpu(
    f: &FrameUniforms,
    phi: &[[f32; 2]],
    atlas: &Atlas,
    detail: bool,
    ij: IVec2,
) -> f32 {
    let at = |o: IVec2| mesh_xy(f, phi, ij + o);
    let (p, east, north, far) = (at(IVec2::ZERO), at(IVec2::X), at(IVec2::Y), at(IVec2::ONE));
    let side = p
        .distance(east)
        .max(p.distance(north))
        .max(far.distance(east).max(far.distance(north)));
    let edge = |q: Vec2| drawn_xy(f, q);
    let mean = 0.25 * (edge(p) + edge(east) + edge(north) + edge(far));
    detailed_at(f, atlas, detail, mean, side).0
}

impl WarpZoomPass {
    /// The detailed geometry image, keeping nothing else (the bake's Φ is dropped).
    pub fn into_detailed(self) -> Buffer {
        self.detailed
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use bytemuck::Zeroable;

    /// A bake (no camera) reads the sketch at −o and keeps o; a view reads it at the vertex's
    /// pixel octave whatever the mesh's spacing, while the split octave stops there.
    #[test]
    fn a_view_reads_the_sketch_at_the_pixel_octave() {
        let mut f = FrameUniforms::zeroed();
        f.atlas.d_atlas = 30.0;
        f.atlas.max_m = 500.0;
        let p = Vec2::new(1000.0, 0.0);
        for o in [-2.0, 0.5, 4.0] {
            assert_eq!(sketch_octave_in_view(&f, p, o), o);
            assert_eq!(split_octave_in_view(&f, p, o), o);
        }
        f.camera.eye = [0.0, 0.0, 2000.0];
        f.camera.pixel_scale = 1e-3;
        // The nearest height the sketch can have under p is its highest, 500 m: 1500 m below
        // the eye and 1000 m across.
        let footprint = 1000f32.hypot(1500.0) * 1e-3;
        let px = (30.0 / footprint).log2();
        for o in [-2.0, 0.5, 4.0, 12.0] {
            assert!((sketch_octave_in_view(&f, p, o) - px).abs() < 1e-5, "{o}");
            assert!(
                (split_octave_in_view(&f, p, o) - o.min(px)).abs() < 1e-5,
                "{o}"
            );
        }
        assert!((sketch_spacing(30.0, px) - footprint).abs() < 1e-3 * footprint);
    }
}
