//! The baselines: the terrain function baked once per scene on a regular grid, drawn by
//! GeoMipMapping (blocks, levels, stitching, geomorphing; `crate::geomipmap`) or whole (brute force).
//! A frame is one named pass, the terrain draw.
//!
//! The bake is the warp & zoom pass run with Φ the identity grid: the same code, hence the same
//! terrain function, as the warped mode's (heights, split octave K − bias, octaves up to K as
//! geometry); the terrain pass's GEOMIPMAP variant draws it with the same shading and bump detail.

use super::{CpuTimes, Lod, Shared};
use crate::camera::Camera;
use crate::error::{Error, Result};
use crate::geomipmap::{BlockGpu, Blocks, Grid, LodParams, Selection, Templates};
use crate::gpu::alloc::Buffer;
use crate::gpu::context::GpuContext;
use crate::gpu::frame_io::{ColourReadback, Timer, read_vec4, uniform_buffer};
use crate::gpu::normals::NormalsPass;
use crate::gpu::terrain::{Shading, TerrainPass, Variant};
use crate::gpu::uniforms::{BlockUniforms, FrameInputs, FrameUniforms};
use crate::gpu::warp_zoom::WarpZoomPass;
use crate::scene::Mode;
use crate::sketch::Atlas;
use std::any::Any;
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
    pub detailed: Buffer,
    /// The grid's normals, unless the terrain is lit per pixel.
    pub normals: Option<Buffer>,
    pub ms: f64,
}

impl Bake {
    /// GPU bytes the baked grid keeps: its positions, and its normals if it has them.
    pub fn bytes(&self) -> u64 {
        self.detailed.bytes() + self.normals.as_ref().map_or(0, |b| b.bytes())
    }
}

/// Bakes the terrain function over the square enclosing the atlas at spacing d_atlas / 2^k, in
/// blocks of `cells` cells a side; its normals too unless the scene lights the terrain per pixel.
pub fn bake(s: &Shared, k: u32, cells: usize) -> Result<Bake> {
    let (ctx, device, atlas, detail) = (s.ctx, &s.alloc, s.atlas, s.detail);
    let start = Instant::now();
    let spacing = atlas.d_atlas() / (1u32 << k) as f64;
    let side = (atlas.max_corner() - atlas.origin).max_element();
    let blocks = ((side / (cells as f64 * spacing)).ceil() as usize).max(1);
    let n = cells * blocks + 1;
    let bytes = (n * n) as u64 * 16;
    if bytes > ctx.limits.max_storage_buffer_binding_size {
        let advice = if k > 0 {
            "; lower geomipmap.k"
        } else {
            "; the sketch is too large to bake at its own spacing: crop it or use the warped mode"
        };
        return Err(Error::Limit {
            what: format!("a {n}² baked grid"),
            limit: "max_storage_buffer_binding_size",
            needed: bytes >> 20,
            allowed: ctx.limits.max_storage_buffer_binding_size >> 20,
            unit: " MiB",
            advice,
        });
    }
    let frame = uniform_buffer(device);
    let uniforms = FrameUniforms::for_bake(atlas, detail, atlas.origin, n as u32);
    ctx.queue
        .write_buffer(&frame, 0, bytemuck::bytes_of(&uniforms));
    let warp_zoom = WarpZoomPass::new(
        device,
        &frame,
        s.atlas_binding,
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
    let normals = if s.scene.render.pixel_normals {
        None
    } else {
        Some(NormalsPass::new(
            device,
            &frame,
            &warp_zoom.detailed,
            n as u32,
        )?)
    };
    let mut encoder = device.create_command_encoder(&Default::default());
    warp_zoom.record(&mut encoder, n as u32, None);
    if let Some(pass) = &normals {
        pass.record(&mut encoder, n as u32, None);
    }
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
        normals: normals.map(NormalsPass::into_normals),
        ms: start.elapsed().as_secs_f64() * 1e3,
    })
}

/// GeoMipMap or brute force (`kind`) over one baked grid.
pub struct Baselines {
    pub kind: Mode,
    pub bake: Bake,
    pub blocks: Blocks,
    pub templates: Templates,
    pub selection: Selection,
    /// τ, the exact bound, geomorphing: how GeoMipMap chooses levels.
    pub params: LodParams,
    indices: Vec<u32>,
    block_buffer: Buffer,
    terrain: TerrainPass,
    readback: ColourReadback,
    /// Precomputation (bake, δ, quadtree), milliseconds.
    pub precompute_ms: f64,
}

impl Baselines {
    /// `kind`: `Mode::Geomipmap` or `Mode::Bruteforce`.
    pub fn new(s: &Shared, kind: Mode) -> Result<Baselines> {
        let start = Instant::now();
        let (scene, detail) = (s.scene, s.detail);
        let device = &s.alloc;
        let k = scene.geomipmap.k.unwrap_or_else(|| default_k(s.atlas));
        let cells = scene.geomipmap.block as usize - 1;
        let bake = bake(s, k, cells)?;
        let blocks = Blocks::new(&bake.grid);
        let templates = Templates::new(&bake.grid);
        let per_side = blocks.per_side;
        let capacity = (per_side * per_side * cells * cells * 6) as u64;
        let block_buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("blocks"),
            size: (per_side * per_side * std::mem::size_of::<BlockGpu>()) as u64,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let noise = detail.octaves > 0;
        let variant = Variant {
            noise,
            bump: noise && scene.detail.bump,
            shading: match &bake.normals {
                Some(normals) => Shading::MeshNormals(wgpu::Buffer::clone(normals)),
                None => Shading::PixelNormals,
            },
            importance: None,
            geomipmap: Some((wgpu::Buffer::clone(&block_buffer), capacity)),
            positions: s.positions,
            atlas: s.atlas_binding.clone(),
            shadows: s.scene.render.shadows,
            detail_shadows: s.scene.render.detail_shadows,
            samples: s.samples,
        };
        let n = bake.grid.n as u32;
        let (width, height) = (scene.camera.width, scene.camera.height);
        let terrain =
            TerrainPass::new(device, s.frame, &bake.detailed, n, width, height, &variant)?;
        let readback = ColourReadback::new(device, width, height);
        let mut selection = Selection::default();
        if kind == Mode::Bruteforce {
            selection.all_at(&bake.grid, &blocks, 0);
        }
        let g = &scene.geomipmap;
        Ok(Baselines {
            kind,
            params: LodParams {
                tau: g.tau,
                exact: g.exact,
                morph: g.morph,
                reach_m: detail.reach_m(),
            },
            precompute_ms: start.elapsed().as_secs_f64() * 1e3,
            bake,
            blocks,
            templates,
            selection,
            indices: Vec::new(),
            block_buffer,
            terrain,
            readback,
        })
    }
}

impl Lod for Baselines {
    fn passes(&self) -> &'static [&'static str] {
        &[TerrainPass::NAME]
    }

    /// Chooses the blocks for `camera` (GeoMipMap; brute force draws all, always).
    fn prepare(&mut self, _: &Atlas, camera: &Camera) -> CpuTimes {
        let start = Instant::now();
        if self.kind == Mode::Geomipmap {
            self.selection
                .select(&self.bake.grid, &self.blocks, camera, &self.params);
        }
        CpuTimes {
            us: start.elapsed().as_secs_f64() * 1e6,
            ..CpuTimes::default()
        }
    }

    fn frame_inputs<'a>(&'a self, f: &mut FrameInputs<'a>) {
        let g = &self.bake.grid;
        f.mesh_origin = Some(g.origin);
        f.mesh = g.n as u32;
        f.block = BlockUniforms {
            cells: g.cells as u32,
            index_bits: g.slot_shift(),
            levels: g.levels() as u32,
            pad: 0,
        };
    }

    fn record(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        t: Option<&Timer>,
    ) -> &'static [&'static str] {
        let queue = &ctx.queue;
        self.templates
            .append(&self.selection.gpu, &mut self.indices);
        queue.write_buffer(
            &self.block_buffer,
            0,
            bytemuck::cast_slice(&self.selection.gpu),
        );
        self.terrain.write_indices(queue, &self.indices);
        let draw = !self.indices.is_empty();
        self.terrain
            .record(encoder, draw, t.map(|t| t.render(TerrainPass::NAME)));
        self.readback.record(encoder, &self.terrain.colour);
        &[TerrainPass::NAME]
    }

    fn read_image(&self, ctx: &GpuContext) -> Result<Vec<u8>> {
        self.readback.read(ctx)
    }

    fn read_positions(&self, ctx: &GpuContext, camera: &Camera) -> Result<Vec<[f32; 4]>> {
        self.terrain.read_positions(ctx, camera)
    }

    fn triangles(&self) -> u64 {
        self.indices.len() as u64 / 3
    }

    fn visible(&self) -> bool {
        !self.selection.visible.is_empty()
    }

    fn blocks(&self) -> Option<usize> {
        Some(self.selection.gpu.len())
    }

    fn precompute(&self) -> Option<(f64, u64)> {
        Some((self.precompute_ms, self.bake.bytes()))
    }

    fn as_any(&self) -> &dyn Any {
        self
    }

    fn as_any_mut(&mut self) -> &mut dyn Any {
        self
    }
}
