//! What the window writes: screenshots and recorded paths, into `--out-dir` under names that never
//! overwrite a file.

use super::App;
use crate::output::{write_atomic, write_image};
use std::path::{Path, PathBuf};
use terrain_engine::flight::flycam::{PathRecorder, scene_with_path};
use terrain_engine::{Error, Result, Role};

/// `dir/<name(0)>`, or the first of `dir/<name(n)>`, n = 1, 2, … that does not exist yet.
fn unused(dir: &Path, name: impl Fn(usize) -> String) -> PathBuf {
    (0..)
        .map(|n| dir.join(name(n)))
        .find(|p| !p.exists())
        .expect("some number is free")
}

impl App {
    /// Writes `rgba` (`width` × `height`, the pixels presented) as the next screenshot.
    pub(super) fn screenshot(&mut self, rgba: &[u8], width: u32, height: u32) -> Result<PathBuf> {
        let path = match &self.o.screenshot {
            Some(p) if self.shots == 0 => p.clone(),
            _ => {
                let stem = self.stem();
                unused(&self.o.out_dir, |n| format!("{stem}-view-{}.png", n + 1))
            }
        };
        self.shots += 1;
        write_image(&path, width, height, rgba)?;
        Ok(path)
    }

    pub(super) fn stem(&self) -> String {
        self.o
            .scene_path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "scene".into())
    }

    pub(super) fn toggle_recording(&mut self) -> Result<()> {
        let Some(r) = self.recorder.take() else {
            self.recorder = Some(PathRecorder::default());
            self.message = "recording".into();
            return Ok(());
        };
        let Some(path) = r.finish(self.cam.key().0) else {
            self.message = "nothing recorded: fly, then stop".into();
            return Ok(());
        };
        // A sketch given in place of the scene is named by its absolute path, as the flown scene
        // lands in another folder.
        let absolute = std::path::absolute(&self.o.scene_path)
            .map_err(|e| Error::io(Role::Scene, &self.o.scene_path, e))?;
        let (text, _) = terrain_engine::scene::scene_text(&absolute)?;
        let out = scene_with_path(&text, &self.o.scene_path, &path)?;
        let stem = self.stem();
        let file = unused(&self.o.out_dir, |n| match n {
            0 => format!("{stem}-flown.toml"),
            n => format!("{stem}-flown-{}.toml", n + 1),
        });
        write_atomic(&file, out.as_bytes())?;
        self.message = format!("{} keys written to {}", path.keys.len(), file.display());
        Ok(())
    }
}
