//! The CPU stage at 128²: sketch map, importance and warp, each alone and together, on every
//! bundled view: jacksboro, gaussian and hills near the ground and from high up.
//!
//! `cargo bench --bench cpu_stage`; criterion prints the median of each. `stage` is a frame that
//! warps anew, `stage_held` one that keeps the held warp (`warp.hold`, a still camera).

use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;
use std::path::Path;
use terrain::scene;
use terrain::scene::{Scene, WarpMethod};
use terrain::stage::CpuStage;

fn bench_scene(c: &mut Criterion, name: &str) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("sketches")
        .join(format!("{name}.toml"));
    let scene = Scene::load(&path).expect("bundled scene");
    let atlas = scene::load_atlas(&scene).expect("bundled sketch");
    let detail = scene::detail_of(&scene, &atlas);
    let camera = scene::camera_of(&scene, &atlas).expect("bundled camera");
    let mut stage = CpuStage::new(&scene, &detail).expect("stage");
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
            stage
                .sketch_map
                .update(&atlas, &camera, stage.params.reach_m, false)
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
        g.bench_function(label, |b| {
            b.iter(|| stage.warp.run(&stage.importance.importance, d0))
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
        bench_scene(c, scene);
    }
}

criterion_group!(benches, cpu_stage);
criterion_main!(benches);
