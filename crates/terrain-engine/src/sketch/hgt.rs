//! SRTM `.hgt`, bare or zipped (`N36W084.hgt.zip`, as USGS and OpenTopography ship them): a square
//! of big-endian i16 heights, rows north first, −32768 for voids. The size tells the resolution
//! (1201² for 3″, 3601² for 1″); the name tells the south-west node (`N36W084`: 36° N, 84° W), so
//! tiles of a glob line up and share their edge rows as the format intends.
//!
//! Rules: a zip is opened only to find one `.hgt` entry whose stated size is a tile's; that many
//! bytes and no more are inflated, so a damaged or hostile archive costs at most one tile.

use super::RawGrid;
use super::georef::{Georef, Units};
use crate::error::{Error, Result, Role};
use std::io::Read;
use std::path::Path;

const VOID: i16 = -32768;
const TILE_3S: usize = 1201 * 1201 * 2;
const TILE_1S: usize = 3601 * 3601 * 2;

/// `spacing_given`: the scene sets the spacing, so a name without a latitude is no error.
pub fn read_file(path: &Path, spacing_given: bool) -> Result<RawGrid> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(Role::Sketch, path, e))?;
    parse(path, &bytes, spacing_given)
}

/// A `.hgt.zip`: the one `.hgt` inside, named for its corner (or named by the zip).
pub fn read_zip_file(path: &Path, spacing_given: bool) -> Result<RawGrid> {
    let file = std::fs::File::open(path).map_err(|e| Error::io(Role::Sketch, path, e))?;
    parse_zip(path, std::io::BufReader::new(file), spacing_given)
}

pub fn parse_zip<R: Read + std::io::Seek>(
    path: &Path,
    reader: R,
    spacing_given: bool,
) -> Result<RawGrid> {
    let bad = |reason: String| Error::sketch(path, reason);
    let mut zip = zip::ZipArchive::new(reader)
        .map_err(|e| Error::decode(Role::Sketch, path, "not a readable zip", e))?;
    let names: Vec<String> = zip
        .file_names()
        .filter_map(|n| n.ok())
        .filter(|n| n.to_ascii_lowercase().ends_with(".hgt"))
        .map(|n| n.into_owned())
        .collect();
    let [name] = names.as_slice() else {
        return Err(bad(format!(
            "zip holds {} `.hgt` files; a tile's zip holds one",
            names.len()
        )));
    };
    let mut entry = zip
        .by_name(name)
        .map_err(|e| Error::decode(Role::Sketch, path, "zip entry unreadable", e))?;
    let size = entry.size();
    if size != TILE_3S as u64 && size != TILE_1S as u64 {
        return Err(bad(format!(
            "`{name}` in the zip is {size} bytes, neither a 3″ tile ({TILE_3S}) nor a 1″ tile ({TILE_1S})"
        )));
    }
    let mut bytes = Vec::with_capacity(size as usize);
    (&mut entry)
        .take(size)
        .read_to_end(&mut bytes)
        .map_err(|e| Error::decode(Role::Sketch, path, "corrupt or truncated zip entry", e))?;
    // The entry's own name carries the corner; the zip's name stands in when it does not.
    let inner = Path::new(name);
    let named = if tile_corner(inner).is_some() {
        inner
    } else {
        path
    };
    parse_named(path, named, &bytes, spacing_given)
}

pub fn parse(path: &Path, bytes: &[u8], spacing_given: bool) -> Result<RawGrid> {
    parse_named(path, path, bytes, spacing_given)
}

/// `path` is named in errors, `named` tells the tile's corner.
fn parse_named(path: &Path, named: &Path, bytes: &[u8], spacing_given: bool) -> Result<RawGrid> {
    let (side, arcsec) = match bytes.len() {
        TILE_3S => (1201, 3.0),
        TILE_1S => (3601, 1.0),
        n => {
            return Err(Error::sketch(
                path,
                format!(
                    "{n} bytes is neither a 3″ tile ({TILE_3S}) nor a 1″ tile ({TILE_1S}); truncated?"
                ),
            ));
        }
    };
    let (lat, lon) = match tile_corner(named) {
        Some(c) => c,
        // The spacing computed here is replaced by the scene's.
        None if spacing_given => (0.0, 0.0),
        None => {
            return Err(Error::sketch(
                path,
                "cannot tell the tile's corner: name it like N36W084.hgt (or set sketch.spacing_m)",
            ));
        }
    };
    let mut data = vec![0.0f32; side * side];
    for (k, pair) in bytes.chunks_exact(2).enumerate() {
        let v = i16::from_be_bytes([pair[0], pair[1]]);
        let (col, row_from_north) = (k % side, k / side);
        data[(side - 1 - row_from_north) * side + col] =
            if v == VOID { f32::NAN } else { v as f32 };
    }
    let cell = arcsec / 3600.0;
    let georef = Georef {
        west: lon,
        south: lat,
        cell_x: cell,
        cell_y: cell,
        units: Units::Degrees,
        epsg: None,
    };
    Ok(RawGrid::georeferenced(side, side, data, georef))
}

/// Latitude and longitude of the south-west node from a name like `N36W084` or `s12e130`.
fn tile_corner(path: &Path) -> Option<(f64, f64)> {
    let name = path.file_name()?.to_str()?.to_ascii_uppercase();
    let b = name.as_bytes();
    let sign = |c: u8, pos: u8, neg: u8| match c {
        c if c == pos => Some(1.0),
        c if c == neg => Some(-1.0),
        _ => None,
    };
    let lat_sign = sign(*b.first()?, b'N', b'S')?;
    let lat_digits = name[1..].bytes().take_while(u8::is_ascii_digit).count();
    let lat: f64 = name.get(1..1 + lat_digits)?.parse().ok()?;
    let rest = &name[1 + lat_digits..];
    let lon_sign = sign(*rest.as_bytes().first()?, b'E', b'W')?;
    let lon_digits = rest[1..].bytes().take_while(u8::is_ascii_digit).count();
    let lon: f64 = rest.get(1..1 + lon_digits)?.parse().ok()?;
    (lat <= 90.0 && lon <= 180.0).then_some((lat_sign * lat, lon_sign * lon))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn corner_from_tile_names() {
        assert_eq!(tile_corner(Path::new("a/N36W084.hgt")), Some((36.0, -84.0)));
        assert_eq!(
            tile_corner(Path::new("s12e130.hgt.zip")),
            Some((-12.0, 130.0))
        );
        assert_eq!(tile_corner(Path::new("tile.hgt")), None);
        assert_eq!(tile_corner(Path::new("N36.hgt")), None);
    }
}
