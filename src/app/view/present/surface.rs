//! The surface path: the terrain drawn by [`terrain_engine::Terrain`] into the surface's texture,
//! the figures composited over it.
//!
//! Rule: nothing of the frame leaves the GPU but a screenshot, a copy of the texture presented
//! (drawn offscreen in the surface's format and copied onto it where the surface allows no copies).

use super::overlay::Composite;
use super::{Drawn, Want};
use crate::app::hud::{self, Figures, Status};
use crate::{Error, Result};
use std::sync::{Arc, Mutex};
use std::time::Instant;
use terrain_engine::Camera;
use terrain_engine::alloc::{Alloc, Ledger, OnDevice, Texture};
use terrain_engine::readback::Readback;
use terrain_engine::scene::{Mode, Scene};
use terrain_engine::sketch::Atlas;
use terrain_engine::{Description, Targets, Terrain};
use winit::event_loop::ActiveEventLoop;
use winit::window::Window;

const DEPTH: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// The surface path: the terrain drawn on the surface's device into its texture.
pub(in crate::app::view) struct SurfacePath {
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
    pub(super) device: wgpu::Device,
    queue: wgpu::Queue,
    ledger: Ledger,
    /// What the window's own objects share (the terrain's share its context's).
    shared: OnDevice,
    depth: Texture,
    pub(super) terrain: Option<Terrain>,
    composite: Composite,
    /// Each frame's submit-to-completion time, ms, as the queue's callbacks report it.
    pub(super) gpu_ms: Arc<Mutex<Vec<f64>>>,
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
        .map_err(|e| terrain_engine::Error::device("the adapter that presents to the window", e))?;
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
        let shared = OnDevice::default();
        let alloc = Alloc {
            device: &device,
            ledger: &ledger,
            shared: &shared,
        };
        let depth = depth_texture(&alloc, config.width, config.height);
        let composite = Composite::new(&device, config.format);
        Ok(Ok(SurfacePath {
            surface,
            config,
            device,
            queue,
            ledger,
            shared,
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
            shared: &self.shared,
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
            .map_err(|e| terrain_engine::Error::device("the device was lost", e).into())
    }

    pub(super) fn draw(
        &mut self,
        camera: &Camera,
        want: &Want,
        status: &Status,
        shot: bool,
    ) -> Result<Drawn> {
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
            shared: &self.shared,
        };
        self.composite
            .update(&alloc, &self.queue, hud::lines(&figures, status), camera);

        let drawn = |shot, presented| Drawn {
            shot,
            width: camera.width,
            height: camera.height,
            cpu_ms: info.cpu_us * 1e-3,
            presented,
        };
        let Some(frame) = next_texture(&self.surface, &self.device, &self.config)? else {
            return Ok(drawn(None, false));
        };
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
        terrain_engine::clear(&mut encoder, &view, &depth);
        terrain.record(&mut encoder, &view, &depth)?;
        self.composite.overlay(&mut encoder, &view);
        if offscreen.is_some() {
            let surface = frame.texture.create_view(&Default::default());
            self.composite
                .copy(&self.device, &mut encoder, &view, &surface);
        }
        // A screenshot is the pixels presented, never a second rendering of the frame.
        let readback = match shot {
            true => {
                let r = Readback::new(&self.device, target)?;
                r.record(&mut encoder, target)?;
                Some(r)
            }
            false => None,
        };
        let submitted = Instant::now();
        self.queue.submit([encoder.finish()]);
        let times = self.gpu_ms.clone();
        self.queue.on_submitted_work_done(move || {
            if let Ok(mut t) = times.lock() {
                t.push(submitted.elapsed().as_secs_f64() * 1e3);
            }
        });
        let rgba = readback
            .map(|r| opaque(r.read_rgba(&self.device)))
            .transpose()?;
        self.queue.present(frame);
        self.poll()?;
        Ok(drawn(rgba, true))
    }
}

/// `surface`'s next texture, the surface configured again where it has changed (or was lost);
/// `None` where the window shows nothing now (minimised, covered, or the compositor too slow to
/// hand a texture over): the frame is skipped and the next one tries again.
fn next_texture(
    surface: &wgpu::Surface,
    device: &wgpu::Device,
    config: &wgpu::SurfaceConfiguration,
) -> Result<Option<wgpu::SurfaceTexture>> {
    for _ in 0..3 {
        match surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(t)
            | wgpu::CurrentSurfaceTexture::Suboptimal(t) => return Ok(Some(t)),
            wgpu::CurrentSurfaceTexture::Timeout | wgpu::CurrentSurfaceTexture::Occluded => {
                return Ok(None);
            }
            _ => surface.configure(device, config),
        }
    }
    Err(Error::window(
        "its surface",
        "gives no texture to draw into, configured three times",
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

/// A read-back's RGBA made opaque: a surface's alpha is the compositor's, not the picture's.
fn opaque(rgba: terrain_engine::Result<Vec<u8>>) -> terrain_engine::Result<Vec<u8>> {
    let mut rgba = rgba?;
    rgba.chunks_exact_mut(4).for_each(|px| px[3] = 255);
    Ok(rgba)
}
