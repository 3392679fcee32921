//! `terrain scene SKETCH [-o FILE]`: a starter scene for a sketch, every key with a comment.

use anyhow::Result;
use std::path::{Path, PathBuf};
use terrain_cli::output::write_atomic;
use terrain_engine::scene;
use terrain_engine::{Error, Role};

#[derive(clap::Args)]
pub struct Args {
    /// The sketch (height map): any format `terrain info` reads, a quoted glob, a .vrt or a tile
    /// pyramid's folder.
    sketch: PathBuf,
    /// Where to write the scene (.toml; its folder is created); without it, standard output.
    #[arg(short = 'o', long = "output", value_name = "FILE")]
    output: Option<PathBuf>,
    /// Overrides a key of the scene written, e.g. `--set camera.heading_deg=90` (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    set: Vec<String>,
}

/// The scene manual, whose key descriptions the starter's comments are.
const MANUAL: &str = include_str!("../../../docs/scene.md");

pub fn run(a: Args) -> Result<()> {
    if let Some(out) = &a.output
        && out
            .extension()
            .is_none_or(|e| !e.eq_ignore_ascii_case("toml"))
    {
        let why = "a scene is TOML: give a .toml file name";
        return Err(Error::file(Role::Output, out, why).into());
    }
    if !scene::is_sketch_path(&a.sketch) {
        let why = "is a scene already; give the sketch it names";
        return Err(Error::file(Role::Sketch, &a.sketch, why).into());
    }
    let scene = crate::load_scene(&a.sketch, &a.set)?;
    let atlas = scene::load_atlas(&scene)?;
    let named = match &a.output {
        Some(out) => relative_to(&a.sketch, out.parent().unwrap_or(Path::new(""))),
        None => a.sketch.clone(),
    };
    let text = scene::starter(&scene, &atlas, &named, MANUAL)?;
    match &a.output {
        Some(out) => {
            write_atomic(out, text.as_bytes())?;
            eprintln!("{}: a scene for {}", out.display(), a.sketch.display());
        }
        None => out!("{text}"),
    }
    Ok(())
}

/// `sketch` as a path from the folder `dir`: its file name when both are the same folder, else
/// absolute (a scene's paths resolve against its own folder).
fn relative_to(sketch: &Path, dir: &Path) -> PathBuf {
    let abs = |p: &Path| std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf());
    let folder = sketch.parent().unwrap_or(Path::new(""));
    match (abs(folder) == abs(dir), sketch.file_name()) {
        (true, Some(name)) => PathBuf::from(name),
        _ => abs(sketch),
    }
}
