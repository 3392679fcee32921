//! What a new user meets first: the refusals the docs promise, warnings where a sketch's units
//! are guessed, and the command line's help.

mod common;
use common::*;
use std::path::{Path, PathBuf};

/// A bundled scene with `extra` appended, written to `dir`.
fn scene_plus(dir: &Path, bundled: &str, extra: &str) -> PathBuf {
    let text = std::fs::read_to_string(manifest_dir().join("sketches").join(bundled)).unwrap();
    let path = dir.join(bundled);
    std::fs::write(&path, format!("{text}\n{extra}")).unwrap();
    path
}

/// Runs `args`, expecting exit `code` and one line on stderr that holds every one of `causes`.
fn refused(args: &[&str], code: i32, causes: &[&str]) {
    let (got, _, err) = terrain(args);
    assert_eq!(got, code, "{args:?}: {err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{args:?}: {err}");
    for cause in causes {
        assert!(
            err.contains(cause),
            "{args:?}: {err:?} does not name {cause:?}"
        );
    }
}

#[test]
fn a_planet_refuses_what_it_cannot_draw_yet() {
    let dir = scratch("first-run-planet");
    let out = dir.join("x.png");
    let out = out.to_str().unwrap();
    for (key, toml) in [
        ("render.msaa", "[render]\nmsaa = \"4x\"\n"),
        ("render.detail_shadows", "[render]\ndetail_shadows = true\n"),
    ] {
        let scene = scene_plus(&dir, "planet-10km.toml", toml);
        let scene = scene.to_str().unwrap();
        refused(
            &["render", scene, "-o", out, "--size", "16"],
            1,
            &["planet-10km.toml", key],
        );
    }
    // The same keys given on the command line are usage errors naming the argument.
    let planet = manifest_dir().join("sketches/planet-10km.toml");
    let planet = planet.to_str().unwrap();
    refused(
        &["render", planet, "-o", out, "--set", "render.msaa=4x"],
        2,
        &["render.msaa=4x", "planet"],
    );
    assert!(!dir.join("x.png").exists());
    // What a planet can draw stays allowed: `auto` and `off`, and the sketch's shadow switch.
    let text = std::fs::read_to_string(planet).unwrap();
    for render in ["msaa = \"auto\"", "msaa = \"off\"", "shadows = false"] {
        scene(&format!("{text}\n[render]\n{render}\n"), dir.clone());
    }
}

#[test]
fn warp_refuses_a_planet() {
    let dir = scratch("first-run-warp-planet");
    let planet = manifest_dir().join("sketches/planet-10km.toml");
    refused(
        &[
            "warp",
            planet.to_str().unwrap(),
            "--out-dir",
            dir.to_str().unwrap(),
            "--repeat",
            "1",
        ],
        1,
        &["planet-10km.toml", "planet", "clipmaps"],
    );
    assert!(!dir.join("mesh.png").exists());
}

/// A 16-bit grey PNG of `n`² pixels whose values run from 10,000 to 50,000 (a DEM exported with
/// its relief stretched over the range).
fn write_png16(path: &Path, n: u32) {
    let mut bytes = Vec::new();
    let mut enc = png::Encoder::new(&mut bytes, n, n);
    enc.set_color(png::ColorType::Grayscale);
    enc.set_depth(png::BitDepth::Sixteen);
    let mut w = enc.write_header().unwrap();
    let px: Vec<u8> = (0..n * n)
        .flat_map(|k| ((10_000 + 40_000 * k / (n * n - 1)) as u16).to_be_bytes())
        .collect();
    w.write_image_data(&px).unwrap();
    drop(w);
    std::fs::write(path, bytes).unwrap();
}

/// The `warning:` lines of a run that succeeded.
fn warnings(args: &[&str]) -> Vec<String> {
    let (code, _, err) = terrain(args);
    assert_eq!(code, 0, "{args:?}: {err}");
    err.lines()
        .filter(|l| l.starts_with("warning:"))
        .map(String::from)
        .collect()
}

#[test]
fn a_png_without_units_is_warned_about_once_by_every_command() {
    let dir = scratch("first-run-png-units");
    let png = dir.join("dem.png");
    write_png16(&png, 16);
    // Over the sketch (a camera farther off than the sketch's size is a warning of its own).
    let camera = "[camera]\nposition = [4.0, 4.0, 60000.0]\nlook_at = [8.0, 8.0, 30000.0]\n";
    let bare = dir.join("bare.toml");
    std::fs::write(&bare, format!("[sketch]\npath = \"dem.png\"\n{camera}")).unwrap();
    let (png, bare, d) = (
        png.to_str().unwrap(),
        bare.to_str().unwrap(),
        dir.to_str().unwrap(),
    );
    let shot = dir.join("x.png");
    let shot = shot.to_str().unwrap();
    let pyramid = dir.join("pyramid");
    let runs: [&[&str]; 4] = [
        &["info", png],
        &[
            "warp",
            bare,
            "--out-dir",
            d,
            "--no-figures",
            "--repeat",
            "1",
        ],
        &["render", bare, "-o", shot, "--size", "16"],
        &["tiles", png, "--out-dir", pyramid.to_str().unwrap()],
    ];
    for args in runs {
        let lines = warnings(args);
        assert_eq!(lines.len(), 1, "{args:?}: {lines:?}");
        for part in [
            "dem.png",
            "0 to 65535 m",
            "1 m cells",
            "sketch.height_range_m",
            "sketch.spacing_m",
            ".pgw",
        ] {
            assert!(
                lines[0].contains(part),
                "{args:?}: {:?} lacks {part:?}",
                lines[0]
            );
        }
    }
    // Both units stated: no warning; the spacing stated alone: the warning names the heights' key.
    let stated = dir.join("stated.toml");
    let keys = "height_range_m = [100.0, 900.0]\nspacing_m = 30.0\n";
    std::fs::write(
        &stated,
        format!("[sketch]\npath = \"dem.png\"\n{keys}{camera}"),
    )
    .unwrap();
    let stated = stated.to_str().unwrap();
    assert!(
        warnings(&[
            "warp",
            stated,
            "--out-dir",
            d,
            "--no-figures",
            "--repeat",
            "1"
        ])
        .is_empty()
    );
    std::fs::write(dir.join("dem.pgw"), "30\n0\n0\n-30\n15\n465\n").unwrap();
    let lines = warnings(&["info", png]);
    assert!(
        lines.len() == 1 && lines[0].contains("height_range_m") && !lines[0].contains("spacing"),
        "{lines:?}"
    );
    assert!(warnings(&["info", png, "--height-scale", "0.01"]).is_empty());
    // A PNG its header refuses gets the error's one line alone.
    let rgb = dir.join("rgb.png");
    let mut bytes = Vec::new();
    let mut enc = png::Encoder::new(&mut bytes, 2, 2);
    enc.set_color(png::ColorType::Rgb);
    enc.write_header()
        .unwrap()
        .write_image_data(&[0; 12])
        .unwrap();
    std::fs::write(&rgb, bytes).unwrap();
    refused(
        &["info", rgb.to_str().unwrap()],
        1,
        &["rgb.png", "grayscale"],
    );
    // Stated heights on guessed cells: the line names the cells alone.
    std::fs::remove_file(dir.join("dem.pgw")).unwrap();
    let lines = warnings(&["info", png, "--height-scale", "0.01"]);
    assert!(
        lines.len() == 1
            && lines[0].contains("1 m")
            && lines[0].contains("sketch.spacing_m")
            && !lines[0].contains("height_range_m"),
        "{lines:?}"
    );
    assert!(warnings(&["info", png, "--height-scale", "0.01", "--spacing-m", "30"]).is_empty());
}

/// A 120 × 91 Float32 TIFF of heights −1437 … 2205 m without a georeference (no ModelPixelScale,
/// ModelTiepoint or ModelTransformation tag): what a program that knows no GeoTIFF writes.
fn write_plain_tiff(path: &Path) {
    let (w, h) = (120u32, 91u32);
    let data: Vec<f32> = (0..w * h)
        .map(|k| -1437.0 + 3642.0 * ((k % w) as f32 / (w - 1) as f32))
        .collect();
    let f = std::fs::File::create(path).unwrap();
    let mut enc = tiff::encoder::TiffEncoder::new(f).unwrap();
    enc.write_image::<tiff::encoder::colortype::Gray32Float>(w, h, &data)
        .unwrap();
}

#[test]
fn a_tiff_without_a_georeference_is_warned_about_once_like_a_png() {
    let dir = scratch("first-run-plain-tiff");
    let tif = dir.join("plain.tif");
    write_plain_tiff(&tif);
    let tif = tif.to_str().unwrap();
    let shot = dir.join("x.png");
    let shot = shot.to_str().unwrap();
    for args in [
        &["info", tif][..],
        &["render", tif, "-o", shot, "--size", "16"],
    ] {
        let lines = warnings(args);
        assert_eq!(lines.len(), 1, "{args:?}: {lines:?}");
        for part in ["plain.tif", "no georeference", "1 m", "sketch.spacing_m"] {
            assert!(
                lines[0].contains(part),
                "{args:?}: {lines:?} lacks {part:?}"
            );
        }
    }
    // The spacing stated: nothing left to guess, and 3.6 km across a 3.6 km relief is terrain.
    assert!(warnings(&["info", tif, "--spacing-m", "30"]).is_empty());
    let set = ["--set", "sketch.spacing_m=30"];
    assert!(warnings(&["render", tif, "-o", shot, "--size", "16", set[0], set[1]]).is_empty());
}

#[test]
fn a_relief_taller_than_three_times_the_sketch_names_the_likely_unit() {
    let dir = scratch("first-run-tall-relief");
    let tif = dir.join("plain.tif");
    write_plain_tiff(&tif);
    let tif = tif.to_str().unwrap();
    // 1 m cells stated: 3642 m of relief over 119 m is no landscape.
    let lines = warnings(&["info", tif, "--spacing-m", "1"]);
    assert_eq!(lines.len(), 1, "{lines:?}");
    for part in [
        "plain.tif",
        "3642 m",
        "119 m",
        "degrees",
        "feet",
        "sketch.spacing_m",
        "sketch.height_scale",
    ] {
        assert!(lines[0].contains(part), "{lines:?} lacks {part:?}");
    }
    // Just under three times its extent (1190 m at 10 m cells): quiet.
    assert!(warnings(&["info", tif, "--spacing-m", "10.3"]).is_empty());
    // The same through a scene, once per command however often the sketch is read.
    let shot = dir.join("x.png");
    let set = ["--set", "sketch.spacing_m=1"];
    let args = [
        "render",
        tif,
        "-o",
        shot.to_str().unwrap(),
        "--size",
        "16",
        set[0],
        set[1],
    ];
    let lines = warnings(&args);
    assert!(lines.len() == 1 && lines[0].contains("relief"), "{lines:?}");
}

#[test]
fn a_png_that_fails_to_read_gets_its_error_alone() {
    let dir = scratch("first-run-damaged-png");
    let whole = dir.join("whole.png");
    write_png16(&whole, 16);
    let bytes = std::fs::read(&whole).unwrap();
    // Its header intact (the units it would guess are known), its pixels cut short.
    let cut = dir.join("cut.png");
    std::fs::write(&cut, &bytes[..bytes.len() * 2 / 3]).unwrap();
    let scene = dir.join("cut.toml");
    std::fs::write(&scene, "[sketch]\npath = \"cut.png\"\n").unwrap();
    let shot = dir.join("x.png");
    refused(&["info", cut.to_str().unwrap()], 1, &["cut.png", "PNG"]);
    refused(
        &[
            "render",
            scene.to_str().unwrap(),
            "-o",
            shot.to_str().unwrap(),
        ],
        1,
        &["cut.png", "PNG"],
    );
    // The intact file still warns about its units.
    assert_eq!(warnings(&["info", whole.to_str().unwrap()]).len(), 1);
}

#[test]
fn terrain_alone_prints_its_commands() {
    let (code, out, err) = terrain(&[]);
    assert_eq!(code, 2, "{out}{err}");
    let help = format!("{out}{err}");
    assert!(help.contains("Usage: terrain <COMMAND>"), "{help}");
    for command in [
        "info", "tiles", "warp", "render", "compare", "fly", "batch", "view",
    ] {
        assert!(
            help.lines().any(|l| l.trim_start().starts_with(command)),
            "{command} missing from {help}"
        );
    }
}

#[test]
fn a_usage_error_points_at_the_help_of_its_command() {
    refused(
        &["render", "--bogus"],
        2,
        &["--bogus", "(terrain render --help lists"],
    );
    refused(
        &["tiles", "a.asc", "--threads", "many"],
        2,
        &["many", "(terrain tiles --help lists"],
    );
    refused(&["rendr"], 2, &["rendr", "(terrain --help lists"]);
}

#[test]
fn tiles_names_its_folder_out_dir_like_every_command() {
    let dir = scratch("first-run-tiles");
    let asc = dir.join("small.asc");
    let rows: String = (0..4).map(|r| format!("{r} 1 2 3\n")).collect();
    std::fs::write(
        &asc,
        format!("ncols 4\nnrows 4\nxllcorner 0\nyllcorner 0\ncellsize 30\n{rows}"),
    )
    .unwrap();
    let asc = asc.to_str().unwrap();
    // `--out`, the earlier name, still works for scripts; the help shows the one name.
    for (flag, folder) in [("--out-dir", "new"), ("--out", "old")] {
        let out = dir.join(folder);
        let (code, _, err) = terrain(&["tiles", asc, flag, out.to_str().unwrap()]);
        assert_eq!(code, 0, "{flag}: {err}");
        assert!(out.join("pyramid.toml").is_file(), "{flag}");
    }
    let (_, help, _) = terrain(&["tiles", "--help"]);
    assert!(help.contains("--out-dir <OUT_DIR>"), "{help}");
    assert!(!help.contains("--out <"), "{help}");
}

/// The entries of a `--help` text's Arguments and Options sections that have no description.
fn undescribed(help: &str) -> Vec<String> {
    let mut section = "";
    let mut bare = Vec::new();
    for line in help.lines() {
        if !line.starts_with(' ') {
            section = line;
            continue;
        }
        let entry = line.trim_start();
        let listed = section == "Arguments:" || section == "Options:";
        // An entry's name and its description are two spaces apart.
        if listed && entry.starts_with(['-', '<', '[']) && !entry.trim_end().contains("  ") {
            bare.push(entry.trim_end().to_string());
        }
    }
    bare
}

#[test]
fn every_argument_and_option_of_every_command_says_what_it_is() {
    for command in [
        "info", "tiles", "warp", "render", "compare", "fly", "batch", "view",
    ] {
        let (code, help, err) = terrain(&[command, "--help"]);
        assert_eq!(code, 0, "{command}: {err}");
        assert!(help.contains("Options:"), "{command}: {help}");
        let bare = undescribed(&help);
        assert!(
            bare.is_empty(),
            "terrain {command} --help: {bare:?} without a description"
        );
    }
    let (_, help, _) = terrain(&["render", "--help"]);
    assert!(
        help.contains(
            "A scene file (.toml), or a sketch (height map) to render with every default"
        ),
        "{help}"
    );
}

#[test]
fn the_licences_cargo_toml_names_are_in_the_tree() {
    let manifest = std::fs::read_to_string(manifest_dir().join("Cargo.toml")).unwrap();
    assert!(manifest.contains("license = \"MIT OR Apache-2.0\""));
    let read = |name: &str| {
        std::fs::read_to_string(manifest_dir().join(name)).unwrap_or_else(|e| panic!("{name}: {e}"))
    };
    let mit = read("LICENSE-MIT");
    assert!(
        mit.contains("Copyright (c) The terrain developers"),
        "{mit}"
    );
    assert!(mit.contains("Permission is hereby granted, free of charge"));
    let apache = read("LICENSE-APACHE");
    assert!(apache.contains("Apache License") && apache.contains("Version 2.0, January 2004"));
    assert!(apache.contains("END OF TERMS AND CONDITIONS"));
}
