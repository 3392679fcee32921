//! Synthetic sketches for demos and tests, each a closed-form function of the node position so that
//! a test can state what the sketch is: gaussian mountain (the paper's Fig. 3), hills, ridges,
//! cliff (a 400 m step across the middle), flat, spike (one tall node on a plain).

use super::RawGrid;
use crate::error::{Error, Result};
use std::f64::consts::TAU;

pub const NAMES: [&str; 6] = ["gaussian", "hills", "ridges", "cliff", "flat", "spike"];

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    Gaussian,
    Hills,
    Ridges,
    Cliff,
    Flat,
    Spike,
}
const KINDS: [Kind; 6] = [
    Kind::Gaussian,
    Kind::Hills,
    Kind::Ridges,
    Kind::Cliff,
    Kind::Flat,
    Kind::Spike,
];
pub const DEFAULT_SIZE: usize = 257;
pub const DEFAULT_SPACING_M: f64 = 30.0;

/// A `size`² grid of spacing `spacing_m`.
pub(crate) fn generate(name: &str, size: usize, spacing_m: f64) -> Result<RawGrid> {
    let kind = NAMES
        .iter()
        .position(|&n| n == name)
        .map(|k| KINDS[k])
        .ok_or_else(|| {
            Error::value(
                "sketch.synthetic",
                format!(
                    "unknown synthetic sketch `{name}` (one of {})",
                    NAMES.join(", ")
                ),
            )
        })?;
    let n = size;
    let mut data = Vec::with_capacity(n * n);
    for j in 0..n {
        for i in 0..n {
            // Unit coordinates in [0, 1] across the sketch.
            let (u, v) = (i as f64 / (n - 1) as f64, j as f64 / (n - 1) as f64);
            data.push(height(kind, u, v, i, j, n) as f32);
        }
    }
    Ok(RawGrid {
        width: n,
        height: n,
        dx: spacing_m,
        dy: spacing_m,
        data,
        georef: None,
    })
}

fn height(kind: Kind, u: f64, v: f64, i: usize, j: usize, n: usize) -> f64 {
    match kind {
        Kind::Gaussian => {
            let r2 = (u - 0.5).powi(2) + (v - 0.5).powi(2);
            100.0 + 1500.0 * (-r2 / (2.0 * 0.15f64.powi(2))).exp()
        }
        Kind::Hills => {
            // Wavelengths are fractions of the sketch, so the hills stay hills at any size.
            let w = |k: f64, a: f64, b: f64, p: f64| (TAU * k * (a * u + b * v) + p).sin();
            400.0
                + 180.0 * w(2.0, 1.0, 0.3, 0.4) * w(1.5, -0.2, 1.0, 1.1)
                + 90.0 * w(4.5, 0.7, 0.7, 2.0)
                + 45.0 * w(9.0, -0.8, 0.6, 0.3)
        }
        Kind::Ridges => {
            let s = (TAU * 3.0 * (0.8 * u + 0.6 * v)).sin().abs();
            let bend = 0.15 * (TAU * 1.5 * v).sin();
            let t = (TAU * 3.0 * (0.8 * (u + bend) + 0.6 * v)).sin().abs();
            200.0 + 900.0 * (1.0 - t).powi(2) + 60.0 * s
        }
        Kind::Cliff => {
            if i < n / 2 {
                100.0
            } else {
                500.0
            }
        }
        Kind::Flat => 100.0,
        Kind::Spike => {
            if i == n / 2 && j == n / 2 {
                1500.0
            } else {
                100.0
            }
        }
    }
}
