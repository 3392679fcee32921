//! Axes: the range an axis shows and its labelled ticks (the rules in [`super::chart`]'s doc), and
//! [`Frame`], the axis as plotters draws it.

use plotters::coord::combinators::LogCoord;
use plotters::coord::ranged1d::{DefaultFormatting, KeyPointHint, Ranged};
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;

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

/// An axis as drawn: its range and its labelled ticks. To plotters it is an axis whose mapping
/// is plotters' own (linear, or its `log_scale`) and whose key points are our ticks.
#[derive(Clone)]
pub struct Frame {
    pub lo: f64,
    pub hi: f64,
    pub log: bool,
    pub ticks: Vec<(f64, String)>,
}

impl Frame {
    pub fn new(axis: &Axis, (lo, hi): (f64, f64)) -> Frame {
        Frame {
            lo,
            hi,
            log: axis.scale == Scale::Log10,
            ticks: labelled_ticks(lo, hi, axis.scale),
        }
    }

    fn t(&self, v: f64) -> f64 {
        if self.log { v.log10() } else { v }
    }

    /// Whether `v` is drawn: finite, positive on a log axis, and inside the range.
    pub fn inside(&self, v: f64) -> bool {
        if !v.is_finite() || (self.log && v <= 0.0) {
            return false;
        }
        let (lo, hi, t) = (self.t(self.lo), self.t(self.hi), self.t(v));
        let slack = 1e-9 * (hi - lo).abs();
        t >= lo - slack && t <= hi + slack
    }

    pub fn label(&self, v: f64) -> String {
        self.ticks
            .iter()
            .find(|t| t.0 == v)
            .map_or_else(|| number(v), |t| t.1.clone())
    }
}

impl Ranged for Frame {
    type FormatOption = DefaultFormatting;
    type ValueType = f64;

    fn map(&self, v: &f64, limit: (i32, i32)) -> i32 {
        if self.log {
            LogCoord::from((self.lo..self.hi).log_scale()).map(v, limit)
        } else {
            RangedCoordf64::from(self.lo..self.hi).map(v, limit)
        }
    }

    /// The ticks, drawn as the grid's lines; no lighter lines between them.
    fn key_points<H: KeyPointHint>(&self, hint: H) -> Vec<f64> {
        if hint.weight().allow_light_points() {
            Vec::new()
        } else {
            self.ticks.iter().map(|t| t.0).collect()
        }
    }

    fn range(&self) -> std::ops::Range<f64> {
        self.lo..self.hi
    }
}

pub fn range(axis: &Axis, values: impl Iterator<Item = f64>, bars_from_zero: bool) -> (f64, f64) {
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
    fn points_map_into_the_plot_and_outside_points_are_left_out() {
        let axis = Axis::new("x", Scale::Log10);
        let f = Frame::new(&axis, (1.0, 100.0));
        let m: plotters::coord::combinators::LogCoord<f64> = (1.0..100.0).log_scale().into();
        assert_eq!(m.map(&10.0, (0, 200)), 100);
        assert!(f.inside(10.0) && f.inside(1.0) && f.inside(100.0));
        assert!(!f.inside(0.0));
        assert!(!f.inside(f64::NAN));
        assert!(!f.inside(1000.0));
    }
}
