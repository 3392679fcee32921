//! `terrain`: large terrains whose rough shape comes from a height map (the *sketch*) and whose
//! fine detail is procedural, rendered by geometry image warping (Dachsbacher & Stamminger,
//! *Rendering Procedural Terrain by Geometry Image Warping*, 2004).
//!
//! A host application draws a terrain with its own device: a [`Description`] (a [`Scene`] with
//! its sketch read) states the limits and features a device needs, a [`Terrain`] prepares each
//! frame on the CPU and records it into the host's encoder, into the host's colour and depth
//! views. [`Terrain::ground`] (or [`Ground`] from a [`Description`], without a GPU) answers
//! heights, normals and rays on the ground the terrain draws; [`Terrain::pick`] turns a pixel and
//! its depth into a world point. [`Terrain::render_to_image`] reads a frame back, over the
//! [`readback`] module a host may use for its own textures.
//!
//! This crate is the front door: the types a host names. The machinery behind it (the CPU
//! stage, the passes, tile pyramids, the renderer with a device of its own that the `terrain`
//! tools measure with) is the `terrain-engine` crate. Rejected: one crate whose every module
//! was public for the tools' sake, where a host met a hundred and sixty items to find the five
//! it needs.
//!
//! # A host drawing a terrain
//!
//! The host owns the device, the queue and the targets; the terrain records into them. Depth is
//! reversed-Z: clear it to 0 (or call [`clear`]). docs/embedding.md in the repository is a whole
//! program of this, with the conventions as formulas.
//!
//! ```no_run
//! use std::path::Path;
//! use terrain::{Description, Scene, Targets, Terrain, wgpu};
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
//! use terrain::{Description, Ground, Scene, glam::DVec2};
//!
//! let scene = Scene::parse("[sketch]\nsynthetic = \"hills\"\n", ".".into()).unwrap();
//! let description = Description::new(scene)?;
//! let detail = description.detail();
//! let ground = Ground::new(description.scene(), description.atlas(), &detail);
//! let atlas = description.atlas();
//! let centre = atlas.origin + DVec2::new(atlas.dx, atlas.dy) * (atlas.width() as f64 / 2.0);
//! let z = ground.height_at(centre, 0.0)?.expect("ground inside the sketch");
//! assert!(z.is_finite());
//! # Ok::<(), terrain::Error>(())
//! ```
//!
//! Rules: the library prints nothing and writes no file it was not asked to: its notes go
//! through the `log` crate. Every item here is the engine's own type, re-exported, so a host
//! that needs the engine as well mixes the two freely.

#![deny(missing_docs)]

// The versions of wgpu and glam the API's types are of, for a host to name them by.
pub use terrain_engine::{glam, wgpu};

pub use terrain_engine::scene::{Mode, Scene};
pub use terrain_engine::sketch::Atlas;
pub use terrain_engine::stage::StageTimes;
pub use terrain_engine::{
    Camera, Description, Detail, Error, FrameInfo, Geo, Ground, Light, PlanetGround, Result, Role,
    Targets, Terrain, View, clear,
};

/// Reading a texture back to the CPU: [`Terrain::render_to_image`]'s and the tools' one way,
/// for a host's own textures as well.
pub mod readback {
    pub use terrain_engine::readback::{Readback, depths, read_texture};
}

/// The scene file's schema: one section per table of the TOML (docs/scene.md in the repository
/// lists every key), for a host that builds or adjusts a scene in code.
pub mod scene {
    pub use terrain_engine::scene::{
        CameraSection, DetailSection, Fault, GeoMipMapSection, ImportanceSection, LightSection,
        Mode, Msaa, Outside, PathKey, PathSection, PlanetSection, ReferenceSection, RenderSection,
        Scene, SketchSection, StreamSection, Style, SurfaceSection, Triangulation, WarpMethod,
        WarpSection,
    };
}

/// The sketch: the height map read into its [`Atlas`], with how it was read and where it lies
/// on the Earth.
pub mod sketch {
    pub use terrain_engine::sketch::{Atlas, Georef, Level, LoadOptions, Units};
}
