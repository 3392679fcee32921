//! The program's outputs: images by extension, CSV rows, `.npy`, each written atomically and
//! several together through [`terrain_engine::io`] (re-exported here).
//!
//! Rules:
//! - Every writer creates the output's folder first: `-o out/x.png` on a fresh clone, where `out/`
//!   does not exist, works like every `--out-dir`.
//! - An image's format comes from its extension (`.png`, `.jpg`/`.jpeg`); any other extension is
//!   refused before anything is rendered, never written as PNG bytes under a foreign name.
//! - A command with several outputs stages them all ([`Staged`], [`add_image`]) and renames them
//!   into place only once every one is written, so when one fails none is left behind.
//!
//! CSV goes through the csv crate (rows as serde structs, so a header cannot drift from its
//! cells). `.npy` is written by hand, 20 lines: npyz (0.8) writes the shape as `(32, 48, 4, )`,
//! which NumPy reads but never writes, so files would differ from `numpy.save`'s and from what
//! scripts that read the header text expect (the tests among them).

use crate::progress::Progress;
use std::io::Write;
use std::path::Path;
pub use terrain_engine::io::{Staged, create_folder, create_parent, write_atomic};
use terrain_engine::{Error, Result, Role};

/// Images above this many pixels show their encoding's progress.
const PROGRESS_PIXELS: u64 = 8 << 20;

/// An image file format, chosen by the output's extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageFormat {
    Png,
    /// Baseline JPEG at quality 92 (the alpha channel, always opaque in renders, is dropped).
    Jpeg,
}

impl ImageFormat {
    /// The format `path`'s extension names, or a one-line refusal naming the output.
    pub fn of(path: &Path) -> Result<ImageFormat> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        match ext.as_deref() {
            Some("png") => Ok(ImageFormat::Png),
            Some("jpg" | "jpeg") => Ok(ImageFormat::Jpeg),
            Some(e) => Err(Error::file(
                Role::Output,
                path,
                format!("cannot write `.{e}` images: give a .png or .jpg file name"),
            )),
            None => Err(Error::file(
                Role::Output,
                path,
                "no extension: give a .png or .jpg file name",
            )),
        }
    }
}

/// Encodes an image in the format of `path`'s extension and stages it.
pub fn add_image(
    staged: &mut Staged,
    path: &Path,
    width: u32,
    height: u32,
    rgba: &[u8],
) -> Result<()> {
    let bytes = encode_image(path, width, height, rgba)?;
    staged.add(path, &bytes)
}

/// Encodes 8-bit RGBA pixels in the format `path` names (PNG or JPEG).
pub fn encode_image(path: &Path, width: u32, height: u32, rgba: &[u8]) -> Result<Vec<u8>> {
    let fail = |e: &dyn std::fmt::Display| Error::file(Role::Output, path, e.to_string());
    let pixels = width as u64 * height as u64;
    let mut progress = (pixels > PROGRESS_PIXELS).then(|| {
        let name = path.file_name().unwrap_or_default().to_string_lossy();
        Progress::new(&format!("encoding {name}"), height as f64)
    });
    let mut bytes = Vec::new();
    match ImageFormat::of(path)? {
        ImageFormat::Png => {
            let mut enc = png::Encoder::new(&mut bytes, width, height);
            enc.set_color(png::ColorType::Rgba);
            enc.set_depth(png::BitDepth::Eight);
            // High compression costs 3–4× the time of Balanced for ~5 % smaller files: worth it for
            // a snapshot, not for a picture of hundreds of megapixels.
            enc.set_compression(if pixels > PROGRESS_PIXELS {
                png::Compression::Balanced
            } else {
                png::Compression::High
            });
            let mut w = enc.write_header().map_err(|e| fail(&e))?;
            let mut stream = w.stream_writer().map_err(|e| fail(&e))?;
            let row = width as usize * 4;
            let rows_per_chunk = (1 << 20) / row.max(1) + 1;
            for chunk in rgba.chunks(row * rows_per_chunk) {
                stream.write_all(chunk).map_err(|e| fail(&e))?;
                if let Some(p) = &mut progress {
                    p.advance((chunk.len() / row) as f64, "rows");
                }
            }
            stream.finish().map_err(|e| fail(&e))?;
        }
        ImageFormat::Jpeg => {
            let rgb: Vec<u8> = rgba
                .chunks_exact(4)
                .flat_map(|p| [p[0], p[1], p[2]])
                .collect();
            image::codecs::jpeg::JpegEncoder::new_with_quality(&mut bytes, 92)
                .encode(&rgb, width, height, image::ExtendedColorType::Rgb8)
                .map_err(|e| fail(&e))?;
            if let Some(p) = &mut progress {
                p.advance(height as f64, "rows");
            }
        }
    }
    if let Some(p) = progress {
        p.finish();
    }
    Ok(bytes)
}

/// Encodes 8-bit RGBA pixels (PNG or JPEG, by the extension) and writes them atomically.
pub fn write_image(path: &Path, width: u32, height: u32, rgba: &[u8]) -> Result<()> {
    let bytes = encode_image(path, width, height, rgba)?;
    write_atomic(path, &bytes)
}

/// `values` (row-major, of `shape`) as a NumPy `.npy` file of little-endian f64, byte for byte
/// what `numpy.save` writes for that array.
pub fn npy_f64(shape: &[usize], values: &[f64]) -> Vec<u8> {
    npy(
        "<f8",
        shape,
        values.iter().flat_map(|v| v.to_le_bytes()),
        values.len(),
    )
}

/// As [`npy_f64`], of f32.
pub fn npy_f32(shape: &[usize], values: &[f32]) -> Vec<u8> {
    npy(
        "<f4",
        shape,
        values.iter().flat_map(|v| v.to_le_bytes()),
        values.len(),
    )
}

fn npy(descr: &str, shape: &[usize], data: impl Iterator<Item = u8>, count: usize) -> Vec<u8> {
    debug_assert_eq!(shape.iter().product::<usize>(), count);
    let dims: Vec<String> = shape.iter().map(|d| d.to_string()).collect();
    let tuple = if dims.len() == 1 {
        format!("({},)", dims[0])
    } else {
        format!("({})", dims.join(", "))
    };
    let mut header = format!("{{'descr': '{descr}', 'fortran_order': False, 'shape': {tuple}, }}");
    // Magic (6) + version (2) + length (2) + header + newline, padded to a multiple of 64.
    let unpadded = 10 + header.len() + 1;
    header.push_str(&" ".repeat((64 - unpadded % 64) % 64));
    header.push('\n');
    let mut bytes = Vec::with_capacity(10 + header.len() + 8 * count);
    bytes.extend_from_slice(b"\x93NUMPY\x01\x00");
    bytes.extend_from_slice(&(header.len() as u16).to_le_bytes());
    bytes.extend_from_slice(header.as_bytes());
    bytes.extend(data);
    bytes
}

/// A number written with `D` decimals (in CSV cells: as many as the figure can tell, the same
/// width every row).
#[derive(Clone, Copy, Debug)]
pub struct Fixed<const D: usize>(pub f64);

impl<const D: usize> serde::Serialize for Fixed<D> {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        s.collect_str(&format_args!("{:.*}", D, self.0))
    }
}

/// Rows of a serde struct as CSV, its field names the header (through the csv crate).
pub fn csv_bytes<T: serde::Serialize>(rows: &[T]) -> Vec<u8> {
    let mut w = csv::Writer::from_writer(Vec::new());
    for row in rows {
        // A flat struct of numbers, strings and options into memory: nothing can fail.
        w.serialize(row).expect("a flat row serialises");
    }
    w.into_inner().expect("writing into a Vec")
}

/// Writes [`npy_f64`] atomically.
pub fn write_npy_f64(path: &Path, shape: &[usize], values: &[f64]) -> Result<()> {
    write_atomic(path, &npy_f64(shape, values))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    fn scratch(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        dir
    }

    #[test]
    fn npy_header_is_aligned_and_data_follows() {
        let dir = scratch("npy");
        let path = dir.join("a.npy");
        write_npy_f64(
            &path,
            &[2, 3, 4],
            &(0..24).map(|v| v as f64).collect::<Vec<_>>(),
        )
        .unwrap();
        let bytes = std::fs::read(&path).unwrap();
        assert_eq!(&bytes[..8], b"\x93NUMPY\x01\x00");
        let len = u16::from_le_bytes([bytes[8], bytes[9]]) as usize;
        assert_eq!((10 + len) % 64, 0);
        let header = std::str::from_utf8(&bytes[10..10 + len]).unwrap();
        assert!(
            header.contains("'shape': (2, 3, 4)") && header.ends_with('\n'),
            "{header}"
        );
        assert_eq!(bytes.len(), 10 + len + 24 * 8);
        let last = f64::from_le_bytes(bytes[bytes.len() - 8..].try_into().unwrap());
        assert_eq!(last, 23.0);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn formats_come_from_the_extension_and_others_are_refused() {
        let dir = scratch("formats");
        let px = [10u8, 200, 30, 255].repeat(16);
        write_image(&dir.join("a/b.png"), 4, 4, &px).unwrap();
        write_image(&dir.join("c.JPG"), 4, 4, &px).unwrap();
        assert!(
            std::fs::read(dir.join("a/b.png"))
                .unwrap()
                .starts_with(b"\x89PNG")
        );
        assert!(
            std::fs::read(dir.join("c.JPG"))
                .unwrap()
                .starts_with(&[0xFF, 0xD8])
        );
        let e = write_image(&dir.join("d.webp"), 4, 4, &px).unwrap_err();
        assert!(
            e.to_string().contains("output") && e.to_string().contains(".webp"),
            "{e}"
        );
        assert!(!dir.join("d.webp").exists());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
