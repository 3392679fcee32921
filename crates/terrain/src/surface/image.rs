//! A user's imagery draped over the ground (`surface.image`): an RGB or RGBA GeoTIFF (or COG),
//! or a PNG with a world file, resampled once onto a grid of the sketch's world metres that the
//! shading samples per pixel.
//!
//! Rules:
//! - The image is placed by its georeference through the sketch's coordinate system: world
//!   metres → the sketch file's coordinates → latitude and longitude → the image's coordinates,
//!   the conversion `lat_deg`/`lon_deg` cameras use. Where both name the same system, the
//!   coordinates pass straight through; a PNG's world file names none and is read in the sketch's.
//! - The conversion is exact on a lattice every [`LATTICE`] texels and bilinear between (a
//!   projection is smooth over a few hundred metres; per texel it would cost seconds).
//! - The drape's texels are no finer than the image's pixels on the ground nor more than
//!   [`MAX_SIDE`] a side; samples are bilinear in the image's encoded values.
//! - Where the image does not cover (beyond it, its alpha, its nodata), the procedural surface
//!   shows; coverage fades over [`FEATHER`] texels inside the image's edge, so no seam is drawn.
//!
//! Rejected: converting each pixel's position on the GPU. The shader would need every projection
//! PROJ knows; the CPU does it once per scene.

use crate::error::{Error, Result, Role};
use crate::sketch::{Atlas, Georef, Units};
use glam::DVec2;
use std::path::Path;

/// The drape's largest side in texels: 2048² RGBA is 16 MiB of GPU memory.
pub const MAX_SIDE: usize = 2048;
/// Texels between exact conversions of the image's coordinates.
pub const LATTICE: usize = 16;
/// Texels over which the image's coverage fades in from its edge.
pub const FEATHER: f64 = 6.0;

/// The image resampled onto the sketch's world grid.
#[derive(Clone, Debug)]
pub struct Drape {
    /// Texels per row (west to east).
    pub width: usize,
    /// Rows (south to north); texel (0, 0) is centred on the sketch's south-west node.
    pub height: usize,
    /// Texel size in metres.
    pub texel: DVec2,
    /// RGBA8 per texel, row 0 south; alpha is the coverage (feathered at the image's edge).
    pub rgba: Vec<u8>,
    /// The share of the sketch the image covers.
    pub covered: f64,
}

/// An image as read: RGBA8 rows from the north, and where its pixels' centres lie.
struct Picture {
    width: usize,
    height: usize,
    rgba: Vec<u8>,
    georef: Georef,
    /// The image names no coordinate system (a world file): read in the sketch's.
    in_sketch_crs: bool,
}

/// Reads the image at `path` and drapes it over `atlas`'s sketch.
pub fn drape(path: &Path, atlas: &Atlas) -> Result<Drape> {
    let picture = read(path)?;
    let Some(sketch) = atlas.georef else {
        return Err(Error::file(
            Role::Image,
            path,
            "the sketch has no georeference to place the image by (give the sketch a \
             georeferenced file)",
        ));
    };
    let sketch = sketch.resolved(atlas.width(), atlas.levels[0].height);
    let to_image =
        conversion(&picture, &sketch).map_err(|why| Error::file(Role::Image, path, why))?;
    let drape = resample(&picture, atlas, &sketch, &to_image)
        .map_err(|why| Error::file(Role::Image, path, why))?;
    if drape.covered <= 0.0 {
        return Err(Error::file(
            Role::Image,
            path,
            "the image misses the sketch entirely (check both files' coordinate systems)",
        ));
    }
    Ok(drape)
}

/// How a point in the sketch file's coordinates becomes one in the image's.
type Conversion = Box<dyn Fn([f64; 2]) -> std::result::Result<[f64; 2], String>>;

fn conversion(picture: &Picture, sketch: &Georef) -> std::result::Result<Conversion, String> {
    let image = picture.georef;
    let same = picture.in_sketch_crs
        || (image.units == sketch.units && image.epsg == sketch.epsg && image.epsg.is_some())
        || (image.units == Units::Degrees && sketch.units == Units::Degrees);
    if same {
        return Ok(Box::new(Ok));
    }
    // Both must convert through latitude and longitude; try one point now for the message.
    let (s, i) = (*sketch, image);
    let probe = s
        .to_lat_lon(s.west, s.south)
        .and_then(|[lat, lon]| i.from_lat_lon(lat, lon));
    probe.map_err(|why| {
        format!("its coordinate system cannot be converted to the sketch's: {why}")
    })?;
    Ok(Box::new(move |[x, y]| {
        let [lat, lon] = s.to_lat_lon(x, y)?;
        i.from_lat_lon(lat, lon)
    }))
}

/// The drape's grid over the sketch and each texel's colour.
fn resample(
    picture: &Picture,
    atlas: &Atlas,
    sketch: &Georef,
    to_image: &Conversion,
) -> std::result::Result<Drape, String> {
    let extent = DVec2::new(
        (atlas.width() - 1) as f64 * atlas.dx,
        (atlas.levels[0].height - 1) as f64 * atlas.dy,
    );
    let (px_x, px_y) = picture.georef.spacing_m(picture.width, picture.height);
    let pixel_m = px_x.min(px_y).max(1e-3);
    let side = |e: f64| ((e / pixel_m).ceil() as usize + 1).clamp(2, MAX_SIDE);
    let (width, height) = (side(extent.x), side(extent.y));
    let texel = extent / DVec2::new((width - 1) as f64, (height - 1) as f64);
    // The sketch file's coordinates of a world offset from the south-west node.
    let file_of = |d: DVec2| {
        [
            sketch.west + d.x / atlas.dx * sketch.cell_x,
            sketch.south + d.y / atlas.dy * sketch.cell_y,
        ]
    };
    // Image pixel coordinates (column, row from the north) on the lattice.
    let (lw, lh) = ((width - 1) / LATTICE + 2, (height - 1) / LATTICE + 2);
    let mut lattice = vec![DVec2::NAN; lw * lh];
    for j in 0..lh {
        for i in 0..lw {
            let d = DVec2::new((i * LATTICE) as f64, (j * LATTICE) as f64) * texel;
            if let Ok([x, y]) = to_image(file_of(d)) {
                lattice[j * lw + i] = pixel_of(&picture.georef, picture.height, x, y);
            }
        }
    }
    let mut rgba = vec![0u8; width * height * 4];
    let mut covered = 0usize;
    for j in 0..height {
        for i in 0..width {
            let (li, lj) = (i / LATTICE, j / LATTICE);
            let (fx, fy) = (
                (i % LATTICE) as f64 / LATTICE as f64,
                (j % LATTICE) as f64 / LATTICE as f64,
            );
            let at = |a: usize, b: usize| lattice[b * lw + a];
            let a = at(li, lj).lerp(at(li + 1, lj), fx);
            let b = at(li, lj + 1).lerp(at(li + 1, lj + 1), fx);
            let p = a.lerp(b, fy);
            if let Some(c) = sample(picture, p) {
                rgba[(j * width + i) * 4..][..4].copy_from_slice(&c);
                covered += usize::from(c[3] > 0);
            }
        }
    }
    feather(&mut rgba, width, height);
    Ok(Drape {
        width,
        height,
        texel,
        rgba,
        covered: covered as f64 / (width * height) as f64,
    })
}

/// The pixel position (column, row from the north, pixel centres at whole numbers) of a point
/// in the image's coordinates.
fn pixel_of(g: &Georef, height: usize, x: f64, y: f64) -> DVec2 {
    let north = g.south + (height as f64 - 1.0) * g.cell_y;
    DVec2::new((x - g.west) / g.cell_x, (north - y) / g.cell_y)
}

/// The image's colour at pixel position `p`, bilinear; `None` outside its pixels' centres.
fn sample(picture: &Picture, p: DVec2) -> Option<[u8; 4]> {
    let (w, h) = (picture.width, picture.height);
    if !p.is_finite() || p.x < 0.0 || p.y < 0.0 || p.x > (w - 1) as f64 || p.y > (h - 1) as f64 {
        return None;
    }
    let (i, j) = (
        (p.x as usize).min(w.saturating_sub(2)),
        (p.y as usize).min(h.saturating_sub(2)),
    );
    let (fx, fy) = (p.x - i as f64, p.y - j as f64);
    let px = |a: usize, b: usize, c: usize| {
        picture.rgba[((b.min(h - 1)) * w + a.min(w - 1)) * 4 + c] as f64
    };
    let mut out = [0u8; 4];
    for (c, o) in out.iter_mut().enumerate() {
        let top = px(i, j, c) + (px(i + 1, j, c) - px(i, j, c)) * fx;
        let bottom = px(i, j + 1, c) + (px(i + 1, j + 1, c) - px(i, j + 1, c)) * fx;
        *o = (top + (bottom - top) * fy).round().clamp(0.0, 255.0) as u8;
    }
    Some(out)
}

/// Fades the coverage (alpha) to zero over [`FEATHER`] texels inside the edge of what is
/// covered: a two-pass chamfer distance to the nearest uncovered texel.
fn feather(rgba: &mut [u8], w: usize, h: usize) {
    let far = FEATHER as f32 + 1.0;
    let mut d: Vec<f32> = (0..w * h)
        .map(|k| if rgba[k * 4 + 3] == 0 { 0.0 } else { far })
        .collect();
    // The grid's own edge counts as uncovered beyond it only where the image ends there too:
    // the sketch's edge is not the image's.
    let diagonal = std::f32::consts::SQRT_2;
    for j in 0..h {
        for i in 0..w {
            let mut v = d[j * w + i];
            if i > 0 {
                v = v.min(d[j * w + i - 1] + 1.0);
            }
            if j > 0 {
                v = v.min(d[(j - 1) * w + i] + 1.0);
                if i > 0 {
                    v = v.min(d[(j - 1) * w + i - 1] + diagonal);
                }
                if i + 1 < w {
                    v = v.min(d[(j - 1) * w + i + 1] + diagonal);
                }
            }
            d[j * w + i] = v;
        }
    }
    for j in (0..h).rev() {
        for i in (0..w).rev() {
            let mut v = d[j * w + i];
            if i + 1 < w {
                v = v.min(d[j * w + i + 1] + 1.0);
            }
            if j + 1 < h {
                v = v.min(d[(j + 1) * w + i] + 1.0);
                if i + 1 < w {
                    v = v.min(d[(j + 1) * w + i + 1] + diagonal);
                }
                if i > 0 {
                    v = v.min(d[(j + 1) * w + i - 1] + diagonal);
                }
            }
            d[j * w + i] = v;
        }
    }
    for (k, v) in d.iter().enumerate() {
        let fade = (*v as f64 / FEATHER).clamp(0.0, 1.0);
        let a = &mut rgba[k * 4 + 3];
        *a = (*a as f64 * fade).round() as u8;
    }
}

/// Reads an image file: a TIFF by the tiff crate with its GeoTIFF georeference, a PNG with its
/// world file.
fn read(path: &Path) -> Result<Picture> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .unwrap_or_default();
    match ext.as_str() {
        "tif" | "tiff" => read_tiff(path),
        "png" => read_png(path),
        _ => Err(Error::file(
            Role::Image,
            path,
            "give an RGB or RGBA GeoTIFF (.tif) or a PNG with a world file (.pgw)",
        )),
    }
}

fn read_tiff(path: &Path) -> Result<Picture> {
    use tiff::decoder::{Decoder, DecodingResult};
    let bad = |why: String| Error::file(Role::Image, path, why);
    let file = std::fs::File::open(path).map_err(|e| Error::io(Role::Image, path, e))?;
    let mut dec = Decoder::new(std::io::BufReader::new(file))
        .map_err(|e| bad(format!("not a readable TIFF: {e}")))?;
    let (w, h) = dec.dimensions().map_err(|e| bad(e.to_string()))?;
    let (w, h) = (w as usize, h as usize);
    if w < 2 || h < 2 || w.saturating_mul(h) > crate::sketch::max_cells() {
        return Err(bad(format!(
            "{w} × {h} pixels: give at least 2 × 2 and at most 2^28"
        )));
    }
    let colour = dec.colortype().map_err(|e| bad(e.to_string()))?;
    let channels = match colour {
        tiff::ColorType::RGB(8) => 3,
        tiff::ColorType::RGBA(8) => 4,
        tiff::ColorType::Gray(8) => 1,
        other => {
            return Err(bad(format!(
                "{other:?} samples: give 8-bit RGB, RGBA or grey (gdal_translate -ot Byte)"
            )));
        }
    };
    let georef = crate::sketch::tiff_georef(&mut dec, h)
        .map_err(bad)?
        .ok_or_else(|| bad("no georeference (GeoTIFF tags): it cannot be placed".into()))?;
    let DecodingResult::U8(v) = dec
        .read_image()
        .map_err(|e| bad(format!("cannot decode: {e}")))?
    else {
        return Err(bad("not 8-bit samples".into()));
    };
    if v.len() < w * h * channels {
        return Err(bad("truncated: fewer samples than its size".into()));
    }
    let rgba = v
        .chunks_exact(channels)
        .take(w * h)
        .flat_map(|p| match p {
            [g] => [*g, *g, *g, 255],
            [r, g, b] => [*r, *g, *b, 255],
            [r, g, b, a] => [*r, *g, *b, *a],
            _ => [0; 4],
        })
        .collect();
    Ok(Picture {
        width: w,
        height: h,
        rgba,
        georef: georef.resolved(w, h),
        in_sketch_crs: false,
    })
}

fn read_png(path: &Path) -> Result<Picture> {
    let bad = |why: String| Error::file(Role::Image, path, why);
    let file = std::fs::File::open(path).map_err(|e| Error::io(Role::Image, path, e))?;
    let mut decoder = png::Decoder::new(std::io::BufReader::new(file));
    decoder.set_transformations(png::Transformations::EXPAND | png::Transformations::STRIP_16);
    let mut reader = decoder
        .read_info()
        .map_err(|e| bad(format!("not a readable PNG: {e}")))?;
    let size = reader
        .output_buffer_size()
        .ok_or_else(|| bad("too large".into()))?;
    let mut buf = vec![0; size];
    let info = reader
        .next_frame(&mut buf)
        .map_err(|e| bad(format!("cannot decode: {e}")))?;
    let (w, h) = (info.width as usize, info.height as usize);
    let channels = info.color_type.samples();
    let rgba = buf[..info.buffer_size()]
        .chunks_exact(channels)
        .flat_map(|p| match p {
            [g] => [*g, *g, *g, 255],
            [g, a] => [*g, *g, *g, *a],
            [r, g, b] => [*r, *g, *b, 255],
            [r, g, b, a] => [*r, *g, *b, *a],
            _ => [0; 4],
        })
        .collect();
    let world = path.with_extension("pgw");
    let bytes = std::fs::read(&world).map_err(|_| {
        bad(format!(
            "no world file {} beside it: it cannot be placed",
            world.display()
        ))
    })?;
    let gt = crate::sketch::parse_world_file(&world, &bytes)?;
    let georef = Georef::from_geotransform(gt, h, Units::Unknown)
        .ok_or_else(|| bad("its world file is rotated; warp it north-up with gdalwarp".into()))?;
    Ok(Picture {
        width: w,
        height: h,
        rgba,
        georef,
        in_sketch_crs: true,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_feather_fades_in_from_the_edge_of_coverage() {
        let (w, h) = (32, 1);
        let mut rgba = vec![255u8; w * h * 4];
        for i in 0..4 {
            rgba[i * 4 + 3] = 0;
        }
        feather(&mut rgba, w, h);
        let alpha: Vec<u8> = rgba.chunks_exact(4).map(|p| p[3]).collect();
        assert_eq!(alpha[3], 0);
        assert!(alpha[4] > 0 && alpha[4] < alpha[6], "{alpha:?}");
        assert_eq!(alpha[4 + FEATHER as usize], 255);
        assert!(alpha.windows(2).skip(3).all(|p| p[0] <= p[1]));
    }
}
