//! Image error of a mode against the reference, each metric as its reference implementation
//! computes it (`tests/metrics.rs` holds them together on committed image pairs; docs/metrics.md
//! says what each is):
//! - PSNR over the RGB values of 8-bit sRGB images, peak 255: scikit-image's
//!   `peak_signal_noise_ratio(data_range=255)`.
//! - SSIM as Wang, Bovik, Sheikh and Simoncelli (2004) define it, on Rec. 709 luma
//!   (0.2126 R' + 0.7152 G' + 0.0722 B' of the sRGB values): an 11×11 Gaussian window of σ = 1.5
//!   px, K1 = 0.01, K2 = 0.03, L = 255, population (co)variances, the mean over the positions
//!   where the window fits — scikit-image's `structural_similarity(gaussian_weights=True,
//!   sigma=1.5, use_sample_covariance=False, data_range=255)` on that luma. Computed by the iqa
//!   crate (`SsimMode::Luma709`).
//! - FLIP mean (flip-rs, NVIDIA's LDR-FLIP at 67.02 pixels per degree: a 0.7 m wide 4K display
//!   seen from 0.7 m, FLIP's default).
//! - The screen-space geometric error from position buffers (`docs/design.md`, Screen-space error
//!   and τ: the distance in pixels between where the mode's surface and the reference's surface
//!   appear).
//! - The terrain's luminance, mean and standard deviation: linear Rec. 709 luminance
//!   (0.2126 R + 0.7152 G + 0.0722 B of the sRGB-decoded values) over the pixels that show ground.
//!   How much contrast the picture keeps: haze that flattens a view from 20 km lowers it.
//!
//! Screen-space error, per pixel x where either image shows ground: if both do, the distance from
//! x to the reference pixel whose ground position is nearest (horizontally) to the mode's at x,
//! searched within `window` pixels, is where the reference shows that same piece of ground; if only
//! one does (a silhouette), the distance to the nearest pixel where the other shows ground. A
//! pixel with no match in the window counts as `window` pixels.
//!
//! Where the reference shows that ground is found to a fraction of a pixel: from the nearest
//! pixel, one step of Newton's method on the reference's ground position as a function of the
//! pixel (its 2×2 Jacobian by differences with the neighbouring ground pixels), the step held
//! within a pixel each way. Rejected: the nearest pixel alone. It counts every error under half a
//! pixel as 0 and every one just over as 1, so from high up, where the errors are small, which
//! mode wins a row is decided by which pixels happen to round (docs/decisions.md, “Screen-space
//! error to a fraction of a pixel”).
//!
//! Rejected alternative: projecting the mode's point onto the reference surface vertically. It
//! needs the terrain function on the CPU per pixel and says nothing at silhouettes.

use serde::Serialize;

/// Mean and standard deviation of the linear luminance of an RGBA8 sRGB image over the pixels
/// where `ground` is true; `None` when no pixel shows ground.
pub fn terrain_luminance(rgba: &[u8], ground: impl Iterator<Item = bool>) -> Option<(f64, f64)> {
    let decode = |v: u8| {
        let c = v as f64 / 255.0;
        if c <= 0.04045 {
            c / 12.92
        } else {
            ((c + 0.055) / 1.055).powf(2.4)
        }
    };
    let values: Vec<f64> = rgba
        .chunks_exact(4)
        .zip(ground)
        .filter(|(_, g)| *g)
        .map(|(p, _)| 0.2126 * decode(p[0]) + 0.7152 * decode(p[1]) + 0.0722 * decode(p[2]))
        .collect();
    if values.is_empty() {
        return None;
    }
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let var = values.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / n;
    Some((mean, var.sqrt()))
}

/// PSNR in dB between two RGBA8 images of one size, over RGB; infinity when identical.
pub fn psnr(a: &[u8], b: &[u8]) -> f64 {
    assert_eq!(a.len(), b.len(), "images of different sizes");
    let (mut sum, mut count) = (0.0f64, 0usize);
    for (pa, pb) in a.chunks_exact(4).zip(b.chunks_exact(4)) {
        for c in 0..3 {
            let d = pa[c] as f64 - pb[c] as f64;
            sum += d * d;
            count += 1;
        }
    }
    if sum == 0.0 {
        return f64::INFINITY;
    }
    10.0 * (255.0f64 * 255.0 / (sum / count as f64)).log10()
}

fn rgb(rgba: &[u8]) -> Vec<u8> {
    rgba.chunks_exact(4)
        .flat_map(|p| [p[0], p[1], p[2]])
        .collect()
}

/// SSIM of `test` against `reference` (RGBA8 sRGB, `width` columns) on luma, as the module doc
/// defines it: 1 for identical images; `None` for images under 11×11 pixels or of other sizes.
pub fn ssim(reference: &[u8], test: &[u8], width: u32) -> Option<f64> {
    let height = (reference.len() / 4) as u32 / width.max(1);
    let a = iqa::Image::rgba8(width, height, reference.to_vec()).ok()?;
    let b = iqa::Image::rgba8(width, height, test.to_vec()).ok()?;
    let options = iqa::SsimOptions {
        mode: iqa::SsimMode::Luma709,
    };
    iqa::ssim(&a, &b, options).ok()
}

/// Mean LDR-FLIP error of `test` against `reference` (RGBA8 sRGB): 0 for identical images.
pub fn flip_mean(reference: &[u8], test: &[u8], width: u32) -> Option<f64> {
    let w = width as usize;
    let h = reference.len() / 4 / w.max(1);
    let a = flip_rs::RgbImage::new(w, h, rgb(reference)).ok()?;
    let b = flip_rs::RgbImage::new(w, h, rgb(test)).ok()?;
    let ppd = flip_rs::pixels_per_degree(0.7, 3840.0, 0.7).ok()?;
    let map = flip_rs::ldr_flip(&a, &b, ppd).ok()?;
    let stats = map.statistics();
    stats.finite.then_some(stats.mean as f64)
}

#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct ScreenError {
    pub mean_px: f64,
    pub p95_px: f64,
    pub max_px: f64,
    /// Pixels where either image shows ground.
    pub pixels: usize,
}

/// Screen-space error of `mode` against `reference`: position buffers of `width` columns, each
/// pixel (x, y, z, w) with w = 1 on ground and 0 on sky.
pub fn screen_space_error(
    mode: &[[f32; 4]],
    reference: &[[f32; 4]],
    width: usize,
    window: usize,
) -> ScreenError {
    assert_eq!(
        mode.len(),
        reference.len(),
        "position buffers of different sizes"
    );
    let height = mode.len() / width;
    let ground = |b: &[[f32; 4]], x: usize, y: usize| b[y * width + x][3] > 0.5;
    let mut errors = Vec::new();
    for y in 0..height {
        for x in 0..width {
            let (m, r) = (ground(mode, x, y), ground(reference, x, y));
            if !m && !r {
                continue;
            }
            let (x0, x1) = (x.saturating_sub(window), (x + window).min(width - 1));
            let (y0, y1) = (y.saturating_sub(window), (y + window).min(height - 1));
            let mut best = window as f64;
            if m && r {
                let p = mode[y * width + x];
                let mut nearest = (f64::INFINITY, 0, 0);
                for v in y0..=y1 {
                    for u in x0..=x1 {
                        let q = reference[v * width + u];
                        if q[3] > 0.5 {
                            let d = ((q[0] - p[0]) as f64).hypot((q[1] - p[1]) as f64);
                            if d < nearest.0 {
                                nearest = (d, u, v);
                            }
                        }
                    }
                }
                let (d, u, v) = nearest;
                if d.is_finite() {
                    let (du, dv) = subpixel(reference, width, height, (u, v), p);
                    let at = (u as f64 + du - x as f64).hypot(v as f64 + dv - y as f64);
                    best = at.min(window as f64);
                }
            } else {
                // A silhouette: the nearest pixel where the other image shows ground.
                let other = if m { reference } else { mode };
                for v in y0..=y1 {
                    for u in x0..=x1 {
                        if ground(other, u, v) {
                            best = best.min((u as f64 - x as f64).hypot(v as f64 - y as f64));
                        }
                    }
                }
            }
            errors.push(best);
        }
    }
    summarise(errors)
}

/// The offset (each within ±1 pixel) from pixel `at` of the reference to where its ground position
/// would be `p`'s (horizontally): one Newton step with the Jacobian of the position by pixel,
/// from central differences where both neighbours show ground, one-sided where one does. (0, 0)
/// where neither does along an axis or the Jacobian is singular (ground seen edge-on).
fn subpixel(
    reference: &[[f32; 4]],
    width: usize,
    height: usize,
    at: (usize, usize),
    p: [f32; 4],
) -> (f64, f64) {
    let xy = |u: usize, v: usize| {
        let q = reference[v * width + u];
        (q[3] > 0.5).then(|| [q[0] as f64, q[1] as f64])
    };
    let (u, v) = at;
    let Some(c) = xy(u, v) else {
        return (0.0, 0.0);
    };
    // The derivative along one axis: `before` and `after` are the neighbours, when in the image.
    let slope = |before: Option<[f64; 2]>, after: Option<[f64; 2]>| match (before, after) {
        (Some(b), Some(a)) => Some([0.5 * (a[0] - b[0]), 0.5 * (a[1] - b[1])]),
        (None, Some(a)) => Some([a[0] - c[0], a[1] - c[1]]),
        (Some(b), None) => Some([c[0] - b[0], c[1] - b[1]]),
        (None, None) => None,
    };
    let ju = slope(
        u.checked_sub(1).and_then(|u| xy(u, v)),
        (u + 1 < width).then(|| xy(u + 1, v)).flatten(),
    );
    let jv = slope(
        v.checked_sub(1).and_then(|v| xy(u, v)),
        (v + 1 < height).then(|| xy(u, v + 1)).flatten(),
    );
    let (Some(ju), Some(jv)) = (ju, jv) else {
        return (0.0, 0.0);
    };
    let det = ju[0] * jv[1] - ju[1] * jv[0];
    let scale = (ju[0].hypot(ju[1]) * jv[0].hypot(jv[1])).max(f64::MIN_POSITIVE);
    // Columns within a thousandth of parallel (or NaN): the step along them is not determined.
    let determined = det.abs() > 1e-3 * scale;
    if !determined {
        return (0.0, 0.0);
    }
    let (ex, ey) = (p[0] as f64 - c[0], p[1] as f64 - c[1]);
    let du = (ex * jv[1] - ey * jv[0]) / det;
    let dv = (ju[0] * ey - ju[1] * ex) / det;
    (du.clamp(-1.0, 1.0), dv.clamp(-1.0, 1.0))
}

fn summarise(mut errors: Vec<f64>) -> ScreenError {
    if errors.is_empty() {
        return ScreenError::default();
    }
    errors.sort_by(f64::total_cmp);
    let n = errors.len();
    ScreenError {
        mean_px: errors.iter().sum::<f64>() / n as f64,
        p95_px: errors[((n as f64 * 0.95) as usize).min(n - 1)],
        max_px: errors[n - 1],
        pixels: n,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn terrain_luminance_counts_ground_pixels_only() {
        // Black and white ground, a grey sky pixel left out: mean ½, deviation ½.
        let rgba = [0, 0, 0, 255, 255, 255, 255, 255, 128, 128, 128, 255];
        let (mean, std) = terrain_luminance(&rgba, [true, true, false].into_iter()).unwrap();
        assert!(
            (mean - 0.5).abs() < 1e-12 && (std - 0.5).abs() < 1e-12,
            "{mean} {std}"
        );
        assert!(terrain_luminance(&rgba, [false; 3].into_iter()).is_none());
    }

    /// A ground plane seen so that pixel (x, y) shows ground point (x·10, y·7), sky above row 4.
    fn plane(w: usize, h: usize, shift: (i64, i64)) -> Vec<[f32; 4]> {
        ground(w, h, (shift.0 as f64, shift.1 as f64), 0.0)
    }

    /// [`plane`] shifted by any amount, and with `mix` 1 a general affine map: pixel (x, y) shows
    /// (x·10 + y·3·mix, y·7 + x·2·mix), so that the ground's axes need not be the pixels'.
    fn ground(w: usize, h: usize, shift: (f64, f64), mix: f64) -> Vec<[f32; 4]> {
        (0..w * h)
            .map(|k| {
                let (i, j) = ((k % w) as f64, (k / w) as f64);
                let (x, y) = (i - shift.0, j - shift.1);
                if y < 4.0 {
                    [0.0; 4]
                } else {
                    let ground = [x * 10.0 + y * 3.0 * mix, y * 7.0 + x * 2.0 * mix];
                    [ground[0] as f32, ground[1] as f32, 0.0, 1.0]
                }
            })
            .collect()
    }

    #[test]
    fn identical_images_score_infinite_psnr_and_zero_error() {
        let img: Vec<u8> = (0..64 * 4).map(|k| (k * 37 % 251) as u8).collect();
        assert_eq!(psnr(&img, &img), f64::INFINITY);
        let p = plane(32, 24, (0, 0));
        let e = screen_space_error(&p, &p, 32, 8);
        assert_eq!((e.mean_px, e.max_px), (0.0, 0.0));
        assert_eq!(e.pixels, 32 * 20);
    }

    #[test]
    fn a_known_shift_gives_the_known_error() {
        let (w, h) = (48, 40);
        let reference = plane(w, h, (0, 0));
        for shift in [(3i64, 0i64), (0, 2), (3, 4)] {
            let mode = plane(w, h, shift);
            let e = screen_space_error(&mode, &reference, w, 8);
            let want = ((shift.0 * shift.0 + shift.1 * shift.1) as f64).sqrt();
            // The median pixel sees the shift exactly; the image border and the shifted horizon
            // (a silhouette) are the only other values.
            assert!(
                (e.p95_px - want).abs() < 1e-9,
                "shift {shift:?}: p95 {} want {want}",
                e.p95_px
            );
            assert!(
                e.mean_px > 0.8 * want && e.mean_px <= want + 1e-9,
                "shift {shift:?}: mean {}",
                e.mean_px
            );
        }
    }

    #[test]
    fn a_shift_of_a_fraction_of_a_pixel_is_measured_to_that_fraction() {
        let (w, h) = (48, 40);
        let reference = ground(w, h, (0.0, 0.0), 1.0);
        // Under half a pixel (the nearest pixel alone says 0), and past it (it says 2 for 1.6).
        for shift in [(0.3, 0.2), (-0.25, 0.0), (1.6, 0.0), (0.7, -1.3)] {
            // The shifted ground inside a block away from the borders and the horizon; the
            // reference's own elsewhere, where the error is 0.
            let shifted = ground(w, h, shift, 1.0);
            let mut mode = reference.clone();
            let block = (12..28, 12..36);
            for y in block.0.clone() {
                for x in block.1.clone() {
                    mode[y * w + x] = shifted[y * w + x];
                }
            }
            let e = screen_space_error(&mode, &reference, w, 8);
            let want = f64::hypot(shift.0, shift.1);
            let share = (16 * 24) as f64 / e.pixels as f64;
            assert!(
                (e.max_px - want).abs() < 1e-3 && (e.mean_px - want * share).abs() < 1e-3 * want,
                "shift {shift:?}: max {} mean {}, want {want} and {}",
                e.max_px,
                e.mean_px,
                want * share
            );
        }
    }

    #[test]
    fn ssim_and_flip_are_perfect_for_identical_images_and_worse_for_others() {
        let (w, h) = (48u32, 32u32);
        let img: Vec<u8> = (0..w * h)
            .flat_map(|k| {
                let (x, y) = (k % w, k / w);
                [(x * 5) as u8, (y * 7) as u8, ((x * y) % 251) as u8, 255]
            })
            .collect();
        let shifted: Vec<u8> = (0..w * h)
            .flat_map(|k| {
                let (x, y) = ((k % w + 3) % w, k / w);
                [(x * 5) as u8, (y * 7) as u8, ((x * y) % 251) as u8, 255]
            })
            .collect();
        assert!((ssim(&img, &img, w).unwrap() - 1.0).abs() < 1e-9);
        assert_eq!(flip_mean(&img, &img, w).unwrap(), 0.0);
        assert!(ssim(&img, &shifted, w).unwrap() < 0.9);
        assert!(flip_mean(&img, &shifted, w).unwrap() > 0.05);
    }

    #[test]
    fn psnr_falls_with_noise() {
        let a = vec![100u8; 400];
        let mut b = a.clone();
        b[0] = 110;
        let db = psnr(&a, &b);
        assert!(db.is_finite() && db > 40.0, "{db}");
    }
}
