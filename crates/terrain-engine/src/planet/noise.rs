//! The procedural detail on a sphere: the planar octaves of [`crate::detail`] carried to a 3-D
//! lattice, evaluated on the sphere of the planet's radius. The GPU twin is
//! `shaders/shared/sphere.wgsl`, line for line: every function here that takes f32 and i32/u32 has
//! a WGSL function of the same name.
//!
//! Rules:
//! - Octave k keeps the planar frequency `f_k = 2^(k−1)/d_atlas` (d_atlas: the global sketch's
//!   cell at the equator), weight `A·g^(k−1)` and [`LATTICE_PER_CYCLE`] cells per cycle; only the
//!   lattice gains a third axis. A 3-D lattice has no seam anywhere: not at the date line, not at
//!   the poles, where any map-based (equirectangular or cube-face) lattice has one.
//! - Gradients are unit vectors uniform on the sphere (two hashed fractions); the fade is quintic,
//!   so value and gradient are continuous.
//! - Precision: positions are split as in the plane. [`SphereOctave::split`] takes the anchor (the
//!   camera's nadir on the sphere, f64 metres from the planet's centre) apart into a whole cell
//!   (i32, wrapping) and a fraction, once per frame; a vertex adds only its small f32 offset from
//!   the anchor. Noise is never evaluated from a large f32.
//!
//! Rejected alternative: the planar noise on each face of a cube. It needs a blend across the 12
//! edges of the cube (a seam or a smear of the detail there), and its cells stretch by up to
//! 1.7× toward the corners, so an octave's spectrum would change across the planet.

use crate::detail::{LATTICE_PER_CYCLE, hash};
use glam::{DVec3, IVec3, Vec3};

/// Scales the noise's RMS to the planar noise's [`crate::detail::NOISE_RMS`] (measured: 0.190
/// unscaled, see `noise_rms_is_about_the_planar_noise`), so a scene's amplitude means the same
/// relief on a planet as on a sketch.
const VALUE_SCALE: f32 = 1.63;

/// Unit gradient at a lattice point: z and the azimuth from two 16-bit halves of one hash.
pub fn lattice_gradient3(cell: IVec3, seed: u32) -> Vec3 {
    let h = hash((cell.x as u32) ^ hash((cell.y as u32) ^ hash((cell.z as u32) ^ hash(seed))));
    let z = 1.0 - 2.0 * (h & 0xffff) as f32 / 65535.0;
    let a = (h >> 16) as f32 * (std::f32::consts::TAU / 65536.0);
    let r = (1.0 - z * z).max(0.0).sqrt();
    Vec3::new(r * a.cos(), r * a.sin(), z)
}

/// Value and gradient d/df in the cell with lower corner `cell` at fraction `f`.
pub fn gradient_noise3(cell: IVec3, f: Vec3, seed: u32) -> (f32, Vec3) {
    let u = f * f * f * (f * (f * 6.0 - 15.0) + 10.0);
    let du = 30.0 * f * f * (f * (f - 2.0) + 1.0);
    let mut value = 0.0;
    let mut grad = Vec3::ZERO;
    for corner in 0..8u32 {
        let o = IVec3::new(
            (corner & 1) as i32,
            ((corner >> 1) & 1) as i32,
            (corner >> 2) as i32,
        );
        let g = lattice_gradient3(cell + o, seed);
        let v = g.dot(f - o.as_vec3());
        // The corner's trilinear weight and its derivative along each axis.
        let w = Vec3::select(o.cmpeq(IVec3::ONE), u, Vec3::ONE - u);
        let dw = Vec3::select(o.cmpeq(IVec3::ONE), du, -du);
        let weight = w.x * w.y * w.z;
        value += weight * v;
        grad += weight * g + v * Vec3::new(dw.x * w.y * w.z, w.x * dw.y * w.z, w.x * w.y * dw.z);
    }
    (value * VALUE_SCALE, grad * VALUE_SCALE)
}

/// One octave's constants for one frame: the anchor split into a cell and a fraction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SphereOctave {
    pub lattice: IVec3,
    pub phase: Vec3,
    /// Lattice cells per metre.
    pub scale: f32,
    /// w_k, metres.
    pub weight: f32,
    pub seed: u32,
}

impl SphereOctave {
    /// Splits `anchor` (metres from the planet's centre, f64) on a lattice of `scale` cells per
    /// metre.
    pub fn split(anchor: DVec3, scale: f64, weight: f64, seed: u32) -> SphereOctave {
        let q = anchor * scale;
        let c = q.floor();
        SphereOctave {
            lattice: IVec3::new(wrap_i32(c.x), wrap_i32(c.y), wrap_i32(c.z)),
            phase: (q - c).as_vec3(),
            scale: scale as f32,
            weight: weight as f32,
            seed,
        }
    }
}

#[cfg(test)]
/// n_k and its gradient per metre at `rel` metres from the anchor (the GPU's path).
pub fn octave_rel(o: &SphereOctave, rel: Vec3) -> (f32, Vec3) {
    let q = rel * o.scale + o.phase;
    let c = q.floor();
    let (v, g) = gradient_noise3(o.lattice + c.as_ivec3(), q - c, o.seed);
    (v, g * o.scale)
}

/// n_k at a point `p` (metres from the planet's centre), split in f64: exact at any radius.
pub fn octave_at(scale: f64, seed: u32, p: DVec3) -> (f32, Vec3) {
    let q = p * scale;
    let c = q.floor();
    let cell = IVec3::new(wrap_i32(c.x), wrap_i32(c.y), wrap_i32(c.z));
    let (v, g) = gradient_noise3(cell, (q - c).as_vec3(), seed);
    (v, g * scale as f32)
}

/// Lattice cells per metre of octave k for a sketch cell of `d_atlas` metres.
pub fn lattice_scale(d_atlas: f64, k: u32) -> f64 {
    (k as f64 - 1.0).exp2() / d_atlas * LATTICE_PER_CYCLE
}

fn wrap_i32(c: f64) -> i32 {
    (c as i64) as i32
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The noise is continuous across every cell face, in value and gradient, and its gradient is
    /// the derivative of its value.
    #[test]
    fn noise_is_smooth_and_its_gradient_is_its_derivative() {
        let mut worst_step: f32 = 0.0;
        let mut worst_grad: f32 = 0.0;
        for i in 0..200 {
            let t = i as f64 * 0.37;
            let p = DVec3::new(
                3.0 + t.sin() * 5.0,
                -2.0 + t * 0.1,
                7.0 + (t * 0.7).cos() * 4.0,
            );
            let e = 1e-4;
            let (v, g) = octave_at(1.0, 9, p);
            for axis in 0..3 {
                let mut d = DVec3::ZERO;
                d[axis] = e;
                let (a, _) = octave_at(1.0, 9, p + d);
                let (b, _) = octave_at(1.0, 9, p - d);
                let numeric = (a - b) / (2.0 * e as f32);
                worst_grad = worst_grad.max((numeric - g[axis]).abs());
            }
            // Across the cell face at the next whole x.
            let face = DVec3::new(p.x.ceil(), p.y, p.z);
            let (a, _) = octave_at(1.0, 9, face - DVec3::X * 1e-7);
            let (b, _) = octave_at(1.0, 9, face + DVec3::X * 1e-7);
            worst_step = worst_step.max((a - b).abs());
            assert!(v.abs() < 1.5, "{v}");
        }
        assert!(worst_step < 1e-4, "step {worst_step}");
        assert!(worst_grad < 2e-2, "gradient error {worst_grad}");
    }

    /// The GPU's path (a cell and fraction per frame plus an f32 offset) gives the f64 split's
    /// value at the Earth's radius.
    #[test]
    fn the_split_path_agrees_with_the_exact_one_at_the_earths_radius() {
        let r = crate::sketch::EARTH_RADIUS_M;
        let anchor = DVec3::new(0.3, -0.5, 0.8).normalize() * r;
        for k in [1u32, 8, 16, 20] {
            let scale = lattice_scale(19_546.0, k);
            let o = SphereOctave::split(anchor, scale, 1.0, 5);
            // Offsets up to 500 lattice cells: an octave is drawn (b_k > 0) only within a few
            // hundred of its cells of the camera at any picture size this renderer makes.
            for cells in [
                Vec3::new(0.1, 0.2, -0.3),
                Vec3::new(12.0, -40.0, 9.0),
                Vec3::new(-300.0, 200.0, 100.0),
            ] {
                let off = cells / scale as f32;
                let (a, _) = octave_rel(&o, off);
                let (b, _) = octave_at(scale, 5, anchor + off.as_dvec3());
                // Both sum the fraction and the offset in f32; they differ by its rounding.
                assert!((a - b).abs() < 1e-4, "k {k} offset {off}: {a} vs {b}");
            }
        }
    }

    /// Its RMS, the figure the default amplitude divides by, is about the planar noise's.
    #[test]
    fn noise_rms_is_about_the_planar_noise() {
        let mut sum = 0.0f64;
        let n = 40_000;
        for i in 0..n {
            let t = i as f64;
            let p = DVec3::new(
                (t * 0.618_034).fract() * 97.0,
                (t * 0.414_214).fract() * 89.0,
                (t * 0.732_051).fract() * 83.0,
            );
            let (v, _) = octave_at(1.0, 3, p);
            sum += (v as f64).powi(2);
        }
        let rms = (sum / n as f64).sqrt();
        assert!((rms - crate::detail::NOISE_RMS).abs() < 0.02, "rms {rms}");
    }
}
