//! One frame on the GPU as a flat list of passes: upload Φ and the uniform block, warp & zoom,
//! normals, terrain (with the sky). Sky-only frames skip the first two and the terrain draw.
//! Timing: timestamp queries per pass where the adapter has them, else wall time around submit.

use super::context::GpuContext;
use super::normals::NormalsPass;
use super::terrain::{TerrainPass, Variant};
use super::uniforms::{FrameUniforms, View};
use super::warp_zoom::WarpZoomPass;
use crate::atlas::Atlas;
use crate::error::{Error, Result};
use serde::Serialize;
use std::time::Instant;

/// Milliseconds per pass (`None` where the adapter cannot time passes).
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct PassTimes {
    pub warp_zoom_ms: Option<f64>,
    pub normals_ms: Option<f64>,
    pub terrain_ms: Option<f64>,
}

#[derive(Clone, Copy, Debug, Serialize)]
pub struct FrameStats {
    /// GPU time of the frame: the passes' sum with timestamps, else submit-to-idle wall time.
    pub gpu_ms: f64,
    /// Submit to readback done, always measured (it includes the readback copy and the wait).
    pub gpu_wall_ms: f64,
    pub passes: PassTimes,
    pub triangles: u64,
}

pub struct Options {
    pub n: u32,
    pub mesh: u32,
    pub width: u32,
    pub height: u32,
    pub octaves: u32,
    pub bump: bool,
    pub view: View,
}

pub struct Renderer {
    frame: wgpu::Buffer,
    _atlas: wgpu::Buffer,
    warp_zoom: WarpZoomPass,
    normals: NormalsPass,
    terrain: TerrainPass,
    importance: Option<wgpu::Buffer>,
    readback: wgpu::Buffer,
    timer: Option<Timer>,
    width: u32,
    height: u32,
    /// Bytes of GPU memory this renderer allocated.
    pub gpu_bytes: u64,
}

struct Timer {
    queries: wgpu::QuerySet,
    resolve: wgpu::Buffer,
    read: wgpu::Buffer,
    period_ns: f64,
}

const PASSES: u32 = 3;

impl Renderer {
    pub fn new(ctx: &GpuContext, atlas: &Atlas, o: &Options) -> Result<Renderer> {
        let device = &ctx.device;
        let frame = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("frame"),
            size: std::mem::size_of::<FrameUniforms>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
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
        };
        let terrain = TerrainPass::new(
            device,
            &frame,
            &warp_zoom.detailed,
            &normals.normals,
            o.mesh,
            o.width,
            o.height,
            &variant,
        )?;
        let padded = padded_row(o.width) as u64;
        let readback = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("readback"),
            size: padded * o.height as u64,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let timer = ctx.timestamps.then(|| Timer {
            queries: device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("pass times"),
                ty: wgpu::QueryType::Timestamp,
                count: 2 * PASSES,
            }),
            resolve: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("timestamps"),
                size: 16 * PASSES as u64,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            }),
            read: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("timestamps read"),
                size: 16 * PASSES as u64,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            period_ns: ctx.queue.get_timestamp_period() as f64,
        });
        let mesh_bytes = (o.mesh * o.mesh) as u64 * 16;
        let gpu_bytes = std::mem::size_of::<FrameUniforms>() as u64
            + atlas_bytes
            + (o.n * o.n) as u64 * 8
            + 2 * mesh_bytes
            + terrain.triangles() * 12
            + 2 * (o.width * o.height) as u64 * 4
            + padded * o.height as u64
            + importance.as_ref().map_or(0, |b| b.size());
        Ok(Renderer {
            frame,
            _atlas: atlas_buffer,
            warp_zoom,
            normals,
            terrain,
            importance,
            readback,
            timer,
            width: o.width,
            height: o.height,
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
        let q = self.timer.as_ref().map(|t| &t.queries);
        let compute_ts = |k: u32| {
            q.map(|qs| wgpu::ComputePassTimestampWrites {
                query_set: qs,
                beginning_of_pass_write_index: Some(2 * k),
                end_of_pass_write_index: Some(2 * k + 1),
            })
        };
        if visible {
            self.warp_zoom.record(&mut encoder, compute_ts(0));
            self.normals.record(&mut encoder, compute_ts(1));
        }
        let render_ts = q.map(|qs| wgpu::RenderPassTimestampWrites {
            query_set: qs,
            beginning_of_pass_write_index: Some(4),
            end_of_pass_write_index: Some(5),
        });
        self.terrain.record(&mut encoder, visible, render_ts);
        let padded = padded_row(self.width);
        encoder.copy_texture_to_buffer(
            self.terrain.colour.as_image_copy(),
            wgpu::TexelCopyBufferInfo {
                buffer: &self.readback,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(padded),
                    rows_per_image: None,
                },
            },
            wgpu::Extent3d {
                width: self.width,
                height: self.height,
                depth_or_array_layers: 1,
            },
        );
        if let Some(t) = &self.timer {
            // A sky-only frame wrote only the terrain pass's pair; resolve offsets must be aligned,
            // so it goes to the start of the buffer.
            let used = if visible { 0..2 * PASSES } else { 4..6 };
            encoder.resolve_query_set(&t.queries, used, &t.resolve, 0);
            encoder.copy_buffer_to_buffer(&t.resolve, 0, &t.read, 0, 16 * PASSES as u64);
        }
        let start = Instant::now();
        queue.submit([encoder.finish()]);
        let pixels = read_buffer(ctx, &self.readback, |bytes| {
            unpad(bytes, self.width, self.height)
        })?;
        let wall_ms = start.elapsed().as_secs_f64() * 1e3;
        let passes = self.pass_times(ctx, visible)?;
        let summed = [passes.warp_zoom_ms, passes.normals_ms, passes.terrain_ms]
            .iter()
            .map(|v| v.unwrap_or(0.0))
            .sum::<f64>();
        let stats = FrameStats {
            gpu_ms: if self.timer.is_some() {
                summed
            } else {
                wall_ms
            },
            gpu_wall_ms: wall_ms,
            passes,
            triangles: if visible { self.terrain.triangles() } else { 0 },
        };
        Ok((pixels, stats))
    }

    /// Milliseconds per pass from the timestamp queries of the frame just rendered. A sky-only
    /// frame resolved only the terrain pass's pair, to the start of the buffer.
    fn pass_times(&self, ctx: &GpuContext, visible: bool) -> Result<PassTimes> {
        let Some(t) = &self.timer else {
            return Ok(PassTimes::default());
        };
        let ticks: Vec<u64> = read_buffer(ctx, &t.read, |b| bytemuck::cast_slice(b).to_vec())?;
        let ms = |k: usize| {
            let dt = ticks[2 * k + 1].saturating_sub(ticks[2 * k]);
            Some(dt as f64 * t.period_ns * 1e-6)
        };
        Ok(if visible {
            PassTimes {
                warp_zoom_ms: ms(0),
                normals_ms: ms(1),
                terrain_ms: ms(2),
            }
        } else {
            PassTimes {
                warp_zoom_ms: Some(0.0),
                normals_ms: Some(0.0),
                terrain_ms: ms(0),
            }
        })
    }

    /// The detailed geometry image of the last frame, read back (for tests).
    pub fn read_detailed(&self, ctx: &GpuContext) -> Result<Vec<[f32; 4]>> {
        read_vec4(ctx, &self.warp_zoom.detailed)
    }

    /// The normals of the last frame, read back (for tests).
    pub fn read_normals(&self, ctx: &GpuContext) -> Result<Vec<[f32; 4]>> {
        read_vec4(ctx, &self.normals.normals)
    }
}

fn read_vec4(ctx: &GpuContext, source: &wgpu::Buffer) -> Result<Vec<[f32; 4]>> {
    {
        let size = source.size();
        let staging = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("detailed readback"),
            size,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        encoder.copy_buffer_to_buffer(source, 0, &staging, 0, size);
        ctx.queue.submit([encoder.finish()]);
        read_buffer(ctx, &staging, |b| bytemuck::cast_slice(b).to_vec())
    }
}

/// The atlas pyramid in a read-only storage buffer (see `shaders/shared/atlas.wgsl` for why not
/// a texture).
fn upload_atlas(ctx: &GpuContext, atlas: &Atlas) -> (wgpu::Buffer, u64) {
    let texels = super::uniforms::atlas_texels(atlas);
    let buffer = wgpu::util::DeviceExt::create_buffer_init(
        &ctx.device,
        &wgpu::util::BufferInitDescriptor {
            label: Some("sketch atlas"),
            contents: bytemuck::cast_slice(&texels),
            usage: wgpu::BufferUsages::STORAGE,
        },
    );
    (buffer, texels.len() as u64 * 4)
}

fn padded_row(width: u32) -> u32 {
    (width * 4).div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT
}

/// Rows top first (the render target's), without the copy's row padding.
fn unpad(bytes: &[u8], width: u32, height: u32) -> Vec<u8> {
    let padded = padded_row(width) as usize;
    let row = width as usize * 4;
    (0..height as usize)
        .flat_map(|y| bytes[y * padded..y * padded + row].iter().copied())
        .collect()
}

fn read_buffer<T>(
    ctx: &GpuContext,
    buffer: &wgpu::Buffer,
    f: impl FnOnce(&[u8]) -> T,
) -> Result<T> {
    let slice = buffer.slice(..);
    let (tx, rx) = std::sync::mpsc::channel();
    slice.map_async(wgpu::MapMode::Read, move |r| {
        let _ = tx.send(r);
    });
    ctx.wait()?;
    rx.recv()
        .map_err(|_| Error::Gpu("readback callback never ran".into()))?
        .map_err(|e| Error::Gpu(format!("readback failed: {e}")))?;
    let out = {
        let view = slice
            .get_mapped_range()
            .map_err(|e| Error::Gpu(format!("readback mapping: {e}")))?;
        f(&view)
    };
    buffer.unmap();
    Ok(out)
}
