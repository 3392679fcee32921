//! `terrain tiles IMAGE`: an 8-bit GeoTIFF image converted into an image pyramid with bounded
//! memory, resumably.
//!
//! Rules:
//! - Level 0 is cut band by band (one tile row and its borders), each band decoded from the
//!   strips or tiles under its rows alone ([`crate::surface::tiff`]); level l is cut band by band
//!   from level l−1's tiles. What is held at once is a band, the file's chunk rows under it and
//!   one tile per encoding thread, whatever the image's height: about 2 KB per pixel of width
//!   for a file tiled by 256 rows (docs/decisions.md, “Image pyramids”).
//! - Resuming is the heights' (`convert::build`): `build.json` fingerprints the source and the
//!   kind, tiles are renamed into place, a band whose tiles are all whole is skipped, and
//!   `pyramid.toml` is written last.

use super::resume::{Plan, remove_temporaries, stamp, start_or_resume, write_quietly};
use super::{BuildOptions, BuildSummary, band_rows, folder_bytes};
use crate::error::{Error, Result, Role};
use crate::io::write_atomic;
use crate::sketch::tiles::image::{ImageMeta, ImagePyramid, encode_tile, tile_is_whole};
use crate::sketch::tiles::{BORDER, FORMAT, Kind, META, SIDE, TILE, level_sizes, tile_path};
use crate::surface::tiff::{ImageTiff, Samples};
use std::path::Path;
use std::time::Instant;

/// Converts the image at `src` into a pyramid in `out` (created, or resumed where a run stopped).
pub(crate) fn build(src: &Path, out: &Path, opts: &BuildOptions) -> Result<BuildSummary> {
    let start = Instant::now();
    let bad = |why: String| Error::file(Role::Image, src, why);
    let load = &opts.load;
    if load.spacing_m.is_some() || load.height_scale.is_some() || load.height_range_m.is_some() {
        return Err(bad(
            "an image keeps its georeference: --spacing-m and --height-scale are for heights"
                .into(),
        ));
    }
    if crate::sketch::is_glob(src) || !super::is_tiff(src) {
        return Err(bad(
            "an image pyramid is made from a GeoTIFF; make one with `gdal_translate -of GTiff \
             -co TILED=YES -co COMPRESS=DEFLATE IN OUT.tif`"
                .into(),
        ));
    }
    let mut tiff = ImageTiff::open(src)?;
    let Some(georef) = tiff.georef else {
        return Err(bad(
            "no georeference (GeoTIFF tags): its pyramid could never be placed".into(),
        ));
    };
    let (width, height) = (tiff.width, tiff.height);
    let band_pixels = width * (TILE + 2 * BORDER);
    if band_pixels > crate::sketch::load::max_cells() {
        return Err(bad(format!(
            "a band of {width}×{} pixels is more than the {} held at once",
            TILE + 2 * BORDER,
            crate::sketch::load::max_cells()
        )));
    }
    let plan = Plan {
        format: FORMAT.into(),
        kind: Kind::Image,
        sources: vec![stamp(src)?],
        spacing_m: None,
        height_scale: None,
        height_range_m: None,
    };
    start_or_resume(out, &plan)?;
    let summary = |meta: &ImageMeta, written: usize| BuildSummary {
        kind: Kind::Image,
        width: meta.width,
        height: meta.height,
        levels: meta.levels.len(),
        tiles: meta.tile_count(),
        tiles_written: written,
        sources: 1,
        disk_bytes: folder_bytes(out),
        seconds: start.elapsed().as_secs_f64(),
    };
    if out.join(META).is_file() {
        // Whole already: nothing to read or write.
        return Ok(summary(&ImagePyramid::open(out)?.meta, 0));
    }
    let meta = ImageMeta {
        format: FORMAT.into(),
        kind: Kind::Image,
        source: src.display().to_string(),
        samples: match tiff.samples {
            Samples::Grey => "grey",
            Samples::GreyAlpha => "grey+alpha",
            Samples::Rgb => "rgb",
            Samples::Rgba => "rgba",
        }
        .into(),
        width,
        height,
        tile: TILE,
        border: BORDER,
        levels: level_sizes(width, height),
        georef: super::meta_georef(georef),
    };
    remove_temporaries(out);
    let threads = match opts.threads {
        0 => std::thread::available_parallelism().map_or(1, |n| n.get()),
        n => n,
    };
    let mut progress = crate::progress::start("image tiles", Some(meta.tile_count() as f64));
    let mut written = 0;
    for l in 0..meta.levels.len() {
        let [w, h] = meta.levels[l];
        let (tx_count, bands) = meta.tiles(l);
        for ty in 0..bands {
            let missing: Vec<usize> = (0..tx_count)
                .filter(|&tx| !tile_is_whole(&tile_path(out, l, tx, ty)))
                .collect();
            if !missing.is_empty() {
                let (r0, r1) = band_rows(ty, h);
                let band = if l == 0 {
                    let mut band = vec![0u8; w * (r1 - r0) * 4];
                    // The next band starts two rows below this one's top.
                    let next = ((ty + 1) * TILE).saturating_sub(BORDER);
                    tiff.rows_into(r0, r1, next, &mut band)?;
                    band
                } else {
                    coarser_band(out, &meta, l, (r0, r1))?
                };
                write_band(out, (l, ty), (w, h), r0, &band, &missing, threads)?;
                written += missing.len();
            }
            progress.advance(tx_count as f64, &format!("level {l}, row {ty}"));
        }
    }
    progress.finish();
    let text = toml::to_string(&meta).map_err(|e| Error::encode("pyramid.toml", e))?;
    write_atomic(&out.join(META), text.as_bytes())?;
    Ok(summary(&meta, written))
}

/// Level l's rows `r0..r1`, each pixel the alpha-weighted mean of its 2×2 pixels of level l−1,
/// read tile by tile from its tiles: a 2×2 box never straddles a tile (tiles start at even
/// pixels), so level l−1's rows are never held whole.
fn coarser_band(
    out: &Path,
    meta: &ImageMeta,
    l: usize,
    (r0, r1): (usize, usize),
) -> Result<Vec<u8>> {
    let [w, _] = meta.levels[l];
    let (t, b, side) = (meta.tile, meta.border, meta.tile + 2 * meta.border);
    let (tiles_x, _) = meta.tiles(l - 1);
    let mut band = vec![0u8; w * (r1 - r0) * 4];
    let (f0, f1) = (2 * r0, 2 * r1);
    for fty in f0 / t..=(f1 - 1) / t {
        for ftx in 0..tiles_x {
            let fine = crate::sketch::tiles::image::read_tile_file(
                &tile_path(out, l - 1, ftx, fty),
                side,
            )?;
            let at = |x: usize, y: usize| {
                let k = ((y - fty * t + b) * side + x - ftx * t + b) * 4;
                [fine[k], fine[k + 1], fine[k + 2], fine[k + 3]]
            };
            let (y0, y1) = (f0.max(fty * t) / 2, f1.min(fty * t + t) / 2);
            let (x0, x1) = (ftx * t / 2, ((ftx * t + t) / 2).min(w));
            for j in y0..y1 {
                for i in x0..x1 {
                    let (x, y) = (2 * i, 2 * j);
                    let p = [at(x, y), at(x + 1, y), at(x, y + 1), at(x + 1, y + 1)];
                    band[((j - r0) * w + i) * 4..][..4].copy_from_slice(&mean(&p));
                }
            }
        }
    }
    Ok(band)
}

/// The alpha-weighted mean of four RGBA8 pixels, rounded; alpha their plain mean. Four fully
/// transparent pixels give their plain mean colour.
fn mean(p: &[[u8; 4]; 4]) -> [u8; 4] {
    let alpha: u32 = p.iter().map(|q| q[3] as u32).sum();
    let mut out = [0u8; 4];
    for (c, o) in out.iter_mut().enumerate().take(3) {
        let weighted: u32 = p.iter().map(|q| q[c] as u32 * q[3] as u32).sum();
        let plain = || (p.iter().map(|q| q[c] as u32).sum::<u32>() + 2) / 4;
        *o = (weighted + alpha / 2)
            .checked_div(alpha)
            .unwrap_or_else(plain) as u8;
    }
    out[3] = ((alpha + 2) / 4) as u8;
    out
}

/// Cuts the band's `missing` tiles (band rows from `r0` of a level `w` × `h`) and writes them,
/// encoded on `threads` threads.
fn write_band(
    out: &Path,
    (l, ty): (usize, usize),
    (w, h): (usize, usize),
    r0: usize,
    band: &[u8],
    missing: &[usize],
    threads: usize,
) -> Result<()> {
    let chunk = missing.len().div_ceil(threads.max(1)).max(1);
    std::thread::scope(|scope| {
        let jobs: Vec<_> = missing
            .chunks(chunk)
            .map(|txs| {
                scope.spawn(move || -> Result<()> {
                    let mut tile = vec![0u8; SIDE * SIDE * 4];
                    for &tx in txs {
                        for j in 0..SIDE {
                            let gy = (ty * TILE + j).saturating_sub(BORDER).min(h - 1);
                            for i in 0..SIDE {
                                let gx = (tx * TILE + i).saturating_sub(BORDER).min(w - 1);
                                let src = &band[((gy - r0) * w + gx) * 4..][..4];
                                tile[(j * SIDE + i) * 4..][..4].copy_from_slice(src);
                            }
                        }
                        write_quietly(&tile_path(out, l, tx, ty), &encode_tile(&tile, SIDE)?)?;
                    }
                    Ok(())
                })
            })
            .collect();
        jobs.into_iter()
            .try_for_each(|j| j.join().expect("a tile encoder does not panic"))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_mean_weighs_colour_by_alpha() {
        let opaque = [
            [10, 20, 30, 255],
            [12, 20, 30, 255],
            [10, 22, 30, 255],
            [10, 20, 33, 255],
        ];
        assert_eq!(mean(&opaque), [11, 21, 31, 255]);
        // Black transparent pixels beside a red edge leave it red, half covering.
        let edge = [
            [200, 0, 0, 255],
            [0, 0, 0, 0],
            [200, 0, 0, 255],
            [0, 0, 0, 0],
        ];
        assert_eq!(mean(&edge), [200, 0, 0, 128]);
        assert_eq!(mean(&[[8, 8, 8, 0]; 4]), [8, 8, 8, 0]);
    }
}
