//! `terrain view` under Xvfb on whatever adapter there is: it opens a window, draws frames, writes
//! a screenshot of what it presented and exits; the screenshot shows the terrain `render` draws
//! for the same camera, with the on-screen figures over it. Driven by xdotool's keys, it switches
//! mode, records the path flown and quits.

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

    let render = rendered(&dir, "warped");
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

/// `render` of the gaussian scene at 160×120 in `mode`, RGBA.
fn rendered(dir: &std::path::Path, mode: &str) -> Vec<u8> {
    let scene = manifest_dir().join("sketches/gaussian.toml");
    let png = dir.join(format!("render-{mode}.png"));
    let out = Command::new(env!("CARGO_BIN_EXE_terrain"))
        .args(["render", scene.to_str().unwrap(), "--mode", mode, "-o"])
        .arg(&png)
        .args(["--set", "camera.width=160", "--set", "camera.height=120"])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    read_png(&png).unwrap().2
}

#[test]
fn view_keys_switch_mode_record_the_path_and_quit() {
    if !cfg!(feature = "view") {
        eprintln!("built without the `view` feature: nothing to test");
        return;
    }
    if !(has("xvfb-run") && has("xdotool")) {
        eprintln!(
            "xvfb-run or xdotool is not installed (Debian: apt-get install xvfb xauth xdotool): keys not tested"
        );
        return;
    }
    let dir = scratch("view-keys");
    let scene = dir.join("gaussian.toml");
    std::fs::copy(manifest_dir().join("sketches/gaussian.toml"), &scene).unwrap();
    let shot = dir.join("shot.png");
    // 2: GeoMipMap; P: screenshot; R, W held for 2 s, R: a recorded flight north; Esc: quit.
    let script = format!(
        "timeout 120 {bin} view {scene} --size 160x120 --screenshot {shot} & pid=$!\n\
         wid=$(xdotool search --sync --name 'terrain view')\n\
         xdotool windowfocus --sync $wid\n\
         sleep 1; xdotool key 2; sleep 3; xdotool key p; sleep 1\n\
         xdotool key r; xdotool keydown w; sleep 2; xdotool keyup w; xdotool key r; sleep 1\n\
         xdotool key Escape\n\
         wait $pid\n",
        bin = env!("CARGO_BIN_EXE_terrain"),
        scene = scene.display(),
        shot = shot.display(),
    );
    let out = Command::new("xvfb-run")
        .args(["-a", "-s", "-screen 0 640x480x24", "sh", "-c", &script])
        .output()
        .expect("run xvfb-run");
    assert!(
        out.status.success(),
        "view: {}",
        String::from_utf8_lossy(&out.stderr)
    );

    // The screenshot after `2` is GeoMipMap's frame, not the warped one.
    let (_, _, view) = read_png(&shot).expect("screenshot written by P");
    let band = |img: &[u8]| img[56 * 160 * 4..104 * 160 * 4].to_vec();
    let gmm = psnr(&band(&view), &band(&rendered(&dir, "geomipmap")));
    let warped = psnr(&band(&view), &band(&rendered(&dir, "warped")));
    assert!(
        gmm >= 40.0 && warped < gmm - 5.0,
        "GeoMipMap {gmm:.1} dB, warped {warped:.1} dB"
    );

    // R … R wrote the scene with the path flown: north (W, the camera looks north), at speed.
    let flown = dir.join("gaussian-flown.toml");
    let recorded = terrain::scene::Scene::load(&flown).expect("the recorded scene loads");
    let path = recorded.path.expect("a [path]");
    let (first, last) = (
        path.keys[0].position,
        path.keys[path.keys.len() - 1].position,
    );
    assert!(
        path.keys.len() >= 2 && last[1] - first[1] > 10.0,
        "{:?}",
        path.keys
    );
    assert!(
        (last[0] - first[0]).abs() < 1.0,
        "moved sideways: {first:?} → {last:?}"
    );
    assert!(terrain::path::CameraPath::new(&path).is_ok());
}
