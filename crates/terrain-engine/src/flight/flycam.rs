//! The interactive camera of `terrain view`: yaw and pitch from the mouse, movement from the keys
//! at a speed that scales with the height above the ground, never below the ground; and the
//! recorder that writes the path flown in the scene's `[path]` format.
//!
//! Rules: yaw 0 looks north (+y) and grows towards east; pitch is kept within ±89°, so the view is
//! never straight up or down and "forward" on the ground stays defined. Speed is 0.8 × the height
//! above the ground per second (at least 5 m/s; ×4 with Shift), so crossing a valley and skimming a
//! ridge both feel controllable. After every move the eye is lifted to the ground's height plus
//! the procedural detail's reach plus a clearance, so no octave can poke through the near plane.
//!
//! Over a planet ([`PlanetFlyCamera`]) the camera holds its keys instead: the nadir's latitude
//! and longitude, the altitude above the ground, heading and pitch. It moves along great circles
//! (the heading turning with the track), at the same 0.8 × altitude per second, at most a radian
//! of arc a second, and never lower than the clearance above the ground.
//!
//! Rejected alternative: a fixed speed. Near the ground it overshoots a hill in one frame; 10 km up
//! it takes minutes to cross the sketch.

use crate::Camera;
use crate::scene::{PathKey, PathSection, Scene};
use crate::sketch::Atlas;
use crate::{Error, Result, Role};
use glam::DVec3;
use std::path::Path;

/// Metres kept between the eye and the highest the terrain can reach under it.
pub const CLEARANCE_M: f64 = 2.0;
const MAX_PITCH: f64 = 89.0 * std::f64::consts::PI / 180.0;
/// Radians per pixel of mouse motion.
const LOOK_PER_PX: f64 = 0.004;

/// The keys held in a frame, as the camera reads them.
#[derive(Clone, Copy, Debug, Default)]
pub struct Motion {
    /// Each in −1 … 1: forward/back (W/S), right/left (D/A), up/down (E/Q).
    pub forward: f64,
    /// Right (D) is positive.
    pub right: f64,
    /// Up (E) is positive.
    pub up: f64,
    /// Shift held: four times the speed.
    pub fast: bool,
}

/// The interactive camera over a sketch: an eye in world metres, yaw and pitch in radians.
#[derive(Clone, Debug)]
pub struct FlyCamera {
    /// World metres.
    pub eye: DVec3,
    /// 0 looks north (+y), growing towards east.
    pub yaw: f64,
    /// Above the horizon is positive, within ±89°.
    pub pitch: f64,
}

impl FlyCamera {
    /// The fly camera where `c` stands, looking where it looks.
    pub fn from_camera(c: &Camera) -> FlyCamera {
        FlyCamera::looking(c.eye, c.forward)
    }

    /// A camera at `eye` looking along `dir`.
    pub fn looking(eye: DVec3, dir: DVec3) -> FlyCamera {
        FlyCamera {
            eye,
            yaw: dir.x.atan2(dir.y),
            pitch: dir.z.clamp(-1.0, 1.0).asin().clamp(-MAX_PITCH, MAX_PITCH),
        }
    }

    /// The unit direction the camera looks in.
    pub fn forward(&self) -> DVec3 {
        let (sy, cy) = self.yaw.sin_cos();
        let (sp, cp) = self.pitch.sin_cos();
        DVec3::new(cp * sy, cp * cy, sp)
    }

    /// Turns by a mouse motion of (dx, dy) pixels (dragging right looks right, down looks down).
    pub fn look(&mut self, dx: f64, dy: f64) {
        look(&mut self.yaw, &mut self.pitch, dx, dy);
    }

    /// The speed in m/s at a height `above` the ground.
    pub fn speed(above: f64, fast: bool) -> f64 {
        above.max(0.0).mul_add(0.8, 0.0).max(5.0) * if fast { 4.0 } else { 1.0 }
    }

    /// Moves for `dt` seconds; `floor`: the least height the eye may have here (None off the sketch).
    pub fn step(&mut self, dt: f64, m: &Motion, floor: Option<f64>) {
        let above = floor.map_or(self.eye.z, |f| self.eye.z - f);
        let speed = FlyCamera::speed(above, m.fast);
        let (sy, cy) = self.yaw.sin_cos();
        let ahead = DVec3::new(sy, cy, 0.0);
        let right = DVec3::new(cy, -sy, 0.0);
        let v = ahead * m.forward + right * m.right + DVec3::Z * m.up;
        if v.length_squared() > 0.0 && dt.is_finite() && dt > 0.0 {
            self.eye += v.normalize() * speed * dt.min(0.25);
        }
        self.keep_above(floor);
    }

    /// Lifts the eye to `floor` where it is below it.
    pub fn keep_above(&mut self, floor: Option<f64>) {
        if let Some(f) = floor {
            self.eye.z = self.eye.z.max(f);
        }
    }

    /// The camera to draw: this eye and direction, `fov_y_deg`, an image of `width` × `height`.
    pub fn camera(&self, fov_y_deg: f64, width: u32, height: u32, far: f64) -> Result<Camera> {
        Camera::new(
            self.eye,
            self.eye + self.forward() * 100.0,
            fov_y_deg,
            width,
            height,
            far,
        )
    }
}

fn look(yaw: &mut f64, pitch: &mut f64, dx: f64, dy: f64) {
    *yaw = (*yaw + dx * LOOK_PER_PX).rem_euclid(std::f64::consts::TAU);
    *pitch = (*pitch - dy * LOOK_PER_PX).clamp(-MAX_PITCH, MAX_PITCH);
}

/// The interactive camera over a planet of `radius` metres: its keys, angles in radians.
#[derive(Clone, Debug)]
pub struct PlanetFlyCamera {
    /// The nadir's latitude.
    pub lat: f64,
    /// The nadir's longitude.
    pub lon: f64,
    /// Above the ground (the terrain function with every octave, or the sea), metres.
    pub altitude: f64,
    /// The heading: 0 north, growing towards east.
    pub yaw: f64,
    /// Above the horizon is positive.
    pub pitch: f64,
    /// The planet's radius, metres.
    pub radius: f64,
}

impl PlanetFlyCamera {
    /// The most arc the camera crosses in a second, radians: from orbit, a sixth of the planet.
    const MAX_ARC_PER_S: f64 = 1.0;
    /// The highest it flies, metres.
    const MAX_ALTITUDE_M: f64 = 1e8;

    /// The scene camera's keys.
    pub fn of_scene(scene: &Scene, radius: f64) -> PlanetFlyCamera {
        let c = &scene.camera;
        PlanetFlyCamera {
            lat: c.lat_deg.unwrap_or(0.0).to_radians(),
            lon: c.lon_deg.unwrap_or(0.0).to_radians(),
            altitude: c.altitude_m.unwrap_or(1.0),
            yaw: c.heading().to_radians(),
            pitch: c.pitch().to_radians().clamp(-MAX_PITCH, MAX_PITCH),
            radius,
        }
    }

    /// Turns by a mouse motion of `dx`, `dy` pixels.
    pub fn look(&mut self, dx: f64, dy: f64) {
        look(&mut self.yaw, &mut self.pitch, dx, dy);
    }

    /// Moves for `dt` seconds: along the ground at the heading (and to its right), up and down
    /// in altitude.
    pub fn step(&mut self, dt: f64, m: &Motion) {
        if !(dt.is_finite() && dt > 0.0) {
            return;
        }
        let dt = dt.min(0.25);
        let speed = FlyCamera::speed(self.altitude, m.fast);
        let (ahead, right) = (m.forward, m.right);
        let along = ahead.hypot(right);
        let norm = along.hypot(m.up);
        if norm == 0.0 {
            return;
        }
        if along > 0.0 {
            let arc = (speed * dt * along / norm / self.radius).min(Self::MAX_ARC_PER_S * dt);
            let bearing = self.yaw + right.atan2(ahead);
            let (lat, lon, track) = crate::planet::travel(self.lat, self.lon, bearing, arc);
            (self.lat, self.lon) = (lat, lon);
            self.yaw = (self.yaw + track - bearing).rem_euclid(std::f64::consts::TAU);
        }
        self.altitude =
            (self.altitude + speed * dt * m.up / norm).clamp(CLEARANCE_M, Self::MAX_ALTITUDE_M);
    }

    /// The camera's keys as a `[path]` key.
    pub fn key(&self) -> PathKey {
        PathKey {
            position: None,
            look_at: None,
            map_xy: None,
            lat_deg: Some(self.lat.to_degrees()),
            lon_deg: Some(self.lon.to_degrees()),
            altitude_m: Some(self.altitude),
            heading_deg: Some(self.yaw.to_degrees()),
            pitch_deg: Some(self.pitch.to_degrees()),
        }
    }

    /// Where the eye is, metres from the planet's centre (the altitude counted from the sphere):
    /// for measuring the distance flown.
    pub fn world(&self) -> DVec3 {
        crate::planet::unit(self.lat, self.lon) * (self.radius + self.altitude)
    }

    /// The camera `scene`'s camera becomes with these keys, at `width` × `height`.
    pub fn camera(&self, scene: &Scene, atlas: &Atlas, width: u32, height: u32) -> Result<Camera> {
        let mut s = scene.clone();
        let c = &mut s.camera;
        c.lat_deg = Some(self.lat.to_degrees());
        c.lon_deg = Some(self.lon.to_degrees());
        c.altitude_m = Some(self.altitude);
        c.heading_deg = Some(self.yaw.to_degrees());
        c.pitch_deg = Some(self.pitch.to_degrees());
        (c.width, c.height) = (width, height);
        crate::scene::camera_of(&s, atlas)
    }
}

/// Records the path flown: a key every second of flight or 500 m (over a planet, every second).
#[derive(Debug, Default)]
pub struct PathRecorder {
    /// The keys recorded so far.
    pub keys: Vec<PathKey>,
    distance_m: f64,
    seconds: f64,
    since_key_s: f64,
    since_key_m: f64,
    last: Option<DVec3>,
}

impl PathRecorder {
    const EVERY_S: f64 = 1.0;
    const EVERY_M: f64 = 500.0;

    /// A planar camera's key: its position, looking 1 km ahead.
    pub fn key_of(cam: &FlyCamera) -> PathKey {
        PathKey::at(
            cam.eye.to_array(),
            Some((cam.eye + cam.forward() * 1000.0).to_array()),
        )
    }

    /// Records the camera's `key` after `dt` seconds of flight, the eye at `at` (world metres).
    pub fn record(&mut self, key: PathKey, at: DVec3, dt: f64) {
        let moved = self.last.map_or(0.0, |l| (at - l).length());
        // Time counts from the first recorded position, as distance does.
        let dt = if self.last.is_some() { dt } else { 0.0 };
        self.distance_m += moved;
        self.since_key_m += moved;
        self.seconds += dt;
        self.since_key_s += dt;
        // A planet's flight spends equal time between keys, so its keys come by time alone.
        let far = key.position.is_some() && self.since_key_m >= Self::EVERY_M;
        let due =
            self.keys.is_empty() || (moved > 0.0 && (self.since_key_s >= Self::EVERY_S || far));
        if due {
            self.keys.push(key);
            self.since_key_s = 0.0;
            self.since_key_m = 0.0;
        }
        self.last = Some(at);
    }

    /// The path flown, ending at `last` (the camera's key now), or None when it has fewer than
    /// two distinct keys. A planet's path (keys without a position) takes the time flown as its
    /// duration; a sketch's, the mean speed.
    pub fn finish(&self, last: PathKey) -> Option<PathSection> {
        let mut keys = self.keys.clone();
        keys.push(last);
        // A planar key where the last one stood adds nothing but a zero-length span, which the
        // centripetal spline cannot parameterise.
        keys.dedup_by(|a, b| match (a.position, b.position) {
            (Some(p), Some(q)) => p == q,
            _ => a == b,
        });
        let planet = keys.iter().any(|k| k.position.is_none());
        (keys.len() >= 2 && self.distance_m > 0.0).then(|| PathSection {
            speed_mps: (self.distance_m / self.seconds.max(1e-3)).max(1.0),
            duration_s: planet.then_some(self.seconds.max(1e-3)),
            keys,
        })
    }
}

/// The text of the scene file `scene_path` with its `[path]` replaced by `path` (other keys
/// untouched).
pub fn scene_with_path(scene_text: &str, scene_path: &Path, path: &PathSection) -> Result<String> {
    let mut table: toml::Table = scene_text
        .parse()
        .map_err(|e| Error::decode(Role::Scene, scene_path, "not TOML", e))?;
    let keys: Vec<toml::Value> = path
        .keys
        .iter()
        .map(|k| toml::Value::try_from(k).expect("numbers"))
        .collect();
    let mut p = toml::Table::new();
    match path.duration_s {
        Some(d) => p.insert("duration_s".into(), toml::Value::Float(d)),
        None => p.insert("speed_mps".into(), toml::Value::Float(path.speed_mps)),
    };
    p.insert("keys".into(), toml::Value::Array(keys));
    table.insert("path".into(), toml::Value::Table(p));
    toml::to_string(&table).map_err(|e| Error::encode("flown scene", e))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cam() -> FlyCamera {
        FlyCamera {
            eye: DVec3::new(0.0, 0.0, 100.0),
            yaw: 0.0,
            pitch: 0.0,
        }
    }

    #[test]
    fn moves_faster_higher_up_and_never_below_the_floor() {
        assert_eq!(FlyCamera::speed(0.0, false), 5.0);
        assert_eq!(FlyCamera::speed(1000.0, false), 800.0);
        assert_eq!(FlyCamera::speed(1000.0, true), 3200.0);
        let mut c = cam();
        let down = Motion {
            up: -1.0,
            ..Motion::default()
        };
        for _ in 0..100 {
            c.step(0.1, &down, Some(60.0));
        }
        assert_eq!(c.eye.z, 60.0);
        let mut c = cam();
        c.step(
            0.1,
            &Motion {
                forward: 1.0,
                ..Motion::default()
            },
            Some(0.0),
        );
        // Yaw 0 is north: 0.1 s at 80 m/s (100 m up) is 8 m north.
        assert!(
            (c.eye - DVec3::new(0.0, 8.0, 100.0)).length() < 1e-9,
            "{}",
            c.eye
        );
    }

    #[test]
    fn look_keeps_pitch_off_the_poles_and_round_trips_a_camera() {
        let mut c = cam();
        c.look(0.0, -1e6);
        assert!(c.pitch <= MAX_PITCH && c.forward().z < 1.0);
        let camera = c.camera(60.0, 64, 64, 1e4).unwrap();
        let back = FlyCamera::from_camera(&camera);
        assert!((back.forward() - c.forward()).length() < 1e-9);
    }

    #[test]
    fn recorded_path_is_a_scene_path() {
        let mut c = cam();
        let mut r = PathRecorder::default();
        let ahead = Motion {
            forward: 1.0,
            ..Motion::default()
        };
        for _ in 0..50 {
            c.step(0.1, &ahead, Some(0.0));
            r.record(PathRecorder::key_of(&c), c.eye, 0.1);
        }
        let path = r.finish(PathRecorder::key_of(&c)).unwrap();
        assert!(path.keys.len() >= 5, "{}", path.keys.len());
        assert!((path.speed_mps - 80.0).abs() < 1.0, "{}", path.speed_mps);
        let text = scene_with_path(
            "[sketch]\nsynthetic = \"hills\"\n[path]\nkeys = []\n",
            Path::new("flown.toml"),
            &path,
        )
        .unwrap();
        let scene = crate::scene::Scene::parse(
            &format!(
                "{text}\n[camera]\nposition = [0.0, 0.0, 900.0]\nlook_at = [10.0, 10.0, 0.0]\n"
            ),
            std::path::PathBuf::new(),
        )
        .unwrap();
        assert!(crate::flight::path::CameraPath::new(scene.path.as_ref().unwrap()).is_ok());
    }

    fn planet_cam() -> PlanetFlyCamera {
        PlanetFlyCamera {
            lat: 0.0,
            lon: 0.0,
            altitude: 1000.0,
            yaw: 0.0,
            pitch: -0.2,
            radius: crate::planet::EARTH_RADIUS_M,
        }
    }

    /// Over a planet: 0.1 s north at 1 km is 80 m of meridian; east along the equator the
    /// heading holds; down, the altitude stops at the clearance; and the path recorded is a
    /// planet's `[path]` (its keys, the time flown) that a planet flight takes.
    #[test]
    fn a_planet_camera_flies_great_circles_and_records_a_planet_path() {
        let r = crate::planet::EARTH_RADIUS_M;
        let mut c = planet_cam();
        let ahead = Motion {
            forward: 1.0,
            ..Motion::default()
        };
        c.step(0.1, &ahead);
        assert!(
            (c.lat * r - 80.0).abs() < 1e-6 && c.lon.abs() < 1e-15,
            "{c:?}"
        );
        let mut east = planet_cam();
        east.yaw = std::f64::consts::FRAC_PI_2;
        east.step(0.1, &ahead);
        assert!((east.lon * r - 80.0).abs() < 1e-6 && east.lat.abs() < 1e-12);
        assert!((east.yaw - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
        let mut low = planet_cam();
        let down = Motion {
            up: -1.0,
            ..Motion::default()
        };
        for _ in 0..200 {
            low.step(0.1, &down);
        }
        assert_eq!(low.altitude, CLEARANCE_M);

        let mut c = planet_cam();
        let mut rec = PathRecorder::default();
        for _ in 0..30 {
            c.step(0.1, &ahead);
            rec.record(c.key(), c.world(), 0.1);
        }
        let path = rec.finish(c.key()).unwrap();
        assert!(path.keys.len() >= 3 && path.keys.iter().all(|k| k.position.is_none()));
        assert!(
            (path.duration_s.unwrap() - 2.9).abs() < 1e-9,
            "{:?}",
            path.duration_s
        );
        let text = scene_with_path(
            "[sketch]\nsynthetic = \"planet\"\n",
            Path::new("flown.toml"),
            &path,
        )
        .unwrap();
        let scene = crate::scene::Scene::parse(
            &format!("{text}\n[camera]\nlat_deg = 0.0\nlon_deg = 0.0\naltitude_m = 1000.0\n"),
            std::path::PathBuf::new(),
        )
        .unwrap();
        let flight = crate::flight::path::PlanetFlight::of_scene(&scene, r).unwrap();
        let end = flight.at(flight.duration_s);
        assert!((end[0].to_radians() - c.lat).abs() < 1e-12, "{end:?}");
    }
}
