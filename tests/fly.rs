//! `terrain fly` into a folder it wrote before, and a flight of many files.

mod common;
use common::*;
use std::io::BufRead;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Duration;

/// A quick scene over the synthetic hills, flown from its camera.
fn scene(dir: &Path) -> PathBuf {
    let path = dir.join("fly.toml");
    std::fs::write(
        &path,
        "[sketch]\nsynthetic = \"hills\"\n[camera]\nposition = [500.0, 300.0, 900.0]\nlook_at = [3800.0, 4000.0, 200.0]\nwidth = 16\nheight = 16\n[warp]\nmesh = 16\n[detail]\noctaves = 0\n",
    )
    .unwrap();
    path
}

fn fly(scene: &Path, out: &Path, frames: &str) -> String {
    let (code, _, err) = terrain(&[
        "fly",
        scene.to_str().unwrap(),
        "--out-dir",
        out.to_str().unwrap(),
        "--frames",
        frames,
        "--no-mp4",
    ]);
    assert_eq!(code, 0, "{err}");
    err
}

fn names(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

/// A shorter flight into the same folder leaves none of the longer one's frames (which an MP4
/// of `frame-%05d.png` would take in too), and nothing else there is touched.
#[test]
fn a_second_flight_leaves_none_of_the_first_ones_frames() {
    let dir = scratch("fly-again");
    let scene = scene(&dir);
    let out = dir.join("out");
    fly(&scene, &out, "6");
    let theirs = ["frame-1.png", "frame-notes.png", "my-frame-00009.png"];
    for name in theirs {
        std::fs::write(out.join(name), b"not a frame of ours").unwrap();
    }
    std::fs::write(out.join(".frame-00004.png.77.tmp"), b"torn").unwrap();
    let err = fly(&scene, &out, "2");
    // Two frames are not many files: nothing said of them.
    assert!(!err.contains("files, about"), "{err}");
    let mut expected: Vec<String> = [
        "animation.png",
        "frame-00000.png",
        "frame-00001.png",
        "frames.csv",
    ]
    .iter()
    .chain(&theirs)
    .map(|s| s.to_string())
    .collect();
    expected.sort();
    assert_eq!(names(&out), expected);
    let apng = png::Decoder::new(std::io::BufReader::new(
        std::fs::File::open(out.join("animation.png")).unwrap(),
    ));
    let info = apng.read_info().unwrap();
    assert_eq!(
        info.info().animation_control().map(|a| a.num_frames),
        Some(2)
    );
}

/// 100,000 frames are 100,002 files: said, with their size, before the first frame.
#[test]
fn a_flight_of_many_files_says_so_before_it_starts() {
    let dir = scratch("fly-many");
    let scene = scene(&dir);
    let out = dir.join("out");
    let mut child = Command::new(env!("CARGO_BIN_EXE_terrain"))
        .args(["fly", scene.to_str().unwrap(), "--out-dir"])
        .arg(&out)
        .args(["--frames", "100000", "--size", "8", "--no-mp4"])
        .env("TERRAIN_QUIET", "1")
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let stderr = child.stderr.take().unwrap();
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        for line in std::io::BufReader::new(stderr)
            .lines()
            .map_while(Result::ok)
        {
            if tx.send(line).is_err() {
                break;
            }
        }
    });
    let mut said = Vec::new();
    let line = loop {
        match rx.recv_timeout(Duration::from_secs(60)) {
            Ok(l) if l.contains("files") => break Some(l),
            Ok(l) => said.push(l),
            Err(_) => break None,
        }
    };
    child.kill().unwrap();
    child.wait().unwrap();
    let line = line.unwrap_or_else(|| panic!("nothing said of the files: {said:?}"));
    assert!(
        line.starts_with("fly: that is 100002 files, about ") && line.contains(" MB"),
        "{line}"
    );
}

/// `fly`'s frames overlap each frame's CPU stage with the GPU's drawing of the frame before
/// (`Renderer::render_each`); the frames are those drawn one at a time, byte for byte, in the
/// warped mode (whose stage holds its warp from frame to frame) and GeoMipMap, and at a size
/// that changes along the way.
#[test]
fn frames_drawn_with_the_next_ones_stage_overlapped_equal_frames_drawn_one_at_a_time() {
    use terrain_engine::scene::{Mode, Scene};
    use terrain_engine::{Renderer, View};
    let mut scene = Scene::load(&manifest_dir().join("sketches/jacksboro.toml")).unwrap();
    (scene.camera.width, scene.camera.height) = (64, 48);
    for mode in [Mode::Warped, Mode::Geomipmap] {
        let mut r = Renderer::new(&scene, mode, View::Shaded).unwrap();
        let base = terrain_engine::scene::camera_of(&scene, &r.atlas).unwrap();
        let cameras: Vec<_> = (0..5)
            .map(|k| {
                let mut c = base.clone();
                c.eye += c.forward * (40.0 * k as f64);
                if k == 3 {
                    (c.width, c.height) = (48, 64);
                }
                c
            })
            .collect();
        let one_at_a_time: Vec<Vec<u8>> =
            cameras.iter().map(|c| r.render(c).unwrap().rgba).collect();
        let mut r = Renderer::new(&scene, mode, View::Shaded).unwrap();
        let mut overlapped = Vec::new();
        r.render_each(&cameras, |k, frame| {
            assert_eq!(
                (frame.width, frame.height),
                (cameras[k].width, cameras[k].height)
            );
            overlapped.push(frame.rgba);
            Ok(true)
        })
        .unwrap();
        assert_eq!(overlapped.len(), cameras.len());
        for (k, (a, b)) in overlapped.iter().zip(&one_at_a_time).enumerate() {
            let differing = a.iter().zip(b).filter(|(x, y)| x != y).count();
            assert_eq!(differing, 0, "{mode} frame {k}: {differing} bytes differ");
        }
    }
}
