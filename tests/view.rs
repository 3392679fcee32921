//! `terrain view` under Xvfb on whatever adapter there is: it opens a window, draws frames, writes
//! a screenshot of what it presented and exits; the screenshot shows the terrain `render` draws
//! for the same camera, with the on-screen figures over it, through the wgpu surface and through
//! the CPU copy it falls back to. Driven by xdotool's keys, it switches mode, records the path
//! flown and quits.
//!
//! This file has its own harness (libtest-mimic) so that a machine without Xvfb or xdotool
//! reports these tests as ignored, with the reason, instead of passing them having checked
//! nothing. Where `TERRAIN_REQUIRE_VIEW_TESTS` is set (`.ci/run` sets it) a missing tool fails
//! them instead: CI always runs them.

mod common;
use common::*;
use libtest_mimic::Arguments;
use std::process::Command;

/// A test's name, its body, and the programs it needs.
type ViewTest = (&'static str, fn(), &'static [&'static str]);

fn main() {
    let args = Arguments::from_args();
    let tests: [ViewTest; 8] = [
        (
            "the_host_example_draws_the_terrain_and_its_own_mast_in_a_window",
            the_host_example_draws_the_terrain_and_its_own_mast_in_a_window,
            &["xvfb-run"],
        ),
        (
            "the_readme_view_commands_run_as_written",
            the_readme_view_commands_run_as_written,
            &["xvfb-run"],
        ),
        (
            "view_flies_a_sketch_of_each_format_given_by_itself",
            view_flies_a_sketch_of_each_format_given_by_itself,
            &["xvfb-run"],
        ),
        (
            "view_opens_draws_and_screenshots_itself_under_xvfb",
            view_opens_draws_and_screenshots_itself_under_xvfb,
            &["xvfb-run"],
        ),
        (
            "view_presents_through_a_surface_and_prints_its_figures_as_json",
            view_presents_through_a_surface_and_prints_its_figures_as_json,
            &["xvfb-run"],
        ),
        (
            "view_presents_through_the_cpu_where_asked_and_shows_the_same_terrain",
            view_presents_through_the_cpu_where_asked_and_shows_the_same_terrain,
            &["xvfb-run"],
        ),
        (
            "view_keys_switch_mode_record_the_path_and_quit",
            view_keys_switch_mode_record_the_path_and_quit,
            &["xvfb-run", "xdotool"],
        ),
        (
            "view_flies_over_a_planet_and_records_a_planet_path",
            view_flies_over_a_planet_and_records_a_planet_path,
            &["xvfb-run", "xdotool"],
        ),
    ];
    let trials = tests
        .into_iter()
        .map(|(name, test, tools)| {
            skippable_trial(name, test, missing(tools), "TERRAIN_REQUIRE_VIEW_TESTS")
        })
        .collect();
    libtest_mimic::run(&args, trials).exit();
}

/// Why these tests cannot run here, if they cannot.
fn missing(tools: &[&str]) -> Option<String> {
    if !cfg!(feature = "view") {
        return Some("built without the `view` feature".into());
    }
    let absent: Vec<&str> = tools.iter().copied().filter(|t| !has(t)).collect();
    (!absent.is_empty()).then(|| {
        format!(
            "{} not installed (Debian: apt-get install xvfb xauth xdotool)",
            absent.join(" and ")
        )
    })
}

fn has(program: &str) -> bool {
    Command::new("sh")
        .args(["-c", &format!("command -v {program}")])
        .output()
        .is_ok_and(|o| o.status.success())
}

/// A sketch of each reader's format (and a glob of tiles) in place of the scene: the window opens
/// on the default view, draws two frames and shows ground in its screenshot.
fn view_flies_a_sketch_of_each_format_given_by_itself() {
    let dir = scratch("view-own");
    let formats = manifest_dir().join("tests/data/formats");
    let sketches = [
        "utm-metres-Float32.tif",
        "grid.asc",
        "N36W084.hgt.zip",
        "grid.xyz",
        "mosaic.vrt",
        "tiles/*.tif",
        "cog-Int16.tif",
    ];
    for (k, name) in sketches.iter().enumerate() {
        let shot = dir.join(format!("shot-{k}.png"));
        let out = Command::new("xvfb-run")
            .args(["-a", "-s", "-screen 0 640x480x24"])
            .arg(env!("CARGO_BIN_EXE_terrain"))
            .arg("view")
            .arg(formats.join(name))
            .args(["--size", "96x72", "--frames", "2", "--screenshot"])
            .arg(&shot)
            .output()
            .expect("run xvfb-run");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "view {name} failed: {err}");
        let (w, h, rgba) = read_png(&shot).expect("screenshot written");
        assert_eq!((w, h), (96, 72), "{name}");
        // Not one flat colour: the ground, lit and textured, is on screen.
        let distinct: std::collections::HashSet<&[u8]> = rgba.chunks_exact(4).collect();
        assert!(distinct.len() > 100, "{name}: {} colours", distinct.len());
    }
    // Left alone, the window tours the default orbit: later frames see the sketch from elsewhere.
    let later = dir.join("later.png");
    let out = Command::new("xvfb-run")
        .args(["-a", "-s", "-screen 0 640x480x24"])
        .arg(env!("CARGO_BIN_EXE_terrain"))
        .arg("view")
        .arg(formats.join(sketches[0]))
        .args(["--size", "96x72", "--frames", "40", "--screenshot"])
        .arg(&later)
        .output()
        .expect("run xvfb-run");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let (first, last) = (read_png(&dir.join("shot-0.png")), read_png(&later));
    let (first, last) = (first.unwrap().2, last.unwrap().2);
    // Below the figures at the top, the terrain moved.
    let terrain = |img: &[u8]| img[40 * 96 * 4..].to_vec();
    assert_ne!(terrain(&first), terrain(&last), "the view did not tour");
}

/// The README's `terrain view` lines as written (its stand-in sketch for `my_dem.tif`), each
/// drawing a few frames to a screenshot: tests/documents.rs runs every other README command.
fn the_readme_view_commands_run_as_written() {
    let dir = scratch("view-readme");
    let lines: Vec<String> = readme_commands()
        .into_iter()
        .filter(|c| c.starts_with("terrain view "))
        .collect();
    assert!(!lines.is_empty(), "the README shows no view command");
    for (k, line) in lines.iter().enumerate() {
        let line = line.replace("my_dem.tif", "tests/data/formats/utm-metres-Float32.tif");
        let shot = dir.join(format!("shot-{k}.png"));
        let out = Command::new("xvfb-run")
            .args(["-a", "-s", "-screen 0 640x480x24"])
            .arg(env!("CARGO_BIN_EXE_terrain"))
            .args(line.split_whitespace().skip(1))
            .args(["--size", "64x48", "--frames", "2", "--screenshot"])
            .arg(&shot)
            .current_dir(manifest_dir())
            .output()
            .expect("run xvfb-run");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "`{line}` failed: {err}");
        assert!(read_png(&shot).is_some(), "`{line}` wrote no screenshot");
    }
}

/// `examples/host.rs`, a host that owns its window, surface and device, draws frames under Xvfb
/// and writes the last: the terrain, and its own red mast standing on it.
fn the_host_example_draws_the_terrain_and_its_own_mast_in_a_window() {
    let dir = scratch("view-host");
    let shot = dir.join("host.png");
    let example = std::path::Path::new(env!("CARGO_BIN_EXE_terrain"))
        .with_file_name("examples")
        .join("host");
    let out = Command::new("xvfb-run")
        .args(["-a", "-s", "-screen 0 640x480x24"])
        .arg(&example)
        .arg(manifest_dir().join("sketches/jacksboro.toml"))
        .args(["--frames", "3", "--screenshot"])
        .arg(&shot)
        .env("XDG_RUNTIME_DIR", std::env::temp_dir())
        .output()
        .expect("run xvfb-run");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{} failed: {err}", example.display());
    let (w, h, rgba) = read_png(&shot).expect("screenshot written");
    assert_eq!((w, h), (480, 320));
    let pixels: Vec<&[u8]> = rgba.chunks_exact(4).collect();
    let mast = pixels.iter().filter(|p| p[..3] == [255, 0, 0]).count();
    assert!(mast > 100, "{mast} pixels of the mast");
    // Ground below the horizon: lit, textured, not the mast.
    let ground: std::collections::HashSet<&[u8]> = pixels[(h as usize / 2) * w as usize..]
        .iter()
        .copied()
        .filter(|p| p[..3] != [255, 0, 0])
        .collect();
    assert!(ground.len() > 500, "{} colours of ground", ground.len());
}

fn view_opens_draws_and_screenshots_itself_under_xvfb() {
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

/// `view` of the gaussian scene at 160×120 for `frames` frames with `--json`, its screenshot
/// written to `shot`, with `env` set: the JSON object it printed.
fn view_json(
    shot: &std::path::Path,
    frames: u32,
    env: &[(&str, &str)],
) -> serde_json::Map<String, serde_json::Value> {
    let scene = manifest_dir().join("sketches/gaussian.toml");
    let out = Command::new("xvfb-run")
        .args(["-a", "-s", "-screen 0 640x480x24"])
        .arg(env!("CARGO_BIN_EXE_terrain"))
        .args([
            "view",
            scene.to_str().unwrap(),
            "--size",
            "160x120",
            "--json",
        ])
        .args(["--frames", &frames.to_string(), "--screenshot"])
        .arg(shot)
        .envs(env.iter().copied())
        .output()
        .expect("run xvfb-run");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "view failed: {err}");
    let stdout = String::from_utf8_lossy(&out.stdout);
    let lines: Vec<&str> = stdout.lines().collect();
    assert_eq!(lines.len(), 1, "one JSON line on stdout: {stdout}");
    match serde_json::from_str(lines[0]) {
        Ok(serde_json::Value::Object(o)) => o,
        _ => panic!("not a JSON object: {stdout}"),
    }
}

/// Under Xvfb a surface can be made: the window presents through it, and `--json` says so with
/// the frame count and positive medians.
fn view_presents_through_a_surface_and_prints_its_figures_as_json() {
    let dir = scratch("view-json");
    let json = view_json(&dir.join("shot.png"), 5, &[]);
    assert_eq!(json["present"], "surface", "{json:?}");
    assert_eq!(json["frames"], 5, "{json:?}");
    for key in ["interval_ms_median", "cpu_ms_median", "gpu_ms_median"] {
        let v = json[key].as_f64();
        assert!(v.is_some_and(|v| v > 0.0), "{key}: {json:?}");
    }
}

/// `TERRAIN_VIEW_PRESENT=cpu` takes the fallback, the frame read back and drawn through
/// softbuffer: the same terrain `render` draws, between the figures.
fn view_presents_through_the_cpu_where_asked_and_shows_the_same_terrain() {
    let dir = scratch("view-cpu");
    let shot = dir.join("shot.png");
    let json = view_json(&shot, 3, &[("TERRAIN_VIEW_PRESENT", "cpu")]);
    assert_eq!(json["present"], "cpu", "{json:?}");
    assert_eq!(json["frames"], 3, "{json:?}");
    let (w, h, view) = read_png(&shot).expect("screenshot written");
    assert_eq!((w, h), (160, 120));
    let band = |img: &[u8]| img[56 * 160 * 4..104 * 160 * 4].to_vec();
    let db = psnr(&band(&view), &band(&rendered(&dir, "warped")));
    assert!(
        db >= 40.0,
        "the CPU path's terrain differs from render's: {db:.1} dB"
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

/// A shell function for the xdotool scripts: `written FILE` waits (up to a minute) until the
/// window has written FILE. A screenshot is taken at the next frame drawn, seconds after its key
/// on a loaded machine, so a key that moves the camera waits for the shot before it.
const WRITTEN: &str =
    "written() { n=0; while [ ! -s \"$1\" ] && [ $n -lt 600 ]; do sleep 0.1; n=$((n+1)); done; }";

fn view_keys_switch_mode_record_the_path_and_quit() {
    let dir = scratch("view-keys");
    let scene = dir.join("gaussian.toml");
    std::fs::copy(manifest_dir().join("sketches/gaussian.toml"), &scene).unwrap();
    let shot = dir.join("shot.png");
    // 2: GeoMipMap; P: screenshot; R, W held for 2 s, R: a recorded flight north; Esc: quit.
    let script = format!(
        "timeout 120 {bin} view {scene} --size 160x120 --screenshot {shot} --out-dir {dir} & pid=$!\n\
         wid=$(xdotool search --sync --name 'terrain view')\n\
         xdotool windowfocus --sync $wid\n\
         {WRITTEN}\n\
         sleep 1; xdotool key 2; sleep 3; xdotool key p; written {shot}\n\
         xdotool key p; written {dir}/gaussian-view-2.png\n\
         xdotool key r; xdotool keydown w; sleep 2; xdotool keyup w; xdotool key r; sleep 1\n\
         xdotool key Escape\n\
         wait $pid\n",
        bin = env!("CARGO_BIN_EXE_terrain"),
        scene = scene.display(),
        shot = shot.display(),
        dir = dir.join("views").display(),
    );
    // A screenshot of an earlier session that the second P must not overwrite.
    std::fs::create_dir_all(dir.join("views")).unwrap();
    std::fs::write(dir.join("views/gaussian-view-1.png"), b"earlier").unwrap();
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

    // The second P took the next free name in --out-dir.
    assert_eq!(
        std::fs::read(dir.join("views/gaussian-view-1.png")).unwrap(),
        b"earlier"
    );
    let (w, h, _) = read_png(&dir.join("views/gaussian-view-2.png")).expect("second screenshot");
    assert_eq!((w, h), (160, 120));

    // R … R wrote the scene with the path flown into --out-dir: north (W, the camera looks
    // north), at speed.
    let flown = dir.join("views/gaussian-flown.toml");
    let recorded = terrain_engine::scene::Scene::load(&flown).expect("the recorded scene loads");
    let path = recorded.path.expect("a [path]");
    let (first, last) = (
        path.keys[0].position.expect("a planar key"),
        path.keys[path.keys.len() - 1]
            .position
            .expect("a planar key"),
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
    assert!(terrain_engine::flight::path::CameraPath::new(&path).is_ok());
}

/// Over a planet the window draws what `render` draws (clipmaps), and W flies along the
/// camera's heading on a great circle: the recorded `[path]` is a planet's (the camera's keys,
/// the time flown), heading east as the scene looks, at the altitude it started from.
fn view_flies_over_a_planet_and_records_a_planet_path() {
    let dir = scratch("view-planet");
    let scene = dir.join("planet.toml");
    let text = std::fs::read_to_string(manifest_dir().join("sketches/planet-10km.toml")).unwrap();
    // A coarser planet than the bundled one, so llvmpipe draws a frame in well under a second.
    let text = text
        .replace(
            "[planet]\n",
            "[planet]\nphi_steps = 128\nrings_per_level = 10\n",
        )
        .replace(
            "synthetic = \"planet\"\n",
            "synthetic = \"planet\"\nsize = 256\n",
        );
    std::fs::write(&scene, text).unwrap();
    let shot = dir.join("shot.png");
    let script = format!(
        "timeout 120 {bin} view {scene} --size 160x120 --screenshot {shot} --out-dir {dir} & pid=$!\n\
         wid=$(xdotool search --sync --name 'terrain view')\n\
         xdotool windowfocus --sync $wid\n\
         {WRITTEN}\n\
         sleep 2; xdotool key p; written {shot}\n\
         xdotool key r; xdotool keydown w; sleep 2; xdotool keyup w; xdotool key r; sleep 1\n\
         xdotool key Escape\n\
         wait $pid\n",
        bin = env!("CARGO_BIN_EXE_terrain"),
        scene = scene.display(),
        shot = shot.display(),
        dir = dir.join("views").display(),
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
    let (_, _, view) = read_png(&shot).expect("screenshot written by P");
    let png = dir.join("render.png");
    let rendered = Command::new(env!("CARGO_BIN_EXE_terrain"))
        .args(["render", scene.to_str().unwrap(), "-o"])
        .arg(&png)
        .args(["--size", "160x120"])
        .output()
        .unwrap();
    assert!(
        rendered.status.success(),
        "{}",
        String::from_utf8_lossy(&rendered.stderr)
    );
    let band = |img: &[u8]| img[56 * 160 * 4..104 * 160 * 4].to_vec();
    let db = psnr(&band(&view), &band(&read_png(&png).unwrap().2));
    assert!(
        db >= 40.0,
        "the window's planet differs from render's: {db:.1} dB"
    );

    let flown = dir.join("views/planet-flown.toml");
    let recorded = terrain_engine::scene::Scene::load(&flown).expect("the recorded scene loads");
    let path = recorded.path.clone().expect("a [path]");
    let (first, last) = (&path.keys[0], &path.keys[path.keys.len() - 1]);
    assert!(path.duration_s.is_some_and(|d| d > 1.0), "{path:?}");
    let east = last.lon_deg.unwrap() - first.lon_deg.unwrap();
    let north = last.lat_deg.unwrap() - first.lat_deg.unwrap();
    // Heading 100°: mostly east, a little south; 8 km/s at 10 km for about 2 s.
    assert!(
        east > 0.05 && north < 0.0 && north.abs() < east,
        "{first:?} → {last:?}"
    );
    assert!(
        (last.altitude_m.unwrap() - 10_000.0).abs() < 1.0,
        "{last:?}"
    );
    assert!(terrain_engine::flight::path::PlanetFlight::of_scene(&recorded, 6_371_000.0).is_ok());
}
