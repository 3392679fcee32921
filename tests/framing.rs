//! The default camera frames a user's sketch so that it fills the picture (docs/scene.md, “The
//! default camera”): the sketch's share of the frame by `--positions`, its central 80 % in view,
//! from the south and 35–60° down; the starter scene framed anew when its heading and pitch are
//! edited; `render --json`'s `camera.look_at` on the ground the view is centred on.

mod common;

use common::{manifest_dir, read_npy, scratch, terrain};
use glam::DVec3;
use std::path::{Path, PathBuf};

/// The least share of a square frame, and of a 16:9 one, the sketch fills in the default view.
const SQUARE_SHARE: f64 = 0.40;
const WIDE_SHARE: f64 = 0.35;

/// What a test needs of a sketch: its extent (world metres from the south-west node) and heights.
struct Sketch {
    path: PathBuf,
    size: [f64; 2],
    z: [f64; 2],
}

fn sketch(path: PathBuf) -> Sketch {
    let (code, out, err) = terrain(&["info", path.to_str().unwrap(), "--json"]);
    assert_eq!(code, 0, "{err}");
    let info: serde_json::Value = serde_json::from_str(&out).unwrap();
    let g = |k: &str| info[k].as_f64().unwrap();
    Sketch {
        size: [
            (g("width") - 1.0) * g("dx_m"),
            (g("height") - 1.0) * g("dy_m"),
        ],
        // Ground below the water (at 0 m by default) lies under its flat surface.
        z: [g("min_m").max(0.0), g("max_m").max(0.0)],
        path,
    }
}

/// The committed fixtures: a UTM GeoTIFF, a geographic grid, a State Plane GeoTIFF in feet and
/// the bundled DEM.
fn fixtures() -> Vec<Sketch> {
    let formats = manifest_dir().join("tests/data/formats");
    [
        formats.join("utm-metres-Float32.tif"),
        formats.join("grid.asc"),
        formats.join("stateplane-feet-Float32.tif"),
        manifest_dir().join("sketches/jacksboro_fault_dem.asc"),
    ]
    .into_iter()
    .map(sketch)
    .collect()
}

/// `render SCENE --size SIZE --positions … --json` with `sets`: the JSON and the share of the
/// frame's pixels whose world position lies on the sketch's rectangle.
fn render(
    scene: &Path,
    s: &Sketch,
    size: &str,
    sets: &[&str],
    out: &Path,
) -> (serde_json::Value, f64) {
    let (png, npy) = (out.with_extension("png"), out.with_extension("npy"));
    let mut args = vec![
        "render",
        scene.to_str().unwrap(),
        "-o",
        png.to_str().unwrap(),
        "--size",
        size,
        "--positions",
        npy.to_str().unwrap(),
        "--json",
    ];
    for set in sets {
        args.extend(["--set", set]);
    }
    let (code, stdout, err) = terrain(&args);
    assert_eq!(code, 0, "{args:?}: {err}");
    let json: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    let (_, values) = read_npy(&npy);
    let [w, h] = s.size;
    let on_sketch = values
        .chunks_exact(4)
        .filter(|p| p[3] > 0.5 && (0.0..=w).contains(&p[0]) && (0.0..=h).contains(&p[1]))
        .count();
    (json, on_sketch as f64 / (values.len() / 4) as f64)
}

fn v3(camera: &serde_json::Value, key: &str) -> DVec3 {
    let a: Vec<f64> = camera[key]
        .as_array()
        .unwrap_or_else(|| panic!("no {key} in {camera}"))
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    DVec3::new(a[0], a[1], a[2])
}

/// Where `p` lands in the frame of the camera `render --json` reports: (x, y) in tangents of
/// the half angles over the frame's own (±1 is the frame's edge), and its depth.
fn in_frame(json: &serde_json::Value, p: DVec3) -> (f64, f64, f64) {
    let camera = &json["camera"];
    let eye = v3(camera, "position");
    let forward = (v3(camera, "look_at") - eye).normalize();
    let right = forward.cross(DVec3::Z).normalize();
    let up = right.cross(forward);
    let aspect = json["width"].as_f64().unwrap() / json["height"].as_f64().unwrap();
    // The scenes here keep the default 60° vertical field of view.
    let tan = 30f64.to_radians().tan();
    let q = p - eye;
    let depth = forward.dot(q);
    (
        right.dot(q) / depth / (tan * aspect),
        up.dot(q) / depth / tan,
        depth,
    )
}

/// The sketch's central 80 % (its rectangle shrunk by a tenth on each side), from its lowest
/// to its highest height, lies whole in the frame.
fn assert_core_in_frame(json: &serde_json::Value, s: &Sketch, what: &str) {
    let [w, h] = s.size;
    for x in [0.1 * w, 0.9 * w] {
        for y in [0.1 * h, 0.9 * h] {
            for z in s.z {
                let (sx, sy, depth) = in_frame(json, DVec3::new(x, y, z));
                assert!(
                    depth > 0.0 && sx.abs() <= 1.0 && sy.abs() <= 1.0,
                    "{what}: ({x:.0}, {y:.0}, {z:.0}) at ({sx:.3}, {sy:.3}) of the frame"
                );
            }
        }
    }
}

/// Each fixture by itself, square and 16:9: the sketch fills at least 40 % and 35 % of the
/// frame, its central 80 % in view, seen from the south, 35–60° down.
#[test]
fn the_default_view_fills_the_frame_with_the_sketch() {
    let dir = scratch("framing-default");
    for (k, s) in fixtures().iter().enumerate() {
        for (size, least) in [("128", SQUARE_SHARE), ("224x126", WIDE_SHARE)] {
            let what = format!("{} at {size}", s.path.display());
            let (json, share) = render(&s.path, s, size, &[], &dir.join(format!("{k}-{size}")));
            assert!(share >= least, "{what}: the sketch fills {share:.3}");
            assert_core_in_frame(&json, s, &what);
            let camera = &json["camera"];
            let (heading, pitch) = (
                camera["heading_deg"].as_f64().unwrap(),
                camera["pitch_deg"].as_f64().unwrap(),
            );
            assert!(heading.abs() < 1e-6, "{what}: {camera}");
            assert!((-60.0..=-35.0).contains(&pitch), "{what}: {camera}");
            let eye = v3(camera, "position");
            assert!(
                eye.y < 0.5 * s.size[1],
                "{what}: eye {eye} north of the centre"
            );
        }
    }
}

/// The README's edit: `terrain scene` writes the default view by heading and pitch, so turning
/// it (west, and west and steeper) frames the sketch anew from the other side.
#[test]
fn the_starter_scene_frames_the_sketch_anew_when_turned() {
    let dir = scratch("framing-starter");
    let s = sketch(manifest_dir().join("tests/data/formats/utm-metres-Float32.tif"));
    let toml = dir.join("mine.toml");
    let (code, _, err) = terrain(&[
        "scene",
        s.path.to_str().unwrap(),
        "-o",
        toml.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    let turns: [&[&str]; 2] = [
        &["camera.heading_deg=270"],
        &["camera.heading_deg=270", "camera.pitch_deg=-60"],
    ];
    for (k, sets) in turns.iter().enumerate() {
        let what = format!("{sets:?}");
        let (json, share) = render(&toml, &s, "128", sets, &dir.join(format!("turn-{k}")));
        assert!(share >= SQUARE_SHARE, "{what}: the sketch fills {share:.3}");
        assert_core_in_frame(&json, &s, &what);
        let camera = &json["camera"];
        let heading = camera["heading_deg"].as_f64().unwrap();
        assert!((heading - 270.0).abs() < 1e-6, "{what}: {camera}");
        // Looking west, from the east.
        assert!(
            v3(camera, "position").x > 0.5 * s.size[0],
            "{what}: {camera}"
        );
    }
}

/// `camera.look_at` is where the view's central ray meets the ground, as `terrain height` gives
/// it at the footprint the ray reaches it with; a `look_at` the scene gives is reported as given.
#[test]
fn the_reported_look_at_is_on_the_ground() {
    let dir = scratch("framing-look-at");
    let s = sketch(manifest_dir().join("sketches/jacksboro_fault_dem.asc"));
    let at_place = [
        "camera.lat_deg=36.55",
        "camera.lon_deg=-84.25",
        "camera.altitude_m=500",
        "camera.pitch_deg=-20",
    ];
    for (k, sets) in [&[][..], &at_place[..]].iter().enumerate() {
        let what = format!("{sets:?}");
        let (json, _) = render(&s.path, &s, "64", sets, &dir.join(format!("view-{k}")));
        let camera = &json["camera"];
        let (eye, look) = (v3(camera, "position"), v3(camera, "look_at"));
        // The footprint the march reaches the ground with: its distance times a pixel's angle.
        let footprint = (look - eye).length() * 2.0 * 30f64.to_radians().tan() / 64.0;
        let mut args = vec![
            "height".to_string(),
            s.path.to_str().unwrap().to_string(),
            "--xy".into(),
            format!("{},{}", look.x, look.y),
            "--footprint-m".into(),
            footprint.to_string(),
            "--json".into(),
        ];
        for set in *sets {
            args.extend(["--set".to_string(), set.to_string()]);
        }
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let (code, out, err) = terrain(&args);
        assert_eq!(code, 0, "{err}");
        let height: serde_json::Value = serde_json::from_str(&out).unwrap();
        let ground = height["z"].as_f64().unwrap();
        assert!(
            (look.z - ground).abs() < 0.5,
            "{what}: look_at {look} against the ground's {ground:.2}"
        );
        // On the sketch, in the centre of the frame.
        assert!((0.0..=s.size[0]).contains(&look.x) && (0.0..=s.size[1]).contains(&look.y));
        let (sx, sy, _) = in_frame(&json, look);
        assert!(sx.abs() < 1e-9 && sy.abs() < 1e-9, "{what}: {camera}");
    }
    // A look_at the scene gives stays the scene's.
    let given = [15000.0, 16000.0, 5000.0];
    let (json, _) = render(
        &s.path,
        &s,
        "32",
        &[
            "camera.position=[15000.0, -5000.0, 9000.0]",
            &format!("camera.look_at={given:?}"),
        ],
        &dir.join("given"),
    );
    assert_eq!(v3(&json["camera"], "look_at"), DVec3::from(given));
}
