//! The library as a program other than `terrain` uses it: its notes reach the program's logger
//! (the `log` crate) and never its stderr, and GeoMipMap over a tile pyramid leaves the folder as
//! it was unless the program asks for its block figures to be kept.
//!
//! A logger is the process's, so these tests have a binary of their own.

mod common;

use common::scratch;
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use terrain_engine::Renderer;
use terrain_engine::View;
use terrain_engine::scene::Mode;

/// Every record of `terrain`'s targets: level, target and text.
struct Capture(Mutex<Vec<(log::Level, String, String)>>);

static CAPTURE: Capture = Capture(Mutex::new(Vec::new()));

impl log::Log for Capture {
    fn enabled(&self, metadata: &log::Metadata) -> bool {
        metadata.target().starts_with("terrain")
    }

    fn log(&self, record: &log::Record) {
        if self.enabled(record.metadata()) {
            let entry = (
                record.level(),
                record.target().to_string(),
                record.args().to_string(),
            );
            self.0.lock().unwrap().push(entry);
        }
    }

    fn flush(&self) {}
}

/// The bundled Jacksboro sketch converted to a pyramid in a scratch folder `name`.
fn jacksboro_pyramid(name: &str) -> PathBuf {
    let asc = common::manifest_dir().join("sketches/jacksboro_fault_dem.asc");
    let pyr = scratch(name).join("pyr");
    terrain_engine::sketch::convert::build(&asc, &pyr, &Default::default()).unwrap();
    pyr
}

/// The bundled Jacksboro scene at 128² over the pyramid `pyr`, GeoMipMap's frame limited to 8
/// blocks (so its first frame notes the ones it leaves out).
fn tight_scene(pyr: &Path) -> terrain_engine::scene::Scene {
    let dir = common::manifest_dir().join("sketches");
    let text = std::fs::read_to_string(dir.join("jacksboro.toml"))
        .unwrap()
        .replace(
            "path = \"jacksboro_fault_dem.asc\"",
            &format!("path = {:?}", pyr.display().to_string()),
        )
        .replace("width = 512", "width = 128")
        .replace("height = 512", "height = 128");
    let mut scene = common::scene(&text, dir);
    scene.geomipmap.max_blocks = 8;
    scene
}

/// The block figures' files in `pyr`.
fn kept_figures(pyr: &Path) -> Vec<String> {
    std::fs::read_dir(pyr)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with("geomipmap-"))
        .collect()
}

const CHILD: &str = "TERRAIN_LIBRARY_QUIET_CHILD";

/// A GeoMipMap frame over a pyramid that leaves blocks out notes it through `log`, and prints
/// nothing: the render runs in a child process whose stderr is checked.
#[test]
fn a_renders_note_reaches_the_log_and_not_stderr() {
    if std::env::var_os(CHILD).is_some() {
        return render_with_a_note();
    }
    let name = "a_renders_note_reaches_the_log_and_not_stderr";
    let out = std::process::Command::new(std::env::current_exe().unwrap())
        .args([name, "--exact", "--nocapture", "--test-threads=1"])
        .env(CHILD, "1")
        .env_remove("TERRAIN_QUIET")
        .output()
        .unwrap();
    let (stdout, stderr) = (
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr),
    );
    assert!(
        out.status.success() && stdout.contains("1 passed"),
        "{stdout}\n{stderr}"
    );
    assert!(
        !stderr.contains("GeoMipMap sees") && !stderr.lines().any(|l| l.starts_with("note:")),
        "the library printed:\n{stderr}"
    );
}

fn render_with_a_note() {
    log::set_logger(&CAPTURE).unwrap();
    log::set_max_level(log::LevelFilter::Info);
    let pyr = jacksboro_pyramid("library-quiet-note");
    let scene = tight_scene(&pyr);
    let mut r = Renderer::new(&scene, Mode::Geomipmap, View::Shaded).unwrap();
    let camera = terrain_engine::scene::camera_of(&scene, &r.atlas).unwrap();
    let frame = r.render(&camera).unwrap();
    assert_eq!(frame.blocks, Some(8));
    let notes = CAPTURE.0.lock().unwrap();
    assert!(
        notes.iter().any(|(level, target, text)| {
            *level == log::Level::Info
                && target.starts_with("terrain_engine::")
                && text.starts_with("GeoMipMap sees ")
                && text.contains("so the farthest")
        }),
        "{notes:?}"
    );
}

/// GeoMipMap over a pyramid measures its blocks and writes nothing into the folder; once the
/// program asks, the figures are kept there.
#[test]
fn geomipmap_keeps_its_block_figures_only_when_asked() {
    let pyr = jacksboro_pyramid("library-quiet-figures");
    let scene = tight_scene(&pyr);
    Renderer::new(&scene, Mode::Geomipmap, View::Shaded).unwrap();
    assert_eq!(kept_figures(&pyr), Vec::<String>::new());
    terrain_engine::sketch::tiles::set_keep_figures(true);
    Renderer::new(&scene, Mode::Geomipmap, View::Shaded).unwrap();
    terrain_engine::sketch::tiles::set_keep_figures(false);
    let block = scene.geomipmap.block;
    assert_eq!(kept_figures(&pyr), vec![format!("geomipmap-{block}.bin")]);
}
