//! The sketch atlas: the whole height map in main memory, in metres, with a mip pyramid.
//!
//! Rules:
//! - Row 0 is the southern edge; texel (i, j) is the grid node at `origin + (i·dx, j·dy)`.
//! - Every height is finite and within ±`MAX_HEIGHT_M` (1000 km): nodata, NaN and heights
//!   beyond it are filled from valid neighbours by the loader (`fill`) and counted in
//!   [`Atlas::nodata`], never passed on.
//! - Level l of the pyramid is a 2×2 box average of level l−1 (sizes halved rounding down, as
//!   texture mips are), so a level-l texel's centre lies at level-0 coordinate `2^l·i + (2^l − 1)/2`.
//!   Sampling between levels is trilinear on the CPU, bicubic per level on the GPU.
//!
//! Rejected alternative: resampling the sketch map straight from level 0 with a wide filter. At
//! 50 km up a 128² sketch map spans thousands of atlas texels each; a per-frame wide filter would cost
//! milliseconds, the pyramid costs one build at load time (a third more memory).

mod asc;
// The converters write zstd tiles and read their sources in place (Unix positional reads).
#[cfg(feature = "zstd")]
pub mod convert;
pub(crate) mod cubic;
pub(crate) mod fill;
pub(crate) mod georef;
mod geotiff;
mod grid;
mod hgt;
mod load;
pub(crate) mod mosaic;
mod png;
mod pyramid;
mod streamed;
pub(crate) mod synthetic;
pub mod tiles;
mod xyz;

pub use georef::{Georef, US_SURVEY_FOOT_M, Units};
pub(crate) use geotiff::{gdal_nodata, georef as tiff_georef, refuse_compression};
pub use load::{
    Extent, GridHeader, LoadOptions, RawGrid, limit_cells, max_cells, parse_grid, read_grid,
    read_header, warnings,
};
pub use mosaic::{is_glob, list_glob};
pub use png::parse_world_file;
pub use pyramid::Level;
pub(crate) use pyramid::build_pyramid;

use crate::error::Result;
use glam::DVec2;

/// The Earth's mean radius, metres, for converting geographic cells to metres at their mid
/// latitude and as a planet's default radius: 6371 km, the IUGG mean (6,371,008.8 m) rounded to
/// a value f32 holds exactly, as the planet's uniforms hold it (1.4 ppm apart).
pub const EARTH_RADIUS_M: f64 = 6_371_000.0;
/// Heights beyond ±1000 km (after `sketch.height_scale`) are no terrain's (the Earth's relief
/// spans 20 km), and squared or summed in f32 downstream they would overflow. Up to 1 % of a
/// sketch's cells beyond it are taken as nodata and filled (a Float64 file damaged into 1e180 m, a
/// float DEM whose −3.4e38 nodata its header does not declare; GDAL reads them as values); more
/// are heights in another unit, and the sketch is refused with a hint to set the scale.
pub(crate) const MAX_HEIGHT_M: f64 = 1.0e6;

/// The side of the window a level not in memory is measured on for
/// [`Atlas::level_curvature`]: 512², whose stride (2) visits as many texels as on a level held
/// whole.
pub(crate) const CURVATURE_WINDOW: usize = 512;

/// The sketch in memory: its heights in metres on a regular grid, with the mip pyramid the CPU
/// stage and the GPU sample (see the module's rules for its layout).
#[derive(Clone, Debug)]
pub struct Atlas {
    /// Grid spacing in metres along x (east).
    pub dx: f64,
    /// Grid spacing in metres along y (north).
    pub dy: f64,
    /// World position of the south-west node.
    pub origin: DVec2,
    /// Cells that held nodata or NaN in the file and were filled.
    pub nodata: usize,
    /// The lowest height of level 0, metres (after `sketch.height_scale`).
    pub min_m: f32,
    /// The highest height of level 0, metres (after `sketch.height_scale`).
    pub max_m: f32,
    /// The mean height of the edge nodes: where a plain beyond the sketch lies.
    pub edge_mean_m: f32,
    /// The water's surface: ground below it lies under flat water (`sketch.water_level_m`).
    pub water_m: f32,
    /// `levels[0]` is the atlas itself.
    pub levels: Vec<Level>,
    /// Where the file put its south-west node, in the file's coordinate system (not the world's:
    /// the world is `origin`-based metres), when the file says.
    pub georef: Option<Georef>,
    /// Levels finer than this are not held in memory (their `data` is empty): a tile pyramid
    /// streamed to the GPU through the tile cache keeps only its coarse levels here, and the CPU
    /// reads the finest of those. 0 for a sketch read whole.
    pub resident_from: usize,
    /// The tile pyramid the sketch streams from, when it is one.
    pub pyramid: Option<crate::sketch::tiles::Pyramid>,
    /// [`Atlas::finest_relief`] measured when the finest levels were read, for a streamed sketch.
    pub relief_m: Option<[f64; 2]>,
}

impl Atlas {
    /// The share of the sketch's edge nodes (on the finest level held in memory) below the
    /// water's surface: above one half, the world beyond the sketch is the sea.
    pub fn edge_under_water(&self) -> f64 {
        let level = &self.levels[self.resident_from.min(self.levels.len() - 1)];
        let (under, n) = level.edge().fold((0usize, 0usize), |(u, n), z| {
            (u + usize::from(z < self.water_m), n + 1)
        });
        under as f64 / n.max(1) as f64
    }

    /// Nodes per row of level 0 (west to east).
    pub fn width(&self) -> usize {
        self.levels[0].width
    }

    /// The sketch's relief in its two finest bands, metres: the spread of what level 0 adds to
    /// level 1 of the pyramid (wavelengths of 2–4 cells), and of what level 1 adds to level 2
    /// (4–8 cells). The spread is robust, 1.4826 × the median absolute value (the standard
    /// deviation where the band is normal), so a few cliffs or filled voids do not stand for the
    /// whole sketch: on the bundled DEM the RMS is within 5 % of
    /// it, but on the synthetic cliff (a plain with one step) the RMS is 14 m where the plain has
    /// none. At most about 256² texels are
    /// visited, so a sketch of any size costs the same.
    pub fn finest_relief(&self) -> [f64; 2] {
        if let Some(r) = self.relief_m {
            return r;
        }
        let band = |l: usize| -> f64 {
            if l + 1 >= self.levels.len() {
                return 0.0;
            }
            let level = &self.levels[l];
            let stride = (level.width.max(level.height) / 256).max(1);
            let s = (1u64 << l) as f64;
            let mut values = Vec::new();
            for j in (0..level.height).step_by(stride) {
                for i in (0..level.width).step_by(stride) {
                    // Level l's texel (i, j) in level-0 texel units, where sample_texel works.
                    let (u, v) = ((i as f64 + 0.5) * s - 0.5, (j as f64 + 0.5) * s - 0.5);
                    let fine = level.data[j * level.width + i] as f64;
                    let coarse = self.sample_texel(u, v, (l + 1) as f64) as f64;
                    values.push((fine - coarse).abs());
                }
            }
            if values.is_empty() {
                return 0.0;
            }
            let mid = values.len() / 2;
            let (_, median, _) = values.select_nth_unstable_by(mid, f64::total_cmp);
            1.4826 * *median
        };
        [band(0), band(1)]
    }
    /// The mean curvature of each pyramid level, 1/m: the largest of its second differences
    /// (|h_xx|, |h_yy|, |h_xy|, the heights raised to `water_m`) at its own spacing, as the
    /// importance's geometric-error term takes them from the sketch map, averaged over the level.
    /// A level not held in memory (a streamed pyramid's finest) is measured on its central
    /// window of at most 512² texels, read from its tiles (NaN where they cannot
    /// be read): counting only the levels in memory gave a sketch larger than memory, seen from
    /// high up, less of the error term than the same sketch held whole (jacksboro-high over its
    /// pyramid with `stream.cpu_mb = 0.1`, levels 0 and 1 on disk: warped needed 0.963×
    /// GeoMipMap's triangles, 0.916× with the windows, 0.921× with the pyramid all in memory;
    /// `terrain compare S --out-dir D --modes warped,geomipmap --repeat 1 --path-frames 0`,
    /// `summary.md`'s geometric mean). Every k-th texel of a
    /// level is visited, k its larger side ÷ 256 rounded down (fewer than 512² texels), so a
    /// sketch of any size costs about the same.
    ///
    /// Natural terrain is rough at every scale: on the bundled DEM the mean doubles with each
    /// finer level (0.56·10⁻³ at 320 m, 1.1·10⁻³ at 160 m, 2.0·10⁻³ at 80 m), so a sketch map
    /// coarser than the atlas sees a fraction of the curvature its samples meet.
    pub fn level_curvature(&self, water_m: f32) -> Vec<f64> {
        self.levels
            .iter()
            .enumerate()
            .map(|(l, level)| {
                let scale = (1u64 << l) as f64;
                let (dx, dy) = (self.dx * scale, self.dy * scale);
                match self.tiled_window(l) {
                    Some(window) => window.mean_curvature(dx, dy, water_m),
                    None => level.mean_curvature(dx, dy, water_m),
                }
            })
            .collect()
    }

    /// Level `l`'s central window of at most [`CURVATURE_WINDOW`]² texels from the tiles, where
    /// the level is not in memory but a pyramid holds it; None otherwise or where a tile cannot
    /// be read.
    fn tiled_window(&self, l: usize) -> Option<Level> {
        let pyramid = self
            .pyramid
            .as_ref()
            .filter(|_| self.levels[l].data.is_empty())?;
        pyramid.central_window(l, CURVATURE_WINDOW).ok()
    }

    /// Rows of level 0 (south to north).
    pub fn height(&self) -> usize {
        self.levels[0].height
    }
    /// Bytes of heights in the whole pyramid held in memory (what the GPU holds of a whole atlas).
    pub fn bytes(&self) -> u64 {
        self.levels.iter().map(|l| l.data.len() as u64 * 4).sum()
    }

    /// `d_atlas`: the smaller grid spacing, the scale of octave 1.
    pub fn d_atlas(&self) -> f64 {
        self.dx.min(self.dy)
    }
    /// World position of the north-east node.
    pub fn max_corner(&self) -> DVec2 {
        self.origin
            + DVec2::new(
                (self.width() - 1) as f64 * self.dx,
                (self.height() - 1) as f64 * self.dy,
            )
    }

    /// Height at level-0 texel (u, v), bilinear on level 0, clamped to the edge: from memory, or
    /// for a streamed sketch from the tile that holds it. A point query, for the ground under a
    /// camera: a check on the coarse levels held in memory would let a camera sink under a peak
    /// they smooth away. Errors only where a tile cannot be read.
    pub fn ground_texel(&self, u: f64, v: f64) -> Result<f32> {
        match &self.pyramid {
            Some(p) if self.resident_from > 0 => p.bilinear(0, u, v),
            _ => Ok(self.levels[0].bilinear(u, v)),
        }
    }

    /// Height at a position given in level-0 texel units, at mip level `lod` (fractional ≥ 0 is
    /// trilinear; below 0 is level 0), clamped to the edge.
    pub fn sample_texel(&self, u: f64, v: f64, lod: f64) -> f32 {
        let lod = lod.clamp(self.resident_from as f64, (self.levels.len() - 1) as f64);
        let l0 = lod.floor() as usize;
        let t = (lod - l0 as f64) as f32;
        let a = self.levels[l0].bilinear_at_level(u, v, l0);
        if t == 0.0 || l0 + 1 >= self.levels.len() {
            return a;
        }
        let b = self.levels[l0 + 1].bilinear_at_level(u, v, l0 + 1);
        a + (b - a) * t
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ramp(w: usize, h: usize) -> Atlas {
        let data = (0..w * h).map(|k| (k % w) as f32).collect();
        let raw = RawGrid {
            width: w,
            height: h,
            dx: 10.0,
            dy: 10.0,
            data,
            georef: None,
        };
        Atlas::from_raw(raw, &LoadOptions::default()).unwrap()
    }

    /// A paraboloid h = a·x² + b·y² has second differences 2a and 2b at every level (a box
    /// filter adds a constant to a quadratic), so each level's mean is the larger, 2b, in 1/m;
    /// a plane has none; water above the ground flattens it; a level not in memory is NaN.
    #[test]
    fn level_curvature_is_the_mean_second_difference_of_each_level() {
        let (w, h, d) = (300, 260, 20.0);
        let (a, b) = (1e-4f64, 3e-4f64);
        let grid = |f: &dyn Fn(f64, f64) -> f64| {
            let data = (0..w * h)
                .map(|k| f((k % w) as f64 * d, (k / w) as f64 * d) as f32)
                .collect();
            let raw = RawGrid {
                width: w,
                height: h,
                dx: d,
                dy: d,
                data,
                georef: None,
            };
            Atlas::from_raw(raw, &LoadOptions::default()).unwrap()
        };
        let bowl = grid(&|x, y| a * (x - 3000.0).powi(2) + b * (y - 2600.0).powi(2));
        let c = bowl.level_curvature(f32::NEG_INFINITY);
        assert_eq!(c.len(), bowl.levels.len());
        for (l, &v) in c.iter().enumerate().take(c.len() - 1) {
            assert!((v - 2.0 * b).abs() < 0.02 * 2.0 * b, "level {l}: {v}");
        }
        let plane = grid(&|x, y| 0.3 * x - 0.1 * y + 50.0);
        assert!(plane.level_curvature(f32::NEG_INFINITY)[0].abs() < 1e-7);
        assert!(bowl.level_curvature(1e9)[0] == 0.0, "under water");
        let mut streamed = bowl.clone();
        streamed.levels[0].data.clear();
        let c = streamed.level_curvature(f32::NEG_INFINITY);
        assert!(c[0].is_nan() && (c[1] - 2.0 * b).abs() < 0.02 * 2.0 * b);
    }

    #[test]
    fn pyramid_keeps_a_linear_ramp_in_place_at_every_level() {
        // A ramp h = u must sample as u at every level, or the level offsets are wrong.
        let a = ramp(64, 64);
        for lod in [0.0, 1.0, 2.5, 4.0] {
            let h = a.sample_texel(20.0, 30.0, lod);
            assert!((h - 20.0).abs() < 1e-4, "lod {lod}: {h}");
        }
    }
}
