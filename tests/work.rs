//! The counting variant (`gpu::work`, `render --json`'s `work_per_px`): it draws the pictures the
//! shaders users draw with do, and counts what the shading evaluates: noise octaves only where
//! there is noise, shadow steps only where shadows are drawn, one tally per pixel for the
//! reference (a compute invocation a pixel).

mod common;
use common::*;
use terrain_engine::scene::{Mode, Scene};
use terrain_engine::{Renderer, View, Work};

/// `sketches/jacksboro.toml` at `size`², with `edit` applied.
fn jacksboro(size: u32, edit: impl FnOnce(&mut Scene)) -> Scene {
    let mut scene = Scene::load(&manifest_dir().join("sketches/jacksboro.toml")).unwrap();
    (scene.camera.width, scene.camera.height) = (size, size);
    edit(&mut scene);
    scene
}

/// The frame of `scene`'s camera drawn plainly and by a counting renderer on the same device:
/// the plain image, the counted one, and the count.
fn both(scene: &Scene, mode: Mode) -> (Vec<u8>, Vec<u8>, Work) {
    let mut plain = Renderer::new(scene, mode, View::Shaded).unwrap();
    let camera = terrain_engine::scene::camera_of(scene, plain.atlas()).unwrap();
    let expected = plain.render_settled(&camera).unwrap();
    assert!(expected.work.is_none(), "a plain renderer counts nothing");
    let ctx = plain.ctx().clone();
    let atlas = plain.atlas().clone();
    let mut counting = Renderer::counting_work(ctx, scene, atlas, mode, View::Shaded).unwrap();
    let counted = counting.render_settled(&camera).unwrap();
    let work = counted
        .work
        .expect("a counting renderer's frame carries its work");
    (expected.rgba, counted.rgba, work)
}

#[test]
fn counting_changes_no_pixel_and_counts_each_kind_of_work() {
    for mode in [Mode::Warped, Mode::Geomipmap] {
        // The shadow marched at every pixel, not read from the sun clearance map.
        let scene = jacksboro(96, |s| s.render.sun_map = false);
        let (plain, counted, work) = both(&scene, mode);
        assert!(
            plain == counted,
            "{mode}: the counting variant drew another picture"
        );
        // Every pixel is shaded at least once (deferred: the G-buffer's fragments, then each
        // pixel's shading).
        assert!(work.invocations >= 96 * 96, "{mode}: {work:?}");
        assert!(work.octaves > 0 && work.atlas_taps > 0, "{mode}: {work:?}");
        // The sun stands over jacksboro's ridges: their shadow rays march.
        assert!(work.shadow_steps > 0, "{mode}: {work:?}");
    }
}

#[test]
fn work_left_out_of_a_scene_is_not_counted() {
    let scene = jacksboro(64, |s| s.render.shadows = false);
    let (_, _, work) = both(&scene, Mode::Warped);
    assert_eq!(
        work.shadow_steps, 0,
        "no shadows, no shadow steps: {work:?}"
    );
    assert!(work.octaves > 0, "{work:?}");
    let scene = jacksboro(64, |s| {
        s.detail.octaves = Some(0);
        s.render.sun_map = false;
    });
    let (_, _, work) = both(&scene, Mode::Warped);
    assert_eq!(work.octaves, 0, "no noise, no octaves: {work:?}");
    assert!(work.shadow_steps > 0 && work.atlas_taps > 0, "{work:?}");
}

#[test]
fn the_reference_counts_one_invocation_per_pixel_and_far_more_work() {
    let scene = jacksboro(48, |s| s.render.msaa = terrain_engine::scene::Msaa::Off);
    let (plain, counted, reference) = both(&scene, Mode::Reference);
    assert!(
        plain == counted,
        "the counting variant drew another picture"
    );
    assert_eq!(reference.invocations, 48 * 48, "{reference:?}");
    // The reference marches every pixel's ray through the terrain function: octaves and taps
    // at every step, where a mesh mode evaluates them once at the surface.
    let (_, _, warped) = both(&scene, Mode::Warped);
    assert!(
        reference.atlas_taps > 10 * warped.atlas_taps && reference.octaves > 10 * warped.octaves,
        "reference {reference:?}, warped {warped:?}"
    );
}

#[test]
fn render_json_reports_the_work_per_pixel_showing_ground() {
    let dir = scratch("work-render-json");
    let out = dir.join("x.png");
    let scene = manifest_dir().join("sketches/jacksboro.toml");
    let (code, stdout, stderr) = terrain(&[
        "render",
        scene.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--size",
        "48",
        "--json",
        "--set",
        "render.sun_map=false",
    ]);
    assert_eq!(code, 0, "{stderr}");
    let r: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    for key in ["octaves", "shadow_steps", "atlas_taps"] {
        let v = r["work_per_px"][key].as_f64();
        assert!(v.is_some_and(|v| v > 0.0), "{key}: {}", r["work_per_px"]);
    }
}
