//! What each pass asks of the GPU, counted by the adapter: vertex and fragment shader
//! invocations, primitives out of the clipper, compute invocations (WebGPU's pipeline statistics
//! queries, where the adapter has them: Vulkan drivers, Mesa's lavapipe among them; not GL).
//! These are the figures a change to a pass is judged by on a machine without a GPU, where
//! timings come from a CPU rasteriser.
//!
//! Rules: every pass records through a [`Probe`], which writes its timestamps (where the renderer
//! times passes) and wraps each of its GPU passes in a statistics query (where it counts them);
//! a pass of several GPU passes (the terrain's G-buffer and shading) counts each in a slot of its
//! own, summed by name when read. A query left unwritten is never resolved. Rejected: counting
//! invocations in the shaders with atomics, which changes the work it counts; what a pixel's
//! shading evaluates is counted so, in a variant of its own ([`super::work`]).

use super::alloc::{Alloc, Buffer, Tracked};
use super::context::GpuContext;
use super::frame_io::{Timer, read_buffer};
use crate::error::Result;
use std::cell::RefCell;

/// The statistics counted, in the order a query's results hold them (their bits' order).
const KINDS: wgpu::PipelineStatisticsTypes =
    wgpu::PipelineStatisticsTypes::VERTEX_SHADER_INVOCATIONS
        .union(wgpu::PipelineStatisticsTypes::CLIPPER_PRIMITIVES_OUT)
        .union(wgpu::PipelineStatisticsTypes::FRAGMENT_SHADER_INVOCATIONS)
        .union(wgpu::PipelineStatisticsTypes::COMPUTE_SHADER_INVOCATIONS);

/// GPU passes one of the renderer's passes may record (the terrain pass's G-buffer, shading
/// and depth copy).
const PER_PASS: u32 = 3;

/// Where each resolved query lands: resolve offsets must be aligned to this.
const STRIDE: u64 = wgpu::QUERY_RESOLVE_BUFFER_ALIGNMENT;

/// One pass's counts in a frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct PassCounters {
    /// Vertex shader invocations.
    pub vertex_invocations: u64,
    /// Fragment shader invocations (per sample where a frame is multisampled and shaded per
    /// sample; per pixel and covered quad otherwise).
    pub fragment_invocations: u64,
    /// Primitives out of the clipper: the triangles rasterised.
    pub primitives: u64,
    /// Compute shader invocations.
    pub compute_invocations: u64,
}

impl PassCounters {
    fn add(&mut self, o: PassCounters) {
        self.vertex_invocations += o.vertex_invocations;
        self.fragment_invocations += o.fragment_invocations;
        self.primitives += o.primitives;
        self.compute_invocations += o.compute_invocations;
    }
}

/// The counts of a frame's passes, by pass name, in the order they ran.
pub type FrameCounters = Vec<(&'static str, PassCounters)>;

/// A renderer's statistics queries: [`PER_PASS`] slots for each of its passes.
pub struct Counters {
    names: &'static [&'static str],
    queries: Tracked<wgpu::QuerySet>,
    resolve: Buffer,
    read: Buffer,
    /// The slots written since the last [`Counters::resolve`].
    written: RefCell<Vec<u32>>,
}

impl Counters {
    /// `None` where the device was opened without pipeline statistics queries.
    pub fn new(device: &Alloc, names: &'static [&'static str]) -> Option<Counters> {
        let features = device.device.features();
        if !features.contains(wgpu::Features::PIPELINE_STATISTICS_QUERY) {
            return None;
        }
        let slots = names.len() as u32 * PER_PASS;
        let buffer = |label, usage| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: slots as u64 * STRIDE,
                usage,
                mapped_at_creation: false,
            })
        };
        Some(Counters {
            names,
            queries: device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("pass counters"),
                ty: wgpu::QueryType::PipelineStatistics(KINDS),
                count: slots,
            }),
            resolve: buffer(
                "counters",
                wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
            ),
            read: buffer(
                "counters read",
                wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            ),
            written: RefCell::new(Vec::new()),
        })
    }

    /// The slot of GPU pass `sub` of pass `name`, marked written.
    fn slot(&self, name: &str, sub: u32) -> u32 {
        let pass = self
            .names
            .iter()
            .position(|n| *n == name)
            .unwrap_or_else(|| panic!("pass {name} is not one of the counters' {:?}", self.names))
            as u32;
        let slot = pass * PER_PASS + sub.min(PER_PASS - 1);
        self.written.borrow_mut().push(slot);
        slot
    }

    /// Resolves the slots written this frame, each to its own aligned place, and copies them out.
    pub fn resolve(&self, encoder: &mut wgpu::CommandEncoder) {
        for &slot in self.written.borrow().iter() {
            let at = slot as u64 * STRIDE;
            encoder.resolve_query_set(&self.queries, slot..slot + 1, &self.resolve, at);
        }
        let size = self.resolve.size();
        encoder.copy_buffer_to_buffer(&self.resolve, 0, &self.read, 0, size);
    }

    /// The counts of the frame resolved, after its submission completed, summed by pass.
    pub fn read(&self, ctx: &GpuContext) -> Result<FrameCounters> {
        let words: Vec<u64> = read_buffer(ctx, &self.read, |b| bytemuck::cast_slice(b).to_vec())?;
        let mut out: FrameCounters = Vec::new();
        let mut written = std::mem::take(&mut *self.written.borrow_mut());
        written.sort_unstable();
        written.dedup();
        for slot in written {
            let k = (slot as u64 * STRIDE / 8) as usize;
            let counts = PassCounters {
                vertex_invocations: words[k],
                primitives: words[k + 1],
                fragment_invocations: words[k + 2],
                compute_invocations: words[k + 3],
            };
            let name = self.names[(slot / PER_PASS) as usize];
            match out.iter_mut().find(|(n, _)| *n == name) {
                Some((_, c)) => c.add(counts),
                None => out.push((name, counts)),
            }
        }
        Ok(out)
    }
}

/// What a pass records about itself as it runs: its timestamps where the renderer times passes,
/// its counts where it counts them. The default records neither (a bake, a host's frame).
#[derive(Clone, Copy, Default)]
pub struct Probe<'a> {
    /// The frame's pass timer.
    pub timer: Option<&'a Timer>,
    /// The frame's statistics queries.
    pub counters: Option<&'a Counters>,
}

impl<'a> Probe<'a> {
    /// The timestamp writes of compute pass `name`.
    pub fn compute(&self, name: &str) -> Option<wgpu::ComputePassTimestampWrites<'a>> {
        self.timer.map(|t| t.compute(name))
    }

    /// The timestamp writes of render pass `name`.
    pub fn render(&self, name: &str) -> Option<wgpu::RenderPassTimestampWrites<'a>> {
        self.timer.map(|t| t.render(name))
    }

    /// Starts counting GPU pass `sub` of compute pass `name`; [`Probe::end_compute`] ends it.
    pub fn begin_compute(&self, pass: &mut wgpu::ComputePass, name: &str, sub: u32) {
        if let Some(c) = self.counters {
            pass.begin_pipeline_statistics_query(&c.queries, c.slot(name, sub));
        }
    }

    /// Ends what [`Probe::begin_compute`] started.
    pub fn end_compute(&self, pass: &mut wgpu::ComputePass) {
        if self.counters.is_some() {
            pass.end_pipeline_statistics_query();
        }
    }

    /// Starts counting GPU pass `sub` of render pass `name`; [`Probe::end_render`] ends it.
    pub fn begin_render(&self, pass: &mut wgpu::RenderPass, name: &str, sub: u32) {
        if let Some(c) = self.counters {
            pass.begin_pipeline_statistics_query(&c.queries, c.slot(name, sub));
        }
    }

    /// Ends what [`Probe::begin_render`] started.
    pub fn end_render(&self, pass: &mut wgpu::RenderPass) {
        if self.counters.is_some() {
            pass.end_pipeline_statistics_query();
        }
    }
}
