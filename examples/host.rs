// A host creates its own resources, outside the library's ledger.
#![allow(clippy::disallowed_methods)]

//! A host application that embeds the terrain: its own window, surface, device and geometry.
//!
//! It opens a winit window, creates a wgpu surface and a device with what
//! `terrain::Description` asks for, and each frame records the terrain into its own encoder,
//! into the surface's texture and its own depth buffer, then draws a marker of its own: a red
//! mast standing on the ground (placed with the height query) in front of the camera, hidden
//! wherever the terrain is nearer. The camera circles the mast.
//!
//! `cargo run --release --example host -- [SCENE] [--frames N] [--screenshot FILE]`: SCENE
//! defaults to sketches/jacksboro.toml; with `--frames N` it draws N frames, writes the last to
//! FILE (PNG) and exits.

use std::path::PathBuf;
use std::sync::Arc;
use terrain::Camera;
use terrain::readback::Readback;
use terrain::{Description, Targets, Terrain};
use winit::application::ApplicationHandler;
use winit::event::WindowEvent;
use winit::event_loop::{ActiveEventLoop, EventLoop};
use winit::window::{Window, WindowId};

const DEPTH: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

struct Options {
    scene: PathBuf,
    frames: Option<u64>,
    screenshot: Option<PathBuf>,
}

fn options() -> anyhow::Result<Options> {
    let mut o = Options {
        scene: PathBuf::from("sketches/jacksboro.toml"),
        frames: None,
        screenshot: None,
    };
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--frames" => o.frames = Some(args.next().unwrap_or_default().parse()?),
            "--screenshot" => o.screenshot = args.next().map(PathBuf::from),
            _ if a.starts_with("--") => anyhow::bail!("unknown option {a}"),
            _ => o.scene = PathBuf::from(a),
        }
    }
    Ok(o)
}

/// What the host draws with: everything made once the window exists.
struct Gpu {
    window: Arc<Window>,
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
    device: wgpu::Device,
    queue: wgpu::Queue,
    depth: wgpu::TextureView,
    terrain: Terrain,
    mast: Mast,
    /// The scene's camera: the circle's start.
    start: Camera,
    /// The mast's foot, world metres.
    foot: glam::DVec3,
}

struct App {
    o: Options,
    gpu: Option<Gpu>,
    frame: u64,
    error: Option<anyhow::Error>,
}

fn main() -> anyhow::Result<()> {
    let o = options()?;
    let event_loop = EventLoop::new()?;
    let mut app = App {
        o,
        gpu: None,
        frame: 0,
        error: None,
    };
    event_loop.run_app(&mut app)?;
    match app.error {
        Some(e) => Err(e),
        None => Ok(()),
    }
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.gpu.is_some() {
            return;
        }
        match Gpu::new(event_loop, &self.o.scene) {
            Ok(gpu) => {
                gpu.window.request_redraw();
                self.gpu = Some(gpu);
            }
            Err(e) => self.fail(event_loop, e),
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            WindowEvent::Resized(size) => {
                if let Some(gpu) = &mut self.gpu {
                    gpu.resize(size.width, size.height);
                }
            }
            WindowEvent::RedrawRequested => {
                if let Err(e) = self.redraw(event_loop) {
                    self.fail(event_loop, e);
                }
            }
            _ => {}
        }
    }
}

impl App {
    fn fail(&mut self, event_loop: &ActiveEventLoop, e: anyhow::Error) {
        self.error = Some(e);
        event_loop.exit();
    }

    fn redraw(&mut self, event_loop: &ActiveEventLoop) -> anyhow::Result<()> {
        let Some(gpu) = &mut self.gpu else {
            return Ok(());
        };
        let last = self.o.frames.is_some_and(|n| self.frame + 1 >= n);
        let shot = gpu.draw(self.frame, last && self.o.screenshot.is_some())?;
        self.frame += 1;
        if last {
            if let (Some(path), Some((w, h, rgba))) = (&self.o.screenshot, shot) {
                write_png(path, w, h, &rgba)?;
            }
            event_loop.exit();
        } else {
            gpu.window.request_redraw();
        }
        Ok(())
    }
}

impl Gpu {
    fn new(event_loop: &ActiveEventLoop, scene: &std::path::Path) -> anyhow::Result<Gpu> {
        let attributes = Window::default_attributes()
            .with_title("terrain: a host")
            .with_inner_size(winit::dpi::PhysicalSize::new(480u32, 320u32));
        let window = Arc::new(event_loop.create_window(attributes)?);
        let instance =
            wgpu::Instance::new(wgpu::InstanceDescriptor::new_with_display_handle_from_env(
                Box::new(event_loop.owned_display_handle()),
            ));
        let surface = instance.create_surface(window.clone())?;
        let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            compatible_surface: Some(&surface),
            ..Default::default()
        }))?;
        let description = Description::new(terrain::scene::Scene::load(scene)?)?;
        let (device, queue) =
            pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
                label: Some("host"),
                required_features: Description::optional_features(adapter.features()),
                required_limits: description.required_limits(),
                ..Default::default()
            }))?;
        let size = window.inner_size();
        let caps = surface.get_capabilities(&adapter);
        let (width, height) = (size.width.max(1), size.height.max(1));
        let mut config = surface
            .get_default_config(&adapter, width, height)
            .ok_or_else(|| anyhow::anyhow!("the adapter cannot present to this window"))?;
        if let Some(srgb) = caps.formats.iter().copied().find(|f| f.is_srgb()) {
            config.format = srgb;
        }
        // Copies out of the surface, for the screenshot, where it allows them.
        config.usage |= caps.usages & wgpu::TextureUsages::COPY_SRC;
        let format = config.format;
        surface.configure(&device, &config);
        let start = description.camera(config.width, config.height)?;
        let targets = Targets {
            colour: format,
            depth: DEPTH,
            samples: 1,
        };
        let terrain = Terrain::new(&device, &queue, targets, description)?;
        // The mast stands where the camera looks, a third of the way there, on the ground.
        let look = start.eye + start.forward * 2000.0;
        let ground = terrain
            .ground()
            .height_at(look.truncate(), 0.0)?
            .unwrap_or(0.0);
        let foot = glam::DVec3::new(look.x, look.y, ground);
        let mast = Mast::new(&device, format);
        let depth = depth_view(&device, config.width, config.height);
        Ok(Gpu {
            window,
            surface,
            config,
            device,
            queue,
            depth,
            terrain,
            mast,
            start,
            foot,
        })
    }

    fn resize(&mut self, width: u32, height: u32) {
        self.config.width = width.max(1);
        self.config.height = height.max(1);
        self.surface.configure(&self.device, &self.config);
        self.depth = depth_view(&self.device, self.config.width, self.config.height);
    }

    /// The camera of frame `k`: the scene's, turned about the mast by half a degree a frame.
    fn camera(&self, k: u64) -> anyhow::Result<Camera> {
        let turn = glam::DQuat::from_rotation_z((k as f64 * 0.5).to_radians());
        let eye = self.foot + turn * (self.start.eye - self.foot);
        let target = self.foot + glam::DVec3::Z * 100.0;
        let (w, h) = (self.config.width, self.config.height);
        Ok(Camera::new(
            eye,
            target,
            self.start.fov_y.to_degrees(),
            w,
            h,
            self.start.far,
        )?)
    }

    /// The surface's next texture, the surface configured again where it has changed.
    fn next_texture(&mut self) -> anyhow::Result<wgpu::SurfaceTexture> {
        for _ in 0..3 {
            match self.surface.get_current_texture() {
                wgpu::CurrentSurfaceTexture::Success(t)
                | wgpu::CurrentSurfaceTexture::Suboptimal(t) => return Ok(t),
                _ => self.surface.configure(&self.device, &self.config),
            }
        }
        anyhow::bail!("the window's surface gives no texture to draw into")
    }

    /// Draws frame `k`; with `shot`, also reads it back (width, height, RGBA).
    fn draw(&mut self, k: u64, shot: bool) -> anyhow::Result<Option<(u32, u32, Vec<u8>)>> {
        let camera = self.camera(k)?;
        self.terrain.prepare(&camera)?;
        let frame = self.next_texture()?;
        let mut encoder = self.device.create_command_encoder(&Default::default());
        self.draw_into(&mut encoder, &frame.texture, &camera)?;
        // The screenshot: the surface's texture where it allows copies, else the same frame drawn
        // again into a texture that does.
        let copy;
        let readback = if shot {
            let copyable = frame
                .texture
                .usage()
                .contains(wgpu::TextureUsages::COPY_SRC);
            let source = match copyable {
                true => &frame.texture,
                false => {
                    copy = self.offscreen(&frame.texture);
                    self.draw_into(&mut encoder, &copy, &camera)?;
                    &copy
                }
            };
            let readback = Readback::new(&self.device, source)?;
            readback.record(&mut encoder, source)?;
            Some((source.width(), source.height(), readback))
        } else {
            None
        };
        self.queue.submit([encoder.finish()]);
        let image = match readback {
            Some((w, h, r)) => Some((w, h, r.read_rgba(&self.device)?)),
            None => None,
        };
        self.queue.present(frame);
        Ok(image)
    }

    /// The terrain, then the mast over it, into `target` and the host's depth.
    fn draw_into(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        target: &wgpu::Texture,
        camera: &Camera,
    ) -> anyhow::Result<()> {
        let view = target.create_view(&Default::default());
        terrain::clear(encoder, &view, &self.depth);
        self.terrain.record(encoder, &view, &self.depth)?;
        self.mast
            .draw(&self.queue, encoder, &view, &self.depth, camera, self.foot);
        Ok(())
    }

    /// A texture like `like` that can be copied from.
    fn offscreen(&self, like: &wgpu::Texture) -> wgpu::Texture {
        self.device.create_texture(&wgpu::TextureDescriptor {
            label: Some("screenshot"),
            size: like.size(),
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: like.format(),
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
            view_formats: &[],
        })
    }
}

fn depth_view(device: &wgpu::Device, width: u32, height: u32) -> wgpu::TextureView {
    device
        .create_texture(&wgpu::TextureDescriptor {
            label: Some("host depth"),
            size: wgpu::Extent3d {
                width,
                height,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: DEPTH,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            view_formats: &[],
        })
        .create_view(&Default::default())
}

/// A render pass over what the host's targets hold.
fn begin<'e>(
    encoder: &'e mut wgpu::CommandEncoder,
    colour: &wgpu::TextureView,
    depth: &wgpu::TextureView,
) -> wgpu::RenderPass<'e> {
    encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some("host"),
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
    })
}

/// The host's own geometry: a red mast, 300 m tall and 60 m across, at a world point.
struct Mast {
    pipeline: wgpu::RenderPipeline,
    uniforms: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
}

const MAST: &str = r#"
struct U { view_proj: mat4x4<f32>, foot: vec4<f32> }
@group(0) @binding(0) var<uniform> u: U;
@vertex
fn vs(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    // Two quads crossing at the mast's axis, six vertices each.
    let corner = array<vec2<f32>, 6>(vec2(-1.0, 0.0), vec2(1.0, 0.0), vec2(1.0, 1.0),
                                     vec2(-1.0, 0.0), vec2(1.0, 1.0), vec2(-1.0, 1.0));
    let c = corner[i % 6u];
    var across = vec3<f32>(30.0 * c.x, 0.0, 0.0);
    if (i >= 6u) {
        across = vec3<f32>(0.0, 30.0 * c.x, 0.0);
    }
    let p = u.foot.xyz + across + vec3<f32>(0.0, 0.0, 300.0 * c.y);
    return u.view_proj * vec4<f32>(p, 1.0);
}
@fragment
fn fs() -> @location(0) vec4<f32> {
    return vec4<f32>(1.0, 0.0, 0.0, 1.0);
}
"#;

impl Mast {
    fn new(device: &wgpu::Device, format: wgpu::TextureFormat) -> Mast {
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("mast"),
            source: wgpu::ShaderSource::Wgsl(MAST.into()),
        });
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("mast"),
            layout: None,
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
                targets: &[Some(format.into())],
            }),
            primitive: Default::default(),
            // Reversed-Z, as the terrain's depth: nearer is greater.
            depth_stencil: Some(wgpu::DepthStencilState {
                format: DEPTH,
                depth_write_enabled: Some(true),
                depth_compare: Some(wgpu::CompareFunction::GreaterEqual),
                stencil: Default::default(),
                bias: Default::default(),
            }),
            multisample: Default::default(),
            multiview_mask: None,
            cache: None,
        });
        let uniforms = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("mast"),
            size: 80,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("mast"),
            layout: &pipeline.get_bind_group_layout(0),
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: uniforms.as_entire_binding(),
            }],
        });
        Mast {
            pipeline,
            uniforms,
            bind_group,
        }
    }

    fn draw(
        &self,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        colour: &wgpu::TextureView,
        depth: &wgpu::TextureView,
        camera: &Camera,
        foot: glam::DVec3,
    ) {
        // Positions relative to the terrain's frame origin, in f32 near the camera.
        let local = (foot - Terrain::frame_origin(camera)).as_vec3();
        let mut data = Terrain::view_proj(camera).to_cols_array().to_vec();
        data.extend([local.x, local.y, local.z, 1.0]);
        queue.write_buffer(&self.uniforms, 0, bytemuck::cast_slice(&data));
        let mut pass = begin(encoder, colour, depth);
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &self.bind_group, &[]);
        pass.draw(0..12, 0..1);
    }
}

/// `rgba` written as an opaque 8-bit RGBA PNG at `path`.
fn write_png(path: &std::path::Path, width: u32, height: u32, rgba: &[u8]) -> anyhow::Result<()> {
    let opaque: Vec<u8> = rgba
        .chunks_exact(4)
        .flat_map(|p| [p[0], p[1], p[2], 255])
        .collect();
    let file = std::io::BufWriter::new(std::fs::File::create(path)?);
    let mut encoder = png::Encoder::new(file, width, height);
    encoder.set_color(png::ColorType::Rgba);
    encoder.set_depth(png::BitDepth::Eight);
    encoder.write_header()?.write_image_data(&opaque)?;
    Ok(())
}
