//! Animations a person can open: an APNG (every browser and most viewers play it) streamed frame
//! by frame, and an MP4 through ffmpeg when ffmpeg is on the PATH.
//!
//! Rules: the APNG is written into a temporary file beside its target and renamed over it only
//! when its last frame is in, so a reader never sees a torn animation; frames are stored as RGB
//! (the renders are opaque) with fast compression, as a long flythrough is hundreds of frames.
//! The MP4 is H.264 in yuv420p (what players and browsers accept), encoded from the numbered PNG
//! frames, also into a temporary file first.
//!
//! Rejected alternative: an animated GIF. Its 256-colour palette bands the sky's gradient and
//! dithers the terrain's texture, which is the detail a flythrough is made to show.

use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};
use std::process::Command;
use terrain_engine::{Error, Result, Role};

pub struct Apng {
    writer: Option<png::Writer<BufWriter<File>>>,
    tmp: PathBuf,
    path: PathBuf,
    frames_left: u32,
}

fn io(path: &Path, e: impl std::fmt::Display) -> Error {
    Error::io(Role::Output, path, std::io::Error::other(e.to_string()))
}

impl Apng {
    /// An animation of `frames` frames of `width`×`height`, played at `fps`, looping.
    pub fn create(path: &Path, width: u32, height: u32, frames: u32, fps: f64) -> Result<Apng> {
        let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("out");
        let tmp = path.with_file_name(format!(".{name}.{}.tmp", std::process::id()));
        let file = File::create(&tmp).map_err(|e| Error::io(Role::Output, &tmp, e))?;
        let mut enc = png::Encoder::new(BufWriter::new(file), width, height);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        enc.set_compression(png::Compression::Fast);
        enc.set_animated(frames.max(1), 0)
            .map_err(|e| io(path, e))?;
        // The delay as a fraction of a second: 1000 / (fps · 1000).
        let den = (fps * 100.0).round().clamp(1.0, u16::MAX as f64) as u16;
        enc.set_frame_delay(100, den).map_err(|e| io(path, e))?;
        let writer = enc.write_header().map_err(|e| io(path, e))?;
        Ok(Apng {
            writer: Some(writer),
            tmp,
            path: path.to_path_buf(),
            frames_left: frames.max(1),
        })
    }

    /// Appends a frame of RGBA8 pixels.
    pub fn add(&mut self, rgba: &[u8]) -> Result<()> {
        let rgb: Vec<u8> = rgba
            .chunks_exact(4)
            .flat_map(|p| [p[0], p[1], p[2]])
            .collect();
        let w = self
            .writer
            .as_mut()
            .ok_or_else(|| io(&self.path, "finished"))?;
        w.write_image_data(&rgb).map_err(|e| io(&self.path, e))?;
        self.frames_left = self.frames_left.saturating_sub(1);
        Ok(())
    }

    /// Completes the file and renames it into place; every announced frame must be in.
    pub fn finish(mut self) -> Result<()> {
        if self.frames_left > 0 {
            return Err(io(
                &self.path,
                format!("{} frames missing", self.frames_left),
            ));
        }
        let w = self
            .writer
            .take()
            .ok_or_else(|| io(&self.path, "finished"))?;
        w.finish().map_err(|e| io(&self.path, e))?;
        std::fs::rename(&self.tmp, &self.path).map_err(|e| Error::io(Role::Output, &self.path, e))
    }
}

impl Drop for Apng {
    fn drop(&mut self) {
        if self.writer.is_some() {
            self.writer = None;
            let _ = std::fs::remove_file(&self.tmp);
        }
    }
}

/// Whether `ffmpeg` runs.
/// An APNG made from PNG frames already on disk (when ffmpeg failed on them).
pub fn apng_from_frames(path: &Path, frames: &[PathBuf], w: u32, h: u32, fps: f64) -> Result<()> {
    let mut apng = Apng::create(path, w, h, frames.len() as u32, fps)?;
    for f in frames {
        let file = File::open(f).map_err(|e| Error::io(Role::Output, f, e))?;
        let mut reader = png::Decoder::new(std::io::BufReader::new(file))
            .read_info()
            .map_err(|e| io(f, e))?;
        let mut buf = vec![0; reader.output_buffer_size().unwrap_or(0)];
        let info = reader.next_frame(&mut buf).map_err(|e| io(f, e))?;
        if (info.width, info.height, info.color_type) != (w, h, png::ColorType::Rgba) {
            return Err(Error::file(Role::Output, f, "not a frame of this flight"));
        }
        apng.add(&buf[..info.buffer_size()])?;
    }
    apng.finish()
}

pub fn ffmpeg_available() -> bool {
    Command::new("ffmpeg")
        .arg("-version")
        .output()
        .is_ok_and(|o| o.status.success())
}

/// Encodes `dir/<pattern>` (an ffmpeg pattern such as `frame-%05d.png`) at `fps` into `out`.
pub fn mp4(dir: &Path, pattern: &str, fps: f64, out: &Path) -> Result<()> {
    let tmp = out.with_extension("tmp.mp4");
    let result = Command::new("ffmpeg")
        .args(["-y", "-loglevel", "error", "-framerate"])
        .arg(format!("{fps}"))
        .arg("-i")
        .arg(dir.join(pattern))
        .args([
            "-c:v",
            "libx264",
            "-pix_fmt",
            "yuv420p",
            "-vf",
            "pad=ceil(iw/2)*2:ceil(ih/2)*2",
        ])
        .arg(&tmp)
        .output()
        .map_err(|e| Error::io(Role::Output, out, e))?;
    if !result.status.success() {
        let _ = std::fs::remove_file(&tmp);
        let why = String::from_utf8_lossy(&result.stderr);
        let line = why.lines().last().unwrap_or("failed");
        return Err(io(out, format!("ffmpeg: {line}")));
    }
    std::fs::rename(&tmp, out).map_err(|e| Error::io(Role::Output, out, e))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn apng_holds_every_frame_and_nothing_is_left_on_failure() {
        let dir = std::env::temp_dir().join(format!("apng-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("a.png");
        let mut a = Apng::create(&path, 4, 3, 3, 30.0).unwrap();
        for k in 0..3u8 {
            a.add(&[k * 50; 4 * 4 * 3]).unwrap();
        }
        a.finish().unwrap();
        let decoder = png::Decoder::new(std::io::BufReader::new(File::open(&path).unwrap()));
        let reader = decoder.read_info().unwrap();
        let control = reader.info().animation_control().unwrap();
        assert_eq!((control.num_frames, control.num_plays), (3, 0));

        let short = dir.join("b.png");
        let mut b = Apng::create(&short, 4, 3, 3, 30.0).unwrap();
        b.add(&[0; 48]).unwrap();
        assert!(b.finish().is_err());
        let left: Vec<_> = std::fs::read_dir(&dir)
            .unwrap()
            .flatten()
            .map(|e| e.file_name())
            .collect();
        assert_eq!(left, vec![std::ffi::OsString::from("a.png")], "{left:?}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
