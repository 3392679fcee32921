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
