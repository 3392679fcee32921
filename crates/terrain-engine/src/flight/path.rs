//! Camera paths (the scene's `[path]`, `docs/scene.md`): a smooth curve through the key positions,
//! travelled at constant speed, looking at each key's `look_at` or ahead along the curve.
//!
//! Rules: the curve is a centripetal Catmull-Rom spline through every key (the end keys
//! mirrored), so it passes through each key without overshooting loops where keys bunch up.
//! Arc length is tabulated (512 samples a segment) and inverted by bisection, so equal steps in
//! time are equal steps in distance. The view direction at a point between keys i and i+1 blends,
//! with a smoothstep in the segment's parameter, key i's and key i+1's directions, where a key's
//! direction is towards its `look_at`, or else the curve's direction `LOOK_AHEAD_S` seconds ahead.
//! A camera the curve takes under the sketch's surface is lifted to `CLEARANCE_M` above it.
//!
//! Rejected alternative: uniform Catmull-Rom by key index, traversed in its own parameter. Its
//! speed changes with the spacing of the keys (a camera that lurches), and its uniform
//! parameterisation loops past closely spaced keys.

use crate::Camera;
use crate::scene::{self as place, ground_under};
use crate::scene::{PathKey, PathSection, Scene};
use crate::sketch::Atlas;
use crate::{Error, Result};
use glam::{DVec2, DVec3};

/// Arc-length samples per segment.
const SAMPLES: usize = 512;
/// How far ahead (in seconds of travel) a key without `look_at` looks.
pub const LOOK_AHEAD_S: f64 = 2.0;
/// The least height above the sketch's surface a path's camera keeps.
pub const CLEARANCE_M: f64 = 2.0;

/// A sketch's camera path: the curve through its keys and its arc length.
pub struct CameraPath {
    keys: Vec<PathKey>,
    /// Metres a second along the curve.
    pub speed_mps: f64,
    /// Cumulative arc length at each (segment, sample), `SAMPLES + 1` per segment.
    lengths: Vec<f64>,
}

impl CameraPath {
    /// The path through `section`'s keys (at least two).
    pub fn new(section: &PathSection) -> Result<CameraPath> {
        if section.keys.len() < 2 {
            return Err(Error::value(
                "path.keys",
                "a camera path needs at least 2 keys",
            ));
        }
        let mut path = CameraPath {
            keys: section.keys.clone(),
            speed_mps: section.speed_mps,
            lengths: Vec::new(),
        };
        let mut total = 0.0;
        for seg in 0..path.segments() {
            let mut prev = path.curve(seg, 0.0);
            path.lengths.push(total);
            for k in 1..=SAMPLES {
                let p = path.curve(seg, k as f64 / SAMPLES as f64);
                total += (p - prev).length();
                path.lengths.push(total);
                prev = p;
            }
        }
        if !(total.is_finite() && total > 1e-6) {
            return Err(Error::value(
                "path.keys",
                "the camera path has no length (its keys coincide)",
            ));
        }
        Ok(path)
    }

    /// The scene's path (its keys placed in world metres by `scene::place`); without one, a
    /// scene whose camera has a place flies it straight ahead (its horizontal view direction)
    /// for 10 s at the default speed, keeping its view direction, and a scene without one orbits
    /// the sketch (`scene::place::default_path`) in 10 s.
    pub fn of_scene(scene: &Scene, atlas: &Atlas) -> Result<CameraPath> {
        if scene.planet().is_some() {
            return Err(Error::value(
                "path",
                "a planet scene flies a planet's flight, not a planar path",
            ));
        }
        if let Some(p) = &scene.path {
            let keys = p
                .keys
                .iter()
                .enumerate()
                .map(|(k, key)| place::resolve_key(scene, atlas, k, key))
                .collect::<Result<Vec<_>>>()?;
            return CameraPath::new(&PathSection { keys, ..p.clone() });
        }
        if !scene.camera.is_placed() {
            let mut orbit = CameraPath::new(&place::default_path(scene, atlas))?;
            orbit.speed_mps = orbit.length_m() / place::DEFAULT_PATH_S;
            return Ok(orbit);
        }
        let (eye, look) = place::pose(scene, atlas)?;
        let speed = 150.0;
        let heading = (look - eye).truncate().try_normalize().unwrap_or(DVec2::Y);
        let step = (heading * speed * 10.0).extend(0.0);
        CameraPath::new(&PathSection {
            speed_mps: speed,
            duration_s: None,
            keys: vec![
                PathKey::at(eye.to_array(), Some(look.to_array())),
                PathKey::at((eye + step).to_array(), Some((look + step).to_array())),
            ],
        })
    }

    fn segments(&self) -> usize {
        self.keys.len() - 1
    }

    /// The curve's length, metres.
    pub fn length_m(&self) -> f64 {
        *self.lengths.last().unwrap_or(&0.0)
    }

    /// Seconds from the first key to the last.
    pub fn duration_s(&self) -> f64 {
        self.length_m() / self.speed_mps
    }

    fn key(&self, i: isize) -> DVec3 {
        let n = self.keys.len() as isize;
        // `Scene::check` gives every key of a planar path its position.
        let at = |k: isize| DVec3::from(self.keys[k as usize].position.unwrap_or_default());
        match i {
            i if i < 0 => 2.0 * at(0) - at(1),
            i if i >= n => 2.0 * at(n - 1) - at(n - 2),
            i => at(i),
        }
    }

    /// Centripetal Catmull-Rom (Barry–Goldman) on segment `seg` at parameter `u` ∈ [0, 1].
    fn curve(&self, seg: usize, u: f64) -> DVec3 {
        let i = seg as isize;
        let p = [
            self.key(i - 1),
            self.key(i),
            self.key(i + 1),
            self.key(i + 2),
        ];
        let knot = |a: DVec3, b: DVec3| (b - a).length().sqrt().max(1e-9);
        let t0 = 0.0;
        let t1 = t0 + knot(p[0], p[1]);
        let t2 = t1 + knot(p[1], p[2]);
        let t3 = t2 + knot(p[2], p[3]);
        let t = t1 + u * (t2 - t1);
        let lerp = |a: DVec3, b: DVec3, ta: f64, tb: f64| a + (b - a) * ((t - ta) / (tb - ta));
        let a1 = lerp(p[0], p[1], t0, t1);
        let a2 = lerp(p[1], p[2], t1, t2);
        let a3 = lerp(p[2], p[3], t2, t3);
        let b1 = lerp(a1, a2, t0, t2);
        let b2 = lerp(a2, a3, t1, t3);
        lerp(b1, b2, t1, t2)
    }

    /// The segment and its parameter at arc length `s` (clamped to the path).
    fn locate(&self, s: f64) -> (usize, f64) {
        let s = s.clamp(0.0, self.length_m());
        let k = self
            .lengths
            .partition_point(|&l| l <= s)
            .clamp(1, self.lengths.len() - 1);
        let (lo, hi) = (self.lengths[k - 1], self.lengths[k]);
        let frac = if hi > lo { (s - lo) / (hi - lo) } else { 0.0 };
        let seg = ((k - 1) / (SAMPLES + 1)).min(self.segments() - 1);
        let local = (k - 1) - seg * (SAMPLES + 1);
        (
            (seg),
            ((local as f64 + frac) / SAMPLES as f64).clamp(0.0, 1.0),
        )
    }

    /// The position at arc length `s`.
    pub fn position(&self, s: f64) -> DVec3 {
        let (seg, u) = self.locate(s);
        self.curve(seg, u)
    }

    /// The unit view direction at arc length `s`.
    pub fn direction(&self, s: f64) -> DVec3 {
        let (seg, u) = self.locate(s);
        let eye = self.curve(seg, u);
        let ahead = {
            let a = self.speed_mps * LOOK_AHEAD_S;
            let (p, q) = if s + a <= self.length_m() {
                (eye, self.position(s + a))
            } else {
                (self.position(s - a), eye)
            };
            (q - p).try_normalize().unwrap_or(DVec3::Y)
        };
        let towards = |k: usize| match self.keys[k].look_at {
            Some(t) => (DVec3::from(t) - eye).try_normalize().unwrap_or(ahead),
            None => ahead,
        };
        let w = u * u * (3.0 - 2.0 * u);
        (towards(seg) * (1.0 - w) + towards(seg + 1) * w)
            .try_normalize()
            .unwrap_or(ahead)
    }

    /// The camera at time `t_s` (seconds from the start), lifted above the sketch's surface,
    /// with the scene camera's lens and image.
    pub fn camera(&self, t_s: f64, scene: &Scene, atlas: &Atlas) -> Result<Camera> {
        let s = t_s * self.speed_mps;
        let mut eye = self.position(s);
        if let Some(ground) = ground_under(atlas, eye.truncate())? {
            eye.z = eye.z.max(ground + CLEARANCE_M);
        }
        let mut base = scene.clone();
        base.camera.aim(eye, eye + self.direction(s) * 100.0);
        crate::scene::camera_of(&base, atlas)
    }
}

/// What a command flies: a sketch's camera path, or a flight over a planet.
pub enum Flight {
    /// Over a sketch.
    Path(CameraPath),
    /// Over a planet.
    Planet(PlanetFlight),
}

impl Flight {
    /// The scene's `[path]`, or without one its camera flown straight ahead (see
    /// [`CameraPath::of_scene`] and [`PlanetFlight::of_scene`]).
    pub fn of_scene(scene: &Scene, atlas: &Atlas) -> Result<Flight> {
        Ok(match scene.planet() {
            Some(p) => Flight::Planet(PlanetFlight::of_scene(scene, p.radius_m)?),
            None => Flight::Path(CameraPath::of_scene(scene, atlas)?),
        })
    }

    /// Seconds from the first key to the last.
    pub fn duration_s(&self) -> f64 {
        match self {
            Flight::Path(p) => p.duration_s(),
            Flight::Planet(f) => f.duration_s,
        }
    }

    /// The camera at time `t_s` from the start, with the scene camera's lens and image.
    pub fn camera(&self, t_s: f64, scene: &Scene, atlas: &Atlas) -> Result<Camera> {
        match self {
            Flight::Path(p) => p.camera(t_s, scene, atlas),
            Flight::Planet(f) => f.camera(t_s, scene, atlas),
        }
    }

    /// `frames` cameras `1/fps` seconds apart from the start (the last no further than the end).
    pub fn cameras(
        &self,
        frames: usize,
        fps: f64,
        scene: &Scene,
        atlas: &Atlas,
    ) -> Result<Vec<Camera>> {
        (0..frames)
            .map(|i| self.camera((i as f64 / fps).min(self.duration_s()), scene, atlas))
            .collect()
    }

    /// Where the flight comes from, for reports.
    pub fn source(&self, scene: &Scene) -> &'static str {
        match (self, scene.path.is_some()) {
            (_, true) => "scene [path]",
            (Flight::Path(_), false) => "default: straight ahead at 150 m/s",
            (Flight::Planet(_), false) => {
                "default: straight ahead, at the camera's altitude, its altitude's distance in 10 s"
            }
        }
    }
}

/// The eye of `camera` in world metres: a planet's from its centre (`radius` its sphere's).
pub fn world_eye(camera: &Camera, radius: Option<f64>) -> DVec3 {
    match (camera.geo, radius) {
        (Some(g), Some(r)) => {
            crate::planet::unit(g.lat, g.lon) * r
                + crate::planet::Tangent::at(g.lat, g.lon).world(camera.eye)
        }
        _ => camera.eye,
    }
}

/// A flight over a planet (`[path]` keys with `lat_deg`, `lon_deg`, `altitude_m`, `heading_deg`,
/// `pitch_deg`): each key to the next in equal time, `path.duration_s` (60 s by default) in all.
/// Between two keys the nadir moves along the great circle, the altitude geometrically (a
/// descent from orbit to the ground spends as long on each factor of height), heading the short
/// way round and pitch linearly, each eased in and out by a smoothstep, so the camera rests at
/// every key. Constant speed, as the planar path keeps it, means nothing across seven orders of
/// magnitude of height.
pub struct PlanetFlight {
    keys: Vec<PathKey>,
    /// The flight's length in time, seconds.
    pub duration_s: f64,
    /// Whether the camera rests at each key (a scene's path) or moves evenly (the default pass).
    ease: bool,
}

/// A planet flight's default duration, seconds.
pub const PLANET_FLIGHT_S: f64 = 60.0;
/// The default pass over a planet without a `[path]`: this long, seconds.
pub const PLANET_PASS_S: f64 = 10.0;

impl PlanetFlight {
    /// The scene's `[path]`; without one, a pass of [`PLANET_PASS_S`] seconds straight ahead
    /// along the great circle of the camera's heading, at its altitude and pitch, covering its
    /// altitude in ground distance (at least 10 m, at most a tenth of `radius`): from every height
    /// the same apparent speed, evenly, with no rest at either end.
    pub fn of_scene(scene: &Scene, radius: f64) -> Result<PlanetFlight> {
        if let Some(p) = &scene.path {
            return Ok(PlanetFlight {
                keys: p.keys.clone(),
                duration_s: p.duration_s.unwrap_or(PLANET_FLIGHT_S),
                ease: true,
            });
        }
        let c = &scene.camera;
        let (lat, lon) = (
            c.lat_deg.unwrap_or(0.0).to_radians(),
            c.lon_deg.unwrap_or(0.0).to_radians(),
        );
        let altitude = c.altitude_m.unwrap_or(1.0);
        let angle = altitude.clamp(10.0, 0.1 * radius) / radius;
        let (lat2, lon2, track) = crate::planet::travel(lat, lon, c.heading().to_radians(), angle);
        let key = |lat: f64, lon: f64, heading: f64| PathKey {
            position: None,
            look_at: None,
            map_xy: None,
            lat_deg: Some(lat.to_degrees()),
            lon_deg: Some(lon.to_degrees()),
            altitude_m: Some(altitude),
            heading_deg: Some(heading),
            pitch_deg: Some(c.pitch()),
        };
        Ok(PlanetFlight {
            keys: vec![
                key(lat, lon, c.heading()),
                key(lat2, lon2, track.to_degrees()),
            ],
            duration_s: PLANET_PASS_S,
            ease: false,
        })
    }

    /// The camera keys' values at time `t_s`: latitude, longitude (degrees), altitude (metres),
    /// heading and pitch (degrees).
    pub fn at(&self, t_s: f64) -> [f64; 5] {
        let segments = (self.keys.len() - 1) as f64;
        let x = (t_s / self.duration_s).clamp(0.0, 1.0) * segments;
        let seg = (x.floor() as usize).min(self.keys.len() - 2);
        let u = x - seg as f64;
        let w = if self.ease {
            u * u * (3.0 - 2.0 * u)
        } else {
            u
        };
        let (a, b) = (&self.keys[seg], &self.keys[seg + 1]);
        let get = |k: &PathKey| {
            (
                k.lat_deg.unwrap_or(0.0).to_radians(),
                k.lon_deg.unwrap_or(0.0).to_radians(),
                k.altitude_m.unwrap_or(1.0),
                k.heading_deg.unwrap_or(0.0),
                k.pitch_deg.unwrap_or(0.0),
            )
        };
        let (la, oa, ha, da, pa) = get(a);
        let (lb, ob, hb, db, pb) = get(b);
        // The great circle between the two nadirs.
        let (ua, ub) = (crate::planet::unit(la, oa), crate::planet::unit(lb, ob));
        let angle = ua.angle_between(ub);
        let dir = if angle < 1e-12 {
            ua
        } else {
            (ua * ((1.0 - w) * angle).sin() + ub * (w * angle).sin()) / angle.sin()
        };
        let (lat, lon) = crate::planet::lat_lon(dir);
        let altitude = (ha.ln() + (hb.ln() - ha.ln()) * w).exp();
        let turn = (db - da + 540.0).rem_euclid(360.0) - 180.0;
        [
            lat.to_degrees(),
            lon.to_degrees(),
            altitude,
            da + turn * w,
            pa + (pb - pa) * w,
        ]
    }

    /// The camera at time `t_s`, with the scene camera's lens and image.
    pub fn camera(&self, t_s: f64, scene: &Scene, atlas: &Atlas) -> Result<Camera> {
        let [lat, lon, altitude, heading, pitch] = self.at(t_s);
        let mut s = scene.clone();
        let c = &mut s.camera;
        c.lat_deg = Some(lat);
        c.lon_deg = Some(lon);
        c.altitude_m = Some(altitude);
        c.heading_deg = Some(heading);
        c.pitch_deg = Some(pitch);
        crate::scene::camera_of(&s, atlas)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A planet's flight rests at each key, spends equal time from key to key, and halves the
    /// geometric mean of two altitudes at the middle of their segment.
    #[test]
    fn a_planet_flight_passes_its_keys_and_descends_geometrically() {
        let key = |lat: f64, lon: f64, alt: f64, heading: f64| PathKey {
            position: None,
            look_at: None,
            map_xy: None,
            lat_deg: Some(lat),
            lon_deg: Some(lon),
            altitude_m: Some(alt),
            heading_deg: Some(heading),
            pitch_deg: Some(-30.0),
        };
        let flight = PlanetFlight {
            keys: vec![
                key(10.0, 170.0, 2e7, 350.0),
                key(12.0, -170.0, 2e3, 10.0),
                key(12.0, -169.0, 2.0, 10.0),
            ],
            duration_s: 20.0,
            ease: true,
        };
        let start = flight.at(0.0);
        assert!(
            (start[0] - 10.0).abs() < 1e-9
                && (start[1] - 170.0).abs() < 1e-9
                && (start[2] - 2e7).abs() < 1e-3
        );
        let mid = flight.at(5.0);
        assert!(
            (mid[2] - (2e7f64 * 2e3).sqrt()).abs() < 1e-6 * mid[2],
            "{}",
            mid[2]
        );
        // Across the date line, not around the world; heading through north, not south.
        assert!(mid[1].abs() > 170.0, "{}", mid[1]);
        assert!(
            mid[3].rem_euclid(360.0) < 1.0 || mid[3].rem_euclid(360.0) > 359.0,
            "{}",
            mid[3]
        );
        let key1 = flight.at(10.0);
        assert!((key1[2] - 2e3).abs() < 1e-6 && (key1[0] - 12.0).abs() < 1e-9);
        let end = flight.at(20.0);
        assert!((end[2] - 2.0).abs() < 1e-9 && (end[1] + 169.0).abs() < 1e-9);
    }

    fn section(points: &[[f64; 3]]) -> PathSection {
        PathSection {
            speed_mps: 100.0,
            duration_s: None,
            keys: points.iter().map(|&p| PathKey::at(p, None)).collect(),
        }
    }

    #[test]
    fn passes_through_every_key_at_constant_speed() {
        let keys = [
            [0.0, 0.0, 100.0],
            [1000.0, 0.0, 120.0],
            [1100.0, 50.0, 120.0],
            [3000.0, 2000.0, 300.0],
        ];
        let path = CameraPath::new(&section(&keys)).unwrap();
        for key in keys {
            let nearest = (0..=4000)
                .map(|k| {
                    (path.position(path.length_m() * k as f64 / 4000.0) - DVec3::from(key)).length()
                })
                .fold(f64::INFINITY, f64::min);
            assert!(nearest < 2.0, "key {key:?} missed by {nearest} m");
        }
        // Equal steps in distance along the curve: chords of a 10 m step are 10 m (to curvature).
        let steps: Vec<f64> = (0..200)
            .map(|k| {
                let s = path.length_m() * k as f64 / 200.0;
                (path.position(s + 10.0) - path.position(s)).length()
            })
            .collect();
        let (lo, hi) = steps
            .iter()
            .fold((f64::MAX, 0.0f64), |(a, b), &v| (a.min(v), b.max(v)));
        assert!(lo > 9.5 && hi < 10.02, "step lengths {lo}..{hi}");
    }

    #[test]
    fn looks_ahead_or_at_targets() {
        let mut s = section(&[[0.0, 0.0, 100.0], [1000.0, 0.0, 100.0]]);
        let path = CameraPath::new(&s).unwrap();
        let d = path.direction(300.0);
        assert!((d - DVec3::X).length() < 1e-6, "{d}");
        s.keys[0].look_at = Some([0.0, 1000.0, 100.0]);
        s.keys[1].look_at = Some([1000.0, 1000.0, 100.0]);
        let path = CameraPath::new(&s).unwrap();
        let d = path.direction(500.0);
        assert!((d - DVec3::Y).length() < 1e-6, "{d}");
    }

    #[test]
    fn coincident_keys_are_an_error() {
        assert!(CameraPath::new(&section(&[[5.0, 5.0, 5.0], [5.0, 5.0, 5.0]])).is_err());
    }
}
