//! What `surface.image` names, opened: an image file read whole (a GeoTIFF, or a PNG or JPEG
//! with a world file), or an image pyramid's folder read where the drape needs it.
//!
//! Rules:
//! - A GeoTIFF is placed by its GeoTIFF tags, or else by a world file beside it; a PNG or JPEG
//!   by its world file alone. A world file is looked for by GDAL's names: the extension's first
//!   and last letters and `w` (`.tfw`, `.pgw`, `.jgw`), the extension and `w` (`.tifw`,
//!   `.pngw`, `.jpgw`, `.jpegw`), then `.wld`; each in lower and upper case. It names no
//!   coordinate system, so its coordinates are read as the sketch's.
//! - A file read whole holds at most [`crate::sketch::max_cells`] pixels; a larger GeoTIFF is
//!   refused with the `terrain tiles` command that makes it a pyramid.
//! - A JPEG is decoded in strict mode: a truncated or damaged file is refused, not drawn with
//!   grey where its data ends.
//!
//! Rejected alternative: the `image` crate for PNG and JPEG. Its decoders are these same
//! crates (`png`, `zune-jpeg`) behind a dynamic image type; the core calls them directly, as
//! it does `png` for sketches, and stays within what builds for wasm32.

use crate::error::{Error, Result, Role};
use crate::sketch::tiles::ImagePyramid;
use crate::sketch::{Georef, Units};
use std::path::{Path, PathBuf};

/// World files are six numbers; a larger file is not one.
const MAX_WORLD_FILE_BYTES: u64 = 4096;

/// An image as read: RGBA8 rows from the south, and where its pixels' centres lie.
pub(super) struct Picture {
    pub(super) width: usize,
    pub(super) height: usize,
    pub(super) rgba: Vec<u8>,
    pub(super) georef: Georef,
    /// The image names no coordinate system (a world file): read in the sketch's.
    pub(super) in_sketch_crs: bool,
    /// The column and row (from the south) of the first pixel on its level: the pixels are a
    /// window of a pyramid's level, or (0, 0), the whole image.
    pub(super) origin: [usize; 2],
}

/// An image read whole, or a pyramid whose tiles are read under the sketch.
pub(super) enum Source {
    Whole(Picture),
    Pyramid(ImagePyramid),
}

/// Opens what `path` names.
pub(super) fn open(path: &Path) -> Result<Source> {
    if path.is_dir() {
        if !crate::sketch::tiles::is_pyramid(path) {
            return Err(Error::file(
                Role::Image,
                path,
                "a folder without pyramid.toml: give an image file, or the folder `terrain \
                 tiles IMAGE --out-dir DIR` wrote",
            ));
        }
        return ImagePyramid::open(path).map(Source::Pyramid);
    }
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .unwrap_or_default();
    match ext.as_str() {
        "tif" | "tiff" => read_tiff(path),
        "png" => read_png(path),
        "jpg" | "jpeg" => read_jpeg(path),
        _ => Err(Error::file(
            Role::Image,
            path,
            "give an RGB, RGBA or grey GeoTIFF (.tif), a PNG or JPEG with a world file (.pgw, \
             .jgw), or an image pyramid's folder (`terrain tiles`)",
        )),
    }
    .map(Source::Whole)
}

/// Refuses an image of more pixels than are read whole.
fn check_size(path: &Path, w: usize, h: usize, pyramid: bool) -> Result<()> {
    let limit = crate::sketch::max_cells();
    if w < 2 || h < 2 {
        return Err(Error::file(
            Role::Image,
            path,
            format!("{w} × {h} pixels: give at least 2 × 2"),
        ));
    }
    if (w as u128) * (h as u128) <= limit as u128 {
        return Ok(());
    }
    let how = match pyramid {
        true => format!(
            "convert it with `terrain tiles {} --out-dir DIR` and give DIR",
            path.display()
        ),
        false => "make it a tiled GeoTIFF (`gdal_translate -of GTiff -co TILED=YES \
                  -co COMPRESS=DEFLATE IN OUT.tif`) and convert that with `terrain tiles`"
            .into(),
    };
    Err(Error::file(
        Role::Image,
        path,
        format!("{w} × {h} pixels is more than the {limit} read whole; {how}"),
    ))
}

fn read_tiff(path: &Path) -> Result<Picture> {
    let mut tiff = crate::surface::tiff::ImageTiff::open(path)?;
    let (w, h) = (tiff.width, tiff.height);
    check_size(path, w, h, true)?;
    let (georef, in_sketch_crs) = match tiff.georef {
        Some(g) => (g, false),
        None => match world_file(path) {
            Some(world) => (read_world_file(&world, h)?, true),
            None => {
                return Err(Error::file(
                    Role::Image,
                    path,
                    "no georeference (GeoTIFF tags or a .tfw world file): it cannot be placed",
                ));
            }
        },
    };
    let mut rgba = vec![0u8; w * h * 4];
    tiff.rows_into(0, h, h, &mut rgba)?;
    Ok(Picture {
        width: w,
        height: h,
        rgba,
        georef,
        in_sketch_crs,
        origin: [0, 0],
    })
}

fn read_png(path: &Path) -> Result<Picture> {
    let bad = |why: String| Error::file(Role::Image, path, why);
    let world = needed_world_file(path)?;
    let file = std::fs::File::open(path).map_err(|e| Error::io(Role::Image, path, e))?;
    let mut decoder = png::Decoder::new(std::io::BufReader::new(file));
    decoder.set_transformations(png::Transformations::EXPAND | png::Transformations::STRIP_16);
    let mut reader = decoder
        .read_info()
        .map_err(|e| Error::decode(Role::Image, path, "not a readable PNG", e))?;
    let (w, h) = (reader.info().width as usize, reader.info().height as usize);
    check_size(path, w, h, false)?;
    let size = reader
        .output_buffer_size()
        .ok_or_else(|| bad("too large".into()))?;
    let mut buf = vec![0; size];
    let info = reader
        .next_frame(&mut buf)
        .map_err(|e| Error::decode(Role::Image, path, "corrupt or truncated PNG", e))?;
    let rgba = south_first(&buf[..info.buffer_size()], w, h, info.color_type.samples());
    Ok(Picture {
        width: w,
        height: h,
        rgba,
        georef: read_world_file(&world, h)?,
        in_sketch_crs: true,
        origin: [0, 0],
    })
}

fn read_jpeg(path: &Path) -> Result<Picture> {
    use zune_jpeg::JpegDecoder;
    use zune_jpeg::zune_core::bytestream::ZCursor;
    use zune_jpeg::zune_core::colorspace::ColorSpace;
    use zune_jpeg::zune_core::options::DecoderOptions;
    let world = needed_world_file(path)?;
    // The compressed file is a small part of the decoded pixels: read whole.
    let bytes = std::fs::read(path).map_err(|e| Error::io(Role::Image, path, e))?;
    let options = DecoderOptions::default()
        .set_strict_mode(true)
        .set_max_width(usize::from(u16::MAX))
        .set_max_height(usize::from(u16::MAX))
        .jpeg_set_out_colorspace(ColorSpace::RGBA);
    let mut dec = JpegDecoder::new_with_options(ZCursor::new(&bytes[..]), options);
    let not_jpeg = |e| Error::decode(Role::Image, path, "not a readable JPEG", e);
    dec.decode_headers().map_err(not_jpeg)?;
    let info = dec
        .info()
        .ok_or_else(|| Error::file(Role::Image, path, "a JPEG without dimensions"))?;
    let (w, h) = (usize::from(info.width), usize::from(info.height));
    check_size(path, w, h, false)?;
    let pixels = dec
        .decode()
        .map_err(|e| Error::decode(Role::Image, path, "corrupt or truncated JPEG", e))?;
    let channels = dec.output_colorspace().map_or(4, |c| c.num_components());
    if pixels.len() < w * h * channels {
        return Err(Error::file(
            Role::Image,
            path,
            "truncated: fewer pixels than its size",
        ));
    }
    Ok(Picture {
        width: w,
        height: h,
        rgba: south_first(&pixels, w, h, channels),
        georef: read_world_file(&world, h)?,
        in_sketch_crs: true,
        origin: [0, 0],
    })
}

/// Decoded rows (north first, `channels` samples a pixel) as RGBA8 rows from the south.
fn south_first(pixels: &[u8], w: usize, h: usize, channels: usize) -> Vec<u8> {
    let mut rgba = Vec::with_capacity(w * h * 4);
    for row in pixels.chunks_exact(w * channels).take(h).rev() {
        rgba.extend(
            row.chunks_exact(channels)
                .flat_map(|p| crate::surface::tiff::rgba(p, None)),
        );
    }
    rgba
}

/// The world file beside `path` by GDAL's names, if there is one.
pub(super) fn world_file(path: &Path) -> Option<PathBuf> {
    let ext = path.extension()?.to_str()?.to_ascii_lowercase();
    let (first, last) = (ext.chars().next()?, ext.chars().last()?);
    [format!("{first}{last}w"), format!("{ext}w"), "wld".into()]
        .into_iter()
        .flat_map(|e| [e.to_ascii_uppercase(), e])
        .map(|e| path.with_extension(e))
        .find(|p| p.is_file())
}

/// The world file a PNG or JPEG must have: its path, or an error naming the names looked for.
fn needed_world_file(path: &Path) -> Result<PathBuf> {
    world_file(path).ok_or_else(|| {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .unwrap_or("")
            .to_ascii_lowercase();
        let (first, last) = (
            ext.chars().next().unwrap_or('x'),
            ext.chars().last().unwrap_or('x'),
        );
        Error::file(
            Role::Image,
            path,
            format!(
                "no world file beside it (.{first}{last}w, .{ext}w or .wld): it cannot be placed"
            ),
        )
    })
}

/// A world file's georeference for an image `height` rows tall.
fn read_world_file(world: &Path, height: usize) -> Result<Georef> {
    let bad = |why: String| Error::file(Role::Image, world, why);
    let len = std::fs::metadata(world)
        .map_err(|e| Error::io(Role::Image, world, e))?
        .len();
    if len > MAX_WORLD_FILE_BYTES {
        return Err(bad(format!(
            "world file is {len} bytes; it holds six numbers"
        )));
    }
    let bytes = std::fs::read(world).map_err(|e| Error::io(Role::Image, world, e))?;
    // The parser names the file a sketch's; here it is the image's.
    let gt = crate::sketch::parse_world_file(world, &bytes).map_err(|e| match e {
        Error::File { reason, .. } => bad(reason),
        e => e,
    })?;
    Georef::from_geotransform(gt, height, Units::Unknown)
        .ok_or_else(|| bad("world file is rotated; warp the image north-up with gdalwarp".into()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn world_files_are_found_by_gdals_names() {
        let dir = std::env::temp_dir().join(format!("terrain-world-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let jpg = dir.join("a.jpg");
        assert_eq!(world_file(&jpg), None);
        for name in ["a.wld", "a.jpgw", "a.JGW"] {
            std::fs::write(dir.join(name), "1\n0\n0\n-1\n0.5\n9.5\n").unwrap();
            assert_eq!(world_file(&jpg), Some(dir.join(name)), "{name}");
        }
        std::fs::write(dir.join("b.jpeg.txt"), "").unwrap();
        std::fs::write(dir.join("b.jgw"), "").unwrap();
        assert_eq!(world_file(&dir.join("b.jpeg")), Some(dir.join("b.jgw")));
        let _ = std::fs::remove_dir_all(&dir);
    }
}
