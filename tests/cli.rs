//! The command line on good and bad input: every bad input exits non-zero with one line on
//! stderr naming the cause, and never panics.

mod common;
use common::*;
use std::path::{Path, PathBuf};

/// Runs and checks the one-line failure naming `cause`; its exit code.
fn fails_with(args: &[&str], cause: &str) -> i32 {
    let (code, _, err) = terrain(args);
    assert_ne!(code, 0, "{args:?} succeeded");
    assert!(!err.contains("panicked"), "{args:?} panicked: {err}");
    assert_eq!(
        err.trim_end().lines().count(),
        1,
        "{args:?}: not one line: {err}"
    );
    assert!(
        err.contains(cause),
        "{args:?}: {err:?} does not name {cause:?}"
    );
    code
}

fn write(dir: &Path, name: &str, bytes: impl AsRef<[u8]>) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

const CAMERA: &str =
    "[camera]\nposition = [-200.0, -200.0, 900.0]\nlook_at = [1000.0, 1000.0, 100.0]\n";

fn scene_for(dir: &Path, sketch: &Path) -> PathBuf {
    write(
        dir,
        &format!("{}.toml", sketch.file_name().unwrap().to_string_lossy()),
        format!(
            "[sketch]\npath = {:?}\n{CAMERA}",
            sketch.file_name().unwrap()
        ),
    )
}

#[test]
fn usage_errors_are_one_line_too() {
    fails_with(&["rendr"], "unrecognized subcommand");
    fails_with(&["render"], "--output");
    fails_with(
        &["render", "x.toml", "-o", "x.png", "--mode", "fast"],
        "fast",
    );
    let scene = manifest_dir().join("sketches/hills.toml");
    fails_with(
        &[
            "render",
            scene.to_str().unwrap(),
            "-o",
            "x.png",
            "--tau",
            "-1",
        ],
        "'-1' for '--tau",
    );
}

#[test]
fn info_reads_the_bundled_sketch() {
    let path = manifest_dir().join("sketches/jacksboro_fault_dem.asc");
    let (code, out, _) = terrain(&["info", path.to_str().unwrap(), "--json"]);
    assert_eq!(code, 0);
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(
        (v["width"].as_u64(), v["height"].as_u64()),
        (Some(403), Some(344))
    );
    assert_eq!(
        (
            v["min_m"].as_f64(),
            v["max_m"].as_f64(),
            v["nodata"].as_u64()
        ),
        (Some(236.0), Some(1076.0), Some(0))
    );
    let spacing = v["spacing_m"].as_f64().unwrap();
    assert!((spacing - 74.4).abs() < 0.5, "{spacing}");
}

/// `terrain modes --json` is the mode table, row by row in its order: what scripts iterate.
#[test]
fn modes_lists_the_mode_table() {
    use terrain_engine::scene::{MODES, Scenes};
    let (code, out, err) = terrain(&["modes", "--json"]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    let rows = v["modes"].as_array().expect("modes");
    assert_eq!(rows.len(), MODES.len());
    for (row, m) in rows.iter().zip(&MODES) {
        assert_eq!(row["name"], m.mode.name());
        assert_eq!(row["display"], m.display);
        let scenes = match m.scenes {
            Scenes::Flat => "flat",
            Scenes::Planet => "planet",
            Scenes::Both => "both",
        };
        assert_eq!(row["scenes"], scenes);
        let sweep: Vec<&str> = m.sweep.iter().map(|&(key, _)| key).collect();
        assert_eq!(row["sweep"], serde_json::json!(sweep));
    }
    let (code, table, _) = terrain(&["modes"]);
    assert_eq!(code, 0);
    assert_eq!(table.lines().count(), MODES.len() + 1, "{table}");
    assert!(table.contains("geomipmap   GeoMipMap"), "{table}");
}

/// A reader that stops reading (`terrain info … | head -c 0`) ends the program quietly: exit 0,
/// nothing on stderr. `println!` panicked there, on the broken pipe.
#[cfg(unix)]
#[test]
fn a_closed_stdout_ends_the_program_without_a_panic() {
    use std::process::{Command, Stdio};
    let path = manifest_dir().join("sketches/jacksboro_fault_dem.asc");
    let mut child = Command::new(env!("CARGO_BIN_EXE_terrain"))
        .args(["info", path.to_str().unwrap(), "--json"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run terrain");
    // Closed before terrain has read the 403 × 344 sketch it reports on.
    drop(child.stdout.take());
    let out = child.wait_with_output().expect("terrain ends");
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{err}");
    assert!(err.is_empty(), "{err}");
}

#[test]
fn warp_writes_its_figures_and_statistics() {
    let dir = scratch("cli-warp");
    let scene = manifest_dir().join("sketches/jacksboro.toml");
    let (code, out, err) = terrain(&[
        "warp",
        scene.to_str().unwrap(),
        "--out-dir",
        dir.to_str().unwrap(),
        "--json",
        "--repeat",
        "2",
    ]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    for key in [
        "cells_visible",
        "ratio_within_0_5_2",
        "ratio_within_0_5_1",
        "demand_met",
        "flipped_cells",
        "nonfinite",
        "cpu_stage_us",
    ] {
        assert!(v.get(key).is_some(), "missing {key}");
    }
    assert!(v["ratio_within_0_5_2"].as_f64().unwrap() >= 0.85);
    assert_eq!(v["flipped_cells"].as_u64(), Some(0));
    for f in ["importance.png", "mesh.png", "ratio.png"] {
        let bytes = std::fs::read(dir.join(f)).unwrap();
        assert!(bytes.starts_with(b"\x89PNG"), "{f}");
    }
}

#[test]
fn malformed_sketches_fail_with_their_cause() {
    let dir = scratch("cli-malformed");
    let header = "ncols 4\nnrows 3\nxllcorner 0\nyllcorner 0\ncellsize 30\n";
    let cases: Vec<(PathBuf, &str)> = vec![
        (
            write(&dir, "truncated.asc", format!("{header}1 2 3 4\n5 6 7")),
            "truncated",
        ),
        (
            write(&dir, "header.asc", "ncols 4\nrows 3\ncellsize 30\n1 2 3 4"),
            "unknown header key `rows`",
        ),
        (
            write(&dir, "garbage.asc", [0u8, 159, 146, 150, 255, 0, 1, 2]),
            "binary",
        ),
        (
            write(&dir, "empty.asc", "ncols 0\nnrows 0\ncellsize 30\n"),
            "0×0",
        ),
        (
            write(&dir, "negative.asc", "ncols -4\nnrows 3\ncellsize 30\n"),
            "-4×3",
        ),
        (
            write(
                &dir,
                "text.asc",
                format!("{header}1 2 x 4 5 6 7 8 9 10 11 12"),
            ),
            "not a number",
        ),
        (write(&dir, "short.hgt", vec![0u8; 1000]), "neither"),
        (
            write(&dir, "garbage.png", b"\x89PNG\r\n\x1a\nnot really"),
            "PNG",
        ),
        (write(&dir, "garbage.tif", b"II*\0garbage"), "TIFF"),
        (
            write(&dir, "irregular.xyz", "0 0 1\n1 0 1\n0 1 1\n1.7 1 1\n"),
            "regular spacing",
        ),
        (write(&dir, "unknown.dem", "1 2 3"), "unknown sketch format"),
        (dir.join("missing.asc"), "No such file"),
    ];
    for (path, cause) in &cases {
        fails_with(&["info", path.to_str().unwrap()], cause);
        let scene = scene_for(&dir, path);
        fails_with(
            &[
                "warp",
                scene.to_str().unwrap(),
                "--out-dir",
                dir.join("out").to_str().unwrap(),
            ],
            cause,
        );
    }
}

#[test]
fn malformed_scenes_fail_naming_the_key() {
    let dir = scratch("cli-scenes");
    let sketch = "[sketch]\nsynthetic = \"hills\"\n";
    let cases = [
        (
            format!("{sketch}{CAMERA}fov = 60.0\n"),
            "unknown field `fov`",
        ),
        (
            format!("{sketch}{}", CAMERA.replace("900.0", "nan")),
            "camera.position",
        ),
        (
            format!(
                "{sketch}{}",
                CAMERA.replace("[1000.0, 1000.0, 100.0]", "[-200.0, -200.0, 900.0]")
            ),
            "look_at",
        ),
        (
            format!("{sketch}{CAMERA}fov_y_deg = 0.0\n"),
            "camera.fov_y_deg",
        ),
        (format!("{sketch}{CAMERA}width = 0\n"), "camera.width"),
        (
            format!("{sketch}{CAMERA}[warp]\nquad_px = 0.0\n"),
            "warp.quad_px",
        ),
        (format!("{sketch}{CAMERA}[warp]\nsize = 1\n"), "warp.size"),
        (
            format!("{sketch}{CAMERA}[detail]\noctaves = 99\n"),
            "detail.octaves",
        ),
        (
            format!("[sketch]\nsynthetic = \"volcano\"\n{CAMERA}"),
            "volcano",
        ),
        (
            format!("[sketch]\nsynthetic = \"hills\"\nsize = 1\n{CAMERA}"),
            "sketch.size",
        ),
        (
            format!("{sketch}[camera]\nposition = [0.0, 0.0]\nlook_at = [1.0, 1.0, 1.0]\n"),
            "line 4",
        ),
        (
            format!("{sketch}[camera]\nlook_at = [1.0, 1.0, 1.0]\n"),
            "camera: look_at and altitude_m need a place",
        ),
        ("this is not toml".to_string(), "line 1"),
    ];
    for (k, (text, cause)) in cases.iter().enumerate() {
        let path = write(&dir, &format!("s{k}.toml"), text);
        fails_with(
            &[
                "warp",
                path.to_str().unwrap(),
                "--out-dir",
                dir.join("out").to_str().unwrap(),
            ],
            cause,
        );
    }
}

/// Each reader on a small valid file of its format, written here.
#[test]
fn every_format_reads() {
    let dir = scratch("cli-formats");
    // SRTM 3″: 1201² big-endian i16, rows north first, one void.
    let mut hgt = Vec::with_capacity(1201 * 1201 * 2);
    for k in 0..1201 * 1201 {
        let v: i16 = if k == 5000 { -32768 } else { (k % 1201) as i16 };
        hgt.extend_from_slice(&v.to_be_bytes());
    }
    write(&dir, "N36W084.hgt", &hgt);
    // 16-bit grayscale PNG, 3×2.
    let mut png_bytes = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut png_bytes, 3, 2);
        enc.set_color(png::ColorType::Grayscale);
        enc.set_depth(png::BitDepth::Sixteen);
        let mut w = enc.write_header().unwrap();
        let px: Vec<u8> = [0u16, 100, 65535, 10, 20, 30]
            .iter()
            .flat_map(|v| v.to_be_bytes())
            .collect();
        w.write_image_data(&px).unwrap();
    }
    write(&dir, "h16.png", &png_bytes);
    // Float TIFF, 3×3, with a NaN.
    let tif = dir.join("f32.tif");
    {
        let f = std::fs::File::create(&tif).unwrap();
        let mut enc = tiff::encoder::TiffEncoder::new(f).unwrap();
        let data = [1.0f32, 2.0, 3.0, 4.0, f32::NAN, 6.0, 7.0, 8.0, 9.0];
        enc.write_image::<tiff::encoder::colortype::Gray32Float>(3, 3, &data)
            .unwrap();
    }
    write(
        &dir,
        "grid.xyz",
        "X;Y;Z\n100;200;5\n102;200;6\n100;202;7\n102;202;8\n",
    );
    let expect = [
        ("N36W084.hgt", 1201, 1, 0.0, 1200.0),
        ("h16.png", 3, 0, 0.0, 65535.0),
        ("f32.tif", 3, 1, 1.0, 9.0),
        ("grid.xyz", 2, 0, 5.0, 8.0),
    ];
    for (name, width, nodata, min, max) in expect {
        let (code, out, err) = terrain(&["info", dir.join(name).to_str().unwrap(), "--json"]);
        assert_eq!(code, 0, "{name}: {err}");
        let v: serde_json::Value = serde_json::from_str(&out).unwrap();
        assert_eq!(v["width"].as_u64(), Some(width), "{name}");
        assert_eq!(v["nodata"].as_u64(), Some(nodata), "{name}");
        assert_eq!(
            (v["min_m"].as_f64(), v["max_m"].as_f64()),
            (Some(min), Some(max)),
            "{name}"
        );
    }
    // SRTM 3″ at 36.5° N: 92.66 m north–south, 74.5 m east–west.
    let (_, out, _) = terrain(&["info", dir.join("N36W084.hgt").to_str().unwrap(), "--json"]);
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert!(
        (v["dy_m"].as_f64().unwrap() - 92.66).abs() < 0.05
            && (v["dx_m"].as_f64().unwrap() - 74.5).abs() < 0.2,
        "{v}"
    );
}

#[test]
fn render_writes_world_positions_that_agree_between_modes() {
    let dir = scratch("positions");
    let scene = manifest_dir().join("sketches/gaussian.toml");
    let mut world = Vec::new();
    for mode in ["reference", "warped"] {
        let npy = dir.join(format!("{mode}.npy"));
        let (code, _, err) = terrain(&[
            "render",
            scene.to_str().unwrap(),
            "-o",
            dir.join(format!("{mode}.png")).to_str().unwrap(),
            "--mode",
            mode,
            "--set",
            "camera.width=48",
            "--set",
            "camera.height=32",
            "--positions",
            npy.to_str().unwrap(),
        ]);
        assert_eq!(code, 0, "{err}");
        let (header, values) = read_npy(&npy);
        assert!(header.contains("'shape': (32, 48, 4)"), "{header}");
        assert_eq!(values.len(), 32 * 48 * 4);
        world.push(values);
    }
    // Ground pixels lie on the sketch (7680 m square) at the mountain's heights; the sky has w = 0.
    let (reference, warped) = (&world[0], &world[1]);
    let ground: Vec<usize> = (0..32 * 48)
        .filter(|&k| reference[4 * k + 3] == 1.0)
        .collect();
    assert!(
        ground.len() > 32 * 48 / 3 && ground.len() < 32 * 48,
        "{} ground pixels",
        ground.len()
    );
    let mut gaps: Vec<f64> = Vec::new();
    for &k in &ground {
        let p = &reference[4 * k..4 * k + 3];
        assert!(
            (0.0..=7680.0).contains(&p[0]) && (0.0..=7680.0).contains(&p[1]),
            "{p:?}"
        );
        assert!(p[2] > -100.0 && p[2] < 2000.0, "{p:?}");
        if warped[4 * k + 3] == 1.0 {
            let q = &warped[4 * k..4 * k + 3];
            gaps.push(
                ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt(),
            );
        }
    }
    gaps.sort_by(f64::total_cmp);
    // The same pixel sees the same ground in both: 2.3 m apart at the median, where a pixel here
    // spans 50–100 m; positions left relative to the camera would be kilometres off.
    let median = gaps[gaps.len() / 2];
    eprintln!("median gap {median:.2} m over {} pixels", gaps.len());
    assert!(
        median < 20.0,
        "median gap {median} m between the warped and the reference positions"
    );
}

/// [`fails_with`], exiting with `code`.
fn fails_as(args: &[&str], code: i32, cause: &str) {
    assert_eq!(fails_with(args, cause), code, "{args:?}");
}

#[test]
fn messages_name_the_files_role_and_the_key() {
    let dir = scratch("cli-roles");
    let small = manifest_dir().join("sketches/jacksboro-small.toml");
    let small = small.to_str().unwrap();
    let at = |name: &str| dir.join(name).to_str().unwrap().to_string();
    // A bad override is a usage error (2) that blames the override and names its key.
    fails_as(
        &[
            "render",
            small,
            "-o",
            &at("x.png"),
            "--set",
            "detail.octaves=many",
        ],
        2,
        "--set detail.octaves=many: invalid type",
    );
    fails_as(
        &[
            "render",
            small,
            "-o",
            &at("x.png"),
            "--set",
            "detail.gain=3",
        ],
        2,
        "--set detail.gain=3: must be in [0, 1]",
    );
    // Missing files say which file they were.
    fails_as(
        &["render", &at("none.toml"), "-o", &at("x.png")],
        1,
        "error: scene ",
    );
    let nosketch = write(
        &dir,
        "nosketch.toml",
        format!("[sketch]\npath = \"gone.asc\"\n{CAMERA}"),
    );
    fails_as(
        &["render", nosketch.to_str().unwrap(), "-o", &at("x.png")],
        1,
        "error: sketch ",
    );
    fails_as(
        &["batch", &at("none-jobs.toml"), "--out-dir", &at("b")],
        1,
        "error: jobs file ",
    );
    fails_as(&["info", small], 1, "a scene file, not a height map");
    for (args, cause) in [
        (vec!["--frames", "1"], "no display"),
        (vec!["--size", "0"], "--size"),
    ] {
        if cfg!(feature = "view") && std::env::var_os("DISPLAY").is_none() {
            let mut a = vec!["view", small];
            a.extend(args);
            let (code, _, err) = terrain(&a);
            let want = if cause == "--size" { 2 } else { 1 };
            assert_eq!(code, want, "{err}");
            assert!(err.contains(cause) && !err.contains(".rs:"), "{err}");
        }
    }
    assert_eq!(
        std::fs::read_dir(&dir).unwrap().count(),
        1,
        "nothing written but the scene"
    );
}

#[test]
fn outputs_make_their_folders_take_their_format_from_the_name_and_land_together() {
    let dir = scratch("cli-outputs");
    let small = manifest_dir().join("sketches/jacksboro-small.toml");
    let small = small.to_str().unwrap();
    let at = |name: &str| dir.join(name).to_str().unwrap().to_string();
    let (code, _, err) = terrain(&[
        "render",
        small,
        "-o",
        &at("new/deeper/x.jpg"),
        "--size",
        "48x32",
    ]);
    assert_eq!(code, 0, "{err}");
    let jpg = std::fs::read(dir.join("new/deeper/x.jpg")).unwrap();
    assert!(jpg.starts_with(&[0xFF, 0xD8, 0xFF]), "not a JPEG");
    fails_as(&["render", small, "-o", &at("x.webp")], 1, "output ");
    // The positions' folder cannot be made (a file is in the way): the image is not written
    // either.
    write(&dir, "blocker", "");
    fails_as(
        &[
            "render",
            small,
            "-o",
            &at("y.png"),
            "--positions",
            &at("blocker/p.npy"),
        ],
        1,
        "blocker",
    );
    assert!(!dir.join("y.png").exists() && !dir.join("x.webp").exists());
    let left: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".tmp"))
        .collect();
    assert!(left.is_empty(), "temporary files left: {left:?}");
}

#[test]
fn size_has_one_syntax_one_range_and_one_exit_code_everywhere() {
    let scene = manifest_dir().join("sketches/jacksboro-small.toml");
    let scene = scene.to_str().unwrap();
    let dir = scratch("cli-size");
    let d = dir.to_str().unwrap();
    for size in ["0", "16385", "12x", "axb"] {
        for cmd in [
            vec!["render", scene, "-o", "x.png"],
            vec!["fly", scene, "--out-dir", d],
            vec!["compare", scene, "--out-dir", d],
            vec!["view", scene],
        ] {
            let mut args = cmd.clone();
            args.extend(["--size", size]);
            fails_as(&args, 2, "expected N or WxH, each 1 to 16384 pixels");
        }
    }
    let (code, _, err) = terrain(&[
        "render",
        scene,
        "-o",
        &format!("{d}/s.png"),
        "--size",
        "24x16",
    ]);
    assert_eq!(code, 0, "{err}");
    let (w, h, _) = read_png(&dir.join("s.png")).unwrap();
    assert_eq!((w, h), (24, 16));
}

#[test]
fn pass_times_are_keyed_by_the_passes_that_ran() {
    let scene = manifest_dir().join("sketches/jacksboro-small.toml");
    let dir = scratch("cli-passes");
    for (mode, passes) in [
        (
            "warped",
            &["warp_zoom", "mesh_split", "normals", "terrain"][..],
        ),
        ("geomipmap", &["terrain"][..]),
        ("reference", &["reference"][..]),
    ] {
        let png = dir.join(format!("{mode}.png"));
        let (code, out, err) = terrain(&[
            "render",
            scene.to_str().unwrap(),
            "-o",
            png.to_str().unwrap(),
            "--mode",
            mode,
            "--size",
            "32",
            "--json",
        ]);
        assert_eq!(code, 0, "{err}");
        let v: serde_json::Value = serde_json::from_str(&out).unwrap();
        let got: Vec<&str> = v["passes_ms"]
            .as_object()
            .unwrap()
            .keys()
            .map(String::as_str)
            .collect();
        if v["gpu_timing"] == "timestamp queries" {
            let mut want = passes.to_vec();
            want.sort();
            let mut got = got.clone();
            got.sort();
            assert_eq!(got, want, "{mode}");
        } else {
            assert!(got.is_empty(), "{mode}: untimed passes reported: {got:?}");
        }
    }
}

/// `terrain web` with a module given (`--pkg`) writes the site: the page, the module, the scene
/// as resolved with its sketch beside it, and `site.json`; the page's reading of those bytes
/// (`Description::from_bytes`) gives the atlas and camera `render` reads from the files. What
/// the page cannot fetch is refused in one line.
#[test]
fn web_writes_a_site_the_page_reads_as_render_does() {
    use terrain::{Description, Scene};
    let dir = scratch("web-site");
    let pkg = dir.join("pkg");
    std::fs::create_dir_all(&pkg).unwrap();
    write(&pkg, "terrain_web.js", "export default function init() {}");
    write(&pkg, "terrain_web_bg.wasm", b"\0asm\x01\0\0\0");
    let site = dir.join("site");
    let jacksboro = manifest_dir().join("sketches/jacksboro.toml");
    let (code, _, err) = terrain(&[
        "web",
        jacksboro.to_str().unwrap(),
        "--out-dir",
        site.to_str().unwrap(),
        "--pkg",
        pkg.to_str().unwrap(),
        "--size",
        "64x48",
        "--mode",
        "warped",
        "--set",
        "detail.octaves=3",
        "--set",
        "render.mode=\"reference\"",
    ]);
    assert_eq!(code, 0, "{err}");
    for f in [
        "index.html",
        "main.js",
        "pkg/terrain_web.js",
        "pkg/terrain_web_bg.wasm",
    ] {
        assert!(site.join(f).is_file(), "{f} missing");
    }
    let meta: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(site.join("site.json")).unwrap()).unwrap();
    assert_eq!(meta["mode"], "warped", "--mode over the scene's");
    assert_eq!(
        (meta["width"].as_u64(), meta["height"].as_u64()),
        (Some(64), Some(48))
    );
    assert_eq!(meta["sketch"], "sketch/jacksboro_fault_dem.asc");

    let text = std::fs::read_to_string(site.join("scene.toml")).unwrap();
    let page_scene = Scene::parse(&text, ".".into()).unwrap();
    assert_eq!(
        page_scene.detail.octaves,
        Some(3),
        "the --set is in the site's scene"
    );
    let bytes = std::fs::read(site.join("sketch/jacksboro_fault_dem.asc")).unwrap();
    let page = Description::from_bytes(page_scene, &bytes).unwrap();
    let mut here = Scene::load_with(&jacksboro, &["detail.octaves=3".into()]).unwrap();
    (here.camera.width, here.camera.height) = (64, 48);
    let native = Description::new(here).unwrap();
    let (pa, na) = (page.atlas(), native.atlas());
    assert_eq!(pa.levels[0].data, na.levels[0].data);
    assert_eq!(
        (pa.dx, pa.origin, pa.water_m),
        (na.dx, na.origin, na.water_m)
    );
    let (a, b) = (page.camera(64, 48).unwrap(), native.camera(64, 48).unwrap());
    assert_eq!((a.eye, a.forward), (b.eye, b.forward));

    let planet = manifest_dir().join("sketches/planet-10km.toml");
    let out = dir.join("planet-site");
    let args = [
        "web",
        planet.to_str().unwrap(),
        "--out-dir",
        out.to_str().unwrap(),
    ];
    fails_with(&args, "planet");
    // The page draws the view's modes; the reference is no mode of the page.
    let args = [
        "web",
        jacksboro.to_str().unwrap(),
        "--out-dir",
        out.to_str().unwrap(),
        "--mode",
        "reference",
    ];
    fails_with(&args, "mode");
    let glob = manifest_dir().join("tests/data/formats/*Float32.tif");
    let args = [
        "web",
        glob.to_str().unwrap(),
        "--out-dir",
        out.to_str().unwrap(),
    ];
    fails_with(&args, "one sketch file");
}
