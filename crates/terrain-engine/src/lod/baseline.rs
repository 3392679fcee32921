//! The baselines: the terrain function baked once per scene on a regular grid (or, over a tile
//! pyramid, read where it is drawn), drawn by GeoMipMapping (blocks, levels, stitching,
//! geomorphing; `crate::geomipmap`) or whole (brute force).
//! A frame is one named pass, the terrain draw.
//!
//! The bake is the warp & zoom pass run with Φ the identity grid: the same code, hence the same
//! terrain function, as the warped mode's (heights, split octave K − bias, octaves up to K as
//! geometry); the terrain pass's GEOMIPMAP variant draws it with the same shading and bump detail.
//!
//! Over a tile pyramid nothing is baked. The grid is the sketch at its own spacing (k = 0, no
//! octave in it), each block's δ and height range come from level 0's tiles
//! ([`crate::sketch::tiles::blocks`]), and the GRID_STREAMED vertex shader evaluates each vertex it draws
//! as the bake would, reading the sketch through the tile cache (which the reads mark), so GPU
//! memory is the tile pool plus this frame's blocks and indices.
//! Rejected: baking blocks on demand into a cache of pages. The README's view of the 32,768²
//! pyramid sees 472,057 blocks to its far plane: 17 KiB each at 33² vertices, 8 GB; baked at
//! their own level they would need a pool per level and a rebake at every level change. The
//! price of evaluating instead is GPU time: up to 11 bicubic reads per vertex with mesh normals
//! and morphing (the same view: 6.1 s a frame on llvmpipe for 1.9 M triangles, median of 200).

use super::{CpuTimes, Lod, Shared};
use crate::camera::Camera;
use crate::error::{Error, Result};
use crate::geomipmap::{BlockGpu, Blocks, Grid, LodParams, Selection, Templates};
use crate::gpu::alloc::{Alloc, Buffer, Ledger};
use crate::gpu::context::GpuContext;
use crate::gpu::counters::Probe;
use crate::gpu::frame_io::{read_pod_later, uniform_buffer};
use crate::gpu::normals::NormalsPass;
use crate::gpu::shaders::Key;
use crate::gpu::shared::{BakedGrid, Heights};
use crate::gpu::terrain::{TerrainPass, Variant};
use crate::gpu::uniforms::{BlockUniforms, FrameInputs, FrameUniforms};
use crate::gpu::warp_zoom::WarpZoomPass;
use crate::scene::Mode;
use crate::sketch::Atlas;
use std::any::Any;
use std::hash::{Hash, Hasher};
use std::sync::Arc;
use web_time::Instant;

/// The largest baked grid the default K allows (2^22 vertices: 64 MiB of vertices and normals).
const MAX_DEFAULT_VERTICES: f64 = 4_194_304.0;

/// K, the octaves baked into the grid: the finest grid (up to K = 3) within the vertex budget.
fn default_k(atlas: &Atlas) -> u32 {
    let side = (atlas.max_corner() - atlas.origin).max_element() / atlas.d_atlas();
    (0..=3u32)
        .rev()
        .find(|&k| (side * (1u32 << k) as f64 + 1.0).powi(2) <= MAX_DEFAULT_VERTICES)
        .unwrap_or(0)
}

/// Cells a grid's side is a multiple of: the largest block but one (65), so that the grids of
/// blocks of 17, 33 and 65 vertices are one grid and their renderers share one bake
/// (`gpu::shared`); blocks of 129 round to their own 128. A grid over a tile pyramid is rounded
/// alike: it is the grid the sketch held whole bakes at k = 0.
const GRID_UNIT: usize = 64;

/// The grid over the square enclosing the atlas at spacing d_atlas / 2^k, in blocks of `cells`
/// cells a side, its side rounded up to a multiple of `unit` cells (at least `cells`), its
/// heights not yet baked.
pub fn grid_of(atlas: &Atlas, k: u32, cells: usize, unit: usize) -> Grid {
    let spacing = atlas.d_atlas() / (1u32 << k) as f64;
    let side = (atlas.max_corner() - atlas.origin).max_element();
    let unit = unit.max(cells);
    let units = ((side / (unit as f64 * spacing)).ceil() as usize).max(1);
    Grid {
        n: unit * units + 1,
        cells,
        spacing,
        origin: atlas.origin,
        heights: Default::default(),
    }
}

/// Bakes the terrain function over [`grid_of`]'s grid; its normals too unless the scene lights
/// the terrain per pixel; warp & zoom in the scheme's variant `key`. A renderer on the same device
/// holding the same bake (the same sketch, terrain function, K and grid) lends it instead.
pub fn bake(s: &Shared, key: Key, k: u32, cells: usize) -> Result<(Grid, Arc<BakedGrid>)> {
    let (ctx, atlas, detail) = (s.ctx, s.atlas, s.detail);
    let mut grid = grid_of(atlas, k, cells, GRID_UNIT);
    let n = grid.n;
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
    let uniforms = FrameUniforms::for_bake(atlas, detail, atlas.origin, n as u32);
    // What the bake reads: the sketch (its buffer, alive while this renderer holds it), the frame's
    // uniforms (the terrain function, the grid's origin and size), the variant, and the spacing.
    let mut hasher = std::collections::hash_map::DefaultHasher::new();
    s.atlas_binding.atlas.hash(&mut hasher);
    bytemuck::bytes_of(&uniforms).hash(&mut hasher);
    let pixel_normals = s.scene.render.pixel_normals;
    let shared_key = format!(
        "{:x} {key:?} k{k} n{n} {}",
        hasher.finish(),
        if pixel_normals {
            "pixel normals"
        } else {
            "mesh normals"
        }
    );
    let baked = s.alloc.shared.baked_grid(shared_key, || {
        bake_grid(s, key, &uniforms, &grid, pixel_normals)
    })?;
    if let Some(heights) = baked.heights.get()? {
        grid.heights = heights;
    }
    Ok((grid, baked))
}

/// Runs warp & zoom (and the normals) over `grid` with Φ the identity and reads its heights back:
/// natively before it returns; in a browser, which cannot wait for its GPU, a few of the page's
/// tasks later ([`Baselines::ready`]).
fn bake_grid(
    s: &Shared,
    key: Key,
    uniforms: &FrameUniforms,
    grid: &Grid,
    pixel_normals: bool,
) -> Result<BakedGrid> {
    let (ctx, device) = (s.ctx, &s.alloc);
    let (n, spacing) = (grid.n, grid.spacing);
    let frame = uniform_buffer(device);
    ctx.queue
        .write_buffer(&frame, 0, bytemuck::bytes_of(uniforms));
    let warp_zoom = WarpZoomPass::new(device, &frame, s.atlas_binding, n as u32, n as u32, key)?;
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
    drop(phi);
    let normals = match pixel_normals {
        true => None,
        false => Some(NormalsPass::new(
            device,
            &frame,
            &warp_zoom.detailed,
            n as u32,
        )?),
    };
    let mut encoder = device.create_command_encoder(&Default::default());
    warp_zoom.record(&mut encoder, n as u32, Probe::default());
    if let Some(pass) = &normals {
        pass.record(&mut encoder, n as u32, Probe::default());
    }
    ctx.queue.submit([encoder.finish()]);
    let detailed = warp_zoom.into_detailed();
    let heights = Heights::default();
    let read = heights.clone();
    read_pod_later::<[f32; 4]>(ctx, &detailed, move |v| {
        read.set(v.map(|v| v.iter().map(|p| p[2]).collect()));
    });
    #[cfg(not(target_arch = "wasm32"))]
    {
        ctx.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| Error::device("device lost while waiting", e))?;
        ctx.raised()?;
        if heights.get()?.is_none() {
            return Err(Error::Internal("the baked grid's read-back never ran"));
        }
    }
    Ok(BakedGrid {
        detailed,
        normals: normals.map(NormalsPass::into_normals),
        heights,
    })
}

/// GeoMipMap or brute force (`kind`) over one baked grid, or GeoMipMap over a streamed sketch.
pub struct Baselines {
    /// Which baseline: [`Mode::Geomipmap`] or [`Mode::Bruteforce`].
    pub kind: Mode,
    /// The grid the blocks divide (its heights empty when streamed).
    pub grid: Grid,
    /// The baked grid on the GPU; `None` over a tile pyramid, whose grid vertices the terrain
    /// pass evaluates where it draws them.
    pub bake: Option<Arc<BakedGrid>>,
    /// The grid's blocks: each one's δ per level and the box of its vertices.
    pub blocks: Blocks,
    /// Triangle templates per level: the interior, and each side's strip toward a neighbour.
    pub templates: Templates,
    /// The last frame's level of each block, and which blocks it drew.
    pub selection: Selection,
    /// τ, the exact bound, geomorphing: how GeoMipMap chooses levels.
    pub params: LodParams,
    /// Indices the last frame drew.
    indices: usize,
    /// The blocks whose indices the index buffer holds: a frame of the same blocks (brute force's
    /// every frame, GeoMipMap's held view) writes none.
    written: Option<Vec<BlockGpu>>,
    block_buffer: Buffer,
    /// Blocks the block buffer holds, and indices the index buffer holds.
    capacity: (usize, usize),
    /// Visible blocks left out of the last frame because the buffers could not hold them.
    pub dropped: usize,
    /// Whether a note has said so (once per renderer).
    noted: bool,
    terrain: TerrainPass,
    /// The renderer's ledger, which the index buffer's growth is counted in.
    ledger: Ledger,
    /// Precomputation (bake, δ, quadtree), milliseconds.
    pub precompute_ms: f64,
}

/// Indices per block a streamed GeoMipMap frame has room for (`geomipmap.max_blocks` sets the
/// blocks): a far block at its coarsest level draws 6, a near one hundreds. The README's view of
/// the 32,768² pyramid draws 472,057 blocks and 5.7 M indices, 12 a block. Never less than room
/// for 8 blocks at their finest level, so a small budget still draws the nearest ground.
const INDICES_PER_BLOCK: usize = 16;

/// The grid and its blocks over a tile pyramid: the sketch at its own spacing (k = 0), δ and
/// height ranges measured on its tiles ([`crate::sketch::tiles::blocks`]) with the vertices on the water
/// where the sketch dips below it, as the bake's. What the bake would put in the grid beyond the
/// sketch (octaves, with k > 0 or a negative bias) is refused, since δ would not see it.
fn streamed_grid(
    s: &Shared,
    pyramid: &crate::sketch::tiles::Pyramid,
    cells: usize,
) -> Result<(Grid, Blocks)> {
    let (scene, atlas) = (s.scene, s.atlas);
    if scene.geomipmap.k.is_some_and(|k| k > 0) {
        return Err(Error::value(
            "geomipmap.k",
            "over a tile pyramid GeoMipMap's grid is the sketch's own nodes: k = 0",
        ));
    }
    if s.detail.octaves > 0 && s.detail.bias < 0.0 {
        return Err(Error::value(
            "detail.bias",
            "a negative bias puts octaves into GeoMipMap's grid, whose δ over a tile pyramid is \
             measured on the sketch alone: use a bias of 0 or more",
        ));
    }
    s.atlas_binding
        .check_vertex_marks(s.ctx, "render.mode", "GeoMipMap", "use warped mode")?;
    let grid = grid_of(atlas, 0, cells, GRID_UNIT);
    let per_side = grid.blocks_per_side();
    let stats =
        crate::sketch::tiles::blocks::block_stats_of(pyramid, cells, per_side, atlas.water_m)?;
    let blocks = Blocks::from_stats(per_side, cells, grid.spacing, stats.delta, stats.z_range);
    Ok((grid, blocks))
}

/// GeoMipMap's scheme: `compare` sweeps τ 0.5, 1, 2, 4, 8 px at blocks of 17, 33 and 65
/// vertices (`geomipmap.tau`, `geomipmap.block`); its settings of one block size share a
/// renderer, τ set per frame ([`Lod::retune`]).
pub(crate) const GEOMIPMAP: super::Scheme = super::Scheme {
    build: |s| Ok(Box::new(Baselines::new(s, Mode::Geomipmap)?)),
    needs: <Baselines as Lod>::needs,
    flags,
    sweep: |_, _, _| {
        let taus = [0.5, 1.0, 2.0, 4.0, 8.0];
        Ok([17.0, 33.0, 65.0]
            .into_iter()
            .flat_map(|block| taus.map(|tau| vec![tau, block]))
            .collect())
    },
    shaders: &[],
    setting: |scene, _| Some(vec![scene.geomipmap.tau, scene.geomipmap.block as f64]),
};

/// Brute force's scheme: `compare` sweeps grid spacings d_atlas/2^K for K = 0 up to the finest
/// the device and the vertex budget allow ([`Baselines::default_k`]; `geomipmap.k`).
pub(crate) const BRUTEFORCE: super::Scheme = super::Scheme {
    build: |s| Ok(Box::new(Baselines::new(s, Mode::Bruteforce)?)),
    needs: <Baselines as Lod>::needs,
    flags,
    shaders: &[],
    sweep: |_, atlas, _| Ok((0..=default_k(atlas)).map(|k| vec![k as f64]).collect()),
    setting: |scene, atlas| {
        let k = scene.geomipmap.k.unwrap_or_else(|| default_k(atlas));
        Some(vec![k as f64])
    },
};

/// The flags of both: a mesh over a baked grid, or over the tile cache where no grid is baked.
fn flags(s: &Shared, key: &mut Key) {
    super::mesh_flags(s, key);
    key.set(Key::GEOMIPMAP, true);
    // No baked grid: the vertex shader evaluates the grid through the tile cache.
    key.set(Key::GRID_STREAMED, s.atlas.pyramid.is_some());
}

impl Baselines {
    /// `geomipmap.k`'s default for `atlas`: the octaves baked into the grid, the finest grid (up
    /// to K = 3) within a vertex budget of 2^22.
    pub fn default_k(atlas: &Atlas) -> u32 {
        default_k(atlas)
    }

    /// `kind`: `Mode::Geomipmap` or `Mode::Bruteforce`.
    pub fn new(s: &Shared, kind: Mode) -> Result<Baselines> {
        let start = Instant::now();
        let (scene, detail) = (s.scene, s.detail);
        let device = &s.alloc;
        let key = super::shader_key(s, kind);
        let cells = scene.geomipmap.block as usize - 1;
        let (grid, blocks, bake) = match &s.atlas.pyramid {
            Some(pyramid) => {
                let (grid, blocks) = streamed_grid(s, pyramid, cells)?;
                (grid, blocks, None)
            }
            None => {
                let k = scene.geomipmap.k.unwrap_or_else(|| default_k(s.atlas));
                let (grid, bake) = bake(s, key, k, cells)?;
                // Made from the heights by `ready`: natively below, in a browser once they
                // arrive.
                let blocks = Blocks::from_stats(0, cells, grid.spacing, Vec::new(), Vec::new());
                (grid, blocks, Some(bake))
            }
        };
        let templates = Templates::new(&grid);
        let all = grid.blocks_per_side().pow(2);
        let capacity = match bake {
            Some(_) => (all, all * cells * cells * 6),
            // An index is slot << slot_shift | vertex: no more slots than 32 bits number.
            None => {
                let max = scene.geomipmap.max_blocks as usize;
                (
                    all.min(max).min(1 << (32 - grid.slot_shift())),
                    (all * cells * cells * 6)
                        .min((max * INDICES_PER_BLOCK).max(8 * cells * cells * 6)),
                )
            }
        };
        let block_buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("blocks"),
            size: (capacity.0 * std::mem::size_of::<BlockGpu>()) as u64,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let variant = Variant {
            key,
            normals: bake
                .as_ref()
                .and_then(|b| b.normals.as_ref())
                .map(|normals| wgpu::Buffer::clone(normals)),
            importance: None,
            geomipmap: Some((wgpu::Buffer::clone(&block_buffer), capacity.1 as u64)),
            atlas: s.atlas_binding.clone(),
            samples: s.samples,
        };
        let n = grid.n as u32;
        let (width, height) = (scene.camera.width, scene.camera.height);
        let detailed = bake.as_ref().map(|b| &*b.detailed);
        let terrain = TerrainPass::new(device, s.frame, detailed, n, width, height, &variant)?;
        let g = &scene.geomipmap;
        let mut baselines = Baselines {
            kind,
            params: LodParams {
                tau: g.tau,
                exact: g.exact,
                morph: g.morph,
                reach_m: detail.reach_m(),
            },
            precompute_ms: start.elapsed().as_secs_f64() * 1e3,
            grid,
            bake,
            blocks,
            templates,
            selection: Selection::default(),
            indices: 0,
            written: None,
            block_buffer,
            capacity,
            dropped: 0,
            noted: false,
            terrain,
            ledger: s.alloc.ledger.clone(),
        };
        baselines.ready()?;
        baselines.precompute_ms = start.elapsed().as_secs_f64() * 1e3;
        Ok(baselines)
    }

    /// The baked grid's heights are still on their way back (in a browser): nothing is drawn.
    fn pending(&self) -> bool {
        self.bake.is_some() && self.blocks.per_side == 0
    }
}

impl Baselines {
    /// Keeps the nearest blocks the buffers hold when the selection is larger (only a streamed
    /// grid's buffers are smaller than its blocks), counting the rest in `dropped`.
    fn fit(&mut self) {
        let sel = &mut self.selection;
        let (max_blocks, max_indices) = self.capacity;
        self.dropped = 0;
        // A baked grid's buffers hold every block at level 0: nothing to count.
        let whole = self.blocks.per_side.pow(2) * self.blocks.cells.pow(2) * 6;
        if sel.gpu.len() <= max_blocks
            && (max_indices >= whole
                || sel
                    .gpu
                    .iter()
                    .map(|g| self.templates.count(g))
                    .sum::<usize>()
                    <= max_indices)
        {
            return;
        }
        let mut order: Vec<usize> = (0..sel.gpu.len()).collect();
        order.sort_by(|&a, &b| {
            let d = |i: usize| sel.distance.get(sel.visible[i]).copied().unwrap_or(0.0);
            d(a).total_cmp(&d(b))
        });
        let mut indices = 0;
        let kept: Vec<usize> = order
            .into_iter()
            .take(max_blocks)
            .take_while(|&i| {
                indices += self.templates.count(&sel.gpu[i]);
                indices <= max_indices
            })
            .collect();
        if !self.noted {
            self.noted = true;
            log::info!(
                "GeoMipMap sees {} blocks; its buffers hold {} blocks and {} indices, so the \
                 farthest {} are left out",
                sel.gpu.len(),
                max_blocks,
                max_indices,
                sel.gpu.len() - kept.len()
            );
        }
        self.dropped = sel.gpu.len() - kept.len();
        sel.gpu = kept.iter().map(|&i| sel.gpu[i]).collect();
        sel.visible = kept.iter().map(|&i| sel.visible[i]).collect();
    }
}

impl Lod for Baselines {
    fn passes(&self) -> &'static [&'static str] {
        &[TerrainPass::NAME]
    }

    /// Nothing beyond the sketch: the baked grid's size depends on the sketch and K, and
    /// [`bake`] holds it to the adapter's limit itself, with advice.
    fn needs(_: &crate::scene::Scene) -> u64 {
        0
    }

    /// Whether the baked grid's heights are back, and the blocks made from them.
    fn ready(&mut self) -> Result<bool> {
        if !self.pending() {
            return Ok(true);
        }
        let Some(heights) = self
            .bake
            .as_ref()
            .map(|b| b.heights.get())
            .transpose()?
            .flatten()
        else {
            return Ok(false);
        };
        self.grid.heights = heights;
        self.blocks = Blocks::new(&self.grid);
        // Brute force draws every block at level 0, always.
        if self.kind == Mode::Bruteforce {
            self.selection.all_at(&self.grid, &self.blocks, 0);
        }
        Ok(true)
    }

    /// τ chooses the blocks each frame: the grid and its δ stay.
    fn retune(&mut self, key: &str, value: f64) {
        if key == "geomipmap.tau" {
            self.params.tau = value;
        }
    }

    /// A fresh renderer uploads its blocks and indices with its first frame.
    fn forget(&mut self) {
        self.written = None;
    }

    fn resize(&mut self, alloc: &crate::gpu::alloc::Alloc, width: u32, height: u32) -> Result<()> {
        self.terrain.resize(alloc, width, height)?;
        Ok(())
    }

    /// Chooses the blocks for `camera` (GeoMipMap; brute force draws all, always).
    fn prepare(&mut self, _: &Atlas, camera: &Camera) -> CpuTimes {
        let start = Instant::now();
        if self.kind == Mode::Geomipmap && !self.pending() {
            self.selection
                .select(&self.grid, &self.blocks, camera, &self.params);
        }
        CpuTimes {
            us: start.elapsed().as_secs_f64() * 1e6,
            ..CpuTimes::default()
        }
    }

    fn frame_inputs<'a>(&'a self, f: &mut FrameInputs<'a>) {
        let g = &self.grid;
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
        probe: Probe,
    ) -> &'static [&'static str] {
        let queue = &ctx.queue;
        self.fit();
        let blocks = &self.selection.gpu;
        let same = self.written.as_deref().is_some_and(|w| {
            bytemuck::cast_slice::<_, u8>(w) == bytemuck::cast_slice::<_, u8>(blocks)
        });
        if !same {
            queue.write_buffer(&self.block_buffer, 0, bytemuck::cast_slice(blocks));
            let device = Alloc {
                device: &ctx.device,
                ledger: &self.ledger,
                shared: &ctx.shared,
            };
            // Made for the upload and dropped after it: a baked grid's whole index list is
            // tens of MB, which a renderer kept between frames would hold for nothing.
            let mut indices = Vec::new();
            self.templates.append(blocks, &mut indices);
            self.indices = indices.len();
            self.terrain.write_indices(&device, queue, &indices);
            // Kept in the allocation of the blocks written before.
            match &mut self.written {
                Some(written) => written.clone_from(blocks),
                None => self.written = Some(blocks.clone()),
            }
        }
        let draw = self.indices > 0;
        self.terrain.record(encoder, draw, probe);
        &[TerrainPass::NAME]
    }

    fn output(&self) -> crate::gpu::output::Source<'_> {
        self.terrain.output()
    }

    fn read_positions(&self, ctx: &GpuContext, camera: &Camera) -> Result<Vec<[f32; 4]>> {
        self.terrain.read_positions(ctx, camera)
    }

    fn triangles(&self) -> u64 {
        self.indices as u64 / 3
    }

    fn visible(&self) -> bool {
        !self.selection.visible.is_empty()
    }

    fn blocks(&self) -> Option<usize> {
        Some(self.selection.gpu.len())
    }

    fn precompute(&self) -> Option<(f64, u64)> {
        Some((
            self.precompute_ms,
            self.bake.as_ref().map_or(0, |b| b.bytes()),
        ))
    }

    fn as_any(&self) -> &dyn Any {
        self
    }

    fn as_any_mut(&mut self) -> &mut dyn Any {
        self
    }
}
