//! The sketch map: the square region of the atlas that encloses the view frustum's footprint,
//! resampled to n² (128² in the paper) from the atlas's mip pyramid.
//!
//! Rules:
//! - The footprint is the frustum (to the far distance) cut by the slab of the sketch's heights,
//!   widened by the procedural detail's reach, then clipped to the atlas.
//! - The spacing `d0` is `d_atlas · 2^(q/4)` for a whole q, and the region's corner is a whole
//!   multiple of `d0` from the atlas origin. So every sample lies on a lattice fixed in the world:
//!   moving the camera shifts which lattice points are taken, never where they are, and the sketch
//!   map does not swim. It changes only when q does, in steps of 19 %.
//! - With nothing in view the region is the whole atlas and [`SketchMap::visible`] is false.
//!
//! Rejected alternative: the exact bounding square, resampled anew each frame. Its samples slide
//! over the atlas as the camera moves, and the terrain's silhouette wobbles with them.

use crate::atlas::Atlas;
use crate::camera::Camera;
use glam::DVec2;

#[derive(Clone, Debug)]
pub struct SketchMap {
    pub n: usize,
    /// World position of texel (0, 0), the region's south-west corner.
    pub origin: DVec2,
    /// `d0`: metres between texels.
    pub spacing: f64,
    /// Heights, row-major, row 0 south.
    pub heights: Vec<f32>,
    /// Whether any of the atlas is in view.
    pub visible: bool,
    /// The footprint's box (world), clipped to the atlas, when visible.
    pub footprint: Option<(DVec2, DVec2)>,
}

impl SketchMap {
    pub fn new(n: usize) -> SketchMap {
        SketchMap {
            n,
            origin: DVec2::ZERO,
            spacing: 1.0,
            heights: vec![0.0; n * n],
            visible: false,
            footprint: None,
        }
    }

    /// Side of the region in metres.
    pub fn extent(&self) -> f64 {
        (self.n - 1) as f64 * self.spacing
    }

    /// Chooses the region for `camera` and resamples the atlas into it; allocates nothing.
    /// `reach_m`: how far procedural detail can lift or sink the surface.
    pub fn update(&mut self, atlas: &Atlas, camera: &Camera, reach_m: f64) {
        let z_lo = atlas.min_m as f64 - reach_m;
        let z_hi = atlas.max_m as f64 + reach_m;
        let (a_lo, a_hi) = (atlas.origin, atlas.max_corner());
        let clipped = camera
            .footprint(z_lo, z_hi)
            .map(|(lo, hi)| (lo.max(a_lo), hi.min(a_hi)))
            .filter(|(lo, hi)| lo.x <= hi.x && lo.y <= hi.y);
        self.visible = clipped.is_some();
        self.footprint = clipped;
        let (lo, hi) = clipped.unwrap_or((a_lo, a_hi));
        self.choose_region(atlas, lo, hi);
        resample(atlas, self.origin, self.spacing, self.n, &mut self.heights);
    }

    fn choose_region(&mut self, atlas: &Atlas, lo: DVec2, hi: DVec2) {
        let d_atlas = atlas.d_atlas();
        let n = self.n as f64;
        // Two texels of slack, so that snapping the corner down never uncovers the footprint.
        let side = (hi - lo).max_element().max(8.0 * d_atlas);
        let q = (4.0 * (side / ((n - 3.0).max(1.0) * d_atlas)).log2()).ceil();
        let d0 = d_atlas * (q / 4.0).exp2();
        let full = (n - 1.0) * d0;
        let centre = 0.5 * (lo + hi);
        let snap = |w: f64, o: f64| ((w - o) / d0).floor() * d0 + o;
        let mut corner = DVec2::new(
            snap(centre.x - 0.5 * full, atlas.origin.x),
            snap(centre.y - 0.5 * full, atlas.origin.y),
        );
        // Keep the region inside the atlas where the atlas is wider than the region.
        let a_hi = atlas.max_corner();
        for axis in 0..2 {
            let last = snap(a_hi[axis] - full, atlas.origin[axis]);
            if last >= atlas.origin[axis] {
                corner[axis] = corner[axis].clamp(atlas.origin[axis], last);
            }
        }
        self.origin = corner;
        self.spacing = d0;
    }

    /// World position of texel (i, j).
    pub fn texel_world(&self, i: usize, j: usize) -> DVec2 {
        self.origin + DVec2::new(i as f64, j as f64) * self.spacing
    }
}

/// Samples `atlas` on the n² lattice `origin + (i, j)·spacing` at the matching mip level.
pub fn resample(atlas: &Atlas, origin: DVec2, spacing: f64, n: usize, out: &mut [f32]) {
    let lod = (spacing / atlas.d_atlas()).log2();
    let u0 = (origin.x - atlas.origin.x) / atlas.dx;
    let v0 = (origin.y - atlas.origin.y) / atlas.dy;
    let (du, dv) = (spacing / atlas.dx, spacing / atlas.dy);
    for j in 0..n {
        let v = v0 + j as f64 * dv;
        let row = &mut out[j * n..(j + 1) * n];
        for (i, h) in row.iter_mut().enumerate() {
            *h = atlas.sample_texel(u0 + i as f64 * du, v, lod);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::atlas::LoadOptions;
    use glam::DVec3;

    fn hills() -> Atlas {
        Atlas::synthetic("hills", 257, &LoadOptions::default()).unwrap()
    }

    #[test]
    fn region_encloses_the_footprint_and_snaps_to_a_fixed_lattice() {
        let atlas = hills();
        let mut map = SketchMap::new(128);
        for dx in [0.0, 3.7, 11.2] {
            let eye = DVec3::new(2000.0 + dx, 1500.0, 900.0);
            let cam = Camera::new(
                eye,
                DVec3::new(4000.0 + dx, 5000.0, 300.0),
                60.0,
                512,
                512,
                6000.0,
            )
            .unwrap();
            map.update(&atlas, &cam, 50.0);
            let (lo, hi) = map.footprint.unwrap();
            let end = map.origin + DVec2::splat(map.extent());
            assert!(map.origin.x <= lo.x && map.origin.y <= lo.y && end.x >= hi.x && end.y >= hi.y);
            let k = (map.origin - atlas.origin) / map.spacing;
            assert!(
                (k - k.round()).abs().max_element() < 1e-9,
                "corner off lattice: {k}"
            );
            let q = 4.0 * (map.spacing / atlas.d_atlas()).log2();
            assert!((q - q.round()).abs() < 1e-9);
        }
    }

    #[test]
    fn sky_view_takes_the_whole_atlas_and_is_not_visible() {
        let atlas = hills();
        let cam = Camera::new(
            DVec3::new(100.0, 100.0, 5000.0),
            DVec3::new(100.0, 100.0, 9000.0),
            60.0,
            64,
            64,
            1e5,
        )
        .unwrap();
        let mut map = SketchMap::new(128);
        map.update(&atlas, &cam, 50.0);
        assert!(!map.visible);
        assert!(map.extent() >= 256.0 * 30.0);
    }
}
