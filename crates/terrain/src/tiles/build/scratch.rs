//! Reading the sources into scratch: each copied once, one in memory at a time, into a raw file
//! that level 0's bands read by rows, and the mosaic they place.
//!
//! Rule: a source is read and height-scaled as the atlas would read it, so a sketch with no
//! nodata converts bit for bit; a scratch file a run before wrote is read back, not redone.

use super::bands::band_rows;
use super::resume::write_quietly;
use crate::error::{Error, Result, Role};
use crate::sketch::georef::{Georef, Units};
use crate::sketch::mosaic::{self, TileExtent};
use crate::sketch::{LoadOptions, read_grid, scale_heights};
use crate::tiles::{Meta, MetaGeoref};
use serde::{Deserialize, Serialize};
use std::os::unix::fs::FileExt;
use std::path::{Path, PathBuf};

/// A source copied to scratch: `src-K.f32` (row-major f32, row 0 south) and `src-K.json`.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub(super) struct Scratch {
    pub(super) width: usize,
    pub(super) height: usize,
    pub(super) dx: f64,
    pub(super) dy: f64,
    pub(super) georef: Option<MetaGeoref>,
}

/// Copies each source into scratch (one in memory at a time), or reads back what a run before
/// copied.
pub(super) fn copy_sources(
    sources: &[PathBuf],
    dir: &Path,
    load: &LoadOptions,
) -> Result<Vec<Scratch>> {
    let mut progress = crate::progress::start("reading sources", Some(sources.len() as f64));
    let mut out = Vec::with_capacity(sources.len());
    for (k, path) in sources.iter().enumerate() {
        let info = dir.join(format!("src-{k}.json"));
        let done = std::fs::read(&info)
            .ok()
            .and_then(|b| serde_json::from_slice::<Scratch>(&b).ok());
        let scratch = match done {
            Some(s) => s,
            None => {
                let mut raw = read_grid(path, load)?;
                scale_heights(&mut raw.data, load).map_err(|e| match e {
                    Error::Value { reason, .. } => Error::sketch(path, reason),
                    e => e,
                })?;
                let mut bytes = Vec::with_capacity(raw.data.len() * 4);
                for h in &raw.data {
                    bytes.extend_from_slice(&h.to_le_bytes());
                }
                write_quietly(&dir.join(format!("src-{k}.f32")), &bytes)?;
                let s = Scratch {
                    width: raw.width,
                    height: raw.height,
                    dx: raw.dx,
                    dy: raw.dy,
                    georef: raw.georef.map(meta_georef),
                };
                let json =
                    serde_json::to_vec(&s).map_err(|e| Error::encode("scratch record", e))?;
                write_quietly(&info, &json)?;
                s
            }
        };
        out.push(scratch);
        progress.advance(1.0, &path.display().to_string());
    }
    progress.finish();
    Ok(out)
}

pub(super) type Placed = (usize, usize, f64, f64, Vec<(usize, usize)>, Option<Georef>);

/// The mosaic's size, spacing and each source's offset, as [`crate::sketch`] places a glob.
pub(super) fn place(
    src: &Path,
    sources: &[PathBuf],
    scratch: &[Scratch],
    load: &LoadOptions,
) -> Result<Placed> {
    let (width, height, offsets, georef, (dx, dy)) = if sources.len() == 1 {
        let s = &scratch[0];
        (
            s.width,
            s.height,
            vec![(0, 0)],
            s.georef.as_ref().map(georef_of),
            (s.dx, s.dy),
        )
    } else {
        let extents: Vec<TileExtent> = sources
            .iter()
            .zip(scratch)
            .map(|(path, s)| TileExtent {
                path,
                georef: s.georef.as_ref().map(georef_of),
                width: s.width,
                height: s.height,
            })
            .collect();
        let p = mosaic::place(src, &extents)?;
        // Resolved at the mosaic's size, as the in-memory mosaic's RawGrid::georeferenced does.
        let georef = p.georef.resolved(p.width, p.height);
        let spacing = georef.spacing_m(p.width, p.height);
        (p.width, p.height, p.offsets, Some(georef), spacing)
    };
    let (dx, dy) = load.spacing_m.map_or((dx, dy), |s| (s, s));
    if !(dx.is_finite() && dy.is_finite() && dx > 0.0 && dy > 0.0) {
        return Err(Error::sketch(
            src,
            format!("grid spacing {dx} × {dy} m is not positive and finite; set --spacing-m"),
        ));
    }
    Ok((width, height, dx, dy, offsets, georef))
}

/// Level 0's rows `ty·TILE − BORDER .. (ty+1)·TILE + BORDER` (clamped), filled: (first row, rows).
pub(super) fn level0_band(
    meta: &Meta,
    ty: usize,
    dir: &Path,
    scratch: &[Scratch],
    offsets: &[(usize, usize)],
) -> Result<(usize, Vec<f32>)> {
    let (w, h) = (meta.width, meta.height);
    let (r0, r1) = band_rows(ty, h);
    let mut band = vec![f32::NAN; w * (r1 - r0)];
    let mut row = Vec::new();
    for (k, (s, &(x0, y0))) in scratch.iter().zip(offsets).enumerate() {
        let (lo, hi) = (r0.max(y0), r1.min(y0 + s.height));
        if lo >= hi {
            continue;
        }
        let path = dir.join(format!("src-{k}.f32"));
        let file = std::fs::File::open(&path).map_err(|e| Error::io(Role::Sketch, &path, e))?;
        row.resize(s.width * 4, 0u8);
        for r in lo..hi {
            file.read_exact_at(&mut row, ((r - y0) * s.width * 4) as u64)
                .map_err(|e| Error::io(Role::Sketch, &path, e))?;
            let dst = &mut band[(r - r0) * w + x0..(r - r0) * w + x0 + s.width];
            for (d, b) in dst.iter_mut().zip(row.chunks_exact(4)) {
                let v = f32::from_le_bytes(b.try_into().expect("4 bytes"));
                if v.is_finite() {
                    *d = v;
                }
            }
        }
    }
    Ok((r0, band))
}

pub(super) fn meta_georef(g: Georef) -> MetaGeoref {
    MetaGeoref {
        units: match g.units {
            Units::Degrees => "degrees".into(),
            Units::Linear(m) => format!("{m}"),
            Units::Unknown => "unknown".into(),
        },
        west: g.west,
        south: g.south,
        cell_x: g.cell_x,
        cell_y: g.cell_y,
        epsg: g.epsg,
    }
}

/// The inverse of `meta_georef`.
pub fn georef_of(m: &MetaGeoref) -> Georef {
    Georef {
        west: m.west,
        south: m.south,
        cell_x: m.cell_x,
        cell_y: m.cell_y,
        units: match m.units.as_str() {
            "degrees" => Units::Degrees,
            "unknown" => Units::Unknown,
            s => s.parse().map_or(Units::Unknown, Units::Linear),
        },
        epsg: m.epsg,
    }
}
