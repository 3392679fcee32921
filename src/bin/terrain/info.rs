//! `terrain info FILE`: what a sketch file holds, as the readers see it.

use anyhow::Result;
use serde::Serialize;
use std::path::PathBuf;
use terrain::sketch::{Atlas, LoadOptions};

#[derive(clap::Args)]
pub struct Args {
    file: PathBuf,
    /// Grid spacing in metres, for formats that carry none (PNG).
    #[arg(long)]
    spacing_m: Option<f64>,
    #[arg(long)]
    json: bool,
}

/// `--json`: the keys DESIGN.md fixes (`width`, `height`, `spacing_m`, `min_m`, `max_m`,
/// `nodata`) and the cell size per axis.
#[derive(Serialize)]
struct Report {
    file: String,
    width: usize,
    height: usize,
    /// The smaller of `dx_m` and `dy_m`: d_atlas.
    spacing_m: f64,
    dx_m: f64,
    dy_m: f64,
    min_m: f32,
    max_m: f32,
    nodata: usize,
}

pub fn run(a: Args) -> Result<()> {
    let opts = LoadOptions {
        spacing_m: a.spacing_m,
        ..LoadOptions::default()
    };
    let atlas = Atlas::load(&a.file, &opts)?;
    let r = Report {
        file: a.file.display().to_string(),
        width: atlas.width(),
        height: atlas.height(),
        spacing_m: atlas.d_atlas(),
        dx_m: atlas.dx,
        dy_m: atlas.dy,
        min_m: atlas.min_m,
        max_m: atlas.max_m,
        nodata: atlas.nodata,
    };
    if a.json {
        return crate::print_json(&r);
    }
    println!(
        "{}: {} × {} cells of {:.2} × {:.2} m ({:.1} × {:.1} km), heights {:.1} … {:.1} m, {} nodata filled",
        r.file,
        r.width,
        r.height,
        r.dx_m,
        r.dy_m,
        (r.width - 1) as f64 * r.dx_m / 1000.0,
        (r.height - 1) as f64 * r.dy_m / 1000.0,
        r.min_m,
        r.max_m,
        r.nodata
    );
    Ok(())
}
