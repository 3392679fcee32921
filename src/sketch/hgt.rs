//! SRTM `.hgt`: a square of big-endian i16 heights, rows north first, −32768 for voids. The size
//! tells the resolution (1201² for 3″, 3601² for 1″); the file name (`N36W084.hgt`) tells the
//! south-west corner, whose latitude converts the arc-second cells to metres.

use super::{RawGrid, degrees_to_metres};
use crate::error::{Error, Result, Role};
use std::path::Path;

const VOID: i16 = -32768;

/// `spacing_given`: the scene sets the spacing, so a name without a latitude is no error.
pub fn read(path: &Path, spacing_given: bool) -> Result<RawGrid> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(Role::Sketch, path, e))?;
    let (side, arcsec) = match bytes.len() {
        n if n == 1201 * 1201 * 2 => (1201, 3.0),
        n if n == 3601 * 3601 * 2 => (3601, 1.0),
        n => {
            return Err(Error::sketch(
                path,
                format!(
                    "{n} bytes is neither a 3″ tile (2884802) nor a 1″ tile (25934402); truncated?"
                ),
            ));
        }
    };
    let lat = match tile_latitude(path) {
        Some(lat) => lat,
        // The spacing computed here is replaced by the scene's.
        None if spacing_given => 0.0,
        None => {
            return Err(Error::sketch(
                path,
                "cannot tell the tile's latitude: name it like N36W084.hgt (or set sketch.spacing_m)",
            ));
        }
    };
    let cell = arcsec / 3600.0;
    let (dx, dy) = degrees_to_metres(cell, cell, lat + 0.5);
    let mut data = vec![0.0f32; side * side];
    for (k, pair) in bytes.chunks_exact(2).enumerate() {
        let v = i16::from_be_bytes([pair[0], pair[1]]);
        let (col, row_from_north) = (k % side, k / side);
        data[(side - 1 - row_from_north) * side + col] =
            if v == VOID { f32::NAN } else { v as f32 };
    }
    Ok(RawGrid {
        width: side,
        height: side,
        dx,
        dy,
        data,
    })
}

/// Latitude of the south-west corner from a name like `N36W084` or `s12e130`.
fn tile_latitude(path: &Path) -> Option<f64> {
    let stem = path.file_stem()?.to_str()?.to_ascii_uppercase();
    let sign = match stem.as_bytes().first()? {
        b'N' => 1.0,
        b'S' => -1.0,
        _ => return None,
    };
    let digits: String = stem[1..]
        .chars()
        .take_while(|c| c.is_ascii_digit())
        .collect();
    let lat: f64 = digits.parse().ok()?;
    (lat <= 90.0).then_some(sign * lat)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn latitude_from_tile_names() {
        assert_eq!(tile_latitude(Path::new("a/N36W084.hgt")), Some(36.0));
        assert_eq!(tile_latitude(Path::new("s12e130.hgt")), Some(-12.0));
        assert_eq!(tile_latitude(Path::new("tile.hgt")), None);
    }
}
