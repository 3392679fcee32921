//! Extreme cases of the CPU stage: each must give a finite, sound warp (see `assert_sound`).

mod common;
use common::*;
use glam::DVec2;
use terrain_engine::scene::WarpMethod;
use terrain_engine::stage::Warp;

fn synthetic(name: &str, size: usize, position: [f64; 3], look_at: [f64; 3]) -> String {
    format!(
        "[sketch]\nsynthetic = \"{name}\"\nsize = {size}\n[camera]\nposition = {position:?}\nlook_at = {look_at:?}\n"
    )
}

/// Ground height of a synthetic sketch under (x, y), read off the atlas.
fn ground(name: &str, x: f64, y: f64) -> f64 {
    let s = scene(
        &synthetic(name, 257, [0.0, 0.0, 1e4], [1.0, 1.0, 0.0]),
        manifest_dir(),
    );
    let a = terrain_engine::scene::load_atlas(&s).unwrap();
    a.sample_texel(x / a.dx, y / a.dy, 0.0) as f64
}

#[test]
fn one_metre_above_the_ground_looking_across() {
    let z = ground("hills", 3000.0, 3000.0) + 1.0;
    let s = scene(
        &synthetic(
            "hills",
            257,
            [3000.0, 3000.0, z],
            [6000.0, 5000.0, z - 50.0],
        ),
        manifest_dir(),
    );
    let r = run(&s);
    assert!(r.stage.sketch_map.visible);
    assert_sound(&r, "1 m above hills");
    assert!(
        r.quality.cells_visible > 1000,
        "{}",
        r.quality.cells_visible
    );
}

#[test]
fn one_metre_above_a_cliff_edge() {
    // The cliff steps from 100 m to 500 m at x = 128·30 m; stand 1 m above its top edge, looking
    // over and down.
    let x = 128.0 * 30.0 + 1.0;
    let s = scene(
        &synthetic(
            "cliff",
            257,
            [x, 3000.0, 501.0],
            [x - 2000.0, 4000.0, 100.0],
        ),
        manifest_dir(),
    );
    let r = run(&s);
    assert_sound(&r, "above a cliff");
}

#[test]
fn looking_straight_down() {
    let s = scene(
        &synthetic(
            "gaussian",
            257,
            [3840.0, 3840.0, 4000.0],
            [3840.0, 3840.0, 0.0],
        ),
        manifest_dir(),
    );
    let r = run(&s);
    assert_sound(&r, "straight down");
    assert!(r.quality.cells_visible > 10_000);
}

#[test]
fn looking_at_the_sky_shows_nothing_and_stays_sound() {
    let s = scene(
        &synthetic(
            "hills",
            257,
            [3000.0, 3000.0, 2000.0],
            [3000.0, 3100.0, 5000.0],
        ),
        manifest_dir(),
    );
    let r = run(&s);
    assert!(!r.stage.sketch_map.visible);
    assert_eq!(r.quality.cells_visible, 0);
    assert_sound(&r, "sky");
}

#[test]
fn camera_outside_the_sketch() {
    let s = scene(
        &synthetic(
            "ridges",
            257,
            [-3000.0, -2000.0, 900.0],
            [3840.0, 3840.0, 300.0],
        ),
        manifest_dir(),
    );
    let r = run(&s);
    assert!(r.stage.sketch_map.visible);
    assert_sound(&r, "outside");
    // The region encloses the atlas's visible part, not the empty ground around the camera: it
    // reaches past the atlas only by the few texels of slack a region larger than the atlas has.
    let m = &r.stage.sketch_map;
    // The camera looks north-east, so the region is turned (`stage::Turn`).
    assert_ne!(m.turn, terrain_engine::stage::Turn::None);
    let centre = m.world(DVec2::splat(0.5 * m.extent()));
    let atlas_centre = 0.5 * (r.atlas.origin + r.atlas.max_corner());
    assert!(
        (centre - atlas_centre).abs().max_element() <= m.spacing,
        "{centre} vs {atlas_centre}"
    );
}

#[test]
fn fifty_kilometres_up() {
    let s = scene(
        &synthetic(
            "hills",
            257,
            [3840.0, 3000.0, 50_000.0],
            [3840.0, 3900.0, 0.0],
        ),
        manifest_dir(),
    );
    let r = run(&s);
    assert_sound(&r, "50 km up");
    assert!(r.quality.cells_visible > 1000);
}

#[test]
fn tiny_two_by_two_atlas() {
    let s = scene(
        &synthetic("gaussian", 2, [10.0, -50.0, 200.0], [15.0, 15.0, 0.0]),
        manifest_dir(),
    );
    let r = run(&s);
    assert_sound(&r, "2×2 atlas");
}

#[test]
fn large_4097_squared_atlas() {
    let s = scene(
        &synthetic(
            "hills",
            4097,
            [20_000.0, 5_000.0, 900.0],
            [60_000.0, 60_000.0, 300.0],
        ),
        manifest_dir(),
    );
    let r = run(&s);
    assert!(r.atlas.levels.len() >= 12);
    assert_sound(&r, "4097² atlas");
}

fn nan_sketch(
    dir: &std::path::Path,
    name: &str,
    nan: impl Fn(usize, usize) -> bool,
) -> std::path::PathBuf {
    let n = 65;
    let mut text = format!(
        "ncols {n}\nnrows {n}\nxllcorner 0\nyllcorner 0\ncellsize 30\nNODATA_value -9999\n"
    );
    for j in 0..n {
        let row: Vec<String> = (0..n)
            .map(|i| {
                if nan(i, j) {
                    if (i + j) % 2 == 0 {
                        "nan".into()
                    } else {
                        "-9999".into()
                    }
                } else {
                    format!("{}", 200 + (i * j) % 50)
                }
            })
            .collect();
        text += &(row.join(" ") + "\n");
    }
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

#[test]
fn all_nan_and_half_nan_sketches() {
    let dir = scratch("nan-sketches");
    for (name, nan) in [
        (
            "all.asc",
            Box::new(|_, _| true) as Box<dyn Fn(usize, usize) -> bool>,
        ),
        ("half.asc", Box::new(|i, _| i < 32)),
    ] {
        let path = nan_sketch(&dir, name, nan);
        let toml = format!(
            "[sketch]\npath = {:?}\n[camera]\nposition = [-500.0, -500.0, 800.0]\nlook_at = [1000.0, 1000.0, 200.0]\n",
            path
        );
        let r = run(&scene(&toml, dir.clone()));
        assert!(r.atlas.nodata > 0);
        assert!(
            r.atlas
                .levels
                .iter()
                .all(|l| l.data.iter().all(|h| h.is_finite()))
        );
        assert_sound(&r, name);
    }
}

#[test]
fn thousands_of_kilometres_from_the_origin_gives_the_same_warp() {
    let near = synthetic(
        "ridges",
        257,
        [2000.0, 1000.0, 800.0],
        [4000.0, 5000.0, 300.0],
    );
    let off = 4_000_000.0;
    let far = format!(
        "[sketch]\nsynthetic = \"ridges\"\nsize = 257\norigin_m = [{off:.1}, {off:.1}]\n[camera]\nposition = [{}, {}, 800.0]\nlook_at = [{}, {}, 300.0]\n",
        2000.0 + off,
        1000.0 + off,
        4000.0 + off,
        5000.0 + off
    );
    let a = run(&scene(&near, manifest_dir()));
    let b = run(&scene(&far, manifest_dir()));
    assert_sound(&b, "4000 km away");
    assert_eq!(
        a.stage.sketch_map.origin + DVec2::splat(off),
        b.stage.sketch_map.origin
    );
    let worst = a
        .stage
        .warp
        .phi
        .iter()
        .zip(&b.stage.warp.phi)
        .map(|(p, q)| (p[0] - q[0]).abs().max((p[1] - q[1]).abs()))
        .fold(0.0f32, f32::max);
    // Φ is region-local: the offset never reaches f32. The camera's local position carries the
    // rounding of 4e6 + x in f64 (≈1e-9 m), so Φ agrees to far below a millimetre.
    assert!(worst < 1e-3, "Φ differs by {worst} m");
}

#[test]
fn importance_spanning_twelve_orders_of_magnitude() {
    let n = 128;
    let mut importance = vec![0.0f32; n * n];
    let mut x = 12345u32;
    for v in importance.iter_mut() {
        // xorshift32: any spread of values does; no generator is under test here.
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        *v = 10f32.powf(-6.0 + 12.0 * (x as f32 / u32::MAX as f32));
    }
    // And a smooth 12-order ramp, which the random field does not exercise.
    let ramp: Vec<f32> = (0..n * n)
        .map(|k| 10f32.powf(-6.0 + 12.0 * (k % n) as f32 / (n - 1) as f32))
        .collect();
    for (what, imp) in [("random", &importance), ("ramp", &ramp)] {
        let mut w = Warp::new(n, WarpMethod::Guarded, 0.0);
        w.run(imp, 10.0);
        let phi = &w.phi;
        assert!(
            phi.iter().all(|p| p[0].is_finite() && p[1].is_finite()),
            "{what}"
        );
        for s in 0..n - 1 {
            assert!(
                terrain_engine::stage::pair_unfolded(phi, n, s),
                "{what}: fold at column {s}"
            );
        }
        assert_eq!(phi[0], [0.0, 0.0]);
        assert_eq!(phi[n * n - 1], [1270.0, 1270.0]);
    }
}
