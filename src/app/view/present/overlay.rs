//! The overlay pass: the figures drawn on the CPU into a transparent, premultiplied texture and
//! blended over the frame, and the full-screen copy of an offscreen frame onto the surface.
//!
//! Rule: the overlay is uploaded only when its text changes; these are the window's own passes,
//! never a renderer's.

use crate::app::hud;
use terrain_engine::Camera;
use terrain_engine::alloc::{Alloc, Texture};

/// The window's own full-screen passes: the figures' overlay blended over the frame, and a
/// texture copied onto the surface. Not a renderer pass: the terrain never goes through it.
const COMPOSITE: &str = r#"
@group(0) @binding(0) var source: texture_2d<f32>;

@vertex
fn vs(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let uv = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(uv * 2.0 - 1.0, 0.0, 1.0);
}

fn linear(c: vec3<f32>) -> vec3<f32> {
    let low = c / 12.92;
    let high = pow((c + 0.055) / 1.055, vec3<f32>(2.4));
    return select(high, low, c <= vec3<f32>(0.04045));
}

// The overlay holds premultiplied sRGB bytes; the target blends straight colour, in linear
// light where it encodes sRGB itself.
@fragment
fn overlay(@builtin(position) p: vec4<f32>) -> @location(0) vec4<f32> {
    let c = textureLoad(source, vec2<i32>(p.xy), 0);
    if (c.a <= 0.0) {
        discard;
    }
    var rgb = c.rgb / c.a;
    if (SRGB_TARGET) {
        rgb = linear(rgb);
    }
    return vec4<f32>(rgb, c.a);
}

// A texture of the target's own format: what it holds, unchanged.
@fragment
fn copy(@builtin(position) p: vec4<f32>) -> @location(0) vec4<f32> {
    return textureLoad(source, vec2<i32>(p.xy), 0);
}
"#;

pub(super) struct Composite {
    overlay: wgpu::RenderPipeline,
    copy: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
    /// The figures' text, and the overlay texture it was drawn into.
    drawn: Option<(Vec<String>, Texture, wgpu::BindGroup)>,
}

impl Composite {
    pub(super) fn new(device: &wgpu::Device, format: wgpu::TextureFormat) -> Composite {
        let source = format!(
            "const SRGB_TARGET: bool = {};\n{COMPOSITE}",
            format.is_srgb()
        );
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("view composite"),
            source: wgpu::ShaderSource::Wgsl(source.into()),
        });
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("view composite"),
            entries: &[wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::FRAGMENT,
                ty: wgpu::BindingType::Texture {
                    sample_type: wgpu::TextureSampleType::Float { filterable: false },
                    view_dimension: wgpu::TextureViewDimension::D2,
                    multisampled: false,
                },
                count: None,
            }],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("view composite"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = |entry: &str, blend: Option<wgpu::BlendState>| {
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some("view composite"),
                layout: Some(&pipeline_layout),
                vertex: wgpu::VertexState {
                    module: &module,
                    entry_point: Some("vs"),
                    compilation_options: Default::default(),
                    buffers: &[],
                },
                fragment: Some(wgpu::FragmentState {
                    module: &module,
                    entry_point: Some(entry),
                    compilation_options: Default::default(),
                    targets: &[Some(wgpu::ColorTargetState {
                        format,
                        blend,
                        write_mask: wgpu::ColorWrites::ALL,
                    })],
                }),
                primitive: Default::default(),
                depth_stencil: None,
                multisample: Default::default(),
                multiview_mask: None,
                cache: None,
            })
        };
        Composite {
            overlay: pipeline("overlay", Some(wgpu::BlendState::ALPHA_BLENDING)),
            copy: pipeline("copy", None),
            layout,
            drawn: None,
        }
    }

    /// The overlay of `lines` at `camera`'s size, drawn and uploaded where either changed.
    pub(super) fn update(
        &mut self,
        alloc: &Alloc,
        queue: &wgpu::Queue,
        lines: Vec<String>,
        camera: &Camera,
    ) {
        let size = wgpu::Extent3d {
            width: camera.width,
            height: camera.height,
            depth_or_array_layers: 1,
        };
        if let Some((drawn, texture, _)) = &self.drawn
            && *drawn == lines
            && texture.size() == size
        {
            return;
        }
        let texture = match self.drawn.take() {
            Some((_, t, _)) if t.size() == size => t,
            _ => alloc.create_texture(&wgpu::TextureDescriptor {
                label: Some("view figures"),
                size,
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: wgpu::TextureFormat::Rgba8Unorm,
                usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
                view_formats: &[],
            }),
        };
        let rgba = hud::overlay(size.width, size.height, &lines);
        queue.write_texture(
            texture.as_image_copy(),
            &rgba,
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(size.width * 4),
                rows_per_image: None,
            },
            size,
        );
        let bind_group = self.bind(alloc, &texture.create_view(&Default::default()));
        self.drawn = Some((lines, texture, bind_group));
    }

    fn bind(&self, device: &wgpu::Device, view: &wgpu::TextureView) -> wgpu::BindGroup {
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("view composite"),
            layout: &self.layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: wgpu::BindingResource::TextureView(view),
            }],
        })
    }

    /// Blends the figures over `target`.
    pub(super) fn overlay(&self, encoder: &mut wgpu::CommandEncoder, target: &wgpu::TextureView) {
        let Some((_, _, bind_group)) = &self.drawn else {
            return;
        };
        pass(encoder, target, &self.overlay, bind_group);
    }

    /// Writes `source` (of `target`'s format and size) into `target`.
    pub(super) fn copy(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        source: &wgpu::TextureView,
        target: &wgpu::TextureView,
    ) {
        let bind_group = self.bind(device, source);
        pass(encoder, target, &self.copy, &bind_group);
    }
}

/// One full-screen triangle of `pipeline` into `target`, over what it holds.
fn pass(
    encoder: &mut wgpu::CommandEncoder,
    target: &wgpu::TextureView,
    pipeline: &wgpu::RenderPipeline,
    bind_group: &wgpu::BindGroup,
) {
    let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some("view composite"),
        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
            view: target,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations {
                load: wgpu::LoadOp::Load,
                store: wgpu::StoreOp::Store,
            },
        })],
        depth_stencil_attachment: None,
        timestamp_writes: None,
        occlusion_query_set: None,
        multiview_mask: None,
    });
    pass.set_pipeline(pipeline);
    pass.set_bind_group(0, bind_group, &[]);
    pass.draw(0..3, 0..1);
}
