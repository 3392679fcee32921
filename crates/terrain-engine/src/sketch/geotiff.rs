//! GeoTIFF as GDAL writes it: classic and BigTIFF, either byte order, strips or tiles of any size,
//! compression none, LZW, DEFLATE, ZSTD or PackBits with predictor 1, 2 or 3, one band of Int8 to
//! Float64. The first image is read: the full resolution, also of a cloud-optimised GeoTIFF
//! (whose overviews follow it). `GDAL_NODATA`, pixel-is-area and pixel-is-point, geographic
//! coordinate systems and projected ones in metres or feet are honoured.
//!
//! Rules:
//! - The header, layout and georeference are read first, without a cell ([`Windows`]); read
//!   whole, the size is then checked against [`max_cells`](super::max_cells) before anything is
//!   allocated, and the grid is filled chunk by chunk (strip or tile), converting each to f32 as it
//!   is decoded, so a Float64 file never holds a second full-size copy.
//! - Read by bands of rows (`terrain tiles`, [`Windows::rows_into`]), only the chunk rows under a
//!   band are decoded, and the rows decoded for the next band are kept: a file of any size is
//!   read decoding each chunk once and holding about one chunk row, which must lie within the
//!   cell limit. A cloud-optimised GeoTIFF's
//!   overviews are never read (`crate::sketch::tiles` averages every coarser level from level 0).
//! - Lossy or unsupported compressions (JPEG, LERC, WebP, JPEG XL, LZMA, CCITT) are refused by
//!   name before any data is read, with the command that rewrites the file.
//! - `GDAL_NODATA` (the one ASCII tag read) is read only when its entry claims at most
//!   [`MAX_NODATA_CHARS`]: a damaged count must not allocate. tiff 0.11.3 also printed a `dbg!`
//!   line there, and failed LZW tiles narrower than their tile width; both are fixed in
//!   `vendor/tiff` (`patches/tiff-0.11.3.patch`, written to go upstream).
//!
//! Rejected alternative: `Decoder::read_image` and one conversion of the whole buffer (the
//! previous reader). It holds the decoded samples and a converted copy at once (a 2²⁸-cell
//! Float64 file: 2 GiB plus 1 GiB) and cannot tell which chunk was damaged.

use super::RawGrid;
use super::georef::{FOOT_M, Georef, US_SURVEY_FOOT_M, Units};
use crate::error::{Error, Result, Role};
use std::io::{Read, Seek};
use std::path::Path;
use tiff::decoder::{ChunkType, Decoder, DecodingResult, Limits};
use tiff::tags::Tag;

/// `GDAL_NODATA` is a number in ASCII; a longer entry is damage.
const MAX_NODATA_CHARS: u64 = 64;

/// GeoTIFF tags and keys (GeoTIFF 1.1, OGC 19-008r4).
const GEO_KEY_DIRECTORY: u16 = 34735;
const GEO_DOUBLE_PARAMS: u16 = 34736;
const MODEL_TRANSFORMATION: u16 = 34264;
const GT_MODEL_TYPE: u16 = 1024;
const GT_RASTER_TYPE: u16 = 1025;
const PROJ_LINEAR_UNITS: u16 = 3076;
const PROJ_LINEAR_UNIT_SIZE: u16 = 3077;
const GEOGRAPHIC_TYPE: u16 = 2048;
const PROJECTED_CS_TYPE: u16 = 3072;
/// GeoTIFF's code for a coordinate system the file defines itself rather than by EPSG code.
const USER_DEFINED: u16 = 32767;

pub fn read_file(path: &Path) -> Result<RawGrid> {
    let file = std::fs::File::open(path).map_err(|e| Error::io(Role::Sketch, path, e))?;
    read(path, std::io::BufReader::new(file))
}

pub fn read<R: Read + Seek>(path: &Path, reader: R) -> Result<RawGrid> {
    let mut tiff = Windows::checked(path, reader, true)?;
    let mut data = vec![f32::NAN; tiff.width * tiff.height];
    tiff.rows_into(0, tiff.height, tiff.height, &mut data)?;
    Ok(RawGrid::new(tiff.width, tiff.height, data, tiff.georef))
}

/// A GeoTIFF opened for reading by bands of rows: its header, layout and georeference read, no
/// cells. What it holds at once is one decoded chunk and about one chunk row of f32 cells.
pub struct Windows<R: Read + Seek> {
    path: std::path::PathBuf,
    dec: Decoder<R>,
    pub width: usize,
    pub height: usize,
    pub georef: Option<Georef>,
    nodata: Option<f64>,
    /// Chunk (strip or tile) size, and chunks per chunk row.
    cw: usize,
    ch: usize,
    across: usize,
    /// Rows a band read last that the next one asks for again, or that lie above it in a chunk
    /// row already decoded: the first row (from the south) and the cells.
    kept: Option<(usize, Vec<f32>)>,
}

/// Opens a GeoTIFF file for [`Windows::rows_into`], reading its header alone.
pub fn open(path: &Path) -> Result<Windows<std::io::BufReader<std::fs::File>>> {
    let file = std::fs::File::open(path).map_err(|e| Error::io(Role::Sketch, path, e))?;
    Windows::new(path, std::io::BufReader::new(file))
}

impl<R: Read + Seek> Windows<R> {
    /// Reads the header, layout and georeference; any size up to 2^31 a side is accepted here
    /// (the caller bounds what it allocates), one chunk row within the cell limit.
    pub fn new(path: &Path, reader: R) -> Result<Windows<R>> {
        Windows::checked(path, reader, false)
    }

    /// [`Windows::new`], or with `whole` the size checked against the cell limit first.
    fn checked(path: &Path, reader: R, whole: bool) -> Result<Windows<R>> {
        let bad = |reason: String| Error::sketch(path, reason);
        let tiff = |what: &'static str| move |e| Error::decode(Role::Sketch, path, what, e);
        let mut dec = Decoder::new(reader).map_err(tiff("not a readable TIFF"))?;
        let (w, h) = dec.dimensions().map_err(tiff("TIFF has no dimensions"))?;
        let (w, h) = match whole {
            true => RawGrid::check_size(path, w as i64, h as i64)?,
            false => RawGrid::check_size_unlimited(path, w as i64, h as i64)?,
        };
        // One decoded chunk, in Float64, is the largest buffer the crate needs; a tag claiming
        // more is damage and must not allocate.
        let (cw, ch) = dec.chunk_dimensions();
        let (cw, ch) = (cw as usize, ch as usize);
        let chunk_cells = (cw.min(w) as u128) * (ch.min(h) as u128);
        if (w as u128) * (ch.min(h) as u128) > super::max_cells() as u128 {
            return Err(bad(format!(
                "TIFF chunks of {cw}×{ch} make rows of more than the {} cells held at once; \
                 rewrite it tiled with `gdal_translate -co TILED=YES -co COMPRESS=DEFLATE IN OUT`",
                super::max_cells()
            )));
        }
        let mut limits = Limits::default();
        limits.decoding_buffer_size = (chunk_cells as usize * 8).max(1 << 20);
        dec = dec.with_limits(limits);
        refuse_compression(&mut dec).map_err(bad)?;
        let samples: u16 = dec
            .find_tag_unsigned(Tag::SamplesPerPixel)
            .map_err(tiff("TIFF SamplesPerPixel unreadable"))?
            .unwrap_or(1);
        if samples != 1 {
            return Err(bad(format!(
                "TIFF has {samples} bands; a height map has one (take it with `gdal_translate -b 1`)"
            )));
        }
        let nodata = gdal_nodata(&mut dec);
        let georef = georef(&mut dec, h).map_err(bad)?;
        let chunks = match dec.get_chunk_type() {
            ChunkType::Strip => dec.strip_count(),
            ChunkType::Tile => dec.tile_count(),
        }
        .map_err(tiff("TIFF chunk layout unreadable"))?;
        let across = w.div_ceil(cw.max(1));
        let expected = across * h.div_ceil(ch.max(1));
        if cw == 0 || ch == 0 || chunks as usize != expected {
            return Err(bad(format!(
                "TIFF has {chunks} chunks of {cw}×{ch} for {w}×{h} cells; {expected} expected"
            )));
        }
        Ok(Windows {
            path: path.to_path_buf(),
            dec,
            width: w,
            height: h,
            georef,
            nodata,
            cw,
            ch,
            across,
            kept: None,
        })
    }

    /// Rows `lo..hi` (counted from the south) into `out`, row-major, nodata as NaN: decoded from
    /// the chunk rows under them alone. Rows from `next` (the first row the next call asks for;
    /// `hi` or above when none) up to the top of the last chunk row decoded are kept, so reading
    /// bands upwards decodes every chunk once.
    pub fn rows_into(&mut self, lo: usize, hi: usize, next: usize, out: &mut [f32]) -> Result<()> {
        let (w, h, ch) = (self.width, self.height, self.ch);
        assert!(lo < hi && hi <= h && out.len() >= w * (hi - lo));
        // Chunk row k holds file rows k·ch.. (north first): rows h − min((k+1)·ch, h) .. h − k·ch
        // from the south.
        let south = |k: usize| (h - ((k + 1) * ch).min(h), h - k * ch);
        // What the call before kept: rows ka..kb, usable when they start at or below `lo`.
        let (ka, mut kept) = self.kept.take().unwrap_or_default();
        let kb = ka + kept.len() / w;
        let usable = ka <= lo && lo < kb;
        let from_kept = if usable { hi.min(kb) } else { lo };
        if usable {
            out[..(from_kept - lo) * w].copy_from_slice(&kept[(lo - ka) * w..(from_kept - ka) * w]);
        }
        let top = if from_kept < hi {
            south((h - hi) / ch).1
        } else {
            kb
        };
        // Kept for the next call: rows nk0..top, what is already kept moved down in place.
        let nk0 = next.max(lo);
        if usable && nk0 < kb {
            kept.drain(..(nk0 - ka) * w);
        } else {
            kept.clear();
        }
        kept.resize(top.saturating_sub(nk0) * w, f32::NAN);
        if from_kept < hi {
            for k in (h - hi) / ch..=(h - 1 - from_kept) / ch {
                let targets = [((lo, hi), &mut *out), ((nk0, top.max(nk0)), &mut kept[..])];
                self.decode_row(k, targets)?;
            }
        }
        if !kept.is_empty() {
            self.kept = Some((nk0, kept));
        }
        Ok(())
    }

    /// Decodes chunk row `k` into each target: a buffer holding rows `.0` (from the south).
    fn decode_row(&mut self, k: usize, targets: [((usize, usize), &mut [f32]); 2]) -> Result<()> {
        let mut targets = targets;
        for c in 0..self.across {
            let chunk = (k * self.across + c) as u32;
            let (dw, dh) = self.dec.chunk_data_dimensions(chunk);
            let values = self
                .dec
                .read_chunk(chunk)
                .map_err(|e| Error::decode(Role::Sketch, &self.path, chunk_name(&self.dec), e))?;
            let rect = (c * self.cw, k * self.ch, dw as usize, dh as usize);
            for (rows, out) in &mut targets {
                if rows.0 < rows.1 {
                    place(
                        &values,
                        rect,
                        (self.width, self.height),
                        *rows,
                        self.nodata,
                        out,
                    )
                    .map_err(|reason| Error::sketch(&self.path, reason))?;
                }
            }
        }
        Ok(())
    }
}

fn chunk_name<R: Read + Seek>(dec: &Decoder<R>) -> &'static str {
    match dec.get_chunk_type() {
        ChunkType::Strip => "TIFF strip corrupt or truncated",
        ChunkType::Tile => "TIFF tile corrupt or truncated",
    }
}

/// Refuses the compressions the `tiff` crate cannot read, by name.
pub(crate) fn refuse_compression<R: Read + Seek>(
    dec: &mut Decoder<R>,
) -> std::result::Result<(), String> {
    let code: u16 = dec
        .find_tag_unsigned(Tag::Compression)
        .map_err(|e| format!("TIFF compression tag unreadable: {e}"))?
        .unwrap_or(1);
    let name = match code {
        1 | 5 | 8 | 32946 | 32773 | 50000 => return Ok(()),
        2..=4 => "CCITT fax",
        6 | 7 => "JPEG (lossy)",
        34887 => "LERC",
        34925 => "LZMA",
        50001 => "WebP",
        50002 | 52546 => "JPEG XL",
        other => return Err(format!("TIFF compression {other} is not a known method")),
    };
    Err(format!(
        "TIFF compression {name} is not read; rewrite it with `gdal_translate -co COMPRESS=DEFLATE IN OUT`"
    ))
}

pub(crate) fn gdal_nodata<R: Read + Seek>(dec: &mut Decoder<R>) -> Option<f64> {
    let ptr = dec.ifd_pointer()?;
    let dir = dec.read_directory(ptr).ok()?;
    if dir.get(Tag::GdalNodata)?.count() > MAX_NODATA_CHARS {
        return None;
    }
    let text = dec.get_tag_ascii_string(Tag::GdalNodata).ok()?;
    let text = text.trim_matches(char::from(0)).trim();
    // GDAL writes "nan" for a NaN nodata; NaN cells are nodata anyway.
    text.parse().ok().filter(|v: &f64| v.is_finite())
}

/// Copies one decoded chunk into the grid (row 0 south), nodata and non-finite values as NaN.
fn place(
    values: &DecodingResult,
    (x0, y0, dw, dh): (usize, usize, usize, usize),
    (w, h): (usize, usize),
    rows: (usize, usize),
    nodata: Option<f64>,
    data: &mut [f32],
) -> std::result::Result<(), String> {
    fn copy<T: Copy>(
        src: &[T],
        rect: (usize, usize, usize, usize),
        size: (usize, usize),
        (lo, hi): (usize, usize),
        data: &mut [f32],
        convert: impl Fn(T) -> f32,
    ) -> std::result::Result<(), String> {
        let (x0, y0, dw, dh) = rect;
        let (w, h) = size;
        if src.len() < dw * dh || x0 + dw > w || y0 + dh > h {
            return Err(format!(
                "TIFF chunk at ({x0}, {y0}) holds {} samples for {dw}×{dh}",
                src.len()
            ));
        }
        for (r, row) in src.chunks_exact(dw).take(dh).enumerate() {
            let south = h - 1 - (y0 + r);
            if !(lo..hi).contains(&south) {
                continue;
            }
            let out = (south - lo) * w + x0;
            for (d, &v) in data[out..out + dw].iter_mut().zip(row) {
                *d = convert(v);
            }
        }
        Ok(())
    }
    let rect = (x0, y0, dw, dh);
    let size = (w, h);
    let cell = |v: f64| -> f32 {
        let f = v as f32;
        let missing = nodata.is_some_and(|nd| v == nd || f == nd as f32);
        if missing || !f.is_finite() {
            f32::NAN
        } else {
            f
        }
    };
    match values {
        DecodingResult::U8(v) => copy(v, rect, size, rows, data, |x| cell(x.into())),
        DecodingResult::I8(v) => copy(v, rect, size, rows, data, |x| cell(x.into())),
        DecodingResult::U16(v) => copy(v, rect, size, rows, data, |x| cell(x.into())),
        DecodingResult::I16(v) => copy(v, rect, size, rows, data, |x| cell(x.into())),
        DecodingResult::U32(v) => copy(v, rect, size, rows, data, |x| cell(x.into())),
        DecodingResult::I32(v) => copy(v, rect, size, rows, data, |x| cell(x.into())),
        DecodingResult::U64(v) => copy(v, rect, size, rows, data, |x| cell(x as f64)),
        DecodingResult::I64(v) => copy(v, rect, size, rows, data, |x| cell(x as f64)),
        DecodingResult::F16(v) => copy(v, rect, size, rows, data, |x| cell(x.to_f64())),
        DecodingResult::F32(v) => copy(v, rect, size, rows, data, |x| cell(x.into())),
        DecodingResult::F64(v) => copy(v, rect, size, rows, data, cell),
    }
}

/// The grid's georeference from the GeoTIFF tags, if it has one.
pub(crate) fn georef<R: Read + Seek>(
    dec: &mut Decoder<R>,
    height: usize,
) -> std::result::Result<Option<Georef>, String> {
    let keys = geo_keys(dec);
    let key = |id: u16| keys.iter().find(|k| k.0 == id).map(|k| k.1);
    let units = match key(GT_MODEL_TYPE) {
        Some(GeoValue::Short(2)) => Units::Degrees,
        Some(GeoValue::Short(1)) => match key(PROJ_LINEAR_UNITS) {
            Some(GeoValue::Short(9002)) => Units::Linear(FOOT_M),
            Some(GeoValue::Short(9003)) => Units::Linear(US_SURVEY_FOOT_M),
            Some(GeoValue::Short(32767)) => match key(PROJ_LINEAR_UNIT_SIZE) {
                Some(GeoValue::Double(m)) if m > 0.0 && m.is_finite() => Units::Linear(m),
                _ => Units::Linear(1.0),
            },
            _ => Units::Linear(1.0),
        },
        _ => Units::Unknown,
    };
    let code = match units {
        Units::Degrees => key(GEOGRAPHIC_TYPE),
        _ => key(PROJECTED_CS_TYPE),
    };
    let epsg = match code {
        Some(GeoValue::Short(c)) if c != USER_DEFINED && c != 0 => Some(c),
        _ => None,
    };
    let point = key(GT_RASTER_TYPE) == Some(GeoValue::Short(2));
    let tag = |dec: &mut Decoder<R>, t: u16| -> Option<Vec<f64>> {
        dec.get_tag_f64_vec(Tag::Unknown(t)).ok()
    };
    let scale = dec.get_tag_f64_vec(Tag::ModelPixelScaleTag).ok();
    let tie = dec.get_tag_f64_vec(Tag::ModelTiepointTag).ok();
    let (sx, sy, tx, ty, ti, tj) = match (scale.as_deref(), tie.as_deref()) {
        (Some([sx, sy, ..]), Some([i, j, _, x, y, ..])) => (*sx, *sy, *x, *y, *i, *j),
        _ => match tag(dec, MODEL_TRANSFORMATION).as_deref() {
            Some([a, b, _, d, e, f, _, hh, ..]) => {
                if *b != 0.0 || *e != 0.0 {
                    return Err("GeoTIFF grid is rotated; warp it north-up with gdalwarp".into());
                }
                (*a, -*f, *d, *hh, 0.0, 0.0)
            }
            _ => return Ok(None),
        },
    };
    if !(sx > 0.0 && sy > 0.0 && [sx, sy, tx, ty, ti, tj].iter().all(|v| v.is_finite())) {
        return Err(format!(
            "GeoTIFF pixel scale {sx} × {sy} is not positive and finite"
        ));
    }
    // Pixel-is-area ties the cell's corner, pixel-is-point its centre (the node).
    let half = if point { 0.0 } else { 0.5 };
    let west = tx + (half - ti) * sx;
    let north = ty - (half - tj) * sy;
    Ok(Some(Georef {
        west,
        south: north - (height as f64 - 1.0) * sy,
        cell_x: sx,
        cell_y: sy,
        units,
        epsg,
    }))
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum GeoValue {
    Short(u16),
    Double(f64),
    Other,
}

/// The GeoKey directory as (key, value) pairs; empty when absent or damaged.
fn geo_keys<R: Read + Seek>(dec: &mut Decoder<R>) -> Vec<(u16, GeoValue)> {
    let Ok(dir) = dec.get_tag_u16_vec(Tag::Unknown(GEO_KEY_DIRECTORY)) else {
        return Vec::new();
    };
    let doubles = dec
        .get_tag_f64_vec(Tag::Unknown(GEO_DOUBLE_PARAMS))
        .unwrap_or_default();
    let count = dir.get(3).copied().unwrap_or(0) as usize;
    dir.get(4..)
        .unwrap_or(&[])
        .chunks_exact(4)
        .take(count)
        .map(|k| {
            let value = match k[1] {
                0 => GeoValue::Short(k[3]),
                GEO_DOUBLE_PARAMS => doubles
                    .get(k[3] as usize)
                    .map_or(GeoValue::Other, |v| GeoValue::Double(*v)),
                _ => GeoValue::Other,
            };
            (k[0], value)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use tiff::encoder::{TiffEncoder, colortype::Gray32Float};

    /// A 3 × 2 Float32 TIFF with the given GeoTIFF tags (GDAL writes a ModelTransformation only
    /// for rotated grids; other writers use it north-up).
    fn tiff_with(transform: [f64; 16], keys: &[u16]) -> Vec<u8> {
        let mut bytes = std::io::Cursor::new(Vec::new());
        let mut enc = TiffEncoder::new(&mut bytes).unwrap();
        let mut image = enc.new_image::<Gray32Float>(3, 2).unwrap();
        let dir = image.encoder();
        dir.write_tag(Tag::Unknown(MODEL_TRANSFORMATION), &transform[..])
            .unwrap();
        dir.write_tag(Tag::Unknown(GEO_KEY_DIRECTORY), keys)
            .unwrap();
        image
            .write_data(&[1.0f32, 2.0, 3.0, 4.0, 5.0, 6.0])
            .unwrap();
        bytes.into_inner()
    }

    #[test]
    fn a_north_up_model_transformation_in_feet_places_the_grid() {
        // Projected (1024 = 1), pixel-is-area (1025 = 1), international feet (3076 = 9002).
        let keys = [1, 1, 0, 3, 1024, 0, 1, 1, 1025, 0, 1, 1, 3076, 0, 1, 9002];
        let t = [
            10.0, 0.0, 0.0, 1000.0, 0.0, -20.0, 0.0, 5000.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0,
        ];
        let g = read(
            Path::new("t.tif"),
            std::io::Cursor::new(tiff_with(t, &keys)),
        )
        .unwrap();
        let r = g.georef.unwrap();
        assert_eq!((r.west, r.south), (1005.0, 4970.0));
        assert_eq!(r.units, Units::Linear(FOOT_M));
        assert!((g.dx - 3.048).abs() < 1e-12 && (g.dy - 6.096).abs() < 1e-12);
        // Row 0 is the south: the file's second row.
        assert_eq!(g.data, vec![4.0, 5.0, 6.0, 1.0, 2.0, 3.0]);
    }

    #[test]
    fn a_rotated_grid_is_refused() {
        let t = [
            10.0, 1.0, 0.0, 1000.0, 0.5, -20.0, 0.0, 5000.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0,
        ];
        let err = read(
            Path::new("t.tif"),
            std::io::Cursor::new(tiff_with(t, &[1, 1, 0, 0])),
        )
        .unwrap_err()
        .to_string();
        assert!(err.contains("rotated"), "{err}");
    }
}
