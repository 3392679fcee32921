//! Image pyramids: a user's imagery on disk as RGBA8 tiles of every mip level, for images larger
//! than memory (`terrain tiles ortho.tif --out-dir DIR` writes one; `surface.image = "DIR"`
//! drapes it, reading one level's tiles under the sketch).
//!
//! Rules:
//! - The layout is the height pyramid's ([`crate::sketch::tiles`]): level 0 is the image's pixels, row 0
//!   south; level l halves level l−1 rounding down, down to the last level whose sides are both
//!   ≥ 2; tiles of [`TILE`](super::TILE)² pixels with a border of [`BORDER`](super::BORDER) on
//!   every side, clamped to the
//!   level's edge; `L<l>/<ty>/<tx>.tile`; every file written under a temporary name and renamed;
//!   `pyramid.toml` written last, with `kind = "image"`.
//! - A coarser pixel is the alpha-weighted mean of its 2×2 pixels below (alpha their plain
//!   mean): where the image stops covering, the transparent pixels' colours do not bleed into
//!   the edge's. Level l's pixel (i, j) covers level 0's `2^l·i ..` east and `2^l·j ..` north, so
//!   its centre lies `(2^l − 1)/2` level-0 pixels north-east of theirs ([`ImagePyramid::georef`]);
//!   an odd side drops its last pixel, as the heights' levels do.
//! - A tile file is a 12-byte header (magic `TTI1`, side, payload length) and a zstd frame with
//!   its checksum of the RGBA8 pixels, each byte less the same channel's byte west of it: PNG's
//!   Sub filter.
//! - An image pyramid keeps the source's georeference; an image without one is refused when
//!   converted, as it could never be placed.
//!
//! Rejected alternatives: plain zstd on the RGBA bytes, and the heights' layout of one plane per
//! channel, each differenced: on textured imagery both compress less than the Sub filter
//! (figures in docs/decisions.md, “Image pyramids”).

use super::codec::{compress, decompress_tile};
use super::{FORMAT, Kind, META, MetaGeoref, level_sizes, tile_path};
use crate::error::{Error, Result, Role};
use crate::sketch::georef::Georef;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

const MAGIC: &[u8; 4] = b"TTI1";
/// Bytes before the zstd frame.
pub(crate) const HEADER_BYTES: usize = 12;

/// `pyramid.toml` of an image pyramid.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ImageMeta {
    /// The layout's name and version, `terrain-tiles 1`; another is refused.
    pub format: String,
    /// Always [`Kind::Image`].
    pub kind: Kind,
    /// What it was converted from.
    pub source: String,
    /// What the source's pixels held: `grey`, `grey+alpha`, `rgb` or `rgba`.
    pub samples: String,
    /// Level 0's pixels per row (west to east).
    pub width: usize,
    /// Level 0's rows (south to north).
    pub height: usize,
    /// Interior pixels per tile side ([`TILE`](super::TILE)).
    pub tile: usize,
    /// Border pixels on each side of a tile ([`BORDER`](super::BORDER)).
    pub border: usize,
    /// Each level's pixels, level 0 first.
    pub levels: Vec<[usize; 2]>,
    /// Level 0's south-west pixel's centre and pixel size, in the source's coordinate system.
    pub georef: MetaGeoref,
}

impl ImageMeta {
    /// Tiles of level `l` along x and y.
    pub fn tiles(&self, l: usize) -> (usize, usize) {
        super::tiles_of(self.levels[l], self.tile)
    }
    /// Tiles in the whole pyramid.
    pub fn tile_count(&self) -> usize {
        super::tile_count(&self.levels, self.tile)
    }
}

/// An opened image pyramid folder.
#[derive(Clone, Debug)]
pub struct ImagePyramid {
    /// The folder, holding `pyramid.toml` and the tiles.
    pub dir: PathBuf,
    /// Its `pyramid.toml`.
    pub meta: ImageMeta,
}

impl ImagePyramid {
    /// Reads and checks `DIR/pyramid.toml`; a height pyramid is refused, naming what it holds.
    pub fn open(dir: &Path) -> Result<ImagePyramid> {
        let path = dir.join(META);
        let bad = |why: String| Error::file(Role::Image, &path, why);
        let kind = super::kind_of(&path, Role::Image)?;
        if kind != Kind::Image {
            return Err(bad(format!(
                "the pyramid holds {} (`terrain tiles` of a height map), not an image: give it \
                 as sketch.path; an image's pyramid says kind = \"image\"",
                kind.noun()
            )));
        }
        let text = std::fs::read_to_string(&path).map_err(|e| Error::io(Role::Image, &path, e))?;
        let meta: ImageMeta = toml::from_str(&text)
            .map_err(|e| Error::decode(Role::Image, &path, "a pyramid.toml", e))?;
        if meta.format != FORMAT {
            return Err(bad(format!(
                "format is {:?}; this terrain reads {FORMAT:?}: convert the image again",
                meta.format
            )));
        }
        if meta.width < 2 || meta.height < 2 || meta.levels != level_sizes(meta.width, meta.height)
        {
            return Err(bad(format!(
                "levels do not follow from {}×{} pixels",
                meta.width, meta.height
            )));
        }
        if !(16..=4096).contains(&meta.tile) || !meta.tile.is_multiple_of(2) || meta.border > 8 {
            return Err(bad(format!(
                "tile {} with border {} is not a layout this terrain writes",
                meta.tile, meta.border
            )));
        }
        let g = &meta.georef;
        let finite = [g.west, g.south, g.cell_x, g.cell_y]
            .iter()
            .all(|v| v.is_finite());
        if !(finite && g.cell_x > 0.0 && g.cell_y > 0.0) {
            return Err(bad("georef is not finite with positive pixels".into()));
        }
        Ok(ImagePyramid {
            dir: dir.to_path_buf(),
            meta,
        })
    }

    /// Stored pixels per tile side.
    pub fn side(&self) -> usize {
        self.meta.tile + 2 * self.meta.border
    }

    /// Where level `l`'s pixel centres lie: level 0's georeference with pixels 2^l as large,
    /// its south-west centre `(2^l − 1)/2` level-0 pixels north-east.
    pub fn georef(&self, l: usize) -> Georef {
        let g = self.meta.georef.georef();
        let scale = (1u64 << l) as f64;
        let shift = (scale - 1.0) * 0.5;
        Georef {
            west: g.west + shift * g.cell_x,
            south: g.south + shift * g.cell_y,
            cell_x: g.cell_x * scale,
            cell_y: g.cell_y * scale,
            ..g
        }
    }

    /// Tile (tx, ty) of level `l`, border included: RGBA8, row-major, row 0 south.
    pub fn tile(&self, l: usize, tx: usize, ty: usize) -> Result<Vec<u8>> {
        read_tile_file(&tile_path(&self.dir, l, tx, ty), self.side())
    }

    /// Pixels `x0 .. x0 + w` × `y0 .. y0 + h` of level `l` (inside the level; rows from the
    /// south), RGBA8 row-major, from the interiors of the tiles under them alone.
    pub fn window(&self, l: usize, x0: usize, y0: usize, w: usize, h: usize) -> Result<Vec<u8>> {
        let (t, b, side) = (self.meta.tile, self.meta.border, self.side());
        let [lw, lh] = self.meta.levels[l];
        assert!(w > 0 && h > 0 && x0 + w <= lw && y0 + h <= lh);
        let mut out = vec![0u8; w * h * 4];
        for ty in y0 / t..=(y0 + h - 1) / t {
            for tx in x0 / t..=(x0 + w - 1) / t {
                let tile = self.tile(l, tx, ty)?;
                let (c0, c1) = (x0.max(tx * t), (x0 + w).min(tx * t + t));
                for r in y0.max(ty * t)..(y0 + h).min(ty * t + t) {
                    let src = &tile[((r - ty * t + b) * side + b + c0 - tx * t) * 4..];
                    out[((r - y0) * w + c0 - x0) * 4..][..(c1 - c0) * 4]
                        .copy_from_slice(&src[..(c1 - c0) * 4]);
                }
            }
        }
        Ok(out)
    }
}

/// Encodes `side`² RGBA8 pixels (row-major, row 0 south).
pub(crate) fn encode_tile(rgba: &[u8], side: usize) -> Result<Vec<u8>> {
    debug_assert_eq!(rgba.len(), 4 * side * side);
    let frame = compress(&predicted(rgba, side))?;
    let mut out = Vec::with_capacity(HEADER_BYTES + frame.len());
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&(side as u32).to_le_bytes());
    out.extend_from_slice(&(frame.len() as u32).to_le_bytes());
    out.extend_from_slice(&frame);
    Ok(out)
}

/// Each byte less the same channel's byte of the pixel west of it (wrapping), row by row: PNG's
/// Sub filter.
fn predicted(rgba: &[u8], side: usize) -> Vec<u8> {
    let mut out = rgba.to_vec();
    for row in out.chunks_exact_mut(side * 4) {
        // East to west, so every difference reads the original.
        for i in (4..side * 4).rev() {
            row[i] = row[i].wrapping_sub(row[i - 4]);
        }
    }
    out
}

/// A tile's side and payload length from its first [`HEADER_BYTES`].
fn parse_header(path: &Path, bytes: &[u8]) -> Result<(usize, usize)> {
    let bad = |why: String| Error::file(Role::Image, path, format!("tile {why}"));
    if bytes.len() < HEADER_BYTES {
        return Err(bad(format!(
            "is truncated: {} bytes, its header alone is {HEADER_BYTES}",
            bytes.len()
        )));
    }
    if &bytes[0..4] != MAGIC {
        return Err(bad(
            "does not start with TTI1: not an image tile of `terrain tiles`".into(),
        ));
    }
    let u32_at = |k: usize| u32::from_le_bytes(bytes[k..k + 4].try_into().expect("4 bytes"));
    let side = u32_at(4) as usize;
    if !(2..=4096).contains(&side) {
        return Err(bad(format!("claims a side of {side} pixels")));
    }
    Ok((side, u32_at(8) as usize))
}

/// Decodes a whole tile file into `side`² RGBA8 pixels.
pub(crate) fn decode_tile(path: &Path, bytes: &[u8]) -> Result<(usize, Vec<u8>)> {
    let (side, payload) = parse_header(path, bytes)?;
    let bad = |why: String| Error::file(Role::Image, path, format!("tile {why}"));
    let frame = &bytes[HEADER_BYTES..];
    if frame.len() != payload {
        return Err(bad(format!(
            "is truncated or padded: {} bytes of pixels where its header says {payload}",
            frame.len()
        )));
    }
    let mut rgba = decompress_tile(frame, side, "pixels")?.map_err(bad)?;
    for row in rgba.chunks_exact_mut(side * 4) {
        for i in 4..side * 4 {
            row[i] = row[i].wrapping_add(row[i - 4]);
        }
    }
    Ok((side, rgba))
}

/// A tile file's pixels, checked to hold `side`² of them.
pub(crate) fn read_tile_file(path: &Path, side: usize) -> Result<Vec<u8>> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(Role::Image, path, e))?;
    let (s, rgba) = decode_tile(path, &bytes)?;
    if s != side {
        return Err(Error::file(
            Role::Image,
            path,
            format!("tile is {s}² pixels; its pyramid's are {side}²"),
        ));
    }
    Ok(rgba)
}

/// Whether an image tile file is there and as long as its header says.
pub(crate) fn tile_is_whole(path: &Path) -> bool {
    use std::io::Read;
    let Ok(mut file) = std::fs::File::open(path) else {
        return false;
    };
    let mut head = [0u8; HEADER_BYTES];
    if file.read_exact(&mut head).is_err() {
        return false;
    }
    let len = file.metadata().map_or(0, |m| m.len());
    parse_header(path, &head).is_ok_and(|(_, payload)| len == (HEADER_BYTES + payload) as u64)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A smooth RGBA tile with a transparent corner.
    fn tile(side: usize) -> Vec<u8> {
        (0..side * side)
            .flat_map(|k| {
                let (x, y) = (k % side, k / side);
                [
                    (x * 255 / side) as u8,
                    (y * 255 / side) as u8,
                    ((x + y) % 256) as u8,
                    if x + y < 8 { 0 } else { 255 },
                ]
            })
            .collect()
    }

    #[test]
    fn an_image_tile_round_trips_and_damage_is_one_line() {
        let rgba = tile(260);
        let bytes = encode_tile(&rgba, 260).unwrap();
        let (side, back) = decode_tile(Path::new("t"), &bytes).unwrap();
        assert_eq!((side, &back), (260, &rgba));
        let cut = decode_tile(Path::new("L0/0/0.tile"), &bytes[..bytes.len() - 5]).unwrap_err();
        assert!(cut.to_string().contains("truncated"), "{cut}");
        let mut flipped = bytes.clone();
        let last = flipped.len() - 8;
        flipped[last] ^= 0x40;
        let err = decode_tile(Path::new("L0/0/0.tile"), &flipped).unwrap_err();
        assert!(
            err.to_string()
                .starts_with("surface image L0/0/0.tile: tile"),
            "{err}"
        );
        // A height tile where an image tile belongs says what it is not.
        let heights = crate::sketch::tiles::codec::encode_tile(&[0.0; 16], 4, 0.0, 0.0, 0).unwrap();
        let err = decode_tile(Path::new("x"), &heights).unwrap_err();
        assert!(err.to_string().contains("TTI1"), "{err}");
    }

    /// The predictor earns its place on textured imagery: 256² windows of the gallery's
    /// pictures (the procedural detail's texture, JPEG's blocks), Sub-filtered against zstd on
    /// the plain RGBA, at the same level. The imagery fixture (a colour ramp upsampled
    /// bilinearly 30 times) is printed too: there plain zstd finds the upsampling's repeats.
    #[test]
    fn the_sub_filter_beats_plain_zstd_on_textured_imagery() {
        use zune_jpeg::zune_core::{bytestream::ZCursor, colorspace::ColorSpace, options};
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
        let measure = |images: Vec<(usize, usize, Vec<u8>)>| {
            let (mut predicted, mut plain, mut raw) = (0usize, 0usize, 0usize);
            for (w, h, rgba) in images {
                let side = 256;
                for y0 in (0..h.saturating_sub(side - 1)).step_by(side) {
                    for x0 in (0..w.saturating_sub(side - 1)).step_by(side) {
                        let window: Vec<u8> = (0..side)
                            .flat_map(|r| &rgba[((y0 + r) * w + x0) * 4..][..side * 4])
                            .copied()
                            .collect();
                        predicted += encode_tile(&window, side).unwrap().len() - HEADER_BYTES;
                        plain += compress(&window).unwrap().len();
                        raw += window.len();
                    }
                }
            }
            (raw, plain, predicted)
        };
        let mut gallery = Vec::new();
        let dir = root.join("docs/pictures/gallery");
        for e in std::fs::read_dir(&dir).unwrap().flatten() {
            if e.path().extension().is_some_and(|x| x == "jpg") {
                let bytes = std::fs::read(e.path()).unwrap();
                let out =
                    options::DecoderOptions::default().jpeg_set_out_colorspace(ColorSpace::RGBA);
                let mut dec =
                    zune_jpeg::JpegDecoder::new_with_options(ZCursor::new(&bytes[..]), out);
                let rgba = dec.decode().unwrap();
                let info = dec.info().unwrap();
                gallery.push((usize::from(info.width), usize::from(info.height), rgba));
            }
        }
        let mut fine =
            crate::surface::tiff::ImageTiff::open(&root.join("tests/data/surface/ortho-fine.tif"))
                .unwrap();
        let (w, h) = (fine.width, fine.height);
        let mut smooth = vec![0u8; w * h * 4];
        fine.rows_into(0, h, h, &mut smooth).unwrap();
        let figures = [
            ("the gallery's pictures", measure(gallery)),
            ("ortho-fine.tif", measure(vec![(w, h, smooth)])),
        ];
        for (name, (raw, plain, predicted)) in figures {
            eprintln!(
                "{name}: raw {raw} B, plain zstd {plain} B ({:.2}×), Sub-filtered {predicted} B ({:.2}×)",
                raw as f64 / plain as f64,
                raw as f64 / predicted as f64
            );
        }
        let (raw, plain, predicted) = figures[0].1;
        assert!(raw >= 10 * 256 * 256 * 4, "{raw} B of windows");
        assert!(
            predicted < plain,
            "Sub-filtered {predicted} B, plain {plain} B"
        );
    }
}
