//! The camera and its view frustum, in f64 world metres.
//!
//! Rules: `forward`, `right`, `up` are orthonormal and right-handed with z up; a camera looking
//! straight up or down takes north (+y) as its screen's up, so no view direction is degenerate.
//! The frustum is the pyramid from the eye to the far plane (the near plane is the eye itself:
//! the footprint must not lose ground just in front of a camera 1 m above it).

use crate::error::{Error, Result};
use glam::{DVec2, DVec3};

/// A pinhole camera: where the eye stands, where it looks, and the image it takes.
///
/// ```
/// use glam::DVec3;
/// use terrain::Camera;
///
/// // 100 m up, looking north and down at a point 1 km away.
/// let (eye, look_at) = (DVec3::new(0.0, 0.0, 100.0), DVec3::new(0.0, 1000.0, 0.0));
/// let cam = Camera::new(eye, look_at, 60.0, 640, 480, 5000.0)?;
/// assert!((cam.forward.length() - 1.0).abs() < 1e-12);
/// assert!(cam.right.x > 0.99, "north-facing: right is east");
/// assert!((cam.f_px() - 240.0 / 30f64.to_radians().tan()).abs() < 1e-9);
/// # Ok::<(), terrain::Error>(())
/// ```
#[derive(Clone, Debug)]
pub struct Camera {
    /// The eye, world metres (x east, y north, z up).
    pub eye: DVec3,
    /// The unit view direction.
    pub forward: DVec3,
    /// The unit vector toward the image's right edge, horizontal unless the view is vertical.
    pub right: DVec3,
    /// The unit vector toward the image's top edge, `right × forward`.
    pub up: DVec3,
    /// The vertical field of view, radians (the scene gives `camera.fov_y_deg`, default 60°).
    pub fov_y: f64,
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// The far clipping distance, metres (`camera.far_m`; by default the sketch's farthest corner).
    pub far: f64,
    /// The near plane, metres. With reversed-Z and an infinite far plane depth precision does
    /// not suffer from a small one on an adapter with a 0..1 clip range; where the driver maps
    /// depth through −1..1 (wgpu's GL backend on llvmpipe) `0.5 + 0.5·near/w` rounds to 0.5 for
    /// `w` beyond about 10⁶ near planes, so a planet's camera moves it out with its height.
    pub near: f64,
    /// A planet's camera: where it stands. Its `eye` and directions are then in the nadir's
    /// tangent frame (x east, y north, z up), from the sphere's point under it.
    pub geo: Option<Geo>,
}

/// Where a planet's camera stands: the latitude and longitude of its nadir (radians, f64).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Geo {
    /// Latitude of the nadir, radians, north positive, in [−π/2, π/2].
    pub lat: f64,
    /// Longitude of the nadir, radians, east positive.
    pub lon: f64,
}

/// A plane `n·p + d ≥ 0` inside; `n` is a unit vector, so the left side is a distance in metres.
/// The near plane of a planar camera, metres.
pub const NEAR_M: f64 = 0.05;

#[derive(Clone, Copy, Debug)]
pub struct Plane {
    pub n: DVec3,
    pub d: f64,
}

impl Plane {
    pub fn distance(&self, p: DVec3) -> f64 {
        self.n.dot(p) + self.d
    }
}

impl Camera {
    /// A camera at `eye` looking at `look_at` (world metres), with a vertical field of view of
    /// `fov_y_deg` degrees, an image of `width`×`height` pixels and its far plane at `far`
    /// metres. Fails with [`Error::Camera`] where a value is not finite, `look_at` coincides with
    /// `eye`, the field of view lies outside (0, 180), the image is empty or `far` not positive.
    pub fn new(
        eye: DVec3,
        look_at: DVec3,
        fov_y_deg: f64,
        width: u32,
        height: u32,
        far: f64,
    ) -> Result<Camera> {
        let all = [eye.to_array(), look_at.to_array()].concat();
        if all.iter().any(|v| !v.is_finite()) {
            return Err(Error::Camera(format!(
                "position {eye} or look_at {look_at} is not finite"
            )));
        }
        let dir = look_at - eye;
        if dir.length() < 1e-9 * (1.0 + eye.length()) {
            return Err(Error::Camera("look_at coincides with position".into()));
        }
        if !(fov_y_deg > 0.0 && fov_y_deg < 180.0) {
            return Err(Error::Camera(format!(
                "fov_y_deg {fov_y_deg} outside (0, 180)"
            )));
        }
        if width == 0 || height == 0 {
            return Err(Error::Camera(format!(
                "image size {width}×{height} is empty"
            )));
        }
        if !(far.is_finite() && far > 0.0) {
            return Err(Error::Camera(format!("far distance {far} is not positive")));
        }
        let forward = dir.normalize();
        let right = match forward.cross(DVec3::Z).try_normalize() {
            Some(r) if forward.z.abs() < 1.0 - 1e-9 => r,
            _ => forward.cross(DVec3::Y).normalize(),
        };
        let up = right.cross(forward);
        Ok(Camera {
            eye,
            forward,
            right,
            up,
            fov_y: fov_y_deg.to_radians(),
            width,
            height,
            far,
            near: NEAR_M,
            geo: None,
        })
    }

    /// Width over height of the image.
    pub fn aspect(&self) -> f64 {
        self.width as f64 / self.height as f64
    }
    /// `tan(fov_y / 2)`: the image's half height at unit distance.
    pub fn tan_half_y(&self) -> f64 {
        (0.5 * self.fov_y).tan()
    }
    /// `tan(fov_x / 2)`: the image's half width at unit distance.
    pub fn tan_half_x(&self) -> f64 {
        self.tan_half_y() * self.aspect()
    }
    /// `f_px = (height_px / 2) / tan(fov_y / 2)`: pixels per unit of tangent.
    pub fn f_px(&self) -> f64 {
        0.5 * self.height as f64 / self.tan_half_y()
    }

    /// The direction from the eye through `pixel`, scaled to 1 along `forward`. `pixel` is in
    /// pixels from the image's top-left corner, x right and y down; pixel (i, j)'s centre is
    /// (i + ½, j + ½). With `ndc = (2·x/width − 1, 1 − 2·y/height)` it is
    /// `forward + ndc.x·tan(fov_x/2)·right + ndc.y·tan(fov_y/2)·up`.
    pub fn pixel_ray(&self, pixel: DVec2) -> DVec3 {
        let ndc_x = 2.0 * pixel.x / self.width as f64 - 1.0;
        let ndc_y = 1.0 - 2.0 * pixel.y / self.height as f64;
        self.forward
            + self.right * (ndc_x * self.tan_half_x())
            + self.up * (ndc_y * self.tan_half_y())
    }

    /// The point seen at `pixel` (as [`Camera::pixel_ray`] places it) at reversed-Z `depth`, the
    /// depth the terrain writes: `depth = near / w` with `w` the distance along `forward`, so the
    /// point is `eye + (near / depth)·pixel_ray(pixel)`, in the camera's world metres (a
    /// planet camera's: its tangent frame). `None` for depth 0 (sky: reversed-Z's infinitely
    /// far plane) or anything but a depth in (0, 1].
    ///
    /// ```
    /// use glam::{DVec2, DVec3};
    /// use terrain::Camera;
    ///
    /// let cam = Camera::new(DVec3::new(0.0, 0.0, 100.0), DVec3::new(0.0, 1000.0, 0.0), 60.0, 640, 480, 5000.0)?;
    /// let centre = DVec2::new(320.0, 240.0);
    /// let p = cam.unproject(centre, cam.near / 500.0).unwrap();
    /// assert!((p - (cam.eye + cam.forward * 500.0)).length() < 1e-9);
    /// assert_eq!(cam.unproject(centre, 0.0), None);
    /// # Ok::<(), terrain::Error>(())
    /// ```
    pub fn unproject(&self, pixel: DVec2, depth: f64) -> Option<DVec3> {
        if !(depth > 0.0 && depth <= 1.0 && pixel.is_finite()) {
            return None;
        }
        Some(self.eye + self.pixel_ray(pixel) * (self.near / depth))
    }

    /// The four side planes (through the eye) and the far plane, inward normals.
    pub fn planes(&self) -> [Plane; 5] {
        let (tx, ty) = (self.tan_half_x(), self.tan_half_y());
        let side = |n: DVec3| {
            let n = n.normalize();
            Plane {
                n,
                d: -n.dot(self.eye),
            }
        };
        [
            side(self.forward * tx + self.right),
            side(self.forward * tx - self.right),
            side(self.forward * ty + self.up),
            side(self.forward * ty - self.up),
            Plane {
                n: -self.forward,
                d: self.forward.dot(self.eye) + self.far,
            },
        ]
    }

    /// The far rectangle's corners.
    fn far_corners(&self) -> [DVec3; 4] {
        let (tx, ty) = (self.tan_half_x(), self.tan_half_y());
        let c = self.eye + self.forward * self.far;
        let (r, u) = (self.right * tx * self.far, self.up * ty * self.far);
        [c - r - u, c + r - u, c + r + u, c - r + u]
    }

    /// The xy bounding box of the frustum's part between heights `z_lo` and `z_hi`, or `None` when
    /// the frustum does not reach that slab (looking at the sky from above the terrain).
    ///
    /// The vertices of (pyramid ∩ slab) are the pyramid's vertices inside the slab and its edges'
    /// crossings of the slab's two planes; their box is the footprint's box.
    pub fn footprint(&self, z_lo: f64, z_hi: f64) -> Option<(DVec2, DVec2)> {
        self.footprint_along(z_lo, z_hi, DVec2::X, DVec2::Y)
    }

    /// [`Camera::footprint`]'s box along the unit axes `s` and `t` instead of x and y: each
    /// vertex's coordinates `(p·s, p·t)`. Along x and y, exactly `footprint`'s.
    fn footprint_along(&self, z_lo: f64, z_hi: f64, s: DVec2, t: DVec2) -> Option<(DVec2, DVec2)> {
        let (points, k) = self.footprint_points(z_lo, z_hi);
        box_along(&points[..k], s, t)
    }

    /// The footprint's part over the rectangle `[lo, hi]` (the atlas), its box along the unit
    /// axes `s` and `t`; `None` where they do not meet. For a region turned against the
    /// rectangle, the box of the footprint clipped to the rectangle is much smaller than the
    /// footprint's box clipped to the rectangle's box.
    pub fn footprint_over(
        &self,
        z_lo: f64,
        z_hi: f64,
        (lo, hi): (DVec2, DVec2),
        s: DVec2,
        t: DVec2,
    ) -> Option<(DVec2, DVec2)> {
        let (points, k) = self.footprint_points(z_lo, z_hi);
        let (mut poly, mut m) = convex_hull(&points[..k]);
        // Sutherland–Hodgman against the rectangle's four sides: (axis, bound, keep below).
        for (axis, bound, below) in [
            (0, lo.x, false),
            (0, hi.x, true),
            (1, lo.y, false),
            (1, hi.y, true),
        ] {
            let inside = |p: DVec2| {
                if below {
                    p[axis] <= bound
                } else {
                    p[axis] >= bound
                }
            };
            let mut out = [DVec2::ZERO; CLIPPED];
            let mut count = 0;
            // A convex polygon gains at most one vertex a side, so this never drops one; it
            // bounds what a hull made of points past f64's range could hold.
            let mut push = |p: DVec2| {
                if count < CLIPPED {
                    out[count] = p;
                    count += 1;
                }
            };
            for i in 0..m {
                let (a, b) = (poly[i], poly[(i + 1) % m]);
                if inside(a) {
                    push(a);
                }
                if inside(a) != inside(b) {
                    let f = (bound - a[axis]) / (b[axis] - a[axis]);
                    push(a + (b - a) * f);
                }
            }
            (poly, m) = (out, count);
        }
        box_along(&poly[..m], s, t)
    }

    /// The vertices of (pyramid ∩ slab), in xy: the eye and far corners inside the slab, and the
    /// edges' crossings of its two planes (at most 5 + 8·2).
    fn footprint_points(&self, z_lo: f64, z_hi: f64) -> ([DVec2; POINTS], usize) {
        let far = self.far_corners();
        let vertices = [self.eye, far[0], far[1], far[2], far[3]];
        let edges = [
            (0, 1),
            (0, 2),
            (0, 3),
            (0, 4),
            (1, 2),
            (2, 3),
            (3, 4),
            (4, 1),
        ];
        let mut points = [DVec2::ZERO; POINTS];
        let mut k = 0;
        let mut add = |p: DVec3| {
            points[k] = p.truncate();
            k += 1;
        };
        for v in vertices {
            if (z_lo..=z_hi).contains(&v.z) {
                add(v);
            }
        }
        for (a, b) in edges {
            let (pa, pb) = (vertices[a], vertices[b]);
            for z in [z_lo, z_hi] {
                let (da, db) = (pa.z - z, pb.z - z);
                if da * db < 0.0 {
                    add(pa + (pb - pa) * (da / (da - db)));
                }
            }
        }
        (points, k)
    }
}

/// The most vertices of the footprint ([`Camera::footprint_points`]).
const POINTS: usize = 21;
/// The most vertices of its hull clipped by a rectangle: one more per side.
const CLIPPED: usize = POINTS + 4;

/// The box of `points` along the unit axes `s` and `t`: `(p·s, p·t)`; `None` for no points.
fn box_along(points: &[DVec2], s: DVec2, t: DVec2) -> Option<(DVec2, DVec2)> {
    let mut lo = DVec2::splat(f64::INFINITY);
    let mut hi = DVec2::splat(f64::NEG_INFINITY);
    for p in points {
        let f = DVec2::new(p.dot(s), p.dot(t));
        lo = lo.min(f);
        hi = hi.max(f);
    }
    (lo.x <= hi.x).then_some((lo, hi))
}

/// The convex hull of `points` counter-clockwise (Andrew's monotone chain), without allocating.
fn convex_hull(points: &[DVec2]) -> ([DVec2; CLIPPED], usize) {
    // Finite points only, so that every turn's sign is a number (a valid camera's always are).
    let mut sorted = [DVec2::ZERO; POINTS];
    let mut k = 0;
    for p in points.iter().filter(|p| p.is_finite()).take(POINTS) {
        sorted[k] = *p;
        k += 1;
    }
    let sorted = &mut sorted[..k];
    sorted.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    let mut hull = [DVec2::ZERO; CLIPPED];
    if k < 3 {
        hull[..k].copy_from_slice(sorted);
        return (hull, k);
    }
    let cross = |o: DVec2, a: DVec2, b: DVec2| (a - o).perp_dot(b - o);
    let mut m = 0;
    // Each chain holds at most k points, so the hull at most k + 1 before the last is dropped;
    // the bound on m only guards against a turn that overflows to NaN.
    for &p in sorted.iter() {
        while m >= 2 && cross(hull[m - 2], hull[m - 1], p) <= 0.0 {
            m -= 1;
        }
        if m < CLIPPED {
            hull[m] = p;
            m += 1;
        }
    }
    let lower = m + 1;
    for &p in sorted.iter().rev().skip(1) {
        while m >= lower && cross(hull[m - 2], hull[m - 1], p) <= 0.0 {
            m -= 1;
        }
        if m < CLIPPED {
            hull[m] = p;
            m += 1;
        }
    }
    // The last point is the first again.
    (hull, m - 1)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cam(eye: DVec3, at: DVec3) -> Camera {
        Camera::new(eye, at, 60.0, 512, 512, 10_000.0).unwrap()
    }

    #[test]
    fn basis_is_orthonormal_even_straight_down() {
        for at in [
            DVec3::new(10.0, 5.0, 0.0),
            DVec3::new(0.0, 0.0, -5.0),
            DVec3::new(0.0, 0.0, 9.0),
        ] {
            let c = cam(DVec3::new(0.0, 0.0, 1.0), at);
            for v in [c.forward, c.right, c.up] {
                assert!((v.length() - 1.0).abs() < 1e-12);
            }
            assert!(c.forward.dot(c.right).abs() < 1e-12 && c.forward.dot(c.up).abs() < 1e-12);
        }
    }

    #[test]
    fn planes_contain_the_view_axis_and_exclude_behind() {
        let c = cam(DVec3::new(0.0, 0.0, 100.0), DVec3::new(0.0, 1000.0, 0.0));
        let ahead = c.eye + c.forward * 500.0;
        let behind = c.eye - c.forward * 500.0;
        assert!(c.planes().iter().all(|p| p.distance(ahead) > 0.0));
        assert!(c.planes().iter().any(|p| p.distance(behind) < 0.0));
    }

    /// The footprint clipped to a rectangle: over a rectangle that holds it all, its own box
    /// (to rounding); over a smaller one, a box inside both the footprint's and the rectangle's,
    /// and along turned axes smaller than the footprint's box clipped to the rectangle's box.
    #[test]
    fn footprint_over_a_rectangle_clips_the_footprint_itself() {
        let c = cam(
            DVec3::new(1000.0, 500.0, 800.0),
            DVec3::new(6000.0, 6000.0, 300.0),
        );
        let h = std::f64::consts::FRAC_1_SQRT_2;
        let (s, t) = (DVec2::new(h, -h), DVec2::new(h, h));
        let whole = (DVec2::splat(-1e6), DVec2::splat(1e6));
        for (s, t) in [(DVec2::X, DVec2::Y), (s, t)] {
            let (lo, hi) = c.footprint_along(0.0, 600.0, s, t).unwrap();
            let (a, b) = c.footprint_over(0.0, 600.0, whole, s, t).unwrap();
            assert!((a - lo).abs().max_element() < 1e-6 && (b - hi).abs().max_element() < 1e-6);
        }
        let rect = (DVec2::ZERO, DVec2::splat(7680.0));
        let (lo, hi) = c.footprint_over(0.0, 600.0, rect, s, t).unwrap();
        let (f_lo, f_hi) = c.footprint_along(0.0, 600.0, s, t).unwrap();
        // The rectangle's corners along the axes.
        let corners = [0.0, 7680.0].map(|x| [0.0, 7680.0].map(|y| DVec2::new(x, y)));
        let along = corners
            .as_flattened()
            .iter()
            .map(|p| DVec2::new(p.dot(s), p.dot(t)));
        let (r_lo, r_hi) = along.fold((DVec2::splat(1e9), DVec2::splat(-1e9)), |(a, b), p| {
            (a.min(p), b.max(p))
        });
        let eps = 1e-6;
        assert!(lo.cmpge(f_lo.max(r_lo) - eps).all() && hi.cmple(f_hi.min(r_hi) + eps).all());
        let (b_lo, b_hi) = (f_lo.max(r_lo), f_hi.min(r_hi));
        assert!(
            (hi - lo).max_element() < 0.9 * (b_hi - b_lo).max_element(),
            "clipped {lo} {hi}, box clipped {b_lo} {b_hi}"
        );
        // Beside the rectangle, nothing.
        let away = (DVec2::splat(-9000.0), DVec2::splat(-8000.0));
        assert!(c.footprint_over(0.0, 600.0, away, s, t).is_none());
    }

    #[test]
    fn footprint_straight_down_is_centred_and_sky_view_is_empty() {
        let c = cam(
            DVec3::new(500.0, 500.0, 1000.0),
            DVec3::new(500.0, 500.0, 0.0),
        );
        let (lo, hi) = c.footprint(0.0, 10.0).unwrap();
        let half = 1000.0 * (30f64).to_radians().tan();
        assert!((lo.x - (500.0 - half)).abs() < 1.0 && (hi.y - (500.0 + half)).abs() < 1.0);
        let sky = cam(DVec3::new(0.0, 0.0, 1000.0), DVec3::new(0.0, 0.0, 2000.0));
        assert!(sky.footprint(0.0, 500.0).is_none());
    }

    #[test]
    fn impossible_cameras_are_errors() {
        let e = DVec3::new(0.0, 0.0, 1.0);
        assert!(Camera::new(e, e, 60.0, 8, 8, 1.0).is_err());
        assert!(Camera::new(DVec3::NAN, e, 60.0, 8, 8, 1.0).is_err());
        assert!(Camera::new(e, DVec3::ZERO, 0.0, 8, 8, 1.0).is_err());
        assert!(Camera::new(e, DVec3::ZERO, 60.0, 0, 8, 1.0).is_err());
    }
}
