//! The figures `terrain view` draws over each frame: mode, view, size and frame rate; the CPU
//! stage's and each GPU pass's time; triangles, height above the ground and flying speed; the
//! controls. White text over a one-pixel black shadow, so it reads on sky and snow alike.
//!
//! Rules: the text is laid out once ([`lines`]) and drawn either over a frame's pixels
//! ([`draw`], the CPU presentation) or into a transparent overlay ([`overlay`], premultiplied
//! RGBA, composited over the surface's texture on the GPU); the two show the same text in the
//! same place.

use crate::plot::{Rgb, draw_on_rgba, font};
use terrain_engine::Frame;
use terrain_engine::View;
use terrain_engine::flight::flycam::FlyCamera;
use terrain_engine::scene::Mode;
use terrain_engine::stage::StageTimes;

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

/// What the frame itself says about its cost.
#[derive(Clone, Debug, Default)]
pub struct Figures {
    pub width: u32,
    pub height: u32,
    /// The warped mode's CPU stage by part.
    pub stage: StageTimes,
    /// All the frame's CPU work, µs.
    pub cpu_us: f64,
    pub gpu_ms: f64,
    /// Each pass's time, ms, where the passes are timed.
    pub passes: Vec<(String, f64)>,
    pub triangles: u64,
}

impl Figures {
    /// A frame rendered and read back.
    pub fn of_frame(frame: &Frame) -> Figures {
        Figures {
            width: frame.width,
            height: frame.height,
            stage: frame.cpu,
            cpu_us: frame.cpu_us,
            gpu_ms: frame.gpu.gpu_ms,
            passes: frame
                .gpu
                .passes
                .0
                .iter()
                .map(|(n, ms)| (n.to_string(), *ms))
                .collect(),
            triangles: frame.gpu.triangles,
        }
    }
}

const HELP: &str = "drag: look · WASD QE: move (Shift ×4) · 1 2 3: mode · V: view · F: freeze · R: record · P: screenshot · Esc";

/// The figures' lines, top first (the controls' line last).
pub fn lines(f: &Figures, s: &Status) -> Vec<String> {
    let passes = if f.passes.is_empty() {
        "passes not timed".to_string()
    } else {
        let each: Vec<String> = f
            .passes
            .iter()
            .map(|(n, ms)| format!("{n} {ms:.1}"))
            .collect();
        each.join(", ")
    };
    vec![
        format!(
            "{} · {} · {}×{} · {:.1} fps {}",
            s.mode.display(),
            s.view.name(),
            f.width,
            f.height,
            1.0 / s.dt.max(1e-6),
            s.flags.join(" · ")
        ),
        format!(
            "CPU {:.2} ms (sketch map {:.2}, importance {:.2}, warp {:.2}) · GPU {:.1} ms ({})",
            f.cpu_us * 1e-3,
            f.stage.sketch_map_us * 1e-3,
            f.stage.importance_us * 1e-3,
            f.stage.warp_us * 1e-3,
            f.gpu_ms,
            passes
        ),
        format!(
            "{} triangles · {:.0} m above the ground · {:.0} m/s",
            f.triangles,
            s.above_m,
            FlyCamera::speed(s.above_m, false)
        ),
        HELP.to_string(),
    ]
}

/// Draws `lines` over `rgba` (`width` × `height`, opaque); the pixels are left as they were
/// where the text cannot be drawn (the font is bundled: it can).
pub fn draw(rgba: &mut [u8], width: u32, height: u32, lines: &[String]) {
    let (figures, help) = lines.split_at(lines.len().saturating_sub(1));
    let mut texts: Vec<(&str, f64, i32)> = figures
        .iter()
        .enumerate()
        .map(|(k, line)| (line.as_str(), 12.0, 8 + 16 * k as i32))
        .collect();
    texts.extend(help.iter().map(|l| (l.as_str(), 11.0, height as i32 - 15)));
    let mut drawn = rgba.to_vec();
    let done = draw_on_rgba(&mut drawn, width, height, |area| {
        for &(text, size, y) in &texts {
            area.draw_text(text, &font(size, Rgb::BLACK), (7, y + 1))?;
            area.draw_text(text, &font(size, Rgb::WHITE), (6, y))?;
        }
        Ok(())
    });
    if done.is_ok() {
        rgba.copy_from_slice(&drawn);
    }
}

/// `lines` alone, `width` × `height`: premultiplied RGBA, transparent where there is no text.
/// The text is drawn over black and over white; where the two differ the text lets that much
/// of the background through, which gives its coverage.
pub fn overlay(width: u32, height: u32, lines: &[String]) -> Vec<u8> {
    let n = width as usize * height as usize * 4;
    let mut black: Vec<u8> = [0, 0, 0, 255].repeat(n / 4);
    let mut white = vec![255u8; n];
    draw(&mut black, width, height, lines);
    draw(&mut white, width, height, lines);
    let mut out = vec![0u8; n];
    for ((o, b), w) in out
        .chunks_exact_mut(4)
        .zip(black.chunks_exact(4))
        .zip(white.chunks_exact(4))
    {
        let through = (0..3).map(|c| w[c].saturating_sub(b[c])).max().unwrap_or(0);
        let alpha = 255 - through;
        // Drawn over black, the pixel is the text's colour times its coverage: premultiplied.
        for c in 0..3 {
            o[c] = b[c].min(alpha);
        }
        o[3] = alpha;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_overlay_composited_over_pixels_gives_the_text_drawn_on_them() {
        let (w, h) = (200, 40);
        let lines = vec!["CPU 1.00 ms".to_string(), "Esc".to_string()];
        let grey: Vec<u8> = [90, 140, 200, 255].repeat((w * h) as usize);
        let mut direct = grey.clone();
        draw(&mut direct, w, h, &lines);
        let over = overlay(w, h, &lines);
        assert!(over.chunks_exact(4).any(|p| p[3] == 0), "not transparent");
        assert!(over.chunks_exact(4).any(|p| p[3] == 255), "no text");
        for ((d, o), g) in direct
            .chunks_exact(4)
            .zip(over.chunks_exact(4))
            .zip(grey.chunks_exact(4))
        {
            for c in 0..3 {
                let composite = o[c] as f64 + (255 - o[3]) as f64 / 255.0 * g[c] as f64;
                assert!((composite - d[c] as f64).abs() <= 2.0, "{d:?} {o:?}");
            }
        }
    }
}
