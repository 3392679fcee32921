//! The `terrain` command line: one file per command, each with its arguments (`Args`), its run
//! and its `--json` output as a serde struct. Every command prints one line naming the cause and
//! exits non-zero on bad input: 2 for a usage error (clap's, a bad option value, a bad `--set`),
//! 1 for bad input found while working. `--json` prints one JSON object on stdout; messages go to
//! stderr.

/// `print!` to stdout, except that a reader gone away (`terrain warp … --json | head -c 100`)
/// ends the program quietly, as it ends `cat`, where `print!` would panic on the broken pipe.
macro_rules! out {
    ($($arg:tt)*) => {
        $crate::write_out(format_args!($($arg)*))
    };
}

/// [`out!`] with a newline.
macro_rules! outln {
    ($($arg:tt)*) => {
        $crate::write_out(format_args!("{}\n", format_args!($($arg)*)))
    };
}

mod args;
mod batch;
mod compare;
mod fly;
mod height;
mod info;
mod modes;
mod notes;
mod render;
mod scene;
mod tiles;
mod view;
mod warp;
mod web;

use clap::{Parser, Subcommand};
use terrain_engine::Error;

#[derive(Parser)]
#[command(
    name = "terrain",
    version,
    about = "Procedural terrain by geometry image warping",
    arg_required_else_help = true
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Reads a sketch and prints its size, spacing, height range and nodata count.
    Info(info::Args),
    /// Lists the level-of-detail modes: `--mode`'s choices, the scenes each draws, what
    /// `compare` sweeps.
    Modes(modes::Args),
    /// Converts a sketch (a file or a glob of tiles) into a tile pyramid on disk, with bounded
    /// memory; resumable. Scenes name the pyramid's folder as their sketch.
    Tiles(tiles::Args),
    /// Writes a starter scene for a sketch: the default camera by heading and pitch (framed anew
    /// when they change), every key with a comment, to edit.
    Scene(scene::Args),
    /// Runs the CPU stage for the scene's camera; writes importance.png, mesh.png, ratio.png.
    Warp(warp::Args),
    /// The terrain's height and normal at a point, as the reference draws it: for placing
    /// objects on the ground.
    Height(height::Args),
    /// Renders a snapshot of the scene from its camera (headless, on whatever adapter there is).
    Render(render::Args),
    /// Every mode over a sweep of its quality setting against the reference image; writes
    /// report.csv, report.json, summary.md and figures (error_vs_time.svg/.png, ...) to --out-dir.
    Compare(compare::Args),
    /// Renders the scene's camera path (its `[path]`, else one orbit of the sketch in 10 s) to numbered PNG
    /// frames, an animation (MP4 when ffmpeg is installed, else APNG) and frames.csv in --out-dir.
    Fly(fly::Args),
    /// Many snapshots from a jobs file on one device; manifest.jsonl lists each with its status.
    Batch(batch::Args),
    /// An interactive window flying through the terrain (mouse look, WASD/QE, 1/2/3 modes,
    /// V views, F freeze, R record the path, P screenshot, Esc quit).
    View(view::Args),
    /// Writes the scene as a static web site drawn in the browser through WebGPU (the same
    /// renderer, as WebAssembly); --serve serves it on 127.0.0.1.
    Web(web::Args),
}

/// The exit code of every usage error: an unknown option, a bad option value, a bad `--set`.
/// Bad input found while working (a file, a scene key, the device) exits with 1.
const USAGE: i32 = 2;

fn main() {
    // Mesa's Vulkan device-select layer connects to a Wayland display whenever an adapter is
    // requested; where XDG_RUNTIME_DIR is unset or empty (a container, a CI job, ssh) libwayland
    // then prints an error line about a display nobody asked for, breaking the one-line-error
    // rule. Pointing it at the temporary folder makes the probe fail quietly instead; a real
    // Wayland session always sets it.
    if std::env::var_os("XDG_RUNTIME_DIR").is_none_or(|v| v.is_empty())
        && std::env::var_os("WAYLAND_DISPLAY").is_none()
    {
        // SAFETY: the first statement of main, before any thread exists.
        unsafe { std::env::set_var("XDG_RUNTIME_DIR", std::env::temp_dir()) };
    }
    // Usage errors as one line too, like every other bad input; help and version print in full.
    // `terrain` alone prints the help (on stderr, exit 2) rather than a line about a missing
    // command.
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e)
            if !e.use_stderr()
                || e.kind() == clap::error::ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand =>
        {
            e.exit()
        }
        Err(e) => {
            eprintln!("{}", usage_line(&e.to_string()));
            std::process::exit(USAGE);
        }
    };
    // The library prints nothing: its notes and progress are shown here.
    notes::install();
    terrain_engine::progress::set_reporter(Box::new(terrain_cli::progress::Bars));
    // GeoMipMap's block figures over a pyramid are kept in its folder for the next command.
    terrain_engine::sketch::tiles::set_keep_figures(true);
    let result = match cli.command {
        Command::Info(a) => info::run(a),
        Command::Modes(a) => modes::run(a),
        Command::Tiles(a) => tiles::run(a),
        Command::Scene(a) => scene::run(a),
        Command::Warp(a) => warp::run(a),
        Command::Height(a) => height::run(a),
        Command::Render(a) => render::run(a),
        Command::Compare(a) => compare::run(a),
        Command::Fly(a) => fly::run(a),
        Command::Batch(a) => batch::run(a),
        Command::View(a) => view::run(a),
        Command::Web(a) => web::run(a),
    };
    if let Err(e) = result {
        eprintln!("error: {}", one_line(&e));
        // A bad `--set` is a usage error like any bad option: the same exit code as clap's.
        let usage = matches!(e.downcast_ref(), Some(Error::Override { .. }));
        std::process::exit(if usage { USAGE } else { 1 });
    }
}

/// A clap error as one line: the cause (everything before clap's usage block), then the help of
/// the command given (`terrain render --help`), or the top level's where none is known.
fn usage_line(text: &str) -> String {
    use clap::CommandFactory;
    let cause: Vec<&str> = text
        .lines()
        .take_while(|l| !l.starts_with("Usage:"))
        .map(str::trim)
        .filter(|l| !l.is_empty() && !l.starts_with("tip:") && !l.starts_with("For more"))
        .collect();
    // The top level takes no option but --help and --version, so a command is the first argument.
    let first = std::env::args().nth(1).unwrap_or_default();
    let help = match Cli::command().find_subcommand(&first) {
        Some(c) => format!(
            "terrain {} --help lists its arguments and options",
            c.get_name()
        ),
        None => "terrain --help lists the commands and options".into(),
    };
    format!("{} ({help})", cause.join(" "))
}

/// The error and its causes on one line, each cause once: a library error prints its source
/// already (`output x.png: No such file…`), which anyhow's `{:#}` would print again.
fn one_line(e: &anyhow::Error) -> String {
    let mut line = String::new();
    for cause in e.chain() {
        let text = cause.to_string().replace('\n', " ");
        if !line.contains(&text) {
            if !line.is_empty() {
                line += ": ";
            }
            line += &text;
        }
    }
    line
}

/// The scene at `path` with its `--set` overrides: every command that reads a scene loads it
/// here. What its sketch leaves in doubt is warned about once the sketch is read
/// (`scene::load_atlas`), never before: a file that fails to read gets its error alone.
fn load_scene(
    path: &std::path::Path,
    set: &[String],
) -> anyhow::Result<terrain_engine::scene::Scene> {
    Ok(terrain_engine::scene::Scene::load_with(path, set)?)
}

/// The library's warnings on stderr, one `warning:` line each and each once per command (the
/// library prints nothing).
fn warn(lines: &[String]) {
    for line in lines {
        notes::warning(line);
    }
}

/// Prints `value` as one JSON object on stdout.
fn print_json(value: &impl serde::Serialize) -> anyhow::Result<()> {
    outln!("{}", serde_json::to_string(value)?);
    Ok(())
}

/// Writes to stdout and flushes; a closed pipe exits with 0 (the reader took what it wanted),
/// any other failure with 1 and one line.
fn write_out(text: std::fmt::Arguments) {
    use std::io::Write;
    let mut stdout = std::io::stdout().lock();
    if let Err(e) = stdout.write_fmt(text).and_then(|()| stdout.flush()) {
        if e.kind() == std::io::ErrorKind::BrokenPipe {
            std::process::exit(0);
        }
        eprintln!("error: stdout: {e}");
        std::process::exit(1);
    }
}
