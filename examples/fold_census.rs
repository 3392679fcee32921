//! The census behind the guard's shortcut (`stage::warp::fallback_pairs`): on many cameras, how
//! many column pairs the plain warp folds, and what the guarded warp gives with the shortcut at
//! each threshold against its rounds alone (columns on the mean column warp, the share of visible
//! cells with density ratio in [½, 1] and [½, 2], flipped cells).
//!
//! The cameras: each bundled scene's own, 40 along its flight (its `[path]`, or straight ahead),
//! and on the three near scenes' sketches 80 at random (10 m to 5 km above the sketch's highest
//! point, any heading, pitched 80° down to 10° up) from a fixed seed.
//!
//! At the bundled scenes' `warp.size`, 128.
//!
//! `cargo run --release --example fold_census`

use glam::DVec3;
use std::path::PathBuf;
use terrain_engine::Camera;
use terrain_engine::flight::path::Flight;
use terrain_engine::scene::{self, Scene, WarpMethod};
use terrain_engine::stage::CpuStage;
use terrain_engine::stage::pair_unfolded;
use terrain_engine::stage::quality;

/// Thresholds tried, in folded pairs of 127; the last is the rounds alone.
const THRESHOLDS: [usize; 7] = [8, 12, 16, 24, 32, 64, usize::MAX];

/// One camera under one threshold: columns on the mean, the two shares, flipped cells.
type Outcome = (usize, f64, f64, usize);

fn main() -> anyhow::Result<()> {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("sketches");
    // (plain warp's folded pairs, outcome per threshold) per camera
    let mut census: Vec<(usize, Vec<Outcome>)> = Vec::new();
    let mut seed: u64 = 0x9e37_79b9_7f4a_7c15;
    for name in [
        "jacksboro",
        "jacksboro-high",
        "gaussian",
        "gaussian-high",
        "hills",
        "hills-high",
        "jacksboro-flight",
    ] {
        let scene = Scene::load(&dir.join(format!("{name}.toml")))?;
        let atlas = scene::load_atlas(&scene)?;
        let detail = scene::detail_of(&scene, &atlas);
        let mut cameras = vec![scene::camera_of(&scene, &atlas)?];
        let flight = Flight::of_scene(&scene, &atlas)?;
        for k in 0..40 {
            let t = flight.duration_s() * k as f64 / 39.0;
            cameras.push(flight.camera(t, &scene, &atlas)?);
        }
        if ["jacksboro", "gaussian", "hills"].contains(&name) {
            for _ in 0..80 {
                cameras.push(random_camera(&scene, &atlas, &mut seed)?);
            }
        }
        let mut stage = CpuStage::new(&scene, &detail)?;
        for camera in &cameras {
            stage.forget();
            stage.warp.method = WarpMethod::Plain;
            stage.run(&atlas, camera);
            let n = stage.warp.n();
            let folded = (0..n - 1)
                .filter(|&s| !pair_unfolded(&stage.warp.phi, n, s))
                .count();
            stage.warp.method = WarpMethod::Guarded;
            let outcomes = THRESHOLDS
                .iter()
                .map(|&pairs| {
                    stage.warp.fallback_pairs = pairs;
                    let spacing = stage.sketch_map.spacing;
                    stage.warp.run(&stage.importance.importance, spacing as f32);
                    let mut ratios = Vec::new();
                    let q = quality::measure(
                        &stage.warp.phi,
                        n,
                        spacing,
                        &stage.importance,
                        &mut ratios,
                    );
                    let w = &stage.warp;
                    (
                        w.guarded_columns,
                        q.ratio_within_0_5_1,
                        q.ratio_within_0_5_2,
                        q.flipped_cells,
                    )
                })
                .collect();
            census.push((folded, outcomes));
        }
    }
    report(&census);
    Ok(())
}

/// A camera over the sketch from `seed` (xorshift), or the scene's error if it cannot be made.
fn random_camera(
    scene: &Scene,
    atlas: &terrain_engine::sketch::Atlas,
    seed: &mut u64,
) -> anyhow::Result<Camera> {
    let mut rnd = || {
        *seed ^= *seed << 13;
        *seed ^= *seed >> 7;
        *seed ^= *seed << 17;
        (*seed >> 11) as f64 / (1u64 << 53) as f64
    };
    let (lo, hi) = (atlas.origin, atlas.max_corner());
    let x = lo.x + (hi.x - lo.x) * (0.1 + 0.8 * rnd());
    let y = lo.y + (hi.y - lo.y) * (0.1 + 0.8 * rnd());
    let z = atlas.max_m as f64 + 10f64.powf(1.0 + 2.7 * rnd());
    let heading = std::f64::consts::TAU * rnd();
    let pitch = (-80.0 + 90.0 * rnd()).to_radians();
    let look = DVec3::new(
        heading.cos() * pitch.cos(),
        heading.sin() * pitch.cos(),
        pitch.sin(),
    );
    let eye = DVec3::new(x, y, z);
    let mut s = scene.clone();
    s.camera.aim(eye, eye + look * 100.0);
    Ok(scene::camera_of(&s, atlas)?)
}

fn report(census: &[(usize, Vec<Outcome>)]) {
    let rounds = THRESHOLDS.len() - 1;
    println!("{} cameras", census.len());
    println!("\nplain warp's folded pairs → the guard's rounds alone (columns on the mean):");
    for lo in (0..128).step_by(16) {
        let on_mean: Vec<usize> = census
            .iter()
            .filter(|(f, _)| (lo..lo + 16).contains(f))
            .map(|(_, o)| o[rounds].0)
            .collect();
        if let Some(least) = on_mean.iter().min() {
            let all = on_mean.iter().filter(|&&m| m == 128).count();
            let mean = on_mean.iter().sum::<usize>() as f64 / on_mean.len() as f64;
            println!(
                "  {lo:3}–{:3}: {:3} cameras, {all:3} end with all 128, least {least:3}, mean {mean:5.1}",
                lo + 15,
                on_mean.len()
            );
        }
    }
    println!("\nthe shortcut at each threshold against the rounds alone:");
    for (k, &pairs) in THRESHOLDS[..rounds].iter().enumerate() {
        let diff = |f: &dyn Fn(&Outcome) -> f64| -> Vec<f64> {
            census
                .iter()
                .map(|(_, o)| f(&o[k]) - f(&o[rounds]))
                .collect()
        };
        let in1 = diff(&|o| 100.0 * o.1);
        let in2 = diff(&|o| 100.0 * o.2);
        let cols = diff(&|o| o.0 as f64);
        let changed = cols.iter().filter(|&&c| c != 0.0).count();
        let flipped: usize = census.iter().map(|(_, o)| o[k].3).sum();
        let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
        let least = |v: &[f64]| v.iter().copied().fold(f64::INFINITY, f64::min);
        let most = |v: &[f64]| v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        println!(
            "  {pairs:2} pairs: {changed:3} cameras changed; [½, 1] {:+.3} points mean ({:+.2} … {:+.2}), [½, 2] {:+.3} mean (least {:+.2}); columns on the mean {:+.2} mean (most {:+.0}); {flipped} flipped",
            mean(&in1),
            least(&in1),
            most(&in1),
            mean(&in2),
            least(&in2),
            mean(&cols),
            most(&cols),
        );
    }
}
