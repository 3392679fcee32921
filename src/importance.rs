//! The importance map: samples per metre wanted at each sketch map texel,
//! `I = max(min(I_v·S_f·S_b, I_s), I_floor)` as DESIGN.md defines it.
//!
//! Rules:
//! - `I_v = f_px / (C·d)`, with d clamped below by half the sketch map spacing: the warp is
//!   piecewise linear between texels and cannot deliver a demand that varies inside one.
//! - `S_f` is the product over the frustum's five planes of a smoothstep from 0 at `margin` metres
//!   outside to 1 on the plane; the margin covers a texel's reach (1.5·d0), the detail's
//!   displacement and 5 % of the distance (the GPU's upsampled mesh bulges past the texels).
//!   Texels outside the atlas have `S_f = 0`: there is no terrain there to see.
//! - `S_b` is 1 for front-facing and silhouette texels (n·v ≥ −0.05) and falls smoothly to
//!   `backface_floor` at n·v = −0.35.
//! - `I_floor` is `floor` × the least importance of a texel in view, so the invisible rest of the
//!   region keeps a few cells and the warp's weights stay positive. Nothing in view: uniform 1.
//! - Computed in f32 relative to the region's corner; world-scale values never enter the loop.

use crate::camera::Camera;
use crate::sketch_map::SketchMap;
use glam::{DVec2, DVec3, Vec3};

#[derive(Clone, Debug)]
pub struct ImportanceParams {
    pub quad_px: f64,
    pub view: bool,
    pub frustum: bool,
    pub backface: bool,
    pub max_per_m: Option<f64>,
    pub floor: f64,
    pub backface_floor: f64,
    /// How far procedural detail can displace the surface, metres (widens the frustum margin).
    pub reach_m: f64,
}

#[derive(Clone, Debug)]
pub struct ImportanceMap {
    pub n: usize,
    /// I, samples per metre, row-major like the sketch map.
    pub importance: Vec<f32>,
    /// S_f alone (1 when the frustum factor is off), for deciding which cells are visible.
    pub frustum: Vec<f32>,
    /// Texels whose raw importance was NaN or infinite (replaced by the floor). Always 0 unless a
    /// bug lets one through; reported so that a bug shows.
    pub nonfinite: usize,
}

impl ImportanceMap {
    pub fn new(n: usize) -> ImportanceMap {
        ImportanceMap {
            n,
            importance: vec![1.0; n * n],
            frustum: vec![0.0; n * n],
            nonfinite: 0,
        }
    }

    /// Fills the map for `camera` over `map`; `surface_max` is I_s per texel when a map gives it.
    /// Allocates nothing.
    pub fn update(
        &mut self,
        map: &SketchMap,
        atlas_bounds: (DVec2, DVec2),
        camera: &Camera,
        surface_max: Option<&[f32]>,
        p: &ImportanceParams,
    ) {
        let n = map.n;
        let d0 = map.spacing;
        let local = |w: DVec3| w - map.origin.extend(0.0);
        let eye = local(camera.eye).as_vec3();
        let planes = camera.planes().map(|pl| {
            let d = pl.d + pl.n.dot(map.origin.extend(0.0));
            (pl.n.as_vec3(), d as f32)
        });
        let k_view = (camera.f_px() / p.quad_px) as f32;
        let d_min = (0.5 * d0) as f32;
        let centre = map.origin + DVec2::splat(0.5 * map.extent());
        let uniform_view = (camera.f_px()
            / (p.quad_px * (camera.eye - centre.extend(0.0)).length().max(d0)))
            as f32;
        let margin_base = (1.5 * d0 + p.reach_m) as f32;
        // Texels outside the atlas: compare in texel units, with a tolerance for the snapping.
        let inside = |a: f64, lo: f64, hi: f64| a >= lo - 1e-6 * d0 && a <= hi + 1e-6 * d0;
        let i_s_const = p.max_per_m.map(|v| v as f32).unwrap_or(f32::INFINITY);
        let inv_2d0 = (0.5 / d0) as f32;
        let h = &map.heights;
        let mut min_visible = f32::INFINITY;
        self.nonfinite = 0;

        for j in 0..n {
            let y = (j as f64 * d0) as f32;
            let y_in = inside(
                map.origin.y + j as f64 * d0,
                atlas_bounds.0.y,
                atlas_bounds.1.y,
            );
            let (jm, jp) = (j.saturating_sub(1), (j + 1).min(n - 1));
            for i in 0..n {
                let k = j * n + i;
                let pos = Vec3::new((i as f64 * d0) as f32, y, h[k]);
                let to_eye = eye - pos;
                let dist = to_eye.length();
                let i_v = if p.view {
                    k_view / dist.max(d_min)
                } else {
                    uniform_view
                };
                let x_in = inside(
                    map.origin.x + i as f64 * d0,
                    atlas_bounds.0.x,
                    atlas_bounds.1.x,
                );
                let s_f = if !(x_in && y_in) {
                    0.0
                } else if p.frustum {
                    let margin = margin_base + 0.05 * dist;
                    planes.iter().fold(1.0, |acc, (pn, pd)| {
                        acc * smoothstep((pn.dot(pos) + pd + margin) / margin)
                    })
                } else {
                    1.0
                };
                let s_b = if p.backface {
                    let (im, ip) = (i.saturating_sub(1), (i + 1).min(n - 1));
                    let gx = (h[j * n + ip] - h[j * n + im]) * inv_2d0 * 2.0 / (ip - im) as f32;
                    let gy = (h[jp * n + i] - h[jm * n + i]) * inv_2d0 * 2.0 / (jp - jm) as f32;
                    let normal = Vec3::new(-gx, -gy, 1.0).normalize();
                    backface(normal.dot(to_eye) / dist.max(1e-6), p.backface_floor as f32)
                } else {
                    1.0
                };
                let i_s = surface_max.map_or(i_s_const, |m| m[k].min(i_s_const));
                let mut v = (i_v * s_f * s_b).min(i_s);
                if !v.is_finite() || v < 0.0 {
                    self.nonfinite += 1;
                    v = 0.0;
                }
                self.importance[k] = v;
                self.frustum[k] = s_f;
                if s_f >= 0.5 && v > 0.0 {
                    min_visible = min_visible.min(v);
                }
            }
        }
        self.apply_floor(min_visible, p.floor as f32);
    }

    fn apply_floor(&mut self, min_visible: f32, floor: f32) {
        if !min_visible.is_finite() {
            self.importance.fill(1.0);
            return;
        }
        let i_floor = (min_visible * floor).max(f32::MIN_POSITIVE);
        for v in &mut self.importance {
            *v = v.max(i_floor);
        }
    }

    /// Bilinear sample of `field` at sketch-map texel coordinates (x, y), clamped to the map.
    pub fn sample(&self, field: &[f32], x: f32, y: f32) -> f32 {
        let n = self.n;
        let x = x.clamp(0.0, (n - 1) as f32);
        let y = y.clamp(0.0, (n - 1) as f32);
        let i = (x as usize).min(n - 2);
        let j = (y as usize).min(n - 2);
        let (fx, fy) = (x - i as f32, y - j as f32);
        let at = |a: usize, b: usize| field[b * n + a];
        let lo = at(i, j) + (at(i + 1, j) - at(i, j)) * fx;
        let hi = at(i, j + 1) + (at(i + 1, j + 1) - at(i, j + 1)) * fx;
        lo + (hi - lo) * fy
    }
}

fn smoothstep(t: f32) -> f32 {
    let t = t.clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// S_b from the cosine between the surface normal and the direction to the eye.
fn backface(cos: f32, floor: f32) -> f32 {
    const SILHOUETTE: f32 = -0.05;
    const FADE: f32 = 0.3;
    let t = ((SILHOUETTE - cos) / FADE).clamp(0.0, 1.0);
    1.0 - (1.0 - floor) * smoothstep(t)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn backface_is_one_on_front_and_silhouette_and_floors_behind() {
        assert_eq!(backface(0.8, 0.15), 1.0);
        assert_eq!(backface(-0.04, 0.15), 1.0);
        assert!((backface(-0.9, 0.15) - 0.15).abs() < 1e-6);
        let mid = backface(-0.2, 0.15);
        assert!(mid > 0.15 && mid < 1.0);
    }
}
