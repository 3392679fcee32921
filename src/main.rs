//! The `terrain` command line (DESIGN.md's table). Every command prints one line naming the cause
//! and exits non-zero on bad input; `--json` prints one JSON object on stdout, messages go to stderr.

use anyhow::{Context, Result};
use clap::{Parser, Subcommand};
use serde_json::json;
use std::path::{Path, PathBuf};
use terrain::atlas::{Atlas, LoadOptions};
use terrain::cpu_stage::{self, CpuStage, StageTimes};
use terrain::error::{Error, Role};
use terrain::gpu::uniforms::View;
use terrain::progress::Spinner;
use terrain::render::SceneRenderer;
use terrain::scene::{Mode, Scene, WarpMethod};
use terrain::{figures, output, quality};

#[derive(Parser)]
#[command(
    name = "terrain",
    version,
    about = "Procedural terrain by geometry image warping"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Reads a sketch and prints its size, spacing, height range and nodata count.
    Info {
        file: PathBuf,
        /// Grid spacing in metres, for formats that carry none (PNG).
        #[arg(long)]
        spacing_m: Option<f64>,
        #[arg(long)]
        json: bool,
    },
    /// Runs the CPU stage for the scene's camera; writes importance.png, mesh.png, ratio.png.
    Warp {
        scene: PathBuf,
        #[arg(long)]
        out_dir: PathBuf,
        /// Overrides the scene's warp.method.
        #[arg(long)]
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
        #[arg(long)]
        json: bool,
    },
    /// Renders a snapshot of the scene from its camera (headless, on whatever adapter there is).
    Render {
        scene: PathBuf,
        /// The image: .png or .jpg (its folder is created).
        #[arg(short = 'o', long = "output")]
        output: PathBuf,
        /// Image size: N (square) or WxH; default the scene's camera.width × camera.height.
        #[arg(long, value_name = "N|WxH", value_parser = size_arg)]
        size: Option<(u32, u32)>,
        /// Overrides the scene's render.mode.
        #[arg(long)]
        mode: Option<Mode>,
        #[arg(long, default_value_t = View::Shaded)]
        view: View,
        /// GeoMipMap's τ: the largest projected vertex error, pixels (overrides geomipmap.tau).
        #[arg(long, allow_negative_numbers = true, value_parser = positive_arg)]
        tau: Option<f64>,
        /// Overrides a scene key, e.g. `--set detail.octaves=0` (repeatable).
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
        /// Frames rendered after one warm-up frame; medians are reported, the last is written.
        #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=1000))]
        repeat: u32,
        /// Also writes each pixel's world position (x, y, z metres, then 1 on ground, 0 on sky)
        /// as a NumPy .npy of f64, shape (height, width, 4).
        #[arg(long, value_name = "FILE.npy")]
        positions: Option<PathBuf>,
        #[arg(long)]
        json: bool,
    },
    /// Every mode over a sweep of its quality setting against the reference image; writes
    /// report.csv, report.json, summary.md and figures (error_vs_time.svg/.png, ...) to --out-dir.
    Compare {
        scene: PathBuf,
        #[arg(long)]
        out_dir: PathBuf,
        /// Image size: N (square) or WxH.
        #[arg(long, value_name = "N|WxH", default_value = "256", value_parser = size_arg)]
        size: (u32, u32),
        /// Modes to compare, comma-separated.
        #[arg(long, value_delimiter = ',', default_value = "warped,geomipmap,bruteforce", value_parser = mesh_mode)]
        modes: Vec<Mode>,
        /// Timed frames per setting after one warm-up; medians are reported.
        #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(1..=1000))]
        repeat: u32,
        /// Frames along the camera path (the scene's [path], else straight ahead); 0: none.
        #[arg(long, default_value_t = 24, value_parser = clap::value_parser!(u32).range(0..=100000))]
        path_frames: u32,
        /// Frames per second along the path.
        #[arg(long, default_value_t = 15.0, value_parser = fps_arg)]
        path_fps: f64,
        /// Only redraws error_vs_time and summary.md from --out-dir's report.json.
        #[arg(long)]
        replot: bool,
        /// Overrides a scene key (repeatable).
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
        #[arg(long)]
        json: bool,
    },
    /// Renders the scene's camera path (its [path], else straight ahead) to numbered PNG
    /// frames, an animation (MP4 when ffmpeg is installed, else APNG) and frames.csv in --out-dir.
    Fly {
        scene: PathBuf,
        #[arg(long)]
        out_dir: PathBuf,
        #[arg(long)]
        mode: Option<Mode>,
        #[arg(long, default_value_t = View::Shaded)]
        view: View,
        /// Frames spread evenly over the whole path (default: --fps frames per second of travel,
        /// at most 300; a longer path is spread over 300 frames).
        #[arg(long, value_parser = clap::value_parser!(u32).range(1..=1_000_000))]
        frames: Option<u32>,
        /// Frames per second of the animation (and of travel without --frames).
        #[arg(long, default_value_t = 30.0, value_parser = fps_arg)]
        fps: f64,
        /// Image size: N (square) or WxH; default the scene's.
        #[arg(long, value_name = "N|WxH", value_parser = size_arg)]
        size: Option<(u32, u32)>,
        /// Writes the animation as APNG even when ffmpeg could make an MP4.
        #[arg(long)]
        no_mp4: bool,
        /// Overrides a scene key (repeatable).
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
        #[arg(long)]
        json: bool,
    },
    /// Many snapshots from a jobs file on one device; manifest.jsonl lists each with its status.
    Batch {
        jobs: PathBuf,
        #[arg(long)]
        out_dir: PathBuf,
        /// Renders share i of n (items k with k mod n = i), e.g. --shard 0/4.
        #[arg(long, value_name = "I/N", value_parser = shard_arg)]
        shard: Option<(usize, usize)>,
        /// Skips items the manifest lists as done; retries failed ones.
        #[arg(long)]
        resume: bool,
        /// Merges the shard manifests in --out-dir into manifest.jsonl instead of rendering.
        #[arg(long, conflicts_with_all = ["shard", "resume"])]
        merge: bool,
        #[arg(long)]
        json: bool,
    },
    /// An interactive window flying through the terrain (mouse look, WASD/QE, 1/2/3 modes,
    /// V views, F freeze, R record the path, P screenshot, Esc quit).
    View {
        scene: PathBuf,
        #[arg(long, value_parser = mesh_mode)]
        mode: Option<Mode>,
        /// Window size: N (square) or WxH.
        #[arg(long, value_name = "N|WxH", default_value = "800x450", value_parser = size_arg)]
        size: (u32, u32),
        /// Quits after this many frames (with --screenshot: writes it first).
        #[arg(long, value_parser = clap::value_parser!(u64).range(1..))]
        frames: Option<u64>,
        /// The folder screenshots (P) and recorded paths (R) go to, under names that never
        /// overwrite: <scene>-view-<n>.png, <scene>-flown[-<n>].toml.
        #[arg(long, default_value = ".")]
        out_dir: PathBuf,
        /// The first screenshot's file (P, or on quitting after --frames); later ones go to
        /// --out-dir.
        #[arg(long)]
        screenshot: Option<PathBuf>,
        /// Overrides a scene key (repeatable).
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
    },
}

/// The exit code of every usage error: an unknown option, a bad option value, a bad `--set`.
/// Bad input found while working (a file, a scene key, the device) exits with 1.
const USAGE: i32 = 2;

fn main() {
    // Mesa's EGL probes for a Wayland display whenever an adapter is requested; where
    // XDG_RUNTIME_DIR is unset (a container, a CI job, ssh) libwayland then prints an error line
    // about a display nobody asked for, breaking the one-line-error rule. Pointing it at the
    // temporary folder makes the probe fail quietly instead; a real Wayland session always sets it.
    if std::env::var_os("XDG_RUNTIME_DIR").is_none()
        && std::env::var_os("WAYLAND_DISPLAY").is_none()
    {
        // SAFETY: the first statement of main, before any thread exists.
        unsafe { std::env::set_var("XDG_RUNTIME_DIR", std::env::temp_dir()) };
    }
    // Usage errors as one line too, like every other bad input; help and version print in full.
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) if !e.use_stderr() => e.exit(),
        Err(e) => {
            // The cause is everything before clap's usage block, on one line.
            let text = e.to_string();
            let cause: Vec<&str> = text
                .lines()
                .take_while(|l| !l.starts_with("Usage:"))
                .map(str::trim)
                .filter(|l| !l.is_empty() && !l.starts_with("tip:") && !l.starts_with("For more"))
                .collect();
            eprintln!(
                "{} (terrain --help lists the commands and options)",
                cause.join(" ")
            );
            std::process::exit(USAGE);
        }
    };
    let result = match cli.command {
        Command::Info {
            file,
            spacing_m,
            json,
        } => info(&file, spacing_m, json),
        Command::Warp {
            scene,
            out_dir,
            method,
            repeat,
            no_figures,
            set,
            json,
        } => warp(&scene, &set, &out_dir, method, repeat, !no_figures, json),
        Command::Render {
            scene,
            output,
            size,
            mode,
            view,
            tau,
            set,
            repeat,
            positions,
            json,
        } => render(
            &scene,
            &set,
            &output,
            &RenderOpts {
                size,
                mode,
                view,
                tau,
                repeat,
                positions,
            },
            json,
        ),
        Command::Compare {
            out_dir,
            replot: true,
            ..
        } => terrain::compare::replot(&out_dir)
            .map(|n| println!("{n} rows redrawn in {}", out_dir.display()))
            .map_err(Into::into),
        Command::Compare {
            scene,
            out_dir,
            size,
            modes,
            repeat,
            path_frames,
            path_fps,
            set,
            json,
            ..
        } => compare(
            &scene,
            &set,
            &out_dir,
            terrain::compare::Options {
                size,
                modes,
                repeat,
                path_frames: path_frames as usize,
                path_fps,
                ..Default::default()
            },
            json,
        ),
        Command::Fly {
            scene,
            out_dir,
            mode,
            view,
            frames,
            fps,
            size,
            no_mp4,
            set,
            json,
        } => fly(
            &scene,
            &set,
            &out_dir,
            &FlyArgs {
                mode,
                view,
                frames,
                fps,
                size,
                mp4: !no_mp4,
            },
            json,
        ),
        Command::Batch {
            jobs,
            out_dir,
            shard,
            resume,
            merge,
            json,
        } => batch(&jobs, &out_dir, shard, resume, merge, json),
        Command::View {
            scene,
            mode,
            size,
            frames,
            out_dir,
            screenshot,
            set,
        } => view(
            &scene,
            &set,
            mode,
            ViewArgs {
                size,
                frames,
                out_dir,
                screenshot,
            },
        ),
    };
    if let Err(e) = result {
        eprintln!("error: {}", one_line(&e));
        // A bad `--set` is a usage error like any bad option: the same exit code as clap's.
        let usage = matches!(e.downcast_ref(), Some(Error::Override { .. }));
        std::process::exit(if usage { USAGE } else { 1 });
    }
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

/// The largest image side any command renders (camera.width's range).
const MAX_SIDE: u32 = 16384;

/// `--size`: `N` (square) or `WxH`, each 1 to [`MAX_SIDE`] pixels, the same for every command.
fn size_arg(s: &str) -> Result<(u32, u32), String> {
    let side =
        |v: &str| -> Option<u32> { v.trim().parse().ok().filter(|n| (1..=MAX_SIDE).contains(n)) };
    let size = match s.split_once(['x', 'X', '×']) {
        Some((w, h)) => side(w).zip(side(h)),
        None => side(s).map(|n| (n, n)),
    };
    size.ok_or_else(|| format!("expected N or WxH, each 1 to {MAX_SIDE} pixels"))
}

/// `--fps`, `--path-fps`: frames per second in (0, 1000].
fn fps_arg(s: &str) -> Result<f64, String> {
    s.trim()
        .parse::<f64>()
        .ok()
        .filter(|f| f.is_finite() && *f > 0.0 && *f <= 1000.0)
        .ok_or_else(|| "expected frames per second in (0, 1000]".into())
}

/// `--tau`: a positive number of pixels.
fn positive_arg(s: &str) -> Result<f64, String> {
    s.trim()
        .parse::<f64>()
        .ok()
        .filter(|f| f.is_finite() && *f > 0.0)
        .ok_or_else(|| "expected a positive number of pixels".into())
}

/// `--shard I/N` with 0 ≤ I < N.
fn shard_arg(s: &str) -> Result<(usize, usize), String> {
    s.split_once('/')
        .and_then(|(i, n)| Some((i.trim().parse().ok()?, n.trim().parse().ok()?)))
        .filter(|&(i, n): &(usize, usize)| n > 0 && i < n)
        .ok_or_else(|| "expected I/N with 0 ≤ I < N".into())
}

fn info(file: &Path, spacing_m: Option<f64>, json: bool) -> Result<()> {
    let opts = LoadOptions {
        spacing_m,
        ..LoadOptions::default()
    };
    let atlas = Atlas::load(file, &opts)?;
    let out = json!({
        "file": file.display().to_string(),
        "width": atlas.width(),
        "height": atlas.height(),
        "spacing_m": atlas.d_atlas(),
        "dx_m": atlas.dx,
        "dy_m": atlas.dy,
        "min_m": atlas.min_m,
        "max_m": atlas.max_m,
        "nodata": atlas.nodata,
    });
    if json {
        println!("{out}");
    } else {
        println!(
            "{}: {} × {} cells of {:.2} × {:.2} m ({:.1} × {:.1} km), heights {:.1} … {:.1} m, {} nodata filled",
            file.display(),
            atlas.width(),
            atlas.height(),
            atlas.dx,
            atlas.dy,
            (atlas.width() - 1) as f64 * atlas.dx / 1000.0,
            (atlas.height() - 1) as f64 * atlas.dy / 1000.0,
            atlas.min_m,
            atlas.max_m,
            atlas.nodata
        );
    }
    Ok(())
}

fn warp(
    scene_path: &Path,
    set: &[String],
    out_dir: &Path,
    method: Option<WarpMethod>,
    repeat: u32,
    figures_on: bool,
    json: bool,
) -> Result<()> {
    let mut scene = Scene::load_with(scene_path, set)?;
    if let Some(m) = method {
        scene.warp.method = m;
    }
    let atlas = cpu_stage::load_atlas(&scene)?;
    let detail = cpu_stage::detail_of(&scene, &atlas);
    let camera = cpu_stage::camera_of(&scene, &atlas)?;
    let mut stage = CpuStage::new(&scene, &detail)?;
    stage.run(&atlas, &camera); // warm-up: first-touch page faults are not the stage's cost
    let mut runs: Vec<StageTimes> = (0..repeat).map(|_| stage.run(&atlas, &camera)).collect();
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
    if figures_on {
        std::fs::create_dir_all(out_dir)
            .with_context(|| format!("cannot create {}", out_dir.display()))?;
        figures::write_all(out_dir, &atlas, &stage, &ratios)?;
    }
    let map = &stage.sketch_map;
    let out = json!({
        "method": stage.warp.method.name(),
        "visible": map.visible,
        "cells_visible": q.cells_visible,
        "ratio_within_0_5_2": q.ratio_within_0_5_2,
        "ratio_within_0_5_1": q.ratio_within_0_5_1,
        "ratio_median": q.ratio_median,
        "flipped_cells": q.flipped_cells,
        "nonfinite": q.nonfinite,
        "guarded_columns": stage.warp.guarded_columns,
        "cpu_stage_us": median.total_us(),
        "sketch_map_us": median.sketch_map_us,
        "importance_us": median.importance_us,
        "warp_us": median.warp_us,
        "region": { "origin_m": [map.origin.x, map.origin.y], "spacing_m": map.spacing, "size": n },
        "histogram": q.histogram,
    });
    if json {
        println!("{out}");
    } else {
        println!(
            "{} visible cells: {:.1} % with ratio in [0.5, 2], {:.1} % in [0.5, 1]; {} flipped, {} non-finite; CPU stage {:.0} µs (sketch map {:.0}, importance {:.0}, warp {:.0})",
            q.cells_visible,
            100.0 * q.ratio_within_0_5_2,
            100.0 * q.ratio_within_0_5_1,
            q.flipped_cells,
            q.nonfinite,
            median.total_us(),
            median.sketch_map_us,
            median.importance_us,
            median.warp_us
        );
    }
    Ok(())
}

/// `--modes`, `view --mode`: a mode that draws a mesh (not the reference).
fn mesh_mode(s: &str) -> Result<Mode, String> {
    Mode::MESHES
        .into_iter()
        .find(|m| m.name() == s)
        .ok_or_else(|| {
            let names: Vec<&str> = Mode::MESHES.iter().map(|m| m.name()).collect();
            format!("expected one of {}", names.join(", "))
        })
}

struct FlyArgs {
    mode: Option<Mode>,
    view: View,
    frames: Option<u32>,
    fps: f64,
    size: Option<(u32, u32)>,
    mp4: bool,
}

fn fly(scene_path: &Path, set: &[String], out_dir: &Path, a: &FlyArgs, json: bool) -> Result<()> {
    let mut scene = Scene::load_with(scene_path, set)?;
    if let Some(size) = a.size {
        (scene.camera.width, scene.camera.height) = size;
    }
    let opts = terrain::fly::Options {
        mode: a.mode.unwrap_or(scene.render.mode),
        view: a.view,
        frames: a.frames.map(|n| n as usize),
        fps: a.fps,
        mp4: a.mp4,
    };
    let o = terrain::fly::run(&scene, &opts, out_dir)?;
    if let Some(note) = &o.mp4_note {
        eprintln!("{note}");
    }
    if json {
        let out = json!({
            "adapter": o.adapter,
            "frames": o.frames.len(),
            "frame_ms_median": o.frame_ms_median,
            "frame_ms_p95": o.frame_ms_p95,
            "spread_p95_over_median": o.spread,
            "animation": o.animation.display().to_string(),
            "mp4": o.mp4.as_ref().map(|p| p.display().to_string()),
            "elapsed_s": o.elapsed_s,
        });
        println!("{out}");
    } else {
        println!(
            "{} frames on {} in {:.1} s: frame time median {:.1} ms, p95 {:.1} ms (p95/median {:.2}); {}{}, frames.csv in {}",
            o.frames.len(),
            o.adapter,
            o.elapsed_s,
            o.frame_ms_median,
            o.frame_ms_p95,
            o.spread,
            o.animation.display(),
            o.mp4
                .as_ref()
                .map(|p| format!(", {}", p.display()))
                .unwrap_or_default(),
            out_dir.display()
        );
    }
    Ok(())
}

struct ViewArgs {
    size: (u32, u32),
    frames: Option<u64>,
    out_dir: PathBuf,
    screenshot: Option<PathBuf>,
}

#[cfg(feature = "view")]
fn view(scene_path: &Path, set: &[String], mode: Option<Mode>, a: ViewArgs) -> Result<()> {
    let scene = Scene::load_with(scene_path, set)?;
    let mode = match mode {
        Some(m) => m,
        None if scene.render.mode == Mode::Reference => Mode::Warped,
        None => scene.render.mode,
    };
    let opts = terrain::view::Options {
        scene_path: scene_path.to_path_buf(),
        mode,
        size: a.size,
        frames: a.frames,
        out_dir: a.out_dir,
        screenshot: a.screenshot,
    };
    Ok(terrain::view::run(scene, opts)?)
}

#[cfg(not(feature = "view"))]
fn view(_: &Path, _: &[String], _: Option<Mode>, _: ViewArgs) -> Result<()> {
    anyhow::bail!(
        "this terrain was built without the `view` feature (cargo build --release builds it)"
    )
}

fn batch(
    jobs: &Path,
    out_dir: &Path,
    shard: Option<(usize, usize)>,
    resume: bool,
    merge: bool,
    json: bool,
) -> Result<()> {
    if merge {
        let (lines, missing, failed) = terrain::batch::merge_manifests(jobs, out_dir)?;
        if json {
            println!(
                "{}",
                json!({ "lines": lines, "missing": missing, "failed": failed })
            );
        } else {
            println!(
                "{}: {lines} items, {} missing, {failed} failed",
                out_dir.join("manifest.jsonl").display(),
                missing.len()
            );
        }
        anyhow::ensure!(
            missing.is_empty() && failed == 0,
            "{} items missing{}, {failed} failed: run the shards again with --resume",
            missing.len(),
            missing
                .first()
                .map(|m| format!(" (first {m})"))
                .unwrap_or_default()
        );
        return Ok(());
    }
    let shard = shard.unwrap_or((0, 1));
    let s = terrain::batch::run(jobs, out_dir, &terrain::batch::Options { shard, resume })?;
    let rate = s.rendered as f64 / s.seconds.max(1e-9);
    if json {
        println!(
            "{}",
            json!({
                "items": s.total, "rendered": s.rendered, "skipped": s.skipped, "failed": s.failed,
                "seconds": s.seconds, "snapshots_per_s": rate,
                "manifest": s.manifest.display().to_string(),
            })
        );
    } else {
        println!(
            "{} of {} items rendered in {:.1} s ({rate:.2} snapshots/s), {} already done, {} failed; {}",
            s.rendered,
            s.total,
            s.seconds,
            s.skipped,
            s.failed,
            s.manifest.display()
        );
    }
    anyhow::ensure!(
        s.failed == 0,
        "{} of {} snapshots failed; their causes are in {}",
        s.failed,
        s.total,
        s.manifest.display()
    );
    Ok(())
}

fn compare(
    scene_path: &Path,
    set: &[String],
    out_dir: &Path,
    mut opts: terrain::compare::Options,
    json: bool,
) -> Result<()> {
    opts.modes.dedup();
    anyhow::ensure!(!opts.modes.is_empty(), "--modes: give at least one mode");
    let scene = Scene::load_with(scene_path, set)?;
    let name = scene_path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "scene".into());
    let outcome = terrain::compare::run(&scene, &name, &opts, out_dir)?;
    if json {
        println!("{}", outcome.report);
    } else {
        print!(
            "{}",
            terrain::compare::report::summary_markdown(&name, &outcome.summary)
        );
        let skipped = outcome.report["skipped"].as_array().map_or(0, |a| a.len());
        println!(
            "\n{} settings measured{} in {:.0} s; report.csv, report.json and figures in {}",
            outcome.rows.len(),
            if skipped > 0 {
                format!(", {skipped} skipped (see report.json)")
            } else {
                String::new()
            },
            outcome.report["elapsed_s"].as_f64().unwrap_or(0.0),
            out_dir.display()
        );
    }
    Ok(())
}

fn render(
    scene_path: &Path,
    set: &[String],
    out: &Path,
    opts: &RenderOpts,
    json: bool,
) -> Result<()> {
    // Refused before any work: an image format the extension does not name, positions that are
    // not .npy.
    output::ImageFormat::of(out)?;
    if let Some(p) = &opts.positions
        && p.extension().is_none_or(|e| !e.eq_ignore_ascii_case("npy"))
    {
        return Err(Error::file(
            Role::Output,
            p,
            "--positions writes NumPy: give a .npy file name",
        )
        .into());
    }
    let mut scene = Scene::load_with(scene_path, set)?;
    let mode = opts.mode.unwrap_or(scene.render.mode);
    if let Some(tau) = opts.tau {
        scene.geomipmap.tau = tau;
    }
    if let Some(size) = opts.size {
        (scene.camera.width, scene.camera.height) = size;
    }
    let view = opts.view;
    let mut r = SceneRenderer::with_positions(&scene, mode, view, opts.positions.is_some())?;
    let camera = cpu_stage::camera_of(&scene, r.atlas())?;
    let big = scene.camera.width as u64 * scene.camera.height as u64 > BIG_RENDER_PIXELS;
    let spinner = big.then(|| {
        Spinner::new(&format!(
            "rendering {}×{} ({} frames)",
            scene.camera.width,
            scene.camera.height,
            opts.repeat + 1
        ))
    });
    r.render(&camera)?; // warm-up: shader compilation and first-use allocation
    let mut frames = Vec::with_capacity(opts.repeat as usize);
    for _ in 0..opts.repeat {
        frames.push(r.render(&camera)?);
    }
    if let Some(s) = spinner {
        s.finish();
    }
    let median = |f: &dyn Fn(&terrain::render::Frame) -> f64| {
        let mut v: Vec<f64> = frames.iter().map(f).collect();
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let cpu_us = median(&|f| f.cpu_us);
    let gpu_ms = median(&|f| f.gpu.gpu_ms);
    let gpu_wall_ms = median(&|f| f.gpu.gpu_wall_ms);
    let timed = r.ctx().timestamps;
    let pass = |get: fn(&terrain::gpu::renderer::PassTimes) -> Option<f64>| {
        timed.then(|| median(&|f| get(&f.gpu.passes).unwrap_or(0.0)))
    };
    let last = frames.last().context("no frame rendered")?;
    // The image and the positions land together or not at all.
    let mut staged = output::Staged::default();
    staged.add_image(out, last.width, last.height, &last.rgba)?;
    if let Some(p) = &opts.positions {
        let world = terrain::render::world_positions(&r.read_positions(&camera)?, &camera);
        let shape = [last.height as usize, last.width as usize, 4];
        staged.add(p, &output::npy_f64(&shape, &world))?;
    }
    staged.commit()?;
    let mode_name = mode.name();
    let mut report = json!({
        "adapter": r.ctx().adapter_name(),
        "mode": mode_name,
        "view": view.name(),
        "width": last.width,
        "height": last.height,
        "visible": r.visible(),
        "triangles": last.gpu.triangles,
        "cpu_stage_us": cpu_us,
        "gpu_ms": gpu_ms,
        "frame_ms": gpu_ms + cpu_us * 1e-3,
        "gpu_wall_ms": gpu_wall_ms,
        "gpu_timing": if timed { "timestamp queries" } else { "wall time around submit" },
        "passes_ms": {
            "warp_zoom": pass(|p| p.warp_zoom_ms),
            "normals": pass(|p| p.normals_ms),
            "terrain": pass(|p| p.terrain_ms),
        },
        "gpu_memory_bytes": r.gpu_bytes(),
        "frames": opts.repeat,
        "output": out.display().to_string(),
        "detail": detail_json(&cpu_stage::detail_of(&scene, r.atlas())),
    });
    if let Some((ms, bytes)) = r.precompute() {
        report["blocks_visible"] = json!(last.blocks);
        report["precompute_ms"] = json!(ms);
        report["precompute_bytes"] = json!(bytes);
        report["tau_px"] = json!(scene.geomipmap.tau);
    }
    if json {
        println!("{report}");
    } else {
        println!(
            "{}: {} × {} {mode_name} on {}, {} triangles; CPU {:.0} µs, GPU {:.2} ms ({})",
            out.display(),
            last.width,
            last.height,
            r.ctx().adapter_name(),
            last.gpu.triangles,
            cpu_us,
            gpu_ms,
            report["gpu_timing"].as_str().unwrap_or_default()
        );
    }
    Ok(())
}

/// Renders above this many pixels show a spinner: at 16384² a frame takes minutes on llvmpipe.
const BIG_RENDER_PIXELS: u64 = 8 << 20;

/// The detail used, defaults resolved from the sketch included (docs/scene.md, [detail]).
fn detail_json(d: &terrain::detail::Detail) -> serde_json::Value {
    json!({ "octaves": d.octaves, "amplitude_m": d.amplitude_m, "gain": d.gain, "bias": d.bias })
}

struct RenderOpts {
    size: Option<(u32, u32)>,
    mode: Option<Mode>,
    view: View,
    tau: Option<f64>,
    repeat: u32,
    positions: Option<PathBuf>,
}
