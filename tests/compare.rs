//! `terrain compare` end to end on a small image: one CSV row per mode and setting with every
//! column filled, the JSON report agreeing with it, the figures written, the path's series with
//! brute force (no level of detail) as the zero control, and bad options failing in one line.

mod common;
use common::*;
use terrain_cli::eval::compare::report::{CSV_COLUMNS, Row};
use terrain_cli::eval::compare::sweep::{Setting, at_geomipmap_budgets, default_sweep};
use terrain_engine::scene::Mode;

fn sketch(name: &str) -> String {
    manifest_dir()
        .join("sketches")
        .join(name)
        .display()
        .to_string()
}

fn png_size(path: &std::path::Path) -> (u32, u32) {
    let decoder = png::Decoder::new(std::io::BufReader::new(
        std::fs::File::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display())),
    ));
    let info = decoder.read_info().expect("a PNG").info().clone();
    (info.width, info.height)
}

#[test]
fn compare_reports_every_setting_with_every_column_filled() {
    let dir = scratch("compare-gaussian");
    let out = dir.display().to_string();
    let (code, stdout, err) = terrain(&[
        "compare",
        &sketch("gaussian.toml"),
        "--out-dir",
        &out,
        "--size",
        "64",
        "--modes",
        "warped,geomipmap,bruteforce",
        "--repeat",
        "1",
        "--path-frames",
        "3",
        "--work",
        // A held warp may not change at all over two steps; warped anew each frame, it must.
        "--set",
        "warp.hold=false",
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(stdout.contains("frame time to 30 dB"), "{stdout}");

    let mut scene =
        terrain_engine::scene::Scene::load(&manifest_dir().join("sketches/gaussian.toml")).unwrap();
    (scene.camera.width, scene.camera.height) = (64, 64);
    // As the run had it: the sweep's warped rows depend on the mesh the view asks for.
    scene.warp.hold = false;
    let atlas = terrain_engine::scene::load_atlas(&scene).unwrap();
    let camera = terrain_engine::scene::camera_of(&scene, &atlas).unwrap();
    let modes = [Mode::Warped, Mode::Geomipmap, Mode::Bruteforce];
    let sweep = default_sweep(&modes, &scene, &atlas, &camera).unwrap();
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("report.json")).unwrap()).unwrap();
    let rows: Vec<Row> = serde_json::from_value(report["rows"].clone()).unwrap();
    // Then warped at GeoMipMap's budgets, worked out from the sweep's rows, with the warped rows.
    let in_sweep: Vec<Row> = rows
        .iter()
        .filter(|r| {
            sweep
                .iter()
                .any(|s| s.mode_name() == r.mode && s.label() == r.setting)
        })
        .cloned()
        .collect();
    let at_budgets = at_geomipmap_budgets(scene.warp.quad_px, &in_sweep);
    assert!(!at_budgets.is_empty(), "{rows:?}");
    let settings: Vec<Setting> = modes
        .iter()
        .flat_map(|&m| {
            let extra = if m == Mode::Warped {
                &at_budgets[..]
            } else {
                &[]
            };
            sweep.iter().filter(move |s| s.mode() == m).chain(extra)
        })
        .cloned()
        .collect();
    // Each GeoMipMap row has a warped row with the most triangles a fixed mesh can have within
    // its own.
    for g in rows.iter().filter(|r| r.mode == "geomipmap") {
        let most = 2 * (g.triangles / 2).isqrt().pow(2);
        assert!(
            rows.iter()
                .any(|w| w.mode == "warped" && w.triangles == most),
            "no warped row of {most} triangles for {} ({})",
            g.setting,
            g.triangles
        );
    }
    let csv = std::fs::read_to_string(dir.join("report.csv")).unwrap();
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(lines[0], CSV_COLUMNS.join(","));
    assert_eq!(
        lines.len() - 1,
        settings.len(),
        "one row per setting:\n{csv}"
    );
    for (line, s) in lines[1..].iter().zip(&settings) {
        let cells: Vec<&str> = line.split(',').collect();
        assert_eq!(cells.len(), CSV_COLUMNS.len(), "{line}");
        // Every cell filled, but the counts where the adapter cannot count (GL).
        let counted = CSV_COLUMNS
            .iter()
            .position(|c| *c == "fragments_per_covered_px");
        assert!(
            cells
                .iter()
                .enumerate()
                .all(|(k, c)| !c.is_empty() || Some(k) == counted),
            "empty cell: {line}"
        );
        assert_eq!((cells[0], cells[1]), (s.mode_name(), s.label().as_str()));
        let num = |name: &str| {
            let k = CSV_COLUMNS.iter().position(|c| *c == name).unwrap();
            cells[k]
                .parse::<f64>()
                .unwrap_or_else(|_| panic!("{name}: {line}"))
        };
        assert!(num("triangles") > 0.0, "no triangles: {line}");
        // `--work`: every mode's shading reads the sketch and evaluates the noise.
        assert!(num("atlas_taps_per_px") >= 1.0, "atlas taps: {line}");
        assert!(num("octaves_per_px") > 0.0, "octaves: {line}");
        let covered = num("covered_px");
        assert!(
            covered > 0.0 && covered <= 64.0 * 64.0,
            "covered pixels: {line}"
        );
        if let Some(k) = counted.filter(|&k| !cells[k].is_empty()) {
            // Every pixel showing ground is shaded at least once.
            assert!(cells[k].parse::<f64>().unwrap() >= 1.0, "fragments: {line}");
        }
        assert!(
            (num("triangles_per_px") - num("triangles") / (64.0 * 64.0)).abs() < 1e-4,
            "triangles per pixel: {line}"
        );
        let frame = num("frame_ms");
        assert!(frame > 0.0 && frame >= num("gpu_ms"), "frame time: {line}");
        assert!(
            num("frame_ms_p25") > 0.0 && num("frame_ms_p25") <= num("frame_ms_p75"),
            "frame time's quartiles: {line}"
        );
        let psnr = num("psnr_db");
        assert!(psnr > 10.0 && psnr < 100.0, "PSNR: {line}");
        let sse = num("sse_mean_px");
        assert!(
            sse >= 0.0 && sse <= num("sse_max_px"),
            "screen error: {line}"
        );
        // The LOD update's change along the path's first steps: brute force, with no level of
        // detail, is the control at exactly 0.
        let lod = num("lod_change_levels");
        assert!(lod >= 0.0, "LOD change: {line}");
        assert_eq!(lod == 0.0, cells[0] == "bruteforce", "LOD change: {line}");
    }
    // Some row of every mode is on a front; the fastest row always is.
    for m in ["warped", "geomipmap", "bruteforce"] {
        assert!(lines.iter().any(|l| l.starts_with(m)), "{m} missing");
    }

    assert_eq!(report["rows"].as_array().unwrap().len(), settings.len());
    assert_eq!(report["skipped"].as_array().unwrap().len(), 0);
    // The reference is converged below the differences it measures.
    let best = report["rows"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["psnr_db"].as_f64().unwrap())
        .fold(0.0, f64::max);
    let halving = report["reference"]["psnr_halving_step_db"]
        .as_f64()
        .unwrap();
    assert!(
        halving > best + 3.0,
        "reference moves {halving} dB, best mode {best} dB"
    );
    assert_eq!(report["summary"]["modes"].as_array().unwrap().len(), 3);

    for f in [
        "error_vs_time",
        "error_vs_triangles",
        "lod_change_vs_psnr",
        "ratio_histogram",
        "path_error",
    ] {
        let svg = std::fs::read_to_string(dir.join(format!("{f}.svg"))).unwrap();
        assert!(svg.starts_with("<svg") && svg.contains("</svg>"), "{f}.svg");
        let (w, h) = png_size(&dir.join(format!("{f}.png")));
        assert!(w >= 600 && h >= 400, "{f}.png is {w}×{h}");
    }
    let svg = std::fs::read_to_string(dir.join("error_vs_time.svg")).unwrap();
    for label in [
        "frame time (ms",
        "PSNR (dB",
        "screen-space error (px",
        "Pareto front",
        "GeoMipMap",
    ] {
        assert!(svg.contains(label), "error_vs_time.svg lacks {label:?}");
    }
    assert_eq!(png_size(&dir.join("strip.png")), (4 * 64, 2 * (64 + 36)));
    let npy = std::fs::read(dir.join("reference_positions.npy")).unwrap();
    assert!(npy.starts_with(b"\x93NUMPY") && npy.len() > 64 * 64 * 4 * 8);

    // The path: 3 frames × 3 modes; the first frame has no LOD change, brute force never has one.
    let path = std::fs::read_to_string(dir.join("path.csv")).unwrap();
    let rows: Vec<Vec<&str>> = path
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    assert_eq!(rows.len(), 9, "{path}");
    for r in &rows {
        let change = r[7];
        match (r[0], r[2]) {
            ("0", _) => assert_eq!(change, "", "{r:?}"),
            (_, "bruteforce") => assert_eq!(change.parse::<f64>().unwrap(), 0.0, "{r:?}"),
            _ => assert!(change.parse::<f64>().unwrap() >= 0.0, "{r:?}"),
        }
    }
    // --replot redraws the figure and the summary from report.json alone, the same summary.
    let summary = std::fs::read_to_string(dir.join("summary.md")).unwrap();
    std::fs::remove_file(dir.join("error_vs_time.svg")).unwrap();
    let g = sketch("gaussian.toml");
    let (code, stdout, err) = terrain(&["compare", &g, "--out-dir", &out, "--replot"]);
    assert_eq!(code, 0, "{err}");
    assert!(
        stdout.contains(&format!("{} rows redrawn", settings.len())),
        "{stdout}"
    );
    assert!(dir.join("error_vs_time.svg").is_file());
    assert_eq!(
        std::fs::read_to_string(dir.join("summary.md")).unwrap(),
        summary
    );

    // The warped mesh slides as the camera moves: swimming is measured, not zero.
    let warped_swims = rows
        .iter()
        .any(|r| r[2] == "warped" && r[0] != "0" && r[7].parse::<f64>().unwrap() > 0.0);
    assert!(warped_swims, "{path}");
}

#[test]
fn modes_and_size_narrow_the_sweep() {
    let dir = scratch("compare-narrow");
    let out = dir.display().to_string();
    let (code, _, err) = terrain(&[
        "compare",
        &sketch("hills-high.toml"),
        "--out-dir",
        &out,
        "--size",
        "48",
        "--modes",
        "bruteforce",
        "--repeat",
        "1",
        "--path-frames",
        "0",
    ]);
    assert_eq!(code, 0, "{err}");
    let csv = std::fs::read_to_string(dir.join("report.csv")).unwrap();
    assert!(
        csv.lines().skip(1).all(|l| l.starts_with("bruteforce,K=")),
        "{csv}"
    );
    assert_eq!(png_size(&dir.join("reference.png")), (48, 48));
    assert!(!dir.join("path.csv").exists() && !dir.join("ratio_histogram.svg").exists());
}

#[test]
fn bad_compare_options_fail_in_one_line() {
    let dir = scratch("compare-bad").display().to_string();
    let g = sketch("gaussian.toml");
    for (args, cause) in [
        (vec!["--modes", "warped,lod"], "lod"),
        (vec!["--size", "0"], "size"),
        (vec!["--path-fps", "0"], "path-fps"),
        (vec!["--set", "warp.quad_px=-1"], "warp.quad_px"),
    ] {
        let mut all = vec!["compare", g.as_str(), "--out-dir", dir.as_str()];
        all.extend(args.iter().copied());
        let (code, _, err) = terrain(&all);
        assert_ne!(code, 0, "{all:?} succeeded");
        assert!(!err.contains("panicked"), "{all:?}: {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{all:?}: {err}");
        assert!(err.contains(cause), "{all:?}: {err}");
    }
}

#[test]
fn scene_settings_are_in_the_default_sweep() {
    // The strip and the path show each mode at the scene's setting; with the bundled scenes'
    // defaults those are rows of the sweep, so the strip's images are the report's.
    for name in ["jacksboro", "gaussian", "hills-high"] {
        let scene = terrain_engine::scene::Scene::load(
            &manifest_dir().join(format!("sketches/{name}.toml")),
        )
        .unwrap();
        let atlas = terrain_engine::scene::load_atlas(&scene).unwrap();
        let camera = terrain_engine::scene::camera_of(&scene, &atlas).unwrap();
        let modes = [Mode::Warped, Mode::Geomipmap, Mode::Bruteforce];
        let sweep = default_sweep(&modes, &scene, &atlas, &camera).unwrap();
        for m in [Mode::Warped, Mode::Geomipmap, Mode::Bruteforce] {
            let s: Setting = Setting::of_scene(m, &scene, &atlas).unwrap();
            assert!(sweep.contains(&s), "{name}: {s:?} not swept");
        }
    }
}

/// On a planet `compare` sweeps clipmaps' φ steps and rings per level against the planet's
/// reference (triangles doubling with φ steps), flies the default pass for the path series with
/// the LOD change measured, and refuses planar modes in one line (and clipmaps on a sketch).
#[test]
fn compare_sweeps_a_planets_clipmaps() {
    let dir = scratch("compare-planet");
    let out = dir.display().to_string();
    let planet = sketch("planet-10km.toml");
    let (code, stdout, err) = terrain(&[
        "compare",
        &planet,
        "--out-dir",
        &out,
        "--size",
        "32",
        "--repeat",
        "1",
        "--path-frames",
        "3",
        "--set",
        "sketch.size=128",
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(stdout.contains("clipmaps"), "{stdout}");
    let csv = std::fs::read_to_string(dir.join("report.csv")).unwrap();
    let rows: Vec<Vec<&str>> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    assert_eq!(rows.len(), 8, "{csv}");
    assert!(rows.iter().all(|r| r[0] == "clipmaps"), "{csv}");
    let column = |name: &str| CSV_COLUMNS.iter().position(|c| *c == name).unwrap();
    let triangles: Vec<u64> = rows[..4]
        .iter()
        .map(|r| r[column("triangles")].parse().unwrap())
        .collect();
    for w in triangles.windows(2) {
        assert_eq!(w[1], 2 * w[0], "triangles over φ steps: {triangles:?}");
    }
    for r in &rows {
        for name in ["psnr_db", "sse_mean_px", "lod_change_levels"] {
            let v: f64 = r[column(name)].parse().unwrap_or(f64::NAN);
            assert!(
                v.is_finite() && v >= 0.0,
                "{name} = {}: {csv}",
                r[column(name)]
            );
        }
    }
    let path = std::fs::read_to_string(dir.join("path.csv")).unwrap();
    assert_eq!(path.lines().count(), 4, "{path}");
    assert!(dir.join("error_vs_triangles.png").exists() && dir.join("strip.png").exists());

    for (scene, modes, cause) in [
        (planet.as_str(), "warped", "planet"),
        (&*sketch("gaussian.toml"), "clipmaps", "clipmaps"),
    ] {
        let (code, _, err) = terrain(&["compare", scene, "--out-dir", &out, "--modes", modes]);
        assert_ne!(code, 0, "{modes} on {scene} succeeded");
        assert_eq!(err.trim_end().lines().count(), 1, "{err}");
        assert!(err.contains("--modes") && err.contains(cause), "{err}");
    }
}

/// The warped sweep climbs the budget's ladder in fixed meshes up to 8 triangles a pixel, without
/// repeating the mesh the scene's own setting draws; a larger image climbs further.
#[test]
fn the_warped_sweep_spans_the_budgets_where_geomipmap_competes() {
    let mut scene =
        terrain_engine::scene::Scene::load(&manifest_dir().join("sketches/jacksboro.toml"))
            .unwrap();
    let atlas = terrain_engine::scene::load_atlas(&scene).unwrap();
    let mut fixed_rows = Vec::new();
    for size in [128u32, 512] {
        (scene.camera.width, scene.camera.height) = (size, size);
        let camera = terrain_engine::scene::camera_of(&scene, &atlas).unwrap();
        let sweep = default_sweep(&[Mode::Warped], &scene, &atlas, &camera).unwrap();
        let own = Setting::of_scene(Mode::Warped, &scene, &atlas).unwrap();
        assert_eq!(sweep.last(), Some(&own), "{sweep:?}");
        let meshes: Vec<u32> = sweep[..sweep.len() - 1]
            .iter()
            .map(|s| match (s.mode, &s.values[..]) {
                (Mode::Warped, &[quad_px, mesh, 0.0]) if quad_px == scene.warp.quad_px => {
                    mesh as u32
                }
                other => panic!("not a fixed warped mesh: {other:?}"),
            })
            .collect();
        // Every rung of the ladder within 8 triangles a pixel, less at most one: the rung the
        // scene's own setting draws.
        let pixels = (size * size) as f64;
        let ladder: Vec<u32> = terrain_engine::stage::Budget::new(16, 1024)
            .rungs()
            .iter()
            .copied()
            .filter(|&m| 2.0 * (m as f64 - 1.0).powi(2) <= 8.0 * pixels)
            .collect();
        assert!(
            meshes.iter().all(|m| ladder.contains(m)),
            "{meshes:?} of {ladder:?}"
        );
        assert!(meshes.windows(2).all(|w| w[0] < w[1]), "{meshes:?}");
        assert!(meshes.len() + 1 >= ladder.len(), "{meshes:?} of {ladder:?}");
        fixed_rows.push(meshes.len());
    }
    assert!(
        fixed_rows[1] >= fixed_rows[0] + 3,
        "512² climbs further: {fixed_rows:?}"
    );
}

/// The settings are timed side by side, a frame of each a round (`compare::rounds`): every row
/// gets `--repeat` frames from the rounds, each drawing its own setting's triangles (a renderer
/// left at another GeoMipMap τ draws others, and the row is listed in `skipped`). With no room
/// to keep renderers (`--keep-mib 0`) every setting is timed alone, and the images, triangles
/// and errors are the same: only the times are taken differently.
#[test]
fn compare_times_the_settings_in_rounds() {
    let run = |name: &str, keep_mib: &str| -> serde_json::Value {
        let dir = scratch(name);
        let out = dir.display().to_string();
        let (code, _, err) = terrain(&[
            "compare",
            &sketch("gaussian.toml"),
            "--out-dir",
            &out,
            "--size",
            "48",
            "--modes",
            "warped,geomipmap",
            "--repeat",
            "3",
            "--path-frames",
            "0",
            "--keep-mib",
            keep_mib,
        ]);
        assert_eq!(code, 0, "{err}");
        serde_json::from_str(&std::fs::read_to_string(dir.join("report.json")).unwrap()).unwrap()
    };
    let rounds = run("compare-rounds", "1024");
    let alone = run("compare-alone", "0");
    let rows =
        |r: &serde_json::Value| -> Vec<Row> { serde_json::from_value(r["rows"].clone()).unwrap() };
    let (a, b) = (rows(&rounds), rows(&alone));
    assert!(a.iter().any(|r| r.mode == "geomipmap") && a.iter().any(|r| r.mode == "warped"));
    for key in ["timed_alone", "skipped"] {
        assert_eq!(
            rounds[key],
            serde_json::json!([]),
            "{key}: {:?}",
            rounds[key]
        );
    }
    // Each τ of a block size draws its own triangles, so a round left at another τ shows.
    let gm: Vec<u64> = a
        .iter()
        .filter(|r| r.mode == "geomipmap")
        .map(|r| r.triangles)
        .collect();
    assert!(gm.windows(2).any(|w| w[0] != w[1]), "{gm:?}");
    let named: Vec<String> = serde_json::from_value(alone["timed_alone"].clone()).unwrap();
    assert_eq!(named.len(), b.len(), "{named:?}");
    assert_eq!(a.len(), b.len());
    for (x, y) in a.iter().zip(&b) {
        assert_eq!(x.frames, 3, "{x:?}");
        assert_eq!(y.frames, 3, "{y:?}");
        assert!(x.frame_ms > 0.0 && x.frame_ms.is_finite(), "{x:?}");
        // The frame time's quartiles over the timed frames, whichever way they were timed.
        for r in [x, y] {
            let (p25, p75) = (r.frame_ms_p25.unwrap(), r.frame_ms_p75.unwrap());
            assert!(0.0 < p25 && p25 <= p75 && p75.is_finite(), "{r:?}");
        }
        assert_eq!((&x.setting, x.triangles), (&y.setting, y.triangles));
        assert_eq!(x.psnr_db.to_bits(), y.psnr_db.to_bits(), "{}", x.setting);
        assert_eq!(
            x.sse_mean_px.to_bits(),
            y.sse_mean_px.to_bits(),
            "{}",
            x.setting
        );
    }
}
