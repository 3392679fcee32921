//! Temporal artifacts along a camera path: the change of a frame that the camera's motion does
//! not explain. GeoMipMap's level switches show as popping, the warped mesh sliding over the
//! terrain as swimming.
//!
//! Rules: at frame t the mode first draws camera t with the level of detail it chose for frame
//! t − 1 (GeoMipMap: the previous block levels and morph factors; warped: the previous sketch map
//! and Φ, the CPU stage frozen), then updates it for camera t and draws again. Both images show
//! the same camera, so their difference is the level-of-detail update alone: the mean absolute
//! difference over RGB in 8-bit levels, and the share of pixels that change by more than
//! [`VISIBLE_LEVELS`]. Brute force, which has no level of detail, scores exactly zero: the
//! control.
//!
//! Rejected alternative: reprojecting frame t − 1's error image (mode − reference) into frame t
//! through the reference's positions and differencing: its floor from resampling the per-pixel
//! detail's error swamps what it is to find (docs/decisions.md, “LOD change between frames”).

/// A change a viewer sees on a still image: 2 % of the 8-bit range.
pub const VISIBLE_LEVELS: u8 = 5;

#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct LodChange {
    /// Mean absolute difference over pixels and RGB, 8-bit levels.
    pub mean_levels: f64,
    /// Share of pixels with a channel changed by more than [`VISIBLE_LEVELS`].
    pub changed_share: f64,
}

/// The change from `held` (the previous level of detail) to `updated`, both RGBA8 of one camera.
pub fn lod_change(held: &[u8], updated: &[u8]) -> LodChange {
    assert_eq!(held.len(), updated.len(), "images of different sizes");
    let (mut sum, mut changed) = (0u64, 0usize);
    for (a, b) in held.chunks_exact(4).zip(updated.chunks_exact(4)) {
        let d = [0, 1, 2].map(|c| a[c].abs_diff(b[c]));
        sum += d.iter().map(|&v| v as u64).sum::<u64>();
        changed += usize::from(d.iter().any(|&v| v > VISIBLE_LEVELS));
    }
    let pixels = (held.len() / 4).max(1) as f64;
    LodChange {
        mean_levels: sum as f64 / (3.0 * pixels),
        changed_share: changed as f64 / pixels,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn no_update_scores_zero_and_a_pop_scores_its_size() {
        let img: Vec<u8> = (0..64 * 4).map(|k| (k * 7 % 256) as u8).collect();
        assert_eq!(lod_change(&img, &img), LodChange::default());
        let mut popped = img.clone();
        for px in popped.chunks_exact_mut(4).take(16) {
            for c in &mut px[..3] {
                *c = c.wrapping_add(30);
            }
        }
        let change = lod_change(&img, &popped);
        assert!((change.changed_share - 0.25).abs() < 1e-12, "{change:?}");
        assert!(change.mean_levels > 0.0, "{change:?}");
    }
}
