//! One warped-mode frame on the GPU as a flat list of passes: upload Φ and the uniform block, warp
//! & zoom, normals, terrain (with the sky). Sky-only frames skip the first two and the terrain draw.
//! Timing: timestamp queries per pass where the adapter has them, else wall time around submit.

use super::context::GpuContext;
use super::frame_io::{ColourReadback, Timer, read_vec4, uniform_buffer, upload_atlas};
use super::normals::NormalsPass;
use super::terrain::{TerrainPass, Variant};
use super::uniforms::{FrameUniforms, View};
use super::warp_zoom::WarpZoomPass;
use crate::atlas::Atlas;
use crate::error::Result;
use std::time::Instant;

pub use super::frame_io::{FrameStats, PassTimes};

pub struct Options {
    pub n: u32,
    pub mesh: u32,
    pub width: u32,
    pub height: u32,
    pub octaves: u32,
    pub bump: bool,
    pub view: View,
    /// Also write each pixel's ground position (for screen-space error).
    pub positions: bool,
}

/// The passes of a warped frame, in order.
const PASS_NAMES: [&str; 3] = [WarpZoomPass::NAME, NormalsPass::NAME, TerrainPass::NAME];

pub struct Renderer {
    frame: wgpu::Buffer,
    _atlas: wgpu::Buffer,
    warp_zoom: WarpZoomPass,
    normals: NormalsPass,
    terrain: TerrainPass,
    importance: Option<wgpu::Buffer>,
    readback: ColourReadback,
    timer: Option<Timer>,
    /// Bytes of GPU memory this renderer allocated.
    pub gpu_bytes: u64,
}

impl Renderer {
    pub fn new(ctx: &GpuContext, atlas: &Atlas, o: &Options) -> Result<Renderer> {
        let device = &ctx.device;
        let frame = uniform_buffer(device);
        let (atlas_buffer, atlas_bytes) = upload_atlas(ctx, atlas);
        let detail = o.octaves > 0;
        let warp_zoom = WarpZoomPass::new(device, &frame, &atlas_buffer, o.n, o.mesh, detail)?;
        let normals = NormalsPass::new(device, &frame, &warp_zoom.detailed, o.mesh)?;
        let importance = (o.view == View::Importance).then(|| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("importance"),
                size: (o.n * o.n) as u64 * 4,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        });
        let variant = Variant {
            noise: detail,
            bump: detail && o.bump,
            importance: importance.clone(),
            geomipmap: None,
            positions: o.positions,
        };
        let (detailed, normal_buffer) = (&warp_zoom.detailed, &normals.normals);
        let terrain = TerrainPass::new(
            device,
            &frame,
            detailed,
            normal_buffer,
            o.mesh,
            o.width,
            o.height,
            &variant,
        )?;
        let readback = ColourReadback::new(device, o.width, o.height);
        let mesh_bytes = (o.mesh * o.mesh) as u64 * 16;
        let gpu_bytes = frame.size()
            + atlas_bytes
            + (o.n * o.n) as u64 * 8
            + 2 * mesh_bytes
            + terrain.triangles() * 12
            + terrain.target_bytes()
            + readback.bytes()
            + importance.as_ref().map_or(0, |b| b.size());
        Ok(Renderer {
            frame,
            _atlas: atlas_buffer,
            warp_zoom,
            normals,
            terrain,
            importance,
            readback,
            timer: Timer::new(ctx, &PASS_NAMES),
            gpu_bytes,
        })
    }

    /// Renders one frame and reads it back as RGBA8 (sRGB), rows top first.
    pub fn render(
        &mut self,
        ctx: &GpuContext,
        uniforms: &FrameUniforms,
        phi: &[[f32; 2]],
        importance: Option<&[f32]>,
        visible: bool,
    ) -> Result<(Vec<u8>, FrameStats)> {
        let queue = &ctx.queue;
        queue.write_buffer(&self.frame, 0, bytemuck::bytes_of(uniforms));
        if visible {
            queue.write_buffer(&self.warp_zoom.phi, 0, bytemuck::cast_slice(phi));
            if let (Some(buffer), Some(values)) = (&self.importance, importance) {
                queue.write_buffer(buffer, 0, bytemuck::cast_slice(values));
            }
        }
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        let t = self.timer.as_ref();
        // A sky-only frame runs the terrain pass alone (for the sky).
        let ran: &[&'static str] = if visible {
            &PASS_NAMES
        } else {
            &PASS_NAMES[2..]
        };
        if visible {
            let warp_zoom = t.map(|t| t.compute(WarpZoomPass::NAME));
            self.warp_zoom.record(&mut encoder, warp_zoom);
            self.normals
                .record(&mut encoder, t.map(|t| t.compute(NormalsPass::NAME)));
        }
        let terrain = t.map(|t| t.render(TerrainPass::NAME));
        self.terrain.record(&mut encoder, visible, terrain);
        self.readback.record(&mut encoder, &self.terrain.colour);
        if let Some(t) = t {
            t.resolve(&mut encoder, ran);
        }
        let start = Instant::now();
        queue.submit([encoder.finish()]);
        let pixels = self.readback.read(ctx)?;
        let wall_ms = start.elapsed().as_secs_f64() * 1e3;
        let passes = match t {
            Some(t) => t.read(ctx, ran)?,
            None => PassTimes::default(),
        };
        let triangles = if visible { self.terrain.triangles() } else { 0 };
        Ok((
            pixels,
            FrameStats::new(passes, t.is_some(), wall_ms, triangles),
        ))
    }

    /// The detailed geometry image of the last frame, read back (for tests).
    pub fn read_detailed(&self, ctx: &GpuContext) -> Result<Vec<[f32; 4]>> {
        read_vec4(ctx, &self.warp_zoom.detailed)
    }

    /// Ground positions of the last frame's pixels (metres from the frame origin, w = 1 on
    /// ground); needs `positions` at construction (else the depth was not kept).
    pub fn read_positions(
        &self,
        ctx: &GpuContext,
        view_proj: glam::DMat4,
    ) -> Result<Vec<[f32; 4]>> {
        self.terrain.read_positions(ctx, view_proj)
    }

    /// The normals of the last frame, read back (for tests).
    pub fn read_normals(&self, ctx: &GpuContext) -> Result<Vec<[f32; 4]>> {
        read_vec4(ctx, &self.normals.normals)
    }
}
