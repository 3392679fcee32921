//! `terrain compare SCENE --out-dir D`: every mode against the reference (the library's
//! `compare` module), or `--replot` of an earlier run's figures.

use crate::args;
use anyhow::Result;
use std::path::PathBuf;
use terrain_engine::scene::Mode;

#[derive(clap::Args)]
pub struct Args {
    /// A scene file (.toml), or a sketch (height map) to render with every default.
    scene: PathBuf,
    /// The folder report.csv, report.json, summary.md and the figures are written to.
    #[arg(long)]
    out_dir: PathBuf,
    /// Image size: N (square) or WxH.
    #[arg(long, value_name = "N|WxH", default_value = "256", value_parser = args::size)]
    size: (u32, u32),
    /// Modes to compare, comma-separated [default: warped,geomipmap,bruteforce; a planet's
    /// clipmaps; a tile pyramid's warped,geomipmap].
    #[arg(long, value_delimiter = ',', value_parser = args::mesh_mode)]
    modes: Vec<Mode>,
    /// Timed frames per setting, one of each setting a round (see --keep-mib); medians are reported.
    #[arg(long, default_value_t = 15, value_parser = clap::value_parser!(u32).range(1..=1000))]
    repeat: u32,
    /// GPU memory (MiB) for the renderers kept to time the settings side by side, a frame of
    /// each in turn, `--repeat` rounds; a setting past it is timed alone. 0: every setting alone.
    #[arg(long, value_name = "MIB", default_value_t = terrain_cli::eval::compare::rounds::KEEP_BYTES >> 20)]
    keep_mib: u64,
    /// Frames along the camera path (the scene's `[path]`, else one orbit of the sketch); 0: none.
    #[arg(long, default_value_t = 24, value_parser = clap::value_parser!(u32).range(0..=100000))]
    path_frames: u32,
    /// Frames per second along the path.
    #[arg(long, default_value_t = 15.0, value_parser = args::fps)]
    path_fps: f64,
    /// Also counts what each setting's shading evaluates per pixel (noise octaves, shadow steps,
    /// atlas taps), its frame drawn once more in the counting variant: the report's
    /// `*_per_px` columns.
    #[arg(long)]
    work: bool,
    /// Only redraws error_vs_time and summary.md from --out-dir's report.json.
    #[arg(long)]
    replot: bool,
    /// Overrides a scene key (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    set: Vec<String>,
    /// Prints one JSON object on stdout instead of the summary line.
    #[arg(long)]
    json: bool,
}

pub fn run(a: Args) -> Result<()> {
    if a.replot {
        let n = terrain_cli::eval::compare::replot(&a.out_dir)?;
        outln!("{n} rows redrawn in {}", a.out_dir.display());
        return Ok(());
    }
    let scene = crate::load_scene(&a.scene, &a.set)?;
    let mut modes = a.modes;
    modes.dedup();
    if modes.is_empty() {
        modes = terrain_cli::eval::compare::default_modes(&scene);
    }
    let opts = terrain_cli::eval::compare::Options {
        size: a.size,
        modes,
        repeat: a.repeat,
        path_frames: a.path_frames as usize,
        path_fps: a.path_fps,
        keep_bytes: a.keep_mib.saturating_mul(1 << 20),
        work: a.work,
        ..Default::default()
    };
    let name = a
        .scene
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "scene".into());
    let outcome = terrain_cli::eval::compare::run(&scene, &name, &opts, &a.out_dir)?;
    if a.json {
        return crate::print_json(&outcome.report);
    }
    out!(
        "{}",
        terrain_cli::eval::compare::report::summary_markdown(&name, &outcome.summary)
    );
    let skipped = outcome.report.skipped.len();
    outln!(
        "\n{} settings measured{} in {:.0} s; report.csv, report.json and figures in {}",
        outcome.rows.len(),
        if skipped > 0 {
            format!(", {skipped} skipped (see report.json)")
        } else {
            String::new()
        },
        outcome.report.elapsed_s,
        a.out_dir.display()
    );
    Ok(())
}
