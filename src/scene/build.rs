//! Building what a scene describes: its sketch atlas (from a file or a generator), its camera
//! (checked against the ground), its procedural detail (defaults resolved from the sketch).

use super::Scene;
use crate::camera::Camera;
use crate::detail::Detail;
use crate::error::{Error, Result};
use crate::sketch::{Atlas, LoadOptions};
use glam::{DVec2, DVec3};

/// The scene's overrides for reading its sketch (and its maps).
pub fn scene_load_options(scene: &Scene) -> LoadOptions {
    let s = &scene.sketch;
    LoadOptions {
        spacing_m: s.spacing_m,
        origin_m: s.origin_m.map(DVec2::from),
        height_scale: s.height_scale,
        height_range_m: s.height_range_m,
    }
}

/// The scene's sketch atlas, from its file or synthetic generator.
pub fn load_atlas(scene: &Scene) -> Result<Atlas> {
    let mut atlas = load_sketch(scene)?;
    atlas.water_m = scene.sketch.water_level_m as f32;
    Ok(atlas)
}

fn load_sketch(scene: &Scene) -> Result<Atlas> {
    let opts = scene_load_options(scene);
    match (&scene.sketch.path, &scene.sketch.synthetic) {
        (Some(p), _) => Atlas::load(&scene.resolve(p), &opts),
        (None, Some(name)) => Atlas::synthetic(
            name,
            scene
                .sketch
                .size
                .unwrap_or(crate::sketch::synthetic::DEFAULT_SIZE),
            &opts,
        ),
        (None, None) => Err(Error::value(
            "sketch",
            "the scene has no sketch (give `path` or `synthetic`)",
        )),
    }
}

/// The scene's sun and air.
pub fn light_of(scene: &Scene) -> crate::light::Light {
    let l = &scene.light;
    let (azimuth_deg, elevation_deg) = l.sun_deg();
    crate::light::Light::new(
        azimuth_deg,
        elevation_deg,
        l.haze_visibility_km,
        l.haze_height_m,
        l.exposure_ev,
    )
}

/// The surface's height under a world position, the sketch's or the water's over it, if the
/// position is over the sketch.
pub fn ground_under(atlas: &Atlas, p: DVec2) -> Option<f64> {
    let (lo, hi) = (atlas.origin, atlas.max_corner());
    if p.x < lo.x || p.y < lo.y || p.x > hi.x || p.y > hi.y {
        return None;
    }
    let u = (p.x - atlas.origin.x) / atlas.dx;
    let v = (p.y - atlas.origin.y) / atlas.dy;
    Some((atlas.sample_texel(u, v, 0.0) as f64).max(atlas.water_m as f64))
}

/// The scene's detail parameters over `atlas`; unset octaves and amplitude follow the sketch
/// (`detail::default_octaves`, `detail::default_amplitude_m`; docs/scene.md states the rule).
pub fn detail_of(scene: &Scene, atlas: &Atlas) -> Detail {
    let d = &scene.detail;
    let d_atlas = atlas.d_atlas();
    Detail {
        octaves: d.octaves.unwrap_or_else(|| {
            crate::detail::default_octaves(
                d_atlas,
                crate::scene::FINEST_WAVELENGTH_M,
                crate::scene::MAX_OCTAVES,
            )
        }),
        amplitude_m: d.amplitude_m.unwrap_or_else(|| {
            crate::detail::default_amplitude_m(atlas.finest_relief()[0], d.gain, d_atlas)
        }),
        gain: d.gain,
        seed: d.seed,
        bias: d.bias,
        d_atlas: atlas.d_atlas(),
        // Anchored to the sketch, so the same sketch anywhere on Earth has the same detail.
        lattice_origin_m: atlas.origin,
    }
}

/// The scene's camera; the far distance defaults to the sketch's farthest corner. A camera below
/// the sketch's surface is an error: every view from there shows the underside of the ground.
pub fn camera_of(scene: &Scene, atlas: &Atlas) -> Result<Camera> {
    let c = &scene.camera;
    let eye = DVec3::from(c.position);
    if let Some(ground) = ground_under(atlas, eye.truncate())
        && eye.z < ground
    {
        return Err(Error::Camera(format!(
            "camera.position is {:.1} m below the surface (ground or water: {ground:.1} m at {:.1}, {:.1})",
            ground - eye.z,
            eye.x,
            eye.y
        )));
    }
    let far = c.far_m.unwrap_or_else(|| {
        let (lo, hi) = (atlas.origin, atlas.max_corner());
        let corners = [lo, DVec2::new(hi.x, lo.y), hi, DVec2::new(lo.x, hi.y)];
        let z = [atlas.min_m as f64, atlas.max_m as f64];
        corners
            .iter()
            .flat_map(|c| z.map(|z| (c.extend(z) - eye).length()))
            .fold(1.0, f64::max)
    });
    Camera::new(
        eye,
        DVec3::from(c.look_at),
        c.fov_y_deg,
        c.width,
        c.height,
        far,
    )
}
