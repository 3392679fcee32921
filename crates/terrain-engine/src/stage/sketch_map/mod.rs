//! The sketch map: the square region of the atlas that encloses the view frustum's footprint,
//! resampled to n² (128² in the paper) from the atlas's mip pyramid.
//!
//! Rules:
//! - The footprint is the frustum (to the far distance) cut by the slab of the sketch's heights,
//!   widened by the procedural detail's reach, then clipped to the atlas.
//! - The spacing `d0` is `d_atlas · 2^(q/4)` for a whole q, and the region's corner is a whole
//!   multiple of `d0` from the atlas origin (along the turned axes for a turned region, below). So every sample lies on a lattice fixed in the world:
//!   moving the camera shifts which lattice points are taken, never where they are, and the sketch
//!   map does not swim. It changes only when q does, in steps of 19 %.
//! - With nothing in view the region is the whole atlas and [`SketchMap::visible`] is false.
//! - Asked to hold (`warp.hold`), the region keeps its corner while that corner, at the spacing the
//!   footprint asks for, still encloses the footprint; the heights are then not resampled. A
//!   region that follows the footprint's centre moves every d0 of flight and redoes the warp.
//!
//! - The region's axes follow the view's heading in steps of 45° ([`Turn`]): where the heading
//!   lies within 15° of a diagonal (`stage::heading_of`), the region is a square turned by 45°, so that its t axis
//!   (the warp's second pass, which the guard may send to one shared mapping) runs along the
//!   view's depth, as it does for a view looking north (`stage::warp`'s rule on orientation). A
//!   turned region's spacing is `d0` too, and its texels are the points of the world lattice of
//!   spacing `d0/√2` whose lattice coordinates (from the atlas origin) sum to an even number: a
//!   lattice fixed in the world as the axis-aligned one is, so a turned sketch map does not swim
//!   either. Its heights are resampled along the rows of that finer lattice
//!   (`resample_runs`), with the taps and the levels of the axis-aligned map's spacing.
//!
//! Rejected alternative: the exact bounding square, resampled anew each frame. Its samples slide
//! over the atlas as the camera moves, and the terrain's silhouette wobbles with them. Also
//! rejected: a region turned to the exact heading. Its lattice would turn with the camera, and
//! every sample would slide as the view turns.

mod resample;

pub use resample::{Resampler, resample};

use crate::camera::Camera;
use crate::sketch::Atlas;
use glam::DVec2;

/// How the region's axes lie in the world. Region-local coordinates (u, v) are metres along its
/// s and t axes from texel (0, 0); Φ is in them.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Turn {
    /// s along x, t along y.
    #[default]
    None,
    /// Turned 45° clockwise: t along (1, 1)/√2, for headings north-east and south-west.
    NorthEast,
    /// Turned 45° counter-clockwise: t along (−1, 1)/√2, for headings north-west and south-east.
    NorthWest,
}

impl Turn {
    /// The region's s and t axes as unit vectors in the world (a right-handed pair).
    pub fn axes(self) -> (DVec2, DVec2) {
        let h = std::f64::consts::FRAC_1_SQRT_2;
        match self {
            Turn::None => (DVec2::X, DVec2::Y),
            Turn::NorthEast => (DVec2::new(h, -h), DVec2::new(h, h)),
            Turn::NorthWest => (DVec2::new(h, h), DVec2::new(-h, h)),
        }
    }

    /// A turned region's steps along s and t on the world lattice of spacing `d0/√2`, in its
    /// units; `None` for an axis-aligned region.
    pub(super) fn lattice_steps(self) -> Option<([i64; 2], [i64; 2])> {
        match self {
            Turn::None => None,
            Turn::NorthEast => Some(([1, -1], [1, 1])),
            Turn::NorthWest => Some(([1, 1], [-1, 1])),
        }
    }

    /// World point `w` in the turn's frame: its coordinates along the s and t axes (the world's
    /// own, unchanged, for an axis-aligned region).
    pub fn frame(self, w: DVec2) -> DVec2 {
        match self {
            Turn::None => w,
            _ => {
                let (s, t) = self.axes();
                DVec2::new(w.dot(s), w.dot(t))
            }
        }
    }

    /// Frame coordinates back to the world ([`Turn::frame`]'s inverse).
    pub fn world(self, f: DVec2) -> DVec2 {
        match self {
            Turn::None => f,
            _ => {
                let (s, t) = self.axes();
                s * f.x + t * f.y
            }
        }
    }
}

#[derive(Clone, Debug)]
pub struct SketchMap {
    pub n: usize,
    /// World position of texel (0, 0), the region's corner: its south-west, or for a turned
    /// region its west vertex (`Turn::NorthEast`) or its south vertex (`Turn::NorthWest`).
    pub origin: DVec2,
    /// The region's axes.
    pub turn: Turn,
    /// `d0`: metres between texels.
    pub spacing: f64,
    /// Heights, row-major, row 0 through the corner along s (south for an axis-aligned region).
    pub heights: Vec<f32>,
    /// Whether any of the atlas is in view.
    pub visible: bool,
    resampler: Resampler,
    /// The footprint's box in the turn's frame ([`Turn::frame`]; the world for an axis-aligned
    /// region), clipped to the atlas's box there, when visible.
    pub footprint: Option<(DVec2, DVec2)>,
    /// Whether `heights` hold the region's samples (false until the first update, and forgotten).
    sampled: bool,
}

impl SketchMap {
    pub fn new(n: usize) -> SketchMap {
        SketchMap {
            n,
            origin: DVec2::ZERO,
            turn: Turn::None,
            spacing: 1.0,
            heights: vec![0.0; n * n],
            visible: false,
            footprint: None,
            resampler: Resampler::default(),
            sampled: false,
        }
    }

    /// Forgets the region, so the next update chooses it afresh.
    pub fn forget(&mut self) {
        self.sampled = false;
    }

    /// Side of the region in metres.
    pub fn extent(&self) -> f64 {
        (self.n - 1) as f64 * self.spacing
    }

    /// Chooses the region for `camera`, with its axes turned by `turn`, and resamples the atlas
    /// into it; allocates nothing. `reach_m`: how far procedural detail can lift or sink the
    /// surface. With `hold`, the last region is kept while it still serves (and has the same
    /// turn); returns whether the region changed.
    pub fn update(
        &mut self,
        atlas: &Atlas,
        camera: &Camera,
        reach_m: f64,
        hold: bool,
        turn: Turn,
    ) -> bool {
        let z_lo = atlas.min_m as f64 - reach_m;
        let z_hi = atlas.max_m as f64 + reach_m;
        let (a_lo, a_hi) = atlas_box(atlas, turn);
        let (s, t) = turn.axes();
        let clipped = match turn {
            Turn::None => camera
                .footprint(z_lo, z_hi)
                .map(|(lo, hi)| (lo.max(a_lo), hi.min(a_hi))),
            // Against a turned region the atlas is a diamond: the footprint is clipped to it
            // first (its box clipped to the diamond's box would be up to twice as wide).
            _ => camera.footprint_over(z_lo, z_hi, (atlas.origin, atlas.max_corner()), s, t),
        }
        .filter(|(lo, hi)| lo.x <= hi.x && lo.y <= hi.y);
        self.visible = clipped.is_some();
        self.footprint = clipped;
        let (lo, hi) = clipped.unwrap_or((a_lo, a_hi));
        let before = (self.origin, self.spacing, self.turn);
        let keep = hold && self.sampled && turn == self.turn;
        self.turn = turn;
        self.choose_region(atlas, lo, hi, keep);
        if self.sampled && before == (self.origin, self.spacing, self.turn) {
            return false;
        }
        self.sampled = true;
        let (mut heights, mut resampler) = (
            std::mem::take(&mut self.heights),
            std::mem::take(&mut self.resampler),
        );
        self.resample_into(atlas, &mut heights, &mut resampler);
        (self.heights, self.resampler) = (heights, resampler);
        true
    }

    /// Samples `atlas` (the sketch, or any grid over it) on this region's texels into `out`.
    pub fn resample_into(&self, atlas: &Atlas, out: &mut [f32], r: &mut Resampler) {
        resample(atlas, self.origin, self.spacing, self.turn, self.n, out, r);
    }

    /// The region for the footprint [lo, hi] (in the turn's frame); with `keep`, the current
    /// corner if it still serves.
    fn choose_region(&mut self, atlas: &Atlas, lo: DVec2, hi: DVec2, keep: bool) {
        let d_atlas = atlas.d_atlas();
        let n = self.n as f64;
        // Two texels of slack, so that snapping the corner down never uncovers the footprint.
        let side = (hi - lo).max_element().max(8.0 * d_atlas);
        let q = (4.0 * (side / ((n - 3.0).max(1.0) * d_atlas)).log2()).ceil();
        let d0 = d_atlas * (q / 4.0).exp2();
        let full = (n - 1.0) * d0;
        let turn = self.turn;
        if keep && d0 == self.spacing {
            let c = turn.frame(self.origin);
            let end = c + DVec2::splat(full);
            if c.x <= lo.x && c.y <= lo.y && end.x >= hi.x && end.y >= hi.y {
                return;
            }
        }
        let centre = 0.5 * (lo + hi);
        // The lattice's origin, the atlas's corner, in the turn's frame: whole multiples of d0
        // from it lie on the world lattice (for a turned region, on its even points).
        let o = turn.frame(atlas.origin);
        let snap = |w: f64, o: f64| ((w - o) / d0).floor() * d0 + o;
        let (a_lo, a_hi) = atlas_box(atlas, turn);
        let mut corner = DVec2::ZERO;
        for axis in 0..2 {
            let mut c = centre[axis] - 0.5 * full;
            // Inside the atlas where the atlas is wider than the region.
            if a_hi[axis] - a_lo[axis] >= full {
                c = c.clamp(a_lo[axis], a_hi[axis] - full);
            }
            // Any corner in [hi − full + d0, lo] still covers the footprint after snapping down.
            c = c.clamp(hi[axis] - full + d0, lo[axis]);
            corner[axis] = snap(c, o[axis]);
        }
        self.origin = match turn.lattice_steps() {
            None => corner,
            // From whole steps, so that the corner is a lattice point to the last bit.
            Some((a, b)) => {
                let (i, j) = (
                    ((corner.x - o.x) / d0).round(),
                    ((corner.y - o.y) / d0).round(),
                );
                let d_b = d0 * std::f64::consts::FRAC_1_SQRT_2;
                let step = DVec2::new(
                    i * a[0] as f64 + j * b[0] as f64,
                    i * a[1] as f64 + j * b[1] as f64,
                );
                atlas.origin + step * d_b
            }
        };
        self.spacing = d0;
    }

    /// World position of region-local point `p` (metres along the region's s and t axes).
    pub fn world(&self, p: DVec2) -> DVec2 {
        self.origin + self.turn.world(p)
    }

    /// Region-local coordinates of world point `w` ([`SketchMap::world`]'s inverse).
    pub fn local(&self, w: DVec2) -> DVec2 {
        self.turn.frame(w - self.origin)
    }

    /// World position of texel (i, j).
    pub fn texel_world(&self, i: usize, j: usize) -> DVec2 {
        self.world(DVec2::new(i as f64, j as f64) * self.spacing)
    }
}

/// The atlas's bounding box in `turn`'s frame (the atlas itself for an axis-aligned region).
fn atlas_box(atlas: &Atlas, turn: Turn) -> (DVec2, DVec2) {
    let (a, b) = (atlas.origin, atlas.max_corner());
    [a, DVec2::new(b.x, a.y), b, DVec2::new(a.x, b.y)]
        .map(|c| turn.frame(c))
        .iter()
        .fold(
            (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)),
            |(lo, hi), &c| (lo.min(c), hi.max(c)),
        )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sketch::LoadOptions;
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
            map.update(&atlas, &cam, 50.0, false, Turn::None);
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

    /// A turned region's heights are the atlas's trilinear sample at each texel's world
    /// position (`Atlas::sample_texel` at the region's level), on both turns, with the region
    /// partly off the atlas (clamped as the axis-aligned map clamps); and its texels are points
    /// of the world lattice of spacing d0/√2 whose coordinates sum to an even number.
    #[test]
    fn a_turned_region_samples_the_atlas_at_its_texels() {
        let atlas = hills();
        for turn in [Turn::NorthEast, Turn::NorthWest] {
            for (eye, at) in [
                (
                    DVec3::new(1000.0, 500.0, 760.0),
                    DVec3::new(6000.0, 6000.0, 400.0),
                ),
                (
                    DVec3::new(6500.0, 900.0, 900.0),
                    DVec3::new(1500.0, 5000.0, 300.0),
                ),
                (
                    DVec3::new(3000.0, 3000.0, 6000.0),
                    DVec3::new(3500.0, 3600.0, 0.0),
                ),
            ] {
                let cam = Camera::new(eye, at, 60.0, 512, 512, 9000.0).unwrap();
                let mut map = SketchMap::new(37);
                map.update(&atlas, &cam, 50.0, false, turn);
                let lod = (map.spacing / atlas.d_atlas()).log2();
                let d_b = map.spacing * std::f64::consts::FRAC_1_SQRT_2;
                for j in 0..map.n {
                    for i in 0..map.n {
                        let w = map.texel_world(i, j);
                        let u = (w.x - atlas.origin.x) / atlas.dx;
                        let v = (w.y - atlas.origin.y) / atlas.dy;
                        let want = atlas.sample_texel(u, v, lod);
                        let got = map.heights[j * map.n + i];
                        let at = format!("{turn:?} texel ({i}, {j}) at {w}");
                        assert!(
                            (got - want).abs() <= 1e-3 * want.abs().max(1.0),
                            "{at}: {got} against {want}"
                        );
                        let k = (w - atlas.origin) / d_b;
                        assert!(
                            (k - k.round()).abs().max_element() < 1e-6,
                            "{at}: off the lattice"
                        );
                        assert_eq!((k.x.round() + k.y.round()).rem_euclid(2.0), 0.0, "{at}");
                    }
                }
                // Its footprint, in the turn's frame, lies inside the region.
                let (lo, hi) = map.footprint.unwrap();
                let c = turn.frame(map.origin);
                let end = c + DVec2::splat(map.extent());
                assert!(
                    c.x <= lo.x + 1e-6 && c.y <= lo.y + 1e-6,
                    "{turn:?}: {c} against {lo}"
                );
                assert!(end.x + 1e-6 >= hi.x && end.y + 1e-6 >= hi.y, "{turn:?}");
            }
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
        map.update(&atlas, &cam, 50.0, false, Turn::None);
        assert!(!map.visible);
        assert!(map.extent() >= 256.0 * 30.0);
    }
}
