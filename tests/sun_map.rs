//! The sketch's sun clearance map (`gpu::sun_map`, `render.sun_map`): the mesh modes' shadow read
//! from it is the shadow the ray marched at every pixel draws, on views that meet the sketch's
//! edges and the plain beyond them, for a fraction of the shadow steps; a new sun remakes it.

mod common;
use common::*;
use terrain_cli::eval::metrics::psnr;
use terrain_engine::scene::{Mode, Scene};
use terrain_engine::{Renderer, View, Work};

/// `sketches/NAME.toml` at 128², with the map on or off.
fn scene(name: &str, sun_map: bool) -> Scene {
    let mut scene = Scene::load(&manifest_dir().join(format!("sketches/{name}.toml"))).unwrap();
    (scene.camera.width, scene.camera.height) = (128, 128);
    scene.render.sun_map = sun_map;
    scene
}

/// The frame of `scene`'s camera, and what its shading evaluated.
fn draw(scene: &Scene, mode: Mode) -> (Vec<u8>, Work) {
    let atlas = terrain_engine::scene::load_atlas(scene).unwrap();
    let ctx = terrain_engine::GpuContext::new(&terrain_engine::needs(scene, mode, &atlas)).unwrap();
    let camera = terrain_engine::scene::camera_of(scene, &atlas).unwrap();
    let mut r = Renderer::counting_work(ctx, scene, atlas, mode, View::Shaded).unwrap();
    let frame = r.render_settled(&camera).unwrap();
    (frame.rgba, frame.work.unwrap())
}

/// The picture with the map is the marched one, the sketch's edges and the margin beyond them
/// included; the steps are counted over the sketch alone (`outside = "void"`), where the map
/// stands in for the march: the margin's pixels, drawn by the sky pass, march alike either way.
#[test]
fn the_map_draws_the_marched_shadow_for_fewer_steps() {
    let void = |mut s: Scene| {
        s.sketch.outside = Some(terrain_engine::scene::Outside::Void);
        s
    };
    for name in ["jacksboro", "hills-high", "gaussian-high"] {
        for mode in [Mode::Warped, Mode::Geomipmap] {
            let (mapped, _) = draw(&scene(name, true), mode);
            let (marched, _) = draw(&scene(name, false), mode);
            let db = psnr(&marched, &mapped);
            assert!(
                db > 50.0,
                "{name} {mode}: {db:.1} dB from the marched shadow"
            );
            let (_, with_map) = draw(&void(scene(name, true)), mode);
            let (_, without) = draw(&void(scene(name, false)), mode);
            assert!(
                with_map.shadow_steps * 4 < without.shadow_steps * 3,
                "{name} {mode}: {} shadow steps with the map, {} without",
                with_map.shadow_steps,
                without.shadow_steps
            );
        }
    }
}

#[test]
fn a_new_sun_remakes_the_map() {
    let low_sun = |s: &mut Scene| {
        s.light.sun_elevation_deg = Some(12.0);
        s.light.sun_azimuth_deg = Some(250.0);
    };
    let first = scene("jacksboro", true);
    let mut second = first.clone();
    low_sun(&mut second);
    let mut r = Renderer::new(&first, Mode::Warped, View::Shaded).unwrap();
    let camera = terrain_engine::scene::camera_of(&first, r.atlas()).unwrap();
    let before = r.render_settled(&camera).unwrap().rgba;
    r.relight(&second);
    let relit = r.render_settled(&camera).unwrap().rgba;
    let mut fresh = Renderer::new(&second, Mode::Warped, View::Shaded).unwrap();
    let expected = fresh.render_settled(&camera).unwrap().rgba;
    assert!(relit != before, "the low sun changed nothing");
    assert!(relit == expected, "the relit frame is not the low sun's");
}
