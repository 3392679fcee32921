//! Reading the sources into scratch: each copied once, one in memory at a time, into a raw file
//! that level 0's bands read by rows, and the mosaic they place.
//!
//! Rule: a source is read and height-scaled as the atlas would read it, so a sketch with no
//! nodata converts bit for bit; a scratch file a run before wrote is read back, not redone.

use super::resume::write_quietly;
use crate::error::{Error, Result, Role};
use crate::sketch::georef::{Georef, Units};
use crate::sketch::load::{Beyond, LoadOptions, RawGrid, read_grid, scale_cells, scale_heights};
use crate::sketch::mosaic::{self, TileExtent};
use crate::sketch::tiles::MetaGeoref;
use crate::sketch::tiles::TILE;
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

/// Copies each source into scratch (one at a time), or reads back what a run before copied;
/// heights scaled.
pub(super) fn copy_sources(
    sources: &[PathBuf],
    dir: &Path,
    load: &LoadOptions,
) -> Result<Vec<Scratch>> {
    let mut progress = crate::progress::start("reading sources", Some(sources.len() as f64));
    let mut out = Vec::with_capacity(sources.len());
    for (k, path) in sources.iter().enumerate() {
        out.push(copy_source(k, path, dir, load, true)?);
        progress.advance(1.0, &path.display().to_string());
    }
    progress.finish();
    Ok(out)
}

/// Copies source `k` into scratch as `src-K.f32`, read with `load` and its heights scaled when
/// `scale`, or reads back the record of a copy a run before made. A GeoTIFF is copied band by
/// band from its chunks; any other format is read whole (held once, as in memory), a text grid
/// only up to [`MAX_TEXT_BYTES`].
pub(super) fn copy_source(
    k: usize,
    path: &Path,
    dir: &Path,
    load: &LoadOptions,
    scale: bool,
) -> Result<Scratch> {
    let info = dir.join(format!("src-{k}.json"));
    if let Some(s) = std::fs::read(&info)
        .ok()
        .and_then(|b| serde_json::from_slice::<Scratch>(&b).ok())
    {
        return Ok(s);
    }
    let raw_path = dir.join(format!("src-{k}.f32"));
    let as_sketch = |e| match e {
        Error::Value { reason, .. } => Error::sketch(path, reason),
        e => e,
    };
    let s = if super::is_tiff(path) {
        let mut tiff = crate::sketch::geotiff::open(path)?;
        let (w, h) = (tiff.width, tiff.height);
        let mut beyond = Beyond::default();
        let mut failed = None;
        let (mut rows, mut bytes) = (Vec::new(), Vec::new());
        write_pieces(&raw_path, w * h * 4, |file| {
            for lo in (0..h).step_by(TILE) {
                let hi = (lo + TILE).min(h);
                rows.resize(w * (hi - lo), 0.0);
                let read = tiff
                    .rows_into(lo, hi, hi, &mut rows)
                    .and_then(|()| match scale {
                        true => scale_cells(&mut rows, load).map(|b| beyond.add(b)),
                        false => Ok(()),
                    });
                if let Err(e) = read {
                    failed = Some(e);
                    return Err(std::io::Error::other("source unreadable"));
                }
                bytes.clear();
                bytes.extend(rows.iter().flat_map(|v| v.to_le_bytes()));
                file.write_all_at(&bytes, (lo * w * 4) as u64)?;
            }
            Ok(())
        })
        .map_err(|e| failed.take().map_or(e, as_sketch))?;
        if scale {
            beyond.check(w * h, load).map_err(as_sketch)?;
        }
        let grid = RawGrid::new(w, h, Vec::new(), tiff.georef);
        Scratch {
            width: w,
            height: h,
            dx: grid.dx,
            dy: grid.dy,
            georef: grid.georef.map(meta_georef),
        }
    } else {
        refuse_large_text(path)?;
        let mut raw = read_grid(path, load)?;
        if scale {
            scale_heights(&mut raw.data, load).map_err(as_sketch)?;
        }
        // Row by row, not a second copy of the grid as bytes.
        let mut bytes = Vec::with_capacity(raw.width * 4);
        write_pieces(&raw_path, raw.data.len() * 4, |file| {
            for (r, row) in raw.data.chunks(raw.width).enumerate() {
                bytes.clear();
                bytes.extend(row.iter().flat_map(|v| v.to_le_bytes()));
                file.write_all_at(&bytes, (r * raw.width * 4) as u64)?;
            }
            Ok(())
        })?;
        Scratch {
            width: raw.width,
            height: raw.height,
            dx: raw.dx,
            dy: raw.dy,
            georef: raw.georef.map(meta_georef),
        }
    };
    let json = serde_json::to_vec(&s).map_err(|e| Error::encode("scratch record", e))?;
    write_quietly(&info, &json)?;
    Ok(s)
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
            s.georef.as_ref().map(MetaGeoref::georef),
            (s.dx, s.dy),
        )
    } else {
        let extents: Vec<TileExtent> = sources
            .iter()
            .zip(scratch)
            .map(|(path, s)| TileExtent {
                path,
                georef: s.georef.as_ref().map(MetaGeoref::georef),
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
    let (dx, dy) = spacing(src, (dx, dy), load)?;
    Ok((width, height, dx, dy, offsets, georef))
}

/// The spacing a source says, or `--spacing-m`, checked.
pub(super) fn spacing(src: &Path, (dx, dy): (f64, f64), load: &LoadOptions) -> Result<(f64, f64)> {
    let (dx, dy) = load.spacing_m.map_or((dx, dy), |s| (s, s));
    if !(dx.is_finite() && dy.is_finite() && dx > 0.0 && dy > 0.0) {
        return Err(Error::sketch(
            src,
            format!("grid spacing {dx} × {dy} m is not positive and finite; set --spacing-m"),
        ));
    }
    Ok((dx, dy))
}

/// Text grids larger than this are refused by `terrain tiles`: their readers hold the text and
/// the grid at once (about 1.7 times the file in memory).
pub(super) const MAX_TEXT_BYTES: u64 = 256 << 20;

/// Refuses an ESRI ASCII or XYZ file above [`MAX_TEXT_BYTES`], with the command that makes it a
/// GeoTIFF that converts in bounded memory.
fn refuse_large_text(path: &Path) -> Result<()> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase())
        .unwrap_or_default();
    if !["asc", "grd", "xyz", "csv", "txt"].contains(&ext.as_str()) {
        return Ok(());
    }
    let bytes = std::fs::metadata(path)
        .map_err(|e| Error::io(Role::Sketch, path, e))?
        .len();
    if bytes <= MAX_TEXT_BYTES {
        return Ok(());
    }
    Err(Error::sketch(
        path,
        format!(
            "text grid of {} MiB is more than the {} MiB `terrain tiles` reads whole; make it a \
             GeoTIFF first: `gdal_translate -of GTiff -co TILED=YES -co COMPRESS=DEFLATE {} OUT.tif`",
            bytes >> 20,
            MAX_TEXT_BYTES >> 20,
            path.display()
        ),
    ))
}

/// Writes `len` bytes to a temporary file beside `path` through `write`, then renames it into
/// place.
fn write_pieces(
    path: &Path,
    len: usize,
    write: impl FnOnce(&std::fs::File) -> std::io::Result<()>,
) -> Result<()> {
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir).map_err(|e| Error::io(Role::OutputFolder, dir, e))?;
    }
    let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("src");
    let tmp = path.with_file_name(format!(".{name}.{}.tmp", std::process::id()));
    std::fs::File::create(&tmp)
        .and_then(|file| {
            file.set_len(len as u64)?;
            write(&file)
        })
        .and_then(|()| std::fs::rename(&tmp, path))
        .map_err(|e| {
            let _ = std::fs::remove_file(&tmp);
            Error::io(Role::Output, path, e)
        })
}

pub(in crate::sketch::convert) fn meta_georef(g: Georef) -> MetaGeoref {
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
