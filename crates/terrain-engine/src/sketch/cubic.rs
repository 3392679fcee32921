//! The Catmull–Rom weights every CPU bicubic of the sketch uses: the f64 terrain function
//! (`query`, `planet`) and the f32 twins of the shaders (`gpu::warp_zoom`, `lod::clipmaps::pass`,
//! `tiles::blocks`). The WGSL twin is `catmull_rom` in `shaders/shared/atlas.wgsl`.
//!
//! Rule: one definition, generic over the float, so the f32 twins run the shader's operations in
//! the shader's order and stay bit-identical to it where the tests hold them to the GPU.
//! Rejected alternative: the f64 weights rounded to f32, which differ from the shader's in the
//! last bit and would loosen those tests.

use std::ops::{Add, Mul, Sub};

/// A float the weights are computed in.
pub trait Real: Copy + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> {
    /// A constant of the weights (each exact in f32).
    fn of(v: f64) -> Self;
}

impl Real for f32 {
    fn of(v: f64) -> f32 {
        v as f32
    }
}

impl Real for f64 {
    fn of(v: f64) -> f64 {
        v
    }
}

/// Catmull–Rom weights of the four nodes around fraction `t`.
pub fn catmull_rom<T: Real>(t: T) -> [T; 4] {
    let c = T::of;
    let (t2, t3) = (t * t, t * t * t);
    [
        c(-0.5) * t3 + t2 - c(0.5) * t,
        c(1.5) * t3 - c(2.5) * t2 + c(1.0),
        c(-1.5) * t3 + c(2.0) * t2 + c(0.5) * t,
        c(0.5) * t3 - c(0.5) * t2,
    ]
}

/// The weights' derivatives by `t`.
pub fn catmull_rom_d<T: Real>(t: T) -> [T; 4] {
    let c = T::of;
    let t2 = t * t;
    [
        c(-1.5) * t2 + c(2.0) * t - c(0.5),
        c(4.5) * t2 - c(5.0) * t,
        c(-4.5) * t2 + c(4.0) * t + c(0.5),
        c(1.5) * t2 - t,
    ]
}

/// Weights of the four nodes around a fraction: [`catmull_rom`] or [`catmull_rom_d`] in f64.
pub type Weights = fn(f64) -> [f64; 4];

/// The f64 bicubic on pyramid level `l` at level-0 texel coordinates `uv`, with weights `wx`
/// along x and `wy` along y ([`catmull_rom`] or its derivative), each node from `node(i, j)` of
/// that level: the caller addresses them, clamped to the level's edge (`query`) or wrapped across
/// the date line and the poles (`planet`).
pub fn bicubic<E>(
    uv: glam::DVec2,
    l: usize,
    (wx, wy): (Weights, Weights),
    mut node: impl FnMut(i64, i64) -> Result<f32, E>,
) -> Result<f64, E> {
    let s = (1u64 << l) as f64;
    let x = (uv - glam::DVec2::splat((s - 1.0) * 0.5)) / s;
    let i = x.floor();
    let f = x - i;
    let (ax, ay) = (wx(f.x), wy(f.y));
    let mut sum = 0.0;
    for (r, ayr) in ay.iter().enumerate() {
        for (c, axc) in ax.iter().enumerate() {
            let v = node(i.x as i64 - 1 + c as i64, i.y as i64 - 1 + r as i64)?;
            sum += ayr * axc * v as f64;
        }
    }
    Ok(sum)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The weights sum to one and their derivatives to zero, in both floats, and the f32 weights
    /// are the f32 operations' (not the f64 weights rounded).
    #[test]
    fn weights_partition_unity() {
        for k in 0..=16 {
            let t = k as f64 / 16.0;
            assert!((catmull_rom(t).iter().sum::<f64>() - 1.0).abs() < 1e-12);
            assert!(catmull_rom_d(t).iter().sum::<f64>().abs() < 1e-12);
            let tf = t as f32;
            let w = catmull_rom(tf);
            let (t2, t3) = (tf * tf, tf * tf * tf);
            assert_eq!(w[1], 1.5 * t3 - 2.5 * t2 + 1.0);
            assert!((w.iter().sum::<f32>() - 1.0).abs() < 1e-6);
        }
    }
}
