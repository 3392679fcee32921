//! The CPU stage of a frame: sketch map → importance map → row and column warp → Φ.
//!
//! [`CpuStage`] owns every buffer the stage needs, sized once for the scene's `warp.size`, so a
//! frame allocates nothing; its three parts are timed separately.

use crate::atlas::{Atlas, LoadOptions};
use crate::camera::Camera;
use crate::detail::Detail;
use crate::error::{Error, Result};
use crate::importance::{ImportanceMap, ImportanceParams};
use crate::scene::Scene;
use crate::sketch_map::{Resampler, SketchMap, resample};
use crate::warp::Warp;
use glam::{DVec2, DVec3};
use std::time::Instant;

/// Microseconds spent in each part of the stage.
#[derive(Clone, Copy, Debug, Default, serde::Serialize)]
pub struct StageTimes {
    pub sketch_map_us: f64,
    pub importance_us: f64,
    pub warp_us: f64,
}

impl StageTimes {
    pub fn total_us(&self) -> f64 {
        self.sketch_map_us + self.importance_us + self.warp_us
    }
}

pub struct CpuStage {
    pub sketch_map: SketchMap,
    pub importance: ImportanceMap,
    pub warp: Warp,
    pub params: ImportanceParams,
    /// I_s as an atlas-like grid, when the scene gives a map.
    surface_max_atlas: Option<Atlas>,
    surface_max: Vec<f32>,
    surface_resampler: Resampler,
    /// The ground position of the camera of the last run (for figures).
    pub last_eye: DVec2,
}

impl CpuStage {
    pub fn new(scene: &Scene, detail: &Detail) -> Result<CpuStage> {
        let n = scene.warp.size as usize;
        let imp = &scene.importance;
        let surface_max_atlas = match &imp.max_map {
            Some(p) => Some(Atlas::load(&scene.resolve(p), &scene_load_options(scene))?),
            None => None,
        };
        Ok(CpuStage {
            sketch_map: SketchMap::new(n),
            importance: ImportanceMap::new(n),
            warp: Warp::new(n, scene.warp.method, scene.warp.max_log2_step as f32),
            params: ImportanceParams {
                quad_px: scene.warp.quad_px,
                view: imp.view,
                frustum: imp.frustum,
                backface: imp.backface,
                max_per_m: imp.max_per_m,
                floor: imp.floor,
                backface_floor: imp.backface_floor,
                reach_m: detail.reach_m(),
            },
            surface_max: if surface_max_atlas.is_some() {
                vec![0.0; n * n]
            } else {
                Vec::new()
            },
            surface_max_atlas,
            surface_resampler: Resampler::default(),
            last_eye: DVec2::ZERO,
        })
    }

    /// Runs the stage for `camera`; Φ is then in `self.warp.phi`, relative to `sketch_map.origin`.
    pub fn run(&mut self, atlas: &Atlas, camera: &Camera) -> StageTimes {
        let t0 = Instant::now();
        self.last_eye = camera.eye.truncate();
        self.sketch_map.update(atlas, camera, self.params.reach_m);
        let n = self.sketch_map.n;
        if let Some(m) = &self.surface_max_atlas {
            let map = &self.sketch_map;
            resample(
                m,
                map.origin,
                map.spacing,
                n,
                &mut self.surface_max,
                &mut self.surface_resampler,
            );
        }
        let t1 = Instant::now();
        let bounds = (atlas.origin, atlas.max_corner());
        let surface = self
            .surface_max_atlas
            .as_ref()
            .map(|_| self.surface_max.as_slice());
        self.importance
            .update(&self.sketch_map, bounds, camera, surface, &self.params);
        let t2 = Instant::now();
        self.warp
            .run(&self.importance.importance, self.sketch_map.spacing as f32);
        let t3 = Instant::now();
        let us = |a: Instant, b: Instant| (b - a).as_secs_f64() * 1e6;
        StageTimes {
            sketch_map_us: us(t0, t1),
            importance_us: us(t1, t2),
            warp_us: us(t2, t3),
        }
    }

    /// Φ(s, t) in world metres (f64).
    pub fn phi_world(&self, s: usize, t: usize) -> DVec2 {
        let p = self.warp.phi[t * self.sketch_map.n + s];
        self.sketch_map.origin + DVec2::new(p[0] as f64, p[1] as f64)
    }
}

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
    let opts = scene_load_options(scene);
    match (&scene.sketch.path, &scene.sketch.synthetic) {
        (Some(p), _) => Atlas::load(&scene.resolve(p), &opts),
        (None, Some(name)) => Atlas::synthetic(
            name,
            scene
                .sketch
                .size
                .unwrap_or(crate::atlas::synthetic::DEFAULT_SIZE),
            &opts,
        ),
        (None, None) => Err(Error::Invalid("scene has no sketch".into())),
    }
}

/// The sketch's height under a world position, if the position is over the sketch.
pub fn ground_under(atlas: &Atlas, p: DVec2) -> Option<f64> {
    let (lo, hi) = (atlas.origin, atlas.max_corner());
    if p.x < lo.x || p.y < lo.y || p.x > hi.x || p.y > hi.y {
        return None;
    }
    let u = (p.x - atlas.origin.x) / atlas.dx;
    let v = (p.y - atlas.origin.y) / atlas.dy;
    Some(atlas.sample_texel(u, v, 0.0) as f64)
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
            "camera.position is {:.1} m below the ground ({ground:.1} m at {:.1}, {:.1})",
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
