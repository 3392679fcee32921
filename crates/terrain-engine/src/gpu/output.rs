//! The output pass (`shaders/output.wgsl`): a finished frame written into a host's colour and
//! depth targets, of the host's formats and sample count, inside the host's encoder.
//!
//! Rules: the frame is drawn into the renderer's own targets first, as for a snapshot, then one
//! full-screen triangle writes each pixel's colour and its reversed-Z depth (from the view
//! distance the frame kept, or the reference's hit position) into the host's views, depth-tested
//! `GreaterEqual` (reversed-Z) against what the host drew there before: the host's geometry,
//! drawn with [`crate::host::Terrain::view_proj`], hides the terrain where it is nearer and is
//! hidden where it is farther, drawn before the terrain or after it. On the way, where the scene
//! can show water (`SHORE`), a speck of land or water (a region under four pixels, told by the
//! frame's alpha) takes the colour of the region around it. Rejected: building every pass's
//! pipelines for the host's formats and sample count, a variant of each per host, where this one
//! pass costs a full-screen triangle.

use super::alloc::{Alloc, Buffer};
use super::bindings::{self, Binding, Kind, buffer};
use super::pipeline::shader_module;
use super::shaders::Key;
use crate::error::Result;
use wgpu::ShaderStages as S;

/// Where a scheme leaves its finished frame.
pub enum Source<'a> {
    /// The mesh modes and the planet: the colour target (sRGB) and each pixel's view distance as
    /// four bytes.
    Targets {
        colour: &'a wgpu::TextureView,
        depth: &'a wgpu::TextureView,
    },
    /// The reference: display colour and hit positions (relative to the frame's origin, w = 1 on
    /// ground), a vec4 per pixel.
    Buffers {
        colour: &'a wgpu::Buffer,
        position: &'a wgpu::Buffer,
    },
}

/// The host's targets: formats and samples per pixel.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Targets {
    /// The colour view's format: any renderable one; the picture arrives sRGB-encoded either way
    /// (by an `*Srgb` format, or by the pass where the format is linear).
    pub colour: wgpu::TextureFormat,
    /// The depth view's format (reversed-Z, cleared to 0), e.g. `Depth32Float`.
    pub depth: wgpu::TextureFormat,
    /// Samples per pixel of both views, as the host created them (1, or a count the adapter
    /// allows for both formats, e.g. 4).
    pub samples: u32,
}

/// The uniform block of `output.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub struct OutputUniforms {
    pub view_proj: [[f32; 4]; 4],
    pub near: f32,
    pub width: u32,
    pub height: u32,
    pub encode_srgb: u32,
}

/// The pass's shader, `shaders/output.wgsl`.
pub const SHADER: crate::gpu::pipeline::Shader = shader!("output", BINDINGS);

/// `shaders/output.wgsl`'s bindings: the frame from the reference's buffers (`FROM_BUFFERS`) or
/// from a mesh mode's targets.
pub const BINDINGS: &[Binding] = &[
    Binding::uniform(0, "output", S::FRAGMENT),
    Binding::storage(1, "colour_in", S::FRAGMENT).when(|k| k.contains(Key::FROM_BUFFERS)),
    Binding::storage(2, "position_in", S::FRAGMENT).when(|k| k.contains(Key::FROM_BUFFERS)),
    Binding::new(1, "colour_in", Kind::FloatTexture, S::FRAGMENT)
        .when(|k| !k.contains(Key::FROM_BUFFERS)),
    Binding::new(2, "depth_in", Kind::FloatTexture, S::FRAGMENT)
        .when(|k| !k.contains(Key::FROM_BUFFERS)),
];

pub struct OutputPass {
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
    uniforms: Buffer,
    key: Key,
    encode_srgb: bool,
}

impl OutputPass {
    /// The pass's name: its WGSL file.
    pub const NAME: &'static str = SHADER.name;

    /// For frames left in buffers (the reference, `FROM_BUFFERS` in the scheme's `key`) or in
    /// targets, written into `targets`.
    pub fn new(device: &Alloc, targets: Targets, key: Key) -> Result<OutputPass> {
        let layout = bindings::layout(device, Self::NAME, BINDINGS, 0, key);
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some(Self::NAME),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let shared = format!("{} {key:?} {targets:?}", Self::NAME);
        let pipeline = device.shared.render(shared, || {
            // Parsed only where the device has no such pipeline yet.
            let module = shader_module(device, &SHADER, key)?;
            Ok(
                device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                    label: Some(Self::NAME),
                    layout: Some(&pipeline_layout),
                    vertex: wgpu::VertexState {
                        module: &module,
                        entry_point: Some("vs"),
                        compilation_options: Default::default(),
                        buffers: &[],
                    },
                    fragment: Some(wgpu::FragmentState {
                        module: &module,
                        entry_point: Some("fs"),
                        compilation_options: Default::default(),
                        targets: &[Some(targets.colour.into())],
                    }),
                    primitive: Default::default(),
                    depth_stencil: Some(wgpu::DepthStencilState {
                        format: targets.depth,
                        depth_write_enabled: Some(true),
                        depth_compare: Some(wgpu::CompareFunction::GreaterEqual),
                        stencil: Default::default(),
                        bias: Default::default(),
                    }),
                    multisample: wgpu::MultisampleState {
                        count: targets.samples,
                        ..Default::default()
                    },
                    multiview_mask: None,
                    cache: None,
                }),
            )
        })?;
        let uniforms = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("output uniforms"),
            size: std::mem::size_of::<OutputUniforms>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        Ok(OutputPass {
            pipeline,
            layout,
            uniforms,
            key,
            encode_srgb: !targets.colour.is_srgb(),
        })
    }

    /// The frame's size and projection for the next [`OutputPass::record`].
    pub fn prepare(&self, queue: &wgpu::Queue, camera: &crate::camera::Camera) {
        let origin = super::uniforms::frame_origin(camera);
        let view_proj = super::uniforms::view_proj(camera, origin).as_mat4();
        let u = OutputUniforms {
            view_proj: view_proj.to_cols_array_2d(),
            near: camera.near as f32,
            width: camera.width,
            height: camera.height,
            encode_srgb: self.encode_srgb as u32,
        };
        queue.write_buffer(&self.uniforms, 0, bytemuck::bytes_of(&u));
    }

    /// The bind group that reads the frame a renderer leaves in `source`: made once per renderer,
    /// as its targets live as long as it does.
    pub fn bind(&self, device: &wgpu::Device, source: Source) -> Result<wgpu::BindGroup> {
        if matches!(source, Source::Buffers { .. }) != self.key.contains(Key::FROM_BUFFERS) {
            return Err(crate::error::Error::Internal(
                "an output pass built for one kind of frame given the other",
            ));
        }
        let mut resources = vec![("output", buffer(&self.uniforms))];
        match source {
            Source::Targets { colour, depth } => resources.extend([
                ("colour_in", wgpu::BindingResource::TextureView(colour)),
                ("depth_in", wgpu::BindingResource::TextureView(depth)),
            ]),
            Source::Buffers { colour, position } => resources.extend([
                ("colour_in", buffer(colour)),
                ("position_in", buffer(position)),
            ]),
        }
        let (name, key) = (Self::NAME, self.key);
        bindings::bind_group(device, name, &self.layout, BINDINGS, 0, key, &resources)
    }

    /// Writes the frame `bind_group` ([`OutputPass::bind`]) reads into the host's `colour` and
    /// `depth` views.
    pub fn record(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        bind_group: &wgpu::BindGroup,
        colour: &wgpu::TextureView,
        depth: &wgpu::TextureView,
    ) {
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some(Self::NAME),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: colour,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Load,
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: depth,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Load,
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, bind_group, &[]);
        pass.draw(0..3, 0..1);
    }
}

/// Clears a host's targets as a frame starts: black, and depth 0 (reversed-Z's far).
pub fn clear(
    encoder: &mut wgpu::CommandEncoder,
    colour: &wgpu::TextureView,
    depth: &wgpu::TextureView,
) {
    encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some("clear"),
        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
            view: colour,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations {
                load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                store: wgpu::StoreOp::Store,
            },
        })],
        depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
            view: depth,
            depth_ops: Some(wgpu::Operations {
                load: wgpu::LoadOp::Clear(0.0),
                store: wgpu::StoreOp::Store,
            }),
            stencil_ops: None,
        }),
        timestamp_writes: None,
        occlusion_query_set: None,
        multiview_mask: None,
    });
}
