//! The warp's sample budget (`warp.budget`): the mesh a frame draws follows the density its
//! importance demands, so it grows with the image and shrinks with `quad_px`, within
//! [`warp.min_mesh`, `warp.mesh`].

mod common;
use common::*;
use terrain_engine::scene::Scene;

fn jacksboro(size: u32, quad_px: f64) -> Scene {
    let mut s = Scene::load(&manifest_dir().join("sketches/jacksboro.toml")).unwrap();
    (s.camera.width, s.camera.height) = (size, size);
    s.warp.quad_px = quad_px;
    s.warp.mesh = 2048;
    s
}

#[test]
fn the_budget_grows_with_the_image_and_shrinks_with_quad_px() {
    let small = run(&jacksboro(256, 2.0));
    let large = run(&jacksboro(512, 2.0));
    let coarse = run(&jacksboro(256, 4.0));
    let (ms, ml, mc) = (small.stage.mesh, large.stage.mesh, coarse.stage.mesh);
    let cells = |r: &Run| r.stage.budget.as_ref().unwrap().demanded_cells;
    eprintln!(
        "mesh at 256² {ms} ({:.0} cells), at 512² {ml} ({:.0}), at quad_px 4 {mc} ({:.0})",
        cells(&small),
        cells(&large),
        cells(&coarse)
    );
    assert!(ml > ms && mc < ms, "{ms} {ml} {mc}");
    // I_v ∝ f_px / C: twice the pixels or half the quad size asks for four times the cells (the
    // floor, the cap at half a texel and the frustum margin keep it from being exact).
    let up = cells(&large) / cells(&small);
    let down = cells(&small) / cells(&coarse);
    assert!((3.0..=4.5).contains(&up), "{up}");
    assert!((3.0..=4.5).contains(&down), "{down}");
    // The mesh covers the demand, by at most a rung (a quarter octave) more.
    for (m, r) in [(ms, &small), (ml, &large), (mc, &coarse)] {
        let want = cells(r).sqrt() + 1.0;
        assert!(
            m as f64 >= want && (m as f64) < want * 1.25 + 8.0,
            "{m} for {want}"
        );
    }
}

#[test]
fn without_a_budget_and_at_the_bounds_the_mesh_is_the_scene_s() {
    let mut s = jacksboro(256, 2.0);
    s.warp.budget = false;
    assert_eq!(run(&s).stage.mesh, 2048);
    let mut s = jacksboro(512, 0.05);
    s.warp.mesh = 256;
    assert_eq!(run(&s).stage.mesh, 256, "capped by warp.mesh");
    let mut s = jacksboro(16, 100.0);
    s.warp.min_mesh = 40;
    assert_eq!(run(&s).stage.mesh, 40, "raised to warp.min_mesh");
}

/// One camera over a synthetic sketch, with the error term on or off and no procedural detail
/// (so the sketch's own curvature is all there is).
fn over(sketch: &str, error: bool) -> Run {
    let text = format!(
        "[sketch]\nsynthetic = \"{sketch}\"\nsize = 257\n[camera]\nposition = [1500.0, -300.0, 900.0]\nlook_at = [3000.0, 3000.0, 200.0]\nwidth = 256\nheight = 256\n[detail]\noctaves = 0\n[importance]\nerror = {error}\n[warp]\nmesh = 2048\n"
    );
    run(&scene(&text, manifest_dir()))
}

#[test]
fn under_the_error_term_flat_ground_asks_for_fewer_samples_than_rough() {
    let cells = |r: &Run| r.stage.budget.as_ref().unwrap().demanded_cells;
    let (flat, rough) = (over("flat", true), over("ridges", true));
    let (flat_v, rough_v) = (over("flat", false), over("ridges", false));
    eprintln!(
        "cells: flat {:.0} (without the term {:.0}), ridges {:.0} ({:.0}); meshes {} and {}",
        cells(&flat),
        cells(&flat_v),
        cells(&rough),
        cells(&rough_v),
        flat.stage.mesh,
        rough.stage.mesh
    );
    assert!(cells(&flat) < 0.5 * cells(&rough));
    assert!(flat.stage.mesh < rough.stage.mesh);
    // A flat sketch without detail has no curvature: it keeps the flat share of I_v (1/8 per
    // axis, 1/64 of the cells), the floor and the frustum's margins aside.
    let share = cells(&flat) / cells(&flat_v);
    assert!((share - 1.0 / 64.0).abs() < 0.3 / 64.0, "{share}");
    // The term only ever lowers importance.
    for (a, b) in [(&flat, &flat_v), (&rough, &rough_v)] {
        let (ia, ib) = (
            &a.stage.importance.importance,
            &b.stage.importance.importance,
        );
        assert!(ia.iter().zip(ib).all(|(x, y)| *x <= *y * (1.0 + 1e-6)));
    }
}
