//! The figures `terrain view` draws over each frame: mode, view, size and frame rate; the CPU
//! stage's and each GPU pass's time; triangles, height above the ground and flying speed; the
//! controls. White text over a one-pixel black shadow, so it reads on sky and snow alike.

use crate::app::flycam::FlyCamera;
use crate::eval::plot::{Rgb, draw_on_rgba, font};
use terrain::gpu::uniforms::View;
use terrain::render::Frame;
use terrain::scene::Mode;

/// What the window knows beside the frame.
pub struct Status {
    pub mode: Mode,
    pub view: View,
    /// Seconds since the last frame.
    pub dt: f64,
    pub above_m: f64,
    /// LOD frozen, recording, the last message.
    pub flags: Vec<String>,
}

const HELP: &str = "drag: look · WASD QE: move (Shift ×4) · 1 2 3: mode · V: view · F: freeze · R: record · P: screenshot · Esc";

/// `frame`'s pixels with the figures drawn over them.
pub fn draw(frame: &Frame, s: &Status) -> Vec<u8> {
    let (w, h) = (frame.width, frame.height);
    let g = &frame.gpu;
    let passes = if g.passes.0.is_empty() {
        "passes not timed".to_string()
    } else {
        let each: Vec<String> = g
            .passes
            .0
            .iter()
            .map(|(n, ms)| format!("{n} {ms:.1}"))
            .collect();
        each.join(", ")
    };
    let lines = [
        format!(
            "{} · {} · {}×{} · {:.1} fps {}",
            crate::eval::compare::figures::display(s.mode.name()),
            s.view.name(),
            w,
            h,
            1.0 / s.dt.max(1e-6),
            s.flags.join(" · ")
        ),
        format!(
            "CPU {:.2} ms (sketch map {:.2}, importance {:.2}, warp {:.2}) · GPU {:.1} ms ({})",
            frame.cpu_us * 1e-3,
            frame.cpu.sketch_map_us * 1e-3,
            frame.cpu.importance_us * 1e-3,
            frame.cpu.warp_us * 1e-3,
            g.gpu_ms,
            passes
        ),
        format!(
            "{} triangles · {:.0} m above the ground · {:.0} m/s",
            g.triangles,
            s.above_m,
            FlyCamera::speed(s.above_m, false)
        ),
    ];
    let mut texts: Vec<(&str, f64, i32)> = lines
        .iter()
        .enumerate()
        .map(|(k, line)| (line.as_str(), 12.0, 8 + 16 * k as i32))
        .collect();
    texts.push((HELP, 11.0, h as i32 - 15));
    let mut rgba = frame.rgba.clone();
    let drawn = draw_on_rgba(&mut rgba, w, h, |area| {
        for &(text, size, y) in &texts {
            area.draw_text(text, &font(size, Rgb::BLACK), (7, y + 1))?;
            area.draw_text(text, &font(size, Rgb::WHITE), (6, y))?;
        }
        Ok(())
    });
    // A frame without its figures rather than none (the font is bundled: this does not fail).
    if drawn.is_ok() {
        rgba
    } else {
        frame.rgba.clone()
    }
}
