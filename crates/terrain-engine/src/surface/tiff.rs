//! An 8-bit GeoTIFF image (grey, grey and alpha, RGB or RGBA; strips or tiles; a COG's full
//! resolution) read as RGBA8 rows from its own chunks: whole for a drape, band by band for an
//! image pyramid (`terrain tiles`).
//!
//! Rules:
//! - The header, layout and georeference are read first; rows are then decoded chunk row by
//!   chunk row (a chunk row is one row of strips or tiles across the image), each converted to
//!   RGBA8 as it is decoded. What is held beyond the caller's rows is the chunk rows the next
//!   call asks for again, so bands read upwards decode every chunk once; one chunk row must lie
//!   within the cell limit ([`crate::sketch::max_cells`]).
//! - Grey becomes R = G = B; a missing alpha is 255. Where the file has GDAL's nodata, a pixel
//!   whose every colour sample equals it has alpha 0: it does not cover.
//! - Compressions the tiff crate cannot read (JPEG, WebP, LERC, …) and samples stored band by
//!   band are refused by name, with the `gdal_translate` command that rewrites the file.
//!
//! Rejected alternative: `Decoder::read_image` and one conversion of the whole buffer. It holds
//! the decoded samples and the RGBA copy at once, and an image larger than memory cannot be read
//! at all, where the pyramid's build needs only a band of it.

use crate::error::{Error, Result, Role};
use crate::sketch::Georef;
use std::fs::File;
use std::io::BufReader;
use std::path::{Path, PathBuf};
use tiff::decoder::{ChunkType, Decoder, DecodingResult, Limits};
use tiff::tags::Tag;

/// What a pixel of the file holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Samples {
    /// One grey sample.
    Grey,
    /// Grey and alpha.
    GreyAlpha,
    /// Red, green, blue.
    Rgb,
    /// Red, green, blue, alpha.
    Rgba,
}

impl Samples {
    fn count(self) -> usize {
        match self {
            Samples::Grey => 1,
            Samples::GreyAlpha => 2,
            Samples::Rgb => 3,
            Samples::Rgba => 4,
        }
    }
}

/// An image GeoTIFF opened for reading rows: its header, layout and georeference read.
pub struct ImageTiff {
    path: PathBuf,
    dec: Decoder<BufReader<File>>,
    /// Pixels per row.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// What a pixel holds.
    pub samples: Samples,
    /// Where the pixels' centres lie, when the file says.
    pub georef: Option<Georef>,
    nodata: Option<u8>,
    /// Chunk (strip or tile) size, and chunks per chunk row.
    cw: usize,
    ch: usize,
    across: usize,
    /// Chunk rows decoded and kept for the next call: (chunk row, its RGBA rows north first).
    kept: Vec<(usize, Vec<u8>)>,
}

/// The samples of a TIFF at `path`, read from its header alone; `None` when it is no readable
/// TIFF or not 8-bit. `terrain tiles` tells an image from heights by them.
pub fn samples_of(path: &Path) -> Option<Samples> {
    let file = File::open(path).ok()?;
    let mut dec = Decoder::new(BufReader::new(file)).ok()?;
    samples(dec.colortype().ok()?)
}

fn samples(colour: tiff::ColorType) -> Option<Samples> {
    match colour {
        tiff::ColorType::Gray(8) => Some(Samples::Grey),
        tiff::ColorType::GrayA(8) => Some(Samples::GreyAlpha),
        tiff::ColorType::RGB(8) => Some(Samples::Rgb),
        tiff::ColorType::RGBA(8) => Some(Samples::Rgba),
        _ => None,
    }
}

impl ImageTiff {
    /// Opens the image at `path`, reading its header alone; any size is accepted here (the
    /// caller bounds what it reads at once).
    pub fn open(path: &Path) -> Result<ImageTiff> {
        let bad = |why: String| Error::file(Role::Image, path, why);
        let file = File::open(path).map_err(|e| Error::io(Role::Image, path, e))?;
        let mut dec = Decoder::new(BufReader::new(file))
            .map_err(|e| Error::decode(Role::Image, path, "not a readable TIFF", e))?;
        let (w, h) = dec.dimensions().map_err(|e| bad(e.to_string()))?;
        let (w, h) = (w as usize, h as usize);
        if w < 2 || h < 2 {
            return Err(bad(format!("{w} × {h} pixels: give at least 2 × 2")));
        }
        crate::sketch::refuse_compression(&mut dec).map_err(bad)?;
        let colour = dec.colortype().map_err(|e| bad(e.to_string()))?;
        let samples = samples(colour).ok_or_else(|| {
            bad(format!(
                "{colour:?} samples: give 8-bit RGB, RGBA or grey (gdal_translate -ot Byte)"
            ))
        })?;
        let planar: u16 = dec
            .find_tag_unsigned(Tag::PlanarConfiguration)
            .map_err(|e| bad(format!("TIFF PlanarConfiguration unreadable: {e}")))?
            .unwrap_or(1);
        if planar != 1 && samples != Samples::Grey {
            return Err(bad(
                "its samples are stored band by band; rewrite it pixel by pixel with \
                 `gdal_translate -co INTERLEAVE=PIXEL -co TILED=YES -co COMPRESS=DEFLATE IN OUT`"
                    .into(),
            ));
        }
        let (cw, ch) = dec.chunk_dimensions();
        let (cw, ch) = (cw as usize, ch as usize);
        if cw == 0
            || ch == 0
            || (w as u128) * (ch.min(h) as u128) > crate::sketch::max_cells() as u128
        {
            return Err(bad(format!(
                "TIFF chunks of {cw}×{ch} make rows of more than the {} pixels held at once; \
                 rewrite it tiled with `gdal_translate -co TILED=YES -co COMPRESS=DEFLATE IN OUT`",
                crate::sketch::max_cells()
            )));
        }
        let chunks = match dec.get_chunk_type() {
            ChunkType::Strip => dec.strip_count(),
            ChunkType::Tile => dec.tile_count(),
        }
        .map_err(|e| bad(format!("TIFF chunk layout unreadable: {e}")))?;
        let across = w.div_ceil(cw);
        let expected = across * h.div_ceil(ch);
        if chunks as usize != expected {
            return Err(bad(format!(
                "TIFF has {chunks} chunks of {cw}×{ch} for {w}×{h} pixels; {expected} expected"
            )));
        }
        // One decoded chunk is the largest buffer the crate needs; a tag claiming more than the
        // image rounded up to a power of two is damage and must not allocate.
        let chunk = cw.min(w.next_power_of_two()) * ch.min(h.next_power_of_two());
        let mut limits = Limits::default();
        limits.decoding_buffer_size = (chunk * samples.count()).max(1 << 20);
        dec = dec.with_limits(limits);
        let nodata = crate::sketch::gdal_nodata(&mut dec)
            .filter(|v| v.fract() == 0.0 && (0.0..=255.0).contains(v))
            .map(|v| v as u8);
        let georef = crate::sketch::tiff_georef(&mut dec, h)
            .map_err(bad)?
            .map(|g| g.resolved(w, h));
        Ok(ImageTiff {
            path: path.to_path_buf(),
            dec,
            width: w,
            height: h,
            samples,
            georef,
            nodata,
            cw,
            ch,
            across,
            kept: Vec::new(),
        })
    }

    /// Rows `lo..hi`, counted from the south, into `out` as RGBA8 (row-major, row `lo` first).
    /// The chunk rows that hold rows from `next` up are kept for the next call (`next` ≥ the
    /// image's height: none).
    pub fn rows_into(&mut self, lo: usize, hi: usize, next: usize, out: &mut [u8]) -> Result<()> {
        let (w, h, ch) = (self.width, self.height, self.ch);
        assert!(lo < hi && hi <= h && out.len() >= w * (hi - lo) * 4);
        // Chunk row k holds file rows k·ch.. (north first), rows south(k) from the south.
        let south = |k: usize| (h - ((k + 1) * ch).min(h), h - k * ch);
        let mut kept = std::mem::take(&mut self.kept);
        kept.retain(|(k, _)| south(*k).1 > lo);
        // From the south: the chunk row holding row lo first.
        for k in ((h - hi) / ch..=(h - 1 - lo) / ch).rev() {
            let rows = match kept.iter().position(|(kk, _)| *kk == k) {
                Some(i) => kept.swap_remove(i).1,
                None => self.decode_row(k)?,
            };
            let (s0, s1) = south(k);
            for r in lo.max(s0)..hi.min(s1) {
                // Row r from the south is row s1 − 1 − r of the chunk row, north first.
                let src = &rows[(s1 - 1 - r) * w * 4..][..w * 4];
                out[(r - lo) * w * 4..][..w * 4].copy_from_slice(src);
            }
            if s1 > next {
                kept.push((k, rows));
            }
        }
        self.kept = kept;
        Ok(())
    }

    /// Chunk row `k`, decoded and converted: its rows north first, RGBA8.
    fn decode_row(&mut self, k: usize) -> Result<Vec<u8>> {
        let (w, h) = (self.width, self.height);
        let rows = self.ch.min(h - k * self.ch);
        let mut out = vec![0u8; w * rows * 4];
        let spp = self.samples.count();
        for c in 0..self.across {
            let chunk = (k * self.across + c) as u32;
            let (dw, dh) = self.dec.chunk_data_dimensions(chunk);
            let (dw, dh) = (dw as usize, dh as usize);
            let what = match self.dec.get_chunk_type() {
                ChunkType::Strip => "TIFF strip corrupt or truncated",
                ChunkType::Tile => "TIFF tile corrupt or truncated",
            };
            let values = self
                .dec
                .read_chunk(chunk)
                .map_err(|e| Error::decode(Role::Image, &self.path, what, e))?;
            let DecodingResult::U8(v) = values else {
                return Err(Error::file(
                    Role::Image,
                    &self.path,
                    "not 8-bit unsigned samples",
                ));
            };
            let x0 = c * self.cw;
            if v.len() < dw * dh * spp || x0 + dw > w || dh > rows {
                return Err(Error::file(
                    Role::Image,
                    &self.path,
                    format!(
                        "TIFF chunk {chunk} holds {} samples for {dw}×{dh} pixels",
                        v.len()
                    ),
                ));
            }
            for (r, row) in v.chunks_exact(dw * spp).take(dh).enumerate() {
                let dst = &mut out[(r * w + x0) * 4..][..dw * 4];
                for (d, p) in dst.chunks_exact_mut(4).zip(row.chunks_exact(spp)) {
                    d.copy_from_slice(&rgba(p, self.nodata));
                }
            }
        }
        Ok(out)
    }
}

/// One pixel's samples as RGBA8; alpha 0 where every colour sample is the nodata value.
pub(crate) fn rgba(p: &[u8], nodata: Option<u8>) -> [u8; 4] {
    let mut c = match *p {
        [g] => [g, g, g, 255],
        [g, a] => [g, g, g, a],
        [r, g, b] => [r, g, b, 255],
        [r, g, b, a, ..] => [r, g, b, a],
        [] => [0; 4],
    };
    if let Some(nd) = nodata {
        let colour = if p.len() <= 2 { &p[..1] } else { &p[..3] };
        if colour.iter().all(|&v| v == nd) {
            c[3] = 0;
        }
    }
    c
}

#[cfg(test)]
mod tests {
    use super::*;
    use tiff::encoder::{TiffEncoder, colortype::RGB8};

    /// A 5 × 7 RGB TIFF in strips of `rows` rows, pixel (x, y from the north) = (x, y, x + y),
    /// with GDAL's nodata 0 and a georeference.
    fn write(path: &Path, rows: u32) {
        let file = File::create(path).unwrap();
        let mut enc = TiffEncoder::new(file).unwrap();
        let mut image = enc.new_image::<RGB8>(5, 7).unwrap();
        image.rows_per_strip(rows).unwrap();
        let dir = image.encoder();
        dir.write_tag(Tag::GdalNodata, "0").unwrap();
        dir.write_tag(Tag::ModelPixelScaleTag, &[10.0f64, 10.0, 0.0][..])
            .unwrap();
        dir.write_tag(
            Tag::ModelTiepointTag,
            &[0.0f64, 0.0, 0.0, 1000.0, 2000.0, 0.0][..],
        )
        .unwrap();
        let data: Vec<u8> = (0..7u8)
            .flat_map(|y| (0..5u8).flat_map(move |x| [x, y, x + y]))
            .collect();
        image.write_data(&data).unwrap();
    }

    #[test]
    fn bands_read_upwards_give_the_rows_the_whole_read_gives() {
        let dir = std::env::temp_dir().join(format!("terrain-image-tiff-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        for rows in [1, 2, 3, 7] {
            let path = dir.join(format!("strips-{rows}.tif"));
            write(&path, rows);
            let mut t = ImageTiff::open(&path).unwrap();
            assert_eq!((t.width, t.height, t.samples), (5, 7, Samples::Rgb));
            let g = t.georef.unwrap();
            // Pixel-is-area: the north-west pixel's centre is half a pixel in.
            assert_eq!((g.west, g.south), (1005.0, 2000.0 - 65.0));
            let mut whole = vec![0u8; 5 * 7 * 4];
            t.rows_into(0, 7, 7, &mut whole).unwrap();
            // Row 0 is the south: the file's last row (y = 6).
            assert_eq!(&whole[..8], &[0, 6, 6, 255, 1, 6, 7, 255]);
            // The north-west pixel is (0, 0, 0), nodata in every sample: it does not cover;
            // (1, 0, 1) has a 0 among its samples and covers.
            let north = &whole[6 * 5 * 4..];
            assert_eq!(&north[..8], &[0, 0, 0, 0, 1, 0, 1, 255]);
            // Overlapping bands upwards, as a pyramid's build reads them.
            let mut t = ImageTiff::open(&path).unwrap();
            for (lo, hi, next) in [(0, 3, 1), (1, 5, 3), (3, 7, 7)] {
                let mut band = vec![0u8; 5 * (hi - lo) * 4];
                t.rows_into(lo, hi, next, &mut band).unwrap();
                assert_eq!(
                    band,
                    whole[lo * 20..hi * 20],
                    "rows {lo}..{hi}, strips of {rows}"
                );
            }
        }
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn nodata_in_every_colour_sample_does_not_cover() {
        assert_eq!(rgba(&[3, 3, 3], Some(3))[3], 0);
        assert_eq!(rgba(&[3, 3, 4], Some(3))[3], 255);
        assert_eq!(rgba(&[0, 0, 0, 200], Some(0)), [0, 0, 0, 0]);
        assert_eq!(rgba(&[7], None), [7, 7, 7, 255]);
        assert_eq!(rgba(&[7, 9], Some(7)), [7, 7, 7, 0]);
    }
}
