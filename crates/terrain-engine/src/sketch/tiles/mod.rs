//! Tile pyramids: a sketch on disk as fixed-size tiles of every mip level, for sketches larger than
//! memory (`terrain tiles SRC --out-dir DIR` writes one; a scene's `sketch.path = "DIR"` reads it).
//! An image larger than memory is cut the same way ([`image`]; `surface.image = "DIR"`).
//!
//! Rules:
//! - `pyramid.toml` says what the pyramid holds (`kind`, [`Kind`]; one without it holds
//!   heights): a pyramid given in the other role is refused in one line naming the role, before
//!   any tile is read.
//! - Level 0 is the sketch's grid in metres, nodata filled; level l is the 2×2 box average of level
//!   l−1 with sizes halved rounding down, down to the last level whose sides are both ≥ 2: the
//!   pyramid of [`crate::sketch::Atlas`], computed in the same f32 order, so a pyramid of a sketch
//!   that also fits in memory holds the same numbers bit for bit (a test checks it).
//! - A tile holds [`TILE`]² nodes of its level plus a border of [`BORDER`] nodes on every side
//!   (bicubic sampling at a tile's edge needs two), clamped to the level's edge like a texture
//!   sampler. Tile (tx, ty) of level l covers nodes `tx·TILE .. (tx+1)·TILE` east and `ty·TILE ..`
//!   north, row 0 south as everywhere. Tiles past the level's east or north edge repeat its last
//!   node.
//! - A tile file is a 24-byte header (magic, side, interior min and max, interior nodata count,
//!   payload length) and a zstd frame with its checksum. The heights are stored as the four byte
//!   planes of their f32 bits, each plane differenced along the row: TIFF's floating-point
//!   predictor (3), which zstd then finds runs in.
//! - Every file is written to a temporary name and renamed into place, so a killed build leaves
//!   whole tiles or none; `pyramid.toml` is written last and marks the pyramid complete.
//!
//! Rejected alternatives:
//! - One file per level (a GeoTIFF pyramid): a tile read would need a seek table and locks across
//!   loader threads; separate files are what the loaders open, and what a resume checks.
//! - Plain zstd on the f32 bytes: on the bundled Jacksboro DEM's 128² windows it compresses 2.64×,
//!   the predicted byte planes 4.12× (`cargo test --release --lib tiles -- --nocapture`).

pub(crate) mod blocks;
pub(crate) mod cache;
pub(crate) mod codec;
pub mod image;
pub(crate) mod read;

pub use blocks::{measure as measure_blocks, set_keep_figures};
pub use cache::StreamStats;
pub use image::ImagePyramid;
pub use read::{Pyramid, raw_grid_within};

use crate::error::{Error, Result, Role};

use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Interior nodes per tile side.
pub const TILE: usize = 256;
/// Border nodes on each side of a tile.
pub const BORDER: usize = 2;
/// Stored nodes per tile side.
pub const SIDE: usize = TILE + 2 * BORDER;
/// The name that makes a folder a pyramid, written last.
pub const META: &str = "pyramid.toml";
/// `format` in `pyramid.toml`: bumped when the layout changes.
pub(crate) const FORMAT: &str = "terrain-tiles 1";

/// What a pyramid holds: `kind` in `pyramid.toml`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Kind {
    /// A height map in metres (`sketch.path`); a `pyramid.toml` without `kind` holds heights.
    #[default]
    Heights,
    /// RGBA8 imagery ([`image`], `surface.image`).
    Image,
}

impl Kind {
    /// What the kind is, in a message's words.
    pub(crate) fn noun(self) -> &'static str {
        match self {
            Kind::Heights => "heights",
            Kind::Image => "an image",
        }
    }
}

/// The `kind` of the pyramid whose `pyramid.toml` is at `path`, read before the rest of the file
/// so that a pyramid of the other kind is named as such rather than as unknown keys. `role` is
/// what the caller takes the folder for.
pub(crate) fn kind_of(path: &Path, role: Role) -> Result<Kind> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(role, path, e))?;
    let table: toml::Table =
        toml::from_str(&text).map_err(|e| Error::decode(role, path, "a pyramid.toml", e))?;
    match table.get("kind") {
        None => Ok(Kind::Heights),
        Some(v) => Kind::deserialize(v.clone()).map_err(|_| {
            Error::file(
                role,
                path,
                format!("kind = {v} is not a kind this terrain reads (heights, image)"),
            )
        }),
    }
}

/// `pyramid.toml`: what the pyramid holds, in the sketch's terms.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Meta {
    /// The layout's name and version, `terrain-tiles 1`; another is refused.
    pub format: String,
    /// [`Kind::Heights`]: written by every build, absent from pyramids made before it was.
    #[serde(default)]
    pub kind: Kind,
    /// What it was converted from, for `terrain info`.
    pub source: String,
    /// Level 0's nodes per row (west to east).
    pub width: usize,
    /// Level 0's rows (south to north).
    pub height: usize,
    /// Node spacing east, metres.
    pub dx_m: f64,
    /// Node spacing north, metres.
    pub dy_m: f64,
    /// Interior nodes per tile side ([`TILE`]).
    pub tile: usize,
    /// Border nodes on each side of a tile ([`BORDER`]).
    pub border: usize,
    /// Each level's nodes, level 0 first.
    pub levels: Vec<[usize; 2]>,
    /// The lowest height of level 0, metres.
    pub min_m: f32,
    /// The highest height of level 0, metres.
    pub max_m: f32,
    /// The mean of level 0's edge nodes (where a plain beyond the sketch lies).
    pub edge_mean_m: f32,
    /// Level-0 nodes that held nodata and were filled.
    pub nodata: u64,
    /// The south-west node in the source's coordinate system, when it had one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub georef: Option<MetaGeoref>,
}

/// A [`crate::sketch::Georef`] as `pyramid.toml` spells it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MetaGeoref {
    /// `degrees`, or metres per unit for a projected system.
    pub units: String,
    /// The south-west node's x (easting or longitude), in `units`.
    pub west: f64,
    /// The south-west node's y (northing or latitude), in `units`.
    pub south: f64,
    /// Node spacing along x (east), in `units`.
    pub cell_x: f64,
    /// Node spacing along y (north), in `units`.
    pub cell_y: f64,
    /// The coordinate system's EPSG code, where the source named one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub epsg: Option<u16>,
}

impl MetaGeoref {
    /// The georeference this spells: the inverse of the builder's `meta_georef`.
    pub fn georef(&self) -> crate::sketch::georef::Georef {
        use crate::sketch::georef::{Georef, Units};
        Georef {
            west: self.west,
            south: self.south,
            cell_x: self.cell_x,
            cell_y: self.cell_y,
            units: match self.units.as_str() {
                "degrees" => Units::Degrees,
                "unknown" => Units::Unknown,
                s => s.parse().map_or(Units::Unknown, Units::Linear),
            },
            epsg: self.epsg,
        }
    }
}

impl Meta {
    /// What the conversion found of its source, for `sketch::warnings`.
    pub fn extent(&self) -> crate::sketch::grid::Extent {
        crate::sketch::grid::Extent {
            width: self.width,
            height: self.height,
            dx: self.dx_m,
            dy: self.dy_m,
            min_m: self.min_m as f64,
            max_m: self.max_m as f64,
            georeferenced: self.georef.is_some(),
        }
    }

    /// Tiles of level `l` along x and y.
    pub fn tiles(&self, l: usize) -> (usize, usize) {
        tiles_of(self.levels[l], self.tile)
    }
    /// Tiles in the whole pyramid.
    pub fn tile_count(&self) -> usize {
        tile_count(&self.levels, self.tile)
    }
}

/// Tiles of `tile`² nodes along x and y over a level of `[w, h]` nodes (heights or pixels).
fn tiles_of([w, h]: [usize; 2], tile: usize) -> (usize, usize) {
    (w.div_ceil(tile), h.div_ceil(tile))
}

/// Tiles over every level of a pyramid.
fn tile_count(levels: &[[usize; 2]], tile: usize) -> usize {
    levels
        .iter()
        .map(|&l| {
            let (x, y) = tiles_of(l, tile);
            x * y
        })
        .sum()
}

/// Node counts of every level of a `width` × `height` grid (the atlas's rule).
pub(crate) fn level_sizes(width: usize, height: usize) -> Vec<[usize; 2]> {
    let mut levels = vec![[width, height]];
    loop {
        let [w, h] = *levels.last().expect("a base level");
        let (w, h) = (w / 2, h / 2);
        if w.min(h) < 2 {
            return levels;
        }
        levels.push([w, h]);
    }
}

/// The file of tile (tx, ty) of level `l` under the pyramid folder `dir`.
pub(crate) fn tile_path(dir: &Path, l: usize, tx: usize, ty: usize) -> PathBuf {
    dir.join(format!("L{l}"))
        .join(ty.to_string())
        .join(format!("{tx}.tile"))
}

/// Whether `path` is a pyramid folder (it holds [`META`]).
pub fn is_pyramid(path: &Path) -> bool {
    path.is_dir() && path.join(META).is_file()
}
