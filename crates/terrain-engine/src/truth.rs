//! Ground truth beside a snapshot: what each pixel shows, in the numbers a navigation filter, a
//! depth network or a photogrammetry pipeline reads, and the camera in the conventions their
//! tools use (the project's docs/batch.md, "Ground truth" and "Camera conventions").
//!
//! Rules:
//! - Everything comes from the frame's own view depth (the clip w every pass writes, read back by
//!   [`crate::Renderer::read_positions`]) and the camera, in f64: a pixel's world position is its
//!   centre's ray at that depth, and depth, distance, latitude and longitude and flow follow from
//!   it, so they agree with one another to rounding.
//! - Normals are the terrain function's at the pixel's position and footprint
//!   ([`crate::Ground::normal_at`]): the gradient the mesh modes and the reference shade with.
//! - Sky: depth and distance `inf`, positions 0 with w 0, normals 0, latitude and longitude NaN,
//!   flow NaN and occluded.
//! - The surface class is drawn by the GPU: the frame again in [`View::Surface`], single-sampled
//!   (a multisampled edge would blend two classes' colours), each pixel's colour read back as the
//!   nearest of the legend's; its sky from its own depth.
//! - Cameras in OpenCV's convention: x right, y down, z forward, the top-left pixel's centre at
//!   (0, 0); square pixels, the principal point at the image's centre.
//!
//! Rejected: further render targets for depth and normals. The view depth is kept already, and
//! float targets are not renderable on every adapter (wgpu's GL backend on llvmpipe).

use crate::camera::Camera;
use crate::error::{Error, Result};
use crate::gpu::uniforms::View;
use crate::query::Ground;
use crate::render::Renderer;
use crate::scene::{Mode, Msaa, Scene};
use crate::sketch::Atlas;
use glam::{DMat3, DMat4, DVec2, DVec3};

crate::names::named_enum! {
    /// What a snapshot writes beside (or as) its image (`--outputs`, the Python `outputs=`).
    pub enum Output ("output") {
        /// The picture, 8-bit RGB.
        Rgb = "rgb",
        /// Metres along the optical axis, f32; `inf` on sky.
        Depth = "depth",
        /// Metres along each pixel's ray from the eye, f32; `inf` on sky.
        Distance = "distance",
        /// World metres x, y, z, then 1 on ground and 0 on sky, f64.
        Positions = "positions",
        /// Latitude and longitude, degrees, f64, through the sketch's georeference; NaN on sky.
        Latlon = "latlon",
        /// The shaded surface's world normal, f32; 0 on sky.
        Normals = "normals",
        /// The surface class drawn per pixel, u8, [`SURFACE_CLASSES`] its legend (0 the sky).
        Surface = "surface",
        /// Optical flow to the next frame, pixels, f32 (`fly` only), with its occlusion mask.
        Flow = "flow",
    }
}

/// The outputs named in `list` (commas, spaces allowed), each once, in the order of
/// [`Output::ALL`], `rgb` always among them (the image is what the others lie beside); an unknown
/// name is an error naming the ones there are.
pub fn parse_outputs(list: &str) -> std::result::Result<Vec<Output>, String> {
    let mut wanted = vec![Output::Rgb];
    for name in list.split(',').map(str::trim).filter(|s| !s.is_empty()) {
        let o = Output::parse(name)
            .ok_or_else(|| format!("no output is called {name:?}: give {}", Output::choices()))?;
        wanted.push(o);
    }
    Ok(Output::ALL
        .iter()
        .copied()
        .filter(|o| wanted.contains(o))
        .collect())
}

/// A pinhole camera's intrinsics in pixels, OpenCV's convention (the top-left pixel's centre at
/// (0, 0)): `u = fx·x/z + cx`, `v = fy·y/z + cy` in camera axes x right, y down, z forward.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Intrinsics {
    /// Focal length along x, pixels.
    pub fx: f64,
    /// Focal length along y, pixels (equal to `fx`: square pixels).
    pub fy: f64,
    /// Principal point, x: `(width − 1) / 2`.
    pub cx: f64,
    /// Principal point, y: `(height − 1) / 2`.
    pub cy: f64,
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// The 3×3 matrix `[[fx, 0, cx], [0, fy, cy], [0, 0, 1]]`, rows.
    #[serde(rename = "K")]
    pub k: [[f64; 3]; 3],
}

impl Intrinsics {
    /// The intrinsics of `camera` at its image size.
    pub fn of(camera: &Camera) -> Intrinsics {
        let f = 0.5 * camera.height as f64 / camera.tan_half_y();
        let cx = (camera.width as f64 - 1.0) * 0.5;
        let cy = (camera.height as f64 - 1.0) * 0.5;
        Intrinsics {
            fx: f,
            fy: f,
            cx,
            cy,
            width: camera.width,
            height: camera.height,
            k: [[f, 0.0, cx], [0.0, f, cy], [0.0, 0.0, 1.0]],
        }
    }
}

/// A camera's pose as 4×4 matrices (rows), OpenCV's axes: x right, y down, z forward.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Extrinsics {
    /// World metres to camera axes: `[R | t]` with `t = −R·eye`.
    pub world_to_camera: [[f64; 4]; 4],
    /// Its inverse: the camera's axes as columns, then the eye.
    pub camera_to_world: [[f64; 4]; 4],
}

impl Extrinsics {
    /// The pose of `camera` (a planet's in its nadir's tangent frame, as its positions are).
    pub fn of(camera: &Camera) -> Extrinsics {
        let c2w = camera_to_world(camera);
        Extrinsics {
            world_to_camera: rows(c2w.inverse()),
            camera_to_world: rows(c2w),
        }
    }
}

/// Camera (OpenCV axes) to world: columns right, down, forward, eye.
pub fn camera_to_world(camera: &Camera) -> DMat4 {
    DMat4::from_cols(
        camera.right.extend(0.0),
        (-camera.up).extend(0.0),
        camera.forward.extend(0.0),
        camera.eye.extend(1.0),
    )
}

/// The rotation world to camera (OpenCV axes): rows right, down, forward.
pub fn world_to_camera_rotation(camera: &Camera) -> DMat3 {
    DMat3::from_cols(camera.right, -camera.up, camera.forward).transpose()
}

/// A matrix as its rows.
pub fn rows(m: DMat4) -> [[f64; 4]; 4] {
    let t = m.transpose();
    [
        t.x_axis.to_array(),
        t.y_axis.to_array(),
        t.z_axis.to_array(),
        t.w_axis.to_array(),
    ]
}

/// A camera's projection, made once for the many points it projects.
#[derive(Clone, Copy, Debug)]
pub struct Projection {
    k: Intrinsics,
    rotation: DMat3,
    eye: DVec3,
}

impl Projection {
    /// The projection of `camera` at its image size.
    pub fn of(camera: &Camera) -> Projection {
        Projection {
            k: Intrinsics::of(camera),
            rotation: world_to_camera_rotation(camera),
            eye: camera.eye,
        }
    }

    /// Where world point `p` lands in the image (pixels, OpenCV's convention) and its depth
    /// along the axis; `None` at or behind the eye's plane.
    pub fn point(&self, p: DVec3) -> Option<(DVec2, f64)> {
        let (k, c) = (&self.k, self.rotation * (p - self.eye));
        (c.z > 0.0).then(|| {
            let uv = DVec2::new(k.fx * c.x / c.z + k.cx, k.fy * c.y / c.z + k.cy);
            (uv, c.z)
        })
    }
}

/// A frame's pixels as world points: what every output is computed from.
#[derive(Clone, Debug)]
pub struct Truth {
    /// The camera the frame was drawn from.
    pub camera: Camera,
    /// Per pixel, row-major from the top-left: x, y, z world metres, then 1 on ground and 0 on
    /// sky (all 0 there), as `--positions` writes them.
    pub positions: Vec<f64>,
}

impl Truth {
    /// The truth of a frame from its positions as the passes leave them
    /// ([`crate::Renderer::read_positions`]: f32, relative to the camera's ground point).
    pub fn new(camera: &Camera, relative: &[[f32; 4]]) -> Result<Truth> {
        let n = camera.width as usize * camera.height as usize;
        if relative.len() != n {
            return Err(Error::Query(format!(
                "{} positions for a {}×{} frame",
                relative.len(),
                camera.width,
                camera.height
            )));
        }
        Ok(Truth {
            camera: camera.clone(),
            positions: crate::render::world_positions(relative, camera),
        })
    }

    /// Image width and height, pixels.
    pub fn size(&self) -> (usize, usize) {
        (self.camera.width as usize, self.camera.height as usize)
    }

    /// Pixel `i`'s world point, `None` on sky.
    pub fn point(&self, i: usize) -> Option<DVec3> {
        let q = &self.positions[4 * i..4 * i + 4];
        (q[3] > 0.5).then(|| DVec3::new(q[0], q[1], q[2]))
    }

    fn per_pixel<T>(&self, f: impl Fn(Option<DVec3>) -> T) -> Vec<T> {
        (0..self.positions.len() / 4)
            .map(|i| f(self.point(i)))
            .collect()
    }

    /// Metres along the optical axis per pixel; `inf` on sky.
    pub fn depth(&self) -> Vec<f32> {
        let (eye, f) = (self.camera.eye, self.camera.forward);
        self.per_pixel(|p| p.map_or(f32::INFINITY, |p| (p - eye).dot(f) as f32))
    }

    /// Metres along each pixel's ray from the eye; `inf` on sky.
    pub fn distance(&self) -> Vec<f32> {
        let eye = self.camera.eye;
        self.per_pixel(|p| p.map_or(f32::INFINITY, |p| p.distance(eye) as f32))
    }

    /// Latitude and longitude per pixel (degrees; NaN on sky) through `atlas`'s georeference;
    /// an error where it has none.
    pub fn latlon(&self, atlas: &Atlas) -> Result<Vec<f64>> {
        let Some(georef) = &atlas.georef else {
            return Err(Error::Query(
                "latlon needs a georeferenced sketch (a GeoTIFF, or a file with a .prj); this one \
                 has none"
                    .into(),
            ));
        };
        let mut out = Vec::with_capacity(self.positions.len() / 2);
        for i in 0..self.positions.len() / 4 {
            let ll = match self.point(i) {
                None => [f64::NAN; 2],
                Some(p) => {
                    let [x, y] = crate::scene::map_of_world(atlas, p.truncate())
                        .ok_or_else(|| Error::Query("latlon: no map coordinates".into()))?;
                    georef.to_lat_lon(x, y).map_err(Error::Query)?
                }
            };
            out.extend_from_slice(&ll);
        }
        Ok(out)
    }

    /// The shaded surface's world normal per pixel (x, y, z; 0 on sky): the terrain function's at
    /// the pixel's footprint, its distance times the pixel's angle.
    pub fn normals(&self, ground: &Ground) -> Result<Vec<f32>> {
        let pixel = 2.0 * self.camera.tan_half_y() / self.camera.height.max(1) as f64;
        let eye = self.camera.eye;
        let mut out = Vec::with_capacity(self.positions.len() / 4 * 3);
        for i in 0..self.positions.len() / 4 {
            let n = match self.point(i) {
                None => DVec3::ZERO,
                Some(p) => ground
                    .normal_at(p.truncate(), p.distance(eye) * pixel)?
                    .unwrap_or(DVec3::ZERO),
            };
            out.extend_from_slice(&n.as_vec3().to_array());
        }
        Ok(out)
    }

    /// Optical flow from this frame to `next` (pixels, u then v per pixel; NaN on sky) by
    /// reprojecting each pixel's world point into `next`'s camera, and whether each pixel is
    /// occluded there: behind the eye, out of the image, or behind what `next` shows at the
    /// nearest pixel (farther than [`OCCLUSION_MARGIN`] of its depth). Sky is occluded.
    pub fn flow(&self, next: &Truth) -> (Vec<f32>, Vec<bool>) {
        let (w, _) = self.size();
        let (nw, nh) = next.size();
        let next_depth = next.depth();
        let projection = Projection::of(&next.camera);
        let mut flow = Vec::with_capacity(self.positions.len() / 2);
        let mut occluded = Vec::with_capacity(self.positions.len() / 4);
        for i in 0..self.positions.len() / 4 {
            let Some(p) = self.point(i) else {
                flow.extend_from_slice(&[f32::NAN; 2]);
                occluded.push(true);
                continue;
            };
            let here = DVec2::new((i % w) as f64, (i / w) as f64);
            let Some((uv, z)) = projection.point(p) else {
                flow.extend_from_slice(&[f32::NAN; 2]);
                occluded.push(true);
                continue;
            };
            let d = uv - here;
            flow.extend_from_slice(&[d.x as f32, d.y as f32]);
            let (x, y) = (uv.x.round(), uv.y.round());
            let inside = x >= 0.0 && y >= 0.0 && x < nw as f64 && y < nh as f64;
            let hidden = !inside || {
                let seen = next_depth[y as usize * nw + x as usize] as f64;
                seen < z * (1.0 - OCCLUSION_MARGIN)
            };
            occluded.push(hidden);
        }
        (flow, occluded)
    }
}

/// How much nearer than a reprojected point the next frame may show something at its pixel
/// before the point counts as hidden: a pixel's own slope across it, at grazing views a few
/// per cent of the depth.
pub const OCCLUSION_MARGIN: f64 = 0.02;

pub use crate::surface::SURFACE_CLASSES;

/// A class's colour as the 8-bit sRGB bytes a snapshot holds.
pub fn class_srgb(class: usize) -> [u8; 3] {
    let encode = |v: f32| {
        let s = if v <= 0.003_130_8 {
            12.92 * v
        } else {
            1.055 * v.powf(1.0 / 2.4) - 0.055
        };
        (s * 255.0).round() as u8
    };
    SURFACE_CLASSES[class].1.map(encode)
}

/// A renderer of `scene`'s surface classes on `r`'s device, sketch and mode: the view
/// [`View::Surface`], single-sampled.
pub fn surface_renderer(r: &Renderer, scene: &Scene, mode: Mode) -> Result<Renderer> {
    let mut s = scene.clone();
    s.render.msaa = Msaa::Off;
    Renderer::with_context(r.ctx().clone(), &s, r.atlas().clone(), mode, View::Surface)
}

/// Each pixel's surface class (an index into [`SURFACE_CLASSES`]) from `camera`, drawn by
/// `classes` (a [`surface_renderer`]): the nearest legend colour to what it drew, the sky where
/// its depth shows none.
pub fn surface_classes(classes: &mut Renderer, camera: &Camera) -> Result<Vec<u8>> {
    classes.forget();
    let frame = classes.render_settled(camera)?;
    let relative = classes.read_positions(camera)?;
    let palette: Vec<[u8; 3]> = (0..SURFACE_CLASSES.len()).map(class_srgb).collect();
    Ok(frame
        .rgba
        .chunks_exact(4)
        .zip(&relative)
        .map(|(px, p)| {
            if p[3] < 0.5 {
                return 0;
            }
            let d = |c: &[u8; 3]| {
                (0..3)
                    .map(|k| (px[k] as i32 - c[k] as i32).pow(2))
                    .sum::<i32>()
            };
            // Ground is never the sky's class: the nearest of the rest.
            (1..palette.len())
                .min_by_key(|&k| d(&palette[k]))
                .unwrap_or(0) as u8
        })
        .collect())
}
