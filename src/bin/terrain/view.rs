//! `terrain view SCENE`: the interactive window (the library's `view` module, feature `view`).

use crate::args;
use anyhow::Result;
use std::path::PathBuf;
use terrain_engine::scene::Mode;

#[derive(clap::Args)]
pub struct Args {
    /// A scene file (.toml), or a sketch (height map) to render with every default.
    scene: PathBuf,
    /// The mode [default: the scene's; warped for the reference; clipmaps on a planet].
    #[arg(long, value_parser = args::mesh_mode)]
    mode: Option<Mode>,
    /// Window size: N (square) or WxH.
    #[arg(long, value_name = "N|WxH", default_value = "800x450", value_parser = args::size)]
    size: (u32, u32),
    /// Quits after this many frames (with --screenshot: writes it first).
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..))]
    frames: Option<u64>,
    /// The folder screenshots (P) and recorded paths (R) go to, under names that never
    /// overwrite: `<scene>-view-<n>.png`, `<scene>-flown[-<n>].toml`.
    #[arg(long, default_value = ".")]
    out_dir: PathBuf,
    /// The first screenshot's file (P, or on quitting after --frames); later ones go to
    /// --out-dir.
    #[arg(long)]
    screenshot: Option<PathBuf>,
    /// On quitting, prints one JSON object on stdout: how frames were presented (`present`:
    /// "surface" or "cpu"), `frames`, and the medians `interval_ms_median` (between presented
    /// frames), `cpu_ms_median` (the CPU stage) and `gpu_ms_median`.
    #[arg(long)]
    json: bool,
    /// Overrides a scene key (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    set: Vec<String>,
}

#[cfg(feature = "view")]
pub fn run(a: Args) -> Result<()> {
    let scene = crate::load_scene(&a.scene, &a.set)?;
    let planet = scene.planet().is_some();
    let mode = match a.mode {
        Some(m) if !m.draws(planet) => anyhow::bail!(
            "--mode: a planet scene is viewed in clipmaps mode, not {m} (it draws planar sketches)"
        ),
        Some(m) => m,
        None if planet => Mode::Clipmaps,
        None if scene.render.mode == Mode::Reference => Mode::Warped,
        None => scene.render.mode,
    };
    let opts = terrain_cli::app::view::Options {
        scene_path: a.scene,
        mode,
        size: a.size,
        frames: a.frames,
        out_dir: a.out_dir,
        screenshot: a.screenshot,
    };
    let summary = terrain_cli::app::view::run(scene, opts)?;
    if a.json {
        crate::print_json(&summary)?;
    }
    Ok(())
}

#[cfg(not(feature = "view"))]
pub fn run(_: Args) -> Result<()> {
    anyhow::bail!(
        "this terrain was built without the `view` feature (cargo build --release builds it)"
    )
}
