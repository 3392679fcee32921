//! The GPU plumbing (device and its ledger, bindings, shader composition, read-back, counters,
//! the tile cache's binding) and the passes more than one mode runs: warp & zoom, normals, the
//! terrain pass (with the sky), the sun map and the output pass. A mode's own passes live in its
//! folder under `lod/` (mesh split, the reference, clipmaps and the planet pass). Each pass is a
//! struct owning its pipeline, bind-group layout and resources, with a WGSL file of the same name
//! in `shaders/` and its bindings listed once ([`bindings`]), both in its [`pipeline::Shader`];
//! [`crate::render::Renderer`] runs the passes as a flat list.

pub mod alloc;
pub mod bindings;
pub mod context;
pub mod counters;
pub mod formats;
pub mod frame_io;
pub mod normals;
pub mod output;
pub mod pipeline;
pub mod shaders;
pub mod shared;
pub mod snapshot;
pub mod stream;
pub mod sun_map;
pub mod terrain;
pub mod uniforms;
pub mod warp_zoom;
pub mod work;

/// The shaders of the passes every mode may run, a row a pass; each scheme lists its own
/// (`lod::Scheme::shaders`), and the naga checks run over both (`lod::shaders`).
#[cfg(test)]
pub const SHADERS: [pipeline::Shader; 5] = [
    warp_zoom::SHADER,
    normals::SHADER,
    terrain::SHADER,
    output::SHADER,
    sun_map::SHADER,
];
