//! Helpers shared by the integration tests.
#![allow(dead_code)]

use std::path::PathBuf;
use terrain_engine::Camera;
use terrain_engine::scene;
use terrain_engine::scene::Scene;
use terrain_engine::sketch::Atlas;
use terrain_engine::stage::CpuStage;
use terrain_engine::stage::pair_unfolded;
use terrain_engine::stage::quality::{self, Quality};

pub fn manifest_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// A scratch folder under target/, emptied first.
pub fn scratch(name: &str) -> PathBuf {
    let d = manifest_dir()
        .join("target")
        .join("test-scratch")
        .join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("scratch dir");
    d
}

pub fn scene(toml: &str, base: PathBuf) -> Scene {
    Scene::parse(toml, base).unwrap_or_else(|e| panic!("scene: {e}\n{toml}"))
}

pub struct Run {
    pub atlas: Atlas,
    pub camera: Camera,
    pub stage: CpuStage,
    pub quality: Quality,
}

pub fn run(scene: &Scene) -> Run {
    let atlas = scene::load_atlas(scene).expect("atlas");
    run_with(scene, atlas)
}

pub fn run_with(scene: &Scene, atlas: Atlas) -> Run {
    let detail = scene::detail_of(scene, &atlas);
    let camera = scene::camera_of(scene, &atlas).expect("camera");
    let mut stage = CpuStage::new(scene, &detail).expect("stage");
    stage.run(&atlas, &camera);
    let n = stage.sketch_map.n;
    let mut ratios = Vec::new();
    let quality = quality::measure(
        &stage.warp.phi,
        n,
        stage.sketch_map.spacing,
        &stage.importance,
        &mut ratios,
    );
    Run {
        atlas,
        camera,
        stage,
        quality,
    }
}

/// The properties every guarded warp must have: finite, inside the region, corners and edges kept,
/// rows strictly increasing in x and columns in y, and no flipped triangle (so no flipped cell).
pub fn assert_sound(r: &Run, what: &str) {
    let n = r.stage.sketch_map.n;
    let phi = &r.stage.warp.phi;
    let extent = r.stage.sketch_map.extent() as f32;
    let tol = 1e-4 * extent;
    assert_eq!(r.quality.nonfinite, 0, "{what}: non-finite values");
    assert!(
        r.stage
            .importance
            .importance
            .iter()
            .all(|v| v.is_finite() && *v > 0.0),
        "{what}: importance"
    );
    for (k, p) in phi.iter().enumerate() {
        assert!(
            p[0].is_finite() && p[1].is_finite(),
            "{what}: Φ[{k}] = {p:?}"
        );
        assert!(
            p[0] >= -tol && p[0] <= extent + tol && p[1] >= -tol && p[1] <= extent + tol,
            "{what}: Φ[{k}] = {p:?} outside 0..{extent}"
        );
    }
    for t in 0..n {
        assert!(
            phi[t * n][0].abs() <= tol && (phi[t * n + n - 1][0] - extent).abs() <= tol,
            "{what}: row {t} loses its ends"
        );
        for s in 0..n - 1 {
            assert!(
                phi[t * n + s + 1][0] > phi[t * n + s][0],
                "{what}: row {t} not increasing at {s}"
            );
        }
    }
    for s in 0..n {
        assert!(
            phi[s][1].abs() <= tol && (phi[(n - 1) * n + s][1] - extent).abs() <= tol,
            "{what}: column {s} loses its ends"
        );
        for t in 0..n - 1 {
            assert!(
                phi[(t + 1) * n + s][1] > phi[t * n + s][1],
                "{what}: column {s} not increasing at {t}"
            );
        }
    }
    assert_eq!(r.quality.flipped_cells, 0, "{what}: flipped cells");
    for s in 0..n - 1 {
        assert!(
            pair_unfolded(phi, n, s),
            "{what}: a flipped triangle between columns {s} and {}",
            s + 1
        );
    }
}

#[allow(unused_imports)] // not every test file compares images
pub use terrain_cli::eval::metrics::psnr;

/// An image of |a − b| × 4, for looking at where two renders differ.
pub fn difference(a: &[u8], b: &[u8]) -> Vec<u8> {
    a.chunks_exact(4)
        .zip(b.chunks_exact(4))
        .flat_map(|(pa, pb)| {
            let d = |c: usize| ((pa[c] as i32 - pb[c] as i32).unsigned_abs() * 4).min(255) as u8;
            [d(0), d(1), d(2), 255]
        })
        .collect()
}

pub fn read_png(path: &std::path::Path) -> Option<(u32, u32, Vec<u8>)> {
    let file = std::fs::File::open(path).ok()?;
    let mut reader = png::Decoder::new(std::io::BufReader::new(file))
        .read_info()
        .ok()?;
    let mut buf = vec![0; reader.output_buffer_size()?];
    let info = reader.next_frame(&mut buf).ok()?;
    (info.color_type == png::ColorType::Rgba)
        .then(|| (info.width, info.height, buf[..info.buffer_size()].to_vec()))
}

/// Runs the `terrain` binary (progress lines off); (exit code, stdout, stderr).
pub fn terrain(args: &[&str]) -> (i32, String, String) {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_terrain"))
        .args(args)
        .env("TERRAIN_QUIET", "1")
        .output()
        .expect("run terrain");
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// name → PNG bytes of every snapshot in `dir`.
pub fn pngs(dir: &std::path::Path) -> std::collections::BTreeMap<String, Vec<u8>> {
    std::fs::read_dir(dir)
        .unwrap()
        .flatten()
        .filter(|e| e.file_name().to_string_lossy().ends_with(".png"))
        .map(|e| {
            (
                e.file_name().to_string_lossy().into_owned(),
                std::fs::read(e.path()).unwrap(),
            )
        })
        .collect()
}

/// A test run in its own harness (libtest-mimic) that needs programs the machine may lack: where
/// `why_not` says it cannot run, it reports itself skipped with the reason, unless the
/// environment variable `required` is set (`.ci/run` sets it), where it fails instead. A panic
/// in `test` fails it with the panic's message.
pub fn skippable_trial(
    name: &'static str,
    test: fn(),
    why_not: Option<String>,
    required: &'static str,
) -> libtest_mimic::Trial {
    use libtest_mimic::{Failed, Trial};
    let must = std::env::var_os(required).is_some();
    let reason = why_not.clone();
    let trial = Trial::test(name, move || match &reason {
        Some(why) => Err(Failed::from(format!("{why}, and {required} is set"))),
        None => std::panic::catch_unwind(test).map_err(|p| {
            let text = p
                .downcast_ref::<String>()
                .cloned()
                .or_else(|| p.downcast_ref::<&str>().map(|s| s.to_string()));
            Failed::from(text.unwrap_or_else(|| "panicked".into()))
        }),
    });
    match why_not {
        Some(why) if !must => trial
            .with_kind(format!("skipped: {why}"))
            .with_ignored_flag(true),
        _ => trial,
    }
}

/// Every command line of the README's `sh` blocks, in order, comments dropped.
pub fn readme_commands() -> Vec<String> {
    let readme = std::fs::read_to_string(manifest_dir().join("README.md")).unwrap();
    let mut commands = Vec::new();
    for block in readme.split("```sh\n").skip(1) {
        let body = block.split("```").next().unwrap();
        for line in body.lines() {
            let command = line.split(" #").next().unwrap().trim();
            if !command.is_empty() {
                commands.push(command.to_string());
            }
        }
    }
    commands
}

/// Reads a `.npy` of f64 as written by `render --positions`: (shape, values).
pub fn read_npy(path: &std::path::Path) -> (String, Vec<f64>) {
    let b = std::fs::read(path).unwrap();
    assert_eq!(&b[..8], b"\x93NUMPY\x01\x00");
    let n = u16::from_le_bytes([b[8], b[9]]) as usize;
    let header = String::from_utf8(b[10..10 + n].to_vec()).unwrap();
    let values = b[10 + n..]
        .chunks_exact(8)
        .map(|c| f64::from_le_bytes(c.try_into().unwrap()))
        .collect();
    (header, values)
}

/// The bundled DEM converted by `terrain tiles` into `dir/pyramid`, and `dir/streamed.toml`: the
/// jacksboro scene over that pyramid, with `extra` TOML appended.
pub fn streamed_jacksboro(dir: &std::path::Path, extra: &str) -> PathBuf {
    let pyramid = dir.join("pyramid");
    let dem = manifest_dir().join("sketches/jacksboro_fault_dem.asc");
    let (code, _, err) = terrain(&[
        "tiles",
        dem.to_str().unwrap(),
        "--out-dir",
        pyramid.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    let text = std::fs::read_to_string(manifest_dir().join("sketches/jacksboro.toml"))
        .unwrap()
        .replace("jacksboro_fault_dem.asc", pyramid.to_str().unwrap());
    let scene = dir.join("streamed.toml");
    std::fs::write(&scene, text + extra).unwrap();
    scene
}

/// `terrain render SCENE -o DIR/render.png --size SIZE`'s pixels (RGBA).
pub fn rendered_rgba(scene: &std::path::Path, dir: &std::path::Path, size: u32) -> Vec<u8> {
    rendered_rgba_with(scene, dir, size, &[])
}

/// As [`rendered_rgba`], with `extra` arguments to `render` (a `--mode`, say).
pub fn rendered_rgba_with(
    scene: &std::path::Path,
    dir: &std::path::Path,
    size: u32,
    extra: &[&str],
) -> Vec<u8> {
    let png = dir.join("render.png");
    let size = size.to_string();
    let mut args = vec![
        "render",
        scene.to_str().unwrap(),
        "-o",
        png.to_str().unwrap(),
        "--size",
        &size,
    ];
    args.extend_from_slice(extra);
    let (code, _, err) = terrain(&args);
    assert_eq!(code, 0, "{err}");
    read_png(&png).expect("render wrote its image").2
}
