//! How `terrain view` puts a frame on screen: through a wgpu surface (the terrain drawn by
//! [`terrain_engine::Terrain`] into the surface's texture, the figures composited over it), or,
//! where no surface can be made, through the CPU (the frame read back, the figures drawn on its
//! pixels, the pixels handed to softbuffer).
//!
//! Rules: a screenshot is the pixels presented. On the surface path that is a copy of the
//! surface's texture where the surface allows copies; elsewhere the frame is drawn into a
//! texture of the surface's format, copied from there onto the surface and read back from it.
//! The figures' overlay is drawn on the CPU (transparent, premultiplied) and uploaded only when
//! its text changes; nothing else of the frame leaves the GPU.

mod cpu;
mod overlay;
mod surface;

pub(super) use cpu::CpuPath;
pub(super) use surface::SurfacePath;

use crate::Result;
use crate::app::hud::Status;
use terrain_engine::Camera;
use terrain_engine::View;
use terrain_engine::scene::{Mode, Scene};
use terrain_engine::sketch::Atlas;

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
    /// Whether the frame reached the window (not where it shows nothing: minimised, covered).
    pub presented: bool,
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
