//! A tile's bytes: the header and the zstd frame of its predicted byte planes (the rules are in
//! the module doc of [`crate::sketch::tiles`]).

use crate::error::{Error, Result, Role};
use std::path::Path;

const MAGIC: &[u8; 4] = b"TTL1";
/// Bytes before the zstd frame.
pub const HEADER_BYTES: usize = 24;
/// zstd's level: 3 is its default, the knee between ratio and speed on these planes.
const LEVEL: i32 = 3;

/// What a tile says of itself, readable without decoding it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TileHeader {
    /// Stored nodes per side, border included.
    pub side: usize,
    /// Over the interior nodes (the border repeats neighbours').
    pub min_m: f32,
    pub max_m: f32,
    /// Interior nodes that were nodata in the source and were filled (level 0 only).
    pub nodata: u32,
    /// Bytes of the zstd frame after the header.
    pub payload: usize,
}

impl TileHeader {
    /// Parses the first `HEADER_BYTES` of a tile file.
    pub fn parse(path: &Path, bytes: &[u8]) -> Result<TileHeader> {
        let bad = |why: &str| Error::file(Role::Sketch, path, format!("tile {why}"));
        if bytes.len() < HEADER_BYTES {
            return Err(bad(&format!(
                "is truncated: {} bytes, its header alone is {HEADER_BYTES}",
                bytes.len()
            )));
        }
        if &bytes[0..4] != MAGIC {
            return Err(bad(
                "does not start with TTL1: not a tile of `terrain tiles`",
            ));
        }
        let u32_at = |k: usize| u32::from_le_bytes(bytes[k..k + 4].try_into().expect("4 bytes"));
        let f32_at = |k: usize| f32::from_bits(u32_at(k));
        let header = TileHeader {
            side: u32_at(4) as usize,
            min_m: f32_at(8),
            max_m: f32_at(12),
            nodata: u32_at(16),
            payload: u32_at(20) as usize,
        };
        if !(2..=4096).contains(&header.side) {
            return Err(bad(&format!("claims a side of {} nodes", header.side)));
        }
        if !(header.min_m.is_finite() && header.max_m.is_finite() && header.min_m <= header.max_m) {
            return Err(bad("has a height range that is not finite"));
        }
        Ok(header)
    }
}

/// Encodes `side`² heights (row-major, row 0 south) with the interior statistics given.
pub fn encode_tile(
    heights: &[f32],
    side: usize,
    min_m: f32,
    max_m: f32,
    nodata: u32,
) -> Result<Vec<u8>> {
    debug_assert_eq!(heights.len(), side * side);
    let n = heights.len();
    let mut planes = vec![0u8; 4 * n];
    for (k, h) in heights.iter().enumerate() {
        // Most significant byte first: the sign and exponent plane is the most repetitive.
        for (b, byte) in h.to_bits().to_be_bytes().into_iter().enumerate() {
            planes[b * n + k] = byte;
        }
    }
    // Each plane row differenced from its west neighbour (wrapping), east to west so every
    // difference reads the original.
    for row in planes.chunks_exact_mut(side) {
        for i in (1..side).rev() {
            row[i] = row[i].wrapping_sub(row[i - 1]);
        }
    }
    let frame = compress(&planes)?;
    let mut out = Vec::with_capacity(HEADER_BYTES + frame.len());
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&(side as u32).to_le_bytes());
    out.extend_from_slice(&min_m.to_bits().to_le_bytes());
    out.extend_from_slice(&max_m.to_bits().to_le_bytes());
    out.extend_from_slice(&nodata.to_le_bytes());
    out.extend_from_slice(&(frame.len() as u32).to_le_bytes());
    out.extend_from_slice(&frame);
    Ok(out)
}

/// `bytes` as one zstd frame with its checksum, at the pyramids' level.
#[cfg(feature = "zstd")]
pub(super) fn compress(bytes: &[u8]) -> Result<Vec<u8>> {
    let mut c = zstd::bulk::Compressor::new(LEVEL).expect("zstd accepts its default level");
    c.include_checksum(true)
        .expect("zstd accepts the checksum flag");
    Ok(c.compress(bytes)
        .expect("zstd compresses into a grown buffer"))
}

/// The `4·side²` bytes of `what` (heights, pixels) one tile's zstd frame holds, or why not in
/// the words of the tile's error; the outer error is a build without zstd.
pub(super) fn decompress_tile(
    frame: &[u8],
    side: usize,
    what: &str,
) -> Result<std::result::Result<Vec<u8>, String>> {
    let n = 4 * side * side;
    Ok(match decompress(frame, n)? {
        Err(e) => Err(format!("cannot be decompressed: {e}")),
        Ok(bytes) if bytes.len() != n => Err(format!(
            "holds {} bytes of {what}; a {side}² tile holds {n}",
            bytes.len()
        )),
        Ok(bytes) => Ok(bytes),
    })
}

/// The at most `capacity` bytes of one zstd frame, or why not.
#[cfg(feature = "zstd")]
fn decompress(frame: &[u8], capacity: usize) -> Result<std::result::Result<Vec<u8>, String>> {
    Ok(zstd::bulk::decompress(frame, capacity).map_err(|e| e.to_string()))
}

/// Without zstd (a WebAssembly build: zstd is C) a pyramid's tiles can be neither written nor
/// read.
#[cfg(not(feature = "zstd"))]
pub(super) fn compress(_: &[u8]) -> Result<Vec<u8>> {
    Err(NO_ZSTD)
}

#[cfg(not(feature = "zstd"))]
fn decompress(_: &[u8], _: usize) -> Result<std::result::Result<Vec<u8>, String>> {
    Err(NO_ZSTD)
}

#[cfg(not(feature = "zstd"))]
const NO_ZSTD: Error = Error::Feature {
    what: "a tile pyramid's tiles",
    feature: "zstd",
};

/// Decodes a whole tile file: its header and `side`² finite heights.
pub fn decode_tile(path: &Path, bytes: &[u8]) -> Result<(TileHeader, Vec<f32>)> {
    let header = TileHeader::parse(path, bytes)?;
    let bad = |why: String| Error::file(Role::Sketch, path, format!("tile {why}"));
    let frame = &bytes[HEADER_BYTES..];
    if frame.len() != header.payload {
        return Err(bad(format!(
            "is truncated or padded: {} bytes of heights where its header says {}",
            frame.len(),
            header.payload
        )));
    }
    let side = header.side;
    let n = side * side;
    let mut planes = decompress_tile(frame, side, "heights")?.map_err(bad)?;
    for row in planes.chunks_exact_mut(side) {
        for i in 1..side {
            row[i] = row[i].wrapping_add(row[i - 1]);
        }
    }
    let mut heights = Vec::with_capacity(n);
    for k in 0..n {
        let h = f32::from_bits(u32::from_be_bytes([
            planes[k],
            planes[n + k],
            planes[2 * n + k],
            planes[3 * n + k],
        ]));
        if !h.is_finite() {
            return Err(bad(format!(
                "holds a height that is not finite at node {k}"
            )));
        }
        heights.push(h);
    }
    Ok((header, heights))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tile(side: usize) -> Vec<f32> {
        (0..side * side)
            .map(|k| ((k % side) as f32 * 0.37).sin() * 120.0 + (k / side) as f32 * 0.5 - 3.25)
            .collect()
    }

    #[test]
    fn a_tile_round_trips_bit_for_bit() {
        let h = tile(260);
        let bytes = encode_tile(&h, 260, -3.0, 250.0, 7).unwrap();
        let (header, back) = decode_tile(Path::new("t"), &bytes).unwrap();
        assert_eq!(header.side, 260);
        assert_eq!(header.nodata, 7);
        assert_eq!((header.min_m, header.max_m), (-3.0, 250.0));
        assert!(h.iter().zip(&back).all(|(a, b)| a.to_bits() == b.to_bits()));
    }

    #[test]
    fn damaged_tiles_are_refused_in_one_line() {
        let bytes = encode_tile(&tile(16), 16, 0.0, 1.0, 0).unwrap();
        let cut = decode_tile(Path::new("L0/0/0.tile"), &bytes[..bytes.len() - 3]).unwrap_err();
        assert!(cut.to_string().contains("truncated"), "{cut}");
        let mut flipped = bytes.clone();
        let last = flipped.len() - 8;
        flipped[last] ^= 0x40;
        let err = decode_tile(Path::new("L0/0/0.tile"), &flipped).unwrap_err();
        assert!(
            err.to_string().starts_with("sketch L0/0/0.tile: tile"),
            "{err}"
        );
        let err =
            decode_tile(Path::new("x"), b"PNG\0 not a tile at all, long enough..").unwrap_err();
        assert!(err.to_string().contains("TTL1"), "{err}");
    }

    /// The predictor earns its place: over the bundled DEM's 260² windows, the predicted byte
    /// planes against zstd on the plain f32 bytes, at the same level.
    #[test]
    fn the_byte_plane_predictor_beats_plain_zstd_on_a_real_dem() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../sketches/jacksboro_fault_dem.asc");
        let atlas = crate::sketch::Atlas::load(&path, &Default::default()).unwrap();
        let level = &atlas.levels[0];
        let side = 128;
        let (mut predicted, mut plain) = (0usize, 0usize);
        for y0 in (0..level.height - side).step_by(side) {
            for x0 in (0..level.width - side).step_by(side) {
                let window: Vec<f32> = (0..side * side)
                    .map(|k| level.data[(y0 + k / side) * level.width + x0 + k % side])
                    .collect();
                predicted += encode_tile(&window, side, 0.0, 1.0, 0).unwrap().len() - HEADER_BYTES;
                let bytes: Vec<u8> = window.iter().flat_map(|h| h.to_le_bytes()).collect();
                plain += compress(&bytes).unwrap().len();
            }
        }
        let raw = level.width / side * (level.height / side) * side * side * 4;
        eprintln!(
            "jacksboro: raw {raw} B, plain zstd {plain} B ({:.2}×), predicted planes {predicted} B ({:.2}×)",
            raw as f64 / plain as f64,
            raw as f64 / predicted as f64
        );
        assert!(
            predicted < plain,
            "predicted {predicted} B, plain {plain} B"
        );
    }
}
