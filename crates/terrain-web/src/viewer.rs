//! The viewer: a scene drawn into a canvas, as the crate's rules say.

use crate::frames::{median, push};
use crate::present::{self, Present};
use std::cell::Cell;
use std::collections::{HashSet, VecDeque};
use std::rc::Rc;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use terrain::readback::Readback;
use terrain::{Camera, Description, Mode, Scene, Targets, Terrain, View, wgpu};
use terrain_engine::flight::flycam::{CLEARANCE_M, FlyCamera, Motion};
use terrain_engine::flight::path::CameraPath;
use terrain_engine::scene::{MODES, ModeRow, ground_under};
use wasm_bindgen::prelude::*;

/// The longest step a frame moves the camera by, seconds (a tab in the background for a minute
/// resumes where it was, not a minute further on).
const MOST_DT_S: f64 = 0.25;
/// What a held key adds to the frame's motion.
type Move = fn(&mut Motion);

/// The keys that fly the camera, as `terrain view`'s: W/A/S/D (or the arrows) move, E/Q (or
/// Page Up/Down) rise and sink, Shift hurries.
const MOVES: &[(&str, Move)] = &[
    ("KeyW", |m| m.forward += 1.0),
    ("ArrowUp", |m| m.forward += 1.0),
    ("KeyS", |m| m.forward -= 1.0),
    ("ArrowDown", |m| m.forward -= 1.0),
    ("KeyD", |m| m.right += 1.0),
    ("ArrowRight", |m| m.right += 1.0),
    ("KeyA", |m| m.right -= 1.0),
    ("ArrowLeft", |m| m.right -= 1.0),
    ("KeyE", |m| m.up += 1.0),
    ("PageUp", |m| m.up += 1.0),
    ("KeyQ", |m| m.up -= 1.0),
    ("PageDown", |m| m.up -= 1.0),
    ("ShiftLeft", |_| {}),
    ("ShiftRight", |_| {}),
];
const DEPTH: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
/// Frames submitted and not yet finished on the GPU beyond which an animation frame draws
/// nothing: a browser calls the page sixty times a second whatever its adapter, and on a slow
/// one (SwiftShader: seconds a frame) every frame submitted meanwhile would queue behind the
/// first, a capture or a mode switch minutes late. Two keep a fast GPU busy across the
/// callback's latency.
const MOST_IN_FLIGHT: usize = 2;

/// A scene drawn into a canvas: the page's one object.
#[wasm_bindgen]
pub struct Viewer {
    /// Kept for the viewer's life: Chromium refuses to map a buffer (a capture's) once the
    /// instance and adapter that made its device are gone.
    _instance: wgpu::Instance,
    _adapter: wgpu::Adapter,
    device: wgpu::Device,
    queue: wgpu::Queue,
    present: Present,
    /// The canvas's size, pixels.
    size: (u32, u32),
    /// The scene's own camera at that size: the still, and the far distance a flight keeps.
    scene_camera: Camera,
    targets: Targets,
    depth: wgpu::TextureView,
    description: Description,
    terrain: Terrain,
    mode: Mode,
    view: View,
    /// A terrain switched to and not yet drawn, with its mode and view: GeoMipMap's and brute
    /// force's bake is read back from the GPU before it can draw, which a page cannot wait for,
    /// so the terrain before goes on drawing until it is ready.
    coming: Option<(Terrain, Mode, View)>,
    adapter: String,
    /// `?still=1`: the scene's own camera, held.
    still: bool,
    fly: FlyCamera,
    /// The scene's path (or the default orbit) and the seconds flown along it, until the user
    /// takes over.
    tour: Option<(CameraPath, f64)>,
    motion: Motion,
    /// The keys held (`KeyboardEvent.code`).
    held: HashSet<String>,
    reach_m: f64,
    /// Frames drawn since the mode, view or size last changed.
    frames: u64,
    settled: Arc<AtomicBool>,
    /// Frames submitted and not yet finished on the GPU.
    in_flight: Arc<AtomicUsize>,
    /// A capture asked for and not yet delivered.
    capturing: Rc<Cell<bool>>,
    /// Frames shown by copy before the mode, view or size last changed.
    shown_before: u64,
    last_ms: Option<f64>,
    intervals_ms: VecDeque<f64>,
    cpu_us: VecDeque<f64>,
    triangles: u64,
    /// A capture asked for: the Promise's resolve and reject, for the next frame.
    capture: Option<(js_sys::Function, js_sys::Function)>,
}

#[wasm_bindgen]
impl Viewer {
    /// A viewer of the scene `scene_toml` over the sketch file's `sketch` bytes (ignored for a
    /// synthetic sketch), drawing into `canvas` at its size in `mode` (empty: the scene's).
    /// `still`: the scene's camera, held.
    pub async fn create(
        canvas: web_sys::HtmlCanvasElement,
        scene_toml: String,
        sketch: Vec<u8>,
        mode: String,
        still: bool,
        present: String,
    ) -> Result<Viewer, JsError> {
        let scene = Scene::parse(&scene_toml, ".".into())
            .map_err(|f| JsError::new(&format!("scene.toml: {f}")))?;
        let description = Description::from_bytes(scene, &sketch).map_err(error)?;
        let mode = match mode.as_str() {
            "" => description.scene().render.mode,
            name => Mode::parse(name).ok_or_else(|| {
                JsError::new(&format!("mode `{name}`: one of {}", Mode::choices()))
            })?,
        };
        let (width, height) = (canvas.width().max(1), canvas.height().max(1));
        let instance = wgpu::Instance::new(wgpu::InstanceDescriptor {
            backends: wgpu::Backends::BROWSER_WEBGPU,
            ..wgpu::InstanceDescriptor::new_without_display_handle()
        });
        // A still, or a page asked to (`?present=copy`), is copied into the canvas's 2D
        // context; otherwise the canvas's WebGPU context shows the frames.
        let copy = still || present == "copy";
        let context = copy.then(|| present::context_2d(&canvas)).transpose()?;
        let surface = match copy {
            true => None,
            false => Some(
                instance
                    .create_surface(wgpu::SurfaceTarget::Canvas(canvas))
                    .map_err(|e| JsError::new(&format!("the canvas: {e}")))?,
            ),
        };
        let adapter = instance
            .request_adapter(&wgpu::RequestAdapterOptions {
                compatible_surface: surface.as_ref(),
                ..Default::default()
            })
            .await
            .map_err(|e| JsError::new(&format!("no WebGPU adapter: {e}")))?;
        let (device, queue) = adapter
            .request_device(&wgpu::DeviceDescriptor {
                label: Some("terrain page"),
                required_features: Description::optional_features(adapter.features()),
                required_limits: limits(&description),
                ..Default::default()
            })
            .await
            .map_err(|e| JsError::new(&format!("the WebGPU device: {e}")))?;
        let (present, colour) = match (surface, context) {
            (Some(surface), _) => {
                let mut config = surface
                    .get_default_config(&adapter, width, height)
                    .ok_or_else(|| JsError::new("the adapter cannot draw into this canvas"))?;
                // The canvas's format is plain (bgra8unorm or rgba8unorm); the frame is
                // written through its sRGB view, as every snapshot's colour target is.
                let colour = config.format.add_srgb_suffix();
                config.view_formats = vec![colour];
                // The frame covers the canvas; its alpha is not coverage, so the page behind
                // never shows through.
                config.alpha_mode = wgpu::CompositeAlphaMode::Opaque;
                // A capture copies the canvas's texture.
                config.usage |= wgpu::TextureUsages::COPY_SRC;
                surface.configure(&device, &config);
                (Present::Canvas { surface, config }, colour)
            }
            (None, Some(context)) => {
                let colour = wgpu::TextureFormat::Rgba8UnormSrgb;
                let present = Present::Copy {
                    colour: present::own_colour(&device, colour, (width, height)),
                    context,
                    in_flight: Default::default(),
                    shown: Default::default(),
                };
                (present, colour)
            }
            (None, None) => unreachable!("a surface or a 2D context"),
        };
        let targets = Targets {
            colour,
            depth: DEPTH,
            samples: 1,
        };
        let info = adapter.get_info();
        let camera = description.camera(width, height).map_err(error)?;
        let tour = match still {
            true => None,
            false => Some((
                CameraPath::of_scene(description.scene(), description.atlas()).map_err(error)?,
                0.0,
            )),
        };
        let reach_m = description.detail().reach_m();
        let terrain = Terrain::new(
            &device,
            &queue,
            targets,
            description.clone().with_mode(mode),
        )
        .map_err(error)?;
        Ok(Viewer {
            _instance: instance,
            _adapter: adapter,
            depth: depth_view(&device, width, height),
            device,
            queue,
            present,
            size: (width, height),
            scene_camera: camera.clone(),
            targets,
            description,
            terrain,
            mode,
            view: View::Shaded,
            adapter: adapter_name(&info),
            still,
            fly: FlyCamera::from_camera(&camera),
            tour,
            motion: Motion::default(),
            held: HashSet::new(),
            reach_m,
            frames: 0,
            settled: Arc::default(),
            in_flight: Arc::default(),
            capturing: Rc::default(),
            shown_before: 0,
            last_ms: None,
            intervals_ms: VecDeque::new(),
            cpu_us: VecDeque::new(),
            triangles: 0,
            capture: None,
            coming: None,
        })
    }

    /// Draws a frame at `now_ms` (the animation frame's time): the camera moved by the time
    /// since the last, the CPU stage, the passes into the canvas. Draws nothing while
    /// [`MOST_IN_FLIGHT`] frames are still on the GPU.
    pub fn frame(&mut self, now_ms: f64) -> Result<(), JsError> {
        if self.in_flight.load(Ordering::Acquire) >= MOST_IN_FLIGHT {
            return Ok(());
        }
        let dt = self
            .last_ms
            .map_or(0.0, |l| ((now_ms - l) / 1000.0).clamp(0.0, MOST_DT_S));
        if let Some(last) = self.last_ms {
            push(&mut self.intervals_ms, now_ms - last);
        }
        self.last_ms = Some(now_ms);
        self.take_coming()?;
        // Until the terrain switched to draws, no frame settles: the one before goes on drawing
        // (and a first terrain still reading its bake back draws the sky).
        let ready = self.coming.is_none() && self.terrain.ready().map_err(error)?;
        let camera = self.camera(dt)?;
        let info = self.terrain.prepare(&camera).map_err(error)?;
        push(&mut self.cpu_us, info.cpu_us);
        self.triangles = info.triangles;
        let Some(target) = self.present.target(&self.device)? else {
            return Ok(());
        };
        let texture = target.texture();
        let colour = texture.create_view(&wgpu::TextureViewDescriptor {
            format: Some(self.targets.colour),
            ..Default::default()
        });
        let mut encoder = self.device.create_command_encoder(&Default::default());
        terrain::clear(&mut encoder, &colour, &self.depth);
        self.terrain
            .record(&mut encoder, &colour, &self.depth)
            .map_err(error)?;
        let capture = match self.capture.is_some() {
            true => {
                let r = Readback::new(&self.device, texture).map_err(error)?;
                r.record(&mut encoder, texture).map_err(error)?;
                Some(r)
            }
            false => None,
        };
        let copy = self.present.record_copy(&self.device, &mut encoder)?;
        self.queue.submit([encoder.finish()]);
        self.present.show(&self.queue, target, copy);
        if let (Some(r), Some((resolve, reject))) = (capture, self.capture.take()) {
            let capturing = self.capturing.clone();
            r.read_rgba_later(move |texels| {
                capturing.set(false);
                // A page gone away has no one to tell.
                let _ = match texels {
                    Ok(t) => resolve.call1(&JsValue::NULL, &js_sys::Uint8Array::from(&t[..])),
                    Err(e) => reject.call1(&JsValue::NULL, &JsError::new(&e.to_string()).into()),
                };
            });
        }
        let in_flight = self.in_flight.clone();
        let settled = (self.frames == 0 && ready).then(|| self.settled.clone());
        in_flight.fetch_add(1, Ordering::AcqRel);
        self.queue.on_submitted_work_done(move || {
            in_flight.fetch_sub(1, Ordering::AcqRel);
            if let Some(s) = settled {
                s.store(true, Ordering::Release);
            }
        });
        self.frames += u64::from(ready);
        Ok(())
    }

    /// The next frame's pixels: a Promise of a `Uint8Array`, RGBA rows top first, of the
    /// canvas's texture as the frame left it (copied before it is shown). Where a browser's
    /// screenshot cannot see a WebGPU canvas (headless Chromium on SwiftShader), this can.
    pub fn capture(&mut self) -> js_sys::Promise {
        let mut slot = None;
        let promise = js_sys::Promise::new(&mut |resolve, reject| slot = Some((resolve, reject)));
        self.capture = slot;
        self.capturing.set(true);
        promise
    }

    /// Whether a capture waits for its frame or its copy: a held still draws a frame for it.
    pub fn capture_pending(&self) -> bool {
        self.capturing.get()
    }

    /// Whether a frame with the current mode, view and size has finished on the GPU (and,
    /// shown by copy, reached the canvas).
    pub fn settled(&self) -> bool {
        match self.present.shown() {
            Some(shown) => shown > self.shown_before,
            None => self.settled.load(Ordering::Acquire),
        }
    }

    /// The canvas is now `width` × `height` pixels.
    pub fn resize(&mut self, width: u32, height: u32) -> Result<(), JsError> {
        let (width, height) = (width.max(1), height.max(1));
        if (width, height) == self.size {
            return Ok(());
        }
        self.scene_camera = self.description.camera(width, height).map_err(error)?;
        self.size = (width, height);
        self.present.resize(&self.device, self.size);
        self.depth = depth_view(&self.device, width, height);
        self.unsettle();
        Ok(())
    }

    /// Draws in the mode named `name` from now on (a mode of [`Viewer::modes`]).
    pub fn set_mode(&mut self, name: &str) -> Result<(), JsError> {
        let mode = page_modes()
            .map(|r| r.mode)
            .find(|m| m.name() == name)
            .ok_or_else(|| {
                let names: Vec<&str> = page_modes().map(|r| r.mode.name()).collect();
                JsError::new(&format!("mode `{name}`: one of {}", names.join(", ")))
            })?;
        self.rebuild(mode, self.view)
    }

    /// Draws in the view named `name` (`shaded`, `wireframe`, …) from now on.
    pub fn set_view(&mut self, name: &str) -> Result<(), JsError> {
        let view = View::parse(name)
            .ok_or_else(|| JsError::new(&format!("view `{name}`: one of {}", View::choices())))?;
        self.rebuild(self.mode, view)
    }

    /// The modes the page switches between, those `terrain view` offers on a key: an array of
    /// `{name, label, key}`.
    pub fn modes(&self) -> Result<js_sys::Array, JsError> {
        let rows = js_sys::Array::new();
        for r in page_modes() {
            let o = js_sys::Object::new();
            let key = r.key.map(String::from).unwrap_or_default();
            for (k, v) in [("name", r.mode.name()), ("label", r.display), ("key", &key)] {
                js_sys::Reflect::set(&o, &k.into(), &v.into())
                    .map_err(|_| JsError::new("modes: an object the page cannot write"))?;
            }
            rows.push(&o);
        }
        Ok(rows)
    }

    /// The mode drawn, by name.
    pub fn mode(&self) -> String {
        self.mode.name().into()
    }

    /// The mode switched to and not yet drawn (its bake on its way back from the GPU), by name;
    /// empty when none.
    pub fn coming(&self) -> String {
        self.coming
            .as_ref()
            .map_or(String::new(), |(_, mode, _)| mode.name().into())
    }

    /// The view drawn, by name.
    pub fn view(&self) -> String {
        self.view.name().into()
    }

    /// A key (`KeyboardEvent.code`) went down or up ([`MOVES`]). Moving ends the tour.
    pub fn key(&mut self, code: &str, down: bool) {
        if !MOVES.iter().any(|(c, _)| *c == code) {
            return;
        }
        if down {
            self.held.insert(code.to_string());
            self.tour = None;
        } else {
            self.held.remove(code);
        }
        let mut m = Motion {
            fast: self.held.contains("ShiftLeft") || self.held.contains("ShiftRight"),
            ..Motion::default()
        };
        for (_, push) in MOVES.iter().filter(|(c, _)| self.held.contains(*c)) {
            push(&mut m);
        }
        m.forward = m.forward.clamp(-1.0, 1.0);
        m.right = m.right.clamp(-1.0, 1.0);
        m.up = m.up.clamp(-1.0, 1.0);
        self.motion = m;
    }

    /// A drag (mouse or one finger) of `dx`, `dy` CSS pixels: the camera turns; the tour ends.
    pub fn look(&mut self, dx: f64, dy: f64) {
        self.tour = None;
        self.fly.look(dx, dy);
    }

    /// A pinch or two-finger drag's move: `amount` > 0 forward, for the next frame.
    pub fn nudge(&mut self, amount: f64) {
        self.tour = None;
        self.motion.forward = amount.clamp(-1.0, 1.0);
    }

    /// Whether the scene's path (or the default orbit) is still being flown.
    pub fn touring(&self) -> bool {
        self.tour.is_some()
    }

    /// `{frame_ms, cpu_stage_us, triangles, adapter, mode, view, frames, coming}`: medians over
    /// the last sixty frames (`frame_ms` between animation frames, `cpu_stage_us` the CPU
    /// stage's), the last frame's triangles, the adapter's name, the mode switched to and not
    /// yet drawn.
    pub fn stats(&self) -> Result<JsValue, JsError> {
        let o = js_sys::Object::new();
        let set = |k: &str, v: JsValue| js_sys::Reflect::set(&o, &k.into(), &v).map(|_| ());
        let f = |v: Option<f64>| v.map_or(JsValue::NULL, JsValue::from_f64);
        (|| -> Result<(), JsValue> {
            set("frame_ms", f(median(&self.intervals_ms)))?;
            set("cpu_stage_us", f(median(&self.cpu_us)))?;
            set("triangles", JsValue::from_f64(self.triangles as f64))?;
            set("adapter", self.adapter.as_str().into())?;
            set("mode", self.mode.name().into())?;
            set("view", self.view.name().into())?;
            set("frames", JsValue::from_f64(self.frames as f64))?;
            set("coming", self.coming().into())?;
            set("present", self.present.name().into())
        })()
        .map_err(|_| JsError::new("stats: an object the page cannot write"))?;
        Ok(o.into())
    }
}

impl Viewer {
    /// The camera of this frame, after `dt` seconds of flight.
    fn camera(&mut self, dt: f64) -> Result<Camera, JsError> {
        let (w, h) = self.size;
        if self.still {
            return Ok(self.scene_camera.clone());
        }
        if let Some((path, t)) = &mut self.tour {
            *t = (*t + dt).rem_euclid(path.duration_s());
            let s = *t * path.speed_mps;
            self.fly = FlyCamera::looking(path.position(s), path.direction(s));
        }
        let atlas = self.description.atlas();
        let floor = ground_under(atlas, self.fly.eye.truncate())
            .ok()
            .flatten()
            .map(|g| g + self.reach_m + CLEARANCE_M);
        self.fly.step(dt, &self.motion, floor);
        let scene = self.description.scene();
        self.fly
            .camera(scene.camera.fov_y_deg, w, h, self.scene_camera.far)
            .map_err(error)
    }

    fn rebuild(&mut self, mode: Mode, view: View) -> Result<(), JsError> {
        let description = self.description.clone().with_mode(mode).with_view(view);
        let terrain =
            Terrain::new(&self.device, &self.queue, self.targets, description).map_err(error)?;
        self.coming = Some((terrain, mode, view));
        self.unsettle();
        self.take_coming()
    }

    /// Draws with the terrain switched to from now on, once it is ready.
    fn take_coming(&mut self) -> Result<(), JsError> {
        let Some((terrain, ..)) = &mut self.coming else {
            return Ok(());
        };
        if !terrain.ready().map_err(error)? {
            return Ok(());
        }
        if let Some((terrain, mode, view)) = self.coming.take() {
            (self.terrain, self.mode, self.view) = (terrain, mode, view);
            self.unsettle();
        }
        Ok(())
    }

    fn unsettle(&mut self) {
        self.frames = 0;
        self.settled = Arc::default();
        // A copy in flight shows a frame from before.
        self.shown_before = self.present.shown().unwrap_or(0) + self.present.in_flight() as u64;
    }
}

/// The modes the page offers: those `terrain view` switches between on a key, over a sketch.
fn page_modes() -> impl Iterator<Item = &'static ModeRow> {
    MODES
        .iter()
        .filter(|r| r.key.is_some() && r.mode.draws(false))
}

/// The limits of the largest terrain the page may switch to.
fn limits(description: &Description) -> wgpu::Limits {
    page_modes()
        .map(|r| description.clone().with_mode(r.mode).required_limits())
        .fold(wgpu::Limits::default(), |a, b| wgpu::Limits {
            max_storage_buffer_binding_size: a
                .max_storage_buffer_binding_size
                .max(b.max_storage_buffer_binding_size),
            max_buffer_size: a.max_buffer_size.max(b.max_buffer_size),
            ..a
        })
}

fn depth_view(device: &wgpu::Device, width: u32, height: u32) -> wgpu::TextureView {
    let usage = wgpu::TextureUsages::RENDER_ATTACHMENT;
    present::texture(device, DEPTH, (width, height), usage).create_view(&Default::default())
}

/// The adapter as the browser names it: "google swiftshader", say.
fn adapter_name(info: &wgpu::AdapterInfo) -> String {
    let name = [
        info.name.as_str(),
        info.driver.as_str(),
        info.driver_info.as_str(),
    ]
    .into_iter()
    .filter(|s| !s.is_empty())
    .collect::<Vec<_>>()
    .join(" ");
    if name.is_empty() {
        format!("{:?}", info.backend)
    } else {
        name
    }
}

fn error(e: terrain::Error) -> JsError {
    JsError::new(&e.to_string())
}
