//! Frame times of every mode on one adapter in one run: warped, GeoMipMap at τ = 1, 2, 4, 8 px
//! (de Boer's distance and the exact bound), brute force. Median of `FRAMES` frames after a warm-up.
//!
//! `cargo run --release --example lod_timings [SCENE]` (default: the bundled jacksboro scene).

use anyhow::Context;
use std::path::PathBuf;
use terrain_engine::Baselines;
use terrain_engine::View;
use terrain_engine::scene::Mode;
use terrain_engine::scene::Scene;
use terrain_engine::{Frame, Renderer};

const FRAMES: usize = 10;

fn median(frames: &[Frame], f: impl Fn(&Frame) -> f64) -> f64 {
    let mut v: Vec<f64> = frames.iter().map(f).collect();
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn row(label: &str, frames: &[Frame]) {
    let last = frames.last().expect("frames");
    println!(
        "| {label} | {:.0} | {:.1} | {:.1} | {} | {} |",
        median(frames, |f| f.cpu_us),
        median(frames, |f| f.gpu.gpu_ms),
        median(frames, |f| f.gpu.gpu_ms + f.cpu_us * 1e-3),
        last.gpu.triangles,
        last.blocks.map_or("—".to_string(), |b| b.to_string()),
    );
}

fn main() -> anyhow::Result<()> {
    let path = std::env::args()
        .nth(1)
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("sketches/jacksboro.toml")
        });
    let scene = Scene::load(&path)?;
    println!(
        "| mode | CPU µs (stage or block selection) | GPU ms | frame ms | triangles | blocks |"
    );
    println!("|---|---|---|---|---|---|");
    let mut warped = Renderer::new(&scene, Mode::Warped, View::Shaded)?;
    let camera = terrain_engine::scene::camera_of(&scene, &warped.atlas)?;
    warped.render(&camera)?;
    let frames: Vec<Frame> = (0..FRAMES)
        .map(|_| warped.render(&camera))
        .collect::<Result<_, _>>()?;
    row("warped", &frames);
    let adapter = warped.ctx.adapter_name();
    drop(warped);
    for kind in [Mode::Geomipmap, Mode::Bruteforce] {
        let mut r = Renderer::new(&scene, kind, View::Shaded)?;
        let b = r.lod::<Baselines>().context("a baseline mode")?;
        eprintln!(
            "{kind}: baked {}² grid in {:.0} ms, {:.0} MiB",
            b.grid.n,
            b.precompute_ms,
            b.bake.as_ref().map_or(0, |k| k.bytes()) as f64 / 1048576.0
        );
        let settings: Vec<(String, f64, bool)> = match kind {
            Mode::Geomipmap => [1.0, 2.0, 4.0, 8.0]
                .iter()
                .flat_map(|&tau| {
                    [
                        (format!("geomipmap τ={tau} (de Boer)"), tau, false),
                        (format!("geomipmap τ={tau} (exact)"), tau, true),
                    ]
                })
                .collect(),
            _ => vec![("bruteforce".to_string(), 1.0, false)],
        };
        for (label, tau, exact) in settings {
            let b = r.lod_mut::<Baselines>().context("a baseline mode")?;
            b.params.tau = tau;
            b.params.exact = exact;
            r.render(&camera)?;
            let frames: Vec<Frame> = (0..FRAMES)
                .map(|_| r.render(&camera))
                .collect::<Result<_, _>>()?;
            row(&label, &frames);
        }
    }
    println!(
        "\n{} on {adapter}, {FRAMES} frames each after a warm-up.",
        path.display()
    );
    Ok(())
}
