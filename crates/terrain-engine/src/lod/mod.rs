//! The level-of-detail schemes behind the one [`Renderer`](crate::render::Renderer): the warped
//! geometry image, GeoMipMap and brute force over a baked grid (GeoMipMap over a tile pyramid reads
//! its vertices per frame), and the ray-marched reference.
//!
//! Rules: the renderer owns what every mode shares (device, frame uniforms, atlas buffer, timer,
//! submission and timing); a scheme owns its passes and buffers and answers the renderer through
//! [`Lod`]: prepare on the CPU for a camera, fill its part of the frame's uniforms, record its
//! passes (named, so the timer and the reports key them by name), make its targets for a new
//! image size, give back its image. The shader variant of every pass is [`shader_key`]'s, per
//! scene and mode: a flag is derived there or in its scheme's [`Scheme::flags`], nowhere else.
//! Each scheme states what it needs of the adapter ([`Lod::needs`], no default), so no mode is
//! silently taken to need nothing.
//!
//! Adding a mode: its variant and its row in [`crate::scene::MODES`] (`scene/render.rs`: its
//! names, what it draws, its chart colour, its window key, the keys `compare` sweeps); its
//! folder here, holding its [`Scheme`] (how it is built, what it needs, its shader flags, its
//! default settings for `compare`, its passes' shaders), its passes with their CPU twins and the
//! test holding them together; its module's line and its arm in [`of`] (an exhaustive match:
//! the compiler asks for it); its WGSL in `shaders/`; its page in docs/modes.md. The tools,
//! `compare`, `view` and the naga checks read the table and the schemes, nothing else about it.
//!
//! The mode's variant and row sit in the scene, below the schemes, since the scene parses
//! `render.mode` and checks it against the sketch; a row holding its scheme would make the scene
//! depend on the passes above it, so the one arm in [`of`] joins them.
//!
//! Rejected alternative: an enum of the modes with a `match` in every method (what this replaced:
//! three renderer types each wrapped again, their submit–read–time code written three times). A
//! trait object costs one indirect call per method per frame, nothing beside a GPU frame.

pub mod baseline;
pub mod clipmaps;
pub mod reference;
pub mod warped;

use crate::camera::Camera;
use crate::detail::Detail;
use crate::error::Result;
use crate::gpu::alloc::Alloc;
use crate::gpu::context::GpuContext;
use crate::gpu::counters::Probe;
use crate::gpu::pipeline::Shader;
use crate::gpu::shaders::Key;
use crate::gpu::uniforms::{FrameInputs, View};
use crate::scene::{Mode, Scene};
use crate::sketch::Atlas;
use crate::stage::StageTimes;
use std::any::Any;

/// What a scheme is built from: the scene, and what the renderer already holds.
pub struct Shared<'a> {
    pub ctx: &'a GpuContext,
    /// The device, counting what the scheme allocates in the renderer's ledger.
    pub alloc: Alloc<'a>,
    pub scene: &'a Scene,
    pub atlas: &'a Atlas,
    pub detail: &'a Detail,
    /// The frame's uniform block.
    pub frame: &'a wgpu::Buffer,
    /// The sketch's pyramid on the GPU: whole, or the tile cache's pages (and its marks).
    pub atlas_binding: &'a crate::gpu::stream::AtlasBinding,
    pub view: View,
    /// Samples per pixel: 4 where `render.msaa` asks and the adapter allows, else 1 (the
    /// reference supersamples when it is 4).
    pub samples: u32,
    /// A mesh mode, shading single-sampled frames deferred (`GpuContext::deferred`).
    pub deferred: bool,
}

/// `compare`'s settings of a mode: each the values of its row's swept keys, in order.
pub(crate) type Settings = Vec<Vec<f64>>;

/// What differs by mode beyond its row in [`crate::scene::MODES`], given by the mode's module and
/// found by [`of`]: how its scheme is built, what it needs of the adapter, its flags in the shader
/// variant of its passes, and `compare`'s settings of it.
pub(crate) struct Scheme {
    /// Builds the scheme for a renderer.
    pub build: fn(&Shared) -> Result<Box<dyn Lod>>,
    /// Bytes of its largest storage binding beyond the sketch's, for a scene ([`Lod::needs`]).
    pub needs: fn(&Scene) -> u64,
    /// Sets the flags of its own in the shader variant ([`shader_key`] sets those every mode
    /// shares).
    pub flags: fn(&Shared, &mut Key),
    /// `compare`'s default settings for a scene seen by a camera ([`Mode::default_sweep`]).
    pub sweep: fn(&Scene, &Atlas, &Camera) -> Result<Settings>,
    /// The setting a scene draws with ([`Mode::setting_of`]).
    pub setting: fn(&Scene, &Atlas) -> Option<Vec<f64>>,
    /// The shaders of its own passes (those every mode may run are [`crate::gpu::SHADERS`]).
    #[cfg_attr(not(test), allow(dead_code))]
    pub shaders: &'static [Shader],
}

/// The scheme behind `mode`: one arm a mode, no wildcard, so a new mode's is asked for here.
pub(crate) fn of(mode: Mode) -> &'static Scheme {
    match mode {
        Mode::Warped => &warped::SCHEME,
        Mode::Geomipmap => &baseline::GEOMIPMAP,
        Mode::Bruteforce => &baseline::BRUTEFORCE,
        Mode::Reference => &reference::SCHEME,
        Mode::Clipmaps => &clipmaps::SCHEME,
    }
}

impl Mode {
    /// `compare`'s default settings of this mode for `scene` seen by `camera` (whose image size
    /// is the comparison's): each the values of its row's swept keys
    /// ([`ModeRow::sweep`](crate::scene::ModeRow::sweep)), in order, a flag as 0 or 1; none for a
    /// mode that sweeps no key.
    pub fn default_sweep(
        self,
        scene: &Scene,
        atlas: &Atlas,
        camera: &Camera,
    ) -> Result<Vec<Vec<f64>>> {
        (of(self).sweep)(scene, atlas, camera)
    }

    /// The values of this mode's swept keys that `scene` draws with, defaults resolved for
    /// `atlas`; `None` where it sweeps none or cannot draw the scene.
    pub fn setting_of(self, scene: &Scene, atlas: &Atlas) -> Option<Vec<f64>> {
        (of(self).setting)(scene, atlas)
    }
}

/// Every pass's shader: those every mode may run and each scheme's own, the list the naga checks
/// run over.
#[cfg(test)]
pub(crate) fn shaders() -> impl Iterator<Item = &'static Shader> {
    let own = crate::scene::MODES.iter().flat_map(|r| of(r.mode).shaders);
    crate::gpu::SHADERS.iter().chain(own)
}

/// No settings: the mode of a scheme that `compare` measures against rather than sweeps.
pub(crate) fn no_sweep(_: &Scene, _: &Atlas, _: &Camera) -> Result<Settings> {
    Ok(Vec::new())
}

/// The shader variant every pass of `mode`'s scheme is composed with, for the scene and the
/// renderer's choices in `s`: the flags every mode shares here, the mode's own by its
/// [`Scheme::flags`]; the one place a flag is derived.
pub fn shader_key(s: &Shared, mode: Mode) -> Key {
    let (scene, mut key) = (s.scene, Key::NONE);
    key.set(Key::NOISE, s.detail.octaves > 0);
    key.set(Key::STREAMED, s.atlas_binding.marks.is_some());
    // The counting variant: a renderer made to count gives its passes the tallies.
    key.set(Key::COUNT_WORK, s.atlas_binding.work.is_some());
    // The ground coloured by a ramp: a renderer made for one binds its stops.
    let ramp = s.atlas_binding.ramp.is_some();
    key.set(Key::RAMP, ramp);
    key.set(Key::IMAGE, s.atlas_binding.drape.is_some());
    // The output pass's clean-up of specks at the shore, where water can show: ground of the
    // sketch or beyond it at or under the water's level, and no ramp (which colours the bed).
    let beyond = crate::beyond::Beyond::new(s.atlas, scene.outside(s.atlas));
    key.set(Key::SHORE, !ramp && beyond.meets_water(s.atlas));
    (of(mode).flags)(s, &mut key);
    key
}

/// Whether the bump map is drawn: octaves to draw and `detail.bump`.
pub(crate) fn bump(s: &Shared) -> bool {
    s.detail.octaves > 0 && s.scene.detail.bump
}

/// The sketch's shadow and the detail's (`render.shadows`, `render.detail_shadows`).
pub(crate) fn shadow_flags(s: &Shared, key: &mut Key) {
    let on = s.scene.render.shadows;
    key.set(Key::SHADOWS, on);
    key.set(
        Key::DETAIL_SHADOWS,
        on && s.scene.render.detail_shadows && s.detail.octaves > 0,
    );
}

/// The bump map and its fade, where drawn.
pub(crate) fn bump_flags(s: &Shared, key: &mut Key, bump: bool) {
    key.set(Key::BUMP, bump);
    key.set(Key::BUMP_FADE, bump && s.scene.detail.bump_fade);
}

/// The flags of the modes the terrain pass draws as a mesh over a geometry image (warped,
/// GeoMipMap, brute force).
pub(crate) fn mesh_flags(s: &Shared, key: &mut Key) {
    let pixel_normals = s.scene.render.pixel_normals;
    // Warp & zoom's octaves: the warped mesh's, and the baselines' bake.
    key.set(Key::DETAIL, s.detail.octaves > 0);
    key.set(Key::PIXEL_NORMALS, pixel_normals);
    // Pixel normals hold every octave already: no bump on top of them.
    bump_flags(s, key, bump(s) && !pixel_normals);
    shadow_flags(s, key);
    // The sketch's shadow from its sun clearance map: a renderer made with one binds it.
    key.set(Key::SUN_MAP, s.atlas_binding.sun_seen.is_some());
    // The view distances the output pass reads: a second target of the frame's pass;
    // multisampled, a pass of its own (`gpu::terrain`).
    key.set(Key::POSITIONS, s.samples == 1);
    key.set(Key::DEFERRED, s.deferred);
}

/// The CPU's part of a frame.
#[derive(Clone, Copy, Debug, Default)]
pub struct CpuTimes {
    /// The warped mode's CPU stage, by part (zero for the other modes).
    pub stage: StageTimes,
    /// All the CPU work of the frame: the stage, or the baselines' block selection (µs).
    pub us: f64,
}

/// One level-of-detail scheme.
pub trait Lod: Any {
    /// The passes it may record, in the order it records them (the timer's slots).
    fn passes(&self) -> &'static [&'static str];
    /// Bytes of its largest storage binding beyond the sketch's, for `scene`: what the adapter
    /// must bind before the scheme is built ([`needs`]).
    fn needs(scene: &Scene) -> u64
    where
        Self: Sized;
    /// Makes what depends on the frame's size for frames of `width` × `height`: its targets,
    /// per-pixel buffers and read-back. Pipelines, meshes and the CPU stage stay.
    fn resize(&mut self, alloc: &Alloc, width: u32, height: u32) -> Result<()>;
    /// The CPU work for `camera`: the warped mode's stage, GeoMipMap's block selection.
    fn prepare(&mut self, atlas: &Atlas, camera: &Camera) -> CpuTimes;
    /// Fills its part of the frame's uniform inputs (the rest is the renderer's).
    fn frame_inputs<'a>(&'a self, inputs: &mut FrameInputs<'a>);
    /// Uploads its per-frame data and records its passes and the copy of its image; returns the
    /// passes it recorded (a tail of [`passes`](Lod::passes)).
    fn record(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        probe: Probe,
    ) -> &'static [&'static str];
    /// Where the recorded frame is left, for the output pass to write into a host's targets or a
    /// snapshot's ([`crate::gpu::output`]): every frame keeps its view distances for it.
    fn output(&self) -> crate::gpu::output::Source<'_>;
    /// Ground positions of the last frame's pixels, relative to `camera`'s ground point (w = 1
    /// on ground, 0 on sky).
    fn read_positions(&self, ctx: &GpuContext, camera: &Camera) -> Result<Vec<[f32; 4]>>;
    /// Triangles drawn in the last frame.
    fn triangles(&self) -> u64;
    /// Whether any terrain was in view in the last frame.
    fn visible(&self) -> bool;
    /// Blocks drawn in the last frame (GeoMipMap and brute force).
    fn blocks(&self) -> Option<usize> {
        None
    }
    /// Precomputation: milliseconds and bytes (the baselines' baked grid).
    fn precompute(&self) -> Option<(f64, u64)> {
        None
    }
    /// Takes `value` for the swept key `key` ([`ModeRow::sweep`](crate::scene::ModeRow::sweep))
    /// without being built again, where the scheme can (GeoMipMap's τ, one of its row's
    /// `retuned` keys); others are left as built.
    fn retune(&mut self, _key: &str, _value: f64) {}
    /// Forgets what earlier frames leave to the next (the warped mode's budget hysteresis), so the
    /// next frame is what a fresh renderer would draw: for snapshots of unrelated cameras.
    fn forget(&mut self) {}
    /// Whether the scheme can draw: false while what it reads back from the GPU before its
    /// first frame is on its way (in a browser, which cannot wait for its GPU; natively it is
    /// there once the renderer is made). Frames before then draw the sky alone.
    fn ready(&mut self) -> Result<bool> {
        Ok(true)
    }
    /// Places a planet's sun where `scene`'s camera sees it at the scene's light (see
    /// [`clipmaps::sun_world`]): for a renderer reused across scenes that differ only in the
    /// camera. Nothing to do off a planet, where the light is the frame's.
    fn relight(&mut self, _scene: &Scene) {}
    /// `camera` in the frame of the last frame's level of detail, for drawing with it
    /// ([`Renderer::render_held`](crate::render::Renderer::render_held)): the camera itself, but
    /// for schemes whose geometry is placed relative to the camera it was prepared for.
    fn held_camera(&self, camera: &Camera) -> Camera {
        camera.clone()
    }
    fn as_any(&self) -> &dyn Any;
    fn as_any_mut(&mut self) -> &mut dyn Any;
}
