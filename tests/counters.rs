//! The GPU's work counted per pass (`render --json`'s `counters`, `covered_px`): every pass of
//! every mode is counted, and the counts are the work the passes were given: a compute pass runs
//! one invocation per cell of its grid rounded up to whole 8×8 workgroups, the terrain pass shades
//! at least every pixel that shows ground.
//!
//! The counts come from WebGPU's pipeline statistics queries, which wgpu's Vulkan backend has
//! (Mesa's lavapipe among its drivers) and its GL backend has not. This file has its own harness
//! (libtest-mimic) so that where the adapter cannot count these tests are reported as ignored,
//! with the reason; where `TERRAIN_REQUIRE_COUNTERS` is set (`.ci/run` installs lavapipe and sets
//! it) they fail instead.

mod common;
use common::*;
use libtest_mimic::Arguments;
use serde_json::Value;

fn main() {
    let args = Arguments::from_args();
    let why_not = why_not();
    let tests: [(&'static str, fn()); 3] = [
        (
            "every_pass_of_every_mode_is_counted",
            every_pass_of_every_mode_is_counted,
        ),
        (
            "compute_passes_run_one_invocation_per_cell_of_their_grid",
            compute_passes_run_one_invocation_per_cell_of_their_grid,
        ),
        (
            "the_terrain_pass_shades_every_pixel_that_shows_ground",
            the_terrain_pass_shades_every_pixel_that_shows_ground,
        ),
    ];
    let trials = tests
        .into_iter()
        .map(|(name, test)| {
            skippable_trial(name, test, why_not.clone(), "TERRAIN_REQUIRE_COUNTERS")
        })
        .collect();
    libtest_mimic::run(&args, trials).exit();
}

/// Why the adapter cannot count, if it cannot.
fn why_not() -> Option<String> {
    let r = render("jacksboro", "warped", 32);
    r["counters"].is_null().then(|| {
        format!(
            "the adapter ({}) has no pipeline statistics queries; Debian: apt-get install \
             mesa-vulkan-drivers (lavapipe)",
            r["adapter"].as_str().unwrap_or("?")
        )
    })
}

/// `terrain render sketches/SCENE.toml --mode MODE --size N --json`, parsed.
fn render(scene: &str, mode: &str, size: u32) -> Value {
    let dir = scratch(&format!("counters-{scene}-{mode}-{size}"));
    let scene = manifest_dir().join(format!("sketches/{scene}.toml"));
    let out = dir.join("x.png");
    let (code, stdout, stderr) = terrain(&[
        "render",
        scene.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--mode",
        mode,
        "--size",
        &size.to_string(),
        "--json",
    ]);
    assert_eq!(code, 0, "{stderr}");
    serde_json::from_str(&stdout).unwrap_or_else(|e| panic!("{e}: {stdout}"))
}

/// A count of pass `pass` in `r`.
fn count(r: &Value, pass: &str, what: &str) -> u64 {
    r["counters"][pass][what]
        .as_u64()
        .unwrap_or_else(|| panic!("no {what} for {pass}: {}", r["counters"]))
}

/// Whole 8×8 workgroups over `n` cells: the invocations of one side.
fn padded(n: u64) -> u64 {
    n.div_ceil(8) * 8
}

fn every_pass_of_every_mode_is_counted() {
    let cases = [
        ("jacksboro", "warped", &["warp_zoom", "terrain"][..]),
        ("jacksboro", "geomipmap", &["terrain"][..]),
        ("jacksboro", "bruteforce", &["terrain"][..]),
        ("jacksboro", "reference", &["reference"][..]),
        ("planet-10km", "clipmaps", &["clipmaps", "planet"][..]),
        ("planet-10km", "reference", &["reference"][..]),
    ];
    for (scene, mode, passes) in cases {
        let r = render(scene, mode, 48);
        let counted = r["counters"].as_object().expect("counters");
        for pass in passes {
            let c = &counted[*pass];
            let total: u64 = [
                "vertex_invocations",
                "fragment_invocations",
                "compute_invocations",
            ]
            .iter()
            .map(|w| c[w].as_u64().unwrap())
            .sum();
            assert!(total > 0, "{scene} {mode}: {pass} counted nothing: {c}");
        }
        // Raster passes draw triangles; compute passes draw none.
        for (pass, c) in counted {
            let primitives = c["primitives"].as_u64().unwrap();
            let raster = pass == "terrain" || pass == "planet";
            assert_eq!(primitives > 0, raster, "{scene} {mode}: {pass}: {c}");
        }
    }
}

fn compute_passes_run_one_invocation_per_cell_of_their_grid() {
    // The reference marches one ray per pixel.
    let r = render("jacksboro", "reference", 52);
    assert_eq!(
        count(&r, "reference", "compute_invocations"),
        padded(52) * padded(52)
    );
    // Warp & zoom (and the normals) run once per vertex of the mesh drawn this frame; its
    // fixed triangulation draws two triangles per cell of it.
    let r = render("jacksboro", "warped", 64);
    let triangles = r["triangles"].as_u64().unwrap();
    let cells = triangles / 2;
    let side = (cells as f64).sqrt().round() as u64 + 1;
    assert_eq!((side - 1) * (side - 1), cells, "{triangles} triangles");
    let expected = padded(side) * padded(side);
    assert_eq!(count(&r, "warp_zoom", "compute_invocations"), expected);
    if r["counters"].get("normals").is_some() {
        assert_eq!(count(&r, "normals", "compute_invocations"), expected);
    }
}

fn the_terrain_pass_shades_every_pixel_that_shows_ground() {
    for mode in ["warped", "geomipmap"] {
        let r = render("jacksboro", mode, 64);
        let covered = r["covered_px"].as_u64().unwrap();
        assert!(covered > 64 * 64 / 4, "{mode}: {covered} pixels of ground");
        let fragments = count(&r, "terrain", "fragment_invocations");
        assert!(
            fragments >= covered,
            "{mode}: {fragments} fragments for {covered} pixels"
        );
        let per_px = r["fragments_per_covered_px"].as_f64().unwrap();
        assert!(
            (per_px - fragments as f64 / covered as f64).abs() < 1e-9,
            "{per_px}"
        );
        let vertices = count(&r, "terrain", "vertex_invocations");
        assert!(
            vertices > 0 && count(&r, "terrain", "primitives") > 0,
            "{mode}"
        );
    }
}
