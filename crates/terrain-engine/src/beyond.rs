//! Beyond the sketch: the ground `sketch.outside` puts around it, joined to the sketch without a
//! seam. The WGSL twin is `beyond_ground` in `shaders/shared/surface.wgsl`.
//!
//! Rules:
//! - A point p off the sketch's rectangle, at distance d from its nearest point c on the edge,
//!   lies in the *margin* while d < M. There the ground is the edge's height e = s(c) (the sketch
//!   at c, at the caller's footprint or d/2, the larger, so the edge's profile blurs outward
//!   instead of streaking across the margin) continued along the edge's outward slope
//!   g = ∇s(c)·(p − c)/d and faded to the level L beyond:
//!   `L + (e − L)·w(d/M) + g·d·(1 − d/M)³`, with `w(t) = 1 − t²(3 − 2t)`,
//!   clamped to the heights the sketch and L span. At d = 0 it is the sketch's height and slope;
//!   at d = M the level's, flat: the terrain function is continuous in height and slope.
//! - The octaves continue into the margin, weighted by w: at the edge they are the sketch's own.
//! - L is the plain's height (the mean of the sketch's edge nodes) for `plain`, and for `ocean` a
//!   sea floor below the water's surface (a tenth of the sketch's relief, at least 1 m, under it),
//!   so land at the edge runs down into the sea within the margin. Water covers what lies below
//!   its surface, as on the sketch.
//! - M is twice the sketch's relief, within an eighth and a half of its shorter side: the fade's
//!   steepest slope, 1.5·|e − L|/M, stays under 0.75, and a flat sketch still gets a margin in
//!   proportion to its size.
//!
//! Rejected: extending the atlas itself by the margin. Every mode would draw it for free, but the
//! sketch's size, the framing, the streamed pyramid and every figure measured over the sketch
//! would then include ground the user never gave.

use crate::scene::Outside;
use crate::sketch::Atlas;
use glam::DVec2;

/// The ground beyond a sketch.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Beyond {
    /// What lies there.
    pub outside: Outside,
    /// The level the margin fades to: the plain's height, or the sea floor, metres.
    pub level_m: f64,
    /// The margin's width, metres.
    pub margin_m: f64,
    /// The lowest and highest the margin's ground may reach: the sketch's and the level's span.
    pub span_m: [f64; 2],
}

impl Beyond {
    /// The ground `outside` puts beyond `atlas`.
    pub fn new(atlas: &Atlas, outside: Outside) -> Beyond {
        let (lo, hi) = (atlas.min_m as f64, atlas.max_m as f64);
        let relief = (hi - lo).max(0.0);
        let water = atlas.water_m as f64;
        let level_m = match outside {
            Outside::Ocean => water - (0.1 * relief).max(1.0),
            _ => atlas.edge_mean_m as f64,
        };
        let extent = atlas.max_corner() - atlas.origin;
        let side = extent.x.min(extent.y).max(atlas.d_atlas());
        Beyond {
            outside,
            level_m,
            margin_m: (2.0 * relief).clamp(side / 8.0, side / 2.0),
            span_m: [lo.min(level_m), hi.max(level_m)],
        }
    }

    /// Whether ground at or under `atlas`'s water level can show: the sketch dipping to it, or
    /// the ground beyond reaching it (the sea, or a plain at or under it).
    pub fn meets_water(&self, atlas: &Atlas) -> bool {
        let water = atlas.water_m as f64;
        atlas.min_m as f64 <= water || (self.outside != Outside::Void && self.level_m <= water)
    }

    /// The margin's fade at distance `d` beyond the edge: 1 at the edge, 0 from `margin_m` on,
    /// with no slope at either end.
    pub fn fade(&self, d: f64) -> f64 {
        let t = (d / self.margin_m).clamp(0.0, 1.0);
        1.0 - t * t * (3.0 - 2.0 * t)
    }

    /// The ground (before the octaves and the water) at distance `d` beyond an edge point whose
    /// height is `edge_m` and whose outward slope is `slope`.
    pub fn ground(&self, edge_m: f64, slope: f64, d: f64) -> f64 {
        if d >= self.margin_m {
            return self.level_m;
        }
        let u = (1.0 - d / self.margin_m).powi(3);
        let h = self.level_m + (edge_m - self.level_m) * self.fade(d) + slope * d * u;
        h.clamp(self.span_m[0], self.span_m[1])
    }
}

/// The sketch's rectangle, `lo`…`hi`: the nearest point of it to `p`, and the distance.
pub fn nearest_on(lo: DVec2, hi: DVec2, p: DVec2) -> (DVec2, f64) {
    let c = p.clamp(lo, hi);
    (c, (p - c).length())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn beyond() -> Beyond {
        Beyond {
            outside: Outside::Plain,
            level_m: 100.0,
            margin_m: 1000.0,
            span_m: [0.0, 500.0],
        }
    }

    #[test]
    fn the_margin_starts_at_the_edge_height_and_slope_and_ends_flat_at_the_level() {
        let b = beyond();
        let (e, g) = (400.0, -0.3);
        assert!((b.ground(e, g, 0.0) - e).abs() < 1e-12);
        let h = 1e-4;
        let slope0 = (b.ground(e, g, h) - b.ground(e, g, 0.0)) / h;
        assert!((slope0 - g).abs() < 1e-3, "{slope0}");
        assert_eq!(b.ground(e, g, 1000.0), 100.0);
        assert_eq!(b.ground(e, g, 5000.0), 100.0);
        let slope_m = (b.ground(e, g, 1000.0) - b.ground(e, g, 1000.0 - h)) / h;
        assert!(slope_m.abs() < 1e-3, "{slope_m}");
    }

    #[test]
    fn the_margin_never_leaves_the_span_of_the_sketch_and_the_level() {
        let b = beyond();
        for d in [0.0, 50.0, 200.0, 600.0] {
            let up = b.ground(490.0, 20.0, d);
            let down = b.ground(10.0, -20.0, d);
            assert!(up <= 500.0 && down >= 0.0, "{up} {down}");
        }
    }

    /// A level sketch of `width` × `height` nodes 10 m apart, at 0 m.
    fn level_atlas(width: usize, height: usize) -> Atlas {
        let raw = crate::sketch::RawGrid {
            width,
            height,
            dx: 10.0,
            dy: 10.0,
            data: vec![0.0; width * height],
            georef: None,
        };
        Atlas::from_raw(raw, &crate::sketch::LoadOptions::default()).unwrap()
    }

    #[test]
    fn the_margin_is_twice_the_relief_within_an_eighth_and_a_half_of_the_side() {
        let mut atlas = level_atlas(101, 51);
        atlas.max_m = 10.0;
        // Sides 1000 × 500 m: relief 10 m gives an eighth of 500 m.
        assert_eq!(Beyond::new(&atlas, Outside::Plain).margin_m, 62.5);
        atlas.max_m = 100.0;
        assert_eq!(Beyond::new(&atlas, Outside::Plain).margin_m, 200.0);
        atlas.max_m = 1000.0;
        assert_eq!(Beyond::new(&atlas, Outside::Plain).margin_m, 250.0);
        // The sea floor lies under the water.
        let sea = Beyond::new(&atlas, Outside::Ocean);
        assert!(sea.level_m < atlas.water_m as f64);
    }

    #[test]
    fn water_shows_where_the_sketch_or_the_ground_beyond_meets_its_level() {
        let mut atlas = level_atlas(11, 11);
        let meets = |atlas: &Atlas, outside| Beyond::new(atlas, outside).meets_water(atlas);
        (atlas.min_m, atlas.max_m, atlas.edge_mean_m, atlas.water_m) = (248.0, 1069.0, 400.0, 0.0);
        assert!(!meets(&atlas, Outside::Plain) && !meets(&atlas, Outside::Void));
        assert!(meets(&atlas, Outside::Ocean), "the sea beyond");
        atlas.edge_mean_m = -3.0;
        assert!(meets(&atlas, Outside::Plain), "a plain under the water");
        assert!(!meets(&atlas, Outside::Void), "nothing beyond");
        atlas.water_m = 420.0;
        assert!(meets(&atlas, Outside::Void), "the sketch flooded");
    }
}
