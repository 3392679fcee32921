//! The terrain pass (`shaders/terrain.wgsl`): the detailed geometry image as an indexed quad mesh
//! read from its storage buffers (no vertex upload), and the sky as one full-screen triangle.
//! Reversed-Z depth with an infinite far plane. Owns the colour and depth targets.
//! - Single-sampled (by default), deferred (`Deferred`): the mesh writes a G-buffer, and the
//!   full-screen triangle shades each pixel from it, or draws the sky where no ground was written.
//! - Multisampled (`render.msaa`) or with `render.deferred` off, forward: the mesh is shaded as
//!   it is drawn, then the sky behind it ([`SKY_TEST`]). Multisampled, it draws into
//!   multisampled targets the hardware resolves, and the depth copy for positions in a second,
//!   single-sampled pass of the terrain's depth alone.

use super::alloc::{Alloc, Buffer, Texture};
use super::bindings::{self, Binding, Kind, buffer};
use super::pipeline::Module;
use super::shaders::Key;
use super::stream::AtlasBinding;
use crate::error::Result;
use wgpu::ShaderStages as S;

mod raster;
pub(crate) mod targets;

pub(crate) use raster::RasterPipeline;
use raster::render_pass;

pub use super::formats::{COLOUR, DEPTH, DEPTH_COPY, GBUFFER};

/// The sky's depth test in forward frames (and the planet pass's). The sky lies at depth 0, where
/// reversed-Z clears the depth, and is drawn after the ground, so that it passes only where no
/// ground was drawn and the depth test rejects the rest before its shader runs (nothing in
/// `sky_fs` discards). The images are those of a sky drawn first under the ground: the ground
/// covers every sample it keeps from the sky. Rejected: the sky first, where every pixel pays for
/// the sky (the world beyond the sketch, lit and hazed) and then for the ground
/// (docs/decisions.md, “Sky after the ground”).
pub const SKY_TEST: wgpu::CompareFunction = wgpu::CompareFunction::GreaterEqual;

/// The pass's shader, `shaders/terrain.wgsl`.
pub const SHADER: crate::gpu::pipeline::Shader = shader!("terrain", BINDINGS);

/// `shaders/terrain.wgsl`'s bindings: group 0 for every draw; group 1, the G-buffer the deferred
/// shading reads, its targets in [`GBUFFER`]'s order.
pub const BINDINGS: &[Binding] = &[
    Binding::frame(S::VERTEX_FRAGMENT),
    // The fragment shader reads the sketch; the vertex shader too where it evaluates a streamed
    // grid's vertices.
    Binding::atlas(S::FRAGMENT).when(|k| !k.contains(Key::GRID_STREAMED)),
    Binding::atlas(S::VERTEX_FRAGMENT).when(|k| k.contains(Key::GRID_STREAMED)),
    Binding::wanted(S::FRAGMENT)
        .when(|k| k.contains(Key::STREAMED) && !k.contains(Key::GRID_STREAMED)),
    Binding::wanted(S::VERTEX_FRAGMENT)
        .when(|k| k.contains(Key::STREAMED.union(Key::GRID_STREAMED))),
    Binding::work(S::FRAGMENT),
    Binding::sun_seen(S::FRAGMENT),
    Binding::ramp(S::FRAGMENT),
    Binding::drape(S::FRAGMENT),
    Binding::storage(3, "detailed", S::VERTEX).when(|k| !streamed_grid(k)),
    Binding::storage(4, "normals", S::VERTEX)
        .when(|k| !k.contains(Key::PIXEL_NORMALS) && !streamed_grid(k)),
    Binding::storage(5, "importance", S::FRAGMENT).when(|k| k.contains(Key::IMPORTANCE_VIEW)),
    Binding::storage(6, "blocks", S::VERTEX).when(|k| k.contains(Key::GEOMIPMAP)),
    gbuffer(0, "gbuffer_local_w"),
    gbuffer(1, "gbuffer_normal_split"),
    gbuffer(2, "gbuffer_inscatter_spacing"),
    gbuffer(3, "gbuffer_through_wire"),
];

/// GeoMipMap over a streamed sketch: no baked grid, no vertex normals.
fn streamed_grid(k: Key) -> bool {
    k.contains(Key::GRID_STREAMED.union(Key::GEOMIPMAP))
}

/// A G-buffer target as the deferred shading reads it.
const fn gbuffer(index: u32, name: &'static str) -> Binding {
    Binding::new(index, name, Kind::UintTexture, S::FRAGMENT)
        .in_group(1)
        .when(|k| k.contains(Key::DEFERRED))
}

pub struct TerrainPass {
    /// The mesh: shaded as it is drawn (forward), or written to the G-buffer (deferred).
    ground: wgpu::RenderPipeline,
    /// The full-screen triangle: the sky behind the ground (forward), or the shading of every
    /// pixel from the G-buffer, the sky where no ground was written (deferred).
    screen: wgpu::RenderPipeline,
    bind_group: wgpu::BindGroup,
    index: Buffer,
    index_count: u32,
    /// GeoMipMap: the most indices a frame may draw, which the index buffer grows to at most.
    index_cap: u64,
    /// The side of the quad mesh the index buffer holds (warped mode; 0 for GeoMipMap).
    quad_mesh: u32,
    /// What the targets are made of besides the size.
    sizing: targets::Sizing,
    /// The colour, the depth and its copy (the view distances); multisampled, the colour's
    /// samples (resolved into the colour) and the single-sampled depth pass; deferred, the
    /// G-buffer `ground` writes and `screen` shades the picture from.
    targets: targets::Targets,
}

/// Deferred shading, for single-sampled frames: the mesh writes each pixel's surface (position,
/// normal, split octave, spacing, the air in front of it) to [`GBUFFER`], and one full-screen
/// triangle shades each pixel once, or draws the sky where no ground was written. Drawn forward,
/// a rasteriser runs the fragment shader over every block of pixels a triangle touches (llvmpipe
/// over 4×4 blocks, GPUs over 2×2 quads), so a fine mesh shades most pixels several times over,
/// and the shading (the shadow ray, the bump octaves, the surface types) is most of the pass
/// (docs/decisions.md, “Deferred shading”). Multisampled frames stay forward: a G-buffer of
/// samples would need shading per sample.
struct Deferred {
    bind_group: wgpu::BindGroup,
    views: Vec<wgpu::TextureView>,
    _targets: Vec<Texture>,
}

struct Multisampled {
    colour: wgpu::TextureView,
    /// The depth pass's pipeline and its own single-sampled depth buffer.
    depth_pass: Option<(wgpu::RenderPipeline, wgpu::TextureView)>,
    _targets: Vec<Texture>,
}

/// Which variant of the shaders to build, and the buffers it reads.
///
/// The normals the terrain is lit with follow from the key: the mesh's vertex normals
/// (`normals`, mesh² vec4); with `PIXEL_NORMALS`, the terrain function's normal at each pixel,
/// sampled from the atlas as the reference shades (no vertex normals bound or computed); with
/// `GRID_STREAMED`, a streamed GeoMipMap grid's normals from its vertices evaluated in the vertex
/// shader (the normals pass's central differences).
pub struct Variant {
    /// The shaders' flags ([`crate::lod::shader_key`]); `DEFERRED` shades from a G-buffer
    /// (`Deferred`), single-sampled frames only.
    pub key: Key,
    /// The mesh's vertex normals, unless the key lights the terrain otherwise.
    pub normals: Option<wgpu::Buffer>,
    /// The importance debug view's buffer (n² f32), only when that view is drawn.
    pub importance: Option<wgpu::Buffer>,
    /// GeoMipMap: the per-frame block records and the most indices a frame can draw. The index
    /// buffer is then rewritten every frame instead of holding the warped mesh's quads.
    pub geomipmap: Option<(wgpu::Buffer, u64)>,
    /// The sketch's pyramid: the surface types read its curvature, the shadow ray and pixel
    /// normals its heights.
    pub atlas: AtlasBinding,
    /// Samples per pixel: 1, or 4 multisampled (`render.msaa`).
    pub samples: u32,
}

impl TerrainPass {
    /// The pass's name: its timer key, its `passes_ms` key, its WGSL file.
    pub const NAME: &'static str = SHADER.name;

    #[allow(clippy::too_many_arguments)]
    /// `detailed`: the geometry image; `None` for GeoMipMap over a streamed sketch, whose grid
    /// vertices the vertex shader evaluates from the atlas (GRID_STREAMED).
    pub fn new(
        device: &Alloc,
        frame: &wgpu::Buffer,
        detailed: Option<&wgpu::Buffer>,
        mesh: u32,
        width: u32,
        height: u32,
        variant: &Variant,
    ) -> Result<TerrainPass> {
        let key = variant.key;
        let multisampled = variant.samples > 1;
        let deferred = key.contains(Key::DEFERRED);
        if deferred && multisampled {
            return Err(crate::error::Error::Internal(
                "deferred shading asked of a multisampled frame",
            ));
        }
        let mut targets = vec![Some(wgpu::ColorTargetState::from(COLOUR))];
        if key.contains(Key::POSITIONS) {
            targets.push(Some(DEPTH_COPY.into()));
        }

        let layout = bindings::layout(device, Self::NAME, BINDINGS, 0, key);
        let module = Module::new(device, &SHADER, key);
        // Multisampled: the same shaders with the depth copy's entry point.
        let depth_module = multisampled.then(|| Module::new(device, &SHADER, key | Key::POSITIONS));
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("terrain"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline_of = |layout: &wgpu::PipelineLayout,
                           module: &Module,
                           entry: (&str, &str),
                           targets: &[Option<wgpu::ColorTargetState>],
                           samples: u32,
                           depth: Option<(bool, wgpu::CompareFunction)>| {
            RasterPipeline {
                layout,
                module,
                entry,
                targets,
                samples,
                depth,
            }
            .build(device)
        };
        let ground_test = Some((true, wgpu::CompareFunction::Greater));
        let n = variant.samples;
        let (ground, screen, gbuffer) = if deferred {
            let gbuffer_layout = bindings::layout(device, "terrain g-buffer", BINDINGS, 1, key);
            let shading_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("terrain shading"),
                bind_group_layouts: &[Some(&layout), Some(&gbuffer_layout)],
                immediate_size: 0,
            });
            let gbuffer = GBUFFER.map(|f| Some(f.into()));
            let writes = ("terrain_vs", "gbuffer_fs");
            let shades = ("sky_vs", "deferred_fs");
            (
                pipeline_of(&pipeline_layout, &module, writes, &gbuffer, 1, ground_test)?,
                pipeline_of(&shading_layout, &module, shades, &targets, 1, None)?,
                Some(gbuffer_layout),
            )
        } else {
            let shaded = ("terrain_vs", "terrain_fs");
            let sky = ("sky_vs", "sky_fs");
            let sky_test = Some((false, SKY_TEST));
            (
                pipeline_of(&pipeline_layout, &module, shaded, &targets, n, ground_test)?,
                pipeline_of(&pipeline_layout, &module, sky, &targets, n, sky_test)?,
                None,
            )
        };
        let depth_pipeline = depth_module
            .as_ref()
            .map(|m| {
                let targets = [None, Some(DEPTH_COPY.into())];
                let entry = ("terrain_vs", "depth_fs");
                pipeline_of(&pipeline_layout, m, entry, &targets, 1, ground_test)
            })
            .transpose()?;

        let mut resources = variant.atlas.resources();
        resources.push(("frame", buffer(frame)));
        resources.extend(detailed.map(|d| ("detailed", buffer(d))));
        resources.extend(variant.normals.as_ref().map(|n| ("normals", buffer(n))));
        resources.extend(
            variant
                .importance
                .as_ref()
                .map(|i| ("importance", buffer(i))),
        );
        resources.extend(
            variant
                .geomipmap
                .as_ref()
                .map(|(b, _)| ("blocks", buffer(b))),
        );
        let bind_group =
            bindings::bind_group(device, Self::NAME, &layout, BINDINGS, 0, key, &resources)?;
        let (index, index_count) = match &variant.geomipmap {
            // Room for what frames draw, grown as they need it (`write_indices`), never past
            // the capacity: a baked grid's capacity is every block at level 0, which no view
            // draws (72 MB of indices for the bundled DEM).
            Some((_, capacity)) => (block_indices(device, (*capacity).min(FIRST_INDICES)), 0),
            None => {
                let indices = quad_indices(mesh);
                // STORAGE: an adaptive triangulation's indices are written by `mesh_split` (and
                // read back by the tests).
                let index = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some("quad mesh indices"),
                    contents: bytemuck::cast_slice(&indices),
                    usage: wgpu::BufferUsages::INDEX
                        | wgpu::BufferUsages::COPY_DST
                        | wgpu::BufferUsages::COPY_SRC
                        | wgpu::BufferUsages::STORAGE,
                });
                (index, indices.len() as u32)
            }
        };
        let sizing = targets::Sizing {
            key,
            samples: variant.samples,
            depth_pipeline,
            gbuffer,
        };
        let targets = targets::make(device, (width, height), &sizing)?;
        Ok(TerrainPass {
            ground,
            screen,
            bind_group,
            index_count,
            index_cap: variant.geomipmap.as_ref().map_or(0, |(_, cap)| *cap),
            quad_mesh: if variant.geomipmap.is_some() { 0 } else { mesh },
            index,
            sizing,
            targets,
        })
    }

    /// Makes the targets for frames of `width` × `height` (nothing else depends on the size).
    pub fn resize(&mut self, device: &Alloc, width: u32, height: u32) -> Result<()> {
        self.targets = targets::make(device, (width, height), &self.sizing)?;
        Ok(())
    }

    pub fn triangles(&self) -> u64 {
        self.index_count as u64 / 3
    }

    /// Ground positions of the last frame's pixels, drawn from `camera` (metres from its frame
    /// origin, w = 1 on ground), recovered from the depth copy.
    pub fn read_positions(
        &self,
        ctx: &super::context::GpuContext,
        camera: &crate::camera::Camera,
    ) -> Result<Vec<[f32; 4]>> {
        let view_proj = super::uniforms::view_proj(camera, super::uniforms::frame_origin(camera));
        let depth = &self.targets.depth_copy;
        super::frame_io::positions_from_depth(ctx, depth, view_proj, camera.near)
    }

    /// The frame's colour and view distances.
    pub fn output(&self) -> super::output::Source<'_> {
        self.targets.output()
    }

    /// The warped variant draws a `mesh`² quad mesh this frame (at most the size it was built
    /// for); the indices are rewritten only when the side changes.
    pub fn use_quad_mesh(&mut self, queue: &wgpu::Queue, mesh: u32) {
        if self.quad_mesh == 0 || mesh == self.quad_mesh {
            return;
        }
        let capacity = self.index.size() / 4;
        let indices = quad_indices(mesh);
        if indices.len() as u64 > capacity {
            return;
        }
        queue.write_buffer(&self.index, 0, bytemuck::cast_slice(&indices));
        self.index_count = indices.len() as u32;
        self.quad_mesh = mesh;
    }

    /// The warped variant draws a `mesh`² quad mesh whose indices [`super::mesh_split`] writes
    /// this frame (at most the size it was built for).
    pub fn use_split_mesh(&mut self, mesh: u32) {
        let count = mesh.saturating_sub(1).pow(2) as u64 * 6;
        if self.quad_mesh == 0 || count > self.index.size() / 4 {
            return;
        }
        self.index_count = count as u32;
        self.quad_mesh = mesh;
    }

    /// The quad mesh's index buffer, for a pass that writes it (`mesh_split`).
    pub fn quad_mesh_indices(&self) -> &wgpu::Buffer {
        &self.index
    }

    /// The GeoMipMap variant's indices for this frame.
    pub fn write_indices(&mut self, device: &Alloc, queue: &wgpu::Queue, indices: &[u32]) {
        let room = self.index.size() / 4;
        if indices.len() as u64 > room {
            let needed = indices.len() as u64;
            let grown = needed
                .next_power_of_two()
                .max(2 * room)
                .min(self.index_cap)
                .max(needed);
            self.index = block_indices(device, grown);
        }
        queue.write_buffer(&self.index, 0, bytemuck::cast_slice(indices));
        self.index_count = indices.len() as u32;
    }

    /// The mesh (its index buffer, all of it this frame) with `pipeline`, the bind group set.
    fn draw_mesh(&self, pass: &mut wgpu::RenderPass, pipeline: &wgpu::RenderPipeline) {
        pass.set_pipeline(pipeline);
        pass.set_index_buffer(self.index.slice(..), wgpu::IndexFormat::Uint32);
        pass.draw_indexed(0..self.index_count, 0, 0..1);
    }

    /// The terrain unless nothing of it is in view, then the full-screen triangle: deferred, the
    /// shading of the G-buffer and the sky where no ground was written; forward, the sky where the
    /// terrain left the depth cleared ([`SKY_TEST`]).
    pub fn record(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        draw_terrain: bool,
        probe: super::counters::Probe,
    ) {
        let timestamps = probe.render(Self::NAME);
        let attach = |view, resolve_target| {
            Some(wgpu::RenderPassColorAttachment {
                view,
                depth_slice: None,
                resolve_target,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                    // Samples are resolved at the pass's end and need no keeping.
                    store: if resolve_target.is_some() {
                        wgpu::StoreOp::Discard
                    } else {
                        wgpu::StoreOp::Store
                    },
                },
            })
        };
        let t = &self.targets;
        let attachments = match &t.multisampled {
            Some(ms) => vec![attach(&ms.colour, Some(&t.colour_view))],
            None => {
                vec![
                    attach(&t.colour_view, None),
                    attach(&t.depth_copy_view, None),
                ]
            }
        };
        // The depth, cleared; every pass's own (nothing reads it after).
        let depth = |view| {
            Some(wgpu::RenderPassDepthStencilAttachment {
                view,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(0.0),
                    store: wgpu::StoreOp::Discard,
                }),
                stencil_ops: None,
            })
        };
        if let Some(deferred) = &t.deferred {
            // The pass's timer spans both: from the G-buffer's start to the shading's end.
            let (begin, end) = match timestamps {
                Some(t) => (
                    Some(wgpu::RenderPassTimestampWrites {
                        end_of_pass_write_index: None,
                        ..t
                    }),
                    Some(wgpu::RenderPassTimestampWrites {
                        beginning_of_pass_write_index: None,
                        ..t
                    }),
                ),
                None => (None, None),
            };
            let gbuffer: Vec<_> = deferred.views.iter().map(|v| attach(v, None)).collect();
            let label = "terrain g-buffer";
            let mut pass = render_pass(encoder, label, &gbuffer, depth(&t.depth_view), begin);
            probe.begin_render(&mut pass, Self::NAME, 0);
            pass.set_bind_group(0, &self.bind_group, &[]);
            if draw_terrain {
                self.draw_mesh(&mut pass, &self.ground);
            }
            probe.end_render(&mut pass);
            drop(pass);
            let mut pass = render_pass(encoder, "terrain shading", &attachments, None, end);
            probe.begin_render(&mut pass, Self::NAME, 1);
            pass.set_bind_group(0, &self.bind_group, &[]);
            pass.set_bind_group(1, &deferred.bind_group, &[]);
            pass.set_pipeline(&self.screen);
            pass.draw(0..3, 0..1);
            probe.end_render(&mut pass);
            return;
        }
        let ground_depth = depth(&t.depth_view);
        let mut pass = render_pass(encoder, "terrain", &attachments, ground_depth, timestamps);
        probe.begin_render(&mut pass, Self::NAME, 0);
        pass.set_bind_group(0, &self.bind_group, &[]);
        if draw_terrain {
            self.draw_mesh(&mut pass, &self.ground);
        }
        pass.set_pipeline(&self.screen);
        pass.draw(0..3, 0..1);
        probe.end_render(&mut pass);
        drop(pass);
        let Some(Multisampled {
            depth_pass: Some((pipeline, depth_view)),
            ..
        }) = &t.multisampled
        else {
            return;
        };
        let copy = [None, attach(&t.depth_copy_view, None)];
        let mut pass = render_pass(
            encoder,
            "terrain depth copy",
            &copy,
            depth(depth_view),
            None,
        );
        probe.begin_render(&mut pass, Self::NAME, 2);
        pass.set_bind_group(0, &self.bind_group, &[]);
        if draw_terrain {
            self.draw_mesh(&mut pass, pipeline);
        }
        probe.end_render(&mut pass);
    }
}

/// Indices a GeoMipMap frame's buffer holds at first (256 KiB).
const FIRST_INDICES: u64 = 1 << 16;

/// An index buffer for `count` of a GeoMipMap frame's indices, rewritten every frame.
fn block_indices(device: &Alloc, count: u64) -> Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("block indices"),
        size: count * 4,
        usage: wgpu::BufferUsages::INDEX | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

/// Two counter-clockwise triangles per cell, split along (s,t)–(s+1,t+1): the diagonal the warp's
/// guard keeps unfolded.
pub fn quad_indices(mesh: u32) -> Vec<u32> {
    let mut v = Vec::with_capacity(((mesh - 1) * (mesh - 1) * 6) as usize);
    for t in 0..mesh - 1 {
        for s in 0..mesh - 1 {
            let a = t * mesh + s;
            let (b, c, d) = (a + 1, a + mesh + 1, a + mesh);
            v.extend_from_slice(&[a, b, c, a, c, d]);
        }
    }
    v
}
