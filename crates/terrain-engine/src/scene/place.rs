//! Where a planar scene's camera stands and looks: by world metres, by the sketch file's own
//! coordinates or by latitude and longitude, or, with no place given, a view the sketch fills.
//!
//! Rules:
//! - World metres are measured from the sketch's south-west node (`sketch.origin_m` moves it), x
//!   east, y north. A point in the file's coordinates (`map_xy`) maps to the world node for node,
//!   as the sketch's heights do; `lat_deg`/`lon_deg` are first converted into the file's
//!   coordinates (`Georef::from_lat_lon`), so a geographic sketch uses the very mapping its
//!   metres use and a projected one its own projection.
//! - `altitude_m` counts from the surface under the eye: the sketch's ground or water, and beyond
//!   the sketch what `sketch.outside` puts there (the plain at the edges' mean height, the sea at
//!   0 m; a void counts as the plain's height).
//! - Aim: `look_at`, or `heading_deg` (0 north, 90 east) and `pitch_deg` (0 level, −90 down),
//!   each 0 unless given.
//! - Without a place, the camera frames the sketch ([`framing`]): it looks along `heading_deg`
//!   (north) and `pitch_deg` (−45°) from the least distance at which the sketch's central 80 %
//!   ([`CORE`]: its rectangle shrunk by a tenth on each side, from its lowest to its highest
//!   surface) lies inside the frame, that part's image centred, and above its highest ground.
//!   The rim beyond the central part may leave the frame: the sketch fills half a square frame
//!   and three quarters of a 16:9 one (docs/decisions.md, “The default view fills the frame”).
//! - `camera.look_at` as reported is the scene's own, or where the view's central ray meets the
//!   surface ([`ground_ahead`]), the point a user sees at the frame's centre.
//!
//! Rejected alternatives: a fixed multiple of the sketch's diagonal, which leaves a long or a
//! wide sketch, or a narrow frame, mostly sky or cuts the sketch off; and the whole sketch framed
//! from beyond its edge, which shows it as a small trapezoid over a quarter of a square frame,
//! the plain beyond it the rest.

use super::{Outside, PathKey, PathSection, Placement, Scene};
use crate::error::{Error, Result};
use crate::sketch::Atlas;
use glam::{DVec2, DVec3};
use serde::Serialize;

/// The default view's pitch, degrees: steep enough that the sketch's near and far edges, far
/// apart on screen, leave little of a square frame to the plain beyond them (the sketch fills
/// 0.50 of it at −45°, 0.43 at −40°), shallow enough that its relief reads.
pub const DEFAULT_PITCH_DEG: f64 = -45.0;
/// The share of the frame the framed part may fill: a margin so its corners are not cut.
const FILL: f64 = 0.95;
/// The share of the sketch's width and depth, about its centre, that the default view keeps
/// whole in the frame; the rim beyond it may leave the frame, so the sketch fills it.
pub const CORE: f64 = 0.8;
/// The default path's duration, seconds.
pub const DEFAULT_PATH_S: f64 = 10.0;
/// Keys of the default orbit (the first and last at the same place).
const ORBIT_KEYS: usize = 13;

/// The eye and the point looked at, world metres, of a planar scene's camera over `atlas`.
pub fn pose(scene: &Scene, atlas: &Atlas) -> Result<(DVec3, DVec3)> {
    let c = &scene.camera;
    let Some(eye) = eye_of(scene, atlas, "camera", &c.placement())? else {
        return Ok(framing(
            scene,
            atlas,
            c.heading(),
            c.pitch_deg.unwrap_or(DEFAULT_PITCH_DEG),
        ));
    };
    let target = match c.look_at {
        Some(t) => DVec3::from(t),
        None => eye + direction(c.heading(), c.pitch()) * aim_distance(atlas),
    };
    Ok((eye, target))
}

/// A path key resolved to world metres: its `position` and `look_at` (from its heading and
/// pitch where it gives them), its other place keys cleared.
pub fn resolve_key(scene: &Scene, atlas: &Atlas, k: usize, key: &PathKey) -> Result<PathKey> {
    // `Scene::check` gives every planar key a place; the table names the key in messages.
    let table = format!("path.keys[{k}]");
    let eye = eye_of(scene, atlas, &table, &key.placement())?.unwrap_or_default();
    let look_at = match (key.look_at, key.heading_deg, key.pitch_deg) {
        (Some(t), _, _) => Some(t),
        (None, None, None) => None,
        (None, h, p) => {
            let d = direction(h.unwrap_or(0.0), p.unwrap_or(0.0));
            Some((eye + d * aim_distance(atlas)).to_array())
        }
    };
    Ok(PathKey::at(eye.to_array(), look_at))
}

/// The eye the place keys give (`None` without a place).
fn eye_of(scene: &Scene, atlas: &Atlas, table: &str, p: &Placement) -> Result<Option<DVec3>> {
    if let Some(position) = p.position {
        return Ok(Some(DVec3::from(position)));
    }
    let map = match (p.map_xy, p.lat_deg, p.lon_deg) {
        (Some(xy), _, _) => xy,
        (None, Some(lat), Some(lon)) => {
            let g = georef(scene, atlas, table, "lat_deg")?;
            g.from_lat_lon(lat, lon)
                .map_err(|why| fault(scene, &format!("{table}.lat_deg"), &why))?
        }
        _ => return Ok(None),
    };
    let xy =
        world_of_map(atlas, map).map_err(|why| fault(scene, &format!("{table}.map_xy"), &why))?;
    let ground = surface_m(scene, atlas, xy)?;
    Ok(Some(xy.extend(ground + p.altitude_m.unwrap_or(0.0))))
}

/// One line for each place the scene gives (`[camera]`, each `[path]` key) that lies more than
/// the sketch's size outside the sketch: a view from there shows little or none of it, and a
/// place that far off is most often a coordinate of another place or system (a latitude on a
/// projected sketch far from it). Places that do not resolve are left to the error that says
/// why when the camera is made.
pub fn off_map_warnings(scene: &Scene, atlas: &Atlas) -> Vec<String> {
    let mut places = vec![("camera".to_string(), scene.camera.placement())];
    if let Some(path) = &scene.path {
        for (k, key) in path.keys.iter().enumerate() {
            places.push((format!("path.keys[{k}]"), key.placement()));
        }
    }
    let file = scene
        .source
        .as_ref()
        .map(|p| format!("{}: ", p.display()))
        .unwrap_or_default();
    places
        .iter()
        .filter_map(|(table, p)| {
            let eye = eye_of(scene, atlas, table, p).ok().flatten()?;
            let key = match (p.position, p.map_xy) {
                (Some(_), _) => "position",
                (None, Some(_)) => "map_xy",
                (None, None) => "lat_deg/lon_deg",
            };
            let what = format!("{file}{table}.{key} places the camera");
            off_map_warning(atlas, &what, eye.truncate())
                .map(|line| format!("{line}: the view from there may hold none of it"))
        })
        .collect()
}

/// Where the world point `p`, given by `what` (a key or an argument and what it places), lies
/// more than the sketch's size (its larger side) outside the sketch's rectangle: `{what} {d}
/// outside the sketch, farther than its size ({s})`, for the caller to add what follows.
pub fn off_map_warning(atlas: &Atlas, what: &str, p: DVec2) -> Option<String> {
    let (lo, hi) = (atlas.origin, atlas.max_corner());
    let size = (hi - lo).max_element();
    let outside = (lo - p).max(p - hi).max(DVec2::ZERO).length();
    (outside > size).then(|| {
        format!(
            "{what} {} outside the sketch, farther than its size ({})",
            distance(outside),
            distance(size)
        )
    })
}

/// A distance for a message: kilometres from 1 km up, else metres.
fn distance(m: f64) -> String {
    if m >= 1000.0 {
        format!("{:.1} km", m / 1000.0)
    } else {
        format!("{m:.0} m")
    }
}

fn georef<'a>(
    scene: &Scene,
    atlas: &'a Atlas,
    table: &str,
    key: &str,
) -> Result<&'a crate::sketch::georef::Georef> {
    atlas.georef.as_ref().ok_or_else(|| {
        fault(
            scene,
            &format!("{table}.{key}"),
            "the sketch has no georeference (place the camera by position)",
        )
    })
}

/// One line naming the scene file (where known) and the key.
fn fault(scene: &Scene, key: &str, why: &str) -> Error {
    let reason = format!("{key}: {why}");
    match &scene.source {
        Some(path) => Error::scene(path, reason),
        None => Error::Camera(reason),
    }
}

/// World metres of a point in the sketch file's own coordinates.
pub fn world_of_map(atlas: &Atlas, [x, y]: [f64; 2]) -> std::result::Result<DVec2, String> {
    let g = atlas
        .georef
        .as_ref()
        .ok_or("the sketch has no georeference: its file names no coordinates")?;
    let world = atlas.origin
        + DVec2::new(
            (x - g.west) / g.cell_x * atlas.dx,
            (y - g.south) / g.cell_y * atlas.dy,
        );
    if world.is_finite() {
        Ok(world)
    } else {
        Err(format!("({x}, {y}) is not a finite point"))
    }
}

/// The sketch file's own coordinates of a world point, where the sketch has a georeference.
pub fn map_of_world(atlas: &Atlas, p: DVec2) -> Option<[f64; 2]> {
    let g = atlas.georef.as_ref()?;
    let d = p - atlas.origin;
    Some([
        g.west + d.x / atlas.dx * g.cell_x,
        g.south + d.y / atlas.dy * g.cell_y,
    ])
}

/// The surface under a world point: the sketch's ground or water, and beyond the sketch the
/// margin into the plain (or the sea) `sketch.outside` draws there (its edge read as
/// `ground_under` reads the sketch; over the void, the plain's height, for cameras placed there).
pub fn surface_m(scene: &Scene, atlas: &Atlas, p: DVec2) -> Result<f64> {
    if let Some(ground) = super::ground_under(atlas, p)? {
        return Ok(ground);
    }
    let beyond = crate::beyond::Beyond::new(atlas, scene.outside(atlas));
    if beyond.outside == Outside::Void {
        return Ok((atlas.water_m as f64).max(atlas.edge_mean_m as f64));
    }
    let (edge, d) = crate::beyond::nearest_on(atlas.origin, atlas.max_corner(), p);
    let edge = super::ground_under(atlas, edge)?.unwrap_or(beyond.level_m);
    Ok(beyond.ground(edge, 0.0, d).max(atlas.water_m as f64))
}

/// The unit view direction of a heading (0 north, 90 east) and pitch (0 level, −90 down).
pub fn direction(heading_deg: f64, pitch_deg: f64) -> DVec3 {
    let (h, p) = (heading_deg.to_radians(), pitch_deg.to_radians());
    DVec3::new(h.sin() * p.cos(), h.cos() * p.cos(), p.sin())
}

/// Heading and pitch, degrees, of a view direction (heading 0 when looking straight up or down).
pub fn heading_pitch(dir: DVec3) -> (f64, f64) {
    let d = dir.normalize();
    let heading = if d.truncate().length() > 1e-12 {
        d.x.atan2(d.y).to_degrees().rem_euclid(360.0)
    } else {
        0.0
    };
    (heading, d.z.clamp(-1.0, 1.0).asin().to_degrees())
}

/// How far ahead a camera aimed by heading and pitch looks: any positive distance would do; a
/// sketch-sized one keeps `look_at`'s digits meaningful when written out.
fn aim_distance(atlas: &Atlas) -> f64 {
    (atlas.max_corner() - atlas.origin).length().max(1.0)
}

/// The default view: the sketch seen along `heading_deg` and `pitch_deg`, as near as the frame
/// allows with the sketch's central [`CORE`] share whole in it (`fit`), above its highest ground.
pub fn framing(scene: &Scene, atlas: &Atlas, heading_deg: f64, pitch_deg: f64) -> (DVec3, DVec3) {
    let c = &scene.camera;
    // Level or upward views cannot frame the ground from above: they look over it instead.
    let pitch = pitch_deg.clamp(-89.0, -1.0);
    let (lo, hi) = (atlas.origin, atlas.max_corner());
    let water = atlas.water_m as f64;
    let (z_lo, z_hi) = (
        (atlas.min_m as f64).max(water),
        (atlas.max_m as f64).max(water),
    );
    // The central part's box: its corners at the sketch's lowest and highest surface, so it
    // stays in view whatever the relief under them.
    let margin = (hi - lo) * (0.5 * (1.0 - CORE));
    let (core_lo, core_hi) = (lo + margin, hi - margin);
    let centre = ((lo + hi) * 0.5).extend(0.5 * (z_lo + z_hi));
    let corners: Vec<DVec3> = [core_lo.x, core_hi.x]
        .into_iter()
        .flat_map(|x| [core_lo.y, core_hi.y].map(|y| DVec2::new(x, y)))
        .flat_map(|p| [z_lo, z_hi].map(|z| p.extend(z) - centre))
        .collect();
    let tan_y = (c.fov_y_deg.to_radians() * 0.5).tan() * FILL;
    let h = heading_deg.to_radians();
    let frame = Frame {
        forward: direction(heading_deg, pitch),
        right: DVec3::new(h.cos(), -h.sin(), 0.0),
        tan: [tan_y * c.width as f64 / c.height as f64, tan_y],
    };
    let (offset, mut depth) = fit(&frame, &corners);
    let mut eye = centre + offset;
    // Above the highest ground, so the eye never stands inside a ridge it frames: backed off
    // along the view, which keeps the pitch and keeps every framed point in the frame (each
    // one's depth grows while its offset from the axis stays).
    let floor = z_hi + 0.01 * (hi - lo).length();
    if eye.z < floor {
        let back = (floor - eye.z) / -frame.forward.z;
        eye -= frame.forward * back;
        depth += back;
    }
    (eye, eye + frame.forward * depth)
}

/// A view direction and the frame's half-extents (tangents of the half angles, the margin in).
struct Frame {
    forward: DVec3,
    right: DVec3,
    tan: [f64; 2],
}

/// The nearest eye, relative to the points' centre, whose frame holds every point (`points`,
/// relative to the same centre). The eye is `a·right + b·up − d·forward`; for a distance d the
/// points fit when some offset keeps each one's sideways and upward parts within the frame's
/// tangent of its depth, which bounds a and b to intervals. The least such d is found by
/// bisection, (a, b) centred in their intervals, so the points' image is centred in the frame.
/// Returns the eye and the depth of the centre.
fn fit(frame: &Frame, points: &[DVec3]) -> (DVec3, f64) {
    let up = frame.right.cross(frame.forward);
    let axes = [frame.right, up];
    let place = |d: f64| -> Option<DVec3> {
        let mut eye = -frame.forward * d;
        for (axis, tan) in axes.iter().zip(frame.tan) {
            let (mut lo, mut hi) = (f64::NEG_INFINITY, f64::INFINITY);
            for q in points {
                let depth = frame.forward.dot(*q) + d;
                if depth <= 0.0 {
                    return None;
                }
                let side = axis.dot(*q);
                lo = lo.max(side - tan * depth);
                hi = hi.min(side + tan * depth);
            }
            if lo > hi {
                return None;
            }
            eye += *axis * (0.5 * (lo + hi));
        }
        Some(eye)
    };
    let extent = points.iter().map(|q| q.length()).fold(1.0, f64::max);
    let mut far = extent;
    while place(far).is_none() && far < 1e12 {
        far *= 2.0;
    }
    let mut near = 0.0;
    for _ in 0..64 {
        let mid = 0.5 * (near + far);
        match place(mid) {
            Some(_) => far = mid,
            None => near = mid,
        }
    }
    let eye = place(far).unwrap_or(-frame.forward * far);
    (eye, frame.forward.dot(-eye))
}

/// The default path: one orbit of the sketch's centre, from the default view's distance and
/// height, looking at the centre, [`DEFAULT_PATH_S`] long (its speed set from its length).
pub fn default_path(scene: &Scene, atlas: &Atlas) -> PathSection {
    let pitch = scene.camera.pitch_deg.unwrap_or(DEFAULT_PITCH_DEG);
    let start = scene.camera.heading();
    // Around the sketch's centre, at the widest of the four sides' framing distances and the
    // highest of their heights, so the sketch stays whole from every side.
    let centre = (atlas.origin + atlas.max_corner()) * 0.5;
    let (mut radius, mut height): (f64, f64) = (0.0, f64::NEG_INFINITY);
    for side in [0.0, 90.0, 180.0, 270.0] {
        let (eye, _) = framing(scene, atlas, start + side, pitch);
        radius = radius.max((eye.truncate() - centre).length());
        height = height.max(eye.z);
    }
    let mid_z = 0.5 * (atlas.min_m as f64 + atlas.max_m as f64).max(atlas.water_m as f64);
    let target = centre.extend(mid_z);
    let keys = (0..ORBIT_KEYS)
        .map(|k| {
            let heading = start + 360.0 * k as f64 / (ORBIT_KEYS - 1) as f64;
            let h = heading.to_radians();
            let at = centre - DVec2::new(h.sin(), h.cos()) * radius;
            PathKey::at(at.extend(height).to_array(), Some(target.to_array()))
        })
        .collect();
    PathSection {
        // The chords' length; `CameraPath` measures the curve and the caller may rescale.
        speed_mps: std::f64::consts::TAU * radius / DEFAULT_PATH_S,
        duration_s: None,
        keys,
    }
}

/// The camera a frame used, as `render --json` reports it (`camera`).
#[derive(Clone, Debug, Serialize)]
pub struct CameraReport {
    /// World metres.
    pub position: [f64; 3],
    /// The point looked at, world metres.
    pub look_at: [f64; 3],
    /// Above the surface under the eye.
    pub altitude_m: f64,
    /// The view's compass direction, degrees: 0 north, 90 east.
    pub heading_deg: f64,
    /// The view's elevation, degrees: 0 level, −90 straight down.
    pub pitch_deg: f64,
    /// The eye's latitude, degrees, where the sketch has a georeference that converts.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lat_deg: Option<f64>,
    /// The eye's longitude, degrees, east positive, where `lat_deg` is given.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lon_deg: Option<f64>,
    /// The eye in the file's own coordinates, where the sketch has a georeference.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub map_xy: Option<[f64; 2]>,
}

/// The scene's camera over `atlas` in the keys people place it by. A planet's: its keys, its
/// eye and target in the nadir's tangent frame (`camera`).
pub fn camera_report(
    scene: &Scene,
    atlas: &Atlas,
    camera: &crate::camera::Camera,
) -> Result<CameraReport> {
    if scene.planet().is_none() {
        let (eye, target) = pose(scene, atlas)?;
        return report(scene, atlas, eye, target);
    }
    let c = &scene.camera;
    Ok(CameraReport {
        position: camera.eye.to_array(),
        look_at: (camera.eye + camera.forward).to_array(),
        altitude_m: c.altitude_m.unwrap_or(0.0),
        heading_deg: c.heading(),
        pitch_deg: c.pitch(),
        lat_deg: c.lat_deg,
        lon_deg: c.lon_deg,
        map_xy: None,
    })
}

/// What a planar camera with eye `eye` looking at `target` is in the keys people place it by.
/// Its `look_at` is the scene's own where it gives one, else the ground the view's central ray
/// meets (`ground_ahead`), so it names what the view is centred on; `target` where the ray
/// meets nothing.
pub fn report(scene: &Scene, atlas: &Atlas, eye: DVec3, target: DVec3) -> Result<CameraReport> {
    let (heading_deg, pitch_deg) = heading_pitch(target - eye);
    let look_at = match scene.camera.look_at {
        Some(_) => target,
        None => ground_ahead(scene, atlas, eye, target)?.unwrap_or(target),
    };
    let map_xy = map_of_world(atlas, eye.truncate());
    let lat_lon = match (&atlas.georef, map_xy) {
        (Some(g), Some([x, y])) => g.to_lat_lon(x, y).ok(),
        _ => None,
    };
    Ok(CameraReport {
        position: eye.to_array(),
        look_at: look_at.to_array(),
        altitude_m: eye.z - surface_m(scene, atlas, eye.truncate())?,
        heading_deg,
        pitch_deg,
        lat_deg: lat_lon.map(|l| l[0]),
        lon_deg: lat_lon.map(|l| l[1]),
        map_xy,
    })
}

/// Where the ray from `eye` through `target` first meets the scene's surface (the sketch with
/// its detail, the water, what lies beyond), marched as the reference marches the frame's
/// central pixel; `None` where it meets nothing (the sky, or a void).
pub fn ground_ahead(
    scene: &Scene,
    atlas: &Atlas,
    eye: DVec3,
    target: DVec3,
) -> Result<Option<DVec3>> {
    let detail = super::detail_of(scene, atlas);
    let ground = crate::query::Ground::new(scene, atlas, &detail);
    let c = &scene.camera;
    let pixel = 2.0 * (c.fov_y_deg.to_radians() * 0.5).tan() / f64::from(c.height.max(1));
    ground.ray_cast(eye, target - eye, pixel)
}
