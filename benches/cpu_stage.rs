//! The CPU stage at 128²: sketch map, importance and warp, each alone and together, on every
//! bundled view: jacksboro, gaussian and hills near the ground and from high up; the hills
//! looking east, where the warp runs across (`stage::warp`); and the hills view (north-east,
//! where the region turns, `stage::sketch_map`) with `warp.diagonal` off.
//!
//! `cargo bench --bench cpu_stage`; criterion prints the median of each. `stage` is a frame that
//! warps anew, `stage_held` one that keeps the held warp (`warp.hold`, a still camera).

use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;
use std::path::{Path, PathBuf};
use terrain_engine::scene;
use terrain_engine::scene::{Scene, WarpMethod};
use terrain_engine::stage::CpuStage;

fn sketches() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("sketches")
}

fn bench_scene(c: &mut Criterion, name: &str, scene: &Scene) {
    let atlas = scene::load_atlas(scene).expect("bundled sketch");
    let detail = scene::detail_of(scene, &atlas);
    let camera = scene::camera_of(scene, &atlas).expect("bundled camera");
    let mut stage = CpuStage::new(scene, &detail).expect("stage");
    stage.run(&atlas, &camera);
    let bounds = (atlas.origin, atlas.max_corner());

    let mut g = c.benchmark_group(name);
    // A frame that warps anew: nothing held from the frame before.
    g.bench_function("stage", |b| {
        b.iter(|| {
            stage.forget();
            black_box(stage.run(&atlas, &camera))
        })
    });
    // A frame that keeps the held warp (`warp.hold`): the same camera again.
    if stage.hold.is_some() {
        stage.run(&atlas, &camera);
        g.bench_function("stage_held", |b| {
            b.iter(|| black_box(stage.run(&atlas, &camera)))
        });
        assert!(stage.held, "a still camera keeps its warp");
    }
    g.bench_function("sketch_map", |b| {
        b.iter(|| {
            // Forgotten, so that the region is chosen and resampled (an unchanged region is not).
            stage.sketch_map.forget();
            let turn = stage.sketch_map.turn;
            stage
                .sketch_map
                .update(&atlas, &camera, stage.params.reach_m, false, turn)
        })
    });
    g.bench_function("importance", |b| {
        b.iter(|| {
            stage
                .importance
                .update(&stage.sketch_map, bounds, &camera, None, &stage.params)
        })
    });
    let d0 = stage.sketch_map.spacing as f32;
    for method in [WarpMethod::Guarded, WarpMethod::Plain] {
        stage.warp.method = method;
        let label = format!("warp_{method:?}").to_lowercase();
        let across = stage.warp.across;
        g.bench_function(label, |b| {
            b.iter(|| {
                if across {
                    stage.warp.run_across(&stage.importance.importance, d0)
                } else {
                    stage.warp.run(&stage.importance.importance, d0)
                }
            })
        });
    }
    g.finish();
}

fn cpu_stage(c: &mut Criterion) {
    for scene in [
        "jacksboro",
        "jacksboro-high",
        "gaussian",
        "gaussian-high",
        "hills",
        "hills-high",
    ] {
        let path = sketches().join(format!("{scene}.toml"));
        bench_scene(c, scene, &Scene::load(&path).expect("bundled scene"));
    }
    // The bundled views look north or north-east; this one looks east: the warp runs across.
    let scene = Scene::parse(HILLS_EAST, sketches()).expect("hills looking east");
    bench_scene(c, "hills-east", &scene);
    // The hills view (north-east, a turned region) with the region's axes along x and y, for
    // what the turn costs.
    let mut scene = Scene::load(&sketches().join("hills.toml")).expect("bundled scene");
    scene.warp.diagonal = false;
    bench_scene(c, "hills-axes", &scene);
}

/// `sketches/hills.toml`'s hills and height, looking east across them.
const HILLS_EAST: &str = "[sketch]\nsynthetic = \"hills\"\n[camera]\nposition = [500.0, 3500.0, 760.0]\n\
     look_at = [7933.0, 3500.0, 400.0]\nfov_y_deg = 60.0\nwidth = 512\nheight = 512\n[detail]\namplitude_m = 8.0\ngain = 0.45\n";

criterion_group!(benches, cpu_stage);
criterion_main!(benches);
