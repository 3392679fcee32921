//! The per-frame uniform block (`shaders/shared/frame.wgsl`'s `Frame`), built on the CPU in f64
//! and handed to the GPU in f32 relative to the frame origin, the camera's ground point.

use crate::camera::Camera;
use crate::detail::{Detail, OctaveFrame};
use crate::light::Light;
use crate::scene::Outside;
use crate::sketch::Atlas;
use crate::stage::sketch_map::SketchMap;
use bytemuck::{Pod, Zeroable};
use glam::{DMat4, DVec2, DVec4};

/// The octaves the uniform block holds: the scene's limit (`#import constants` gives the WGSL it).
pub const MAX_OCTAVES: usize = crate::scene::MAX_OCTAVES as usize;
/// Pyramid levels the GPU sees (a 32768² atlas has 15).
pub const MAX_LEVELS: usize = 16;

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

/// The eye and the image.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct CameraUniforms {
    pub view_proj: [[f32; 4]; 4],
    pub inv_view_proj: [[f32; 4]; 4],
    pub eye: [f32; 3],
    /// 2·tan(fov/2)/height: a pixel's footprint per metre of distance.
    pub pixel_scale: f32,
    /// Width and height in pixels.
    pub image: [u32; 2],
    pub view: u32,
    pub pad: u32,
}

/// Sunlight, the air and the surface types' variation.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct ShadingUniforms {
    /// Direction to the sun.
    pub sun: [f32; 3],
    /// The sky's share of its daylight (0 after dusk).
    pub daylight: f32,
    /// The sunlight above the air, linear RGB.
    pub sun_top: [f32; 3],
    /// The sun's relative air mass.
    pub air_mass: f32,
    /// The sky's light on level ground at sea level, linear RGB.
    pub sky_light: [f32; 3],
    /// Light's factor before the tone map.
    pub exposure: f32,
    /// Haze extinction at sea level, per metre.
    pub haze_per_m: f32,
    /// Haze scale height, metres.
    pub haze_height_m: f32,
    /// Beyond the sketch: 0 nothing, 1 a plain at `plain_m`, 2 the sea.
    pub outside: u32,
    /// The level the margin beyond the sketch fades to: the plain's height, or the sea floor
    /// ([`crate::beyond::Beyond`]).
    pub plain_m: f32,
    /// The margin's width, metres.
    pub margin_m: f32,
    /// The lowest and highest the margin's ground reaches.
    pub margin_lo_m: f32,
    pub margin_hi_m: f32,
    pub pad: f32,
}

/// The sketch's pyramid in the atlas buffer.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct AtlasUniforms {
    /// Per level: width, height, first texel, 0; streamed, the last two are the level's first
    /// page-table entry and its tiles a row (see `shaders/shared/atlas.wgsl`).
    pub level: [[u32; 4]; MAX_LEVELS],
    /// Frame origin − atlas origin.
    pub offset: [f32; 2],
    pub inv_spacing: [f32; 2],
    pub d_atlas: f32,
    pub levels: u32,
    /// The sketch's highest height: a shadow ray above it hits nothing.
    pub max_m: f32,
    /// The water's surface: the terrain function is never below it.
    pub water_m: f32,
    /// A streamed pyramid's tile: interior nodes a side, and border nodes on each side (0 when whole).
    pub tile: u32,
    pub border: u32,
    pub pad: [u32; 2],
}

/// The procedural octaves.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct DetailUniforms {
    pub octave: [OctaveGpu; MAX_OCTAVES],
    pub octaves: u32,
    pub bias: f32,
    /// The band above the water over which the octaves fade in (`detail::Detail::shore_m`).
    pub shore_m: f32,
    pub pad: u32,
}

/// The mesh the terrain pass draws: the warped geometry image, or GeoMipMap's baked grid.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct MeshUniforms {
    /// Sketch-map region corner − frame origin.
    pub phi_offset: [f32; 2],
    /// Origin of the mesh's coordinates − frame origin (0 for the warped mesh).
    pub mesh_offset: [f32; 2],
    /// Warp size.
    pub n: u32,
    /// Detailed geometry image size.
    pub mesh: u32,
    /// Sketch-map spacing: metres per warp texel.
    pub d0: f32,
    /// The importance view's scale.
    pub importance_max: f32,
    /// The sketch map region's s and t axes in the world (unit vectors; x and y unless the
    /// region is turned, `stage::sketch_map::Turn`): Φ is along them.
    pub phi_s: [f32; 2],
    pub phi_t: [f32; 2],
}

/// No mesh: zeros, but Φ along x and y (a bake's identity Φ lies along them).
impl Default for MeshUniforms {
    fn default() -> Self {
        MeshUniforms {
            phi_offset: [0.0; 2],
            mesh_offset: [0.0; 2],
            n: 0,
            mesh: 0,
            d0: 0.0,
            importance_max: 0.0,
            phi_s: [1.0, 0.0],
            phi_t: [0.0, 1.0],
        }
    }
}

/// GeoMipMap's blocks.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct BlockUniforms {
    /// Cells per block side.
    pub cells: u32,
    /// Bits of the block-local vertex in an index.
    pub index_bits: u32,
    pub levels: u32,
    pub pad: u32,
}

/// The reference's ray march.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct MarchUniforms {
    /// Lowest and highest ground, with the detail's reach.
    pub lo: f32,
    pub hi: f32,
    /// Step as a fraction of the height above ground.
    pub step: f32,
    pub pad: f32,
}

/// The frame's uniform block (`shaders/shared/frame.wgsl`'s `Frame`): one struct per concern.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct FrameUniforms {
    pub camera: CameraUniforms,
    pub shading: ShadingUniforms,
    pub atlas: AtlasUniforms,
    pub detail: DetailUniforms,
    pub mesh: MeshUniforms,
    pub blocks: BlockUniforms,
    pub march: MarchUniforms,
}

crate::names::named_enum! {
    /// The debug views of `render --view`; the WGSL twins are `VIEW_*` in
    /// `shaders/shared/frame.wgsl` (checked in `checks/shaders.rs`).
    pub enum View ("view") {
        /// The picture: lit, shadowed and hazed, tone-mapped.
        Shaded = "shaded",
        /// The mesh's grid lines over the shaded picture.
        Wireframe = "wireframe",
        /// The split octave, blue (0) to yellow (every octave as geometry).
        SplitOctave = "split-octave",
        /// The warped mode's importance at each point, on a log scale over 12 octaves below its
        /// largest (that mode only).
        Importance = "importance",
        /// The shading normal, `n · 0.5 + 0.5` as RGB.
        Normals = "normals",
        /// Terrain white, sky black: for finding holes.
        Coverage = "coverage",
        /// Each pixel's surface class in its legend's colour (`surface::SURFACE_CLASSES`), unlit
        /// and unhazed: what `--outputs surface` reads back.
        Surface = "surface",
    }
}

/// The frame origin: the camera's ground point; on a planet the nadir of the tangent frame its
/// eye is given in (its own, or the held rings' one, see `lod::clipmaps::reframed`).
pub fn frame_origin(camera: &Camera) -> DVec2 {
    match camera.geo {
        Some(_) => DVec2::ZERO,
        None => camera.eye.truncate(),
    }
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
        DVec4::new(0.0, 0.0, camera.near, 0.0),
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
    pub light: &'a Light,
    /// What the sky pass draws beyond the sketch.
    pub outside: Outside,
    pub mesh: u32,
    pub view: View,
    pub importance_max: f32,
    /// GeoMipMap's block shape; zeros for the other modes.
    pub block: BlockUniforms,
    /// The reference's step: a fraction of the height above ground and of the pixel footprint.
    pub step_factor: f32,
}

impl FrameUniforms {
    pub fn new(f: &FrameInputs) -> FrameUniforms {
        let origin = frame_origin(f.camera);
        FrameUniforms {
            camera: CameraUniforms::new(f.camera, origin, f.view),
            shading: ShadingUniforms::new(f.light, f.atlas, f.outside),
            atlas: AtlasUniforms::new(f.atlas, origin),
            detail: DetailUniforms::new(f.detail, origin),
            mesh: MeshUniforms {
                phi_offset: f
                    .map
                    .map_or([0.0; 2], |m| (m.origin - origin).as_vec2().to_array()),
                mesh_offset: f
                    .mesh_origin
                    .map_or([0.0; 2], |m| (m - origin).as_vec2().to_array()),
                n: f.map.map_or(0, |m| m.n as u32),
                mesh: f.mesh,
                d0: f.map.map_or(0.0, |m| m.spacing as f32),
                importance_max: f.importance_max,
                phi_s: f
                    .map
                    .map_or([1.0, 0.0], |m| m.turn.axes().0.as_vec2().to_array()),
                phi_t: f
                    .map
                    .map_or([0.0, 1.0], |m| m.turn.axes().1.as_vec2().to_array()),
            },
            blocks: f.block,
            march: MarchUniforms {
                lo: (f.atlas.min_m as f64 - f.detail.reach_m()) as f32,
                hi: (f.atlas.max_m as f64 + f.detail.reach_m()).max(f.atlas.water_m as f64) as f32,
                step: f.step_factor,
                pad: 0.0,
            },
        }
    }

    /// The block for baking the terrain function on a regular `n`² grid with warp & zoom: Φ is
    /// the identity grid relative to `origin`, which is also the frame origin; no camera, no
    /// shading.
    pub fn for_bake(atlas: &Atlas, detail: &Detail, origin: DVec2, n: u32) -> FrameUniforms {
        FrameUniforms {
            camera: CameraUniforms::default(),
            shading: ShadingUniforms::default(),
            atlas: AtlasUniforms::new(atlas, origin),
            detail: DetailUniforms::new(detail, origin),
            mesh: MeshUniforms {
                n,
                mesh: n,
                ..MeshUniforms::default()
            },
            blocks: BlockUniforms::default(),
            march: MarchUniforms::default(),
        }
    }
}

impl CameraUniforms {
    pub fn new(camera: &Camera, origin: DVec2, view: View) -> CameraUniforms {
        let vp = view_proj(camera, origin);
        let eye = camera.eye - origin.extend(0.0);
        CameraUniforms {
            view_proj: vp.as_mat4().to_cols_array_2d(),
            inv_view_proj: vp.inverse().as_mat4().to_cols_array_2d(),
            eye: eye.as_vec3().to_array(),
            pixel_scale: (2.0 * camera.tan_half_y() / camera.height as f64) as f32,
            image: [camera.width, camera.height],
            view: view as u32,
            pad: 0,
        }
    }
}

impl ShadingUniforms {
    pub fn new(light: &Light, atlas: &Atlas, outside: Outside) -> ShadingUniforms {
        let beyond = crate::beyond::Beyond::new(atlas, outside);
        ShadingUniforms {
            sun: light.sun.as_vec3().to_array(),
            daylight: light.daylight as f32,
            sun_top: light.sun_top.map(|c| c as f32),
            air_mass: light.air_mass as f32,
            sky_light: light.sky_light.map(|c| c as f32),
            exposure: light.exposure as f32,
            haze_per_m: light.haze_per_m as f32,
            haze_height_m: light.haze_height_m as f32,
            outside: match outside {
                Outside::Void => 0,
                Outside::Plain => 1,
                Outside::Ocean => 2,
            },
            plain_m: beyond.level_m as f32,
            margin_m: beyond.margin_m as f32,
            margin_lo_m: beyond.span_m[0] as f32,
            margin_hi_m: beyond.span_m[1] as f32,
            pad: 0.0,
        }
    }
}

impl AtlasUniforms {
    pub fn new(atlas: &Atlas, origin: DVec2) -> AtlasUniforms {
        AtlasUniforms {
            level: level_table(atlas),
            offset: (origin - atlas.origin).as_vec2().to_array(),
            inv_spacing: [(1.0 / atlas.dx) as f32, (1.0 / atlas.dy) as f32],
            d_atlas: atlas.d_atlas() as f32,
            levels: atlas.levels.len().min(MAX_LEVELS) as u32,
            max_m: atlas.max_m.max(atlas.water_m),
            water_m: atlas.water_m,
            tile: 0,
            border: 0,
            pad: [0; 2],
        }
    }
}

impl DetailUniforms {
    pub fn new(detail: &Detail, origin: DVec2) -> DetailUniforms {
        let mut octave = [OctaveGpu::default(); MAX_OCTAVES];
        for (slot, o) in octave.iter_mut().zip(detail.frame(origin)) {
            *slot = o.into();
        }
        DetailUniforms {
            octave,
            octaves: detail.octaves.min(MAX_OCTAVES as u32),
            bias: detail.bias as f32,
            shore_m: detail.shore_m() as f32,
            pad: 0,
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
