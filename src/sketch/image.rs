//! Raster height maps: 8/16-bit grayscale PNG (no spacing or heights of its own: the scene gives
//! `sketch.spacing_m` and `sketch.height_range_m`) and integer or float TIFF (GeoTIFF pixel scale,
//! tie point and GDAL nodata tags honoured when present).

use super::{LoadOptions, RawGrid, degrees_to_metres};
use crate::error::{Error, Result, Role};
use std::io::BufReader;
use std::path::Path;
use tiff::decoder::{Decoder, DecodingResult};
use tiff::tags::Tag;

pub fn read_png(path: &Path, opts: &LoadOptions) -> Result<RawGrid> {
    let bad = |reason: String| Error::sketch(path, reason);
    let file = std::fs::File::open(path).map_err(|e| Error::io(Role::Sketch, path, e))?;
    let mut decoder = png::Decoder::new(BufReader::new(file));
    decoder.set_transformations(png::Transformations::EXPAND);
    let mut reader = decoder
        .read_info()
        .map_err(|e| Error::decode(Role::Sketch, path, "not a readable PNG", e))?;
    let (w, h) = (reader.info().width, reader.info().height);
    let (w, h) = RawGrid::check_size(path, w as i64, h as i64)?;
    let size = reader
        .output_buffer_size()
        .ok_or_else(|| bad("PNG too large".into()))?;
    let mut buf = vec![0u8; size];
    let info = reader
        .next_frame(&mut buf)
        .map_err(|e| Error::decode(Role::Sketch, path, "corrupt or truncated PNG", e))?;
    let channels = match info.color_type {
        png::ColorType::Grayscale => 1,
        png::ColorType::GrayscaleAlpha => 2,
        other => {
            return Err(bad(format!(
                "PNG is {other:?}; a height map must be 8- or 16-bit grayscale"
            )));
        }
    };
    let sixteen = info.bit_depth == png::BitDepth::Sixteen;
    let max_value = if sixteen { 65535.0 } else { 255.0 };
    let [lo, hi] = opts.height_range_m.unwrap_or([0.0, max_value]);
    let stride = info.line_size;
    let mut data = vec![0.0f32; w * h];
    for row in 0..h {
        let line = &buf[row * stride..(row + 1) * stride];
        for col in 0..w {
            let v = if sixteen {
                let k = col * channels * 2;
                u16::from_be_bytes([line[k], line[k + 1]]) as f64
            } else {
                line[col * channels] as f64
            };
            data[(h - 1 - row) * w + col] = (lo + (hi - lo) * v / max_value) as f32;
        }
    }
    Ok(RawGrid {
        width: w,
        height: h,
        dx: 1.0,
        dy: 1.0,
        data,
    })
}

pub fn read_tiff(path: &Path) -> Result<RawGrid> {
    let bad = |reason: String| Error::sketch(path, reason);
    let file = std::fs::File::open(path).map_err(|e| Error::io(Role::Sketch, path, e))?;
    let tiff = |what: &'static str| move |e| Error::decode(Role::Sketch, path, what, e);
    let mut dec = Decoder::new(BufReader::new(file)).map_err(tiff("not a readable TIFF"))?;
    let (w, h) = dec.dimensions().map_err(tiff("TIFF has no dimensions"))?;
    let (w, h) = RawGrid::check_size(path, w as i64, h as i64)?;
    match dec.colortype() {
        Ok(tiff::ColorType::Gray(_)) => {}
        Ok(other) => {
            return Err(bad(format!(
                "TIFF is {other:?}; a height map has one channel"
            )));
        }
        Err(e) => return Err(tiff("TIFF colour type unreadable")(e)),
    }
    let nodata: Option<f64> = dec
        .get_tag_ascii_string(Tag::GdalNodata)
        .ok()
        .and_then(|s| s.trim_matches(char::from(0)).trim().parse().ok());
    let scale = dec.get_tag_f64_vec(Tag::ModelPixelScaleTag).ok();
    let tie = dec.get_tag_f64_vec(Tag::ModelTiepointTag).ok();
    let image = dec
        .read_image()
        .map_err(tiff("corrupt or truncated TIFF"))?;
    let values: Vec<f64> = match image {
        DecodingResult::U8(v) => v.into_iter().map(f64::from).collect(),
        DecodingResult::U16(v) => v.into_iter().map(f64::from).collect(),
        DecodingResult::U32(v) => v.into_iter().map(f64::from).collect(),
        DecodingResult::U64(v) => v.into_iter().map(|x| x as f64).collect(),
        DecodingResult::I8(v) => v.into_iter().map(f64::from).collect(),
        DecodingResult::I16(v) => v.into_iter().map(f64::from).collect(),
        DecodingResult::I32(v) => v.into_iter().map(f64::from).collect(),
        DecodingResult::I64(v) => v.into_iter().map(|x| x as f64).collect(),
        DecodingResult::F16(v) => v.into_iter().map(|x| x.to_f64()).collect(),
        DecodingResult::F32(v) => v.into_iter().map(f64::from).collect(),
        DecodingResult::F64(v) => v,
    };
    if values.len() != w * h {
        return Err(bad(format!(
            "TIFF holds {} samples for {w}×{h}",
            values.len()
        )));
    }
    let mut data = vec![0.0f32; w * h];
    for (k, v) in values.into_iter().enumerate() {
        let missing = !v.is_finite() || nodata.is_some_and(|nd| v == nd);
        data[(h - 1 - k / w) * w + k % w] = if missing { f32::NAN } else { v as f32 };
    }
    let (dx, dy) = match scale.as_deref() {
        Some([sx, sy, ..]) if *sx > 0.0 && *sy > 0.0 => {
            // Cells under 0.1 with a tie point inside latitude range are degrees.
            let top_lat = tie.as_deref().and_then(|t| t.get(4).copied());
            match top_lat {
                Some(lat) if *sx < 0.1 && lat.abs() <= 90.0 => {
                    degrees_to_metres(*sx, *sy, lat - 0.5 * sy * h as f64)
                }
                _ => (*sx, *sy),
            }
        }
        _ => (1.0, 1.0),
    };
    Ok(RawGrid {
        width: w,
        height: h,
        dx,
        dy,
        data,
    })
}
