//! Planets: the terrain function on a sphere and the geometry that carries a view to it (Clasen &
//! Hege, *Terrain Rendering using Spherical Clipmaps*, 2006).
//!
//! The terrain function of a planet of radius R at the unit vector u is `R + h(u)`, h being the
//! global sketch (equirectangular: longitude −180…180 across, latitude −90…90 up, row 0 south,
//! each texel the centre of its cell) sampled bicubically on the pyramid level of the footprint,
//! plus the procedural octaves of `noise` on the sphere of radius R, each weighted as in the
//! plane (`docs/design.md`, Procedural detail: g_k as geometry, b_k per pixel).
//!
//! Rules:
//! - World axes: x toward latitude 0, longitude 0; y toward longitude 90° E; z north. f64 on the
//!   CPU throughout.
//! - A view is anchored at the camera's nadir: the tangent frame (east, north, up) there, with its
//!   origin on the sphere of radius R. Positions handed to the GPU are metres in that frame, so
//!   they are small near the camera whatever the planet.
//! - Map coordinates of a point at angular distance a and bearing b (0 north, 90° east) from the
//!   nadir come from the spherical direct problem in a form that keeps their relative precision for
//!   small a (`map_offset`): the latitude's change by the half-angle tangent of the sines'
//!   difference, the longitude's by atan2 of the point's coordinates in the nadir's meridian plane.
//!   Clasen & Hege's equations (3)–(4) compute the absolute latitude `acos(p_z) − θ_v`, which in
//!   f32 loses everything below 1e-7 rad (0.6 m on the Earth), and its §5 replaces them near the
//!   viewer by an empirical approximation with a blend to the exact form; this form is exact at
//!   every distance, needs no blend, and its central meridian (b = 0) has a longitude offset of
//!   exactly 0 (Clasen & Hege's fig. 13 cannot happen).
//! - The sketch's texels wrap across the date line and continue across a pole on the opposite
//!   meridian (row −1 is row 0 half the world away), so the bicubic has no seam at either.
//!
//! Rejected alternative: a cube-face parametrisation of the sketch. Files come equirectangular;
//! resampling them onto six faces loses resolution at the faces' centres or doubles the texels.

pub(crate) mod noise;
pub(crate) mod rings;
pub(crate) mod synthetic;

use crate::detail::Detail;
use crate::error::Result;
use crate::sketch::Atlas;
#[cfg(test)]
use glam::Vec2;
use glam::{DVec2, DVec3, Vec4};
use std::f64::consts::{FRAC_PI_2, PI, TAU};

/// The Earth's mean radius, metres: `planet.radius_m`'s default, the one the sketch's degrees
/// are converted with.
pub use crate::sketch::EARTH_RADIUS_M;

/// A planet: its radius and its global sketch.
pub struct Planet<'a> {
    /// The sphere's radius at height 0, metres (`planet.radius_m`).
    pub radius: f64,
    /// The global sketch: equirectangular, width twice its height, row 0 south.
    pub sketch: &'a Atlas,
}

/// The unit vector at latitude `lat`, longitude `lon` (radians).
pub fn unit(lat: f64, lon: f64) -> DVec3 {
    DVec3::new(lat.cos() * lon.cos(), lat.cos() * lon.sin(), lat.sin())
}

/// Latitude and longitude (radians) of a non-zero vector.
pub fn lat_lon(p: DVec3) -> (f64, f64) {
    (p.z.atan2(p.truncate().length()), p.y.atan2(p.x))
}

/// Travel along a great circle: from latitude `lat`, longitude `lon` at `bearing` (radians, 0
/// north, π/2 east) through the angle `angle`; returns where it ends and the track's bearing
/// there (the bearing turns along a great circle unless it runs along a meridian or the
/// equator).
pub fn travel(lat: f64, lon: f64, bearing: f64, angle: f64) -> (f64, f64, f64) {
    let start = unit(lat, lon);
    let t = Tangent::at(lat, lon);
    let along = t.east * bearing.sin() + t.north * bearing.cos();
    let (s, c) = angle.sin_cos();
    let (lat2, lon2) = lat_lon(start * c + along * s);
    let track = Tangent::at(lat2, lon2).local(along * c - start * s);
    (lat2, lon2, track.x.atan2(track.y))
}

/// The tangent frame at latitude `lat`, longitude `lon`: east, north, up (world axes).
#[derive(Clone, Copy, Debug)]
pub struct Tangent {
    /// The unit vector east, in the equator's plane; at a pole it follows `lon`.
    pub east: DVec3,
    /// The unit vector north, along the meridian.
    pub north: DVec3,
    /// The unit outward normal: the point's own direction from the centre.
    pub up: DVec3,
}

impl Tangent {
    /// The frame at latitude `lat`, longitude `lon` (radians).
    pub fn at(lat: f64, lon: f64) -> Tangent {
        let (sl, cl) = lat.sin_cos();
        let (so, co) = lon.sin_cos();
        Tangent {
            east: DVec3::new(-so, co, 0.0),
            north: DVec3::new(-sl * co, -sl * so, cl),
            up: DVec3::new(cl * co, cl * so, sl),
        }
    }

    /// A world vector in this frame's (east, north, up) coordinates.
    pub fn local(&self, v: DVec3) -> DVec3 {
        DVec3::new(v.dot(self.east), v.dot(self.north), v.dot(self.up))
    }

    /// (east, north, up) coordinates as a world vector.
    pub fn world(&self, l: DVec3) -> DVec3 {
        self.east * l.x + self.north * l.y + self.up * l.z
    }
}

/// A point of the view hemisphere at angular distance `a` from the nadir and bearing `b` (0
/// north, π/2 east), as the GPU receives it: (sin a·sin b, sin a·cos b, 1 − cos a, a). The third
/// is computed as 2·sin²(a/2), which keeps its relative precision where 1 − cos a would not.
pub(crate) fn hemisphere_point(a: f64, b: f64) -> Vec4 {
    let (sa, s_half) = (a.sin(), (0.5 * a).sin());
    Vec4::new(
        (sa * b.sin()) as f32,
        (sa * b.cos()) as f32,
        (2.0 * s_half * s_half) as f32,
        a as f32,
    )
}

/// The change of latitude and longitude (radians) from the nadir at latitude with sine `s1` and
/// cosine `c1` to the hemisphere point `v` ([`hemisphere_point`]); f32, as the GPU computes it.
#[cfg(test)]
pub(crate) fn map_offset(s1: f32, c1: f32, v: Vec4) -> Vec2 {
    let (e, n, vers) = (v.x, v.y, v.z);
    // The point in the nadir meridian's frame: x toward the nadir's longitude on the equator's
    // plane, y east, z north.
    let x = c1 * (1.0 - vers) - s1 * n;
    let ds = c1 * n - s1 * vers;
    let c2 = (x * x + e * e).sqrt();
    let d_lat = 2.0 * ds.atan2(c1 + c2);
    let d_lon = e.atan2(x);
    Vec2::new(d_lat, d_lon)
}

/// The same in f64, from the angle and bearing: the CPU's reference, by rotating the vector
/// (asin of the sine of the latitude would lose it near a pole).
#[cfg(test)]
pub(crate) fn map_offset_exact(lat1: f64, a: f64, b: f64) -> DVec2 {
    let t = Tangent::at(lat1, 0.0);
    let (sa, ca) = a.sin_cos();
    let u = t.up * ca + (t.north * b.cos() + t.east * b.sin()) * sa;
    let (lat2, lon2) = lat_lon(u);
    DVec2::new(lat2 - lat1, lon2)
}

impl Planet<'_> {
    /// The sketch's cell at the equator, metres: d_atlas of the detail's octaves.
    pub fn d_atlas(&self) -> f64 {
        TAU * self.radius / self.sketch.width() as f64
    }

    /// Level-0 texel coordinates of latitude `lat`, longitude `lon`.
    pub fn texel(&self, lat: f64, lon: f64) -> DVec2 {
        let (w, h) = (self.sketch.width() as f64, self.sketch.height() as f64);
        DVec2::new((lon + PI) / TAU * w - 0.5, (lat + FRAC_PI_2) / PI * h - 0.5)
    }

    /// The sketch's height at `lat`, `lon` for a footprint of `footprint` metres: bicubic on the
    /// footprint's level (linear between two), as `sphere.wgsl`'s `planet_sketch`. Fails only
    /// where a streamed sketch's tile cannot be read.
    pub fn sketch_height(&self, lat: f64, lon: f64, footprint: f64) -> Result<f64> {
        let levels = self.usable_levels();
        let lod = (footprint.max(1e-9) / self.d_atlas())
            .log2()
            .clamp(0.0, (levels - 1) as f64);
        let l0 = lod.floor() as usize;
        let t = lod - l0 as f64;
        let uv = self.texel(lat, lon);
        let a = self.bicubic(uv, l0)?;
        if t <= 0.0 || l0 + 1 >= levels {
            return Ok(a);
        }
        Ok(a + (self.bicubic(uv, l0 + 1)? - a) * t)
    }

    /// Pyramid levels the wrap can use: those at least 4 texels wide and 2 high, with an even
    /// width (a pole's continuation is half the width away).
    pub fn usable_levels(&self) -> usize {
        self.sketch
            .levels
            .iter()
            .take_while(|l| l.width >= 4 && l.height >= 2 && l.width % 2 == 0)
            .count()
            .max(1)
    }

    /// Texel (i, j) of level `l`, across the date line and the poles: from memory, or on a level
    /// a streamed sketch leaves to the tile cache, from its tile (the last few kept decoded).
    pub fn texel_value(&self, i: i64, j: i64, l: usize) -> Result<f32> {
        let level = &self.sketch.levels[l];
        let (w, h) = (level.width as i64, level.height as i64);
        let (mut i, mut j) = (i, j);
        if j < 0 {
            j = -1 - j;
            i += w / 2;
        } else if j >= h {
            j = 2 * h - 1 - j;
            i += w / 2;
        }
        let (i, j) = (i.rem_euclid(w) as usize, j.clamp(0, h - 1) as usize);
        match &self.sketch.pyramid {
            Some(pyramid) if level.data.is_empty() => pyramid.node(l, i, j),
            _ => Ok(level.data[j * w as usize + i]),
        }
    }

    fn bicubic(&self, uv: DVec2, l: usize) -> Result<f64> {
        let weights = crate::sketch::cubic::catmull_rom;
        crate::sketch::cubic::bicubic(uv, l, (weights, weights), |i, j| self.texel_value(i, j, l))
    }

    /// The terrain function's height at `lat`, `lon` for a footprint of `footprint` metres: the
    /// sketch and every octave with its pixel share b_k (the reference's surface).
    pub fn ground(&self, detail: &Detail, lat: f64, lon: f64, footprint: f64) -> Result<f64> {
        let p = unit(lat, lon) * self.radius;
        let o_px = (detail.d_atlas / footprint.max(1e-9)).log2() as f32;
        let mut h = self.sketch_height(lat, lon, footprint)?;
        for k in 1..=detail.last_octave(o_px) {
            let b = (o_px - k as f32 + 1.0).clamp(0.0, 1.0);
            let (v, _) = noise::octave_at(
                noise::lattice_scale(detail.d_atlas, k),
                detail.octave_seed(k),
                p,
            );
            h += detail.weight(k) * (b * v) as f64;
        }
        Ok(h)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::FRAC_PI_4;

    /// North along a meridian, east along the equator, and a quarter circle east from 45° N,
    /// which meets the equator 90° east heading south-east.
    #[test]
    fn travel_follows_great_circles() {
        let close = |a: (f64, f64, f64), b: (f64, f64, f64)| {
            (a.0 - b.0).abs() < 1e-12 && (a.1 - b.1).abs() < 1e-12 && (a.2 - b.2).abs() < 1e-12
        };
        assert!(close(travel(0.0, 0.0, 0.0, 0.1), (0.1, 0.0, 0.0)));
        assert!(close(
            travel(0.0, 0.3, FRAC_PI_2, 0.2),
            (0.0, 0.5, FRAC_PI_2)
        ));
        let quarter = travel(FRAC_PI_4, 0.0, FRAC_PI_2, FRAC_PI_2);
        assert!(
            close(quarter, (0.0, FRAC_PI_2, 3.0 * FRAC_PI_4)),
            "{quarter:?}"
        );
    }

    /// The f32 offsets keep their relative precision from a millimetre to a hemisphere away, at
    /// the equator, mid latitudes and a metre from a pole; the central meridian's longitude
    /// offset is exactly 0.
    #[test]
    fn map_offsets_are_precise_at_every_distance() {
        let r = EARTH_RADIUS_M;
        for lat1 in [0.0, 0.7, -1.2, FRAC_PI_2 - 1.0 / r] {
            let (s1, c1) = (lat1.sin() as f32, lat1.cos() as f32);
            for a_m in [1e-3, 1.0, 100.0, 1e4, 1e6, 9e6] {
                let a = a_m / r;
                for b in [0.0, 0.3, 1.9, 3.0, -2.2] {
                    let got = map_offset(s1, c1, hemisphere_point(a, b));
                    let want = map_offset_exact(lat1, a, b);
                    // Compare as distances on the ground: the latitude's change, and the
                    // longitude's scaled by the cosine of the point's latitude.
                    let lat2 = lat1 + want.x;
                    let err_m = r
                        * ((got.x as f64 - want.x).powi(2)
                            + (wrap(got.y as f64 - want.y) * lat2.cos()).powi(2))
                        .sqrt();
                    assert!(
                        err_m <= 1e-5 * a_m.max(1.0) + 1e-3,
                        "lat {lat1} a {a_m} m b {b}: {got} vs {want} ({err_m} m)"
                    );
                    if b == 0.0 && lat1 + a < FRAC_PI_2 {
                        assert_eq!(got.y, 0.0, "central meridian moved at {a_m} m");
                    }
                }
            }
        }
    }

    fn wrap(a: f64) -> f64 {
        (a + PI).rem_euclid(TAU) - PI
    }

    fn sketch() -> Atlas {
        synthetic::planet_sketch(256, EARTH_RADIUS_M, 7)
    }

    /// No seam at the date line or across a pole: the sketch's bicubic is continuous there.
    #[test]
    fn the_sketch_has_no_seam_at_the_date_line_or_the_poles() {
        let sketch = sketch();
        let p = Planet {
            radius: EARTH_RADIUS_M,
            sketch: &sketch,
        };
        let e = 1e-9;
        for lat in [-1.0, 0.0, 0.4, 1.3] {
            let a = p.sketch_height(lat, PI - e, 0.0).unwrap();
            let b = p.sketch_height(lat, -PI + e, 0.0).unwrap();
            assert!((a - b).abs() < 1e-3, "date line at {lat}: {a} vs {b}");
        }
        for lon in [0.0, 1.0, -2.5] {
            // Crossing the north pole along a meridian: the height moves on smoothly.
            let before = p.sketch_height(FRAC_PI_2 - 1e-6, lon, 0.0).unwrap();
            let at = p.sketch_height(FRAC_PI_2, lon, 0.0).unwrap();
            let other = p.sketch_height(FRAC_PI_2 - 1e-6, lon + PI, 0.0).unwrap();
            assert!(
                (before - at).abs() < 0.1 && (other - at).abs() < 0.1,
                "pole: {before} {at} {other}"
            );
            // At a pole itself the rows of every meridian meet: the height there differs by
            // meridian by no more than the last row's own spread.
            let row = &p.sketch.levels[0].data[..p.sketch.width()];
            let spread = row.iter().cloned().fold(f32::MIN, f32::max)
                - row.iter().cloned().fold(f32::MAX, f32::min);
            let south = p.sketch_height(-FRAC_PI_2, lon, 0.0).unwrap();
            let south_other = p.sketch_height(-FRAC_PI_2, lon + 2.0, 0.0).unwrap();
            assert!(
                (south - south_other).abs() <= spread as f64,
                "south pole: {south} vs {south_other}"
            );
        }
    }

    #[test]
    fn tangent_frames_are_orthonormal_and_right_handed() {
        for (lat, lon) in [(0.0, 0.0), (0.5, -2.0), (FRAC_PI_2, 1.0), (-FRAC_PI_2, 0.3)] {
            let t = Tangent::at(lat, lon);
            assert!((t.east.cross(t.north) - t.up).length() < 1e-12);
            assert!((t.up - unit(lat, lon)).length() < 1e-12);
            let (la, lo) = lat_lon(t.up);
            if lat.abs() < 1.5 {
                assert!((la - lat).abs() < 1e-12 && (lo - lon).abs() < 1e-12);
            }
        }
    }
}
