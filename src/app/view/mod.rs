//! `terrain view`: an interactive window flying through the terrain.
//!
//! Controls: drag with the left mouse button to look; W/A/S/D to move, Q/E down and up (Shift:
//! ×4), at a speed scaled to the height above the ground; 1/2/3 warped, GeoMipMap, brute force;
//! V cycles the views (shaded, wireframe, split octave, importance, normals, coverage); F freezes
//! the level of detail (the warped mode's CPU stage, GeoMipMap's levels) to look at the mesh from
//! outside; R starts and stops recording the path flown (written to `--out-dir` as
//! `<scene>-flown.toml`, the scene with that `[path]`); P writes a screenshot to `--out-dir`
//! (`<scene>-view-<n>.png`); neither ever overwrites a file, taking the next free number; Esc
//! quits. The figures on screen: mode, view, frame time per pass, triangles, height above the
//! ground. Over a planet the same keys fly great circles (`terrain_engine::flight::flycam::PlanetFlyCamera`) in clipmaps
//! mode (1/2/3 do nothing), and a recorded path is a planet's `[path]`: the camera's keys and the
//! time flown. A sketch given with no camera place and no `[path]` tours its default orbit
//! (`scene::default_path`) until a key or the mouse takes over.
//!
//! Rules: the frame is drawn by the same renderers as every other command, on the device of a
//! wgpu surface made for the window, through the host API ([`terrain_engine::Terrain`], one per mode
//! and view, rebuilt only when the mode or the view changes; a new window size makes its targets
//! alone): recorded into
//! the surface's texture, the figures composited over it from a transparent overlay drawn on the
//! CPU (`present.rs`); the frame's pixels never leave the GPU. Where no surface can be made (none
//! for the window, no adapter that presents to it, a configuration it refuses), or
//! `TERRAIN_VIEW_PRESENT=cpu` asks, the frame is read back and presented through softbuffer with
//! the figures drawn on its pixels: softbuffer needs no GPU on the display's side, so the window
//! opens on any X11 or Wayland display. A screenshot is exactly the pixels presented.
//! `--frames N` quits after N frames, writing `--screenshot` first (how the test drives it under
//! Xvfb); [`run`] returns the session's figures ([`Summary`], `--json`).
//!
//! Rejected alternative: the CPU copy for every frame, a read-back per frame and a second
//! upload to the display (docs/decisions.md, “View presented through a surface”).

use crate::app::hud;
use crate::{Error, Result};
use terrain_engine::flight::flycam::{FlyCamera, PathRecorder, PlanetFlyCamera};
use terrain_engine::flight::path::CameraPath;

mod files;
mod flight;
mod present;
use flight::Flyer;
use present::{CpuPath, Present, SurfacePath, Want};
use std::collections::HashSet;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;
use terrain_engine::View;
use terrain_engine::scene;
use terrain_engine::scene::{MODES, Mode, Scene};
use terrain_engine::sketch::Atlas;
use winit::application::ApplicationHandler;
use winit::dpi::PhysicalSize;
use winit::event::{ElementState, MouseButton, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::keyboard::{KeyCode, PhysicalKey};
use winit::window::{Window, WindowId};

pub struct Options {
    pub scene_path: PathBuf,
    pub mode: Mode,
    pub size: (u32, u32),
    /// Quit after this many frames.
    pub frames: Option<u64>,
    /// The folder screenshots and recorded paths go to.
    pub out_dir: PathBuf,
    /// The first screenshot's file (P, or on quitting after `frames`); later ones go to `out_dir`.
    pub screenshot: Option<PathBuf>,
}

/// What a session showed, for `--json`.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Summary {
    /// How frames reached the screen: "surface" or "cpu".
    pub present: &'static str,
    pub frames: u64,
    /// The median time between presented frames, ms.
    pub interval_ms_median: Option<f64>,
    /// The median CPU stage (or the baselines' block selection), ms.
    pub cpu_ms_median: Option<f64>,
    /// The median GPU time, ms: on the surface path from submit to the queue's completion
    /// callback (run at the device's next poll: after presenting, or as the next frame starts);
    /// on the CPU path the frame's own (its passes' timestamps, else submit to read-back).
    pub gpu_ms_median: Option<f64>,
}

/// The environment variable that, set to `cpu`, presents through the CPU even where a surface
/// can be made.
pub const PRESENT_ENV: &str = "TERRAIN_VIEW_PRESENT";

struct App {
    o: Options,
    scene: Scene,
    atlas: Atlas,
    reach_m: f64,
    /// The scene camera's far distance (default: the sketch's farthest corner), kept in flight.
    far: f64,
    /// The mode whose needs the device is made for: the largest the window can switch to.
    largest: Mode,
    present: Option<Present>,
    mode: Mode,
    view: View,
    size: (u32, u32),
    frozen: bool,
    cam: Flyer,
    held: HashSet<KeyCode>,
    drag: Option<(f64, f64)>,
    last: Instant,
    frames: u64,
    /// A sketch shown with no camera place and no `[path]` tours its default orbit until a key
    /// or the mouse takes over: the path, and the seconds flown along it.
    tour: Option<(CameraPath, f64)>,
    shots: u32,
    /// Screenshots asked for (P) and not yet written: the next frame's.
    pending_shots: u32,
    recorder: Option<PathRecorder>,
    window: Option<Arc<Window>>,
    error: Option<Error>,
    /// When each frame was presented, and its CPU stage in ms.
    presented_at: Vec<Instant>,
    cpu_ms: Vec<f64>,
    message: String,
}

impl App {
    /// The terrain is built again for the next frame (mode or view changed).
    fn rebuild(&mut self) {
        if let Some(p) = &mut self.present {
            p.forget();
        }
        self.frozen = false;
    }

    /// What the window knows beside the frame, for the figures.
    fn status(&self, dt: f64) -> hud::Status {
        let mut flags = Vec::new();
        if self.frozen {
            flags.push("LOD frozen".to_string());
        }
        if let Some(r) = &self.recorder {
            flags.push(format!("recording ({} keys)", r.keys.len()));
        }
        if !self.message.is_empty() {
            flags.push(self.message.clone());
        }
        hud::Status {
            mode: self.mode,
            view: self.view,
            dt,
            above_m: self.above_m(),
            flags,
        }
    }

    fn key(&mut self, code: KeyCode, el: &ActiveEventLoop) -> Result<()> {
        let digit = match code {
            KeyCode::Digit1 => Some('1'),
            KeyCode::Digit2 => Some('2'),
            KeyCode::Digit3 => Some('3'),
            KeyCode::Digit4 => Some('4'),
            KeyCode::Digit5 => Some('5'),
            _ => None,
        };
        // The mode whose row names the key.
        let new_mode = digit.and_then(|d| MODES.iter().find(|r| r.key == Some(d)).map(|r| r.mode));
        let planet = matches!(self.cam, Flyer::Planet(_));
        let streamed = self.atlas.pyramid.is_some();
        match new_mode.map(|m| switch_mode(self.mode, m, planet, streamed)) {
            Some(Ok(Some(m))) => {
                self.mode = m;
                self.rebuild();
            }
            Some(Err(why)) => self.message = why,
            _ => {}
        }
        match code {
            KeyCode::KeyV => {
                let k = View::ALL.iter().position(|v| *v == self.view).unwrap_or(0);
                self.view = View::ALL[(k + 1) % View::ALL.len()];
                self.rebuild();
            }
            KeyCode::KeyF => self.frozen = !self.frozen,
            KeyCode::KeyR => self.toggle_recording()?,
            KeyCode::KeyP => self.pending_shots += 1,
            KeyCode::Escape => el.exit(),
            _ => {}
        }
        Ok(())
    }

    fn fail(&mut self, el: &ActiveEventLoop, e: Error) {
        self.error = Some(e);
        el.exit();
    }
}

impl ApplicationHandler for App {
    fn resumed(&mut self, el: &ActiveEventLoop) {
        if self.window.is_some() {
            return;
        }
        let attrs = Window::default_attributes()
            .with_title(format!("terrain view: {}", self.o.scene_path.display()))
            .with_inner_size(PhysicalSize::new(self.size.0, self.size.1));
        let window = match el.create_window(attrs) {
            Ok(w) => Arc::new(w),
            Err(e) => return self.fail(el, Error::window("cannot open one", e)),
        };
        match self.open(el, window.clone()) {
            Ok(p) => self.present = Some(p),
            Err(e) => return self.fail(el, e),
        }
        let size = window.inner_size();
        if size.width > 0 && size.height > 0 {
            self.size = (size.width, size.height);
        }
        self.window = Some(window);
        self.last = Instant::now();
    }

    fn window_event(&mut self, el: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        let result = match event {
            WindowEvent::CloseRequested => {
                el.exit();
                Ok(())
            }
            WindowEvent::Resized(s) if s.width > 0 && s.height > 0 => {
                // The next frame's camera has the new size; the terrain makes its targets for it.
                self.size = (s.width, s.height);
                Ok(())
            }
            WindowEvent::KeyboardInput { event, .. } => match event.physical_key {
                PhysicalKey::Code(code) if event.state == ElementState::Pressed => {
                    self.held.insert(code);
                    if event.repeat {
                        Ok(())
                    } else {
                        self.key(code, el)
                    }
                }
                PhysicalKey::Code(code) => {
                    self.held.remove(&code);
                    Ok(())
                }
                _ => Ok(()),
            },
            WindowEvent::MouseInput {
                state,
                button: MouseButton::Left,
                ..
            } => {
                if state == ElementState::Released {
                    self.drag = None;
                } else {
                    self.drag = Some((f64::NAN, f64::NAN));
                }
                Ok(())
            }
            WindowEvent::CursorMoved { position, .. } => {
                if let Some((x, y)) = self.drag {
                    if x.is_finite() {
                        self.cam.look(position.x - x, position.y - y);
                    }
                    self.drag = Some((position.x, position.y));
                }
                Ok(())
            }
            WindowEvent::RedrawRequested => self.redraw(el),
            _ => Ok(()),
        };
        if let Err(e) = result {
            self.fail(el, e);
        }
    }

    fn about_to_wait(&mut self, _: &ActiveEventLoop) {
        if let Some(w) = &self.window {
            w.request_redraw();
        }
    }
}

impl App {
    /// The surface path on `window`, or the CPU path where no surface can be made there (or
    /// the environment asks for it).
    fn open(&self, el: &ActiveEventLoop, window: Arc<Window>) -> Result<Present> {
        let forced = std::env::var(PRESENT_ENV).is_ok_and(|v| v == "cpu");
        let surface = match forced {
            true => Err(format!("{PRESENT_ENV}=cpu")),
            false => SurfacePath::open(el, window.clone(), &self.scene, &self.atlas, self.largest)?,
        };
        Ok(match surface {
            Ok(s) => Present::Surface(Box::new(s)),
            Err(why) => {
                log::info!("presenting through the CPU: {why}");
                let cpu = CpuPath::open(window, &self.scene, &self.atlas, self.largest)?;
                Present::Cpu(Box::new(cpu))
            }
        })
    }

    fn redraw(&mut self, el: &ActiveEventLoop) -> Result<()> {
        let dt = self.step();
        let camera = self.camera()?;
        let last = self.o.frames.is_some_and(|n| self.frames + 1 >= n);
        let shots = self.pending_shots + u32::from(last && self.o.screenshot.is_some());
        let status = self.status(dt);
        let want = Want {
            scene: &self.scene,
            atlas: &self.atlas,
            mode: self.mode,
            view: self.view,
            frozen: self.frozen,
        };
        let Some(present) = &mut self.present else {
            return Ok(());
        };
        let drawn = present.draw(&camera, &want, &status, shots > 0)?;
        if !drawn.presented {
            // Nothing shown (a minimised window): neither a frame nor a screenshot; the next
            // redraw tries again.
            return Ok(());
        }
        self.presented_at.push(Instant::now());
        self.cpu_ms.push(drawn.cpu_ms);
        self.frames += 1;
        if let Some(rgba) = &drawn.shot {
            for _ in 0..shots {
                let p = self.screenshot(rgba, drawn.width, drawn.height)?;
                self.message = format!("screenshot {}", p.display());
            }
            self.pending_shots = 0;
        }
        if last {
            el.exit();
        }
        Ok(())
    }

    /// The session's figures, for `--json`.
    fn summary(&mut self) -> Summary {
        let intervals: Vec<f64> = self
            .presented_at
            .windows(2)
            .map(|w| (w[1] - w[0]).as_secs_f64() * 1e3)
            .collect();
        let gpu = self
            .present
            .as_mut()
            .map(|p| p.gpu_ms())
            .unwrap_or_default();
        Summary {
            present: self.present.as_ref().map_or("none", |p| p.name()),
            frames: self.frames,
            interval_ms_median: median(intervals),
            cpu_ms_median: median(self.cpu_ms.clone()),
            gpu_ms_median: median(gpu),
        }
    }
}

/// The middle value (the mean of the two middle ones for an even count); `None` for none.
fn median(mut v: Vec<f64>) -> Option<f64> {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    match n {
        0 => None,
        _ if n % 2 == 1 => Some(v[n / 2]),
        _ => Some((v[n / 2 - 1] + v[n / 2]) / 2.0),
    }
}

/// The mode a mode key asks for, from `current`: none on a planet (clipmaps draw it) or when
/// it is the current one; refused with a message for the HUD where `requested` bakes the whole
/// sketch and the sketch is streamed, rather than ending the session on the renderer's error.
fn switch_mode(
    current: Mode,
    requested: Mode,
    planet: bool,
    streamed: bool,
) -> std::result::Result<Option<Mode>, String> {
    if planet || requested == current {
        return Ok(None);
    }
    if streamed && requested.bakes_whole_sketch() {
        return Err(format!(
            "{requested} bakes the whole sketch; this one is a streamed tile pyramid"
        ));
    }
    Ok(Some(requested))
}

/// Why no window opens, in the user's terms: winit's message carries its own source path
/// (`os error at …/winit-0.30/src/…/mod.rs:765: …`), which is dropped.
fn no_display(winit: &str) -> String {
    let unset = |v: &str| std::env::var_os(v).is_none_or(|s| s.is_empty());
    let cause = if unset("DISPLAY") && unset("WAYLAND_DISPLAY") {
        "no display: neither DISPLAY nor WAYLAND_DISPLAY is set".to_string()
    } else {
        let cause = match winit.find(".rs:") {
            Some(i) => winit[i..].split_once(": ").map_or(winit, |(_, c)| c),
            None => winit,
        };
        format!("cannot open the display: {}", cause.trim_end_matches('.'))
    };
    format!("{cause}; `terrain view` needs X11 or Wayland (headless: xvfb-run terrain view …)")
}

/// Opens the window and flies until it is closed (or `frames` are drawn); returns what it
/// showed.
pub fn run(scene: Scene, o: Options) -> Result<Summary> {
    let atlas = scene::load_atlas(&scene)?;
    let camera = scene::camera_of(&scene, &atlas)?;
    let reach_m = scene::detail_of(&scene, &atlas).reach_m();
    let (cam, largest) = match scene.planet() {
        Some(p) => (
            Flyer::Planet(PlanetFlyCamera::of_scene(&scene, p.radius_m)),
            Mode::Clipmaps,
        ),
        // Enough for every mode the window can switch to (the warped mode's mesh the largest).
        None => (Flyer::Plane(FlyCamera::from_camera(&camera)), Mode::Warped),
    };
    let tour = match scene.planet().is_none() && scene.path.is_none() && !scene.camera.is_placed() {
        true => Some((CameraPath::of_scene(&scene, &atlas)?, 0.0)),
        false => None,
    };
    let event_loop = EventLoop::new().map_err(|e| Error::NoDisplay {
        cause: no_display(&e.to_string()),
    })?;
    event_loop.set_control_flow(ControlFlow::Poll);
    let mut app = App {
        size: o.size,
        mode: o.mode,
        o,
        cam,
        scene,
        atlas,
        reach_m,
        far: camera.far,
        largest,
        present: None,
        view: View::Shaded,
        frozen: false,
        held: HashSet::new(),
        drag: None,
        last: Instant::now(),
        frames: 0,
        tour,
        shots: 0,
        pending_shots: 0,
        recorder: None,
        window: None,
        error: None,
        presented_at: Vec::new(),
        cpu_ms: Vec::new(),
        message: String::new(),
    };
    event_loop
        .run_app(&mut app)
        .map_err(|e| Error::window("event loop", e))?;
    if let Some(e) = app.error {
        return Err(e);
    }
    if app.recorder.is_some() {
        // Closed while recording: the path flown is kept, not lost.
        app.toggle_recording()?;
        eprintln!("{}", app.message);
    }
    Ok(app.summary())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_mode_key_switches_except_on_a_planet_or_to_a_baseline_over_a_streamed_sketch() {
        let (w, g) = (Mode::Warped, Mode::Geomipmap);
        assert_eq!(switch_mode(w, g, false, false), Ok(Some(g)));
        assert_eq!(switch_mode(w, w, false, false), Ok(None));
        assert_eq!(switch_mode(Mode::Clipmaps, g, true, false), Ok(None));
        let why = switch_mode(w, Mode::Bruteforce, false, true).unwrap_err();
        assert!(why.contains("bruteforce"), "{why}");
        assert_eq!(switch_mode(g, w, false, true), Ok(Some(w)));
    }

    #[test]
    fn the_median_is_the_middle_value_or_the_mean_of_the_two() {
        assert_eq!(median(vec![]), None);
        assert_eq!(median(vec![3.0, 1.0, 2.0]), Some(2.0));
        assert_eq!(median(vec![4.0, 1.0, 2.0, 3.0]), Some(2.5));
    }
}
