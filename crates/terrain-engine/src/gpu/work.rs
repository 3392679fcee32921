//! What the shaders evaluate per pixel, counted by the counting variant (`Key::COUNT_WORK`,
//! `shaders/shared/work.wgsl`): noise octaves, steps of the sun's shadow ray and texels read from
//! the sketch, tallied by each invocation and added to one buffer as each pixel (or sample) of the
//! shading passes is finished. With [`crate::gpu::counters`]' pipeline statistics these are the
//! figures a change to the shading is judged by where no GPU times it.
//!
//! Rules: only a renderer made to count ([`crate::Renderer::counting_work`]) compiles the variant
//! and holds the buffer; its frames are drawn as any other's, and the tallies are cleared before
//! each frame and read back with it. Vertices and the compute passes over the mesh tally without
//! adding: the figures are per pixel. Rejected: counting in every renderer behind a uniform
//! switch, which ships the atomics to every user's shaders and slows the frames it times.

use super::alloc::{Alloc, Buffer};
use super::context::GpuContext;
use super::frame_io::read_buffer;
use crate::error::Result;

/// The tallies' words: octaves, shadow steps, atlas taps, invocations (`work` in the WGSL), each
/// a 64-bit sum as two words, low then high.
const WORDS: u64 = 8;

/// A frame's per-pixel work, summed over the shading passes' invocations.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Work {
    /// Noise octaves evaluated (one octave's lattice noise at one point).
    pub octaves: u64,
    /// Steps of the shadow rays marched toward the sun (the sketch's and the detail's).
    pub shadow_steps: u64,
    /// Texels read from the sketch's atlas.
    pub atlas_taps: u64,
    /// Fragment (or, for the reference, compute) invocations that added their tallies.
    pub invocations: u64,
}

/// [`Work`] per pixel showing ground (`render --json`'s `work_per_px`).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct WorkPerPx {
    /// Noise octaves evaluated per pixel.
    pub octaves: f64,
    /// Shadow-ray steps per pixel.
    pub shadow_steps: f64,
    /// Atlas texels read per pixel.
    pub atlas_taps: f64,
}

impl Work {
    /// Per pixel of `px` (the pixels showing ground, [`crate::covered_px`]).
    pub fn per_px(&self, px: u64) -> WorkPerPx {
        let px = px.max(1) as f64;
        WorkPerPx {
            octaves: self.octaves as f64 / px,
            shadow_steps: self.shadow_steps as f64 / px,
            atlas_taps: self.atlas_taps as f64 / px,
        }
    }
}

/// The counting variant's buffer, bound as `work`, and its read-back.
pub struct Tally {
    pub buffer: Buffer,
    read: Buffer,
}

impl Tally {
    pub fn new(alloc: &Alloc) -> Tally {
        let buffer = |label, usage| {
            alloc.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: WORDS * 4,
                usage,
                mapped_at_creation: false,
            })
        };
        Tally {
            buffer: buffer(
                "work",
                wgpu::BufferUsages::STORAGE
                    | wgpu::BufferUsages::COPY_SRC
                    | wgpu::BufferUsages::COPY_DST,
            ),
            read: buffer(
                "work read",
                wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            ),
        }
    }

    /// Zeroes the tallies before a frame's passes.
    pub fn clear(&self, encoder: &mut wgpu::CommandEncoder) {
        encoder.clear_buffer(&self.buffer, 0, None);
    }

    /// Copies the tallies out after a frame's passes.
    pub fn copy(&self, encoder: &mut wgpu::CommandEncoder) {
        encoder.copy_buffer_to_buffer(&self.buffer, 0, &self.read, 0, WORDS * 4);
    }

    /// The tallies copied, after the frame's submission completed.
    pub fn read(&self, ctx: &GpuContext) -> Result<Work> {
        let w: Vec<u32> = read_buffer(ctx, &self.read, |b| bytemuck::cast_slice(b).to_vec())?;
        let sum = |i: usize| w[2 * i] as u64 | (w[2 * i + 1] as u64) << 32;
        Ok(Work {
            octaves: sum(0),
            shadow_steps: sum(1),
            atlas_taps: sum(2),
            invocations: sum(3),
        })
    }
}
