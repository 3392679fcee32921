//! Writing files atomically: into a temporary file beside the target, then renamed over it, so a
//! reader never sees half a file and a crash leaves the old one (or none), never a torn one. The
//! library writes through here (a tile pyramid's files, GeoMipMap's block figures when asked);
//! the program's outputs too (`terrain_cli::output`).
//!
//! Rules:
//! - Every writer creates the file's folder first.
//! - Several files that belong together are staged ([`Staged`]) and renamed into place only once
//!   every one is written, so when one fails (a folder that cannot be made, a full disk) none is
//!   left behind.
//! - A temporary file is `.NAME.PID.tmp` beside its target: the same file system, so `rename` is
//!   atomic, and a name a resumed build recognises as left over.
//!
//! Rejected alternative: the `tempfile` crate's `NamedTempFile::persist`. It renames one file;
//! the all-or-nothing commit of several is what this module is for, and the temporary name
//! beside the target is two lines.

use crate::error::{Error, Result, Role};
use std::io::Write;
use std::path::{Path, PathBuf};

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

/// Writes `bytes` to `path` through a temporary file, creating its folder.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let mut staged = Staged::default();
    staged.add(path, bytes)?;
    staged.commit()
}

/// Files written to temporary files, renamed into place together by [`Staged::commit`];
/// dropped uncommitted, they are removed.
#[derive(Default)]
pub struct Staged {
    files: Vec<(PathBuf, PathBuf)>,
}

impl Staged {
    /// Writes `bytes` to a temporary file beside `path`, to be renamed over it on commit.
    pub fn add(&mut self, path: &Path, bytes: &[u8]) -> Result<()> {
        let tmp = write_temporary(path, bytes)?;
        self.files.push((tmp, path.to_path_buf()));
        Ok(())
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

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("io-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        dir
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
