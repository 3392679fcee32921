//! `sketch.synthetic = "planet"`: a global sketch from band-limited noise on the unit sphere, so a
//! planet scene needs no file. Continents rise from low-frequency noise over ocean floors, with
//! coastal shelves, and mountain ranges (ridged noise) run where the continental noise is high.
//! Every texel is a function of its 3-D position, so the sketch has no seam at the date line and
//! none at the poles.

use super::noise::octave_at;
use super::unit;
use crate::sketch::{Atlas, LoadOptions, RawGrid};
use glam::DVec3;
use std::f64::consts::{FRAC_PI_2, PI, TAU};

/// The default width of the synthetic planet's sketch (height: half of it): 39 km cells on the
/// Earth, the procedural octaves carrying every finer wavelength.
pub const DEFAULT_WIDTH: usize = 1024;

/// Fractal sum of `octaves` octaves of the sphere's noise at `p` (a unit vector), the first
/// `base` lattice cells per unit, each octave twice the frequency and `gain` the weight.
fn fbm(p: DVec3, base: f64, octaves: u32, gain: f64, seed: u32) -> f64 {
    let (mut sum, mut w, mut s) = (0.0, 1.0, base);
    for k in 0..octaves {
        sum += w * octave_at(s, seed.wrapping_add(k * 7919), p).0 as f64;
        w *= gain;
        s *= 2.0;
    }
    sum
}

fn smoothstep(a: f64, b: f64, x: f64) -> f64 {
    let t = ((x - a) / (b - a)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// The synthetic planet's height (metres) at the unit vector `p`.
pub fn planet_height(p: DVec3, seed: u32) -> f64 {
    let continent = fbm(p, 1.6, 7, 0.5, seed);
    let land = smoothstep(-0.02, 0.12, continent);
    let shelf = smoothstep(-0.12, 0.0, continent);
    let floor = -4800.0 + 900.0 * fbm(p, 6.0, 5, 0.5, seed ^ 0x51);
    let ocean = floor + (floor.abs() - 150.0) * shelf;
    let ridges = (1.0 - fbm(p, 5.0, 6, 0.5, seed ^ 0xa7).abs()).powi(3);
    let range = smoothstep(
        0.12,
        0.45,
        continent + 0.3 * fbm(p, 3.0, 3, 0.5, seed ^ 0x3c),
    );
    let hills = 350.0 * (0.5 + 0.5 * fbm(p, 24.0, 5, 0.5, seed ^ 0x77));
    let ground = 40.0 + hills * land + 5200.0 * ridges * range;
    ocean + (ground - ocean) * land
}

/// The `width` × `width`/2 global sketch for a planet of `radius` metres (equirectangular, texel
/// centres at the cells' middles, row 0 south).
pub fn planet_sketch(width: usize, radius: f64, seed: u32) -> Atlas {
    let width = width.max(8) & !1;
    let height = width / 2;
    let mut data = vec![0.0f32; width * height];
    // Rows in as many bands as there are cores: a 1024 × 512 sketch is 14 million evaluations
    // of the 3-D noise (about 2 s on this project's 2-core machine).
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let band = height.div_ceil(threads) * width;
    std::thread::scope(|scope| {
        for (b, rows) in data.chunks_mut(band).enumerate() {
            scope.spawn(move || {
                for (k, h) in rows.iter_mut().enumerate() {
                    let (i, j) = ((b * band + k) % width, (b * band + k) / width);
                    let lat = (j as f64 + 0.5) / height as f64 * PI - FRAC_PI_2;
                    let lon = (i as f64 + 0.5) / width as f64 * TAU - PI;
                    *h = planet_height(unit(lat, lon), seed) as f32;
                }
            });
        }
    });
    let cell = TAU * radius / width as f64;
    let mut raw = RawGrid::new(width, height, data, None);
    raw.dx = cell;
    raw.dy = cell;
    Atlas::from_raw(raw, &LoadOptions::default()).expect("finite synthetic heights")
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Oceans and continents, in the Earth's proportions roughly, and mountains among them.
    #[test]
    fn the_synthetic_planet_has_oceans_continents_and_mountains() {
        let a = planet_sketch(256, super::super::EARTH_RADIUS_M, 7);
        let d = &a.levels[0].data;
        let sea = d.iter().filter(|&&h| h < 0.0).count() as f64 / d.len() as f64;
        assert!((0.4..0.85).contains(&sea), "sea share {sea}");
        assert!(
            a.max_m > 2500.0 && a.min_m < -3500.0,
            "{} .. {}",
            a.min_m,
            a.max_m
        );
    }
}
