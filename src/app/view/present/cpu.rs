//! The CPU path: the renderer's frame read back, the figures drawn on its pixels, the pixels
//! handed to softbuffer.
//!
//! Rule: it needs no GPU on the display's side, so it opens on any X11 or Wayland display; the
//! screenshot is the very pixels handed to softbuffer.

use super::{Drawn, Want};
use crate::app::hud::{self, Figures, Status};
use crate::{Error, Result};
use std::num::NonZeroU32;
use std::sync::Arc;
use terrain_engine::Camera;
use terrain_engine::GpuContext;
use terrain_engine::Renderer;
use terrain_engine::scene::{Mode, Scene};
use terrain_engine::sketch::Atlas;
use winit::window::Window;

/// The CPU path: the renderer's frame read back and handed to softbuffer.
pub(in crate::app::view) struct CpuPath {
    ctx: GpuContext,
    pub(super) renderer: Option<Renderer>,
    surface: softbuffer::Surface<Arc<Window>, Arc<Window>>,
    pub(super) gpu_ms: Vec<f64>,
}

impl CpuPath {
    /// On `window`, rendering on a device of its own that holds `largest`'s needs.
    pub fn open(window: Arc<Window>, scene: &Scene, atlas: &Atlas, largest: Mode) -> Result<Self> {
        let ctx = GpuContext::new(&terrain_engine::needs(scene, largest, atlas))?;
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

    pub(super) fn draw(
        &mut self,
        camera: &Camera,
        want: &Want,
        status: &Status,
        shot: bool,
    ) -> Result<Drawn> {
        let renderer = match &mut self.renderer {
            Some(r) => r,
            None => self.renderer.insert(Renderer::with_context(
                self.ctx.clone(),
                &want.scene(camera),
                want.atlas.clone(),
                want.mode,
                want.view(),
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
            presented: true,
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
