//! The view factors' row helpers: S_f's frustum planes and their margin, S_b's back-facing
//! fade, the slope S_b reads, and which texels lie on the atlas. Plain functions of a row, called
//! from the row loops (`rows`); the rules are the importance map's (`stage::importance`).

use glam::{DVec2, Vec3};

/// The frustum factor's margin beyond a texel's reach and the detail's, as a share of the
/// texel's distance to the eye: the room the upsampled mesh's cells take past the texels. A
/// wider margin spends cells, from high up, on ground a kilometre outside the view; a narrower
/// one gains nothing more (docs/decisions.md, “Frustum margin”).
pub(super) const MARGIN_SHARE: f32 = 0.02;

/// dh/dx along a row: central differences inside, one-sided at the ends.
pub(super) fn slope_x(row: &[f32], d0: f32, out: &mut [f32]) {
    let n = row.len();
    let half = 0.5 / d0;
    for i in 1..n - 1 {
        out[i] = (row[i + 1] - row[i - 1]) * half;
    }
    out[0] = (row[1] - row[0]) / d0;
    out[n - 1] = (row[n - 1] - row[n - 2]) / d0;
}

/// Whether every texel of a row (x in [0, `x_max`], heights in `h`) is surely on the inner side
/// of a plane, `n·(x, y, z) + d ≥ 0` with `d` at the row's y: its least value over the row's box,
/// less an allowance for the f32 rounding of the per-texel sum (about 50 times the few ulps of
/// its terms that rounding can cost), is positive. The texels' smoothsteps are then exactly 1.
pub(super) fn row_inside(pn: Vec3, d: f32, x_max: f32, (h_lo, h_hi): (f32, f32)) -> bool {
    let (a, c, d) = (pn.x as f64, pn.z as f64, d as f64);
    let (x_max, h_lo, h_hi) = (x_max as f64, h_lo as f64, h_hi as f64);
    let least = d + (a * x_max).min(0.0) + (c * h_lo).min(c * h_hi);
    let scale = d.abs() + (a * x_max).abs() + (c * h_lo).abs().max((c * h_hi).abs());
    least.is_finite() && least > 1e-5 * scale
}

pub(super) fn smoothstep(t: f32) -> f32 {
    let t = t.clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// S_b from the cosine between the surface normal and the direction to the eye.
pub(super) fn backface(cos: f32, floor: f32) -> f32 {
    const SILHOUETTE: f32 = -0.05;
    const FADE: f32 = 0.3;
    let t = ((SILHOUETTE - cos) / FADE).clamp(0.0, 1.0);
    1.0 - (1.0 - floor) * smoothstep(t)
}

/// 1 for the columns in `first ..= last`, 0 elsewhere.
pub(super) fn fill_on_atlas(on: &mut [f32], (first, last): (usize, isize)) {
    for (i, v) in on.iter_mut().enumerate() {
        *v = if i >= first && (i as isize) <= last {
            1.0
        } else {
            0.0
        };
    }
}

/// The texels `base + i·step`, i < n, that lie on the atlas `[lo, hi]` (a slack of 10⁻⁶ texel,
/// as for an axis-aligned region): `(first, last)`, empty when last < first.
pub(super) fn on_atlas(
    base: DVec2,
    step: DVec2,
    n: usize,
    (lo, hi): (DVec2, DVec2),
) -> (usize, isize) {
    let (mut first, mut last) = (0.0f64, (n - 1) as f64);
    for axis in 0..2 {
        let (b, d) = (base[axis], step[axis]);
        if d.abs() < 1e-12 {
            if b < lo[axis] || b > hi[axis] {
                return (1, 0);
            }
            continue;
        }
        let (a, c) = ((lo[axis] - b) / d, (hi[axis] - b) / d);
        first = first.max(a.min(c) - 1e-6);
        last = last.min(a.max(c) + 1e-6);
    }
    let (first, last) = (first.ceil(), last.floor());
    // f64::max and min pass over a NaN (a non-finite corner), which then leaves the row on the
    // atlas, as the axis-aligned range does; a NaN here cannot arise, but would leave it off.
    match first.partial_cmp(&last) {
        Some(std::cmp::Ordering::Less | std::cmp::Ordering::Equal) => {
            (first as usize, last as isize)
        }
        _ => (1, 0),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A plane skipped for a row leaves S_f as evaluating it would have: every texel's smoothstep
    /// is exactly 1. Random planes placed so the least value over the row, at a corner of its box,
    /// is within a metre to a micrometre of zero either way, where the rounding bound decides.
    #[test]
    fn a_skipped_plane_gives_every_texel_of_its_row_one() {
        let mut next = crate::stage::lines::tests::uniform(0x2545_f491);
        let (n, d0) = (64, 30.0f32);
        let x: Vec<f32> = (0..n).map(|i| i as f32 * d0).collect();
        let (mut skipped, mut kept) = (0, 0);
        for _ in 0..20_000 {
            let pn = Vec3::new(next() - 0.5, next() - 0.5, next() - 0.5).normalize();
            let mut row: Vec<f32> = (0..n).map(|_| 1000.0 + 800.0 * next()).collect();
            let (lo, hi) = row
                .iter()
                .fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), &h| {
                    (a.min(h), b.max(h))
                });
            // A texel at the corner of the row's box where the plane is least, so that the
            // rounding of its own value decides.
            let corner = if pn.x < 0.0 { n - 1 } else { 0 };
            row[corner] = if pn.z < 0.0 { hi } else { lo };
            let least = pn.x * x[corner] + pn.z * row[corner];
            let d = -least + (next() - 0.5) * 2.0 * 10f32.powi(-(next() * 6.0) as i32);
            let inv_margin = 1.0 / (50.0 + 100.0 * next());
            if row_inside(pn, d, x[n - 1], (lo, hi)) {
                skipped += 1;
                for i in 0..n {
                    let dist_p = pn.x * x[i] + pn.z * row[i] + d;
                    // The smoothstep is flat at 1 (it gives 1 down to about −4 mm here), so the
                    // sign is checked too: it is what the rounding allowance guarantees.
                    assert!(dist_p >= 0.0, "texel {i}: {dist_p}");
                    assert_eq!(smoothstep(dist_p * inv_margin + 1.0), 1.0, "texel {i}");
                }
            } else {
                kept += 1;
            }
        }
        assert!(
            skipped > 1000 && kept > 1000,
            "{skipped} skipped, {kept} kept"
        );
    }

    #[test]
    fn backface_is_one_on_front_and_silhouette_and_floors_behind() {
        assert_eq!(backface(0.8, 0.15), 1.0);
        assert_eq!(backface(-0.04, 0.15), 1.0);
        assert!((backface(-0.9, 0.15) - 0.15).abs() < 1e-6);
        let mid = backface(-0.2, 0.15);
        assert!(mid > 0.15 && mid < 1.0);
    }
}
