//! Charts: panels side by side, each with x and y axes (linear or log10) and series drawn as
//! lines, markers or bars, a shared legend under the title.
//!
//! Rules: an axis's range is the data's, padded by 5 % (log axes in decades), unless given; ticks
//! are 1-2-5 steps (log axes: 1, 2, 5 × 10^k, or decades when they span more than 3); points
//! outside an axis's range, and non-finite ones, are left out rather than clamped to its edge.

use super::raster::RasterCanvas;
use super::svg::SvgCanvas;
use super::{Anchor, Canvas, Rgb};
use crate::app::output::{write_atomic, write_image};
use crate::error::{Error, Result};
use std::path::Path;

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Scale {
    Linear,
    Log10,
}

#[derive(Clone, Debug)]
pub struct Axis {
    pub label: String,
    pub scale: Scale,
    /// Fixed range; `None` fits the data.
    pub range: Option<(f64, f64)>,
}

impl Axis {
    pub fn new(label: &str, scale: Scale) -> Axis {
        Axis {
            label: label.to_string(),
            scale,
            range: None,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Style {
    /// A line through the points with a filled marker on each.
    LineMarkers,
    /// A dashed staircase with a ring on each point (a Pareto front, in order of x).
    Front,
    Line,
    /// Bars from the axis's bottom, `width` in x units, centred on each point's x.
    Bars(f64),
}

#[derive(Clone, Debug)]
pub struct Series {
    pub name: String,
    pub colour: Rgb,
    pub style: Style,
    pub points: Vec<(f64, f64)>,
}

#[derive(Clone, Debug)]
pub struct Panel {
    pub title: String,
    pub x: Axis,
    pub y: Axis,
    pub series: Vec<Series>,
    /// Horizontal guides (y value, label), e.g. a target error.
    pub guides: Vec<(f64, String)>,
}

#[derive(Clone, Debug)]
pub struct Figure {
    pub title: String,
    pub panels: Vec<Panel>,
    pub width: u32,
    pub height: u32,
}

const MARGIN_L: f32 = 70.0;
const MARGIN_R: f32 = 20.0;
const TOP: f32 = 78.0;
const BOTTOM: f32 = 56.0;

struct Map {
    lo: f64,
    hi: f64,
    log: bool,
    a: f32,
    b: f32,
}

impl Map {
    fn t(&self, v: f64) -> f64 {
        if self.log { v.log10() } else { v }
    }
    fn px(&self, v: f64) -> Option<f32> {
        if !v.is_finite() || (self.log && v <= 0.0) {
            return None;
        }
        let (lo, hi, t) = (self.t(self.lo), self.t(self.hi), self.t(v));
        if t < lo - 1e-9 * (hi - lo).abs() || t > hi + 1e-9 * (hi - lo).abs() {
            return None;
        }
        Some(self.a + (self.b - self.a) * ((t - lo) / (hi - lo)) as f32)
    }
}

fn range(axis: &Axis, values: impl Iterator<Item = f64>, bars_from_zero: bool) -> (f64, f64) {
    if let Some(r) = axis.range {
        return r;
    }
    let log = axis.scale == Scale::Log10;
    let vals: Vec<f64> = values
        .filter(|v| v.is_finite() && (!log || *v > 0.0))
        .collect();
    let (mut lo, mut hi) = vals
        .iter()
        .fold((f64::MAX, f64::MIN), |(a, b), &v| (a.min(v), b.max(v)));
    if vals.is_empty() {
        return if log { (1.0, 10.0) } else { (0.0, 1.0) };
    }
    if log {
        lo = 10f64.powf(lo.log10().floor());
        hi = 10f64.powf(hi.log10().ceil());
        if hi <= lo {
            hi = lo * 10.0;
        }
        return (lo, hi);
    }
    if bars_from_zero {
        lo = lo.min(0.0);
    }
    let pad = if hi > lo {
        0.05 * (hi - lo)
    } else {
        0.5 * hi.abs().max(1.0)
    };
    (
        if bars_from_zero && lo == 0.0 {
            0.0
        } else {
            lo - pad
        },
        hi + pad,
    )
}

/// Tick values of an axis and their labels (a linear axis's with the step's decimals).
fn labelled_ticks(lo: f64, hi: f64, scale: Scale) -> Vec<(f64, String)> {
    let t = ticks(lo, hi, scale);
    match (scale, t.as_slice()) {
        (Scale::Linear, [a, b, ..]) => {
            let decimals = (-(b - a).log10()).ceil().max(0.0) as usize;
            t.iter().map(|v| (*v, format!("{v:.decimals$}"))).collect()
        }
        _ => t.iter().map(|v| (*v, number(*v))).collect(),
    }
}

/// Tick values of an axis.
fn ticks(lo: f64, hi: f64, scale: Scale) -> Vec<f64> {
    match scale {
        Scale::Log10 => {
            let (a, b) = (lo.log10().floor() as i32, hi.log10().ceil() as i32);
            let steps: &[f64] = if b - a > 3 { &[1.0] } else { &[1.0, 2.0, 5.0] };
            (a..=b)
                .flat_map(|e| steps.iter().map(move |m| m * 10f64.powi(e)))
                .filter(|v| *v >= lo * 0.999 && *v <= hi * 1.001)
                .collect()
        }
        Scale::Linear => {
            let raw = (hi - lo) / 6.0;
            let mag = 10f64.powf(raw.log10().floor());
            let step = [1.0, 2.0, 5.0, 10.0]
                .iter()
                .map(|m| m * mag)
                .find(|s| *s >= raw)
                .unwrap_or(10.0 * mag);
            let first = (lo / step - 1e-9).ceil() as i64;
            let last = (hi / step + 1e-9).floor() as i64;
            (first..=last).map(|k| k as f64 * step).collect()
        }
    }
}

/// A tick label: short and without float noise.
pub fn number(v: f64) -> String {
    let a = v.abs();
    if a == 0.0 {
        "0".into()
    } else if !(1e-3..1e5).contains(&a) {
        format!("{v:.0e}")
    } else if a >= 10.0 || (v - v.round()).abs() < 1e-9 {
        format!("{v:.0}")
    } else if a >= 1.0 {
        format!("{v:.1}")
    } else {
        let digits = (-a.log10()).ceil() as usize;
        format!("{v:.digits$}")
    }
}

impl Figure {
    pub fn draw(&self, c: &mut dyn Canvas) {
        c.text(
            self.width as f32 / 2.0,
            24.0,
            &self.title,
            16.0,
            Anchor::Middle,
            false,
            Rgb::BLACK,
        );
        self.legend(c);
        let n = self.panels.len().max(1) as f32;
        let w = self.width as f32 / n;
        for (k, p) in self.panels.iter().enumerate() {
            draw_panel(c, p, k as f32 * w, w, self.height as f32);
        }
    }

    /// One entry per distinct series name, in order of first appearance.
    fn legend(&self, c: &mut dyn Canvas) {
        let mut seen: Vec<(&str, Rgb, Style)> = Vec::new();
        for s in self.panels.iter().flat_map(|p| &p.series) {
            if !seen.iter().any(|(n, _, _)| *n == s.name) {
                seen.push((&s.name, s.colour, s.style));
            }
        }
        let entry_w = 170.0;
        let total = entry_w * seen.len() as f32;
        let mut x = (self.width as f32 - total).max(0.0) / 2.0;
        let y = 50.0;
        for (name, colour, style) in seen {
            match style {
                Style::Bars(_) => c.rect(x, y - 8.0, 18.0, 10.0, colour),
                _ => {
                    c.polyline(
                        &[(x, y - 4.0), (x + 22.0, y - 4.0)],
                        colour,
                        2.0,
                        style == Style::Front,
                    );
                    c.marker(x + 11.0, y - 4.0, 3.5, colour, style != Style::Front);
                }
            }
            c.text(x + 28.0, y, name, 12.0, Anchor::Start, false, Rgb::BLACK);
            x += entry_w;
        }
    }

    pub fn svg(&self) -> String {
        let mut svg = SvgCanvas::new(self.width, self.height);
        self.draw(&mut svg);
        svg.finish()
    }

    /// RGBA8 pixels.
    pub fn png_rgba(&self) -> Result<Vec<u8>> {
        let mut r = RasterCanvas::new(self.width, self.height)
            .ok_or_else(|| Error::Internal("a figure of zero size"))?;
        self.draw(&mut r);
        Ok(r.pixmap.data().to_vec())
    }

    /// Writes `<stem>.svg` and `<stem>.png` atomically.
    pub fn write(&self, stem: &Path) -> Result<()> {
        write_atomic(&stem.with_extension("svg"), self.svg().as_bytes())?;
        write_image(
            &stem.with_extension("png"),
            self.width,
            self.height,
            &self.png_rgba()?,
        )
    }
}

fn draw_panel(c: &mut dyn Canvas, p: &Panel, left: f32, width: f32, height: f32) {
    let bars = p.series.iter().any(|s| matches!(s.style, Style::Bars(_)));
    let xs = p.series.iter().flat_map(|s| {
        let half = if let Style::Bars(w) = s.style {
            0.5 * w
        } else {
            0.0
        };
        s.points.iter().flat_map(move |q| [q.0 - half, q.0 + half])
    });
    let (xlo, xhi) = range(&p.x, xs, false);
    let ys = p
        .series
        .iter()
        .flat_map(|s| s.points.iter().map(|q| q.1))
        .chain(p.guides.iter().map(|g| g.0));
    let (ylo, yhi) = range(&p.y, ys, bars);
    let (x0, x1) = (left + MARGIN_L, left + width - MARGIN_R);
    let (y0, y1) = (height - BOTTOM, TOP);
    let xm = Map {
        lo: xlo,
        hi: xhi,
        log: p.x.scale == Scale::Log10,
        a: x0,
        b: x1,
    };
    let ym = Map {
        lo: ylo,
        hi: yhi,
        log: p.y.scale == Scale::Log10,
        a: y0,
        b: y1,
    };
    for (t, label) in labelled_ticks(xlo, xhi, p.x.scale) {
        if let Some(x) = xm.px(t) {
            c.polyline(&[(x, y0), (x, y1)], Rgb::LIGHT, 1.0, false);
            c.text(
                x,
                y0 + 16.0,
                &label,
                11.0,
                Anchor::Middle,
                false,
                Rgb::BLACK,
            );
        }
    }
    for (t, label) in labelled_ticks(ylo, yhi, p.y.scale) {
        if let Some(y) = ym.px(t) {
            c.polyline(&[(x0, y), (x1, y)], Rgb::LIGHT, 1.0, false);
            c.text(
                x0 - 6.0,
                y + 4.0,
                &label,
                11.0,
                Anchor::End,
                false,
                Rgb::BLACK,
            );
        }
    }
    c.polyline(&[(x0, y1), (x0, y0), (x1, y0)], Rgb::BLACK, 1.2, false);
    c.text(
        (x0 + x1) / 2.0,
        y1 - 8.0,
        &p.title,
        13.0,
        Anchor::Middle,
        false,
        Rgb::BLACK,
    );
    c.text(
        (x0 + x1) / 2.0,
        height - 14.0,
        &p.x.label,
        12.0,
        Anchor::Middle,
        false,
        Rgb::BLACK,
    );
    c.text(
        left + 18.0,
        (y0 + y1) / 2.0,
        &p.y.label,
        12.0,
        Anchor::Middle,
        true,
        Rgb::BLACK,
    );
    for (v, label) in &p.guides {
        if let Some(y) = ym.px(*v) {
            c.polyline(&[(x0, y), (x1, y)], Rgb::GREY, 1.0, true);
            c.text(
                x1 - 4.0,
                y - 4.0,
                label,
                10.0,
                Anchor::End,
                false,
                Rgb::GREY,
            );
        }
    }
    for s in &p.series {
        let pts: Vec<(f32, f32)> = s
            .points
            .iter()
            .filter_map(|&(x, y)| Some((xm.px(x)?, ym.px(y)?)))
            .collect();
        match s.style {
            Style::Bars(w) => {
                for &(x, y) in &s.points {
                    let (Some(a), Some(b), Some(top)) =
                        (xm.px(x - 0.5 * w), xm.px(x + 0.5 * w), ym.px(y))
                    else {
                        continue;
                    };
                    c.rect(a + 1.0, top, (b - a - 2.0).max(1.0), y0 - top, s.colour);
                }
            }
            Style::Line => c.polyline(&pts, s.colour, 2.0, false),
            Style::LineMarkers | Style::Front => {
                let front = s.style == Style::Front;
                if pts.len() > 1 {
                    let line = if front { staircase(&pts) } else { pts.clone() };
                    c.polyline(&line, s.colour, if front { 1.5 } else { 2.0 }, front);
                }
                for &(x, y) in &pts {
                    c.marker(x, y, if front { 6.5 } else { 3.5 }, s.colour, !front);
                }
            }
        }
    }
}

/// A front through points in order of x as a staircase: each point's value holds until the
/// next point (what is attainable at a given cost), then steps.
fn staircase(pts: &[(f32, f32)]) -> Vec<(f32, f32)> {
    let mut out = Vec::with_capacity(2 * pts.len());
    for (k, &p) in pts.iter().enumerate() {
        if k > 0 {
            out.push((p.0, pts[k - 1].1));
        }
        out.push(p);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_are_round_and_inside() {
        assert_eq!(
            ticks(0.0, 10.0, Scale::Linear),
            vec![0.0, 2.0, 4.0, 6.0, 8.0, 10.0]
        );
        assert_eq!(
            ticks(10.0, 100.0, Scale::Log10),
            vec![10.0, 20.0, 50.0, 100.0]
        );
        assert_eq!(ticks(0.01, 1000.0, Scale::Log10).len(), 6);
        assert_eq!(number(0.05), "0.05");
        let l: Vec<String> = labelled_ticks(0.0, 0.3, Scale::Linear)
            .into_iter()
            .map(|t| t.1)
            .collect();
        assert_eq!(l, ["0.00", "0.05", "0.10", "0.15", "0.20", "0.25", "0.30"]);
        assert_eq!(number(2.5), "2.5");
        assert_eq!(number(200.0), "200");
    }

    #[test]
    fn a_front_steps_at_each_point() {
        let s = staircase(&[(0.0, 5.0), (2.0, 3.0), (4.0, 1.0)]);
        assert_eq!(
            s,
            vec![(0.0, 5.0), (2.0, 5.0), (2.0, 3.0), (4.0, 3.0), (4.0, 1.0)]
        );
    }

    #[test]
    fn points_map_into_the_plot_and_outside_points_are_left_out() {
        let m = Map {
            lo: 1.0,
            hi: 100.0,
            log: true,
            a: 0.0,
            b: 200.0,
        };
        assert_eq!(m.px(10.0), Some(100.0));
        assert_eq!(m.px(0.0), None);
        assert_eq!(m.px(f64::NAN), None);
        assert_eq!(m.px(1000.0), None);
    }

    #[test]
    fn svg_and_png_carry_the_same_figure() {
        let fig = Figure {
            title: "t".into(),
            width: 400,
            height: 300,
            panels: vec![Panel {
                title: "p".into(),
                x: Axis::new("frame time (ms)", Scale::Log10),
                y: Axis::new("PSNR (dB)", Scale::Linear),
                series: vec![Series {
                    name: "warped".into(),
                    colour: Rgb(230, 120, 20),
                    style: Style::LineMarkers,
                    points: vec![(10.0, 20.0), (100.0, 30.0)],
                }],
                guides: vec![(30.0, "30 dB".into())],
            }],
        };
        let svg = fig.svg();
        assert!(
            svg.contains("frame time (ms)") && svg.contains("warped") && svg.contains("#e67814")
        );
        let png = fig.png_rgba().unwrap();
        // The series' orange is drawn, and text (dark pixels) is there.
        let orange = png
            .chunks(4)
            .filter(|p| p[0] > 200 && (100..140).contains(&p[1]) && p[2] < 60)
            .count();
        let dark = png
            .chunks(4)
            .filter(|p| p[0] < 60 && p[1] < 60 && p[2] < 60)
            .count();
        assert!(orange > 50 && dark > 200, "orange {orange}, dark {dark}");
    }
}
