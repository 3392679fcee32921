//! Reading a tile pyramid: one tile read and decoded (what a loader thread does per tile, and a
//! point query on a tile it does not keep), and a point query on a tile it keeps.
//!
//! `cargo bench --bench tiles`; criterion prints the median of each. The pyramid is the bundled
//! Jacksboro sketch converted into a scratch folder.

use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;
use std::path::Path;
use terrain_engine::sketch::convert::{BuildOptions, build};
use terrain_engine::sketch::tiles::Pyramid;

fn bench_tiles(c: &mut Criterion) {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("sketches/jacksboro_fault_dem.asc");
    let out = std::env::temp_dir().join(format!("terrain-bench-tiles-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    let opts = BuildOptions {
        load: Default::default(),
        threads: 1,
        ..Default::default()
    };
    build(&src, &out, &opts).expect("jacksboro converts");
    let pyramid = Pyramid::open(&out).expect("the pyramid opens");
    let mut g = c.benchmark_group("tiles");
    g.bench_function("tile_read_decode", |b| {
        b.iter(|| black_box(pyramid.tile(0, 0, 0).expect("tile")))
    });
    pyramid.bilinear(0, 100.5, 100.25).expect("a node");
    g.bench_function("point_query_kept", |b| {
        b.iter(|| {
            black_box(
                pyramid
                    .bilinear(0, black_box(100.5), 100.25)
                    .expect("a node"),
            )
        })
    });
    g.finish();
    let _ = std::fs::remove_dir_all(&out);
}

criterion_group!(benches, bench_tiles);
criterion_main!(benches);
