//! The importance map and the density ratio against `docs/design.md`'s definitions (Importance;
//! Density ratio).

mod common;
use common::*;

/// Straight down from 1.5 km: the region lies inside the atlas. The tests hold the map against
/// Dachsbacher & Stamminger's factors (*Rendering Procedural Terrain by Geometry Image Warping*,
/// 2004), so the geometric-error term (on by default) is off in each.
const DOWN: &str = "[sketch]\nsynthetic = \"flat\"\nsize = 129\n[camera]\nposition = [1920.0, 1920.0, 1500.0]\nlook_at = [1920.0, 1921.0, 0.0]\n";
const BASE: &str = "[sketch]\nsynthetic = \"flat\"\nsize = 129\n[camera]\nposition = [1920.0, -400.0, 600.0]\nlook_at = [1920.0, 2500.0, 100.0]\n";
const NO_ERROR: &str = "[importance]\nerror = false\n";

#[test]
fn view_importance_is_f_px_over_c_d_where_fully_in_view() {
    let r = run(&scene(&format!("{BASE}{NO_ERROR}"), manifest_dir()));
    let m = &r.stage.sketch_map;
    let imp = &r.stage.importance;
    let n = m.n;
    let c = 2.0; // warp.quad_px default
    let mut checked = 0;
    for j in 0..n {
        for i in 0..n {
            let k = j * n + i;
            if imp.frustum[k] < 1.0 {
                continue;
            }
            let p = m.texel_world(i, j).extend(m.heights[k] as f64);
            let d = (p - r.camera.eye).length().max(0.5 * m.spacing);
            let want = r.camera.f_px() / (c * d);
            let got = imp.importance[k] as f64;
            // Flat ground seen from above is front-facing: S_b = 1.
            assert!(
                (got - want).abs() <= 1e-4 * want,
                "texel ({i}, {j}): {got} vs {want}"
            );
            checked += 1;
        }
    }
    assert!(checked > 1000, "{checked}");
}

#[test]
fn factors_switch_off_and_the_floor_holds() {
    let on = run(&scene(&format!("{BASE}{NO_ERROR}"), manifest_dir()));
    let off = run(&scene(
        &format!("{DOWN}[importance]\nerror = false\nfrustum = false\nview = false\n"),
        manifest_dir(),
    ));
    // No frustum: every on-atlas texel is "in view"; no view term: one value everywhere.
    assert!(off.stage.importance.frustum.iter().all(|&f| f == 1.0));
    let first = off.stage.importance.importance[0];
    assert!(off.stage.importance.importance.iter().all(|&v| v == first));
    // With both on, texels out of view sit at the floor: 0.1 × the least visible importance.
    let imp = &on.stage.importance;
    let least_visible = imp
        .importance
        .iter()
        .zip(&imp.frustum)
        .filter(|(_, f)| **f >= 0.5)
        .map(|(v, _)| *v)
        .fold(f32::INFINITY, f32::min);
    let least = imp.importance.iter().copied().fold(f32::INFINITY, f32::min);
    assert!(
        (least - 0.1 * least_visible).abs() <= 1e-6 * least_visible,
        "{least} vs {least_visible}"
    );
}

#[test]
fn backfacing_slopes_are_reduced_but_not_below_the_floor() {
    // Behind the gaussian's peak, seen from low on one side, the far slope faces away.
    let toml = "[sketch]\nsynthetic = \"gaussian\"\n[camera]\nposition = [3840.0, 500.0, 300.0]\nlook_at = [3840.0, 7000.0, 800.0]\n";
    let with = run(&scene(toml, manifest_dir()));
    let without = run(&scene(
        &format!("{toml}[importance]\nbackface = false\n"),
        manifest_dir(),
    ));
    let (a, b) = (&with.stage.importance, &without.stage.importance);
    let ratios: Vec<f32> = a
        .importance
        .iter()
        .zip(&b.importance)
        .zip(&a.frustum)
        .filter(|(_, f)| **f >= 1.0)
        .map(|((x, y), _)| x / y)
        .collect();
    let reduced = ratios.iter().filter(|&&q| q < 0.99).count();
    assert!(reduced > 50, "only {reduced} texels reduced");
    assert!(
        ratios
            .iter()
            .all(|q| (0.15 - 1e-4..=1.0 + 1e-6).contains(q))
    );
}

#[test]
fn surface_bound_caps_importance_from_a_value_and_from_a_map() {
    let capped = run(&scene(
        &format!("{BASE}[importance]\nmax_per_m = 0.02\n"),
        manifest_dir(),
    ));
    assert!(
        capped
            .stage
            .importance
            .importance
            .iter()
            .all(|&v| v <= 0.02 * (1.0 + 1e-6))
    );
    // A map: 0.01 samples per metre on the western half, unbounded (1e6) on the eastern.
    let dir = scratch("importance-map");
    let n = 129;
    let mut text = format!("ncols {n}\nnrows {n}\nxllcorner 0\nyllcorner 0\ncellsize 30\n");
    for _ in 0..n {
        let row: Vec<&str> = (0..n)
            .map(|i| if i < 64 { "0.01" } else { "1000000" })
            .collect();
        text += &(row.join(" ") + "\n");
    }
    std::fs::write(dir.join("max.asc"), text).unwrap();
    let r = run(&scene(
        &format!("{BASE}[importance]\nmax_map = \"max.asc\"\n"),
        dir,
    ));
    let m = &r.stage.sketch_map;
    let mut west = 0;
    for j in 0..m.n {
        for i in 0..m.n {
            let x = m.texel_world(i, j).x;
            let v = r.stage.importance.importance[j * m.n + i];
            if x < 60.0 * 30.0 {
                assert!(v <= 0.01 * (1.0 + 1e-5), "({i}, {j}) at x {x}: {v}");
                west += 1;
            }
        }
    }
    assert!(west > 100);
}

#[test]
fn uniform_importance_gives_the_budget_ratio_everywhere() {
    let r = run(&scene(
        &format!(
            "{DOWN}[importance]\nerror = false\nfrustum = false\nview = false\nbackface = false\n"
        ),
        manifest_dir(),
    ));
    let n = r.stage.sketch_map.n as f64;
    // Φ is the identity; k·I·d0 = (n−1)/n, so every cell's ratio is n/(n−1).
    let mut ratios = Vec::new();
    let st = &r.stage;
    terrain_engine::stage::quality::measure(
        &st.warp.phi,
        st.sketch_map.n,
        st.sketch_map.spacing,
        &st.importance,
        &mut ratios,
    );
    let want = (n / (n - 1.0)) as f32;
    assert!(
        ratios.iter().all(|&q| (q - want).abs() < 1e-3),
        "{:?}",
        &ratios[..4]
    );
    assert_eq!(r.quality.ratio_within_0_5_2, 1.0);
    // Each cell stands for 1/ratio² demanded cells.
    let met = (n / (n - 1.0)).powi(2);
    assert!(
        (r.quality.demand_met - met).abs() < 1e-4,
        "{}",
        r.quality.demand_met
    );
}

/// The warp turns with the view: the paper's mountain looking east (the view's depth along x)
/// gets the density ratio it gets looking north, and Φ is the same grid reflected across the
/// diagonal. Rows first, as for every view before, the east view kept 74 % of its visible cells
/// within [½, 2] and 44 % within [½, 1], against 97 % and 77 % looking north.
#[test]
fn a_view_looking_east_warps_as_well_as_looking_north() {
    let view = |position: &str, look_at: &str| {
        run(&scene(
            &format!(
                "[sketch]\nsynthetic = \"gaussian\"\n[camera]\nposition = {position}\n\
                 look_at = {look_at}\n"
            ),
            manifest_dir(),
        ))
    };
    let north = view("[3840.0, 200.0, 250.0]", "[3840.0, 4000.0, 700.0]");
    let east = view("[200.0, 3840.0, 250.0]", "[4000.0, 3840.0, 700.0]");
    assert!(east.stage.warp.across && !north.stage.warp.across);
    assert_sound(&east, "looking east");
    let (a, b) = (&north.quality, &east.quality);
    assert!(
        b.ratio_within_0_5_2 > 0.95 && b.ratio_within_0_5_1 > 0.7,
        "{b:?}"
    );
    for (x, y) in [
        (a.ratio_within_0_5_2, b.ratio_within_0_5_2),
        (a.ratio_within_0_5_1, b.ratio_within_0_5_1),
    ] {
        assert!((x - y).abs() < 1e-3, "north {a:?}\neast {b:?}");
    }
    let n = north.stage.sketch_map.n;
    let tol = 1e-4 * north.stage.sketch_map.extent() as f32;
    for t in 0..n {
        for s in 0..n {
            let (p, q) = (
                east.stage.warp.phi[t * n + s],
                north.stage.warp.phi[s * n + t],
            );
            assert!(
                (p[0] - q[1]).abs() <= tol && (p[1] - q[0]).abs() <= tol,
                "Φ({s}, {t}): east {p:?}, north reflected {q:?}"
            );
        }
    }
}

/// The same mountain seen along the diagonals: the region turns 45° (`stage::sketch_map::Turn`),
/// and the warp then serves the view nearly as it serves the view looking north (demand met
/// within 0.03, the shares within 2 points), where axis-aligned it met 0.68 of the demand
/// against 0.91. Looking north-west is looking north-east mirrored, and gives the same figures.
#[test]
fn a_view_looking_north_east_warps_nearly_as_well_as_looking_north() {
    use terrain_engine::stage::Turn;
    let view = |position: &str, look_at: &str, diagonal: bool| {
        run(&scene(
            &format!(
                "[sketch]\nsynthetic = \"gaussian\"\n[camera]\nposition = {position}\n\
                 look_at = {look_at}\n[warp]\ndiagonal = {diagonal}\n"
            ),
            manifest_dir(),
        ))
    };
    let north = view("[3840.0, 200.0, 250.0]", "[3840.0, 4000.0, 700.0]", true);
    // Each 3800 m from the centre, as north's camera is.
    let (ne_eye, ne_at) = ("[1152.99, 1152.99, 250.0]", "[3953.14, 3953.14, 700.0]");
    let north_east = view(ne_eye, ne_at, true);
    let north_west = view(
        "[6527.01, 1152.99, 250.0]",
        "[3726.86, 3953.14, 700.0]",
        true,
    );
    let axis_aligned = view(ne_eye, ne_at, false);
    assert_eq!(north.stage.sketch_map.turn, Turn::None);
    assert_eq!(north_east.stage.sketch_map.turn, Turn::NorthEast);
    assert_eq!(north_west.stage.sketch_map.turn, Turn::NorthWest);
    assert_eq!(axis_aligned.stage.sketch_map.turn, Turn::None);
    for (r, name) in [(&north_east, "north-east"), (&north_west, "north-west")] {
        assert_sound(r, name);
    }
    let (a, b, c) = (&north.quality, &north_east.quality, &north_west.quality);
    assert!(
        b.ratio_within_0_5_2 > 0.95 && b.ratio_within_0_5_1 > 0.72,
        "{b:?}"
    );
    assert!(
        (a.demand_met - b.demand_met).abs() < 0.03,
        "north {a:?}\nnorth-east {b:?}"
    );
    for (x, y) in [
        (a.ratio_within_0_5_2, b.ratio_within_0_5_2),
        (a.ratio_within_0_5_1, b.ratio_within_0_5_1),
    ] {
        assert!((x - y).abs() < 0.02, "north {a:?}\nnorth-east {b:?}");
    }
    for (x, y) in [
        (b.demand_met, c.demand_met),
        (b.ratio_within_0_5_2, c.ratio_within_0_5_2),
        (b.ratio_within_0_5_1, c.ratio_within_0_5_1),
    ] {
        assert!((x - y).abs() < 1e-3, "north-east {b:?}\nnorth-west {c:?}");
    }
    let d = &axis_aligned.quality;
    assert!(
        d.demand_met < b.demand_met - 0.15,
        "axis-aligned {d:?}\nturned {b:?}"
    );
}
