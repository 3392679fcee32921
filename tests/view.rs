//! `terrain view` under Xvfb on whatever adapter there is: it opens a window, draws frames, writes
//! a screenshot of what it presented and exits; the screenshot shows the terrain `render` draws
//! for the same camera, with the on-screen figures over it.

mod common;
use common::*;
use std::process::Command;

fn has(program: &str) -> bool {
    Command::new("sh")
        .args(["-c", &format!("command -v {program}")])
        .output()
        .is_ok_and(|o| o.status.success())
}

#[test]
fn view_opens_draws_and_screenshots_itself_under_xvfb() {
    if !cfg!(feature = "view") {
        eprintln!("built without the `view` feature: nothing to test");
        return;
    }
    if !has("xvfb-run") {
        // .ci/run installs it; a machine without it cannot open a window headless.
        eprintln!(
            "xvfb-run is not installed (Debian: apt-get install xvfb xauth): `view` not tested"
        );
        return;
    }
    let dir = scratch("view");
    let shot = dir.join("shot.png");
    let scene = manifest_dir().join("sketches/gaussian.toml");
    let out = Command::new("xvfb-run")
        .args(["-a", "-s", "-screen 0 640x480x24"])
        .arg(env!("CARGO_BIN_EXE_terrain"))
        .args([
            "view",
            scene.to_str().unwrap(),
            "--size",
            "160x120",
            "--frames",
            "3",
            "--screenshot",
        ])
        .arg(&shot)
        .output()
        .expect("run xvfb-run");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "view failed: {err}");
    let (w, h, view) = read_png(&shot).expect("screenshot written");
    assert_eq!((w, h), (160, 120));

    let rendered = dir.join("render.png");
    let out = Command::new(env!("CARGO_BIN_EXE_terrain"))
        .args(["render", scene.to_str().unwrap(), "-o"])
        .arg(&rendered)
        .args(["--set", "camera.width=160", "--set", "camera.height=120"])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let (_, _, render) = read_png(&rendered).unwrap();
    // Between the figures at the top (three lines) and the key help at the bottom, the window
    // shows exactly the terrain `render` draws.
    let band = |img: &[u8], y0: usize, y1: usize| img[y0 * 160 * 4..y1 * 160 * 4].to_vec();
    let db = psnr(&band(&view, 56, 104), &band(&render, 56, 104));
    assert!(
        db >= 40.0,
        "the window's terrain differs from render's: {db:.1} dB"
    );
    // And the figures are drawn over it.
    let top = psnr(&band(&view, 0, 52), &band(&render, 0, 52));
    assert!(
        top < 30.0,
        "no figures on screen ({top:.1} dB against the bare render)"
    );
}
