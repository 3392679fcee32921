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
//! Rejected alternative: a fixed speed. Near the ground it overshoots a hill in one frame; 10 km up
//! it takes minutes to cross the sketch.

use crate::camera::Camera;
use crate::error::{Error, Result, Role};
use crate::scene::{PathKey, PathSection};
use glam::DVec3;
use std::path::Path;

/// Metres kept between the eye and the highest the terrain can reach under it.
pub const CLEARANCE_M: f64 = 2.0;
const MAX_PITCH: f64 = 89.0 * std::f64::consts::PI / 180.0;
/// Radians per pixel of mouse motion.
const LOOK_PER_PX: f64 = 0.004;

#[derive(Clone, Copy, Debug, Default)]
pub struct Motion {
    /// Each in −1 … 1: forward/back (W/S), right/left (D/A), up/down (E/Q).
    pub forward: f64,
    pub right: f64,
    pub up: f64,
    pub fast: bool,
}

#[derive(Clone, Debug)]
pub struct FlyCamera {
    pub eye: DVec3,
    pub yaw: f64,
    pub pitch: f64,
}

impl FlyCamera {
    pub fn from_camera(c: &Camera) -> FlyCamera {
        let f = c.forward;
        FlyCamera {
            eye: c.eye,
            yaw: f.x.atan2(f.y),
            pitch: f.z.clamp(-1.0, 1.0).asin().clamp(-MAX_PITCH, MAX_PITCH),
        }
    }

    pub fn forward(&self) -> DVec3 {
        let (sy, cy) = self.yaw.sin_cos();
        let (sp, cp) = self.pitch.sin_cos();
        DVec3::new(cp * sy, cp * cy, sp)
    }

    /// Turns by a mouse motion of (dx, dy) pixels (dragging right looks right, down looks down).
    pub fn look(&mut self, dx: f64, dy: f64) {
        self.yaw = (self.yaw + dx * LOOK_PER_PX).rem_euclid(std::f64::consts::TAU);
        self.pitch = (self.pitch - dy * LOOK_PER_PX).clamp(-MAX_PITCH, MAX_PITCH);
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

    pub fn keep_above(&mut self, floor: Option<f64>) {
        if let Some(f) = floor {
            self.eye.z = self.eye.z.max(f);
        }
    }

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

/// Records the path flown: a key every `every_s` seconds of flight or `every_m` metres.
#[derive(Debug, Default)]
pub struct PathRecorder {
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

    pub fn record(&mut self, cam: &FlyCamera, dt: f64) {
        let moved = self.last.map_or(0.0, |l| (cam.eye - l).length());
        // Time counts from the first recorded position, as distance does.
        let dt = if self.last.is_some() { dt } else { 0.0 };
        self.distance_m += moved;
        self.since_key_m += moved;
        self.seconds += dt;
        self.since_key_s += dt;
        let due = self.keys.is_empty()
            || (moved > 0.0
                && (self.since_key_s >= Self::EVERY_S || self.since_key_m >= Self::EVERY_M));
        if due {
            self.keys.push(PathKey::at(
                cam.eye.to_array(),
                Some((cam.eye + cam.forward() * 1000.0).to_array()),
            ));
            self.since_key_s = 0.0;
            self.since_key_m = 0.0;
        }
        self.last = Some(cam.eye);
    }

    /// The path flown, or None when it has fewer than two distinct keys.
    pub fn finish(&self, cam: &FlyCamera) -> Option<PathSection> {
        let mut keys = self.keys.clone();
        if keys.last().and_then(|k| k.position) != Some(cam.eye.to_array()) {
            keys.push(PathKey::at(
                cam.eye.to_array(),
                Some((cam.eye + cam.forward() * 1000.0).to_array()),
            ));
        }
        keys.dedup_by(|a, b| a.position == b.position);
        (keys.len() >= 2 && self.distance_m > 0.0).then(|| PathSection {
            speed_mps: (self.distance_m / self.seconds.max(1e-3)).max(1.0),
            duration_s: None,
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
        .map(|k| {
            let mut t = toml::Table::new();
            t.insert(
                "position".into(),
                toml::Value::try_from(k.position).expect("numbers"),
            );
            if let Some(l) = k.look_at {
                t.insert("look_at".into(), toml::Value::try_from(l).expect("numbers"));
            }
            toml::Value::Table(t)
        })
        .collect();
    let mut p = toml::Table::new();
    p.insert("speed_mps".into(), toml::Value::Float(path.speed_mps));
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
            r.record(&c, 0.1);
        }
        let path = r.finish(&c).unwrap();
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
        assert!(crate::app::path::CameraPath::new(scene.path.as_ref().unwrap()).is_ok());
    }
}
