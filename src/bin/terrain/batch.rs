//! `terrain batch JOBS --out-dir D`: many snapshots on one device (the library's `batch` module),
//! sharded, resumed, or the shards' manifests merged.

use crate::args;
use anyhow::Result;
use serde::Serialize;
use std::path::PathBuf;
use terrain_cli::app::batch::{Export, export};
use terrain_engine::scene::Mode;
use terrain_engine::truth::Output;

#[derive(clap::Args)]
pub struct Args {
    /// The jobs file (.toml): a base scene, its random cameras and its jobs (docs/scene.md).
    jobs: PathBuf,
    /// The folder the snapshots and manifest.jsonl are written to.
    #[arg(long)]
    out_dir: PathBuf,
    /// Renders share i of n (items k with k mod n = i), e.g. --shard 0/4.
    #[arg(long, value_name = "I/N", value_parser = args::shard)]
    shard: Option<(usize, usize)>,
    /// Skips items the manifest lists as done; retries failed ones. Refused where the manifest
    /// was made from other inputs (jobs file, base scene, sketches, --set, --size, --mode,
    /// --outputs).
    #[arg(long)]
    resume: bool,
    /// Overrides a scene key in every item (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE", conflicts_with = "merge")]
    set: Vec<String>,
    /// Image size of every item: N (square) or WxH; default each item's scene's.
    #[arg(long, value_name = "N|WxH", value_parser = args::size, conflicts_with = "merge")]
    size: Option<(u32, u32)>,
    /// Overrides every item's render.mode.
    #[arg(long, value_parser = crate::args::named::<Mode>(), conflicts_with = "merge")]
    mode: Option<Mode>,
    /// What each item writes: rgb (its image) and the ground truth beside it (depth, distance,
    /// positions, latlon, normals, surface; docs/batch.md).
    #[arg(long, value_name = "LIST", value_parser = args::outputs, default_value = "rgb", conflicts_with = "merge")]
    outputs: Vec<Vec<Output>>,
    /// Writes the cameras for other tools beside the images once the items are done: nerf
    /// (transforms.json) or colmap (cameras.txt, images.txt, points3D.txt). With --shard, give it
    /// to --merge.
    #[arg(long, value_enum)]
    export: Option<Export>,
    /// Merges the shard manifests in --out-dir into manifest.jsonl instead of rendering.
    #[arg(long, conflicts_with_all = ["shard", "resume"])]
    merge: bool,
    /// Prints one JSON object on stdout instead of the summary line.
    #[arg(long)]
    json: bool,
}

/// `--json` of a batch.
#[derive(Serialize)]
struct Report {
    items: usize,
    rendered: usize,
    skipped: usize,
    failed: usize,
    seconds: f64,
    snapshots_per_s: f64,
    manifest: PathBuf,
    /// What `--export` wrote.
    exported: Vec<PathBuf>,
}

/// `--json` of `--merge`.
#[derive(Serialize)]
struct Merged {
    lines: usize,
    missing: Vec<String>,
    failed: usize,
    exported: Vec<PathBuf>,
}

pub fn run(a: Args) -> Result<()> {
    if a.merge {
        return merge(&a);
    }
    if a.export.is_some() && a.shard.is_some_and(|(_, n)| n > 1) {
        anyhow::bail!(
            "--export with --shard: each shard holds part of the cameras; give --export to \
             `terrain batch --merge` once every shard is done"
        );
    }
    let o = terrain_cli::app::batch::Options {
        shard: a.shard.unwrap_or((0, 1)),
        resume: a.resume,
        overrides: terrain_cli::app::batch::Overrides {
            set: a.set.clone(),
            size: a.size,
            mode: a.mode,
        },
        outputs: a.outputs.concat(),
        export: a.export,
    };
    let s = terrain_cli::app::batch::run(&a.jobs, &a.out_dir, &o)?;
    let r = Report {
        items: s.total,
        rendered: s.rendered,
        skipped: s.skipped,
        failed: s.failed,
        seconds: s.seconds,
        snapshots_per_s: s.rendered as f64 / s.seconds.max(1e-9),
        manifest: s.manifest,
        exported: s.exported,
    };
    if a.json {
        crate::print_json(&r)?;
    } else {
        outln!(
            "{} of {} items rendered in {:.1} s ({:.2} snapshots/s), {} already done, {} failed; {}",
            r.rendered,
            r.items,
            r.seconds,
            r.snapshots_per_s,
            r.skipped,
            r.failed,
            r.manifest.display()
        );
    }
    anyhow::ensure!(
        r.failed == 0,
        "{} of {} snapshots failed; their causes are in {}",
        r.failed,
        r.items,
        r.manifest.display()
    );
    Ok(())
}

fn merge(a: &Args) -> Result<()> {
    let (lines, missing, failed) = terrain_cli::app::batch::merge_manifests(&a.jobs, &a.out_dir)?;
    let exported = match a.export {
        Some(format) => export(format, &a.out_dir.join("manifest.jsonl"))?,
        None => Vec::new(),
    };
    let m = Merged {
        lines,
        missing,
        failed,
        exported,
    };
    if a.json {
        crate::print_json(&m)?;
    } else {
        outln!(
            "{}: {} items, {} missing, {} failed",
            a.out_dir.join("manifest.jsonl").display(),
            m.lines,
            m.missing.len(),
            m.failed
        );
    }
    anyhow::ensure!(
        m.missing.is_empty() && m.failed == 0,
        "{} items missing{}, {} failed: run the shards again with --resume",
        m.missing.len(),
        m.missing
            .first()
            .map(|s| format!(" (first {s})"))
            .unwrap_or_default(),
        m.failed
    );
    Ok(())
}
