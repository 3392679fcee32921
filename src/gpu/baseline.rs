//! The baselines on the GPU: the terrain function baked once per scene on a regular grid, drawn
//! by GeoMipMapping (blocks, levels, stitching, geomorphing) or whole (brute force).
//!
//! The bake is the warp & zoom pass run with Φ the identity grid: the same code, hence the same
//! terrain function, as the warped mode's (heights, split octave K − bias, octaves up to K as
//! geometry); the terrain pass's GEOMIPMAP variant draws it with the same shading and bump detail.

use super::context::GpuContext;
use super::frame_io::{
    ColourReadback, FrameStats, PassTimes, Timer, read_vec4, uniform_buffer, upload_atlas,
};
use super::normals::NormalsPass;
use super::terrain::{TerrainPass, Variant};
use super::uniforms::{FrameUniforms, View};
use super::warp_zoom::WarpZoomPass;
use crate::atlas::Atlas;
use crate::detail::Detail;
use crate::error::{Error, Result};
use crate::geomipmap::{BlockGpu, Blocks, Grid, LodParams, Selection, Templates};
use std::time::Instant;

/// The largest baked grid the default K allows (2^22 vertices: 64 MiB of vertices and normals).
const MAX_DEFAULT_VERTICES: f64 = 4_194_304.0;

/// K, the octaves baked into the grid: the finest grid (up to K = 3) within the vertex budget.
pub fn default_k(atlas: &Atlas) -> u32 {
    let side = (atlas.max_corner() - atlas.origin).max_element() / atlas.d_atlas();
    (0..=3u32)
        .rev()
        .find(|&k| (side * (1u32 << k) as f64 + 1.0).powi(2) <= MAX_DEFAULT_VERTICES)
        .unwrap_or(0)
}

pub struct Bake {
    pub grid: Grid,
    pub detailed: wgpu::Buffer,
    pub normals: wgpu::Buffer,
    pub ms: f64,
    pub bytes: u64,
}

/// Bakes the terrain function over the square enclosing the atlas at spacing d_atlas / 2^k, in
/// blocks of `cells` cells a side.
pub fn bake(
    ctx: &GpuContext,
    atlas: &Atlas,
    atlas_buffer: &wgpu::Buffer,
    detail: &Detail,
    k: u32,
    cells: usize,
) -> Result<Bake> {
    let start = Instant::now();
    let spacing = atlas.d_atlas() / (1u32 << k) as f64;
    let side = (atlas.max_corner() - atlas.origin).max_element();
    let blocks = ((side / (cells as f64 * spacing)).ceil() as usize).max(1);
    let n = cells * blocks + 1;
    let bytes = (n * n) as u64 * 16;
    if bytes > ctx.limits.max_storage_buffer_binding_size {
        let advice = if k > 0 {
            "lower geomipmap.k"
        } else {
            "the sketch is too large to bake at its own spacing; crop it or use the warped mode"
        };
        return Err(Error::Gpu(format!(
            "a {n}² baked grid needs {} MiB buffers, the adapter allows {} MiB; {advice}",
            bytes >> 20,
            ctx.limits.max_storage_buffer_binding_size >> 20
        )));
    }
    let device = &ctx.device;
    let frame = uniform_buffer(device);
    let uniforms = FrameUniforms::for_bake(atlas, detail, atlas.origin, n as u32);
    ctx.queue
        .write_buffer(&frame, 0, bytemuck::bytes_of(&uniforms));
    let warp_zoom = WarpZoomPass::new(
        device,
        &frame,
        atlas_buffer,
        n as u32,
        n as u32,
        detail.octaves > 0,
    )?;
    let phi: Vec<[f32; 2]> = (0..n * n)
        .map(|v| {
            [
                ((v % n) as f64 * spacing) as f32,
                ((v / n) as f64 * spacing) as f32,
            ]
        })
        .collect();
    ctx.queue
        .write_buffer(&warp_zoom.phi, 0, bytemuck::cast_slice(&phi));
    let normals = NormalsPass::new(device, &frame, &warp_zoom.detailed, n as u32)?;
    let mut encoder = device.create_command_encoder(&Default::default());
    warp_zoom.record(&mut encoder, None);
    normals.record(&mut encoder, None);
    ctx.queue.submit([encoder.finish()]);
    let detailed = warp_zoom.into_detailed();
    let heights = read_vec4(ctx, &detailed)?.iter().map(|v| v[2]).collect();
    let grid = Grid {
        n,
        cells,
        spacing,
        origin: atlas.origin,
        heights,
    };
    Ok(Bake {
        grid,
        detailed,
        normals: normals.into_normals(),
        ms: start.elapsed().as_secs_f64() * 1e3,
        bytes: 2 * bytes,
    })
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Baseline {
    GeoMipMap,
    BruteForce,
}

pub struct BaselineOptions {
    pub width: u32,
    pub height: u32,
    pub bump: bool,
    pub view: View,
    pub k: u32,
    /// Cells per block side.
    pub cells: usize,
    pub kind: Baseline,
    /// Also write each pixel's ground position (for screen-space error).
    pub positions: bool,
}

pub struct BaselineRenderer {
    frame: wgpu::Buffer,
    _atlas: wgpu::Buffer,
    pub bake: Bake,
    pub blocks: Blocks,
    pub templates: Templates,
    pub selection: Selection,
    indices: Vec<u32>,
    block_buffer: wgpu::Buffer,
    terrain: TerrainPass,
    readback: ColourReadback,
    timer: Option<Timer>,
    pub kind: Baseline,
    /// Precomputation (bake, δ, quadtree), milliseconds.
    pub precompute_ms: f64,
    pub gpu_bytes: u64,
}

impl BaselineRenderer {
    pub fn new(
        ctx: &GpuContext,
        atlas: &Atlas,
        detail: &Detail,
        o: &BaselineOptions,
    ) -> Result<BaselineRenderer> {
        let start = Instant::now();
        let device = &ctx.device;
        let (atlas_buffer, atlas_bytes) = upload_atlas(ctx, atlas);
        let bake = bake(ctx, atlas, &atlas_buffer, detail, o.k, o.cells)?;
        let blocks = Blocks::new(&bake.grid);
        let templates = Templates::new(&bake.grid);
        let per_side = blocks.per_side;
        let capacity = (per_side * per_side * o.cells * o.cells * 6) as u64;
        let block_buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("blocks"),
            size: (per_side * per_side * std::mem::size_of::<BlockGpu>()) as u64,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let frame = uniform_buffer(device);
        let noise = detail.octaves > 0;
        let variant = Variant {
            noise,
            bump: noise && o.bump,
            importance: None,
            geomipmap: Some((block_buffer.clone(), capacity)),
            positions: o.positions,
        };
        let n = bake.grid.n as u32;
        let terrain = TerrainPass::new(
            device,
            &frame,
            &bake.detailed,
            &bake.normals,
            n,
            o.width,
            o.height,
            &variant,
        )?;
        let readback = ColourReadback::new(device, o.width, o.height);
        let mut selection = Selection::default();
        if o.kind == Baseline::BruteForce {
            selection.all_at(&bake.grid, &blocks, 0);
        }
        let gpu_bytes = frame.size()
            + atlas_bytes
            + bake.bytes
            + capacity * 4
            + block_buffer.size()
            + terrain.target_bytes()
            + readback.bytes();
        Ok(BaselineRenderer {
            frame,
            _atlas: atlas_buffer,
            precompute_ms: start.elapsed().as_secs_f64() * 1e3,
            bake,
            blocks,
            templates,
            selection,
            indices: Vec::new(),
            block_buffer,
            terrain,
            readback,
            timer: Timer::new(ctx, &[TerrainPass::NAME]),
            kind: o.kind,
            gpu_bytes,
        })
    }

    /// Chooses the blocks for `camera` (GeoMipMap; brute force draws all, always). Returns µs.
    pub fn select(&mut self, camera: &crate::camera::Camera, lod: &LodParams) -> f64 {
        let start = Instant::now();
        if self.kind == Baseline::GeoMipMap {
            self.selection
                .select(&self.bake.grid, &self.blocks, camera, lod);
        }
        start.elapsed().as_secs_f64() * 1e6
    }

    /// Ground positions of the last frame's pixels; needs `positions` at construction.
    pub fn read_positions(
        &self,
        ctx: &GpuContext,
        view_proj: glam::DMat4,
    ) -> Result<Vec<[f32; 4]>> {
        self.terrain.read_positions(ctx, view_proj)
    }

    /// Draws the current selection and reads the image back.
    pub fn render(
        &mut self,
        ctx: &GpuContext,
        uniforms: &FrameUniforms,
    ) -> Result<(Vec<u8>, FrameStats)> {
        let queue = &ctx.queue;
        queue.write_buffer(&self.frame, 0, bytemuck::bytes_of(uniforms));
        self.templates
            .append(&self.selection.gpu, &mut self.indices);
        queue.write_buffer(
            &self.block_buffer,
            0,
            bytemuck::cast_slice(&self.selection.gpu),
        );
        self.terrain.write_indices(queue, &self.indices);
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        let t = self.timer.as_ref();
        let draw = !self.indices.is_empty();
        self.terrain
            .record(&mut encoder, draw, t.map(|t| t.render(TerrainPass::NAME)));
        self.readback.record(&mut encoder, &self.terrain.colour);
        if let Some(t) = t {
            t.resolve(&mut encoder, &[TerrainPass::NAME]);
        }
        let start = Instant::now();
        queue.submit([encoder.finish()]);
        let pixels = self.readback.read(ctx)?;
        let wall_ms = start.elapsed().as_secs_f64() * 1e3;
        let passes = match t {
            Some(t) => t.read(ctx, &[TerrainPass::NAME])?,
            None => PassTimes::default(),
        };
        let triangles = self.indices.len() as u64 / 3;
        Ok((
            pixels,
            FrameStats::new(passes, t.is_some(), wall_ms, triangles),
        ))
    }
}
