//! Cutting bands into tiles: a band is one tile row of a level and its borders, level 0's from
//! scratch, a coarser level's averaged from the tiles below; its tiles are encoded in parallel.
//!
//! Rule: a coarser band averages in the atlas's order of additions, so a pyramid's levels and the
//! atlas's agree bit for bit; nodata is filled within the band alone (`convert::build`'s rules).

use super::resume::write_quietly;
use crate::error::{Error, Result, Role};
use crate::sketch::fill;
use crate::sketch::tiles::codec::encode_tile;
use crate::sketch::tiles::{BORDER, Meta, SIDE, TILE, tile_path};
use std::path::Path;

/// Level l's rows of band `ty`, each the box average of two rows of level l−1, read tile by tile
/// from its tiles: a 2×2 box never straddles a tile (tiles start at even nodes), so level l−1's
/// rows are never held whole.
pub(super) fn coarser_band(
    out: &Path,
    meta: &Meta,
    l: usize,
    ty: usize,
) -> Result<(usize, Vec<f32>)> {
    let [w, h] = meta.levels[l];
    let [fw, _] = meta.levels[l - 1];
    let (r0, r1) = band_rows(ty, h);
    let (t, b, side) = (meta.tile, meta.border, meta.tile + 2 * meta.border);
    let (tiles_x, _) = meta.tiles(l - 1);
    let mut band = vec![0f32; w * (r1 - r0)];
    let (f0, f1) = (2 * r0, 2 * r1);
    for fty in f0 / t..=(f1 - 1) / t {
        for ftx in 0..tiles_x {
            let fine =
                crate::sketch::tiles::read::read_tile_file(&tile_path(out, l - 1, ftx, fty), side)?;
            let at = |x: usize, y: usize| fine[(y - fty * t + b) * side + x - ftx * t + b];
            let (y0, y1) = (f0.max(fty * t) / 2, f1.min(fty * t + t) / 2);
            let (x0, x1) = (ftx * t / 2, ((ftx * t + t) / 2).min(w).min(fw / 2));
            for j in y0..y1 {
                for i in x0..x1 {
                    let (x, y) = (2 * i, 2 * j);
                    // The atlas's order of additions, so both pyramids agree bit for bit.
                    band[(j - r0) * w + i] =
                        0.25 * (at(x, y) + at(x + 1, y) + at(x, y + 1) + at(x + 1, y + 1));
                }
            }
        }
    }
    Ok((r0, band))
}

/// The rows a band of tile row `ty` holds, clamped to a level of `h` rows.
pub(in crate::sketch::convert) fn band_rows(ty: usize, h: usize) -> (usize, usize) {
    let r0 = (ty * TILE).saturating_sub(BORDER);
    let r1 = ((ty + 1) * TILE + BORDER).min(h);
    (r0, r1)
}

/// Fills the band's nodata (level 0) and writes its `missing` tiles, encoded on `threads` threads.
#[allow(clippy::too_many_arguments)]
pub(super) fn write_band(
    out: &Path,
    meta: &Meta,
    l: usize,
    ty: usize,
    r0: usize,
    band: &[f32],
    w: usize,
    missing: &[usize],
    threads: usize,
) -> Result<()> {
    let rows = band.len() / w;
    let mut filled;
    let mut nodata_mask = Vec::new();
    let band = if band.iter().any(|h| !h.is_finite()) {
        nodata_mask = band.iter().map(|h| !h.is_finite()).collect();
        filled = band.to_vec();
        fill::fill_nodata(&mut filled, w, rows);
        &filled[..]
    } else {
        band
    };
    let [_, h] = meta.levels[l];
    let dir = tile_path(out, l, 0, ty);
    let dir = dir.parent().expect("a tile has a folder");
    std::fs::create_dir_all(dir).map_err(|e| Error::io(Role::OutputFolder, dir, e))?;
    let chunk = missing.len().div_ceil(threads.max(1));
    std::thread::scope(|scope| {
        let jobs: Vec<_> = missing
            .chunks(chunk.max(1))
            .map(|txs| {
                let mask = &nodata_mask;
                scope.spawn(move || -> Result<()> {
                    let mut tile = vec![0f32; SIDE * SIDE];
                    for &tx in txs {
                        let (mut lo, mut hi, mut nodata) = (f32::INFINITY, f32::NEG_INFINITY, 0u32);
                        for j in 0..SIDE {
                            let gy = (ty * TILE + j).saturating_sub(BORDER).min(h - 1);
                            for i in 0..SIDE {
                                let gx = (tx * TILE + i).saturating_sub(BORDER).min(w - 1);
                                let k = (gy - r0) * w + gx;
                                let v = band[k];
                                tile[j * SIDE + i] = v;
                                let inside = (BORDER..BORDER + TILE).contains(&i)
                                    && (BORDER..BORDER + TILE).contains(&j)
                                    && tx * TILE + i - BORDER < w
                                    && ty * TILE + j - BORDER < h;
                                if inside {
                                    lo = lo.min(v);
                                    hi = hi.max(v);
                                    nodata += mask.get(k).copied().unwrap_or(false) as u32;
                                }
                            }
                        }
                        let bytes = encode_tile(&tile, SIDE, lo, hi, nodata)?;
                        write_quietly(&tile_path(out, l, tx, ty), &bytes)?;
                    }
                    Ok(())
                })
            })
            .collect();
        jobs.into_iter()
            .try_for_each(|j| j.join().expect("a tile encoder does not panic"))
    })
}
