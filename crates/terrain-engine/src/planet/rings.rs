//! The static hemisphere of Clasen & Hege, *Terrain Rendering using Spherical Clipmaps* (2006),
//! §3.4: concentric rings around the viewer's nadir, built once.
//!
//! Rules:
//! - The bearing is cut into `phi_steps` equal steps. Level i covers angular distances θ̃ in
//!   (π/2·2^−(i+1), π/2·2^−i], cut into `rings_per_level` rings at θ̃ = π/2·2^−(i + j/m): one
//!   geometric sequence, so a ring is as far from the next as its distance times a constant and
//!   the triangles keep about one size on screen; the levels only group rings for §4.5's bounds.
//! - A frame draws the levels between the horizon's (eq. 6, from the lowest ground) and the
//!   pixel's (eq. 7–8, from the camera's height over the ground), then the fill level: a fan from
//!   the nadir to the innermost drawn ring, which §4.5 makes about a pixel wide.
//! - Every ring has the same bearings, so neighbouring rings and levels share their vertices'
//!   bearings and a level boundary has no T-junction: no crack can open there (a test walks the
//!   index buffer's edges). The bearing wraps, so there is no seam at θ̃'s zero meridian either.
//!
//! Rejected alternative: geometry clipmaps' square rings (Losasso and Hoppe). Squares on a sphere
//! shrink to slivers toward a pole (Clasen & Hege 2006, §3.1); rings around the nadir are the same
//! everywhere.

use super::hemisphere_point;
use glam::Vec4;
use std::f64::consts::{FRAC_PI_2, TAU};

/// Levels built: the innermost ring lies π/2·2^−36 ≈ 2.3e-11 rad (0.15 mm on the Earth) from the
/// nadir, finer than eq. 8 asks for a camera a metre above the ground.
pub const LEVELS: u32 = 36;

/// The hemisphere's vertices and triangles.
pub struct Rings {
    pub phi_steps: u32,
    pub rings_per_level: u32,
    /// Per vertex: (sin θ̃·sin φ̃, sin θ̃·cos φ̃, 1 − cos θ̃, θ̃); ring r's vertices are
    /// `r·phi_steps ..`, and the nadir is the last vertex.
    pub vertices: Vec<Vec4>,
    /// Quads between rings r and r+1 at `ring_indices(r)`; then one fan per level.
    pub indices: Vec<u32>,
}

/// The levels a frame draws: rings `first_ring..last_ring` and the fill inside `last_ring`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Span {
    pub first_level: u32,
    pub last_level: u32,
}

impl Rings {
    pub fn new(phi_steps: u32, rings_per_level: u32) -> Rings {
        let (n, m) = (phi_steps, rings_per_level);
        let rings = LEVELS * m + 1;
        let mut vertices = Vec::with_capacity(vertex_count(n, m) as usize);
        for r in 0..rings {
            let a = ring_angle(r, m);
            for k in 0..n {
                vertices.push(hemisphere_point(a, TAU * k as f64 / n as f64));
            }
        }
        let nadir = vertices.len() as u32;
        vertices.push(Vec4::ZERO);
        let mut indices = Vec::with_capacity(((rings - 1) * n * 6 + LEVELS * n * 3) as usize);
        for r in 0..rings - 1 {
            for k in 0..n {
                let k1 = (k + 1) % n;
                let (a, b) = (r * n + k, r * n + k1);
                let (c, d) = ((r + 1) * n + k, (r + 1) * n + k1);
                // Counter-clockwise seen from above: outer ring to inner ring, bearing growing
                // clockwise (north to east).
                indices.extend_from_slice(&[a, c, b, b, c, d]);
            }
        }
        for level in 0..LEVELS {
            let r = (level + 1) * m;
            for k in 0..n {
                indices.extend_from_slice(&[r * n + k, nadir, r * n + (k + 1) % n]);
            }
        }
        Rings {
            phi_steps: n,
            rings_per_level: m,
            vertices,
            indices,
        }
    }

    /// The index range of the quads from the outer ring of `span.first_level` to the inner ring
    /// of `span.last_level`, and that of the fan inside it.
    pub fn draw_ranges(&self, span: Span) -> [std::ops::Range<u32>; 2] {
        let (n, m) = (self.phi_steps, self.rings_per_level);
        let quads = |r: u32| r * n * 6;
        let fans = quads(LEVELS * m);
        let fan = fans + span.last_level * n * 3;
        [
            quads(span.first_level * m)..quads((span.last_level + 1) * m),
            fan..fan + n * 3,
        ]
    }

    /// The vertex range a frame computes: the drawn rings and the nadir.
    pub fn vertex_range(&self, span: Span) -> std::ops::Range<u32> {
        let (n, m) = (self.phi_steps, self.rings_per_level);
        span.first_level * m * n..((span.last_level + 1) * m + 1) * n
    }

    /// Index of the nadir vertex.
    pub fn nadir(&self) -> u32 {
        self.vertices.len() as u32 - 1
    }

    /// Triangles drawn for `span`.
    pub fn triangles(&self, span: Span) -> u64 {
        let [q, f] = self.draw_ranges(span);
        ((q.end - q.start) + (f.end - f.start)) as u64 / 3
    }
}

/// Vertices of the hemisphere of `phi_steps` bearings and `rings_per_level` rings a level.
pub fn vertex_count(phi_steps: u32, rings_per_level: u32) -> u64 {
    (LEVELS * rings_per_level + 1) as u64 * phi_steps as u64 + 1
}

/// θ̃ of ring r with m rings per level.
pub fn ring_angle(r: u32, m: u32) -> f64 {
    FRAC_PI_2 * (-(r as f64) / m as f64).exp2()
}

/// The levels a camera `height_m` above the ground at its nadir (and `above_low_m` above the
/// lowest ground, `low_to_high_m` the relief) sees on a planet of `radius` metres, for pixels of
/// `pixel_rad` radians: eq. 6 with the tangent to the lowest ground continued to the highest
/// peak beyond it (the paper's safety factor made exact), eq. 7–8 for the finest level.
pub fn visible_span(
    radius: f64,
    above_low_m: f64,
    low_to_high_m: f64,
    height_m: f64,
    pixel_rad: f64,
) -> Span {
    let low = radius;
    let eye = radius + above_low_m.max(0.0);
    let high = radius + low_to_high_m.max(0.0);
    let theta_max = ((low / eye).clamp(-1.0, 1.0)).acos() + ((low / high).clamp(-1.0, 1.0)).acos();
    let s = height_m.max(1e-3) * pixel_rad.tan();
    let theta_min = s / radius;
    let level_of =
        |theta: f64| ((FRAC_PI_2 / theta).log2().floor().max(0.0) as u32).min(LEVELS - 1);
    let first_level = if theta_max >= FRAC_PI_2 {
        0
    } else {
        level_of(theta_max)
    };
    let last_level = level_of(theta_min).max(first_level);
    Span {
        first_level,
        last_level,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashMap;

    /// Every edge inside the drawn rings and fill belongs to exactly two triangles, and the only
    /// edges with one are on the outermost drawn ring: no crack at any ring or level boundary,
    /// nor at the bearing's wrap.
    #[test]
    fn the_drawn_hemisphere_has_no_crack() {
        let rings = Rings::new(64, 4);
        for span in [
            Span {
                first_level: 0,
                last_level: 0,
            },
            Span {
                first_level: 2,
                last_level: 9,
            },
            Span {
                first_level: 30,
                last_level: 35,
            },
        ] {
            let mut edges: HashMap<(u32, u32), u32> = HashMap::new();
            let mut add = |a: u32, b: u32| *edges.entry((a.min(b), a.max(b))).or_default() += 1;
            for range in rings.draw_ranges(span) {
                for t in rings.indices[range.start as usize..range.end as usize].chunks(3) {
                    add(t[0], t[1]);
                    add(t[1], t[2]);
                    add(t[2], t[0]);
                }
            }
            let outer = span.first_level * 4;
            for (&(a, b), &count) in &edges {
                let on_rim = a / 64 == outer && b / 64 == outer;
                assert_eq!(
                    count,
                    if on_rim { 1 } else { 2 },
                    "edge {a}-{b} in {span:?}"
                );
            }
            assert_eq!(
                rings.triangles(span),
                ((span.last_level + 1 - span.first_level) * 4 * 64 * 2 + 64) as u64
            );
        }
    }

    /// Clasen & Hege 2006, §4.5: from 2 m a ground camera draws deep levels and the horizon's; from orbit
    /// only the coarse ones.
    #[test]
    fn the_visible_levels_follow_the_horizon_and_the_pixel() {
        let r = crate::sketch::EARTH_RADIUS_M;
        let px = 60f64.to_radians() / 512.0;
        let ground = visible_span(r, 2.0 + 500.0, 9000.0, 2.0, px);
        let orbit = visible_span(r, 2e7, 9000.0, 2e7, px);
        let plane = visible_span(r, 1e4, 9000.0, 1e4, px);
        assert!(
            ground.last_level >= 25 && ground.first_level >= 2,
            "{ground:?}"
        );
        assert_eq!(orbit.first_level, 0, "{orbit:?}");
        assert!(orbit.last_level <= 12, "{orbit:?}");
        assert!(
            plane.first_level < ground.last_level && plane.last_level < ground.last_level,
            "{plane:?}"
        );
    }
}
