//! `terrain-engine`: the machinery behind the `terrain` crate, geometry image warping
//! (Dachsbacher & Stamminger, *Rendering Procedural Terrain by Geometry Image Warping*, 2004)
//! with its baselines. A host draws with `terrain`, the front door, whose every item is one of
//! this crate's, re-exported; the `terrain` tools measure with this crate's wider surface: a
//! [`Renderer`] on a device of its own with its counters and pass times, the CPU stage on its
//! own ([`stage`]), tile pyramids ([`sketch::tiles`]), the scene's placement helpers.
//!
//! The modules follow a frame, in the order data flows through it: [`scene`] (the terrain's
//! description, and building a camera, the detail and the sketch from it) → [`sketch`] (the
//! height map read into its [`Atlas`]; [`sketch::tiles`] for pyramids larger than memory) → [`stage`]
//! (the CPU stage: sketch map → importance → warp → Φ, measured by its quality) → the GPU passes
//! (warp & zoom, mesh split, normals, terrain, reference, output; named in [`pass`]) driven by
//! one [`Renderer`] through a level-of-detail scheme ([`Mode`]: [`Warped`], [`Baselines`],
//! [`Reference`], [`Clipmaps`]). [`Detail`] is the procedural model both sides share; [`planet`]
//! carries it onto a sphere. [`Terrain`] draws the same renderer into a host's targets.
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

/// The [`gpu::pipeline::Shader`] of WGSL file `shaders/<name>.wgsl`, whose bindings are `$bindings`.
macro_rules! shader {
    ($name:literal, $bindings:expr) => {
        crate::gpu::pipeline::Shader {
            name: $name,
            source: include_str!(concat!(
                env!("CARGO_MANIFEST_DIR"),
                "/shaders/",
                $name,
                ".wgsl"
            )),
            bindings: $bindings,
        }
    };
}

// The crate's own tests name it as its users do.
#[cfg(test)]
extern crate self as terrain_engine;

mod beyond;
mod camera;
#[cfg(test)]
mod checks;
mod detail;
mod error;
pub mod flight;
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
pub mod truth;

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
    pub const MESH_SPLIT: &str = crate::lod::warped::mesh_split::MeshSplitPass::NAME;
    /// The normals pass of the warped mesh.
    pub const NORMALS: &str = gpu::normals::NormalsPass::NAME;
    /// The terrain pass: the mesh drawn and shaded, with the sky.
    pub const TERRAIN: &str = gpu::terrain::TerrainPass::NAME;
    /// The ray-marched reference.
    pub const REFERENCE: &str = crate::lod::reference::pass::ReferencePass::NAME;
    /// The spherical clipmaps' mesh.
    pub const CLIPMAPS: &str = crate::lod::clipmaps::pass::ClipmapsPass::NAME;
    /// A planet's drawing pass.
    pub const PLANET: &str = crate::lod::clipmaps::planet::PlanetPass::NAME;
    /// The output pass that resolves a frame into the host's colour target.
    pub const OUTPUT: &str = gpu::output::OutputPass::NAME;
}
