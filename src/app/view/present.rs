//! How `terrain view` puts a frame on screen: through a wgpu surface (the terrain drawn by
//! [`terrain::host::Terrain`] into the surface's texture, the figures composited over it), or,
//! where no surface can be made, through the CPU (the frame read back, the figures drawn on its
//! pixels, the pixels handed to softbuffer).
//!
//! Rules: a screenshot is the pixels presented. On the surface path that is a copy of the
//! surface's texture where the surface allows copies; elsewhere the frame is drawn into a
//! texture of the surface's format, copied from there onto the surface and read back from it.
//! The figures' overlay is drawn on the CPU (transparent, premultiplied) and uploaded only when
//! its text changes; nothing else of the frame leaves the GPU.

use crate::app::hud::{self, Figures, Status};
use std::num::NonZeroU32;
use std::sync::{Arc, Mutex};
use std::time::Instant;
use terrain::camera::Camera;
use terrain::error::{Error, Result};
use terrain::gpu::alloc::{Alloc, Ledger, Texture};
use terrain::gpu::context::GpuContext;
use terrain::gpu::uniforms::View;
use terrain::host::{Description, Targets, Terrain};
use terrain::render::Renderer;
use terrain::scene::{Mode, Scene};
use terrain::sketch::Atlas;
use winit::event_loop::ActiveEventLoop;
use winit::window::Window;

/// What the next frame draws, as the window's keys left it.
pub(super) struct Want<'a> {
    pub scene: &'a Scene,
    pub atlas: &'a Atlas,
    pub mode: Mode,
    pub view: View,
    /// Draw with the last frame's level of detail.
    pub frozen: bool,
}

impl Want<'_> {
    /// The scene at `camera`'s size.
    fn scene(&self, camera: &Camera) -> Scene {
        let mut scene = self.scene.clone();
        (scene.camera.width, scene.camera.height) = (camera.width, camera.height);
        scene
    }

    /// The view drawn: the importance view is the warped mode's only.
    fn view(&self) -> View {
        if self.mode != Mode::Warped && self.view == View::Importance {
            View::Shaded
        } else {
            self.view
        }
    }
}

/// What drawing a frame gave.
pub(super) struct Drawn {
    /// The pixels presented, RGBA rows top first, when a screenshot was asked for.
    pub shot: Option<Vec<u8>>,
    pub width: u32,
    pub height: u32,
    /// The frame's CPU stage (or the baselines' block selection), ms.
    pub cpu_ms: f64,
}

pub(super) enum Present {
    Surface(Box<SurfacePath>),
    Cpu(Box<CpuPath>),
}

impl Present {
    /// The path's name, as `--json` prints it.
    pub fn name(&self) -> &'static str {
        match self {
            Present::Surface(_) => "surface",
            Present::Cpu(_) => "cpu",
        }
    }

    /// Drops the terrain or renderer: the next frame builds it for the mode, view and size.
    pub fn forget(&mut self) {
        match self {
            Present::Surface(s) => s.terrain = None,
            Present::Cpu(c) => c.renderer = None,
        }
    }

    pub fn draw(
        &mut self,
        camera: &Camera,
        want: &Want,
        status: &Status,
        shot: bool,
    ) -> Result<Drawn> {
        match self {
            Present::Surface(s) => s.draw(camera, want, status, shot),
            Present::Cpu(c) => c.draw(camera, want, status, shot),
        }
    }

    /// The GPU time of each frame drawn so far, ms (on the surface path: from submit to the
    /// queue's completion callback, waiting for the frames still running).
    pub fn gpu_ms(&mut self) -> Vec<f64> {
        match self {
            Present::Surface(s) => {
                // The callbacks of the last frames run in this wait; a lost device has no more.
                let _ = s.device.poll(wgpu::PollType::wait_indefinitely());
                s.gpu_ms.lock().map(|v| v.clone()).unwrap_or_default()
            }
            Present::Cpu(c) => c.gpu_ms.clone(),
        }
    }
}

/// The CPU path: the renderer's frame read back and handed to softbuffer.
pub(super) struct CpuPath {
    ctx: GpuContext,
    renderer: Option<Renderer>,
    surface: softbuffer::Surface<Arc<Window>, Arc<Window>>,
    gpu_ms: Vec<f64>,
}

impl CpuPath {
    /// On `window`, rendering on a device of its own that holds `largest`'s needs.
    pub fn open(window: Arc<Window>, scene: &Scene, atlas: &Atlas, largest: Mode) -> Result<Self> {
        let ctx = GpuContext::new(&terrain::render::needs(scene, largest, atlas))?;
        let surface = softbuffer::Context::new(window.clone())
            .and_then(|c| softbuffer::Surface::new(&c, window))
            .map_err(|e| Error::window("cannot draw into it", e))?;
        Ok(CpuPath {
            ctx,
            renderer: None,
            surface,
            gpu_ms: Vec::new(),
        })
    }

    fn draw(&mut self, camera: &Camera, want: &Want, status: &Status, shot: bool) -> Result<Drawn> {
        let renderer = match &mut self.renderer {
            Some(r) => r,
            None => self.renderer.insert(Renderer::with_context(
                self.ctx.clone(),
                &want.scene(camera),
                want.atlas.clone(),
                want.mode,
                want.view(),
                false,
            )?),
        };
        let mut frame = if want.frozen {
            renderer.render_held(camera)?
        } else {
            renderer.render(camera)?
        };
        let lines = hud::lines(&Figures::of_frame(&frame), status);
        hud::draw(&mut frame.rgba, frame.width, frame.height, &lines);
        self.present(&frame.rgba, frame.width, frame.height)?;
        self.gpu_ms.push(frame.gpu.gpu_ms);
        Ok(Drawn {
            width: frame.width,
            height: frame.height,
            cpu_ms: frame.cpu_us * 1e-3,
            shot: shot.then_some(frame.rgba),
        })
    }

    fn present(&mut self, rgba: &[u8], width: u32, height: u32) -> Result<()> {
        let (Some(w), Some(h)) = (NonZeroU32::new(width), NonZeroU32::new(height)) else {
            return Ok(());
        };
        let gpu = |e: softbuffer::SoftBufferError| Error::window("cannot draw into it", e);
        self.surface.resize(w, h).map_err(gpu)?;
        let mut buffer = self.surface.buffer_mut().map_err(gpu)?;
        if buffer.len() * 4 != rgba.len() {
            return Ok(()); // resized meanwhile: the next frame matches
        }
        for (dst, p) in buffer.iter_mut().zip(rgba.chunks_exact(4)) {
            *dst = (p[0] as u32) << 16 | (p[1] as u32) << 8 | p[2] as u32;
        }
        buffer.present().map_err(gpu)
    }
}

const DEPTH: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// The surface path: the terrain drawn on the surface's device into its texture.
pub(super) struct SurfacePath {
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
    device: wgpu::Device,
    queue: wgpu::Queue,
    ledger: Ledger,
    depth: Texture,
    terrain: Option<Terrain>,
    composite: Composite,
    /// Each frame's submit-to-completion time, ms, as the queue's callbacks report it.
    gpu_ms: Arc<Mutex<Vec<f64>>>,
}

impl SurfacePath {
    /// A surface on `window` and a device that presents to it, holding `largest`'s needs; `Err`
    /// with the reason where none can be made (no surface, no adapter that presents to it, a
    /// configuration it refuses), for the CPU path to take over. Failing to create the device
    /// on an adapter that presents is an error of its own.
    pub fn open(
        el: &ActiveEventLoop,
        window: Arc<Window>,
        scene: &Scene,
        atlas: &Atlas,
        largest: Mode,
    ) -> Result<std::result::Result<Self, String>> {
        let instance =
            wgpu::Instance::new(wgpu::InstanceDescriptor::new_with_display_handle_from_env(
                Box::new(el.owned_display_handle()),
            ));
        let size = window.inner_size();
        let surface = match instance.create_surface(window) {
            Ok(s) => s,
            Err(e) => return Ok(Err(format!("no surface: {e}"))),
        };
        let options = wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            compatible_surface: Some(&surface),
            ..Default::default()
        };
        let adapter = match pollster::block_on(instance.request_adapter(&options)) {
            Ok(a) => a,
            Err(e) => return Ok(Err(format!("no adapter presents to the window: {e}"))),
        };
        let description = Description::with_atlas(scene.clone(), atlas.clone()).with_mode(largest);
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("terrain view"),
            required_features: Description::optional_features(adapter.features()),
            required_limits: description.required_limits(),
            ..Default::default()
        }))
        .map_err(|e| Error::device("the adapter that presents to the window", e))?;
        let (width, height) = (size.width.max(1), size.height.max(1));
        let Some(mut config) = surface.get_default_config(&adapter, width, height) else {
            return Ok(Err("the adapter cannot present to this window".into()));
        };
        let caps = surface.get_capabilities(&adapter);
        if let Some(srgb) = caps.formats.iter().copied().find(|f| f.is_srgb()) {
            config.format = srgb;
        }
        if config.format.block_copy_size(None) != Some(4) {
            return Ok(Err(format!("a surface of {:?}", config.format)));
        }
        // Screenshots copy the surface's texture where it allows that.
        config.usage |= caps.usages & wgpu::TextureUsages::COPY_SRC;
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        surface.configure(&device, &config);
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Ok(Err(format!("the surface refuses its configuration: {e}")));
        }
        let ledger = Ledger::default();
        let alloc = Alloc {
            device: &device,
            ledger: &ledger,
        };
        let depth = depth_texture(&alloc, config.width, config.height);
        let composite = Composite::new(&device, config.format);
        Ok(Ok(SurfacePath {
            surface,
            config,
            device,
            queue,
            ledger,
            depth,
            terrain: None,
            composite,
            gpu_ms: Arc::default(),
        }))
    }

    fn alloc(&self) -> Alloc<'_> {
        Alloc {
            device: &self.device,
            ledger: &self.ledger,
        }
    }

    /// The surface and the depth texture at `width` × `height`.
    fn fit(&mut self, width: u32, height: u32) {
        if (self.config.width, self.config.height) != (width, height) {
            (self.config.width, self.config.height) = (width, height);
            self.surface.configure(&self.device, &self.config);
            self.depth = depth_texture(&self.alloc(), width, height);
        }
    }

    /// Runs the completion callbacks of the frames the GPU has finished.
    fn poll(&self) -> Result<()> {
        self.device
            .poll(wgpu::PollType::Poll)
            .map(|_| ())
            .map_err(|e| Error::device("the device was lost", e))
    }

    fn draw(&mut self, camera: &Camera, want: &Want, status: &Status, shot: bool) -> Result<Drawn> {
        self.poll()?;
        self.fit(camera.width, camera.height);
        let terrain = match &mut self.terrain {
            Some(t) => t,
            None => {
                let description = Description::with_atlas(want.scene(camera), want.atlas.clone())
                    .with_mode(want.mode)
                    .with_view(want.view());
                let targets = Targets {
                    colour: self.config.format,
                    depth: DEPTH,
                    samples: 1,
                };
                self.terrain.insert(Terrain::new(
                    &self.device,
                    &self.queue,
                    targets,
                    description,
                )?)
            }
        };
        let info = if want.frozen {
            terrain.prepare_held(camera)?
        } else {
            terrain.prepare(camera)?
        };
        let last_gpu = self.gpu_ms.lock().ok().and_then(|v| v.last().copied());
        let figures = Figures {
            width: camera.width,
            height: camera.height,
            stage: info.stage,
            cpu_us: info.cpu_us,
            gpu_ms: last_gpu.unwrap_or(0.0),
            passes: Vec::new(),
            triangles: info.triangles,
        };
        let alloc = Alloc {
            device: &self.device,
            ledger: &self.ledger,
        };
        self.composite
            .update(&alloc, &self.queue, hud::lines(&figures, status), camera);

        let frame = next_texture(&self.surface, &self.device, &self.config)?;
        let mut encoder = self.device.create_command_encoder(&Default::default());
        // Where the surface allows no copies, a screenshot's frame is drawn into a texture that
        // does, and copied from there onto the surface.
        let copyable = frame
            .texture
            .usage()
            .contains(wgpu::TextureUsages::COPY_SRC);
        let offscreen = (shot && !copyable).then(|| {
            alloc.create_texture(&wgpu::TextureDescriptor {
                label: Some("screenshot"),
                size: frame.texture.size(),
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: self.config.format,
                usage: wgpu::TextureUsages::RENDER_ATTACHMENT
                    | wgpu::TextureUsages::TEXTURE_BINDING
                    | wgpu::TextureUsages::COPY_SRC,
                view_formats: &[],
            })
        });
        let target: &wgpu::Texture = offscreen.as_deref().unwrap_or(&frame.texture);
        let view = target.create_view(&Default::default());
        let depth = self.depth.create_view(&Default::default());
        terrain::host::clear(&mut encoder, target, &self.depth);
        terrain.record(&mut encoder, &view, &depth)?;
        self.composite.overlay(&mut encoder, &view);
        if offscreen.is_some() {
            let surface = frame.texture.create_view(&Default::default());
            self.composite
                .copy(&self.device, &mut encoder, &view, &surface);
        }
        let readback = shot.then(|| Readback::record(&alloc, &mut encoder, target));
        let submitted = Instant::now();
        self.queue.submit([encoder.finish()]);
        let times = self.gpu_ms.clone();
        self.queue.on_submitted_work_done(move || {
            if let Ok(mut t) = times.lock() {
                t.push(submitted.elapsed().as_secs_f64() * 1e3);
            }
        });
        let rgba = readback.map(|r| r.read(&self.device)).transpose()?;
        self.queue.present(frame);
        self.poll()?;
        Ok(Drawn {
            shot: rgba,
            width: camera.width,
            height: camera.height,
            cpu_ms: info.cpu_us * 1e-3,
        })
    }
}

/// `surface`'s next texture, the surface configured again where it has changed.
fn next_texture(
    surface: &wgpu::Surface,
    device: &wgpu::Device,
    config: &wgpu::SurfaceConfiguration,
) -> Result<wgpu::SurfaceTexture> {
    for _ in 0..3 {
        match surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(t)
            | wgpu::CurrentSurfaceTexture::Suboptimal(t) => {
                return Ok(t);
            }
            _ => surface.configure(device, config),
        }
    }
    Err(Error::Internal(
        "the window's surface gives no texture to draw into",
    ))
}

fn depth_texture(alloc: &Alloc, width: u32, height: u32) -> Texture {
    alloc.create_texture(&wgpu::TextureDescriptor {
        label: Some("view depth"),
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
}

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

struct Composite {
    overlay: wgpu::RenderPipeline,
    copy: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
    /// The figures' text, and the overlay texture it was drawn into.
    drawn: Option<(Vec<String>, Texture, wgpu::BindGroup)>,
}

impl Composite {
    fn new(device: &wgpu::Device, format: wgpu::TextureFormat) -> Composite {
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
    fn update(&mut self, alloc: &Alloc, queue: &wgpu::Queue, lines: Vec<String>, camera: &Camera) {
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
    fn overlay(&self, encoder: &mut wgpu::CommandEncoder, target: &wgpu::TextureView) {
        let Some((_, _, bind_group)) = &self.drawn else {
            return;
        };
        pass(encoder, target, &self.overlay, bind_group);
    }

    /// Writes `source` (of `target`'s format and size) into `target`.
    fn copy(
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

/// A copy of the presented texture for a screenshot, four bytes a pixel, rows padded to the
/// copy alignment.
struct Readback {
    buffer: terrain::gpu::alloc::Buffer,
    width: u32,
    height: u32,
    row: u32,
    bgra: bool,
}

impl Readback {
    fn record(alloc: &Alloc, encoder: &mut wgpu::CommandEncoder, texture: &wgpu::Texture) -> Self {
        let (width, height) = (texture.width(), texture.height());
        let row = (width * 4).div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT)
            * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
        let buffer = alloc.create_buffer(&wgpu::BufferDescriptor {
            label: Some("screenshot"),
            size: row as u64 * height as u64,
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        encoder.copy_texture_to_buffer(
            texture.as_image_copy(),
            wgpu::TexelCopyBufferInfo {
                buffer: &buffer,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(row),
                    rows_per_image: None,
                },
            },
            texture.size(),
        );
        let bgra = matches!(
            texture.format(),
            wgpu::TextureFormat::Bgra8Unorm | wgpu::TextureFormat::Bgra8UnormSrgb
        );
        Readback {
            buffer,
            width,
            height,
            row,
            bgra,
        }
    }

    /// RGBA rows, top first (BGRA swapped), opaque.
    fn read(self, device: &wgpu::Device) -> Result<Vec<u8>> {
        let (sender, receiver) = std::sync::mpsc::channel();
        self.buffer
            .slice(..)
            .map_async(wgpu::MapMode::Read, move |r| {
                let _ = sender.send(r);
            });
        device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| Error::device("reading the screenshot back", e))?;
        receiver
            .recv()
            .map_err(|_| Error::Internal("the screenshot's mapping never finished"))?
            .map_err(|e| Error::device("reading the screenshot back", e))?;
        let bytes = self
            .buffer
            .slice(..)
            .get_mapped_range()
            .map_err(|e| Error::device("reading the screenshot back", e))?;
        let mut rgba = Vec::with_capacity(self.width as usize * self.height as usize * 4);
        for y in 0..self.height as usize {
            let row = &bytes[y * self.row as usize..][..self.width as usize * 4];
            for px in row.chunks_exact(4) {
                let (r, b) = if self.bgra {
                    (px[2], px[0])
                } else {
                    (px[0], px[2])
                };
                rgba.extend([r, px[1], b, 255]);
            }
        }
        Ok(rgba)
    }
}
