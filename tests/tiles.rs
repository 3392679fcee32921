//! `terrain tiles`: the pyramid on disk holds the atlas's numbers bit for bit, a glob mosaic
//! converts as it loads, a killed build resumes to the same files, and bad folders and damaged
//! tiles are refused in one line.

mod common;

use common::{psnr, scratch, terrain};
use std::path::{Path, PathBuf};
use terrain_engine::sketch::convert::{BuildOptions, build};
use terrain_engine::sketch::tiles::{BORDER, Pyramid, SIDE, TILE};
use terrain_engine::sketch::{Atlas, LoadOptions};

/// Heights with detail at every scale and no symmetry, so a misplaced node shows.
fn height(i: usize, j: usize) -> f32 {
    let (x, y) = (i as f32, j as f32);
    300.0
        + 80.0 * (x * 0.013).sin() * (y * 0.021).cos()
        + 7.0 * ((x * 1.7 + y * 0.3).sin())
        + ((i * 7919 + j * 104_729) % 97) as f32 * 0.11
}

/// An ESRI ASCII grid of `w`×`h` nodes whose south-west node is global node (i0, j0) of a 30 m
/// grid; `hole` marks nodata.
fn write_asc(
    path: &Path,
    w: usize,
    h: usize,
    (i0, j0): (usize, usize),
    hole: impl Fn(usize, usize) -> bool,
) {
    let mut text = format!(
        "ncols {w}\nnrows {h}\nxllcenter {}\nyllcenter {}\ncellsize 30\nNODATA_value -9999\n",
        500_000.0 + 30.0 * i0 as f64,
        4_000_000.0 + 30.0 * j0 as f64
    );
    for r in (0..h).rev() {
        for c in 0..w {
            let (i, j) = (i0 + c, j0 + r);
            if hole(i, j) {
                text += "-9999 ";
            } else {
                text += &format!("{} ", height(i, j));
            }
        }
        text += "\n";
    }
    std::fs::write(path, text).unwrap();
}

fn convert(src: &Path, out: &Path) -> terrain_engine::sketch::convert::BuildSummary {
    build(src, out, &BuildOptions::default())
        .unwrap_or_else(|e| panic!("tiles {}: {e}", src.display()))
}

fn assert_same_atlas(a: &Atlas, b: &Atlas) {
    assert_eq!(a.levels.len(), b.levels.len(), "levels");
    for (l, (x, y)) in a.levels.iter().zip(&b.levels).enumerate() {
        assert_eq!((x.width, x.height), (y.width, y.height), "level {l} size");
        let differ = x
            .data
            .iter()
            .zip(&y.data)
            .filter(|(p, q)| p.to_bits() != q.to_bits())
            .count();
        assert_eq!(differ, 0, "level {l}: {differ} nodes differ");
    }
    assert_eq!(
        (a.dx, a.dy, a.min_m, a.max_m),
        (b.dx, b.dy, b.min_m, b.max_m)
    );
    assert_eq!(
        a.edge_mean_m.to_bits(),
        b.edge_mean_m.to_bits(),
        "edge mean"
    );
    assert_eq!(a.georef, b.georef);
}

#[test]
fn a_pyramid_holds_the_atlas_bit_for_bit_borders_included() {
    let dir = scratch("tiles-atlas");
    let src = dir.join("grid.asc");
    // Sizes that are no multiple of the tile, so edge tiles and odd halvings are exercised.
    write_asc(&src, 611, 529, (0, 0), |_, _| false);
    let out = dir.join("pyramid");
    let s = convert(&src, &out);
    assert_eq!((s.width, s.height, s.sources), (611, 529, 1));
    let from_file = Atlas::load(&src, &LoadOptions::default()).unwrap();
    let from_tiles = Atlas::load(&out, &LoadOptions::default()).unwrap();
    assert_same_atlas(&from_file, &from_tiles);
    // Every stored node, border included, is its level's node clamped to the edge.
    let p = Pyramid::open(&out).unwrap();
    assert_eq!(p.meta.tile_count(), s.tiles);
    for l in 0..p.meta.levels.len() {
        let level = &from_file.levels[l];
        let (nx, ny) = p.meta.tiles(l);
        for ty in 0..ny {
            for tx in 0..nx {
                let t = p.tile(l, tx, ty).unwrap();
                for j in 0..SIDE {
                    for i in 0..SIDE {
                        let gx = (tx * TILE + i).saturating_sub(BORDER).min(level.width - 1);
                        let gy = (ty * TILE + j).saturating_sub(BORDER).min(level.height - 1);
                        let want = level.data[gy * level.width + gx];
                        assert_eq!(
                            t[j * SIDE + i].to_bits(),
                            want.to_bits(),
                            "level {l} tile ({tx},{ty}) node ({i},{j})"
                        );
                    }
                }
            }
        }
    }
}

#[test]
fn a_glob_mosaic_converts_as_it_loads_and_nodata_is_counted() {
    let dir = scratch("tiles-mosaic");
    // Four tiles of unequal size; a small hole inside one band (so the band fill is the atlas's).
    let hole = |i: usize, j: usize| (40..44).contains(&i) && (100..103).contains(&j);
    write_asc(&dir.join("a.asc"), 300, 270, (0, 0), hole);
    write_asc(&dir.join("b.asc"), 213, 270, (300, 0), hole);
    write_asc(&dir.join("c.asc"), 300, 190, (0, 270), hole);
    write_asc(&dir.join("d.asc"), 213, 190, (300, 270), hole);
    let glob = dir.join("*.asc");
    let out = dir.join("pyramid");
    let s = convert(&glob, &out);
    assert_eq!((s.width, s.height, s.sources), (513, 460, 4));
    let from_glob = Atlas::load(&glob, &LoadOptions::default()).unwrap();
    let from_tiles = Atlas::load(&out, &LoadOptions::default()).unwrap();
    assert_same_atlas(&from_glob, &from_tiles);
    let p = Pyramid::open(&out).unwrap();
    assert_eq!(p.meta.nodata, 12);
    assert_eq!(from_glob.nodata, 12);
    assert!(
        !out.join(".build").exists(),
        "scratch removed once complete"
    );
}

#[test]
fn a_coarser_level_stands_in_for_a_pyramid_beyond_the_cell_limit() {
    let dir = scratch("tiles-stand-in");
    let src = dir.join("grid.asc");
    write_asc(&src, 300, 300, (0, 0), |_, _| false);
    let out = dir.join("pyramid");
    convert(&src, &out);
    let atlas = Atlas::load(&src, &LoadOptions::default()).unwrap();
    let g = terrain_engine::sketch::tiles::raw_grid_within(&out, 150 * 150).unwrap();
    assert_eq!((g.width, g.height), (150, 150));
    assert_eq!((g.dx, g.dy), (60.0, 60.0));
    assert!(
        g.data
            .iter()
            .zip(&atlas.levels[1].data)
            .all(|(a, b)| a.to_bits() == b.to_bits())
    );
    // Level 1's first node is the centre of level 0's first 2×2 nodes: half a cell north-east.
    let (a, b) = (atlas.georef.unwrap(), g.georef.unwrap());
    assert_eq!((b.west - a.west, b.south - a.south), (15.0, 15.0));
}

fn all_files(dir: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    let mut out = Vec::new();
    for e in std::fs::read_dir(dir).unwrap().flatten() {
        let p = e.path();
        if p.is_dir() {
            out.extend(all_files(&p));
        } else {
            out.push((p.clone(), std::fs::read(&p).unwrap()));
        }
    }
    out.sort();
    out
}

/// A 16-bit PNG of `n`² nodes (heights are its values, metres).
fn write_png16(path: &Path, n: usize) {
    let mut bytes = Vec::new();
    let mut enc = png::Encoder::new(&mut bytes, n as u32, n as u32);
    enc.set_color(png::ColorType::Grayscale);
    enc.set_depth(png::BitDepth::Sixteen);
    let mut w = enc.write_header().unwrap();
    let data: Vec<u8> = (0..n * n)
        .flat_map(|k| ((height(k % n, k / n) * 20.0) as u16).to_be_bytes())
        .collect();
    w.write_image_data(&data).unwrap();
    w.finish().unwrap();
    std::fs::write(path, bytes).unwrap();
}

#[test]
fn a_killed_build_resumes_to_the_same_files() {
    let dir = scratch("tiles-resume");
    let src = dir.join("big.png");
    write_png16(&src, 3000);
    let (killed, fresh) = (dir.join("killed"), dir.join("fresh"));
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_terrain"))
        .args([
            "tiles",
            src.to_str().unwrap(),
            "--out-dir",
            killed.to_str().unwrap(),
            "--threads",
            "1",
        ])
        .env("TERRAIN_QUIET", "1")
        .spawn()
        .unwrap();
    // SIGKILL as soon as the first tile is in place: no chance to tidy up.
    let first = killed.join("L0/0/0.tile");
    let t0 = std::time::Instant::now();
    while !first.exists() && t0.elapsed().as_secs() < 60 {
        std::thread::sleep(std::time::Duration::from_millis(1));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    assert!(first.exists(), "no tile within 60 s");
    assert!(
        !killed.join("pyramid.toml").exists(),
        "the build finished before it was killed"
    );
    let (code, stdout, stderr) = terrain(&[
        "tiles",
        src.to_str().unwrap(),
        "--out-dir",
        killed.to_str().unwrap(),
        "--json",
    ]);
    assert_eq!(code, 0, "{stderr}");
    let report: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    let (tiles, written) = (
        report["tiles"].as_u64().unwrap(),
        report["tiles_written"].as_u64().unwrap(),
    );
    assert!(
        written < tiles,
        "the resumed run wrote all {tiles} tiles again"
    );
    let (code, _, stderr) = terrain(&[
        "tiles",
        src.to_str().unwrap(),
        "--out-dir",
        fresh.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{stderr}");
    let (a, b) = (all_files(&killed), all_files(&fresh));
    assert_eq!(a.len(), b.len(), "files");
    for ((pa, ba), (pb, bb)) in a.iter().zip(&b) {
        assert_eq!(
            pa.strip_prefix(&killed).unwrap(),
            pb.strip_prefix(&fresh).unwrap()
        );
        assert!(
            ba == bb,
            "{} differs from an uninterrupted build's",
            pa.display()
        );
    }
    // Run again on a whole pyramid: nothing to write.
    let (code, stdout, _) = terrain(&[
        "tiles",
        src.to_str().unwrap(),
        "--out-dir",
        killed.to_str().unwrap(),
        "--json",
    ]);
    assert_eq!(code, 0);
    assert!(stdout.contains("\"tiles_written\":0"), "{stdout}");
}

#[test]
fn folders_of_other_builds_and_damaged_tiles_are_refused_in_one_line() {
    let dir = scratch("tiles-refused");
    let (one, two) = (dir.join("one.asc"), dir.join("two.asc"));
    write_asc(&one, 40, 30, (0, 0), |_, _| false);
    write_asc(&two, 41, 30, (0, 0), |_, _| false);
    let out = dir.join("pyramid");
    convert(&one, &out);
    let (code, _, stderr) = terrain(&[
        "tiles",
        two.to_str().unwrap(),
        "--out-dir",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 1);
    assert!(
        stderr.contains("other sources or options") && stderr.lines().count() == 1,
        "{stderr}"
    );
    let other = dir.join("other");
    std::fs::create_dir_all(&other).unwrap();
    std::fs::write(other.join("notes.txt"), "mine").unwrap();
    let (code, _, stderr) = terrain(&[
        "tiles",
        one.to_str().unwrap(),
        "--out-dir",
        other.to_str().unwrap(),
    ]);
    assert_eq!(code, 1);
    assert!(stderr.contains("not empty"), "{stderr}");
    assert_eq!(
        std::fs::read_to_string(other.join("notes.txt")).unwrap(),
        "mine"
    );
    // A flipped byte in a tile's heights: its checksum catches it, and the message names it.
    let tile = out.join("L0/0/0.tile");
    damage(&tile);
    let (code, _, stderr) = terrain(&["info", out.to_str().unwrap(), "--json"]);
    assert_eq!(code, 0, "info reads pyramid.toml alone: {stderr}");
    let err = Atlas::load(&out, &LoadOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        err.starts_with("sketch ") && err.contains("0.tile: tile"),
        "{err}"
    );
    let (code, _, stderr) = terrain(&[
        "tiles",
        dir.join("missing.asc").to_str().unwrap(),
        "--out-dir",
        dir.join("x").to_str().unwrap(),
    ]);
    assert_eq!(code, 1);
    assert!(
        stderr.starts_with("error: sketch ") && stderr.lines().count() == 1,
        "{stderr}"
    );
}

/// A scratch folder `name` holding the bundled Jacksboro sketch converted to `pyr`: the folder,
/// the sketch and the pyramid.
fn jacksboro_pyramid(name: &str) -> (PathBuf, PathBuf, PathBuf) {
    let dir = scratch(name);
    let asc = common::manifest_dir().join("sketches/jacksboro_fault_dem.asc");
    let pyr = dir.join("pyr");
    convert(&asc, &pyr);
    (dir, asc, pyr)
}

/// Flips a bit near the end of a tile: its checksum no longer holds.
fn damage(tile: &Path) {
    let mut bytes = std::fs::read(tile).unwrap();
    let k = bytes.len() - 10;
    bytes[k] ^= 0x10;
    std::fs::write(tile, bytes).unwrap();
}

/// The bundled Jacksboro scene's text at 128², reading `sketch` (an absolute path), with `extra`
/// appended. Its `detail.bias` is set, so that a pyramid and the sketch in memory draw the same
/// terrain function in GeoMipMap mode too: by default its bias over a pyramid is 0 and in memory
/// −1 (docs/scene.md).
fn jacksboro_text(sketch: &Path, extra: &str) -> String {
    let text = std::fs::read_to_string(common::manifest_dir().join("sketches/jacksboro.toml"))
        .unwrap()
        .replace(
            "path = \"jacksboro_fault_dem.asc\"",
            &format!("path = {:?}", sketch.display().to_string()),
        )
        .replace("width = 512", "width = 128")
        .replace("height = 512", "height = 128")
        .replace("gain = 0.45", "gain = 0.45\nbias = 0.0");
    assert!(
        text.contains("bias = 0.0"),
        "the bundled scene's [detail] changed"
    );
    format!("{text}\n{extra}\n")
}

/// The bundled Jacksboro scene at 128², reading `sketch` (a path), with `extra` appended.
fn jacksboro_scene(sketch: &Path, extra: &str) -> terrain_engine::scene::Scene {
    let dir = common::manifest_dir().join("sketches");
    common::scene(&jacksboro_text(sketch, extra), dir)
}

#[test]
fn a_streamed_pyramid_renders_as_the_sketch_in_memory_once_its_tiles_are_resident() {
    use terrain_engine::Renderer;
    use terrain_engine::View;
    use terrain_engine::scene::Mode;
    let (_, asc, pyr) = jacksboro_pyramid("tiles-streamed");
    // 4 MiB: 15 pages for the pyramid's 11 tiles, of which the top three levels are pinned, so
    // the first frame stands in with them.
    let streamed = jacksboro_scene(&pyr, "[stream]\ngpu_mb = 4");
    let whole = jacksboro_scene(&asc, "");
    for mode in [Mode::Warped, Mode::Reference] {
        let mut m = Renderer::new(&whole, mode, View::Shaded).unwrap();
        let camera = terrain_engine::scene::camera_of(&whole, &m.atlas).unwrap();
        let expected = m.render(&camera).unwrap();
        assert!(expected.stream.is_none());
        let mut s = Renderer::new(&streamed, mode, View::Shaded).unwrap();
        let first = s.render(&camera).unwrap();
        let stats = first.stream.expect("a pyramid streams");
        assert!(stats.stand_in && stats.missing > 0, "{mode}: {stats:?}");
        let first_db = psnr(&first.rgba, &expected.rgba);
        let (mut frames, mut loaded) = (1, 0);
        let last = loop {
            let f = s.render(&camera).unwrap();
            let st = f.stream.unwrap();
            loaded += st.loaded;
            frames += 1;
            if !st.stand_in || frames > 100 {
                break f;
            }
            std::thread::sleep(std::time::Duration::from_millis(5));
        };
        let db = psnr(&last.rgba, &expected.rgba);
        eprintln!(
            "{mode}: first frame {first_db:.1} dB; {loaded} tiles loaded, resident after {frames} frames: {db:.1} dB"
        );
        assert!(frames <= 100, "{mode}: still standing in after 100 frames");
        assert!(loaded > 0);
        assert!(first_db < 50.0, "{mode}: the stand-in frame should differ");
        assert!(
            db >= 50.0,
            "{mode}: {db:.1} dB against the sketch in memory"
        );
    }
    // A negative bias would put octaves into GeoMipMap's grid, whose δ the tiles do not see.
    let mut negative = streamed.clone();
    negative.detail.bias = Some(-1.0);
    let e = Renderer::new(&negative, Mode::Geomipmap, View::Shaded)
        .err()
        .expect("a negative bias over a pyramid is refused in GeoMipMap");
    assert!(e.to_string().contains("detail.bias"), "{e}");
    // Brute force bakes the whole sketch: refused in one line, naming the mode.
    let e = Renderer::new(&streamed, Mode::Bruteforce, View::Shaded)
        .err()
        .expect("brute force on a pyramid is refused");
    let e = e.to_string();
    assert!(
        e.contains("render.mode") && e.contains("bakes the whole sketch"),
        "{e}"
    );
}

/// 87 × 61 of the bundled Jacksboro heights in `dir` as a sketch of 10 m cells: steep (630 m of
/// relief in 870 m) and small enough to render in every mode in a moment.
fn jacksboro_crop(dir: &Path) -> PathBuf {
    let text =
        std::fs::read_to_string(common::manifest_dir().join("sketches/jacksboro_fault_dem.asc"))
            .unwrap();
    let rows: Vec<String> = text
        .lines()
        .skip(106)
        .take(61)
        .map(|l| {
            l.split_whitespace()
                .skip(150)
                .take(87)
                .collect::<Vec<_>>()
                .join(" ")
        })
        .collect();
    let head = "ncols 87\nnrows 61\nxllcorner 0\nyllcorner 0\ncellsize 10\nNODATA_value -32768\n";
    let path = dir.join("jacksboro_crop.asc");
    std::fs::write(&path, head.to_string() + &rows.join("\n")).unwrap();
    path
}

/// The warped mode and the reference draw a pyramid as its source by default; GeoMipMap does
/// once its in-memory bake is the pyramid's grid (`geomipmap.k = 0`, `detail.bias = 0`), which
/// its defaults leave finer (`scene::default_bias`).
#[test]
fn a_pyramid_draws_its_sketchs_picture_by_default_in_every_mode_that_streams() {
    use terrain_engine::Renderer;
    use terrain_engine::View;
    use terrain_engine::scene::Mode;
    let dir = scratch("tiles-defaults");
    let asc = jacksboro_crop(&dir);
    let pyr = dir.join("pyr");
    convert(&asc, &pyr);
    // Nothing under [detail] or [geomipmap]: every default that could follow the storage is
    // left to the scene (bias, k, octaves, amplitude, the far distance).
    let scene = |sketch: &Path| {
        common::scene(
            &format!(
                "[sketch]\npath = {:?}\n[camera]\nposition = [435.0, -150.0, 1150.0]\n\
                 look_at = [435.0, 500.0, 600.0]\nwidth = 96\nheight = 96\n",
                sketch.display().to_string()
            ),
            dir.clone(),
        )
    };
    let (whole, streamed) = (scene(&asc), scene(&pyr));
    let mut pyramid_grid = whole.clone();
    (pyramid_grid.geomipmap.k, pyramid_grid.detail.bias) = (Some(0), Some(0.0));
    for mode in [Mode::Warped, Mode::Geomipmap, Mode::Reference] {
        let whole = match mode {
            Mode::Geomipmap => &pyramid_grid,
            _ => &whole,
        };
        let mut m = Renderer::new(whole, mode, View::Shaded).unwrap();
        let camera = terrain_engine::scene::camera_of(whole, &m.atlas).unwrap();
        let expected = m.render(&camera).unwrap();
        let mut s = Renderer::new(&streamed, mode, View::Shaded).unwrap();
        let camera = terrain_engine::scene::camera_of(&streamed, &s.atlas).unwrap();
        let got = s.render_settled(&camera).unwrap();
        assert!(got.stream.is_some(), "{mode}: the pyramid streams");
        assert_eq!(
            format!("{:?}", s.detail),
            format!("{:?}", m.detail),
            "{mode}: the detail"
        );
        let db = psnr(&got.rgba, &expected.rgba);
        eprintln!("{mode}: {db:.1} dB, {} triangles", got.gpu.triangles);
        assert!(
            db >= 50.0,
            "{mode}: {db:.1} dB against the sketch in memory"
        );
        assert_eq!(
            got.gpu.triangles, expected.gpu.triangles,
            "{mode}: triangles"
        );
    }
}

/// The bundled Jacksboro heights in `dir` as a sketch of square 30 m cells (its own are
/// 0.00083° both ways: 74 × 93 m).
fn jacksboro_in_metres(dir: &Path) -> PathBuf {
    let text =
        std::fs::read_to_string(common::manifest_dir().join("sketches/jacksboro_fault_dem.asc"))
            .unwrap();
    let body: Vec<String> = text
        .lines()
        .map(|l| match l.split_whitespace().next() {
            Some("xllcorner") => "xllcorner 0".into(),
            Some("yllcorner") => "yllcorner 0".into(),
            Some("cellsize") => "cellsize 30".into(),
            _ => l.to_string(),
        })
        .collect();
    let path = dir.join("jacksboro_30m.asc");
    std::fs::write(&path, body.join("\n")).unwrap();
    path
}

#[test]
fn streamed_geomipmap_measures_the_baked_grids_blocks_and_renders_as_it_once_resident() {
    let dir = scratch("tiles-geomipmap");
    let square = jacksboro_in_metres(&dir);
    let degrees = common::manifest_dir().join("sketches/jacksboro_fault_dem.asc");
    // Square cells with water over the valleys (the grid's vertices stand on it); degrees dry.
    for (name, sketch, water) in [("square", square, 450.0), ("degrees", degrees, 0.0)] {
        let pyr = dir.join(format!("pyr-{name}"));
        convert(&sketch, &pyr);
        streamed_geomipmap_matches(name, &sketch, &pyr, water);
    }
}

/// GeoMipMap over `pyr`, converted from `sketch`, against GeoMipMap over `sketch` in memory, with
/// the water at `water` metres.
fn streamed_geomipmap_matches(name: &str, sketch: &Path, pyr: &Path, water: f64) {
    use terrain_engine::Baselines;
    use terrain_engine::Renderer;
    use terrain_engine::View;
    use terrain_engine::scene::Mode;
    // Kept in the folder, as the binary asks (the library alone writes no file).
    terrain_engine::sketch::tiles::set_keep_figures(true);
    // k = 0: over a pyramid the grid is the sketch at its own spacing; the sketch in memory bakes
    // the same grid. 4 MiB of pages: the first frame stands in.
    let mut streamed = jacksboro_scene(pyr, "[geomipmap]\nk = 0\n[stream]\ngpu_mb = 4");
    let mut whole = jacksboro_scene(sketch, "[geomipmap]\nk = 0");
    streamed.sketch.water_level_m = water;
    whole.sketch.water_level_m = water;
    let mut m = Renderer::new(&whole, Mode::Geomipmap, View::Shaded).unwrap();
    let camera = terrain_engine::scene::camera_of(&whole, &m.atlas).unwrap();
    let expected = m.render(&camera).unwrap();
    let mut s = Renderer::new(&streamed, Mode::Geomipmap, View::Shaded).unwrap();

    // δ and height ranges measured on the tiles are the baked grid's.
    let (a, b) = (
        &m.lod::<Baselines>().unwrap().blocks,
        &s.lod::<Baselines>().unwrap().blocks,
    );
    assert_eq!((a.per_side, a.levels), (b.per_side, b.levels), "{name}");
    // The bake samples the sketch bicubically at f32 texel coordinates a few 1e-5 texels off
    // where the CPU computes them: millimetres on Jacksboro's slopes.
    let close = |x: f32, y: f32| (x - y).abs() <= 1e-2 + 1e-4 * x.abs().max(y.abs());
    for k in 0..a.per_side * a.per_side {
        for l in 0..a.levels {
            let (x, y) = (a.delta[k][l], b.delta[k][l]);
            assert!(close(x, y), "{name}: block {k} δ_{l}: {x} vs {y}");
        }
        let (ra, rb) = (a.z_range[k], b.z_range[k]);
        assert!(
            close(ra.0, rb.0) && close(ra.1, rb.1),
            "{name}: block {k}: {ra:?} vs {rb:?}"
        );
    }
    assert!(
        a.delta.iter().any(|d| d[1] > 1.0),
        "{name}: a relief to measure"
    );
    // Kept beside the tiles, and read back by the next renderer.
    let kept = pyr.join(format!("geomipmap-{}.bin", a.cells + 1));
    assert!(kept.exists(), "{name}");
    let delta_of = |scene: &terrain_engine::scene::Scene| {
        let r = Renderer::new(scene, Mode::Geomipmap, View::Shaded).unwrap();
        r.lod::<Baselines>().unwrap().blocks.delta.clone()
    };
    assert_eq!(delta_of(&streamed), b.delta, "{name}");
    // Other water is another grid: the kept figures are not taken for it.
    let mut lower = streamed.clone();
    lower.sketch.water_level_m = water - 100.0;
    let fresh = terrain_engine::sketch::tiles::measure_blocks(
        &Pyramid::open(pyr).unwrap(),
        a.cells,
        a.per_side,
        lower.sketch.water_level_m as f32,
    )
    .unwrap();
    assert_eq!(delta_of(&lower), fresh.delta, "{name}");

    let first = s.render(&camera).unwrap();
    let stats = first.stream.expect("a pyramid streams");
    assert!(stats.stand_in && stats.missing > 0, "{name}: {stats:?}");
    let first_db = psnr(&first.rgba, &expected.rgba);
    let last = s.render_settled(&camera).unwrap();
    assert!(!last.stream.unwrap().stand_in, "{name}");
    assert_eq!(
        last.gpu.triangles, expected.gpu.triangles,
        "{name}: the same blocks at the same levels"
    );
    let db = psnr(&last.rgba, &expected.rgba);
    eprintln!("geomipmap, {name} cells: first frame {first_db:.1} dB, resident {db:.1} dB");
    assert!(first_db < 50.0, "{name}: the stand-in frame should differ");
    // Measured: 95.0 dB with square cells, 88.1 with degrees. With the streamed grid's vertices
    // past the sketch's edge left where the grid puts them, while the bake draws them on it,
    // square cells read 52.5.
    assert!(
        db >= 70.0,
        "{name}: {db:.1} dB against the sketch in memory"
    );
    drop(s);

    // A budget of 8 blocks draws the 8 nearest and counts the ones it left out.
    let mut tight = streamed.clone();
    tight.geomipmap.max_blocks = 8;
    let mut t = Renderer::new(&tight, Mode::Geomipmap, View::Shaded).unwrap();
    let frame = t.render(&camera).unwrap();
    let b = t.lod::<Baselines>().unwrap();
    assert_eq!(frame.blocks, Some(8), "{name}");
    assert_eq!(b.dropped + 8, expected.blocks.unwrap(), "{name}");
}

#[test]
fn a_streamed_sketchs_ground_is_level_0s_so_a_camera_under_a_peak_is_refused() {
    use glam::{DVec2, DVec3};
    use terrain_engine::scene::{camera_of, ground_under, load_atlas};
    let (_, asc, pyr) = jacksboro_pyramid("tiles-ground");
    // cpu_mb = 0: main memory holds the top level alone, 2 × 2 nodes.
    let streamed_scene = jacksboro_scene(&pyr, "[stream]\ncpu_mb = 0");
    let whole_scene = jacksboro_scene(&asc, "");
    let streamed = load_atlas(&streamed_scene).unwrap();
    let whole = load_atlas(&whole_scene).unwrap();
    assert!(streamed.resident_from > 0 && streamed.levels[0].data.is_empty());
    // Nodes, cell interiors, the tile seam at node 256 (read from one tile's border), the edges.
    let (lo, hi) = (whole.origin, whole.max_corner());
    let mut points = Vec::new();
    for &u in &[
        0.0, 0.37, 100.5, 254.9, 255.0, 255.5, 256.0, 256.25, 401.9, 402.0,
    ] {
        for &v in &[0.0, 17.3, 255.75, 256.0, 300.1, 343.0] {
            points.push(lo + DVec2::new(u * whole.dx, v * whole.dy));
        }
    }
    let (mut worst, mut deepest) = (0.0f64, lo);
    for k in 0..2000 {
        let t = DVec2::new(
            (k as f64 * 0.618_034).fract(),
            (k as f64 * 0.414_214).fract(),
        );
        points.push(lo + (hi - lo) * t);
    }
    for &p in &points {
        let a = ground_under(&streamed, p).unwrap().unwrap();
        let b = ground_under(&whole, p).unwrap().unwrap();
        assert_eq!(a.to_bits(), b.to_bits(), "at {p}: {a} streamed, {b} whole");
        // What the coarse levels in memory would have said.
        let (u, v) = ((p.x - lo.x) / whole.dx, (p.y - lo.y) / whole.dy);
        let coarse = streamed.sample_texel(u, v, 0.0) as f64;
        if b - coarse > worst {
            (worst, deepest) = (b - coarse, p);
        }
    }
    assert!(
        worst > 20.0,
        "the top level should smooth a peak away: {worst} m"
    );
    // A camera 1 m under that peak but far above the coarse surface: refused, as in memory.
    let ground = ground_under(&whole, deepest).unwrap().unwrap();
    for scene in [&streamed_scene, &whole_scene] {
        let mut s = scene.clone();
        let eye = deepest.extend(ground - 1.0);
        s.camera.aim(eye, eye + DVec3::new(100.0, 0.0, -10.0));
        let atlas = load_atlas(&s).unwrap();
        let e = camera_of(&s, &atlas).expect_err("under the peak");
        assert!(e.to_string().contains("below the surface"), "{e}");
    }
    // A level-0 tile damaged after the load (which read it for the relief): the query names it
    // rather than answering from a coarser level. A fresh atlas has no tile kept decoded.
    let fresh = load_atlas(&streamed_scene).unwrap();
    let tile = pyr.join("L0/0/0.tile");
    damage(&tile);
    let e = ground_under(&fresh, lo + DVec2::splat(10.0)).unwrap_err();
    assert!(e.to_string().contains("0.tile"), "{e}");
}

/// The error term's curvature of each pyramid level (`Atlas::level_curvature`): a streamed
/// sketch measures the levels it does not hold in memory on windows read from their tiles, so
/// it gets what the sketch held whole gets (here bit for bit: the DEM's levels are smaller than
/// the window). A level whose tile is damaged is NaN, which the term skips, and nothing panics.
#[test]
fn a_streamed_sketch_measures_the_curvature_of_levels_not_in_memory() {
    use terrain_engine::scene::load_atlas;
    let (_, asc, pyr) = jacksboro_pyramid("tiles-curvature");
    let streamed = load_atlas(&jacksboro_scene(&pyr, "[stream]\ncpu_mb = 0")).unwrap();
    let whole = load_atlas(&jacksboro_scene(&asc, "")).unwrap();
    assert!(streamed.resident_from > 1 && streamed.levels[0].data.is_empty());
    for water in [f32::MIN, 400.0] {
        let (a, b) = (
            streamed.level_curvature(water),
            whole.level_curvature(water),
        );
        assert_eq!(a.len(), b.len());
        // Levels under 3 texels a side have no interior texel: NaN either way.
        let interior = whole
            .levels
            .iter()
            .filter(|v| v.width.min(v.height) >= 3)
            .count();
        for (l, (a, b)) in a.iter().zip(&b).enumerate() {
            assert_eq!(b.is_finite(), l < interior, "level {l}: {b}");
            assert_eq!(
                a.to_bits(),
                b.to_bits(),
                "level {l} at water {water}: {a} against {b}"
            );
        }
    }
    damage(&pyr.join("L0/0/0.tile"));
    let a = streamed.level_curvature(f32::MIN);
    assert!(a[0].is_nan(), "a damaged level-0 tile: {}", a[0]);
    assert!(a[1].is_finite() && a[1] > 0.0, "level 1: {}", a[1]);
}

#[test]
fn a_streamed_snapshot_settles_on_the_whole_sketchs_image_and_a_damaged_tile_fails_it() {
    use terrain_engine::Renderer;
    use terrain_engine::View;
    use terrain_engine::scene::Mode;
    let (_, asc, pyr) = jacksboro_pyramid("tiles-settled");
    // Fades of 8 frames, as by default: a settled snapshot places its tiles without them.
    let streamed = jacksboro_scene(&pyr, "[stream]\ngpu_mb = 4");
    let whole = jacksboro_scene(&asc, "");
    let mut m = Renderer::new(&whole, Mode::Warped, View::Shaded).unwrap();
    let camera = terrain_engine::scene::camera_of(&whole, &m.atlas).unwrap();
    let expected = m.render(&camera).unwrap();
    let mut s = Renderer::new(&streamed, Mode::Warped, View::Shaded).unwrap();
    let first = s.render(&camera).unwrap();
    assert!(first.stream.unwrap().stand_in);
    let mut s = Renderer::new(&streamed, Mode::Warped, View::Shaded).unwrap();
    let settled = s.render_settled(&camera).unwrap();
    let stats = settled.stream.unwrap();
    assert!(!stats.stand_in, "{stats:?}");
    let (before, after) = (
        psnr(&first.rgba, &expected.rgba),
        psnr(&settled.rgba, &expected.rgba),
    );
    eprintln!("first frame {before:.1} dB, settled {after:.1} dB");
    assert!(
        before < 50.0 && after >= 50.0,
        "{before:.1} → {after:.1} dB"
    );
    // A damaged tile the loader reads fails the snapshot, naming it; no panic, no stand-in image.
    // (cpu_mb = 0: the load itself reads only the top level and level 0's relief.)
    let streamed = jacksboro_scene(&pyr, "[stream]\ngpu_mb = 4\ncpu_mb = 0");
    let tile = pyr.join("L1/0/0.tile");
    damage(&tile);
    let mut s = Renderer::new(&streamed, Mode::Warped, View::Shaded).unwrap();
    let e = s.render_settled(&camera).err().expect("a damaged tile");
    assert!(
        e.to_string().contains("L1") && e.to_string().lines().count() == 1,
        "{e}"
    );
}

#[test]
fn fly_settle_waits_for_every_frames_tiles_and_without_it_the_first_frame_stands_in() {
    let (dir, _, pyr) = jacksboro_pyramid("tiles-fly-settle");
    let scene = dir.join("scene.toml");
    std::fs::write(&scene, jacksboro_text(&pyr, "[stream]\ngpu_mb = 4")).unwrap();
    let stand_in = |settle: bool| -> Vec<String> {
        let out = dir.join(if settle { "settled" } else { "free" });
        let mut args = vec![
            "fly",
            scene.to_str().unwrap(),
            "--out-dir",
            out.to_str().unwrap(),
            "--frames",
            "3",
            "--size",
            "96",
            "--no-mp4",
        ];
        if settle {
            args.push("--settle");
        }
        let (code, _, stderr) = terrain(&args);
        assert_eq!(code, 0, "{stderr}");
        let csv = std::fs::read_to_string(out.join("frames.csv")).unwrap();
        let mut lines = csv.lines();
        let header: Vec<&str> = lines.next().unwrap().split(',').collect();
        let k = header.iter().position(|&c| c == "stand_in").unwrap();
        lines
            .map(|l| l.split(',').nth(k).unwrap().to_string())
            .collect()
    };
    assert_eq!(stand_in(true), ["false"; 3]);
    assert_eq!(stand_in(false)[0], "true");
}

#[test]
fn compare_over_a_pyramid_sweeps_warped_and_geomipmap_and_refuses_brute_force_before_any_work() {
    use terrain_engine::scene::Mode;
    let (dir, _, pyr) = jacksboro_pyramid("tiles-compare");
    let scene = jacksboro_scene(&pyr, "");
    assert_eq!(
        terrain_cli::eval::compare::default_modes(&scene),
        [Mode::Warped, Mode::Geomipmap]
    );
    let whole = jacksboro_scene(
        &common::manifest_dir().join("sketches/jacksboro_fault_dem.asc"),
        "",
    );
    assert_eq!(terrain_cli::eval::compare::default_modes(&whole).len(), 3);
    let file = dir.join("scene.toml");
    std::fs::write(&file, jacksboro_text(&pyr, "")).unwrap();
    let out = dir.join("cmp");
    let (code, _, stderr) = terrain(&[
        "compare",
        file.to_str().unwrap(),
        "--out-dir",
        out.to_str().unwrap(),
        "--modes",
        "warped,bruteforce",
    ]);
    assert_eq!(code, 1);
    assert!(
        stderr.contains("--modes") && stderr.contains("bruteforce") && stderr.lines().count() == 1,
        "{stderr}"
    );
    assert!(!out.join("report.csv").exists(), "refused before any work");
}

/// A planet's global sketch streamed from a pyramid of several tiles a level (1024 × 512 nodes
/// of 0.35°: level 0 in 4 × 2 tiles) draws as the same sketch in memory once its tiles are
/// resident, in clipmaps and reference modes, on the date line where the bicubic's taps wrap
/// across tiles; the camera is placed on the same ground (read from level 0's tiles); and the
/// first frame, with 4 MiB of pages, stands in.
#[test]
fn a_streamed_planet_draws_as_its_sketch_in_memory_once_resident() {
    use terrain_engine::Renderer;
    use terrain_engine::View;
    use terrain_engine::scene::Mode;
    let dir = scratch("tiles-planet");
    let tif = common::manifest_dir().join("tests/data/planet/global-1024x512.tif");
    let pyr = dir.join("pyr");
    convert(&tif, &pyr);
    let text = |sketch: &Path, extra: &str| {
        format!(
            "[sketch]\npath = {:?}\n[planet]\n[camera]\nlat_deg = 30.0\nlon_deg = 179.9\n\
             altitude_m = 60000.0\npitch_deg = -25.0\nheading_deg = 80.0\nwidth = 96\nheight = 64\n{extra}\n",
            sketch.display().to_string()
        )
    };
    let whole = common::scene(&text(&tif, ""), dir.clone());
    let streamed = common::scene(&text(&pyr, "[stream]\ngpu_mb = 4"), dir.clone());
    // A regional pyramid is no planet: refused in one line, as the file it came from is.
    let (_, _, regional) = jacksboro_pyramid("tiles-planet-regional");
    let e = terrain_engine::scene::load_atlas(&common::scene(&text(&regional, ""), dir.clone()))
        .expect_err("a regional pyramid is refused")
        .to_string();
    assert!(e.contains("global") && !e.contains('\n'), "{e}");
    for mode in [Mode::Clipmaps, Mode::Reference] {
        let mut m = Renderer::new(&whole, mode, View::Shaded).unwrap();
        let camera = terrain_engine::scene::camera_of(&whole, &m.atlas).unwrap();
        let expected = m.render(&camera).unwrap();
        let mut s = Renderer::new(&streamed, mode, View::Shaded).unwrap();
        let placed = terrain_engine::scene::camera_of(&streamed, &s.atlas).unwrap();
        assert!(
            (placed.eye - camera.eye).length() < 1e-6,
            "{mode}: the camera stands on other ground: {} vs {}",
            placed.eye,
            camera.eye
        );
        let first = s.render(&camera).unwrap();
        let stats = first.stream.expect("a pyramid streams");
        assert!(stats.stand_in && stats.missing > 0, "{mode}: {stats:?}");
        let first_db = psnr(&first.rgba, &expected.rgba);
        let last = s.render_settled(&camera).unwrap();
        assert!(!last.stream.unwrap().stand_in, "{mode}");
        let db = psnr(&last.rgba, &expected.rgba);
        eprintln!("planet {mode}: first frame {first_db:.1} dB, resident {db:.1} dB");
        assert!(first_db < 50.0, "{mode}: the stand-in frame should differ");
        assert!(
            db >= 50.0,
            "{mode}: {db:.1} dB against the sketch in memory"
        );
    }
}
