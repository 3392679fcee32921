//! Random cameras over a scene (a batch's `[random]`, the Python `random_cameras`): a pure
//! function of (seed, index), so shards and reruns draw the same ones. Rejected: a generator
//! crate's stream, whose values may change between its versions and would change the cameras.

use crate::camera::Camera;
use crate::error::Result;
use crate::scene::{self, Scene, ground_under};
use crate::sketch::Atlas;
use glam::{DVec2, DVec3};

/// Random cameras stand this far above the sketch's ground, plus the detail's reach (metres).
pub const RANDOM_HEIGHT_M: (f64, f64) = (30.0, 3000.0);
/// Random cameras over a planet stand this far above its ground (metres): from a walk to orbit.
pub const RANDOM_PLANET_ALTITUDE_M: (f64, f64) = (2.0, 2e7);

/// SplitMix64: a tiny, well-mixed generator, so a random camera is a pure function of
/// (seed, index).
struct SplitMix(u64);

impl SplitMix {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Random camera `i` over `atlas`: above the ground by 30 m to 3 km (log-uniform) plus the
/// detail's reach, looking at a point of the sketch 2 to 8 heights away in a random heading.
/// Returns `scene` with its camera keys set to it, and the camera.
pub fn random_camera(
    scene: &Scene,
    atlas: &Atlas,
    reach_m: f64,
    seed: u64,
    i: usize,
) -> Result<(Scene, Camera)> {
    let mut rng = SplitMix(seed ^ (i as u64).wrapping_mul(0xd1b5_4a32_d192_ed03));
    for _ in 0..3 {
        rng.next();
    }
    if let Some(p) = scene.planet() {
        return random_planet_camera(scene, atlas, p.radius_m, &mut rng);
    }
    let (lo, hi) = (atlas.origin, atlas.max_corner());
    let inside = |u: f64, v: f64| DVec2::new(lo.x + (hi.x - lo.x) * u, lo.y + (hi.y - lo.y) * v);
    let ground = inside(0.1 + 0.8 * rng.next(), 0.1 + 0.8 * rng.next());
    let (h0, h1) = RANDOM_HEIGHT_M;
    let above = (h0.ln() + (h1.ln() - h0.ln()) * rng.next()).exp();
    let z = ground_under(atlas, ground)?.unwrap_or(atlas.max_m as f64);
    let eye = ground.extend(z + reach_m + above);
    let heading = std::f64::consts::TAU * rng.next();
    let distance = above * (2.0 + 6.0 * rng.next());
    let aim = ground + DVec2::new(heading.cos(), heading.sin()) * distance;
    let aim = aim.clamp(lo, hi);
    let target = aim.extend(ground_under(atlas, aim)?.unwrap_or(z));
    let mut s = scene.clone();
    let target = if (target - eye).truncate().length() < 1.0 {
        target - DVec3::Y
    } else {
        target
    };
    s.camera.aim(eye, target);
    let camera = scene::camera_of(&s, atlas)?;
    Ok((s, camera))
}

/// A random camera over a planet: its nadir uniform over the sphere, its altitude log-uniform
/// over [`RANDOM_PLANET_ALTITUDE_M`], a random heading, and a pitch from 40° below the horizon
/// (its dip at that altitude) to 10° above it, no steeper than straight down: the ground is in
/// view from any height, the sky and limb often.
fn random_planet_camera(
    scene: &Scene,
    atlas: &Atlas,
    radius: f64,
    rng: &mut SplitMix,
) -> Result<(Scene, Camera)> {
    let lat = (2.0 * rng.next() - 1.0).asin();
    let lon = std::f64::consts::TAU * rng.next() - std::f64::consts::PI;
    let (h0, h1) = RANDOM_PLANET_ALTITUDE_M;
    let altitude = (h0.ln() + (h1.ln() - h0.ln()) * rng.next()).exp();
    let dip = (radius / (radius + altitude)).acos().to_degrees();
    let mut s = scene.clone();
    let c = &mut s.camera;
    c.lat_deg = Some(lat.to_degrees());
    c.lon_deg = Some(lon.to_degrees());
    c.altitude_m = Some(altitude);
    c.heading_deg = Some(360.0 * rng.next());
    c.pitch_deg = Some((-dip - 40.0 + 50.0 * rng.next()).max(-90.0));
    let camera = scene::camera_of(&s, atlas)?;
    Ok((s, camera))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn generator_is_uniform_enough_and_deterministic() {
        let mut a = SplitMix(7);
        let v: Vec<f64> = (0..10000).map(|_| a.next()).collect();
        let mean = v.iter().sum::<f64>() / v.len() as f64;
        assert!((mean - 0.5).abs() < 0.01 && v.iter().all(|x| (0.0..1.0).contains(x)));
        assert_eq!(SplitMix(7).next(), v[0]);
    }
}
