//! The ground truth's files beside an image `DIR/NAME.png` (docs/batch.md, "Ground truth"):
//! `NAME.depth.npy` and `NAME.depth.tif`, `NAME.distance.npy`, `NAME.positions.npy`,
//! `NAME.latlon.npy`, `NAME.normals.npy`, `NAME.surface.png` (indexed, its palette the legend's
//! colours) with `NAME.surface.json` (the legend), and for a flight's frame `NAME.flow.npy`,
//! `NAME.flow.flo` and `NAME.occlusion.png`.
//!
//! Rules: each file is staged with the image ([`Staged`]), so the image and its truth land
//! together or not at all; arrays are `(height, width[, channels])`, row 0 the image's top;
//! what a sketch cannot give (`latlon` without a georeference) is refused before any render.
//! Rejected: one `.npz` per image, which NumPy reads but `numpy.load` maps no part of, and which
//! image tools and GDAL do not open.

use crate::output::{Staged, npy_f32, npy_f64};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use terrain_engine::truth::{Output, SURFACE_CLASSES, Truth, class_srgb};
use terrain_engine::{Atlas, Error, Ground, Result, Role};

/// The files written for one image: output name → path (`rgb` the image itself).
pub type Written = BTreeMap<String, PathBuf>;

/// `DIR/NAME.SUFFIX` beside the image `DIR/NAME.EXT`.
pub fn beside(image: &Path, suffix: &str) -> PathBuf {
    let stem = image.file_stem().unwrap_or_default().to_string_lossy();
    image.with_file_name(format!("{stem}.{suffix}"))
}

/// The files `outputs` write beside `image` (flow's only where `flow` is true), for a resumed
/// batch to find and a killed one's temporary files to be known by.
pub fn files(image: &Path, outputs: &[Output]) -> Vec<PathBuf> {
    outputs
        .iter()
        .flat_map(|o| suffixes(*o))
        .map(|s| beside(image, s))
        .collect()
}

/// Whether `file_suffix` (what follows `NAME.`) is one of the ground truth's files.
pub fn is_truth_suffix(file_suffix: &str) -> bool {
    Output::ALL
        .iter()
        .any(|&o| suffixes(o).contains(&file_suffix))
}

fn suffixes(o: Output) -> &'static [&'static str] {
    match o {
        Output::Rgb => &[],
        Output::Depth => &["depth.npy", "depth.tif"],
        Output::Distance => &["distance.npy"],
        Output::Positions => &["positions.npy"],
        Output::Latlon => &["latlon.npy"],
        Output::Normals => &["normals.npy"],
        Output::Surface => &["surface.png", "surface.json"],
        Output::Flow => &["flow.npy", "flow.flo", "occlusion.png"],
    }
}

/// Refuses what `atlas`'s scene cannot give: `latlon` without a georeference; `flow` outside a
/// flight (`flow_allowed`); anything but depth and distance on a planet, whose positions are in
/// each camera's own tangent frame.
pub fn check(outputs: &[Output], atlas: &Atlas, planet: bool, flow_allowed: bool) -> Result<()> {
    let refuse = |why: String| {
        Err(Error::Value {
            key: "outputs",
            reason: why,
        })
    };
    for &o in outputs {
        if o == Output::Latlon && atlas.georef.is_none() {
            return refuse(
                "latlon needs a georeferenced sketch (a GeoTIFF, or a grid with a .prj); this \
                 one has none"
                    .into(),
            );
        }
        if o == Output::Flow && !flow_allowed {
            return refuse("flow is between a flight's frames: ask `terrain fly` for it".into());
        }
        if planet && !matches!(o, Output::Rgb | Output::Depth | Output::Distance) {
            return refuse(format!(
                "{o} is not written for a planet: give rgb, depth or distance"
            ));
        }
    }
    Ok(())
}

/// Stages the files of `outputs` (but flow) for `truth` beside `image`, with `classes` (the
/// frame's surface classes, where `surface` is asked for); what was staged, by output name.
pub fn stage(
    staged: &mut Staged,
    image: &Path,
    outputs: &[Output],
    truth: &Truth,
    classes: Option<&[u8]>,
    atlas: &Atlas,
    ground: &Ground,
) -> Result<Written> {
    let (w, h) = truth.size();
    let mut written = Written::new();
    written.insert(Output::Rgb.name().into(), image.to_path_buf());
    for &o in outputs {
        let first = match o {
            Output::Rgb | Output::Flow => continue,
            Output::Depth => {
                let depth = truth.depth();
                let npy = beside(image, "depth.npy");
                staged.add(&npy, &npy_f32(&[h, w], &depth))?;
                let tif = beside(image, "depth.tif");
                staged.add(&tif, &tiff_f32(&tif, w, h, &depth)?)?;
                npy
            }
            Output::Distance => add(staged, image, "distance.npy", &[h, w], &truth.distance())?,
            Output::Positions => {
                let p = beside(image, "positions.npy");
                staged.add(&p, &npy_f64(&[h, w, 4], &truth.positions))?;
                p
            }
            Output::Latlon => {
                let p = beside(image, "latlon.npy");
                staged.add(&p, &npy_f64(&[h, w, 2], &truth.latlon(atlas)?))?;
                p
            }
            Output::Normals => add(
                staged,
                image,
                "normals.npy",
                &[h, w, 3],
                &truth.normals(ground)?,
            )?,
            Output::Surface => {
                let classes = classes.ok_or(Error::Internal("surface classes not drawn"))?;
                let png = beside(image, "surface.png");
                staged.add(&png, &indexed_png(&png, w, h, classes)?)?;
                staged.add(&beside(image, "surface.json"), legend().as_bytes())?;
                png
            }
        };
        written.insert(o.name().into(), first);
    }
    Ok(written)
}

fn add(
    staged: &mut Staged,
    image: &Path,
    suffix: &str,
    shape: &[usize],
    v: &[f32],
) -> Result<PathBuf> {
    let p = beside(image, suffix);
    staged.add(&p, &npy_f32(shape, v))?;
    Ok(p)
}

/// Stages the flow from `truth` to `next` beside `image`: `.npy` (height, width, 2) with NaN on
/// sky, Middlebury's `.flo` (unknown flow 1e10 there) and the occlusion mask (255 occluded or
/// leaving the frame, 0 seen in the next frame).
pub fn stage_flow(
    staged: &mut Staged,
    image: &Path,
    truth: &Truth,
    next: &Truth,
) -> Result<Written> {
    let (w, h) = truth.size();
    let (flow, occluded) = truth.flow(next);
    add(staged, image, "flow.npy", &[h, w, 2], &flow)?;
    staged.add(&beside(image, "flow.flo"), &flo(w, h, &flow))?;
    let mask: Vec<u8> = occluded.iter().map(|&o| if o { 255 } else { 0 }).collect();
    let png = beside(image, "occlusion.png");
    staged.add(&png, &gray_png(&png, w, h, &mask)?)?;
    Ok(flow_files(image))
}

/// The files [`stage_flow`] writes beside `image`, by output name.
pub fn flow_files(image: &Path) -> Written {
    Written::from([
        (Output::Flow.name().into(), beside(image, "flow.npy")),
        ("occlusion".into(), beside(image, "occlusion.png")),
    ])
}

/// Middlebury's `.flo`: the tag 202021.25, width and height as i32, then u, v per pixel as f32,
/// little-endian; flow it does not know is above 1e9.
pub fn flo(width: usize, height: usize, flow: &[f32]) -> Vec<u8> {
    let mut b = Vec::with_capacity(12 + 4 * flow.len());
    b.extend_from_slice(&202021.25f32.to_le_bytes());
    b.extend_from_slice(&(width as i32).to_le_bytes());
    b.extend_from_slice(&(height as i32).to_le_bytes());
    for v in flow {
        let v = if v.is_finite() { *v } else { 1e10 };
        b.extend_from_slice(&v.to_le_bytes());
    }
    b
}

/// A 32-bit float single-band TIFF (GDAL and image tools read it; `inf` kept).
fn tiff_f32(path: &Path, width: usize, height: usize, v: &[f32]) -> Result<Vec<u8>> {
    let mut bytes = std::io::Cursor::new(Vec::new());
    let fail = |e: tiff::TiffError| Error::file(Role::Output, path, format!("TIFF: {e}"));
    tiff::encoder::TiffEncoder::new(&mut bytes)
        .map_err(fail)?
        .write_image::<tiff::encoder::colortype::Gray32Float>(width as u32, height as u32, v)
        .map_err(fail)?;
    Ok(bytes.into_inner())
}

/// The surface classes' legend: `{"classes": [{"index", "name", "colour"}, …]}`, `colour` the
/// palette's sRGB bytes in `NAME.surface.png`.
pub fn legend() -> String {
    let classes: Vec<serde_json::Value> = SURFACE_CLASSES
        .iter()
        .enumerate()
        .map(
            |(i, (name, _))| serde_json::json!({"index": i, "name": name, "colour": class_srgb(i)}),
        )
        .collect();
    serde_json::json!({ "classes": classes }).to_string()
}

/// An 8-bit indexed PNG of class indices, its palette the legend's colours.
fn indexed_png(path: &Path, width: usize, height: usize, v: &[u8]) -> Result<Vec<u8>> {
    let mut bytes = Vec::new();
    let fail = |e: png::EncodingError| Error::file(Role::Output, path, format!("PNG: {e}"));
    let mut enc = png::Encoder::new(&mut bytes, width as u32, height as u32);
    enc.set_color(png::ColorType::Indexed);
    enc.set_depth(png::BitDepth::Eight);
    let palette: Vec<u8> = (0..SURFACE_CLASSES.len()).flat_map(class_srgb).collect();
    enc.set_palette(palette);
    let mut w = enc.write_header().map_err(fail)?;
    w.write_image_data(v).map_err(fail)?;
    w.finish().map_err(fail)?;
    Ok(bytes)
}

/// An 8-bit grey PNG.
fn gray_png(path: &Path, width: usize, height: usize, v: &[u8]) -> Result<Vec<u8>> {
    let mut bytes = Vec::new();
    let fail = |e: png::EncodingError| Error::file(Role::Output, path, format!("PNG: {e}"));
    let mut enc = png::Encoder::new(&mut bytes, width as u32, height as u32);
    enc.set_color(png::ColorType::Grayscale);
    enc.set_depth(png::BitDepth::Eight);
    let mut w = enc.write_header().map_err(fail)?;
    w.write_image_data(v).map_err(fail)?;
    w.finish().map_err(fail)?;
    Ok(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn files_sit_beside_the_image_under_its_stem() {
        let image = Path::new("out/shots/north-ridge.png");
        assert_eq!(
            files(image, &[Output::Rgb, Output::Depth, Output::Flow]),
            [
                "out/shots/north-ridge.depth.npy",
                "out/shots/north-ridge.depth.tif",
                "out/shots/north-ridge.flow.npy",
                "out/shots/north-ridge.flow.flo",
                "out/shots/north-ridge.occlusion.png",
            ]
            .map(PathBuf::from)
        );
    }

    #[test]
    fn flo_is_middleburys_layout() {
        let b = flo(2, 1, &[1.5, -2.0, f32::NAN, 0.25]);
        assert_eq!(&b[..4], b"PIEH");
        assert_eq!(i32::from_le_bytes(b[4..8].try_into().unwrap()), 2);
        assert_eq!(i32::from_le_bytes(b[8..12].try_into().unwrap()), 1);
        let f = |k: usize| f32::from_le_bytes(b[12 + 4 * k..16 + 4 * k].try_into().unwrap());
        assert_eq!((f(0), f(1), f(3)), (1.5, -2.0, 0.25));
        assert!(f(2) > 1e9, "unknown flow");
    }
}
