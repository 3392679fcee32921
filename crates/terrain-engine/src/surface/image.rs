//! A user's imagery draped over the ground (`surface.image`): an RGB, RGBA or grey GeoTIFF (or
//! COG), a PNG or JPEG with a world file, or an image pyramid's folder (`terrain tiles`),
//! resampled once onto a grid of the sketch's world metres that the shading samples per pixel.
//!
//! Rules:
//! - The image is placed by its georeference through the sketch's coordinate system: world
//!   metres → the sketch file's coordinates → latitude and longitude → the image's coordinates,
//!   the conversion `lat_deg`/`lon_deg` cameras use. Where both name the same system, the
//!   coordinates pass straight through; a world file names none and is read in the sketch's.
//! - The conversion is exact on a lattice every [`LATTICE`] texels and bilinear between (a
//!   projection is smooth over a few hundred metres; per texel it would cost seconds).
//! - The drape's texels are no finer than the image's pixels on the ground nor more than
//!   [`MAX_SIDE`] a side; samples are bilinear in the image's encoded values.
//! - From a pyramid, one level is read: the one whose pixels are nearest the drape's texels in
//!   octaves, and of it only the tiles under the lattice's pixels and a margin of two, so a
//!   drape reads about 2 · [`MAX_SIDE`]² pixels whatever the image's size (more where the
//!   image's grid is turned against the sketch's). On level 0 the drape equals the one of the
//!   image read whole, texel for texel.
//! - Where the image does not cover (beyond it, its alpha, its nodata), the procedural surface
//!   shows; coverage fades over [`FEATHER`] texels inside the image's edge, so no seam is drawn.
//!
//! Rejected: converting each pixel's position on the GPU. The shader would need every projection
//! PROJ knows; the CPU does it once per scene.

use super::picture::{self, Picture, Source};
use crate::error::{Error, Result, Role};
use crate::sketch::tiles::ImagePyramid;
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

/// Reads the image at `path` (a file, or an image pyramid's folder) and drapes it over
/// `atlas`'s sketch.
pub fn drape(path: &Path, atlas: &Atlas) -> Result<Drape> {
    let source = picture::open(path)?;
    let Some(sketch) = atlas.georef else {
        return Err(Error::file(
            Role::Image,
            path,
            "the sketch has no georeference to place the image by (give the sketch a \
             georeferenced file)",
        ));
    };
    let bad = |why: String| Error::file(Role::Image, path, why);
    let sketch = sketch.resolved(atlas.width(), atlas.levels[0].height);
    let (georef, in_sketch_crs, (w, h)) = match &source {
        Source::Whole(p) => (p.georef, p.in_sketch_crs, (p.width, p.height)),
        Source::Pyramid(p) => (p.georef(0), false, (p.meta.width, p.meta.height)),
    };
    let to_image = conversion(georef, in_sketch_crs, &sketch).map_err(bad)?;
    let (px_x, px_y) = georef.spacing_m(w, h);
    let pixel_m = px_x.min(px_y).max(1e-3);
    let grid = Grid::over(atlas, pixel_m);
    let lattice = grid.lattice(atlas, &sketch, &to_image);
    let picture = match source {
        Source::Whole(p) => Some(p),
        Source::Pyramid(p) => {
            let l = level_for(grid.texel.min_element(), pixel_m, p.meta.levels.len());
            window(&p, l, &lattice)?
        }
    };
    let drape = match picture {
        Some(picture) => grid.sample(&picture, &lattice),
        None => grid.empty(),
    };
    if drape.covered <= 0.0 {
        return Err(bad(
            "the image misses the sketch entirely (check both files' coordinate systems)".into(),
        ));
    }
    Ok(drape)
}

/// How a point in the sketch file's coordinates becomes one in the image's.
type Conversion = Box<dyn Fn([f64; 2]) -> std::result::Result<[f64; 2], String>>;

/// The conversion into an image placed by `image` (`in_sketch_crs`: a world file's, naming no
/// system).
fn conversion(
    image: Georef,
    in_sketch_crs: bool,
    sketch: &Georef,
) -> std::result::Result<Conversion, String> {
    let same = in_sketch_crs
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

/// The pyramid level whose pixels are nearest the drape's texels, in octaves (the level a GPU's
/// nearest mip filter takes): `texel_m` and level 0's `pixel_m` on the ground.
fn level_for(texel_m: f64, pixel_m: f64, levels: usize) -> usize {
    let octaves = (texel_m / pixel_m).log2().round();
    if octaves.is_finite() && octaves > 0.0 {
        (octaves as usize).min(levels - 1)
    } else {
        0
    }
}

/// The pixels of pyramid level `l` under the lattice (the image coordinates the drape samples
/// between), and a margin of two for the bilinear taps: the tiles under the sketch alone.
/// `None` where the lattice misses the level.
fn window(p: &ImagePyramid, l: usize, lattice: &Lattice) -> Result<Option<Picture>> {
    let g = p.georef(l);
    let [lw, lh] = p.meta.levels[l];
    let (mut lo, mut hi) = (DVec2::INFINITY, DVec2::NEG_INFINITY);
    for q in lattice.points.iter().filter(|q| q.is_finite()) {
        let px = pixel_of(&g, *q);
        lo = lo.min(px);
        hi = hi.max(px);
    }
    let (w, h) = ((lw - 1) as f64, (lh - 1) as f64);
    if !(lo.x <= w && lo.y <= h && hi.x >= 0.0 && hi.y >= 0.0) {
        return Ok(None);
    }
    let first = |v: f64| (v.floor() - 2.0).max(0.0) as usize;
    let end = |v: f64, n: usize| ((v.ceil() + 3.0).max(0.0) as usize).min(n);
    let (x0, y0) = (first(lo.x), first(lo.y));
    let (x1, y1) = (end(hi.x, lw), end(hi.y, lh));
    let (ww, wh) = (x1 - x0, y1 - y0);
    if ww.saturating_mul(wh) > crate::sketch::max_cells() {
        return Err(Error::file(
            Role::Image,
            &p.dir,
            format!("level {l}'s window under the sketch is {ww} × {wh} pixels: too many to hold"),
        ));
    }
    Ok(Some(Picture {
        width: ww,
        height: wh,
        rgba: p.window(l, x0, y0, ww, wh)?,
        georef: g,
        in_sketch_crs: false,
        origin: [x0, y0],
    }))
}

/// The drape's grid over the sketch: texel (0, 0) on its south-west node.
struct Grid {
    width: usize,
    height: usize,
    texel: DVec2,
}

/// The image coordinates of every [`LATTICE`]-th texel, `lw` × `lh` of them (NaN where the
/// conversion failed).
struct Lattice {
    lw: usize,
    points: Vec<DVec2>,
}

impl Grid {
    /// Texels no finer than `pixel_m` nor more than [`MAX_SIDE`] a side.
    fn over(atlas: &Atlas, pixel_m: f64) -> Grid {
        let extent = DVec2::new(
            (atlas.width() - 1) as f64 * atlas.dx,
            (atlas.levels[0].height - 1) as f64 * atlas.dy,
        );
        let side = |e: f64| ((e / pixel_m).ceil() as usize + 1).clamp(2, MAX_SIDE);
        let (width, height) = (side(extent.x), side(extent.y));
        let texel = extent / DVec2::new((width - 1) as f64, (height - 1) as f64);
        Grid {
            width,
            height,
            texel,
        }
    }

    fn lattice(&self, atlas: &Atlas, sketch: &Georef, to_image: &Conversion) -> Lattice {
        // The sketch file's coordinates of a world offset from the south-west node.
        let file_of = |d: DVec2| {
            [
                sketch.west + d.x / atlas.dx * sketch.cell_x,
                sketch.south + d.y / atlas.dy * sketch.cell_y,
            ]
        };
        let (lw, lh) = (
            (self.width - 1) / LATTICE + 2,
            (self.height - 1) / LATTICE + 2,
        );
        let mut points = vec![DVec2::NAN; lw * lh];
        for j in 0..lh {
            for i in 0..lw {
                let d = DVec2::new((i * LATTICE) as f64, (j * LATTICE) as f64) * self.texel;
                if let Ok([x, y]) = to_image(file_of(d)) {
                    points[j * lw + i] = DVec2::new(x, y);
                }
            }
        }
        Lattice { lw, points }
    }

    /// Each texel's colour from `picture`, its coverage feathered.
    fn sample(&self, picture: &Picture, lattice: &Lattice) -> Drape {
        let (width, height, lw) = (self.width, self.height, lattice.lw);
        // Pixel positions on the lattice: affine in the image's coordinates, so interpolating
        // them is interpolating the coordinates.
        let pixels: Vec<DVec2> = lattice
            .points
            .iter()
            .map(|q| pixel_of(&picture.georef, *q))
            .collect();
        let mut rgba = vec![0u8; width * height * 4];
        let mut covered = 0usize;
        for j in 0..height {
            for i in 0..width {
                let (li, lj) = (i / LATTICE, j / LATTICE);
                let (fx, fy) = (
                    (i % LATTICE) as f64 / LATTICE as f64,
                    (j % LATTICE) as f64 / LATTICE as f64,
                );
                let at = |a: usize, b: usize| pixels[b * lw + a];
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
        Drape {
            width,
            height,
            texel: self.texel,
            rgba,
            covered: covered as f64 / (width * height) as f64,
        }
    }

    /// A drape that covers nothing.
    fn empty(&self) -> Drape {
        Drape {
            width: self.width,
            height: self.height,
            texel: self.texel,
            rgba: vec![0; self.width * self.height * 4],
            covered: 0.0,
        }
    }
}

/// The pixel position (column, row from the south, pixel centres at whole numbers) of a point
/// in the image's coordinates, on the level `g` places.
fn pixel_of(g: &Georef, q: DVec2) -> DVec2 {
    DVec2::new((q.x - g.west) / g.cell_x, (q.y - g.south) / g.cell_y)
}

/// The picture's colour at its level's pixel position `p`, bilinear; `None` outside its pixels'
/// centres.
fn sample(picture: &Picture, p: DVec2) -> Option<[u8; 4]> {
    let (w, h) = (picture.width, picture.height);
    let [x0, y0] = picture.origin.map(|v| v as f64);
    let inside = p.x >= x0 && p.y >= y0 && p.x <= x0 + (w - 1) as f64 && p.y <= y0 + (h - 1) as f64;
    if !(p.is_finite() && inside) {
        return None;
    }
    // The tap's index on the level, then within the picture: the same weights whichever part
    // of the level the picture holds.
    let [ox, oy] = picture.origin;
    let (i, j) = (
        (p.x as usize).min(ox + w.saturating_sub(2)),
        (p.y as usize).min(oy + h.saturating_sub(2)),
    );
    let (fx, fy) = (p.x - i as f64, p.y - j as f64);
    let (i, j) = (i - ox, j - oy);
    let px = |a: usize, b: usize, c: usize| {
        picture.rgba[((b.min(h - 1)) * w + a.min(w - 1)) * 4 + c] as f64
    };
    let mut out = [0u8; 4];
    for (c, o) in out.iter_mut().enumerate() {
        let south = px(i, j, c) + (px(i + 1, j, c) - px(i, j, c)) * fx;
        let north = px(i, j + 1, c) + (px(i + 1, j + 1, c) - px(i, j + 1, c)) * fx;
        *o = (south + (north - south) * fy).round().clamp(0.0, 255.0) as u8;
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
