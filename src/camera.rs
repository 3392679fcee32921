//! The camera and its view frustum, in f64 world metres.
//!
//! Rules: `forward`, `right`, `up` are orthonormal and right-handed with z up; a camera looking
//! straight up or down takes north (+y) as its screen's up, so no view direction is degenerate.
//! The frustum is the pyramid from the eye to the far plane (the near plane is the eye itself:
//! the footprint must not lose ground just in front of a camera 1 m above it).

use crate::error::{Error, Result};
use glam::{DVec2, DVec3};

#[derive(Clone, Debug)]
pub struct Camera {
    pub eye: DVec3,
    pub forward: DVec3,
    pub right: DVec3,
    pub up: DVec3,
    pub fov_y: f64,
    pub width: u32,
    pub height: u32,
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
    pub lat: f64,
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

    pub fn aspect(&self) -> f64 {
        self.width as f64 / self.height as f64
    }
    pub fn tan_half_y(&self) -> f64 {
        (0.5 * self.fov_y).tan()
    }
    pub fn tan_half_x(&self) -> f64 {
        self.tan_half_y() * self.aspect()
    }
    /// `f_px = (height_px / 2) / tan(fov_y / 2)`: pixels per unit of tangent.
    pub fn f_px(&self) -> f64 {
        0.5 * self.height as f64 / self.tan_half_y()
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
        let mut lo = DVec2::splat(f64::INFINITY);
        let mut hi = DVec2::splat(f64::NEG_INFINITY);
        let mut add = |p: DVec3| {
            lo = lo.min(p.truncate());
            hi = hi.max(p.truncate());
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
        (lo.x <= hi.x).then_some((lo, hi))
    }
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
