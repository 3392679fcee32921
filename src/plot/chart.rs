//! Charts: panels side by side, each with x and y axes (linear or log10) and series drawn as
//! lines, markers or bars, a shared legend under the title; drawn by plotters (see the module
//! above) into an SVG and a PNG from one function.
//!
//! Rules: an axis's range is the data's, padded by 5 % (log axes in decades), unless given; ticks
//! are 1-2-5 steps (log axes: 1, 2, 5 × 10^k, or decades when they span more than 3); points
//! outside an axis's range, and non-finite ones, are left out rather than clamped to its edge.
//!
//! Over 400 lines for its tests (about 160: the SVG's texts and marks and the PNG's pixels held
//! against the figure they draw); the drawing itself is under 300.

pub use super::axis::{Axis, Scale};
use super::axis::{Frame, range};
use super::{Rgb, draw_on_rgba, drawing_error, font, fonts};
use crate::output::{write_atomic, write_image};
use plotters::coord::Shift;
use plotters::element::DashedPathElement;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use std::iter::once;
use std::path::Path;
use terrain_engine::{Error, Result};

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

/// The left margin of a panel (tick labels and the y axis's label), its right margin, the band
/// under it (tick labels and the x axis's label), and the band over the panels (title, legend).
const MARGIN_L: u32 = 70;
const MARGIN_R: u32 = 20;
const BOTTOM: u32 = 50;
const HEAD: u32 = 58;

impl Figure {
    /// Draws the figure on `root`, a drawing area of `width` × `height` pixels.
    pub fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult<(), DB> {
        root.fill(&WHITE)?;
        let (head, body) = root.split_vertically(HEAD);
        head.draw_text(
            &self.title,
            &font(16.0, Rgb::BLACK).pos(Pos::new(HPos::Center, VPos::Top)),
            (self.width as i32 / 2, 8),
        )?;
        self.legend(&head)?;
        let panels = body.split_evenly((1, self.panels.len().max(1)));
        for (p, area) in self.panels.iter().zip(&panels) {
            draw_panel(area, p)?;
        }
        Ok(())
    }

    /// One entry per distinct series name, in order of first appearance, centred in a row.
    fn legend<DB: DrawingBackend>(&self, head: &DrawingArea<DB, Shift>) -> DrawResult<(), DB> {
        let mut seen: Vec<(&str, Rgb, Style)> = Vec::new();
        for s in self.panels.iter().flat_map(|p| &p.series) {
            if !seen.iter().any(|(n, _, _)| *n == s.name) {
                seen.push((&s.name, s.colour, s.style));
            }
        }
        let text = font(12.0, Rgb::BLACK).pos(Pos::new(HPos::Left, VPos::Center));
        let mut widths = Vec::with_capacity(seen.len());
        for (name, _, _) in &seen {
            widths.push(28 + head.estimate_text_size(name, &text)?.0 as i32 + 30);
        }
        let mut x = (self.width as i32 - widths.iter().sum::<i32>()).max(0) / 2;
        let y = 42;
        for ((name, colour, style), w) in seen.into_iter().zip(widths) {
            let c = RGBColor::from(colour);
            match style {
                Style::Bars(_) => {
                    head.draw(&Rectangle::new([(x, y - 5), (x + 18, y + 5)], c.filled()))?
                }
                Style::Front => {
                    head.draw(&DashedPathElement::new(
                        [(x, y), (x + 22, y)],
                        6,
                        4,
                        c.stroke_width(1),
                    ))?;
                    head.draw(&Circle::new((x + 11, y), 5, c.stroke_width(2)))?;
                }
                Style::Line | Style::LineMarkers => {
                    head.draw(&PathElement::new([(x, y), (x + 22, y)], c.stroke_width(2)))?;
                    if style == Style::LineMarkers {
                        head.draw(&Circle::new((x + 11, y), 3.5, c.filled()))?;
                    }
                }
            }
            head.draw_text(name, &text, (x + 28, y))?;
            x += w;
        }
        Ok(())
    }

    fn check_size(&self) -> Result<()> {
        if self.width == 0 || self.height == 0 {
            return Err(Error::Internal("a figure of zero size"));
        }
        fonts()
    }

    /// The figure as an SVG document.
    pub fn svg(&self) -> Result<String> {
        self.check_size()?;
        let mut svg = String::new();
        {
            let root =
                SVGBackend::with_string(&mut svg, (self.width, self.height)).into_drawing_area();
            self.draw(&root).map_err(drawing_error)?;
            root.present().map_err(drawing_error)?;
        }
        Ok(svg)
    }

    /// RGBA8 pixels (opaque).
    pub fn png_rgba(&self) -> Result<Vec<u8>> {
        self.check_size()?;
        let mut px = vec![255u8; 4 * self.width as usize * self.height as usize];
        draw_on_rgba(&mut px, self.width, self.height, |root| self.draw(root))?;
        Ok(px)
    }

    /// Writes `<stem>.svg` and `<stem>.png` atomically.
    pub fn write(&self, stem: &Path) -> Result<()> {
        write_atomic(&stem.with_extension("svg"), self.svg()?.as_bytes())?;
        write_image(
            &stem.with_extension("png"),
            self.width,
            self.height,
            &self.png_rgba()?,
        )
    }
}

/// A panel's axes as drawn: ranges fitted to its series (bars' full widths, guides included).
fn frames(p: &Panel) -> (Frame, Frame) {
    let bars = p.series.iter().any(|s| matches!(s.style, Style::Bars(_)));
    let xs = p.series.iter().flat_map(|s| {
        let half = if let Style::Bars(w) = s.style {
            0.5 * w
        } else {
            0.0
        };
        s.points.iter().flat_map(move |q| [q.0 - half, q.0 + half])
    });
    let x = Frame::new(&p.x, range(&p.x, xs, false));
    let ys = p
        .series
        .iter()
        .flat_map(|s| s.points.iter().map(|q| q.1))
        .chain(p.guides.iter().map(|g| g.0));
    let y = Frame::new(&p.y, range(&p.y, ys, bars));
    (x, y)
}

fn draw_panel<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, p: &Panel) -> DrawResult<(), DB> {
    let (xf, yf) = frames(p);
    let mut chart = ChartBuilder::on(area)
        .caption(&p.title, font(13.0, Rgb::BLACK))
        .margin_top(4)
        .margin_left(4)
        .margin_right(MARGIN_R)
        .x_label_area_size(BOTTOM)
        .y_label_area_size(MARGIN_L)
        .build_cartesian_2d(xf.clone(), yf.clone())?;
    let (xl, yl) = (|v: &f64| xf.label(*v), |v: &f64| yf.label(*v));
    chart
        .configure_mesh()
        .bold_line_style(RGBColor::from(Rgb::LIGHT))
        .light_line_style(TRANSPARENT)
        .axis_style(BLACK)
        .label_style(font(11.0, Rgb::BLACK))
        .axis_desc_style(font(12.0, Rgb::BLACK))
        .x_desc(&p.x.label)
        .y_desc(&p.y.label)
        .x_label_formatter(&xl)
        .y_label_formatter(&yl)
        .draw()?;
    let grey = RGBColor::from(Rgb::GREY);
    for (v, label) in &p.guides {
        if !yf.inside(*v) {
            continue;
        }
        chart.draw_series(once(DashedPathElement::new(
            [(xf.lo, *v), (xf.hi, *v)],
            6,
            4,
            grey.stroke_width(1),
        )))?;
        chart.draw_series(once(
            EmptyElement::at((xf.hi, *v))
                + Text::new(
                    label.clone(),
                    (-4, -3),
                    font(10.0, Rgb::GREY).pos(Pos::new(HPos::Right, VPos::Bottom)),
                ),
        ))?;
    }
    for s in &p.series {
        let c = RGBColor::from(s.colour);
        let pts: Vec<(f64, f64)> = s
            .points
            .iter()
            .copied()
            .filter(|&(px, py)| xf.inside(px) && yf.inside(py))
            .collect();
        match s.style {
            Style::Bars(w) => {
                let bars = pts
                    .iter()
                    .filter(|(px, _)| xf.inside(px - 0.5 * w) && xf.inside(px + 0.5 * w))
                    .map(|&(px, py)| {
                        let mut r =
                            Rectangle::new([(px - 0.5 * w, yf.lo), (px + 0.5 * w, py)], c.filled());
                        r.set_margin(0, 0, 1, 1);
                        r
                    });
                chart.draw_series(bars)?;
            }
            Style::Line => {
                chart.draw_series(LineSeries::new(pts, c.stroke_width(2)))?;
            }
            Style::LineMarkers => {
                chart.draw_series(LineSeries::new(pts.iter().copied(), c.stroke_width(2)))?;
                chart.draw_series(pts.iter().map(|&q| Circle::new(q, 3.5, c.filled())))?;
            }
            Style::Front => {
                chart.draw_series(once(DashedPathElement::new(
                    staircase(&pts),
                    6,
                    4,
                    c.stroke_width(1),
                )))?;
                chart.draw_series(pts.iter().map(|&q| Circle::new(q, 6, c.stroke_width(2))))?;
            }
        }
    }
    Ok(())
}

/// A front through points in order of x as a staircase: each point's value holds until the
/// next point (what is attainable at a given cost), then steps.
fn staircase(pts: &[(f64, f64)]) -> Vec<(f64, f64)> {
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
    fn a_front_steps_at_each_point() {
        let s = staircase(&[(0.0, 5.0), (2.0, 3.0), (4.0, 1.0)]);
        assert_eq!(
            s,
            vec![(0.0, 5.0), (2.0, 5.0), (2.0, 3.0), (4.0, 3.0), (4.0, 1.0)]
        );
    }

    fn figure() -> Figure {
        Figure {
            title: "Error against frame time".into(),
            width: 800,
            height: 400,
            panels: vec![
                Panel {
                    title: "Image error".into(),
                    x: Axis::new("frame time (ms)", Scale::Log10),
                    y: Axis::new("PSNR (dB)", Scale::Linear),
                    series: vec![
                        Series {
                            name: "warped".into(),
                            colour: Rgb(230, 120, 20),
                            style: Style::LineMarkers,
                            points: vec![(10.0, 20.0), (f64::NAN, 25.0), (100.0, 30.0)],
                        },
                        Series {
                            name: "Pareto front".into(),
                            colour: Rgb(40, 100, 200),
                            style: Style::Front,
                            points: vec![(10.0, 20.0), (40.0, 26.0), (100.0, 30.0)],
                        },
                    ],
                    guides: vec![(30.0, "30 dB".into())],
                },
                Panel {
                    title: "Histogram".into(),
                    x: Axis::new("log2 of the ratio", Scale::Linear),
                    y: Axis::new("cells (%)", Scale::Linear),
                    series: vec![Series {
                        name: "geometry image".into(),
                        colour: Rgb(40, 160, 70),
                        style: Style::Bars(0.5),
                        points: vec![(-0.25, 10.0), (0.25, 40.0), (0.75, 20.0)],
                    }],
                    guides: vec![],
                },
            ],
        }
    }

    /// The SVG's texts as (x, y, text).
    fn texts(svg: &str) -> Vec<(f64, f64, String)> {
        svg.split("<text")
            .skip(1)
            .map(|t| {
                let attr = |k: &str| -> f64 {
                    let at = t.find(&format!(" {k}=\"")).unwrap() + k.len() + 3;
                    t[at..at + t[at..].find('"').unwrap()].parse().unwrap()
                };
                let body = &t[t.find('>').unwrap() + 1..t.find("</text>").unwrap()];
                (attr("x"), attr("y"), body.trim().to_string())
            })
            .collect()
    }

    #[test]
    fn svg_and_png_carry_the_same_figure() {
        let fig = figure();
        let svg = fig.svg().unwrap();
        assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
        assert!(
            svg.contains("frame time (ms)") && svg.contains("warped") && svg.contains("#E67814")
        );
        let png = fig.png_rgba().unwrap();
        assert_eq!(png.len(), 4 * 800 * 400);
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

    #[test]
    fn charts_carry_their_labels_legend_and_log_ticks() {
        let fig = figure();
        let svg = fig.svg().unwrap();
        let t = texts(&svg);
        let has = |s: &str| t.iter().any(|x| x.2 == s);
        for s in [
            "Error against frame time",
            "Image error",
            "Histogram",
            "frame time (ms)",
            "PSNR (dB)",
            "log2 of the ratio",
            "cells (%)",
            "30 dB",
            "warped",
            "Pareto front",
            "geometry image",
        ] {
            assert!(has(s), "the SVG lacks {s:?}: {t:?}");
        }
        // Each legend name once, under the title, in order of first appearance.
        let legend: Vec<&(f64, f64, String)> = t
            .iter()
            .filter(|x| ["warped", "Pareto front", "geometry image"].contains(&x.2.as_str()))
            .collect();
        assert_eq!(legend.len(), 3, "{legend:?}");
        assert!(
            legend
                .windows(2)
                .all(|w| w[0].0 < w[1].0 && w[0].1 == w[1].1)
        );
        assert!(legend[0].1 < HEAD as f64);
        // The log axis: ticks 10, 20, 50, 100 at log10 spacing, left to right.
        let row = t.iter().find(|x| x.2 == "100").unwrap().1;
        let x_of = |s: &str| t.iter().find(|x| x.2 == s && x.1 == row).unwrap().0;
        let (a, b, c) = (x_of("10"), x_of("20"), x_of("100"));
        let frac = (b - a) / (c - a);
        assert!(
            (frac - 2f64.log10()).abs() < 0.02,
            "20 sits at {frac} of 10..100"
        );
        // The y axis's label reads upwards.
        assert!(svg.contains("rotate(270"), "no vertical label");
        // The front is a dashed staircase: many short strokes of its blue.
        let front = svg.matches("stroke=\"#2864C8\"").count();
        assert!(front > 10, "{front} strokes of the front");

        // The PNG: the title's text in the band over the panels, dark pixels around its centre.
        let png = fig.png_rgba().unwrap();
        let dark = |x0: usize, x1: usize, y0: usize, y1: usize| {
            (y0..y1)
                .flat_map(|y| (x0..x1).map(move |x| (x, y)))
                .filter(|&(x, y)| png[4 * (y * 800 + x)] < 80)
                .count()
        };
        assert!(dark(250, 550, 0, 30) > 150, "no title");
        assert_eq!(dark(0, 200, 0, 30), 0, "title not centred");
        // The y axis's label: dark pixels in the left margin, around the panel's middle.
        assert!(dark(0, 30, 100, 350) > 40, "no y label");
        assert_eq!(
            dark(0, 30, 0, 100) + dark(0, 30, 350, 400),
            0,
            "y label off centre"
        );
    }
}
