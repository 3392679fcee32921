//! The keys that place and aim the camera: `[camera]` and the `[path]` keys of a flight.
//!
//! Rule: a camera and a path key place themselves by the same keys ([`Placement`]), checked once
//! by `Scene::check` and resolved once by `scene::place`; neither resolves a place itself.

use serde::{Deserialize, Serialize};

/// Where the camera stands and looks. A planar scene places it by `position` (world metres), by
/// `map_xy` (the sketch file's own coordinates) or by `lat_deg` and `lon_deg`, each of the last
/// two with `altitude_m`, and aims it by `look_at` or by `heading_deg` and `pitch_deg`; without a
/// place it frames the whole sketch (`scene::place`). A planet's camera takes `lat_deg`,
/// `lon_deg`, `altitude_m`, `heading_deg` and `pitch_deg`.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct CameraSection {
    /// The eye in world metres (z the height above sea level, not above the ground).
    pub position: Option<[f64; 3]>,
    /// The point looked at, world metres.
    pub look_at: Option<[f64; 3]>,
    /// The eye's x and y in the sketch file's own coordinate system (what `terrain info` prints
    /// as its georeference), with `altitude_m`.
    pub map_xy: Option<[f64; 2]>,
    /// The eye's (a planet's: its nadir's) latitude, degrees, −90 to 90; on a projected sketch
    /// WGS 84, converted through the file's coordinate system.
    pub lat_deg: Option<f64>,
    /// The eye's longitude, degrees, east positive (−360 to 360 on a sketch; on a planet any
    /// value, wrapped).
    pub lon_deg: Option<f64>,
    /// Height above the ground or water under the eye, metres.
    pub altitude_m: Option<f64>,
    /// View direction: 0 north, 90 east (0 unless given; the default view: the side it looks from).
    pub heading_deg: Option<f64>,
    /// View direction: 0 level, −90 straight down (0 unless given; the default view: −45).
    pub pitch_deg: Option<f64>,
    /// Vertical field of view, degrees, in (0, 180) (default 60).
    #[serde(default = "default_fov")]
    pub fov_y_deg: f64,
    /// Image width, pixels, 1 to 16384 (default 512; `--size` overrides).
    #[serde(default = "default_size")]
    pub width: u32,
    /// Image height, pixels, 1 to 16384 (default 512; `--size` overrides).
    #[serde(default = "default_size")]
    pub height: u32,
    /// Far distance in metres; by default the farthest corner of the sketch.
    pub far_m: Option<f64>,
}
/// The `[camera]` keys that say where it stands.
pub const PLACE_KEYS: [&str; 5] = ["position", "map_xy", "lat_deg", "lon_deg", "altitude_m"];
/// The `[camera]` keys that say where it looks.
pub const AIM_KEYS: [&str; 3] = ["look_at", "heading_deg", "pitch_deg"];

/// Lays the camera keys `given` (a jobs file's job, or `--set camera.…`) over the `[camera]`
/// table `base` as one camera: where `given` places the camera, the base's place and aim go
/// whole; where it only aims it, the base's aim goes and its place stays. The optics (`fov_y_deg`,
/// `width`, `height`, `far_m`) merge key by key. Rejected: merging every key, which mixed two
/// cameras' keys into one that gives two places or two aims.
pub fn lay_camera(base: &mut toml::Table, given: &[&str]) {
    let gives = |keys: &[&str]| given.iter().any(|k| keys.contains(k));
    let dropped: &[&str] = match (gives(&PLACE_KEYS), gives(&AIM_KEYS)) {
        (true, _) => &[PLACE_KEYS.as_slice(), AIM_KEYS.as_slice()].concat(),
        (false, true) => &AIM_KEYS,
        (false, false) => &[],
    };
    base.retain(|k, _| !dropped.contains(&k));
}

impl Default for CameraSection {
    fn default() -> Self {
        CameraSection {
            position: None,
            look_at: None,
            map_xy: None,
            lat_deg: None,
            lon_deg: None,
            altitude_m: None,
            heading_deg: None,
            pitch_deg: None,
            fov_y_deg: default_fov(),
            width: default_size(),
            height: default_size(),
            far_m: None,
        }
    }
}
impl CameraSection {
    /// Places a planar scene's camera at `eye` looking at `target`, in place of whatever keys
    /// placed it before.
    pub fn aim(&mut self, eye: glam::DVec3, target: glam::DVec3) {
        *self = CameraSection {
            position: Some(eye.to_array()),
            look_at: Some(target.to_array()),
            ..CameraSection {
                fov_y_deg: self.fov_y_deg,
                width: self.width,
                height: self.height,
                far_m: self.far_m,
                ..CameraSection::default()
            }
        };
    }
    /// `position`, for a camera placed by it (the origin otherwise; `scene::place::pose` places
    /// every camera).
    pub fn eye(&self) -> glam::DVec3 {
        glam::DVec3::from(self.position.unwrap_or_default())
    }
    /// `look_at`, for a camera aimed by it (the origin otherwise).
    pub fn target(&self) -> glam::DVec3 {
        glam::DVec3::from(self.look_at.unwrap_or_default())
    }
    /// `heading_deg`, 0 (north) unless given.
    pub fn heading(&self) -> f64 {
        self.heading_deg.unwrap_or(0.0)
    }
    /// `pitch_deg`, 0 (level) unless given.
    pub fn pitch(&self) -> f64 {
        self.pitch_deg.unwrap_or(0.0)
    }
    /// The keys that place and aim it.
    pub(crate) fn placement(&self) -> Placement {
        Placement {
            position: self.position,
            look_at: self.look_at,
            map_xy: self.map_xy,
            lat_deg: self.lat_deg,
            lon_deg: self.lon_deg,
            altitude_m: self.altitude_m,
            heading_deg: self.heading_deg,
            pitch_deg: self.pitch_deg,
        }
    }
    /// Whether the keys place the camera (a planar scene without a place frames the sketch).
    pub fn is_placed(&self) -> bool {
        self.position.is_some()
            || self.map_xy.is_some()
            || self.lat_deg.is_some()
            || self.lon_deg.is_some()
    }
}

/// The keys a planar camera and a path key share to place and aim it, checked by
/// `Scene::check` and resolved by `scene::place`.
pub(crate) struct Placement {
    pub position: Option<[f64; 3]>,
    pub look_at: Option<[f64; 3]>,
    pub map_xy: Option<[f64; 2]>,
    pub lat_deg: Option<f64>,
    pub lon_deg: Option<f64>,
    pub altitude_m: Option<f64>,
    pub heading_deg: Option<f64>,
    pub pitch_deg: Option<f64>,
}

fn default_fov() -> f64 {
    60.0
}
fn default_size() -> u32 {
    512
}

/// `[path]`: the camera path `fly` and `compare` follow: a smooth (centripetal Catmull–Rom)
/// curve through its keys on a sketch, a flight from key to key on a planet.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct PathSection {
    /// Constant speed along a planar curve, metres per second (> 0, default 150).
    #[serde(default = "default_speed")]
    pub speed_mps: f64,
    /// A planet's flight: how long it takes, seconds (each key to the next in equal time).
    pub duration_s: Option<f64>,
    /// The points the path passes through, at least 2.
    pub keys: Vec<PathKey>,
}
fn default_speed() -> f64 {
    150.0
}

/// One key of a `[path]`: a place and, optionally, an aim, given by the same keys as
/// `[camera]`'s.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct PathKey {
    /// A point of a planar path (required there), world metres.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub position: Option<[f64; 3]>,
    /// Where the camera looks at this key, world metres (default: ahead along the path; not
    /// with `heading_deg`, `pitch_deg`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub look_at: Option<[f64; 3]>,
    /// A sketch's key in the file's own coordinates, with `altitude_m`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub map_xy: Option<[f64; 2]>,
    /// The latitude under the camera, degrees, −90 to 90 (required on a planet).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lat_deg: Option<f64>,
    /// The longitude under the camera, degrees, east positive (required on a planet).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lon_deg: Option<f64>,
    /// The height above the ground or water, metres, 0.01 to 10⁹ (required on a planet).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub altitude_m: Option<f64>,
    /// The view's compass direction, degrees: 0 north, 90 east (default 0).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub heading_deg: Option<f64>,
    /// The view's elevation, degrees: 0 level, −90 straight down (default 0).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pitch_deg: Option<f64>,
}

impl PathKey {
    /// The keys that place and aim it.
    pub(crate) fn placement(&self) -> Placement {
        Placement {
            position: self.position,
            look_at: self.look_at,
            map_xy: self.map_xy,
            lat_deg: self.lat_deg,
            lon_deg: self.lon_deg,
            altitude_m: self.altitude_m,
            heading_deg: self.heading_deg,
            pitch_deg: self.pitch_deg,
        }
    }

    /// A planar key at `position`.
    pub fn at(position: [f64; 3], look_at: Option<[f64; 3]>) -> PathKey {
        PathKey {
            position: Some(position),
            look_at,
            map_xy: None,
            lat_deg: None,
            lon_deg: None,
            altitude_m: None,
            heading_deg: None,
            pitch_deg: None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::lay_camera;

    fn laid(base: &str, given: &[&str]) -> Vec<String> {
        let mut t: toml::Table = base.parse().unwrap();
        lay_camera(&mut t, given);
        t.keys().cloned().collect()
    }

    #[test]
    fn a_place_replaces_place_and_aim_an_aim_only_the_aim() {
        let base = "map_xy = [1.0, 2.0]\naltitude_m = 50.0\nheading_deg = 0.0\npitch_deg = -45.0\n\
                    fov_y_deg = 40.0\nwidth = 64\n";
        assert_eq!(laid(base, &["position", "look_at"]), ["fov_y_deg", "width"]);
        assert_eq!(
            laid(base, &["look_at"]),
            ["altitude_m", "fov_y_deg", "map_xy", "width"]
        );
        assert_eq!(laid(base, &["width"]).len(), 6, "optics merge key by key");
    }
}
