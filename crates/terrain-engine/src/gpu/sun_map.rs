//! The sketch's sun clearance map (`shaders/sun_map.wgsl`): the shadow ray of
//! `shaders/shared/shading.wgsl` (`sketch_sun_clearance`) marched once from the centre of every
//! texel of every pyramid level, its least clearance kept, instead of once per pixel and frame.
//! The terrain pass reads the four texels around a pixel on the level of its footprint, the level
//! its own march would start from (`SUN_MAP`): where all four see the whole sun, or none of it,
//! so does the pixel; elsewhere, on shadow boundaries and near the sketch's edges, it marches.
//!
//! Rules: made for a whole sketch drawn by the mesh modes with shadows on (a tile pyramid and
//! the reference march per pixel); remade on the frame whose sun differs from the one it was made
//! for, and only then, its pipeline compiled for that frame and let go after it (a renderer keeps
//! no code it runs once); laid out as the atlas's levels, a float per texel. Rejected:
//! interpolating the texels' clearance or visibility, which loses steep ridges' shadows (a steep
//! crop of the bundled DEM: 36 dB from the march; docs/decisions.md, “The sketch's shadow from a
//! map”).

use super::alloc::{Alloc, Buffer};
use super::bindings::{Binding, bind_group, buffer, layout};
use super::pipeline::compute_pipeline;
use super::shaders::Key;
use crate::error::Result;
use crate::sketch::Atlas;
use std::cell::Cell;
use wgpu::ShaderStages as S;

/// The pass's shader, `shaders/sun_map.wgsl`.
pub const SHADER: crate::gpu::pipeline::Shader = shader!("sun_map", BINDINGS);

/// `shaders/sun_map.wgsl`'s bindings.
pub const BINDINGS: &[Binding] = &[
    Binding::frame(S::COMPUTE),
    Binding::atlas(S::COMPUTE),
    Binding::wanted(S::COMPUTE),
    Binding::work(S::COMPUTE),
    Binding::sun_seen(S::COMPUTE),
    // Declared where the shading it imports draws a ramp (never set for this pass's scenes).
    Binding::ramp(S::COMPUTE),
    Binding::drape(S::COMPUTE),
    Binding::storage_rw(10, "seen_out", S::COMPUTE),
];

pub struct SunMap {
    pipeline: wgpu::ComputePipeline,
    bind_group: wgpu::BindGroup,
    /// A float per atlas texel, at the atlas's own indices.
    pub seen: Buffer,
    /// Level 0's texels: the pass's grid.
    size: [u32; 2],
    /// The sun direction the map holds, once made.
    made_for: Cell<Option<[f32; 3]>>,
}

impl SunMap {
    /// The pass's name: its label and its WGSL file.
    pub const NAME: &'static str = SHADER.name;

    /// The map of `atlas` (whole, uploaded as `atlas_buffer`), read with the frame's uniforms.
    pub fn new(
        device: &Alloc,
        frame: &wgpu::Buffer,
        atlas: &Atlas,
        atlas_buffer: &wgpu::Buffer,
    ) -> Result<SunMap> {
        // The march alone: no detail, no tallies, the sketch read whole.
        let (name, key) = (Self::NAME, Key::SHADOWS);
        let layout = layout(device, name, BINDINGS, 0, key);
        let pipeline = compute_pipeline(device, &SHADER, key, &layout)?;
        let seen = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("sun seen"),
            size: atlas_buffer.size(),
            usage: wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        });
        let resources = [
            ("frame", buffer(frame)),
            ("atlas", buffer(atlas_buffer)),
            ("seen_out", buffer(&seen)),
        ];
        let bind_group = bind_group(device, name, &layout, BINDINGS, 0, key, &resources)?;
        let level0 = &atlas.levels[0];
        Ok(SunMap {
            pipeline,
            bind_group,
            seen,
            size: [level0.width as u32, level0.height as u32],
            made_for: Cell::new(None),
        })
    }

    /// Records the map's making where the frame's `sun` is not the one it holds; the frame's
    /// uniforms must already be written.
    pub fn record(&self, encoder: &mut wgpu::CommandEncoder, sun: [f32; 3]) {
        if self.made_for.get() == Some(sun) {
            return;
        }
        let probe = super::counters::Probe::default();
        let (b, size) = (&self.bind_group, self.size);
        super::pipeline::dispatch_grid(encoder, Self::NAME, &self.pipeline, b, size, probe);
        self.made_for.set(Some(sun));
    }
}
