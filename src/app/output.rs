//! Writing outputs atomically: into a temporary file beside the target, then renamed over it, so a
//! reader never sees half a file and a crash leaves the old one (or none), never a torn one.
//!
//! Rules:
//! - Every writer creates the output's folder first: `-o out/x.png` on a fresh clone, where `out/`
//!   does not exist, works like every `--out-dir`.
//! - An image's format comes from its extension (`.png`, `.jpg`/`.jpeg`); any other extension is
//!   refused before anything is rendered, never written as PNG bytes under a foreign name.
//! - A command with several outputs stages them all ([`Staged`]) and renames them into place only
//!   once every one is written, so when one fails (a missing folder that cannot be made, a full
//!   disk) none is left behind.
//!
//! CSV goes through the csv crate (rows as serde structs, so a header cannot drift from its
//! cells). `.npy` is written by hand, 20 lines: npyz (0.8) writes the shape as `(32, 48, 4, )`,
//! which NumPy reads but never writes, so files would differ from `numpy.save`'s and from what
//! scripts that read the header text expect (the tests among them).
//!
//! Rejected alternative: the `tempfile` crate's `NamedTempFile::persist`. It renames one file;
//! the all-or-nothing commit of several is what this module is for, and the temporary name
//! beside the target (same file system, so `rename` is atomic) is two lines.

use crate::app::progress::Progress;
use crate::error::{Error, Result, Role};
use std::io::Write;
use std::path::{Path, PathBuf};

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

fn temporary(path: &Path) -> PathBuf {
    let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("out");
    path.with_file_name(format!(".{name}.{}.tmp", std::process::id()))
}

/// Creates the folder `path` will be written into.
pub fn create_parent(path: &Path) -> Result<()> {
    match path.parent().filter(|p| !p.as_os_str().is_empty()) {
        Some(dir) => create_folder(dir),
        None => Ok(()),
    }
}

/// Creates an output folder and its parents.
pub fn create_folder(dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir).map_err(|e| Error::io(Role::OutputFolder, dir, e))
}

fn write_temporary(path: &Path, bytes: &[u8]) -> Result<PathBuf> {
    create_parent(path)?;
    let tmp = temporary(path);
    let result = (|| {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()
    })();
    match result {
        Ok(()) => Ok(tmp),
        Err(e) => {
            let _ = std::fs::remove_file(&tmp);
            Err(Error::io(Role::Output, path, e))
        }
    }
}

pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let mut staged = Staged::default();
    staged.add(path, bytes)?;
    staged.commit()
}

/// Outputs written to temporary files, renamed into place together by [`Staged::commit`];
/// dropped uncommitted, they are removed.
#[derive(Default)]
pub struct Staged {
    files: Vec<(PathBuf, PathBuf)>,
}

impl Staged {
    pub fn add(&mut self, path: &Path, bytes: &[u8]) -> Result<()> {
        let tmp = write_temporary(path, bytes)?;
        self.files.push((tmp, path.to_path_buf()));
        Ok(())
    }

    /// Encodes an image in the format of `path`'s extension and stages it.
    pub fn add_image(&mut self, path: &Path, width: u32, height: u32, rgba: &[u8]) -> Result<()> {
        let bytes = encode_image(path, width, height, rgba)?;
        self.add(path, &bytes)
    }

    /// Renames every staged file over its target.
    pub fn commit(mut self) -> Result<()> {
        for (tmp, path) in std::mem::take(&mut self.files) {
            std::fs::rename(&tmp, &path).map_err(|e| {
                let _ = std::fs::remove_file(&tmp);
                Error::io(Role::Output, &path, e)
            })?;
        }
        Ok(())
    }
}

impl Drop for Staged {
    fn drop(&mut self) {
        for (tmp, _) in &self.files {
            let _ = std::fs::remove_file(tmp);
        }
    }
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
    debug_assert_eq!(shape.iter().product::<usize>(), values.len());
    let dims: Vec<String> = shape.iter().map(|d| d.to_string()).collect();
    let tuple = if dims.len() == 1 {
        format!("({},)", dims[0])
    } else {
        format!("({})", dims.join(", "))
    };
    let mut header = format!("{{'descr': '<f8', 'fortran_order': False, 'shape': {tuple}, }}");
    // Magic (6) + version (2) + length (2) + header + newline, padded to a multiple of 64.
    let unpadded = 10 + header.len() + 1;
    header.push_str(&" ".repeat((64 - unpadded % 64) % 64));
    header.push('\n');
    let mut bytes = Vec::with_capacity(10 + header.len() + 8 * values.len());
    bytes.extend_from_slice(b"\x93NUMPY\x01\x00");
    bytes.extend_from_slice(&(header.len() as u16).to_le_bytes());
    bytes.extend_from_slice(header.as_bytes());
    for v in values {
        bytes.extend_from_slice(&v.to_le_bytes());
    }
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

    #[test]
    fn staged_outputs_land_together_or_not_at_all() {
        let dir = scratch("staged");
        std::fs::create_dir_all(&dir).unwrap();
        // A file where the second output's folder should be: that folder cannot be made.
        std::fs::write(dir.join("blocked"), b"").unwrap();
        let mut s = Staged::default();
        s.add(&dir.join("one.txt"), b"1").unwrap();
        assert!(s.add(&dir.join("blocked/two.txt"), b"2").is_err());
        drop(s);
        let left: Vec<_> = std::fs::read_dir(&dir).unwrap().collect();
        assert_eq!(left.len(), 1, "only `blocked` remains: {left:?}");

        let mut s = Staged::default();
        s.add(&dir.join("one.txt"), b"1").unwrap();
        s.add(&dir.join("sub/two.txt"), b"2").unwrap();
        assert!(!dir.join("one.txt").exists());
        s.commit().unwrap();
        assert_eq!(std::fs::read(dir.join("sub/two.txt")).unwrap(), b"2");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
