//! Procedural detail on the CPU: band-limited gradient noise octaves, the split octave, and the
//! geometry/bump shares of each octave (`docs/design.md`, Procedural detail). The GPU twin is
//! `shaders/shared/noise.wgsl`, line for line: every function below that takes f32 and i32/u32 has
//! a WGSL function of the same name.
//!
//! Rules:
//! - Octave k ≥ 1 has frequency `f_k = 2^(k−1)/d_atlas` and weight `A·g^(k−1)`. Its lattice has
//!   [`LATTICE_PER_CYCLE`] cells per cycle of `f_k`, which puts the noise's spectral peak at `f_k`.
//! - The lattice is hashed without tables (`hash`: a 32-bit integer finaliser), gradients are unit
//!   vectors, the fade is quintic, so value and gradient are continuous.
//! - Precision: a position is split into a whole lattice cell (i32, wrapping) and a fraction in
//!   [0, 1). [`Detail::octave_world`] splits in f64 from the world position, so it is exact at
//!   10,000 km; [`OctaveFrame`] does the same split once per frame for the frame origin, and a GPU
//!   vertex adds only its small f32 offset from it. Noise is never evaluated from a large f32.
//!
//! Rejected alternative: permutation-table Perlin noise. Tables must be uploaded and repeat every
//! 256 cells, which at octave 12 of a 30 m atlas is every 4 m: visible tiling across a valley.

use glam::{DVec2, IVec2, Vec2};

/// Lattice cells per cycle of the octave's frequency (measured: see the spectrum test).
pub const LATTICE_PER_CYCLE: f64 = 1.6;
/// Gradient noise with unit gradients spans about ±1/√2; this scales it to about ±1.
const VALUE_SCALE: f32 = std::f32::consts::SQRT_2;

/// RMS of one octave's noise n_k over the plane (measured: see `noise_rms_is_measured`).
pub const NOISE_RMS: f64 = 0.31;

/// The default octave count for a sketch of cell size `d_atlas`: every octave whose wavelength
/// `d_atlas / 2^(k−1)` is at least `finest_m` (at least one, at most `max`).
pub fn default_octaves(d_atlas: f64, finest_m: f64, max: u32) -> u32 {
    let k = (d_atlas / finest_m).log2().floor() + 1.0;
    if k.is_finite() {
        k.clamp(1.0, max as f64) as u32
    } else {
        1
    }
}

/// The default amplitude of octave 1, metres: the sketch's finest relief (`finest_relief()[0]`,
/// RMS of wavelengths 2–4 cells) carried on by one `gain` step and turned from an RMS into the
/// noise's amplitude, so the detail continues the sketch's own spectrum instead of replacing it.
/// At least 1 % of a cell, so a flat sketch still has a surface.
pub fn default_amplitude_m(finest_relief_m: f64, gain: f64, d_atlas: f64) -> f64 {
    let a = gain * finest_relief_m / NOISE_RMS;
    if a.is_finite() {
        a.max(0.01 * d_atlas)
    } else {
        0.01 * d_atlas
    }
}

/// Scene parameters of the detail, plus the atlas spacing that fixes octave 1.
#[derive(Clone, Debug)]
pub struct Detail {
    /// Noise octaves, 0 to 24 (`detail.octaves`); 0 draws the sketch alone.
    pub octaves: u32,
    /// Amplitude `w_1` of octave 1, metres (`detail.amplitude_m`; by default from the sketch's
    /// relief).
    pub amplitude_m: f64,
    /// Amplitude ratio of each octave to the one before, in [0, 1] (`detail.gain`, default 0.5).
    pub gain: f64,
    /// The noise's seed (`detail.seed`, default 7); each octave hashes it with its index.
    pub seed: u32,
    /// Octaves subtracted from each vertex's split octave (`detail.bias`, −4 to 8): larger
    /// carries fewer octaves as geometry and more as bump.
    pub bias: f64,
    /// The sketch's cell size, metres: octave 1's wavelength, octave k's `d_atlas / 2^(k−1)`.
    pub d_atlas: f64,
    /// World position of lattice cell (0, 0) of every octave (normally the origin).
    pub lattice_origin_m: DVec2,
}

impl Detail {
    /// `f_k`, cycles per metre.
    pub fn frequency(&self, k: u32) -> f64 {
        (k as f64 - 1.0).exp2() / self.d_atlas
    }
    /// `w_k`, metres.
    pub fn weight(&self, k: u32) -> f64 {
        self.amplitude_m * self.gain.powi(k as i32 - 1)
    }
    /// Largest displacement all octaves together can reach (with |n_k| ≤ 1).
    pub fn reach_m(&self) -> f64 {
        (1..=self.octaves).map(|k| self.weight(k)).sum()
    }

    /// The band above the water's surface over which the octaves fade in: twice their reach,
    /// so that within it their share times their reach stays below the height above the water
    /// (`shore` in this module).
    pub fn shore_m(&self) -> f64 {
        2.0 * self.reach_m()
    }
    fn lattice_scale(&self, k: u32) -> f64 {
        self.frequency(k) * LATTICE_PER_CYCLE
    }
    /// The seed of octave `k`'s lattice gradients, as the shaders derive it.
    pub fn octave_seed(&self, k: u32) -> u32 {
        hash(self.seed ^ hash(k))
    }

    /// Octave k's noise n_k at a world position, and its gradient per metre.
    pub fn octave_world(&self, k: u32, p: DVec2) -> (f32, Vec2) {
        let scale = self.lattice_scale(k);
        let q = (p - self.lattice_origin_m) * scale;
        let c = q.floor();
        let cell = IVec2::new(wrap_i32(c.x), wrap_i32(c.y));
        let (v, g) = gradient_noise(cell, (q - c).as_vec2(), self.octave_seed(k));
        (v, g * scale as f32)
    }

    /// The detail at a world position for split octave `o` and pixel octave `o_px`:
    /// `Σ w_k·n_k·(g_k + (1−g_k)·b_k)`, and its gradient. Octaves with `b_k = 0` are not evaluated.
    pub fn height_world(&self, p: DVec2, o: f32, o_px: f32) -> (f32, Vec2) {
        let mut h = 0.0;
        let mut grad = Vec2::ZERO;
        for k in 1..=self.last_octave(o.max(o_px)) {
            let share = octave_share(k, o, o_px);
            let (v, g) = self.octave_world(k, p);
            let w = self.weight(k) as f32 * share;
            h += w * v;
            grad += w * g;
        }
        (h, grad)
    }

    /// The highest octave with any share at octave level `o`: `b_k > 0 ⇔ k < o + 1`.
    pub fn last_octave(&self, o: f32) -> u32 {
        if o.is_nan() || o <= 0.0 {
            return 0;
        }
        (o.ceil() as u32).min(self.octaves)
    }

    /// The per-frame split of each octave for a frame origin (f64 world metres).
    pub fn frame(&self, origin: DVec2) -> Vec<OctaveFrame> {
        (1..=self.octaves)
            .map(|k| {
                let rel = origin - self.lattice_origin_m;
                OctaveFrame::split(
                    rel,
                    self.lattice_scale(k),
                    self.weight(k),
                    self.octave_seed(k),
                )
            })
            .collect()
    }

    /// The split octave at a vertex whose farthest neighbour is `d_max` metres away.
    pub fn split_octave(&self, d_max: f64) -> f32 {
        ((self.d_atlas / d_max.max(1e-9)).log2() - self.bias) as f32
    }
}

/// One octave's constants for one frame: what the GPU receives in its uniform block.
#[derive(Clone, Copy, Debug)]
pub struct OctaveFrame {
    pub lattice: IVec2,
    pub phase: Vec2,
    pub scale: f32,
    pub weight: f32,
    pub seed: u32,
}

impl OctaveFrame {
    /// Splits `origin` (metres from the lattice origin, f64) into a whole cell and a fraction of a
    /// lattice with `scale` cells per metre.
    pub fn split(origin: DVec2, scale: f64, weight: f64, seed: u32) -> OctaveFrame {
        let q = origin * scale;
        let c = q.floor();
        OctaveFrame {
            lattice: IVec2::new(wrap_i32(c.x), wrap_i32(c.y)),
            phase: (q - c).as_vec2(),
            scale: scale as f32,
            weight: weight as f32,
            seed,
        }
    }
}

#[cfg(test)]
/// n_k and its gradient at `local` metres from the frame origin (the GPU's path).
pub fn octave_local(o: &OctaveFrame, local: Vec2) -> (f32, Vec2) {
    let q = local * o.scale + o.phase;
    let c = q.floor();
    let cell = o.lattice + c.as_ivec2();
    let (v, g) = gradient_noise(cell, q - c, o.seed);
    (v, g * o.scale)
}

/// The share of octave k: geometry `g_k = clamp(o − k + 1, 0, 1)` plus the bump remainder
/// `(1 − g_k)·b_k`, `b_k = clamp(o_px − k + 1, 0, 1)`.
pub fn octave_share(k: u32, o: f32, o_px: f32) -> f32 {
    let g = (o - k as f32 + 1.0).clamp(0.0, 1.0);
    let b = (o_px - k as f32 + 1.0).clamp(0.0, 1.0);
    g + (1.0 - g) * b
}

#[cfg(test)]
/// The bump remainder alone, `(1 − g_k)·b_k`: what the per-pixel normal takes of octave k.
pub fn bump_share(k: u32, o: f32, o_px: f32) -> f32 {
    let g = (o - k as f32 + 1.0).clamp(0.0, 1.0);
    let b = (o_px - k as f32 + 1.0).clamp(0.0, 1.0);
    (1.0 - g) * b
}

/// Wraps a whole f64 into i32 the way two's complement addition on the GPU would.
fn wrap_i32(c: f64) -> i32 {
    (c as i64) as i32
}

/// A 32-bit integer finaliser (lowbias32, Wellons): every input bit affects every output bit.
pub fn hash(x: u32) -> u32 {
    let mut x = x;
    x ^= x >> 16;
    x = x.wrapping_mul(0x7feb_352d);
    x ^= x >> 15;
    x = x.wrapping_mul(0x846c_a68b);
    x ^= x >> 16;
    x
}

/// Unit gradient at a lattice point.
pub fn lattice_gradient(cell: IVec2, seed: u32) -> Vec2 {
    let h = hash((cell.x as u32) ^ hash((cell.y as u32) ^ hash(seed)));
    let angle = (h >> 8) as f32 * (std::f32::consts::TAU / 16_777_216.0);
    Vec2::new(angle.cos(), angle.sin())
}

/// Gradient noise in the cell with lower corner `cell` at fraction `f`: value and d/df.
pub fn gradient_noise(cell: IVec2, f: Vec2, seed: u32) -> (f32, Vec2) {
    let ga = lattice_gradient(cell, seed);
    let gb = lattice_gradient(cell + IVec2::new(1, 0), seed);
    let gc = lattice_gradient(cell + IVec2::new(0, 1), seed);
    let gd = lattice_gradient(cell + IVec2::new(1, 1), seed);
    let va = ga.dot(f);
    let vb = gb.dot(f - Vec2::new(1.0, 0.0));
    let vc = gc.dot(f - Vec2::new(0.0, 1.0));
    let vd = gd.dot(f - Vec2::new(1.0, 1.0));
    let u = f * f * f * (f * (f * 6.0 - 15.0) + 10.0);
    let du = 30.0 * f * f * (f * (f - 2.0) + 1.0);
    let k = va - vb - vc + vd;
    let value = va + u.x * (vb - va) + u.y * (vc - va) + u.x * u.y * k;
    let grad = ga
        + u.x * (gb - ga)
        + u.y * (gc - ga)
        + u.x * u.y * (ga - gb - gc + gd)
        + du * (Vec2::new(u.y, u.x) * k + Vec2::new(vb - va, vc - va));
    (value * VALUE_SCALE, grad * VALUE_SCALE)
}

/// The share of the octaves that ground whose sketch height is `z` carries, over water at
/// `water_m` and a shore band `shore_m` wide ([`Detail::shore_m`]): 0 at the water, 1 from the
/// band's top, a smoothstep between (the shaders' `shore` in frame.wgsl). smoothstep(x)·reach ≤
/// 2x·reach for x in [0, 1], which is the height above the water: no octave takes land under it.
pub fn shore(z: f64, water_m: f64, shore_m: f64) -> f64 {
    if shore_m <= 0.0 {
        return 1.0;
    }
    let x = ((z - water_m) / shore_m).clamp(0.0, 1.0);
    x * x * (3.0 - 2.0 * x)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn detail() -> Detail {
        Detail {
            octaves: 12,
            amplitude_m: 30.0,
            gain: 0.5,
            seed: 7,
            bias: 0.5,
            d_atlas: 30.0,
            lattice_origin_m: DVec2::ZERO,
        }
    }

    #[test]
    fn gradient_matches_finite_differences() {
        let d = detail();
        for k in [1, 4, 9] {
            let p = DVec2::new(1234.567, 890.123);
            let (_, g) = d.octave_world(k, p);
            let e = 1e-3 / d.frequency(k);
            let dx = (d.octave_world(k, p + DVec2::X * e).0
                - d.octave_world(k, p - DVec2::X * e).0)
                / (2.0 * e) as f32;
            let dy = (d.octave_world(k, p + DVec2::Y * e).0
                - d.octave_world(k, p - DVec2::Y * e).0)
                / (2.0 * e) as f32;
            let scale = d.frequency(k) as f32;
            assert!(
                (g.x - dx).abs() < 2e-2 * scale && (g.y - dy).abs() < 2e-2 * scale,
                "k {k}: {g} vs {dx},{dy}"
            );
        }
    }

    #[test]
    fn exact_10_000_km_away_with_the_lattice_shifted() {
        let d = detail();
        // A shift that is a whole number of lattice cells of every octave: a whole number of
        // octave 1's cells (d_atlas / LATTICE_PER_CYCLE metres), as octave k has 2^(k−1) per one.
        let cell1 = d.d_atlas / LATTICE_PER_CYCLE;
        let shift = DVec2::splat((1e7 / cell1).round() * cell1);
        let shifted = Detail {
            lattice_origin_m: shift,
            ..d.clone()
        };
        let frame_origin = DVec2::new(1234.5, 678.25);
        let frames = d.frame(frame_origin);
        let frames_far = shifted.frame(frame_origin + shift);
        let mut worst = 0.0f32;
        for a in 0..40 {
            let local = Vec2::new(a as f32 * 37.3 - 700.0, (a * a) as f32 * 1.7 - 300.0);
            let p = frame_origin + local.as_dvec2();
            let (h0, _) = d.height_world(p, 12.0, 12.0);
            let (h1, _) = shifted.height_world(p + shift, 12.0, 12.0);
            let gpu_like: f32 = frames_far
                .iter()
                .zip(&frames)
                .map(|(far, _)| far.weight * octave_local(far, local).0)
                .sum();
            worst = worst.max((h1 - h0).abs()).max((gpu_like - h0).abs());
        }
        // 1e-6 of the amplitude for the f64 world path; the f32 frame path carries the local offset
        // (up to 1 km × 68 cells/m at octave 12) in f32, so it is held to 1e-3 there.
        assert!(worst < 1e-3 * 30.0, "worst {worst}");
        let p = DVec2::new(2345.6, 789.0);
        for k in 1..=12 {
            let (a, _) = d.octave_world(k, p);
            let (b, _) = shifted.octave_world(k, p + shift);
            assert!(
                (a - b).abs() * d.weight(k) as f32 <= 1e-6 * 30.0,
                "octave {k}: {a} {b}"
            );
        }
    }

    #[test]
    fn split_octave_and_shares() {
        let d = detail();
        assert!((d.split_octave(7.5) - 1.5).abs() < 1e-6); // log2(30/7.5) − 0.5
        assert_eq!(octave_share(1, 3.0, 5.0), 1.0);
        assert_eq!(octave_share(7, 3.0, 5.0), 0.0);
        // Half geometry, and the other half is bump up to the pixel octave's share.
        assert!((octave_share(4, 3.5, 3.5) - 0.75).abs() < 1e-6);
        assert_eq!(octave_share(4, 3.5, 5.0), 1.0);
        assert!((bump_share(4, 3.5, 3.5) - 0.25).abs() < 1e-6);
        assert_eq!(bump_share(1, 3.0, 5.0), 0.0);
        assert_eq!(bump_share(5, 3.0, 5.0), 1.0);
        assert_eq!(d.last_octave(3.2), 4);
        assert_eq!(d.last_octave(-1.0), 0);
    }

    #[test]
    fn noise_rms_is_measured() {
        let d = detail();
        let n = 200;
        let mut sum = 0.0f64;
        for j in 0..n {
            for i in 0..n {
                let p = DVec2::new(i as f64 * 7.31, j as f64 * 5.77);
                sum += (d.octave_world(3, p).0 as f64).powi(2);
            }
        }
        let rms = (sum / (n * n) as f64).sqrt();
        assert!((rms / NOISE_RMS - 1.0).abs() < 0.05, "measured {rms:.3}");
    }

    #[test]
    fn defaults_follow_the_cell_size_and_relief() {
        // 74 m cells: octaves down to wavelengths of a decimetre (74/2^9 = 0.15 m).
        assert_eq!(default_octaves(74.4, 0.1, 24), 10);
        assert_eq!(default_octaves(1.0, 0.1, 24), 4);
        assert_eq!(default_octaves(1e9, 0.1, 24), 24);
        assert_eq!(default_octaves(0.01, 0.1, 24), 1);
        // More relief in the sketch, more amplitude in the detail; never zero, never NaN.
        let rough = default_amplitude_m(20.0, 0.5, 30.0);
        let smooth = default_amplitude_m(2.0, 0.5, 30.0);
        assert!((rough / smooth - 10.0).abs() < 1e-9);
        assert_eq!(default_amplitude_m(0.0, 0.5, 30.0), 0.3);
        assert_eq!(default_amplitude_m(f64::NAN, 0.5, 30.0), 0.3);
    }
}
