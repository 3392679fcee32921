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
        stream_cpu_bytes: Some((scene.stream.cpu_mb * 1048576.0) as u64),
    }
}

/// The tile cache's budgets from `[stream]`.
pub(crate) fn stream_config(scene: &Scene) -> crate::gpu::stream::StreamConfig {
    let s = &scene.stream;
    crate::gpu::stream::StreamConfig {
        gpu_bytes: (s.gpu_mb * 1048576.0) as u64,
        loads_per_frame: s.loads_per_frame as usize,
        fade_frames: s.fade_frames,
        threads: s.threads as usize,
    }
}

/// The scene's sketch atlas, from its file or synthetic generator. What the sketch and the
/// scene's places leave in doubt ([`warnings`]) goes to the `log` crate as warnings once the
/// sketch is read: every command reads its scene's sketch here, and a file that fails to read
/// gets its error alone.
pub fn load_atlas(scene: &Scene) -> Result<Atlas> {
    let mut atlas = load_sketch(scene)?;
    atlas.water_m = scene.sketch.water_level_m as f32;
    for line in warnings(scene, &atlas) {
        log::warn!("{line}");
    }
    Ok(atlas)
}

/// The scene's sketch from its file's bytes, read as [`load_atlas`] reads the file (a page
/// fetches them; a browser has no file system). A synthetic sketch ignores `bytes`; a planet's
/// global file and a tile pyramid are refused (they are read from disk).
pub fn load_atlas_from(scene: &Scene, bytes: &[u8]) -> Result<Atlas> {
    let mut atlas = match (&scene.sketch.path, scene.planet()) {
        (Some(p), None) => Atlas::from_bytes(p, bytes, &scene_load_options(scene))?,
        (Some(_), Some(_)) => {
            return Err(Error::value(
                "sketch.path",
                "a planet's global sketch is read from a file, not from bytes",
            ));
        }
        (None, _) => load_sketch(scene)?,
    };
    atlas.water_m = scene.sketch.water_level_m as f32;
    Ok(atlas)
}

/// What the scene's sketch file took on trust (`sketch::warnings`) and the scene's places that
/// lie far off the sketch (`scene::off_map_warnings`), one line each; nothing for a planet,
/// whose sketch is global and whose places are latitudes and longitudes.
pub fn warnings(scene: &Scene, atlas: &Atlas) -> Vec<String> {
    if scene.planet().is_some() {
        return Vec::new();
    }
    let mut lines = match &scene.sketch.path {
        Some(p) => crate::sketch::warnings(
            &scene.resolve(p),
            &scene_load_options(scene),
            &atlas.extent(),
        ),
        None => Vec::new(),
    };
    lines.extend(super::place::off_map_warnings(scene, atlas));
    lines
}

fn load_sketch(scene: &Scene) -> Result<Atlas> {
    let opts = scene_load_options(scene);
    if let Some(planet) = scene.planet() {
        return load_global(scene, planet.radius_m);
    }
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

/// A planet's global sketch: the synthetic planet, or a file whose georeference spans longitude
/// −180…180 and latitude −90…90 in degrees (cells, or nodes at the cells' centres).
fn load_global(scene: &Scene, radius: f64) -> Result<Atlas> {
    let s = &scene.sketch;
    let width = s.size.unwrap_or(crate::planet::synthetic::DEFAULT_WIDTH);
    let Some(path) = &s.path else {
        return Ok(crate::planet::synthetic::planet_sketch(
            width,
            radius,
            scene.detail.seed,
        ));
    };
    let path = scene.resolve(path);
    let mut atlas = Atlas::load(&path, &scene_load_options(scene))?;
    let global = |g: &crate::sketch::georef::Georef| {
        let (w, h) = (atlas.width() as f64, atlas.height() as f64);
        let close = |a: f64, b: f64| (a - b).abs() < 1e-6 * 360.0;
        matches!(g.units, crate::sketch::georef::Units::Degrees)
            && close(g.cell_x * w, 360.0)
            && close(g.cell_y * h, 180.0)
            && close(g.west - 0.5 * g.cell_x, -180.0)
            && close(g.south - 0.5 * g.cell_y, -90.0)
    };
    match &atlas.georef {
        Some(g) if global(g) && atlas.width() % 2 == 0 => {}
        _ => {
            return Err(Error::sketch(
                &path,
                "a planet's sketch must be a global grid: geographic degrees spanning longitude \
                 −180…180 and latitude −90…90 by cells (an even number of columns)",
            ));
        }
    }
    // Metres per cell at the equator: the detail's d_atlas.
    let cell = std::f64::consts::TAU * radius / atlas.width() as f64;
    atlas.dx = cell;
    atlas.dy = cell;
    Ok(atlas)
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

/// The surface's height under a world position, the sketch's at its own spacing (read from the
/// tile for a streamed sketch) or the water's over it, if the position is over the sketch.
pub fn ground_under(atlas: &Atlas, p: DVec2) -> Result<Option<f64>> {
    let (lo, hi) = (atlas.origin, atlas.max_corner());
    if p.x < lo.x || p.y < lo.y || p.x > hi.x || p.y > hi.y {
        return Ok(None);
    }
    let u = (p.x - atlas.origin.x) / atlas.dx;
    let v = (p.y - atlas.origin.y) / atlas.dy;
    Ok(Some(
        (atlas.ground_texel(u, v)? as f64).max(atlas.water_m as f64),
    ))
}

/// The scene's detail parameters over `atlas` in its own `render.mode` ([`detail_for`]).
pub fn detail_of(scene: &Scene, atlas: &Atlas) -> Detail {
    detail_for(scene, atlas, scene.render.mode)
}

/// The scene's detail parameters over `atlas` drawn in `mode`; unset octaves and amplitude follow
/// the sketch (`detail::default_octaves`, `detail::default_amplitude_m`), an unset bias the mode
/// (`scene::default_bias`), never the sketch's storage; docs/scene.md states the rules.
pub fn detail_for(scene: &Scene, atlas: &Atlas, mode: super::Mode) -> Detail {
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
        bias: d
            .bias
            .unwrap_or_else(|| crate::scene::default_bias(scene, atlas, mode)),
        d_atlas: atlas.d_atlas(),
        // Anchored to the sketch, so the same sketch anywhere on Earth has the same detail.
        lattice_origin_m: atlas.origin,
    }
}

/// The scene's camera (placed and aimed by `scene::place`); the far distance defaults to the
/// sketch's farthest corner. A camera below the sketch's surface is an error: every view from
/// there shows the underside of the ground.
pub fn camera_of(scene: &Scene, atlas: &Atlas) -> Result<Camera> {
    if let Some(planet) = scene.planet() {
        return planet_camera(scene, atlas, planet.radius_m);
    }
    let c = &scene.camera;
    let (eye, target) = super::place::pose(scene, atlas)?;
    if let Some(ground) = ground_under(atlas, eye.truncate())?
        && eye.z < ground
    {
        let why = format!(
            "camera.position is {:.1} m below the surface (ground or water: {ground:.1} m at {:.1}, {:.1})",
            ground - eye.z,
            eye.x,
            eye.y
        );
        return Err(match &scene.source {
            Some(path) => Error::scene(path, why),
            None => Error::Camera(why),
        });
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
    Camera::new(eye, target, c.fov_y_deg, c.width, c.height, far)
}

/// A planet's camera: `altitude_m` above the ground at its nadir (the terrain function with
/// every octave), looking along `heading_deg` and `pitch_deg`; its eye in the nadir's tangent
/// frame, from the sphere of the planet's radius. The far distance reaches past the horizon to
/// the highest ground beyond it.
fn planet_camera(scene: &Scene, atlas: &Atlas, radius: f64) -> Result<Camera> {
    let c = &scene.camera;
    let (lat, lon) = (
        c.lat_deg.unwrap_or(0.0).to_radians(),
        c.lon_deg.unwrap_or(0.0).to_radians(),
    );
    let detail = detail_of(scene, atlas);
    let planet = crate::planet::Planet {
        radius,
        sketch: atlas,
    };
    let ground = planet
        .ground(&detail, lat, lon, 0.01)?
        .max(atlas.water_m as f64);
    let eye = DVec3::new(0.0, 0.0, ground + c.altitude_m.unwrap_or(1.0));
    let (h, p) = (c.heading().to_radians(), c.pitch().to_radians());
    let forward = DVec3::new(h.sin() * p.cos(), h.cos() * p.cos(), p.sin());
    let high = atlas.max_m as f64 + detail.reach_m();
    let reach = |z: f64| ((radius + z).powi(2) - radius * radius).max(0.0).sqrt();
    let far = c.far_m.unwrap_or(reach(eye.z) + reach(high)).max(1.0);
    let mut camera = Camera::new(eye, eye + forward, c.fov_y_deg, c.width, c.height, far)?;
    camera.geo = Some(crate::camera::Geo { lat, lon });
    // Nothing lies nearer than the eye's height over the highest ground.
    camera.near = (0.5 * (eye.z - high)).max(crate::camera::NEAR_M);
    Ok(camera)
}
