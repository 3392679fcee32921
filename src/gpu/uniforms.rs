//! The per-frame uniform block (`shaders/shared/frame.wgsl`'s `Frame`), built on the CPU in f64
//! and handed to the GPU in f32 relative to the frame origin, the camera's ground point.

use crate::camera::Camera;
use crate::detail::{Detail, OctaveFrame};
use crate::sketch::Atlas;
use crate::stage::sketch_map::SketchMap;
use bytemuck::{Pod, Zeroable};
use glam::{DMat4, DVec2, DVec3, DVec4};

pub const MAX_OCTAVES: usize = 24;
/// Pyramid levels the GPU sees (a 32768² atlas has 15).
pub const MAX_LEVELS: usize = 16;
/// Nearest depth: with reversed-Z and an infinite far plane, depth precision does not suffer.
const NEAR_M: f64 = 0.05;

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct OctaveGpu {
    pub lattice: [i32; 2],
    pub phase: [f32; 2],
    pub scale: f32,
    pub weight: f32,
    pub seed: u32,
    pub pad: u32,
}

impl From<OctaveFrame> for OctaveGpu {
    fn from(o: OctaveFrame) -> Self {
        OctaveGpu {
            lattice: o.lattice.to_array(),
            phase: o.phase.to_array(),
            scale: o.scale,
            weight: o.weight,
            seed: o.seed,
            pad: 0,
        }
    }
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct FrameUniforms {
    pub view_proj: [[f32; 4]; 4],
    pub inv_view_proj: [[f32; 4]; 4],
    pub eye: [f32; 4],
    pub phi_offset: [f32; 2],
    pub atlas_offset: [f32; 2],
    pub atlas_inv_spacing: [f32; 2],
    pub d_atlas: f32,
    pub bias: f32,
    pub n: u32,
    pub mesh: u32,
    pub octaves: u32,
    pub levels: u32,
    pub sun: [f32; 4],
    pub view: u32,
    pub importance_max: f32,
    pub mesh_offset: [f32; 2],
    pub octave: [OctaveGpu; MAX_OCTAVES],
    pub turbulence: [OctaveGpu; 2],
    /// The atlas pyramid's levels in the atlas buffer: width, height, first texel, 0.
    pub level: [[u32; 4]; MAX_LEVELS],
    /// GeoMipMap blocks: cells per side, index bits of the block-local vertex, levels, 0.
    pub block: [u32; 4],
    /// Reference ray march: lowest and highest ground (with the detail's reach), step factor, 0.
    pub march: [f32; 4],
    /// Image width and height in pixels, 0, 0.
    pub image: [u32; 4],
}

crate::named_enum! {
    /// The debug views of `render --view`; the WGSL twins are `VIEW_*` in
    /// `shaders/shared/frame.wgsl` (checked in `tests/shaders.rs`).
    pub enum View ("view") {
        Shaded = "shaded",
        Wireframe = "wireframe",
        SplitOctave = "split-octave",
        Importance = "importance",
        Normals = "normals",
        /// Terrain white, sky black: for finding holes.
        Coverage = "coverage",
    }
}

/// The frame origin: the camera's ground point.
pub fn frame_origin(camera: &Camera) -> DVec2 {
    camera.eye.truncate()
}

/// The view-projection matrix relative to `origin`: right-handed, reversed-Z, infinite far plane.
pub fn view_proj(camera: &Camera, origin: DVec2) -> DMat4 {
    let eye = camera.eye - origin.extend(0.0);
    let (r, u, f) = (camera.right, camera.up, camera.forward);
    let view = DMat4::from_cols(
        DVec4::new(r.x, u.x, -f.x, 0.0),
        DVec4::new(r.y, u.y, -f.y, 0.0),
        DVec4::new(r.z, u.z, -f.z, 0.0),
        DVec4::new(-r.dot(eye), -u.dot(eye), f.dot(eye), 1.0),
    );
    let fy = 1.0 / camera.tan_half_y();
    let proj = DMat4::from_cols(
        DVec4::new(fy / camera.aspect(), 0.0, 0.0, 0.0),
        DVec4::new(0.0, fy, 0.0, 0.0),
        DVec4::new(0.0, 0.0, 0.0, -1.0),
        DVec4::new(0.0, 0.0, NEAR_M, 0.0),
    );
    proj * view
}

pub struct FrameInputs<'a> {
    pub camera: &'a Camera,
    /// The warped mode's sketch map (Φ is relative to its corner); `None` for the baselines.
    pub map: Option<&'a SketchMap>,
    /// World position the mesh's coordinates are relative to; `None`: the frame origin.
    pub mesh_origin: Option<DVec2>,
    pub atlas: &'a Atlas,
    pub detail: &'a Detail,
    pub mesh: u32,
    pub view: View,
    pub importance_max: f32,
    /// GeoMipMap's block shape (cells, index bits, levels, 0); zeros for the warped mode.
    pub block: [u32; 4],
    /// The reference's step: a fraction of the height above ground and of the pixel footprint.
    pub step_factor: f32,
}

impl FrameUniforms {
    pub fn new(f: &FrameInputs) -> FrameUniforms {
        let origin = frame_origin(f.camera);
        let vp = view_proj(f.camera, origin);
        let eye = f.camera.eye - origin.extend(0.0);
        let pixel_scale = 2.0 * f.camera.tan_half_y() / f.camera.height as f64;
        let mut octave = [OctaveGpu::default(); MAX_OCTAVES];
        for (slot, o) in octave.iter_mut().zip(f.detail.frame(origin)) {
            *slot = o.into();
        }
        // Two octaves of turbulence, 600 m and 150 m, for the surface types' boundaries.
        let turbulence_seed = crate::detail::hash(f.detail.seed ^ 0x5eed);
        let turbulence = [600.0, 150.0].map(|wavelength: f64| {
            let rel = origin - f.detail.lattice_origin_m;
            OctaveFrame::split(rel, 1.6 / wavelength, 1.0, turbulence_seed).into()
        });
        let sun = DVec3::new(0.41, -0.71, 0.57).normalize();
        FrameUniforms {
            view_proj: vp.as_mat4().to_cols_array_2d(),
            inv_view_proj: vp.inverse().as_mat4().to_cols_array_2d(),
            eye: [eye.x as f32, eye.y as f32, eye.z as f32, pixel_scale as f32],
            phi_offset: f
                .map
                .map_or([0.0; 2], |m| (m.origin - origin).as_vec2().to_array()),
            atlas_offset: (origin - f.atlas.origin).as_vec2().to_array(),
            atlas_inv_spacing: [(1.0 / f.atlas.dx) as f32, (1.0 / f.atlas.dy) as f32],
            d_atlas: f.atlas.d_atlas() as f32,
            bias: f.detail.bias as f32,
            n: f.map.map_or(0, |m| m.n as u32),
            mesh: f.mesh,
            octaves: f.detail.octaves.min(MAX_OCTAVES as u32),
            levels: f.atlas.levels.len().min(MAX_LEVELS) as u32,
            sun: [
                sun.x as f32,
                sun.y as f32,
                sun.z as f32,
                f.map.map_or(0.0, |m| m.spacing as f32),
            ],
            view: f.view as u32,
            importance_max: f.importance_max,
            mesh_offset: f
                .mesh_origin
                .map_or([0.0; 2], |m| (m - origin).as_vec2().to_array()),
            octave,
            turbulence,
            level: level_table(f.atlas),
            block: f.block,
            march: [
                (f.atlas.min_m as f64 - f.detail.reach_m()) as f32,
                (f.atlas.max_m as f64 + f.detail.reach_m()) as f32,
                f.step_factor,
                0.0,
            ],
            image: [f.camera.width, f.camera.height, 0, 0],
        }
    }
}

/// Width, height and first texel of each pyramid level, concatenated as [`atlas_texels`] lays them.
pub fn level_table(atlas: &Atlas) -> [[u32; 4]; MAX_LEVELS] {
    let mut table = [[0; 4]; MAX_LEVELS];
    let mut first = 0;
    for (slot, level) in table.iter_mut().zip(&atlas.levels) {
        *slot = [level.width as u32, level.height as u32, first as u32, 0];
        first += level.data.len();
    }
    table
}

/// The pyramid's levels one after another, as the atlas storage buffer holds them.
pub fn atlas_texels(atlas: &Atlas) -> Vec<f32> {
    atlas
        .levels
        .iter()
        .take(MAX_LEVELS)
        .flat_map(|l| l.data.iter().copied())
        .collect()
}

impl FrameUniforms {
    /// The block for baking the terrain function on a regular `n`² grid of `spacing` metres with
    /// warp & zoom: Φ is the identity grid relative to `origin`, which is also the frame origin.
    pub fn for_bake(atlas: &Atlas, detail: &Detail, origin: DVec2, n: u32) -> FrameUniforms {
        let mut octave = [OctaveGpu::default(); MAX_OCTAVES];
        for (slot, o) in octave.iter_mut().zip(detail.frame(origin)) {
            *slot = o.into();
        }
        FrameUniforms {
            view_proj: [[0.0; 4]; 4],
            inv_view_proj: [[0.0; 4]; 4],
            eye: [0.0; 4],
            phi_offset: [0.0; 2],
            atlas_offset: (origin - atlas.origin).as_vec2().to_array(),
            atlas_inv_spacing: [(1.0 / atlas.dx) as f32, (1.0 / atlas.dy) as f32],
            d_atlas: atlas.d_atlas() as f32,
            bias: detail.bias as f32,
            n,
            mesh: n,
            octaves: detail.octaves.min(MAX_OCTAVES as u32),
            levels: atlas.levels.len().min(MAX_LEVELS) as u32,
            sun: [0.0; 4],
            view: 0,
            importance_max: 0.0,
            mesh_offset: [0.0; 2],
            octave,
            turbulence: [OctaveGpu::default(); 2],
            level: level_table(atlas),
            block: [0; 4],
            march: [0.0; 4],
            image: [0; 4],
        }
    }
}
