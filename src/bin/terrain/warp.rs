//! `terrain warp SCENE --out-dir D`: the CPU stage alone, its quality figures and its three
//! figures (importance, the warped mesh, the density ratio).

use anyhow::Result;
use serde::Serialize;
use std::path::PathBuf;
use terrain_engine::scene;
use terrain_engine::scene::WarpMethod;
use terrain_engine::stage::quality::{self, Quality};
use terrain_engine::stage::{CpuStage, StageTimes};

#[derive(clap::Args)]
pub struct Args {
    /// A scene file (.toml), or a sketch (height map) to render with every default.
    scene: PathBuf,
    /// The folder importance.png, mesh.png and ratio.png are written to.
    #[arg(long)]
    out_dir: PathBuf,
    /// Overrides the scene's warp.method.
    #[arg(long, value_parser = crate::args::named::<WarpMethod>())]
    method: Option<WarpMethod>,
    /// Timed runs of the stage (after one warm-up); the median is reported.
    #[arg(long, default_value_t = 9, value_parser = clap::value_parser!(u32).range(1..=10000))]
    repeat: u32,
    /// Skips writing the figures (the statistics only).
    #[arg(long)]
    no_figures: bool,
    /// Overrides a scene key, e.g. `--set warp.quad_px=4` (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    set: Vec<String>,
    /// Prints one JSON object on stdout instead of the summary line.
    #[arg(long)]
    json: bool,
}

/// `--json`: the quality figures `docs/design.md` fixes (Command line outputs) and the stage's
/// times (median of the runs).
#[derive(Serialize)]
struct Report {
    method: WarpMethod,
    visible: bool,
    #[serde(flatten)]
    quality: Quality,
    /// Lines the guard sent to the mean mapping: columns, or rows where the warp ran across.
    guarded_columns: usize,
    /// Whether the warp ran across, columns first (a view whose depth runs along x).
    across: bool,
    cpu_stage_us: f64,
    sketch_map_us: f64,
    importance_us: f64,
    warp_us: f64,
    region: Region,
}

/// The sketch map's region: its corner (texel (0, 0): south-west, or a turned region's west or
/// south vertex), texel spacing, size and turn.
#[derive(Serialize)]
struct Region {
    origin_m: [f64; 2],
    spacing_m: f64,
    size: usize,
    /// The region's axes: `none` (x and y), or turned 45° for a diagonal heading
    /// (`north_east`: its t axis along (1, 1); `north_west`: along (−1, 1)).
    turn: terrain_engine::stage::Turn,
}

pub fn run(a: Args) -> Result<()> {
    let mut scene = crate::load_scene(&a.scene, &a.set)?;
    if scene.planet().is_some() {
        // The stage warps a plane; a planet draws with clipmaps, which have no CPU stage.
        return Err(terrain_engine::Error::scene(
            &a.scene,
            "a planet scene: `terrain warp` runs the warped mode's CPU stage over a planar sketch, \
             and a planet draws with clipmaps",
        )
        .into());
    }
    if let Some(m) = a.method {
        scene.warp.method = m;
    }
    let atlas = scene::load_atlas(&scene)?;
    let detail = scene::detail_of(&scene, &atlas);
    let camera = scene::camera_of(&scene, &atlas)?;
    let mut stage = CpuStage::new(&scene, &detail)?;
    stage.run(&atlas, &camera); // warm-up: first-touch page faults are not the stage's cost
    // Each timed run warps anew, as a first frame does (`warp.hold` keeps a still camera's warp).
    let mut runs: Vec<StageTimes> = (0..a.repeat)
        .map(|_| {
            stage.forget();
            stage.run(&atlas, &camera)
        })
        .collect();
    runs.sort_by(|a, b| a.total_us().total_cmp(&b.total_us()));
    let median = runs[runs.len() / 2];

    let n = stage.sketch_map.n;
    let mut ratios = Vec::with_capacity((n - 1) * (n - 1));
    let q = quality::measure(
        &stage.warp.phi,
        n,
        stage.sketch_map.spacing,
        &stage.importance,
        &mut ratios,
    );
    if !a.no_figures {
        terrain_cli::app::stage_figures::write_all(&a.out_dir, &atlas, &stage, &ratios)?;
    }
    let map = &stage.sketch_map;
    let r = Report {
        method: stage.warp.method,
        visible: map.visible,
        quality: q,
        guarded_columns: stage.warp.guarded_columns,
        across: stage.warp.across,
        cpu_stage_us: median.total_us(),
        sketch_map_us: median.sketch_map_us,
        importance_us: median.importance_us,
        warp_us: median.warp_us,
        region: Region {
            origin_m: [map.origin.x, map.origin.y],
            spacing_m: map.spacing,
            size: n,
            turn: map.turn,
        },
    };
    if a.json {
        return crate::print_json(&r);
    }
    let q = &r.quality;
    outln!(
        "{} visible cells ({:.3}× their demand): {:.1} % with ratio in [0.5, 2], {:.1} % in [0.5, 1]; {} flipped, {} non-finite; CPU stage {:.0} µs (sketch map {:.0}, importance {:.0}, warp {:.0})",
        q.cells_visible,
        q.demand_met,
        100.0 * q.ratio_within_0_5_2,
        100.0 * q.ratio_within_0_5_1,
        q.flipped_cells,
        q.nonfinite,
        r.cpu_stage_us,
        r.sketch_map_us,
        r.importance_us,
        r.warp_us
    );
    Ok(())
}
