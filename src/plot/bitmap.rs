//! The PNG backend: plotters' bitmap backend (RGB), which draws every mark but text. Text is set
//! here, from the same font: plotters' `ab_glyph` text drops each glyph's side bearing and the
//! pen's fractions of a pixel. Measured on DejaVu Sans at the charts' 11 to 13 px, that puts
//! glyphs up to 2 px left of their place and makes gaps between neighbours up to 2 px wrong
//! ("Im age err or", "1 0"); here each glyph is rasterised where the font's advances and kerning
//! put it, anchored as plotters' SVG backend anchors text (so the PNG's text sits where the
//! SVG's does).

use ab_glyph::{Font, FontRef, ScaleFont, point};
use plotters::prelude::BitMapBackend;
use plotters::style::text_anchor::{HPos, VPos};
use plotters_backend::{
    BackendColor, BackendCoord, BackendStyle, BackendTextStyle, DrawingBackend, DrawingErrorKind,
};

type Drawn = Result<(), DrawingErrorKind<<BitMapBackend<'static> as DrawingBackend>::ErrorType>>;

pub struct Bitmap<'a> {
    inner: BitMapBackend<'a>,
    font: FontRef<'static>,
}

impl<'a> Bitmap<'a> {
    /// Over RGB8 pixels, `width` × `height`; `None` where the buffer is short or the font bad.
    pub fn new(rgb: &'a mut [u8], width: u32, height: u32) -> Option<Bitmap<'a>> {
        Some(Bitmap {
            inner: BitMapBackend::with_buffer_and_format(rgb, (width, height)).ok()?,
            font: FontRef::try_from_slice(super::DEJAVU_SANS).ok()?,
        })
    }
}

impl DrawingBackend for Bitmap<'_> {
    type ErrorType = <BitMapBackend<'static> as DrawingBackend>::ErrorType;

    fn get_size(&self) -> (u32, u32) {
        self.inner.get_size()
    }
    fn ensure_prepared(&mut self) -> Drawn {
        self.inner.ensure_prepared()
    }
    fn present(&mut self) -> Drawn {
        self.inner.present()
    }
    fn draw_pixel(&mut self, point: BackendCoord, colour: BackendColor) -> Drawn {
        self.inner.draw_pixel(point, colour)
    }
    fn draw_line<S: BackendStyle>(&mut self, from: BackendCoord, to: BackendCoord, s: &S) -> Drawn {
        self.inner.draw_line(from, to, s)
    }
    fn draw_rect<S: BackendStyle>(
        &mut self,
        upper_left: BackendCoord,
        bottom_right: BackendCoord,
        s: &S,
        fill: bool,
    ) -> Drawn {
        self.inner.draw_rect(upper_left, bottom_right, s, fill)
    }
    fn draw_path<S: BackendStyle, I: IntoIterator<Item = BackendCoord>>(
        &mut self,
        path: I,
        s: &S,
    ) -> Drawn {
        self.inner.draw_path(path, s)
    }
    fn draw_circle<S: BackendStyle>(
        &mut self,
        centre: BackendCoord,
        radius: u32,
        s: &S,
        fill: bool,
    ) -> Drawn {
        self.inner.draw_circle(centre, radius, s, fill)
    }
    fn fill_polygon<S: BackendStyle, I: IntoIterator<Item = BackendCoord>>(
        &mut self,
        vertices: I,
        s: &S,
    ) -> Drawn {
        self.inner.fill_polygon(vertices, s)
    }
    fn blit_bitmap(&mut self, pos: BackendCoord, size: (u32, u32), src: &[u8]) -> Drawn {
        self.inner.blit_bitmap(pos, size, src)
    }

    /// The style's size, anchor, rotation and colour; its family is always the bundled font.
    fn draw_text<S: BackendTextStyle>(
        &mut self,
        text: &str,
        style: &S,
        pos: BackendCoord,
    ) -> Drawn {
        let colour = style.color();
        if colour.alpha == 0.0 {
            return Ok(());
        }
        let size = style.size() as f32;
        let font = self.font.as_scaled(size);
        let ids: Vec<_> = text.chars().map(|c| font.glyph_id(c)).collect();
        let kern = |k: usize| {
            if k > 0 {
                font.kern(ids[k - 1], ids[k])
            } else {
                0.0
            }
        };
        let width: f32 = (0..ids.len())
            .map(|k| kern(k) + font.h_advance(ids[k]))
            .sum();
        let anchor = style.anchor();
        let mut pen = match anchor.h_pos {
            HPos::Left => 0.0,
            HPos::Center => -0.5 * width,
            HPos::Right => -width,
        };
        // The baseline where plotters' SVG backend puts it (dy of 0.76 em, ±0.5 ex), so the PNG's
        // text sits as the SVG's does; DejaVu Sans's x-height is 0.55 em.
        let em = font.height() * self.font.units_per_em().unwrap_or(2048.0)
            / self.font.height_unscaled();
        let baseline = em
            * match anchor.v_pos {
                VPos::Top => 0.76,
                VPos::Center => 0.5 * 0.55,
                VPos::Bottom => -0.5 * 0.55,
            };
        // Coverage in the text's own frame (x along it, y down), then turned and placed.
        let mut coverage: Vec<(i32, i32, f32)> = Vec::new();
        for (k, &id) in ids.iter().enumerate() {
            pen += kern(k);
            let glyph = id.with_scale_and_position(size, point(pen, baseline));
            pen += font.h_advance(id);
            if let Some(outline) = self.font.outline_glyph(glyph) {
                let b = outline.px_bounds();
                outline.draw(|x, y, c| {
                    coverage.push((b.min.x as i32 + x as i32, b.min.y as i32 + y as i32, c));
                });
            }
        }
        let turn = style.transform();
        let (w, h) = self.get_size();
        for (x, y, c) in coverage {
            let (x, y) = turn.transform(x, y);
            let (x, y) = (pos.0 + x, pos.1 + y);
            if x >= 0 && y >= 0 && x < w as i32 && y < h as i32 && c > 0.0 {
                let alpha = colour.alpha * f64::from(c.min(1.0));
                self.inner
                    .draw_pixel((x, y), BackendColor { alpha, ..colour })?;
            }
        }
        Ok(())
    }
}
