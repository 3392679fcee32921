//! Random cameras: a pure function of (seed, index), so shards and reruns draw the same ones.

use crate::camera::Camera;
use crate::error::Result;
use crate::scene::{self, Scene, ground_under};
use crate::sketch::Atlas;
use glam::{DVec2, DVec3};

/// Random cameras stand this far above the sketch's ground, plus the detail's reach (metres).
pub const RANDOM_HEIGHT_M: (f64, f64) = (30.0, 3000.0);

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
pub fn random_camera(
    scene: &Scene,
    atlas: &Atlas,
    reach_m: f64,
    seed: u64,
    i: usize,
) -> Result<Camera> {
    if scene.planet().is_some() {
        return Err(crate::Error::value(
            "random",
            "random cameras over a planet are not built yet: give the jobs their cameras",
        ));
    }
    let mut rng = SplitMix(seed ^ (i as u64).wrapping_mul(0xd1b5_4a32_d192_ed03));
    for _ in 0..3 {
        rng.next();
    }
    let (lo, hi) = (atlas.origin, atlas.max_corner());
    let inside = |u: f64, v: f64| DVec2::new(lo.x + (hi.x - lo.x) * u, lo.y + (hi.y - lo.y) * v);
    let ground = inside(0.1 + 0.8 * rng.next(), 0.1 + 0.8 * rng.next());
    let (h0, h1) = RANDOM_HEIGHT_M;
    let above = (h0.ln() + (h1.ln() - h0.ln()) * rng.next()).exp();
    let z = ground_under(atlas, ground).unwrap_or(atlas.max_m as f64);
    let eye = ground.extend(z + reach_m + above);
    let heading = std::f64::consts::TAU * rng.next();
    let distance = above * (2.0 + 6.0 * rng.next());
    let aim = ground + DVec2::new(heading.cos(), heading.sin()) * distance;
    let aim = aim.clamp(lo, hi);
    let target = aim.extend(ground_under(atlas, aim).unwrap_or(z));
    let mut s = scene.clone();
    let target = if (target - eye).truncate().length() < 1.0 {
        target - DVec3::Y
    } else {
        target
    };
    s.camera.aim(eye, target);
    scene::camera_of(&s, atlas)
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
