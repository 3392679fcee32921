//! A sketch streamed from a tile pyramid: the [`Atlas`] over a [`Pyramid`], its coarse levels in
//! memory and the finer ones left to the tile cache.
//!
//! Rule: the atlas is the pyramid's source of heights, and the pyramid knows nothing of atlases;
//! the tile readers stay below the atlas. Rejected: the reader building the atlas, which tied the
//! two modules in a circle.

use super::Atlas;
use super::grid::{LoadOptions, max_cells};
use super::pyramid::{Level, build_pyramid};
use super::tiles::{META, MetaGeoref, Pyramid};
use crate::error::{Error, Result};
use std::path::Path;

/// Bytes of the coarse levels a streamed sketch holds in memory by default (`stream.cpu_mb`).
pub const DEFAULT_CPU_BYTES: u64 = 256 << 20;
/// The side of the level-0 window a streamed sketch's relief is measured on.
const RELIEF_WINDOW: usize = 1024;

/// A pyramid as a streamed sketch: its true geometry (level 0's spacing and sizes, every level),
/// with the levels from the finest whose pyramid fits `cpu_bytes` held in memory and the finer
/// ones left to the tile cache (empty here). The relief that sets the detail's default amplitude
/// is measured on level 0's central window of at most 1024² nodes, read from its tiles: the
/// finest bands are what it measures, and they are not in memory.
pub fn streamed_atlas(dir: &Path, opts: &LoadOptions) -> Result<Atlas> {
    let pyramid = Pyramid::open(dir)?;
    let m = &pyramid.meta;
    let meta_path = dir.join(META);
    let scaled = opts.height_scale.is_some_and(|s| s != 1.0);
    if scaled || opts.height_range_m.is_some() {
        return Err(Error::value(
            if scaled {
                "sketch.height_scale"
            } else {
                "sketch.height_range_m"
            },
            format!(
                "{}: a tile pyramid's heights are metres; scale them when converting (`terrain tiles --height-scale`)",
                meta_path.display()
            ),
        ));
    }
    if opts.spacing_m.is_some_and(|s| s != m.dx_m || s != m.dy_m) {
        return Err(Error::value(
            "sketch.spacing_m",
            format!(
                "{}: a tile pyramid keeps its spacing ({} × {} m); give it when converting (`terrain tiles --spacing-m`)",
                meta_path.display(),
                m.dx_m,
                m.dy_m
            ),
        ));
    }
    let budget = opts.stream_cpu_bytes.unwrap_or(DEFAULT_CPU_BYTES);
    let bytes_from = |l: usize| -> u64 {
        m.levels[l..]
            .iter()
            .map(|[w, h]| (*w as u64) * (*h as u64) * 4)
            .sum()
    };
    let first = (0..m.levels.len())
        .find(|&l| bytes_from(l) <= budget && m.levels[l][0] * m.levels[l][1] <= max_cells())
        .unwrap_or(m.levels.len() - 1);
    let held = build_pyramid(pyramid.level(first)?);
    let mut levels: Vec<Level> = m.levels[..first]
        .iter()
        .map(|&[width, height]| Level {
            width,
            height,
            data: Vec::new(),
        })
        .collect();
    levels.extend(held);
    let relief_m = if first == 0 {
        None
    } else {
        Some(window_relief(&pyramid)?)
    };
    Ok(Atlas {
        dx: m.dx_m,
        dy: m.dy_m,
        origin: opts.origin_m.unwrap_or(glam::DVec2::ZERO),
        nodata: m.nodata as usize,
        min_m: m.min_m,
        max_m: m.max_m,
        edge_mean_m: m.edge_mean_m,
        water_m: 0.0,
        levels,
        georef: m.georef.as_ref().map(MetaGeoref::georef),
        resident_from: first,
        pyramid: Some(pyramid),
        relief_m,
    })
}

/// [`Atlas::finest_relief`] of level 0's central window.
fn window_relief(pyramid: &Pyramid) -> Result<[f64; 2]> {
    let base = pyramid.central_window(0, RELIEF_WINDOW)?;
    let probe = Atlas {
        dx: pyramid.meta.dx_m,
        dy: pyramid.meta.dy_m,
        origin: glam::DVec2::ZERO,
        nodata: 0,
        min_m: pyramid.meta.min_m,
        max_m: pyramid.meta.max_m,
        edge_mean_m: pyramid.meta.edge_mean_m,
        water_m: 0.0,
        levels: build_pyramid(base),
        georef: None,
        resident_from: 0,
        pyramid: None,
        relief_m: None,
    };
    Ok(probe.finest_relief())
}
