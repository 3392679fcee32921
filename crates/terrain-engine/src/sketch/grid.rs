//! What a sketch is before it becomes an atlas: the options a scene gives a file
//! ([`LoadOptions`]), the grid a reader makes ([`RawGrid`]), what a read found ([`Extent`]) and
//! the largest grid any reader allocates ([`max_cells`]).
//!
//! Rule: this is the bottom of the sketch's readers, depending on none of them, so that the
//! format readers, the tile pyramids and the loader that dispatches between them all stand on
//! it. Rejected: these types in the loader, which tied the tile readers and the loader in a
//! circle.

use super::georef::Georef;
use crate::error::{Error, Result};
use glam::DVec2;
use std::path::Path;

/// Larger grids are refused rather than allocated: 2^28 cells is 1 GiB of f32 before the pyramid.
pub(crate) const MAX_CELLS: usize = 1 << 28;

/// The cell limit in force: [`MAX_CELLS`] unless [`limit_cells`] lowered it.
static CELL_LIMIT: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(MAX_CELLS);

/// Lowers the largest grid any reader allocates, for the whole process: for a fuzz harness or a
/// service that must bound its memory below the default (values above `MAX_CELLS`, 2^28, are
/// clamped).
pub fn limit_cells(cells: usize) {
    CELL_LIMIT.store(cells.min(MAX_CELLS), std::sync::atomic::Ordering::Relaxed);
}

/// The largest grid a reader allocates now (cells): [`limit_cells`]'s, or 2^28; a larger file is
/// read only by `convert::build`, band by band.
pub fn max_cells() -> usize {
    CELL_LIMIT.load(std::sync::atomic::Ordering::Relaxed)
}

/// What a file does not say about itself, from the scene.
#[derive(Clone, Debug, Default)]
pub struct LoadOptions {
    /// Cell size in metres, overriding the file's (`sketch.spacing_m`).
    pub spacing_m: Option<f64>,
    /// World position of the south-west node, metres (`sketch.origin_m`; default the origin).
    pub origin_m: Option<DVec2>,
    /// Multiplies every height (`sketch.height_scale`; default 1).
    pub height_scale: Option<f64>,
    /// For 8/16-bit images: the heights that pixel values 0 and the maximum stand for.
    pub height_range_m: Option<[f64; 2]>,
    /// A streamed tile pyramid: bytes of its coarse levels to hold in memory (`stream.cpu_mb`).
    pub stream_cpu_bytes: Option<u64>,
}

/// A grid as a format reader produces it, before filling and the pyramid.
#[derive(Clone, Debug)]
pub struct RawGrid {
    /// Nodes per row.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// Node spacing along x (east), metres.
    pub dx: f64,
    /// Node spacing along y (north), metres.
    pub dy: f64,
    /// Row-major, row 0 south. Non-finite values are nodata.
    pub data: Vec<f32>,
    /// Where the nodes lie in the file's coordinate system, when the file says (mosaics need it).
    pub georef: Option<Georef>,
}

impl RawGrid {
    /// A grid placed by its georeference when it has one; without, its cells are 1 m until the
    /// scene's `sketch.spacing_m` says otherwise.
    pub fn new(width: usize, height: usize, data: Vec<f32>, georef: Option<Georef>) -> RawGrid {
        match georef {
            Some(g) => RawGrid::georeferenced(width, height, data, g),
            None => RawGrid {
                width,
                height,
                dx: 1.0,
                dy: 1.0,
                data,
                georef: None,
            },
        }
    }

    /// A grid whose spacing follows from its georeference.
    pub fn georeferenced(width: usize, height: usize, data: Vec<f32>, georef: Georef) -> RawGrid {
        let georef = georef.resolved(width, height);
        let (dx, dy) = georef.spacing_m(width, height);
        RawGrid {
            width,
            height,
            dx,
            dy,
            data,
            georef: Some(georef),
        }
    }

    /// Checks the size against the limits before a reader allocates.
    pub fn check_size(path: &Path, width: i64, height: i64) -> Result<(usize, usize)> {
        if width < 2 || height < 2 {
            RawGrid::check_size_unlimited(path, width, height)?;
        }
        let cells = (width as u128) * (height as u128);
        let limit = max_cells();
        if cells > limit as u128 {
            return Err(Error::sketch(
                path,
                format!("grid is {width}×{height}, more than the {limit} cells supported"),
            ));
        }
        Ok((width as usize, height as usize))
    }

    /// Checks that a grid has at least 2×2 nodes and at most 2^31 along a side, whatever the cell
    /// limit: for grids that are streamed rather than allocated (`terrain tiles`).
    pub fn check_size_unlimited(path: &Path, width: i64, height: i64) -> Result<(usize, usize)> {
        if width < 2 || height < 2 {
            return Err(Error::sketch(
                path,
                format!("grid is {width}×{height}; a sketch needs at least 2×2 cells"),
            ));
        }
        if width.max(height) > i32::MAX as i64 {
            return Err(Error::sketch(
                path,
                format!("grid is {width}×{height}; a side longer than 2^31 nodes is no sketch's"),
            ));
        }
        Ok((width as usize, height as usize))
    }
}

/// What a read found of a sketch, for [`warnings`](super::warnings): its nodes, their spacing in metres (after
/// `sketch.spacing_m`), its height range (after `sketch.height_scale`) and whether its file
/// placed it. [`Atlas::extent`](super::Atlas::extent) gives it for a sketch in memory; a tile pyramid's `pyramid.toml`
/// holds the same figures.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Extent {
    /// Nodes along x (east).
    pub width: usize,
    /// Nodes along y (north).
    pub height: usize,
    /// Node spacing along x, metres.
    pub dx: f64,
    /// Node spacing along y, metres.
    pub dy: f64,
    /// The lowest height, metres (0 with `max_m` where the heights were not read).
    pub min_m: f64,
    /// The highest height, metres.
    pub max_m: f64,
    /// Whether the file (or its world file) gave the cells' size and place.
    pub georeferenced: bool,
}
