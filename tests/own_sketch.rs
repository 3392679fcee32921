//! A user's own height map: any sketch a command takes in place of a scene, the default camera
//! that frames it, cameras placed by map coordinates and by latitude and longitude (held to
//! GDAL's `gdaltransform`), and `terrain scene`'s starter.

mod common;

use common::{manifest_dir, scratch, terrain};
use std::path::{Path, PathBuf};

fn formats() -> PathBuf {
    manifest_dir().join("tests/data/formats")
}

/// `render --json` of `args`, parsed; panics with stderr when it fails.
fn render_json(args: &[&str]) -> serde_json::Value {
    let mut all = vec!["render"];
    all.extend_from_slice(args);
    all.push("--json");
    let (code, out, err) = terrain(&all);
    assert_eq!(code, 0, "{all:?}: {err}");
    serde_json::from_str(&out).unwrap_or_else(|e| panic!("{e}: {out}"))
}

/// The share of a `--positions` file's pixels that show the sketch's ground.
fn ground_share(npy: &Path) -> f64 {
    let bytes = std::fs::read(npy).unwrap();
    let header = u16::from_le_bytes([bytes[8], bytes[9]]) as usize + 10;
    let values: Vec<f64> = bytes[header..]
        .chunks_exact(8)
        .map(|b| f64::from_le_bytes(b.try_into().unwrap()))
        .collect();
    let px = values.len() / 4;
    values.chunks_exact(4).filter(|p| p[3] > 0.5).count() as f64 / px as f64
}

/// The least share of a square frame the default view's sketch covers (docs/scene.md, the
/// default camera): its central 80 % framed at −45° fills half the frame (0.50 on these
/// fixtures; `--positions` counts the plain beyond the sketch as not the sketch).
const LEAST_GROUND_SHARE: f64 = 0.4;

/// Every fixture that reads renders by itself, as a scene with every default, with its ground in
/// view from above.
#[test]
fn every_readable_format_fixture_renders_by_itself_with_its_ground_in_view() {
    let dir = scratch("own-formats");
    let mut files: Vec<PathBuf> = std::fs::read_dir(formats())
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .filter(|p| {
            let ext = p.extension().and_then(|e| e.to_str()).unwrap_or("");
            !matches!(ext, "json" | "pgw") && p.is_file()
        })
        .collect();
    files.sort();
    // The tiles folder as a glob of tiles.
    files.push(formats().join("tiles/*.tif"));
    let readable: Vec<PathBuf> = files
        .into_iter()
        .filter(|f| terrain(&["info", f.to_str().unwrap()]).0 == 0)
        .collect();
    assert!(readable.len() > 60, "{} fixtures read", readable.len());
    let chunks: Vec<Vec<PathBuf>> = readable
        .chunks(readable.len().div_ceil(2))
        .map(<[_]>::to_vec)
        .collect();
    std::thread::scope(|s| {
        for chunk in &chunks {
            let dir = &dir;
            s.spawn(move || {
                for (k, f) in chunk.iter().enumerate() {
                    let name = format!(
                        "{}-{k}",
                        f.file_name().unwrap().to_string_lossy().replace('*', "all")
                    );
                    let (png, npy) = (
                        dir.join(format!("{name}.png")),
                        dir.join(format!("{name}.npy")),
                    );
                    let json = render_json(&[
                        f.to_str().unwrap(),
                        "-o",
                        png.to_str().unwrap(),
                        "--size",
                        "128",
                        "--positions",
                        npy.to_str().unwrap(),
                    ]);
                    let info = terrain(&["info", f.to_str().unwrap(), "--json"]).1;
                    let info: serde_json::Value = serde_json::from_str(&info).unwrap();
                    let camera = &json["camera"];
                    assert_frames_the_sketch(camera, &info, f);
                    // Relief taller than the sketch is wide (the 32- and 16-bit fixtures scaled
                    // to tens of kilometres) shows as a spire in a frame of sky.
                    let g = |k: &str| info[k].as_f64().unwrap();
                    let relief = g("max_m") - g("min_m");
                    let share = ground_share(&npy);
                    assert!(
                        share >= LEAST_GROUND_SHARE || relief > g("width") * g("dx_m"),
                        "{}: ground over {share:.3} of the frame",
                        f.display()
                    );
                    assert!(camera["altitude_m"].as_f64().unwrap() > 0.0, "{camera}");
                    assert!(
                        (camera["pitch_deg"].as_f64().unwrap() + 45.0).abs() < 1e-6,
                        "{camera}"
                    );
                }
            });
        }
    });
}

/// The sketch's central 80 % (`info`'s extent shrunk by a tenth on each side, from its lowest
/// to its highest height) lies whole inside the frame of the camera `render --json` reports
/// (60° vertical field of view, square image), seen from the south (the default heading is
/// north).
fn assert_frames_the_sketch(camera: &serde_json::Value, info: &serde_json::Value, f: &Path) {
    let v3 = |k: &str| {
        let a: Vec<f64> = camera[k]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        glam::DVec3::new(a[0], a[1], a[2])
    };
    let (eye, target) = (v3("position"), v3("look_at"));
    let forward = (target - eye).normalize();
    let right = forward.cross(glam::DVec3::Z).normalize();
    let up = right.cross(forward);
    let g = |k: &str| info[k].as_f64().unwrap();
    let (w, h) = (
        (g("width") - 1.0) * g("dx_m"),
        (g("height") - 1.0) * g("dy_m"),
    );
    let tan = 30f64.to_radians().tan();
    for x in [0.1 * w, 0.9 * w] {
        for y in [0.1 * h, 0.9 * h] {
            // Ground below the water (at 0 m by default) lies under its flat surface.
            for z in [g("min_m").max(0.0), g("max_m").max(0.0)] {
                let q = glam::DVec3::new(x, y, z) - eye;
                let depth = forward.dot(q);
                let (sx, sy) = (right.dot(q) / depth, up.dot(q) / depth);
                assert!(
                    depth > 0.0 && sx.abs() <= tan && sy.abs() <= tan,
                    "{}: corner ({x}, {y}, {z}) outside the frame ({sx:.3}, {sy:.3})",
                    f.display()
                );
            }
        }
    }
    assert!(
        eye.y < 0.5 * h,
        "{}: eye {eye} north of the centre",
        f.display()
    );
}

/// A sketch in place of the scene in `fly` flies the default orbit: frames at one distance from
/// the sketch's centre, all around it.
#[test]
fn fly_orbits_a_sketch_given_by_itself() {
    let dir = scratch("own-fly");
    let asc = formats().join("grid.asc");
    let (code, _, err) = terrain(&[
        "fly",
        asc.to_str().unwrap(),
        "--out-dir",
        dir.to_str().unwrap(),
        "--frames",
        "4",
        "--size",
        "32",
    ]);
    assert_eq!(code, 0, "{err}");
    let csv = std::fs::read_to_string(dir.join("frames.csv")).unwrap();
    let mut lines = csv.lines();
    let head: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| head.iter().position(|h| *h == name).unwrap();
    let (x, y) = (col("x_m"), col("y_m"));
    let eyes: Vec<[f64; 2]> = lines
        .map(|l| {
            let v: Vec<&str> = l.split(',').collect();
            [v[x].parse().unwrap(), v[y].parse().unwrap()]
        })
        .collect();
    assert_eq!(eyes.len(), 4);
    let info = terrain(&["info", asc.to_str().unwrap(), "--json"]).1;
    let info: serde_json::Value = serde_json::from_str(&info).unwrap();
    let f = |k: &str| info[k].as_f64().unwrap();
    let centre = [
        0.5 * (f("width") - 1.0) * f("dx_m"),
        0.5 * (f("height") - 1.0) * f("dy_m"),
    ];
    let radius: Vec<f64> = eyes
        .iter()
        .map(|e| (e[0] - centre[0]).hypot(e[1] - centre[1]))
        .collect();
    for r in &radius {
        assert!((r / radius[0] - 1.0).abs() < 0.02, "{radius:?}");
    }
    // The first frame south of the centre, the next ones a third of the way round each.
    assert!(
        eyes[0][1] < centre[1] && (eyes[0][0] - centre[0]).abs() < 1.0,
        "{eyes:?}"
    );
    assert!(eyes[1][0] < centre[0] && eyes[2][0] > centre[0], "{eyes:?}");
}

/// Expected world positions from GDAL 3.6 (Debian's gdal-bin), computed with:
/// - `echo "-84.25 36.55" | gdaltransform -i sketches/jacksboro_fault_dem.asc` → pixel 196.5,
///   line 219.5 (of 403 × 344, pixel-is-area): the node 196 east, 343 − 219 = 124 north of the
///   south-west one;
/// - `echo "-84.2306 36.639" | gdaltransform -s_srs EPSG:4326 -t_srs EPSG:32616` →
///   747598.308200053 4058399.28054532 (utm-metres-Float32.tif, south-west node 746130.5819449155,
///   4056850.7962117507, as `terrain info` and gdalinfo agree);
/// - `… -t_srs EPSG:2274` → 2487650.87604203 844000.119763143 US survey feet
///   (stateplane-feet-Float32.tif, south-west node 2482871.08897647, 839304.2471752663).
#[test]
fn a_camera_by_latitude_and_longitude_stands_where_gdal_puts_it() {
    let ft = 1200.0 / 3937.0;
    let cases = [
        (
            manifest_dir().join("sketches/jacksboro_fault_dem.asc"),
            [36.55, -84.25],
            [196.0 * 74.40117103338355, 124.0 * 92.6625668242124],
        ),
        (
            formats().join("utm-metres-Float32.tif"),
            [36.639, -84.2306],
            [
                747598.308200053 - 746130.5819449155,
                4058399.28054532 - 4056850.7962117507,
            ],
        ),
        (
            formats().join("stateplane-feet-Float32.tif"),
            [36.639, -84.2306],
            [
                (2487650.87604203 - 2482871.08897647) * ft,
                (844000.119763143 - 839304.2471752663) * ft,
            ],
        ),
    ];
    let dir = scratch("own-latlon");
    for (sketch, [lat, lon], want) in cases {
        let set = |k: &str, v: f64| format!("camera.{k}={v}");
        let keys = [
            set("lat_deg", lat),
            set("lon_deg", lon),
            set("altitude_m", 150.0),
            set("heading_deg", 45.0),
            set("pitch_deg", -10.0),
        ];
        let png = dir.join("x.png");
        let mut args = vec![
            sketch.to_str().unwrap(),
            "-o",
            png.to_str().unwrap(),
            "--size",
            "16",
        ];
        for k in &keys {
            args.extend(["--set", k]);
        }
        let camera = render_json(&args)["camera"].clone();
        let pos: Vec<f64> = camera["position"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        let what = sketch.display();
        assert!(
            (pos[0] - want[0]).abs() < 1.0 && (pos[1] - want[1]).abs() < 1.0,
            "{what}: {pos:?} against GDAL's {want:?}"
        );
        // Above the ground there by the altitude: the sketch's nodes read back and bilinear.
        let ground = bilinear_ground(&sketch, [pos[0], pos[1]]);
        assert!(
            (pos[2] - ground - 150.0).abs() < 1.0,
            "{what}: eye {} over ground {ground}",
            pos[2]
        );
        let got = |k: &str| camera[k].as_f64().unwrap();
        assert!(
            (got("heading_deg") - 45.0).abs() < 0.5 && (got("pitch_deg") + 10.0).abs() < 0.5,
            "{camera}"
        );
        assert!(
            (got("lat_deg") - lat).abs() < 1e-6 && (got("lon_deg") - lon).abs() < 1e-6,
            "{camera}"
        );
    }
}

/// The sketch's height at world `p`, bilinear between its four nodes, from the grid as read.
fn bilinear_ground(sketch: &Path, p: [f64; 2]) -> f64 {
    let atlas = terrain_engine::sketch::Atlas::load(sketch, &Default::default()).unwrap();
    let level = &atlas.levels[0];
    let (u, v) = (p[0] / atlas.dx, p[1] / atlas.dy);
    let (i, j) = (u.floor() as usize, v.floor() as usize);
    let (fu, fv) = (u - i as f64, v - j as f64);
    let z = |i: usize, j: usize| level.data[j * level.width + i] as f64;
    let south = z(i, j) * (1.0 - fu) + z(i + 1, j) * fu;
    let north = z(i, j + 1) * (1.0 - fu) + z(i + 1, j + 1) * fu;
    south * (1.0 - fv) + north * fv
}

/// `map_xy` places the eye at the file's own coordinates, the south-west node the world's origin.
#[test]
fn map_xy_is_the_files_own_coordinates() {
    let dir = scratch("own-mapxy");
    let tif = formats().join("utm-metres-Float32.tif");
    let png = dir.join("x.png");
    let json = render_json(&[
        tif.to_str().unwrap(),
        "-o",
        png.to_str().unwrap(),
        "--size",
        "16",
        "--set",
        "camera.map_xy=[747000.0, 4058000.0]",
        "--set",
        "camera.altitude_m=50",
        "--set",
        "camera.pitch_deg=-20",
    ]);
    let pos = &json["camera"]["position"];
    let x = pos[0].as_f64().unwrap() - (747000.0 - 746130.5819449155);
    let y = pos[1].as_f64().unwrap() - (4058000.0 - 4056850.7962117507);
    assert!(x.abs() < 1e-6 && y.abs() < 1e-6, "{pos}");
    // A sketch without a georeference has no map coordinates: one line naming the key.
    let scene = dir.join("hills.toml");
    let text = "[sketch]\nsynthetic = \"hills\"\n[camera]\nmap_xy = [1.0, 2.0]\naltitude_m = 5.0\n";
    std::fs::write(&scene, text).unwrap();
    let (code, _, err) = terrain(&[
        "render",
        scene.to_str().unwrap(),
        "-o",
        png.to_str().unwrap(),
    ]);
    assert_eq!(code, 1);
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.contains("camera.map_xy") && err.contains("no georeference"),
        "{err}"
    );
}

/// `terrain scene` writes a scene that renders as it is, with the camera the sketch alone gets.
#[test]
fn the_starter_scene_renders_the_default_view() {
    let dir = scratch("own-scene");
    let tif = formats().join("utm-metres-Float32.tif");
    let toml = dir.join("mine/scene.toml");
    let (code, _, err) = terrain(&["scene", tif.to_str().unwrap(), "-o", toml.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    let text = std::fs::read_to_string(&toml).unwrap();
    for section in [
        "sketch",
        "camera",
        "detail",
        "warp",
        "importance",
        "render",
        "geomipmap",
        "reference",
        "light",
        "stream",
    ] {
        assert!(
            text.contains(&format!("\n[{section}]\n")),
            "no [{section}]:\n{text}"
        );
    }
    // Every key line carries a comment.
    for line in text
        .lines()
        .filter(|l| l.contains(" = ") && !l.starts_with('#'))
    {
        assert!(line.contains(" # "), "no comment: {line}");
    }
    // The camera as the default view makes it: framed along a heading and a pitch, its place
    // offered commented out (tests/framing.rs turns it).
    assert!(text.contains("\n# map_xy = ["), "{text}");
    assert!(text.contains("\n# altitude_m = "), "{text}");
    assert!(!text.contains("\nmap_xy = "), "{text}");
    assert!(text.contains("\nheading_deg = 0.0 "), "{text}");
    assert!(text.contains("\npitch_deg = -45.0 "), "{text}");
    let png = |name: &str| dir.join(name);
    let from_scene = render_json(&[
        toml.to_str().unwrap(),
        "-o",
        png("a.png").to_str().unwrap(),
        "--size",
        "64",
    ]);
    let by_itself = render_json(&[
        tif.to_str().unwrap(),
        "-o",
        png("b.png").to_str().unwrap(),
        "--size",
        "64",
    ]);
    let (a, b) = (
        &from_scene["camera"]["position"],
        &by_itself["camera"]["position"],
    );
    for k in 0..3 {
        let d = a[k].as_f64().unwrap() - b[k].as_f64().unwrap();
        assert!(d.abs() < 0.01, "{a} against {b}");
    }
    assert_eq!(from_scene["triangles"], by_itself["triangles"]);
    // The place offered, uncommented, holds the camera where the framing put it.
    let held = text
        .replace("\n# map_xy = [", "\nmap_xy = [")
        .replace("\n# altitude_m = ", "\naltitude_m = ");
    let held_toml = dir.join("mine/held.toml");
    std::fs::write(&held_toml, held).unwrap();
    let from_held = render_json(&[
        held_toml.to_str().unwrap(),
        "-o",
        png("c.png").to_str().unwrap(),
        "--size",
        "64",
    ]);
    let c = &from_held["camera"]["position"];
    for k in 0..3 {
        let d = c[k].as_f64().unwrap() - b[k].as_f64().unwrap();
        assert!(d.abs() < 0.02, "{c} against {b}");
    }
    // A scene given where a sketch is asked for is refused.
    let (code, _, err) = terrain(&["scene", toml.to_str().unwrap()]);
    assert_ne!(code, 0);
    assert!(err.contains("is a scene already"), "{err}");
}

/// A path `--set` gives is the user's, typed in the working folder.
#[test]
fn a_set_path_resolves_against_the_working_folder() {
    let dir = scratch("own-set-path");
    let scene = manifest_dir().join("sketches/jacksboro-small.toml");
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_terrain"))
        .current_dir(formats())
        .args(["render", scene.to_str().unwrap(), "-o"])
        .arg(dir.join("x.png"))
        .args([
            "--size",
            "16",
            "--set",
            "sketch.path=grid.asc",
            "--set",
            "camera.position=[100.0, 100.0, 2000.0]",
            "--set",
            "camera.look_at=[1000.0, 1000.0, 500.0]",
        ])
        .env("TERRAIN_QUIET", "1")
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// A jobs file's `scene =` and `warp` take a sketch as the other commands do.
#[test]
fn a_jobs_file_and_warp_take_a_sketch_for_a_scene() {
    let dir = scratch("own-jobs");
    let asc = formats().join("grid.asc");
    let jobs = dir.join("jobs.toml");
    let text = format!(
        "scene = {:?}\n\n[random]\ncount = 2\nseed = 3\n",
        asc.to_string_lossy()
    );
    std::fs::write(&jobs, text).unwrap();
    let out = dir.join("out");
    let (code, _, err) = terrain(&[
        "batch",
        jobs.to_str().unwrap(),
        "--out-dir",
        out.to_str().unwrap(),
        "--size",
        "16",
    ]);
    assert_eq!(code, 0, "{err}");
    for k in 0..2 {
        assert!(out.join(format!("random-{k}.png")).is_file());
    }
    let warp = dir.join("warp");
    let (code, out, err) = terrain(&[
        "warp",
        asc.to_str().unwrap(),
        "--out-dir",
        warp.to_str().unwrap(),
        "--json",
    ]);
    assert_eq!(code, 0, "{err}");
    let json: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert!(json["cells_visible"].as_u64().unwrap() > 0, "{json}");
}

/// A camera or a path key placed far off the sketch (a latitude and longitude half a world away
/// from a UTM sketch, a position 1000 km off) is said once each, naming the key and the distance;
/// places on the sketch are not.
#[test]
fn places_far_off_the_sketch_are_warned_about_once() {
    let dir = scratch("own-sketch-off-map");
    std::fs::copy(
        formats().join("utm-metres-Float32.tif"),
        dir.join("utm.tif"),
    )
    .unwrap();
    let scene = dir.join("far.toml");
    std::fs::write(
        &scene,
        "[sketch]\npath = \"utm.tif\"\n[camera]\nlat_deg = 10.0\nlon_deg = 20.0\n\
         altitude_m = 500.0\n[path]\nkeys = [{ map_xy = [746500.0, 4057000.0], altitude_m = \
         100.0 }, { position = [1.0e6, 0.0, 800.0] }]\n",
    )
    .unwrap();
    let shot = dir.join("x.png");
    let (code, _, err) = terrain(&[
        "render",
        scene.to_str().unwrap(),
        "-o",
        shot.to_str().unwrap(),
        "--size",
        "16",
    ]);
    assert_eq!(code, 0, "{err}");
    let lines: Vec<&str> = err.lines().filter(|l| l.starts_with("warning:")).collect();
    assert_eq!(lines.len(), 2, "{err}");
    assert!(
        lines[0].contains("far.toml")
            && lines[0].contains("camera.lat_deg/lon_deg")
            && lines[0].contains("16566.6 km"),
        "{lines:?}"
    );
    assert!(
        lines[1].contains("path.keys[1].position") && lines[1].contains("997.2 km"),
        "{lines:?}"
    );
    // Placed on the sketch: quiet.
    let near = dir.join("near.toml");
    std::fs::write(
        &near,
        "[sketch]\npath = \"utm.tif\"\n[camera]\nmap_xy = [746500.0, 4057000.0]\n\
         altitude_m = 500.0\npitch_deg = -30.0\n",
    )
    .unwrap();
    let (code, _, err) = terrain(&[
        "render",
        near.to_str().unwrap(),
        "-o",
        shot.to_str().unwrap(),
        "--size",
        "16",
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(!err.contains("warning:"), "{err}");
}
