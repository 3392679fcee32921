//! `terrain info FILE`: what a sketch file holds, as the readers see it.

use anyhow::Result;
use serde::Serialize;
use std::path::PathBuf;
use terrain_engine::sketch::{Atlas, Extent, LoadOptions};
use terrain_engine::sketch::{Georef, Units};

#[derive(clap::Args)]
pub struct Args {
    /// A sketch file (any format of docs/formats.md), a quoted glob of tiles, or a tile
    /// pyramid's folder.
    file: PathBuf,
    /// Grid spacing in metres, for formats that carry none (PNG).
    #[arg(long)]
    spacing_m: Option<f64>,
    /// Metres per unit of the file's heights (0.001 for millimetres), as `sketch.height_scale`.
    #[arg(long)]
    height_scale: Option<f64>,
    /// Prints one JSON object on stdout instead of the summary line.
    #[arg(long)]
    json: bool,
}

/// `--json`: the keys `docs/design.md` fixes (Command line outputs: `width`, `height`,
/// `spacing_m`, `min_m`, `max_m`, `nodata`) and the cell size per axis.
#[derive(Serialize)]
struct Report {
    file: String,
    width: usize,
    height: usize,
    /// The smaller of `dx_m` and `dy_m`: d_atlas.
    spacing_m: f64,
    dx_m: f64,
    dy_m: f64,
    /// Null (with `nodata`) for a GeoTIFF larger than memory, whose header alone is read.
    min_m: Option<f32>,
    max_m: Option<f32>,
    nodata: Option<usize>,
    /// The file's coordinate system and its south-west node there; null when the file has none.
    georef: Option<GeorefReport>,
    /// A tile pyramid's levels (nodes per side, level 0 first) and tiles; absent for a file.
    #[serde(skip_serializing_if = "Option::is_none")]
    levels: Option<Vec<[usize; 2]>>,
    #[serde(skip_serializing_if = "Option::is_none")]
    tiles: Option<usize>,
}

#[derive(Serialize)]
struct GeorefReport {
    /// `degrees`, `metres` or `feet`.
    units: &'static str,
    /// Metres per unit for `metres` and `feet` (0.3048, or 1200/3937 for the US survey foot).
    unit_m: Option<f64>,
    /// The south-west node (a cell's centre, or the sample of a pixel-is-point file).
    west: f64,
    south: f64,
    cell_x: f64,
    cell_y: f64,
}

impl GeorefReport {
    fn new(g: Georef) -> GeorefReport {
        let (units, unit_m) = match g.units {
            Units::Degrees => ("degrees", None),
            Units::Linear(1.0) => ("metres", Some(1.0)),
            Units::Linear(m) => ("feet", Some(m)),
            Units::Unknown => ("metres", Some(1.0)),
        };
        GeorefReport {
            units,
            unit_m,
            west: g.west,
            south: g.south,
            cell_x: g.cell_x,
            cell_y: g.cell_y,
        }
    }

    /// `; south-west node at 84.24667° W 36.62625° N`, or at (x, y) in metres or feet.
    fn describe(&self) -> String {
        match self.units {
            "degrees" => format!(
                "; south-west node at {:.5}° {} {:.5}° {}",
                self.west.abs(),
                if self.west < 0.0 { "W" } else { "E" },
                self.south.abs(),
                if self.south < 0.0 { "S" } else { "N" }
            ),
            units => format!(
                "; south-west node at ({:.2}, {:.2}) {units}",
                self.west, self.south
            ),
        }
    }
}

pub fn run(a: Args) -> Result<()> {
    if terrain_engine::sketch::tiles::is_pyramid(&a.file) {
        return pyramid(a);
    }
    let opts = LoadOptions {
        spacing_m: a.spacing_m,
        height_scale: a.height_scale,
        ..LoadOptions::default()
    };
    // A header that cannot be read leaves the file to the reader, which says why in its terms.
    if let Ok(Some(h)) = terrain_engine::sketch::read_header(&a.file, &opts)
        && (h.width as u128) * (h.height as u128) > terrain_engine::sketch::max_cells() as u128
    {
        return header(a, h, &opts);
    }
    let atlas = Atlas::load(&a.file, &opts)?;
    crate::warn(&terrain_engine::sketch::warnings(
        &a.file,
        &opts,
        &atlas.extent(),
    ));
    let r = Report {
        file: a.file.display().to_string(),
        width: atlas.width(),
        height: atlas.height(),
        spacing_m: atlas.d_atlas(),
        dx_m: atlas.dx,
        dy_m: atlas.dy,
        min_m: Some(atlas.min_m),
        max_m: Some(atlas.max_m),
        nodata: Some(atlas.nodata),
        georef: atlas.georef.map(GeorefReport::new),
        levels: None,
        tiles: None,
    };
    print(&r, a.json)
}

/// A GeoTIFF larger than memory, from its header and georeference alone: its heights are read
/// when `terrain tiles` converts it.
fn header(a: Args, h: terrain_engine::sketch::GridHeader, opts: &LoadOptions) -> Result<()> {
    // Heights unread: the cells' size is all there is to doubt.
    let extent = Extent {
        width: h.width,
        height: h.height,
        dx: h.dx,
        dy: h.dy,
        min_m: 0.0,
        max_m: 0.0,
        georeferenced: h.georef.is_some(),
    };
    crate::warn(&terrain_engine::sketch::warnings(&a.file, opts, &extent));
    let r = Report {
        file: a.file.display().to_string(),
        width: h.width,
        height: h.height,
        spacing_m: h.dx.min(h.dy),
        dx_m: h.dx,
        dy_m: h.dy,
        min_m: None,
        max_m: None,
        nodata: None,
        georef: h.georef.map(GeorefReport::new),
        levels: None,
        tiles: None,
    };
    print(&r, a.json)
}

/// A tile pyramid, from its `pyramid.toml` alone (a 32k² pyramid is not read to describe it).
fn pyramid(a: Args) -> Result<()> {
    let p = terrain_engine::sketch::tiles::Pyramid::open(&a.file)?;
    let m = &p.meta;
    crate::warn(&terrain_engine::sketch::warnings(
        &a.file,
        &LoadOptions::default(),
        &m.extent(),
    ));
    let r = Report {
        file: a.file.display().to_string(),
        width: m.width,
        height: m.height,
        spacing_m: m.dx_m.min(m.dy_m),
        dx_m: m.dx_m,
        dy_m: m.dy_m,
        min_m: Some(m.min_m),
        max_m: Some(m.max_m),
        nodata: Some(m.nodata as usize),
        georef: m.georef.as_ref().map(|g| GeorefReport::new(g.georef())),
        levels: Some(m.levels.clone()),
        tiles: Some(m.tile_count()),
    };
    print(&r, a.json)
}

fn print(r: &Report, json: bool) -> Result<()> {
    if json {
        return crate::print_json(r);
    }
    let heights = match (r.min_m, r.max_m, r.nodata) {
        (Some(lo), Some(hi), Some(nodata)) => {
            format!("heights {lo:.1} … {hi:.1} m, {nodata} nodata filled")
        }
        _ => format!(
            "heights not read (more than {} cells: `terrain tiles` converts it)",
            terrain_engine::sketch::max_cells()
        ),
    };
    outln!(
        "{}: {} × {} cells of {:.2} × {:.2} m ({:.1} × {:.1} km), {heights}{}",
        r.file,
        r.width,
        r.height,
        r.dx_m,
        r.dy_m,
        (r.width - 1) as f64 * r.dx_m / 1000.0,
        (r.height - 1) as f64 * r.dy_m / 1000.0,
        r.georef
            .as_ref()
            .map(GeorefReport::describe)
            .unwrap_or_default()
    );
    if let (Some(levels), Some(tiles)) = (&r.levels, r.tiles) {
        outln!(
            "  a tile pyramid of {} levels (down to {}×{}) in {tiles} tiles",
            levels.len(),
            levels[levels.len() - 1][0],
            levels[levels.len() - 1][1]
        );
    }
    Ok(())
}
