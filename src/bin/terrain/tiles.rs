//! `terrain tiles SRC --out-dir DIR`: a sketch converted into a tile pyramid on disk, streamed with
//! bounded memory and resumable (run it again after a kill). An 8-bit RGB or RGBA GeoTIFF (or a
//! grey one with `--image`) becomes an image pyramid, for `surface.image`.

use anyhow::Result;
use std::path::PathBuf;
use terrain_engine::sketch::LoadOptions;
use terrain_engine::sketch::convert::{BuildOptions, build};
use terrain_engine::sketch::tiles::Kind;

#[derive(clap::Args)]
pub struct Args {
    /// A sketch file, or a quoted glob of tiles (`'srtm/*.hgt'`); or an image GeoTIFF.
    src: PathBuf,
    /// The pyramid's folder: created, or resumed where an interrupted run stopped.
    // `--out`, its first name, kept for scripts that use it.
    #[arg(long, alias = "out")]
    out_dir: PathBuf,
    /// Grid spacing in metres, for formats that carry none (PNG without a world file).
    #[arg(long)]
    spacing_m: Option<f64>,
    /// Metres per unit of the file's heights (0.001 for millimetres), as `sketch.height_scale`.
    #[arg(long)]
    height_scale: Option<f64>,
    /// Converts an 8-bit grey GeoTIFF as an image for `surface.image`, not as heights (an RGB
    /// or RGBA one is an image without it).
    #[arg(long)]
    image: bool,
    /// Threads encoding tiles (default: all cores).
    #[arg(long, default_value_t = 0)]
    threads: usize,
    /// Prints one JSON object on stdout instead of the summary line.
    #[arg(long)]
    json: bool,
}

pub fn run(a: Args) -> Result<()> {
    let opts = BuildOptions {
        load: LoadOptions {
            spacing_m: a.spacing_m,
            height_scale: a.height_scale,
            ..LoadOptions::default()
        },
        threads: a.threads,
        image: a.image,
    };
    let s = build(&a.src, &a.out_dir, &opts)?;
    let heights = s.kind == Kind::Heights;
    if heights {
        // Said once the source was read whole, from what the pyramid recorded of it.
        let meta = terrain_engine::sketch::tiles::Pyramid::open(&a.out_dir)?.meta;
        let extent = meta.extent();
        crate::warn(&terrain_engine::sketch::warnings(
            &a.src, &opts.load, &extent,
        ));
    }
    if a.json {
        return crate::print_json(&s);
    }
    let (what, from) = match heights {
        true => ("nodes", format!("{} source file(s)", s.sources)),
        false => ("pixels", "an image".into()),
    };
    outln!(
        "{}: {} × {} {what} from {from} in {} levels, {} tiles ({} written now), {:.1} MiB, {:.1} s",
        a.out_dir.display(),
        s.width,
        s.height,
        s.levels,
        s.tiles,
        s.tiles_written,
        s.disk_bytes as f64 / (1 << 20) as f64,
        s.seconds
    );
    Ok(())
}
