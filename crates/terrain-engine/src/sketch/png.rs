//! 8/16-bit grayscale PNG. A PNG carries no heights or spacing of its own: pixel values map
//! linearly onto `sketch.height_range_m` (by default the values themselves), and the spacing and
//! position come from its world file when one lies beside it (`NAME.pgw`, `NAME.pngw` or
//! `NAME.wld`, as GDAL writes with `-co WORLDFILE=YES`), else from `sketch.spacing_m`. A
//! transparent grey (`tRNS`, GDAL's nodata for PNG) or alpha 0 is nodata.

use super::georef::{Georef, Units};
use super::{LoadOptions, RawGrid};
use crate::error::{Error, Result, Role};
use std::path::{Path, PathBuf};

/// World files are six numbers; a larger file is not one.
const MAX_WORLD_FILE_BYTES: u64 = 4096;

pub fn read_file(path: &Path, opts: &LoadOptions) -> Result<RawGrid> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(Role::Sketch, path, e))?;
    let world = match world_file(path) {
        Some(wf) => {
            let len = std::fs::metadata(&wf).map(|m| m.len()).unwrap_or(0);
            if len > MAX_WORLD_FILE_BYTES {
                return Err(Error::sketch(
                    &wf,
                    format!("world file is {len} bytes; it holds six numbers"),
                ));
            }
            let text = std::fs::read(&wf).map_err(|e| Error::io(Role::Sketch, &wf, e))?;
            Some(parse_world_file(&wf, &text)?)
        }
        None => None,
    };
    parse(path, &bytes, opts, world)
}

/// What reading the PNG at `path` with `opts` guessed about its units, as one line for the user,
/// or `None` where the scene (or a world file: `spaced`) states them. Without
/// `sketch.height_range_m` or `sketch.height_scale` its values are taken as metres (a 16-bit
/// map's 0 to 65535), and without `sketch.spacing_m` or a world file its cells as 1 m; the line
/// names what was guessed and the key that states it. A height map exported as 16-bit grey often
/// stretches its relief over the whole range, so the guess is as likely 50 km mountains on 1 m
/// cells as terrain. Asked after the file was read: its header is read again for the bit depth.
pub fn units_warning(path: &Path, opts: &LoadOptions, spaced: bool) -> Option<String> {
    let heights_given = opts.height_range_m.is_some() || opts.height_scale.is_some();
    if heights_given {
        return (!spaced).then(|| {
            format!(
                "sketch {}: its cells taken as 1 m; sketch.spacing_m or a .pgw world file \
                 gives their size",
                path.display()
            )
        });
    }
    let file = std::fs::File::open(path).ok()?;
    let decoder = png::Decoder::new(std::io::BufReader::new(file));
    let reader = decoder.read_info().ok()?;
    let bits = match reader.info().bit_depth {
        png::BitDepth::Sixteen => 16,
        _ => 8,
    };
    let top = (1u32 << bits) - 1;
    let values = format!("its {bits}-bit values taken as metres (0 to {top} m)");
    let heights = "sketch.height_range_m gives its heights in metres";
    Some(if spaced {
        format!("sketch {}: {values}; {heights}", path.display())
    } else {
        format!(
            "sketch {}: {values} on 1 m cells; {heights}, sketch.spacing_m or a .pgw world \
             file its spacing",
            path.display()
        )
    })
}

/// The world file beside a PNG, if any.
fn world_file(path: &Path) -> Option<PathBuf> {
    ["pgw", "pngw", "wld", "PGW", "PNGW", "WLD"]
        .iter()
        .map(|ext| path.with_extension(ext))
        .find(|p| p.is_file())
}

/// A world file's six lines: x size, two rotations, −y size, then the centre of the north-west
/// pixel. Returned as a geotransform (corner of the north-west pixel).
pub fn parse_world_file(path: &Path, bytes: &[u8]) -> Result<[f64; 6]> {
    let bad = |reason: String| Error::sketch(path, format!("world file {reason}"));
    let text = std::str::from_utf8(bytes).map_err(|_| bad("is not text".into()))?;
    let v: Vec<f64> = text
        .split_whitespace()
        .map(|t| {
            t.parse::<f64>()
                .map_err(|_| bad(format!("value `{t}` is not a number")))
        })
        .collect::<Result<_>>()?;
    let [a, d, b, e, c, f] = v[..] else {
        return Err(bad(format!("holds {} numbers, not 6", v.len())));
    };
    if !v.iter().all(|x| x.is_finite()) || b != 0.0 || d != 0.0 || !(a > 0.0 && e < 0.0) {
        return Err(bad(
            "is not north-up with positive cells (rotated? warp it with gdalwarp)".into(),
        ));
    }
    Ok([c - 0.5 * a, a, 0.0, f - 0.5 * e, 0.0, e])
}

pub fn parse(
    path: &Path,
    bytes: &[u8],
    opts: &LoadOptions,
    world: Option<[f64; 6]>,
) -> Result<RawGrid> {
    let bad = |reason: String| Error::sketch(path, reason);
    let mut decoder = png::Decoder::new(std::io::Cursor::new(bytes));
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
    let bytes_per = if sixteen { 2 } else { 1 };
    let max_value = if sixteen { 65535.0 } else { 255.0 };
    let [lo, hi] = opts.height_range_m.unwrap_or([0.0, max_value]);
    let stride = info.line_size;
    if buf.len() < stride * h || stride < w * channels * bytes_per {
        return Err(bad(format!("PNG rows of {stride} bytes for {w} pixels")));
    }
    let sample = |line: &[u8], k: usize| -> f64 {
        if sixteen {
            u16::from_be_bytes([line[k], line[k + 1]]) as f64
        } else {
            line[k] as f64
        }
    };
    let mut data = vec![0.0f32; w * h];
    for row in 0..h {
        let line = &buf[row * stride..(row + 1) * stride];
        for col in 0..w {
            let k = col * channels * bytes_per;
            let transparent = channels == 2 && sample(line, k + bytes_per) == 0.0;
            let v = sample(line, k);
            data[(h - 1 - row) * w + col] = if transparent {
                f32::NAN
            } else {
                (lo + (hi - lo) * v / max_value) as f32
            };
        }
    }
    let georef = world.and_then(|gt| Georef::from_geotransform(gt, h, Units::Unknown));
    Ok(RawGrid::new(w, h, data, georef))
}
