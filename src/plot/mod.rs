//! Plots for reports (`compare`'s error against time, histograms, series over a path), written
//! as SVG and PNG from one description, so the two always agree.
//!
//! Rules: the [`plotters`] crate draws the charts. A [`chart::Figure`] is drawn by one function,
//! generic over plotters' backend, once into its SVG backend and once into its bitmap backend
//! (RGB), so the SVG and the PNG carry the same marks. Text is measured, and in the PNG
//! rasterised, from the bundled DejaVu Sans (`assets/fonts`), registered with plotters' `ab_glyph`
//! feature as its `sans-serif` family: no fontconfig, FreeType or system font is read, so a PNG
//! looks the same on a machine with no fonts installed (CI); the SVG names `sans-serif` and leaves
//! the face to its viewer. Text written on rendered frames (the image strip's labels, `view`'s
//! figures) goes through the same bitmap backend, by [`draw_on_rgba`].
//!
//! What stays ours: the axis ranges and the 1-2-5 ticks (given to plotters as an axis's key
//! points, its mapping plotters' own, `log_scale` for log axes), the legend shared by the panels
//! (plotters' legends are per chart), the Pareto staircase's corners, and where the PNG's glyphs
//! go ([`bitmap`]): plotters' `ab_glyph` text drops each glyph's side bearing and the pen's
//! fractions of a pixel, measured as glyphs up to 2 px off their place at the charts' 11 to 13 px
//! ("Im age err or"), so [`bitmap::Bitmap`] wraps plotters' bitmap backend and sets text itself
//! with ab_glyph, everything else passed through.

pub mod axis;
pub mod bitmap;
pub mod chart;

use plotters::coord::Shift;
use plotters::prelude::{
    BitMapBackend, DrawResult, DrawingArea, DrawingAreaErrorKind, IntoDrawingArea,
};
use plotters::style::{FontStyle, IntoFont, RGBColor, TextStyle, register_font};
use std::sync::OnceLock;
use terrain_engine::{Error, Result};

static DEJAVU_SANS: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");

/// The family every text is set in; the bundled font is registered under it.
pub const FAMILY: &str = "sans-serif";

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rgb(pub u8, pub u8, pub u8);

impl Rgb {
    pub const BLACK: Rgb = Rgb(0, 0, 0);
    pub const GREY: Rgb = Rgb(150, 150, 150);
    pub const LIGHT: Rgb = Rgb(225, 225, 225);
    pub const WHITE: Rgb = Rgb(255, 255, 255);
}

impl From<Rgb> for RGBColor {
    fn from(c: Rgb) -> RGBColor {
        RGBColor(c.0, c.1, c.2)
    }
}

/// Registers the bundled font with plotters, once; every drawing calls this first.
pub fn fonts() -> Result<()> {
    static REGISTERED: OnceLock<bool> = OnceLock::new();
    if *REGISTERED.get_or_init(|| register_font(FAMILY, FontStyle::Normal, DEJAVU_SANS).is_ok()) {
        Ok(())
    } else {
        Err(Error::Internal(
            "the bundled font (DejaVu Sans) did not load",
        ))
    }
}

/// Text of `size` pixels in `colour`, anchored at its top left (set the anchor with `.pos`).
pub fn font(size: f64, colour: Rgb) -> TextStyle<'static> {
    (FAMILY, size).into_font().color(&RGBColor::from(colour))
}

/// A plotters drawing failed (it draws into memory: only a font can be missing).
pub fn drawing_error<E: std::error::Error + Send + Sync + 'static>(
    e: DrawingAreaErrorKind<E>,
) -> Error {
    Error::encode("figure", e)
}

/// The drawing area over opaque RGBA8 pixels (a rendered frame, a strip), for `draw` to write
/// on. Plotters' bitmap backend takes RGB, so the pixels go through an RGB copy and come back
/// opaque.
pub fn draw_on_rgba(
    rgba: &mut [u8],
    width: u32,
    height: u32,
    draw: impl FnOnce(&DrawingArea<bitmap::Bitmap<'_>, Shift>) -> DrawResult<(), BitMapBackend<'static>>,
) -> Result<()> {
    fonts()?;
    let n = width as usize * height as usize;
    if rgba.len() != 4 * n {
        return Err(Error::Internal("pixels of another size than the image"));
    }
    let mut rgb = vec![0u8; 3 * n];
    for (out, p) in rgb.chunks_exact_mut(3).zip(rgba.chunks_exact(4)) {
        out.copy_from_slice(&p[..3]);
    }
    {
        let area = bitmap::Bitmap::new(&mut rgb, width, height)
            .ok_or(Error::Internal(
                "the bundled font (DejaVu Sans) did not load",
            ))?
            .into_drawing_area();
        draw(&area).map_err(drawing_error)?;
        area.present().map_err(drawing_error)?;
    }
    for (out, p) in rgba.chunks_exact_mut(4).zip(rgb.chunks_exact(3)) {
        out.copy_from_slice(&[p[0], p[1], p[2], 255]);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use plotters::style::text_anchor::{HPos, Pos, VPos};

    #[test]
    fn text_is_written_on_a_frame_which_stays_opaque() {
        let (w, h) = (200, 60);
        let mut frame = [0u8, 0, 0, 255].repeat(w * h);
        draw_on_rgba(&mut frame, w as u32, h as u32, |area| {
            let style = font(14.0, Rgb::WHITE).pos(Pos::new(HPos::Center, VPos::Top));
            area.draw_text("Hello, terrain", &style, (100, 20))
        })
        .unwrap();
        assert!(frame.chunks(4).all(|p| p[3] == 255), "alpha changed");
        let lit = |x0: usize, x1: usize, y0: usize, y1: usize| {
            (y0..y1)
                .flat_map(|y| (x0..x1).map(move |x| (x, y)))
                .filter(|&(x, y)| frame[4 * (y * w + x)] > 128)
                .count()
        };
        // The text, centred on x = 100 under y = 20, about 100 px wide and 14 high.
        assert!(lit(40, 160, 18, 40) > 100, "no text");
        assert_eq!(lit(0, 40, 0, h) + lit(160, w, 0, h), 0, "text not centred");
        assert_eq!(
            lit(0, w, 0, 17) + lit(0, w, 40, h),
            0,
            "text not under its top"
        );
        // A frame of the wrong size is refused, not drawn past.
        assert!(draw_on_rgba(&mut frame, 10, 10, |_| Ok(())).is_err());
    }
}
