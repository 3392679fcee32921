//! The PNG canvas: shapes by tiny-skia (anti-aliased), text by ab_glyph from the bundled font,
//! blended into an opaque white pixmap.

use super::{Anchor, Canvas, Rgb};
use ab_glyph::{Font, FontRef, PxScale, ScaleFont, point};
use tiny_skia::{Color, FillRule, Paint, PathBuilder, Pixmap, Rect, Stroke, StrokeDash, Transform};

static DEJAVU_SANS: &[u8] = include_bytes!("../../../assets/fonts/DejaVuSans.ttf");

pub struct RasterCanvas {
    pub pixmap: Pixmap,
    font: FontRef<'static>,
}

fn paint(c: Rgb) -> Paint<'static> {
    let mut p = Paint::default();
    p.set_color(Color::from_rgba8(c.0, c.1, c.2, 255));
    p.anti_alias = true;
    p
}

impl RasterCanvas {
    pub fn new(width: u32, height: u32) -> Option<RasterCanvas> {
        let mut pixmap = Pixmap::new(width, height)?;
        pixmap.fill(Color::WHITE);
        let font = FontRef::try_from_slice(DEJAVU_SANS).ok()?;
        Some(RasterCanvas { pixmap, font })
    }

    /// A canvas over opaque RGBA8 pixels (a rendered frame, to write on).
    pub fn from_rgba(width: u32, height: u32, rgba: Vec<u8>) -> Option<RasterCanvas> {
        let pixmap = Pixmap::from_vec(rgba, tiny_skia::IntSize::from_wh(width, height)?)?;
        let font = FontRef::try_from_slice(DEJAVU_SANS).ok()?;
        Some(RasterCanvas { pixmap, font })
    }

    /// The advance width of `text` at `size` pixels.
    pub fn text_width(&self, text: &str, size: f32) -> f32 {
        let f = self.font.as_scaled(PxScale::from(size));
        let mut w = 0.0;
        let mut prev = None;
        for c in text.chars() {
            let id = f.glyph_id(c);
            if let Some(p) = prev {
                w += f.kern(p, id);
            }
            w += f.h_advance(id);
            prev = Some(id);
        }
        w
    }

    /// Blends `colour` at coverage `a` into pixel (x, y); the pixmap is opaque throughout.
    fn blend(&mut self, x: i32, y: i32, colour: Rgb, a: f32) {
        let (w, h) = (self.pixmap.width() as i32, self.pixmap.height() as i32);
        if x < 0 || y < 0 || x >= w || y >= h || a <= 0.0 {
            return;
        }
        let k = ((y * w + x) * 4) as usize;
        let data = self.pixmap.data_mut();
        let a = a.min(1.0);
        for (c, v) in [colour.0, colour.1, colour.2].into_iter().enumerate() {
            data[k + c] = (data[k + c] as f32 * (1.0 - a) + v as f32 * a).round() as u8;
        }
    }
}

impl Canvas for RasterCanvas {
    fn polyline(&mut self, points: &[(f32, f32)], colour: Rgb, width: f32, dashed: bool) {
        let mut pb = PathBuilder::new();
        for (k, &(x, y)) in points.iter().enumerate() {
            if k == 0 {
                pb.move_to(x, y);
            } else {
                pb.line_to(x, y);
            }
        }
        let Some(path) = pb.finish() else { return };
        let stroke = Stroke {
            width,
            line_join: tiny_skia::LineJoin::Round,
            dash: if dashed {
                StrokeDash::new(vec![6.0, 4.0], 0.0)
            } else {
                None
            },
            ..Stroke::default()
        };
        self.pixmap
            .stroke_path(&path, &paint(colour), &stroke, Transform::identity(), None);
    }

    fn rect(&mut self, x: f32, y: f32, w: f32, h: f32, fill: Rgb) {
        if let Some(r) = Rect::from_xywh(x, y, w, h) {
            self.pixmap
                .fill_rect(r, &paint(fill), Transform::identity(), None);
        }
    }

    fn marker(&mut self, x: f32, y: f32, radius: f32, colour: Rgb, filled: bool) {
        let Some(path) = PathBuilder::from_circle(x, y, radius) else {
            return;
        };
        let p = paint(colour);
        if filled {
            self.pixmap
                .fill_path(&path, &p, FillRule::Winding, Transform::identity(), None);
        } else {
            let s = Stroke {
                width: 1.5,
                ..Stroke::default()
            };
            self.pixmap
                .stroke_path(&path, &p, &s, Transform::identity(), None);
        }
    }

    fn text(
        &mut self,
        x: f32,
        y: f32,
        text: &str,
        size: f32,
        anchor: Anchor,
        vertical: bool,
        colour: Rgb,
    ) {
        let width = self.text_width(text, size);
        let start = match anchor {
            Anchor::Start => 0.0,
            Anchor::Middle => -0.5 * width,
            Anchor::End => -width,
        };
        let font = self.font.clone();
        let scaled = font.as_scaled(PxScale::from(size));
        // Lay out along u (the text's direction) from 0 on a baseline v = 0, then place: horizontal
        // text at (x + u, y + v), vertical text (reading upwards) at (x + v, y − u).
        let mut caret = start;
        let mut prev = None;
        let mut coverage: Vec<(i32, i32, f32)> = Vec::new();
        for c in text.chars() {
            let id = scaled.glyph_id(c);
            if let Some(p) = prev {
                caret += scaled.kern(p, id);
            }
            let glyph = id.with_scale_and_position(PxScale::from(size), point(caret, 0.0));
            caret += scaled.h_advance(id);
            prev = Some(id);
            let Some(outline) = font.outline_glyph(glyph) else {
                continue;
            };
            let b = outline.px_bounds();
            outline.draw(|gx, gy, cov| {
                coverage.push((b.min.x as i32 + gx as i32, b.min.y as i32 + gy as i32, cov));
            });
        }
        let (x0, y0) = (x.round() as i32, y.round() as i32);
        for (u, v, cov) in coverage {
            let (px, py) = if vertical {
                (x0 + v, y0 - u)
            } else {
                (x0 + u, y0 + v)
            };
            self.blend(px, py, colour, cov);
        }
    }
}
