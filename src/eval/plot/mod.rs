//! Plots for reports (`compare`'s error against time, histograms, series over a path), written
//! as SVG and PNG from one description, so the two always agree.
//!
//! Rules: a [`chart::Figure`] is drawn through the [`Canvas`] trait, once into an SVG document
//! ([`svg::SvgCanvas`]) and once into a tiny-skia pixmap ([`raster::RasterCanvas`]) whose text is
//! rasterised from the bundled DejaVu Sans (`assets/fonts`), so a PNG looks the same on a machine
//! with no fonts installed.
//!
//! Rejected alternative: a plotting crate (plotters). Its PNG text goes through the system's
//! font stack (fontconfig and FreeType), which a headless CI machine may lack, and our charts
//! need three primitives and a log axis.

pub mod chart;
pub mod raster;
pub mod svg;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rgb(pub u8, pub u8, pub u8);

impl Rgb {
    pub const BLACK: Rgb = Rgb(0, 0, 0);
    pub const GREY: Rgb = Rgb(150, 150, 150);
    pub const LIGHT: Rgb = Rgb(225, 225, 225);
    pub const WHITE: Rgb = Rgb(255, 255, 255);

    pub fn hex(self) -> String {
        format!("#{:02x}{:02x}{:02x}", self.0, self.1, self.2)
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Anchor {
    Start,
    Middle,
    End,
}

/// What a figure is drawn with; coordinates in pixels, y down.
pub trait Canvas {
    fn polyline(&mut self, points: &[(f32, f32)], colour: Rgb, width: f32, dashed: bool);
    fn rect(&mut self, x: f32, y: f32, w: f32, h: f32, fill: Rgb);
    fn marker(&mut self, x: f32, y: f32, radius: f32, colour: Rgb, filled: bool);
    /// `y` is the baseline; `vertical` text reads upwards, its baseline at x.
    #[allow(clippy::too_many_arguments)]
    fn text(
        &mut self,
        x: f32,
        y: f32,
        text: &str,
        size: f32,
        anchor: Anchor,
        vertical: bool,
        colour: Rgb,
    );
}
