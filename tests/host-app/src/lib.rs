//! A host application of the `terrain` library, written as a user writes one: its own instance,
//! adapter and device (made with what the terrain asks for), its own colour and depth textures,
//! and geometry of its own (a wall) drawn with the terrain's view-projection, before or after
//! the terrain, depth-tested against it. `wgpu` and `glam` are the library's re-exports.

// The host creates its own textures and buffers; the repository's lint that routes them through
// the library's ledger is not this application's.
#![allow(clippy::disallowed_methods)]

use terrain::glam::DVec3;
use terrain::wgpu;
use terrain::{Camera, Description, Targets, Terrain};

/// What the host draws into: sRGB colour, 32-bit depth, one sample.
pub const TARGETS: Targets = Targets {
    colour: wgpu::TextureFormat::Rgba8UnormSrgb,
    depth: wgpu::TextureFormat::Depth32Float,
    samples: 1,
};

/// The host's device and its targets.
pub struct Host {
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    pub colour: wgpu::Texture,
    pub depth: wgpu::Texture,
}

impl Host {
    /// A device able to draw `description`, and targets of `width` × `height`.
    pub fn new(description: &Description, width: u32, height: u32) -> Host {
        let instance =
            wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
        let adapter = pollster::block_on(instance.request_adapter(&Default::default()))
            .expect("an adapter (llvmpipe where there is no GPU)");
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("host"),
            required_features: Description::optional_features(adapter.features()),
            required_limits: description.required_limits(),
            ..Default::default()
        }))
        .expect("a device with the terrain's limits");
        let colour = target(&device, TARGETS.colour, width, height);
        let depth = target(&device, TARGETS.depth, width, height);
        Host {
            device,
            queue,
            colour,
            depth,
        }
    }

    /// Views of the host's colour and depth targets.
    pub fn views(&self) -> (wgpu::TextureView, wgpu::TextureView) {
        let view = |t: &wgpu::Texture| t.create_view(&Default::default());
        (view(&self.colour), view(&self.depth))
    }
}

/// A render target the host can read back.
pub fn target(
    device: &wgpu::Device,
    format: wgpu::TextureFormat,
    width: u32,
    height: u32,
) -> wgpu::Texture {
    device.create_texture(&wgpu::TextureDescriptor {
        label: Some("host target"),
        size: wgpu::Extent3d {
            width,
            height,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    })
}

/// When the host draws its geometry.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Order {
    BeforeTheTerrain,
    AfterTheTerrain,
}

/// The host's own geometry: a flat red quad in world metres, drawn with the terrain's
/// view-projection and reversed-Z depth compare `GreaterEqual`.
pub struct Wall {
    corners: [DVec3; 4],
    pipeline: wgpu::RenderPipeline,
    vertices: wgpu::Buffer,
    uniform: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
}

const WALL: &str = r#"
@group(0) @binding(0) var<uniform> view_proj: mat4x4<f32>;
@vertex
fn vs(@location(0) p: vec3<f32>) -> @builtin(position) vec4<f32> {
    return view_proj * vec4<f32>(p, 1.0);
}
@fragment
fn fs() -> @location(0) vec4<f32> {
    return vec4<f32>(1.0, 0.0, 0.0, 1.0);
}
"#;

/// The wall's colour as the colour target holds it.
pub const RED: [u8; 4] = [255, 0, 0, 255];

impl Wall {
    /// A quad through `corners` (in order around it).
    pub fn new(device: &wgpu::Device, corners: [DVec3; 4]) -> Wall {
        let buffer = |label, size, usage| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage: usage | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        };
        let vertices = buffer("wall", 6 * 12, wgpu::BufferUsages::VERTEX);
        let uniform = buffer("view_proj", 64, wgpu::BufferUsages::UNIFORM);
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("wall"),
            source: wgpu::ShaderSource::Wgsl(WALL.into()),
        });
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("wall"),
            layout: None,
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs"),
                compilation_options: Default::default(),
                buffers: &[Some(wgpu::VertexBufferLayout {
                    array_stride: 12,
                    step_mode: wgpu::VertexStepMode::Vertex,
                    attributes: &wgpu::vertex_attr_array![0 => Float32x3],
                })],
            },
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fs"),
                compilation_options: Default::default(),
                targets: &[Some(TARGETS.colour.into())],
            }),
            primitive: Default::default(),
            depth_stencil: Some(wgpu::DepthStencilState {
                format: TARGETS.depth,
                depth_write_enabled: Some(true),
                depth_compare: Some(wgpu::CompareFunction::GreaterEqual),
                stencil: Default::default(),
                bias: Default::default(),
            }),
            multisample: Default::default(),
            multiview_mask: None,
            cache: None,
        });
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: None,
            layout: &pipeline.get_bind_group_layout(0),
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: uniform.as_entire_binding(),
            }],
        });
        Wall {
            corners,
            pipeline,
            vertices,
            uniform,
            bind_group,
        }
    }

    /// Records the wall seen by `camera` into the host's views: positions relative to the
    /// terrain's frame origin, f32 near the camera.
    pub fn draw(
        &self,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        (colour, depth): (&wgpu::TextureView, &wgpu::TextureView),
        camera: &Camera,
    ) {
        let origin = Terrain::frame_origin(camera);
        let local: Vec<[f32; 3]> = [0, 1, 2, 0, 2, 3]
            .iter()
            .map(|&i| (self.corners[i] - origin).as_vec3().to_array())
            .collect();
        queue.write_buffer(&self.vertices, 0, bytemuck::cast_slice(&local));
        let matrix = Terrain::view_proj(camera).to_cols_array();
        queue.write_buffer(&self.uniform, 0, bytemuck::cast_slice(&matrix));
        let load = wgpu::Operations {
            load: wgpu::LoadOp::Load,
            store: wgpu::StoreOp::Store,
        };
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("host geometry"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: colour,
                depth_slice: None,
                resolve_target: None,
                ops: load,
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
        pass.set_bind_group(0, &self.bind_group, &[]);
        pass.set_vertex_buffer(0, self.vertices.slice(..));
        pass.draw(0..6, 0..1);
    }
}

/// One frame of `camera` into the host's targets: cleared, then the terrain and, where given,
/// the wall before or after it; submitted.
pub fn frame(
    host: &Host,
    terrain: &mut Terrain,
    camera: &Camera,
    wall: Option<(&Wall, Order)>,
) -> terrain::Result<()> {
    terrain.prepare(camera)?;
    let (colour, depth) = host.views();
    let mut encoder = host.device.create_command_encoder(&Default::default());
    terrain::clear(&mut encoder, &colour, &depth);
    let draw_wall = |encoder: &mut wgpu::CommandEncoder, when| {
        if let Some((w, _)) = wall.filter(|&(_, order)| order == when) {
            w.draw(&host.queue, encoder, (&colour, &depth), camera);
        }
    };
    draw_wall(&mut encoder, Order::BeforeTheTerrain);
    terrain.record(&mut encoder, &colour, &depth)?;
    draw_wall(&mut encoder, Order::AfterTheTerrain);
    host.queue.submit([encoder.finish()]);
    Ok(())
}
