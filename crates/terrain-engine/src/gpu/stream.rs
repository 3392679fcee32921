//! A streamed sketch on the GPU: the tile cache's pool of pages and its page table in one
//! read-only storage buffer (the atlas binding every planar pass already has), and the marks the
//! shaders leave per page-table entry (`wanted`, cleared before each frame and read back after
//! it). The policy — what to load, keep and evict — is [`crate::sketch::tiles::cache`]'s; this moves the
//! bytes.
//!
//! Rules: the buffer's size is fixed when the renderer is made, from `stream.gpu_mb` and the
//! adapter's binding limit, and never grows; a frame copies at most `stream.loads_per_frame` tiles
//! into it and rewrites the page table whole (175 KB for a 32,768² pyramid: cheaper than tracking
//! which entries a fade or an eviction changed).

use super::alloc::{Alloc, Buffer};
use super::bindings::buffer;
use super::context::GpuContext;
use super::uniforms::{AtlasUniforms, MAX_LEVELS};
use crate::error::{Error, Result};
use crate::sketch::tiles::Pyramid;
use crate::sketch::tiles::cache::{Budget, StreamStats, TileCache};

/// The sketch's atlas as a pass binds it: the heights and, for a streamed pyramid, the marks
/// (`atlas` and `wanted` in `shaders/shared/atlas.wgsl`, [`super::bindings::Binding::atlas`]);
/// in the counting variant, the tallies every reader of the sketch declares (`work`,
/// [`super::work`]).
#[derive(Clone)]
pub struct AtlasBinding {
    pub atlas: wgpu::Buffer,
    pub marks: Option<wgpu::Buffer>,
    pub work: Option<wgpu::Buffer>,
    /// The sketch's sun visibility map, where the frames sample it ([`super::sun_map`]).
    pub sun_seen: Option<wgpu::Buffer>,
    /// The colour ramp's stops, where the ground is drawn with one ([`crate::surface::ramp`]).
    pub ramp: Option<wgpu::Buffer>,
    /// The user's imagery on the sketch's grid, where the ground is drawn with it
    /// ([`crate::surface::image`]).
    pub drape: Option<wgpu::Buffer>,
}

impl AtlasBinding {
    /// The resources, by the names the shaders bind them under.
    pub fn resources(&self) -> Vec<(&'static str, wgpu::BindingResource<'_>)> {
        let mut r = vec![("atlas", buffer(&self.atlas))];
        if let Some(marks) = &self.marks {
            r.push(("wanted", buffer(marks)));
        }
        if let Some(work) = &self.work {
            r.push(("work", buffer(work)));
        }
        if let Some(seen) = &self.sun_seen {
            r.push(("sun_seen", buffer(seen)));
        }
        if let Some(ramp) = &self.ramp {
            r.push(("ramp", buffer(ramp)));
        }
        if let Some(drape) = &self.drape {
            r.push(("drape", buffer(drape)));
        }
        r
    }

    /// Refuses a streamed sketch where a pass reads it in its vertex shader (`what`) and the
    /// adapter cannot write the tile marks from there (`key`: the scene key to name, `instead`:
    /// what to do).
    pub fn check_vertex_marks(
        &self,
        ctx: &GpuContext,
        key: &'static str,
        what: &str,
        instead: &str,
    ) -> Result<()> {
        let writable = wgpu::Features::VERTEX_WRITABLE_STORAGE;
        if self.marks.is_none() || ctx.device.features().contains(writable) {
            return Ok(());
        }
        Err(Error::value(
            key,
            format!(
                "{what} reads a tile pyramid in the vertex shader, and {} cannot write the tile \
                 marks from there: {instead}",
                ctx.adapter_name()
            ),
        ))
    }
}

/// What the scene asks of the stream (the `[stream]` keys, resolved).
#[derive(Clone, Copy, Debug)]
pub struct StreamConfig {
    /// Bytes of GPU memory for pages and page table.
    pub gpu_bytes: u64,
    pub loads_per_frame: usize,
    pub fade_frames: u32,
    pub threads: usize,
}

pub struct Stream {
    cache: TileCache,
    /// Pages, then the page table.
    pub atlas: Buffer,
    /// A u32 mark per page-table entry.
    pub marks: Buffer,
    readback: Buffer,
    /// Floats before the page table.
    table_first: u32,
    tile: u32,
    border: u32,
}

impl Stream {
    pub fn new(
        ctx: &GpuContext,
        alloc: &Alloc,
        pyramid: &Pyramid,
        cfg: StreamConfig,
    ) -> Result<Stream> {
        let side = pyramid.side() as u64;
        let page_bytes = side * side * 4;
        let layout = crate::sketch::tiles::cache::Layout::new(pyramid);
        if layout.first.len() > MAX_LEVELS {
            return Err(Error::sketch(
                &pyramid.dir,
                format!(
                    "a pyramid of {} levels; the shaders' level table holds {MAX_LEVELS} \
                     (sketches up to 65,536 nodes a side)",
                    layout.first.len()
                ),
            ));
        }
        let table_bytes = layout.len as u64 * 8;
        let limit = cfg
            .gpu_bytes
            .min(ctx.limits.max_storage_buffer_binding_size)
            .min(ctx.limits.max_buffer_size);
        // Entries hold page·256 + fade exactly in an f32: pages below 2^16.
        let pages = (limit.saturating_sub(table_bytes) / page_bytes).min(65_535) as usize;
        let cache = TileCache::new(
            pyramid.clone(),
            Budget {
                pages,
                loads_per_frame: cfg.loads_per_frame,
                fade_frames: cfg.fade_frames,
                threads: cfg.threads,
            },
        )?;
        let table_first = pages as u64 * side * side;
        if table_first + 2 * layout.len as u64 > u32::MAX as u64 {
            return Err(Error::value(
                "stream.gpu_mb",
                "the pool is larger than a shader can index",
            ));
        }
        let atlas = alloc.create_buffer(&wgpu::BufferDescriptor {
            label: Some("tile pages and page table"),
            size: table_first * 4 + table_bytes,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let marks = alloc.create_buffer(&wgpu::BufferDescriptor {
            label: Some("tile marks"),
            size: layout.len as u64 * 4,
            usage: wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_SRC
                | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let readback = alloc.create_buffer(&wgpu::BufferDescriptor {
            label: Some("tile marks read-back"),
            size: layout.len as u64 * 4,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        Ok(Stream {
            cache,
            atlas,
            marks,
            readback,
            table_first: table_first as u32,
            tile: pyramid.meta.tile as u32,
            border: pyramid.meta.border as u32,
        })
    }

    pub fn binding(&self) -> AtlasBinding {
        AtlasBinding {
            atlas: wgpu::Buffer::clone(&self.atlas),
            marks: Some(wgpu::Buffer::clone(&self.marks)),
            work: None,
            sun_seen: None,
            ramp: None,
            drape: None,
        }
    }

    /// The atlas uniforms' level table as the streamed shaders read it.
    pub fn uniforms(&self, u: &mut AtlasUniforms) {
        let layout = &self.cache.layout;
        for (l, slot) in u.level.iter_mut().enumerate().take(MAX_LEVELS) {
            if l < layout.first.len() {
                slot[2] = self.table_first + 2 * layout.first[l] as u32;
                slot[3] = layout.tiles[l].0 as u32;
            }
        }
        u.tile = self.tile;
        u.border = self.border;
    }

    /// Before the frame's passes: places arrived tiles, writes them and the page table, and
    /// clears the marks.
    pub fn begin_frame(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
    ) -> Result<()> {
        let (uploads, table_changed) = self.cache.begin_frame()?;
        for u in &uploads {
            ctx.queue.write_buffer(
                &self.atlas,
                u.page as u64 * self.page_floats() * 4,
                bytemuck::cast_slice(&u.heights),
            );
        }
        // Written whole when it changed (175 KB for a 32,768² pyramid): most frames of a flight
        // place nothing and fade nothing.
        if table_changed {
            ctx.queue.write_buffer(
                &self.atlas,
                self.table_first as u64 * 4,
                bytemuck::cast_slice(self.cache.table()),
            );
        }
        encoder.clear_buffer(&self.marks, 0, None);
        Ok(())
    }

    /// After the frame's passes, in the same encoder: the marks to the read-back buffer.
    pub fn record_marks(&self, encoder: &mut wgpu::CommandEncoder) {
        encoder.copy_buffer_to_buffer(&self.marks, 0, &self.readback, 0, self.marks.size());
    }

    /// After the frame was submitted: reads the marks and queues the missing tiles.
    pub fn end_frame(&mut self, ctx: &GpuContext) -> Result<StreamStats> {
        let marks: Vec<u32> = super::frame_io::read_buffer(ctx, &self.readback, |b| {
            bytemuck::cast_slice(b).to_vec()
        })?;
        Ok(self.cache.end_frame(&marks))
    }

    /// Floats per page: a tile with its border.
    fn page_floats(&self) -> u64 {
        let side = (self.tile + 2 * self.border) as u64;
        side * side
    }

    /// Snapshots settle: see [`TileCache::settle`].
    pub fn settle(&mut self, on: bool) {
        self.cache.settle(on);
    }

    pub fn budget(&self) -> Budget {
        self.cache.budget()
    }
}
