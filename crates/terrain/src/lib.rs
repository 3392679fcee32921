//! `terrain`: large terrains whose rough shape comes from a height map (the *sketch*) and whose
//! fine detail is procedural, rendered by geometry image warping (Dachsbacher & Stamminger,
//! *Rendering Procedural Terrain by Geometry Image Warping*, 2004).
//!
//! A host application draws a terrain with its own device: a [`Description`] (a [`Scene`] with
//! its sketch read) states the limits and features a device needs, a [`Terrain`] prepares each
//! frame on the CPU and records it into the host's encoder, into the host's colour and depth
//! views. [`Ground`] (and [`PlanetGround`]) answers heights, normals and rays on the same ground.
//! [`Renderer`] draws frames on a device of its own and reads them back, for snapshots and
//! measurements.
//!
//! The modules follow a frame, in the order data flows through it: [`scene`] (the terrain's
//! description, and building a camera, the detail and the sketch from it) → [`sketch`] (the
//! height map read into its [`Atlas`]; [`sketch::tiles`] for pyramids larger than memory) → [`stage`]
//! (the CPU stage: sketch map → importance → warp → Φ, measured by its quality) → the GPU passes
//! (warp & zoom, mesh split, normals, terrain, reference, output; named in [`pass`]) driven by
//! one [`Renderer`] through a level-of-detail scheme ([`Mode`]: [`Warped`], [`Baselines`],
//! [`Reference`], [`Clipmaps`]). [`Detail`] is the procedural model both sides share; [`planet`]
//! carries it onto a sphere.
//!
//! # A host drawing a terrain
//!
//! The host owns the device, the queue and the targets; the terrain records into them. Depth is
//! reversed-Z: clear it to 0 (or call [`clear`]).
//!
//! ```no_run
//! use std::path::Path;
//! use terrain::{Description, Scene, Targets, Terrain};
//!
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let scene = Scene::load(Path::new("sketches/jacksboro.toml"))?;
//! let description = Description::new(scene)?;
//!
//! // The host's device, created with what the terrain asks for.
//! let instance =
//!     wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
//! let adapter = pollster::block_on(instance.request_adapter(&Default::default()))?;
//! let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
//!     label: Some("host"),
//!     required_features: Description::optional_features(adapter.features()),
//!     required_limits: description.required_limits(),
//!     ..Default::default()
//! }))?;
//!
//! // The host's targets, here textures of its own; a window's surface texture serves as well.
//! let (width, height) = (640, 480);
//! let targets = Targets {
//!     colour: wgpu::TextureFormat::Rgba8UnormSrgb,
//!     depth: wgpu::TextureFormat::Depth32Float,
//!     samples: 1,
//! };
//! let texture = |format| {
//!     device.create_texture(&wgpu::TextureDescriptor {
//!         label: Some("host target"),
//!         size: wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
//!         mip_level_count: 1,
//!         sample_count: 1,
//!         dimension: wgpu::TextureDimension::D2,
//!         format,
//!         usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
//!         view_formats: &[],
//!     })
//! };
//! let colour = texture(targets.colour).create_view(&Default::default());
//! let depth = texture(targets.depth).create_view(&Default::default());
//!
//! let mut camera = description.camera(width, height)?;
//! let mut terrain = Terrain::new(&device, &queue, targets, description)?;
//! for _frame in 0..100 {
//!     terrain.prepare(&camera)?;
//!     let mut encoder = device.create_command_encoder(&Default::default());
//!     terrain::clear(&mut encoder, &colour, &depth);
//!     terrain.record(&mut encoder, &colour, &depth)?;
//!     // ... the host's own geometry, drawn with `Terrain::view_proj(&camera)` ...
//!     queue.submit([encoder.finish()]);
//!     camera.eye += camera.forward * 10.0;
//! }
//! # Ok(())
//! # }
//! ```
//!
//! # Heights without a GPU
//!
//! ```
//! use glam::DVec2;
//! use terrain::{Ground, Scene, scene};
//!
//! let scene = Scene::parse("[sketch]\nsynthetic = \"hills\"\n", ".".into()).unwrap();
//! let atlas = scene::load_atlas(&scene)?;
//! let detail = scene::detail_of(&scene, &atlas);
//! let ground = Ground::new(&scene, &atlas, &detail);
//! let centre = atlas.origin + DVec2::new(atlas.dx, atlas.dy) * (atlas.width() as f64 / 2.0);
//! let z = ground.height_at(centre, 0.0)?.expect("ground inside the sketch");
//! assert!(z.is_finite());
//! # Ok::<(), terrain::Error>(())
//! ```
//!
//! Rules: the library prints nothing and writes no file it was not asked to: its notes go
//! through the `log` crate, its long work reports to [`progress`]. It holds no command line,
//! chart, progress bar or image metric: those are the tools' (the `terrain-cli` crate and its
//! `terrain` binary). Rejected: one crate for both, where every embedder compiled the commands'
//! dependencies.

#![deny(missing_docs)]
// Builds without zstd (WebAssembly) leave the pyramid builders out, the only users of some
// readers' helpers; builds for other than x86-64 leave the CPU stage's AVX2 paths out, the only
// readers of some of its scratch. Those builds are checked to compile, not linted.
#![cfg_attr(
    not(all(feature = "zstd", target_arch = "x86_64")),
    allow(dead_code, unused_imports, unused_variables)
)]

// The crate's own tests name it as its users do.
#[cfg(test)]
extern crate self as terrain;

mod beyond;
mod camera;
#[cfg(test)]
mod checks;
mod detail;
mod error;
mod geomipmap;
mod gpu;
mod host;
pub mod io;
mod light;
mod lod;
mod names;
pub mod planet;
pub mod progress;
mod query;
pub mod readback;
mod render;
pub mod scene;
pub mod sketch;
pub mod stage;
pub mod surface;

// The versions of wgpu and glam the API's types are of, for a host to name them by.
pub use glam;
pub use wgpu;

pub use camera::{Camera, Geo};
pub use detail::Detail;
pub use error::{Error, Result, Role};
pub use gpu::alloc;
pub use gpu::context::{GpuContext, Needs};
pub use gpu::counters::{FrameCounters, PassCounters};
pub use gpu::frame_io::PassTimes;
pub use gpu::output::Targets;
pub use gpu::uniforms::View;
pub use gpu::work::{Work, WorkPerPx};
pub use host::{Description, FrameInfo, Terrain, clear};
pub use light::Light;
pub use lod::baseline::Baselines;
pub use lod::clipmaps::Clipmaps;
pub use lod::reference::Reference;
pub use lod::warped::Warped;
pub use names::Named;
pub use query::{Ground, PlanetGround};
pub use render::{Frame, Renderer, covered_px, needs, world_positions};
pub use scene::{Mode, Scene};
pub use sketch::Atlas;

/// The names a frame's passes are timed and reported by: the keys of [`PassTimes`] and of
/// `passes_ms` in the tools' JSON.
pub mod pass {
    use crate::gpu;

    /// The warp & zoom pass: the warped geometry image upsampled to the mesh.
    pub const WARP_ZOOM: &str = gpu::warp_zoom::WarpZoomPass::NAME;
    /// The mesh split pass: each vertex's split octave and its procedural displacement.
    pub const MESH_SPLIT: &str = gpu::mesh_split::MeshSplitPass::NAME;
    /// The normals pass of the warped mesh.
    pub const NORMALS: &str = gpu::normals::NormalsPass::NAME;
    /// The terrain pass: the mesh drawn and shaded, with the sky.
    pub const TERRAIN: &str = gpu::terrain::TerrainPass::NAME;
    /// The ray-marched reference.
    pub const REFERENCE: &str = gpu::reference::ReferencePass::NAME;
    /// The spherical clipmaps' mesh.
    pub const CLIPMAPS: &str = gpu::clipmaps::ClipmapsPass::NAME;
    /// A planet's drawing pass.
    pub const PLANET: &str = gpu::planet::PlanetPass::NAME;
    /// The output pass that resolves a frame into the host's colour target.
    pub const OUTPUT: &str = gpu::output::OutputPass::NAME;
}
