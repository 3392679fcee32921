//! GeoMipMapping on the CPU: level choice, τ, shared edges, geomorphing (no GPU needed; the grid
//! is the sketch sampled on the CPU, which is all these properties depend on).

use glam::{DVec2, DVec3, DVec4};
use proptest::prelude::*;
use terrain_engine::Camera;
use terrain_engine::geomipmap::{
    Blocks, Grid, LodParams, Selection, Templates, choose_level, morphed_height,
};
use terrain_engine::gpu::uniforms::view_proj;
use terrain_engine::sketch::{Atlas, LoadOptions};

/// Cells per block side in these tests (the default).
const BLOCK: usize = terrain_engine::geomipmap::DEFAULT_CELLS;

/// A `blocks`² grid over a synthetic sketch at spacing `spacing`, with noise octaves down to the
/// grid's spacing as a baked grid has them (without them every other vertex would lie on its
/// neighbours' line, and no level would differ).
fn grid(name: &str, blocks: usize, spacing: f64) -> Grid {
    let atlas = Atlas::synthetic(name, 257, &LoadOptions::default()).unwrap();
    let detail = terrain_engine::Detail {
        octaves: 6,
        amplitude_m: 12.0,
        gain: 0.5,
        seed: 3,
        bias: 0.0,
        d_atlas: atlas.d_atlas(),
        lattice_origin_m: DVec2::ZERO,
    };
    let o = (atlas.d_atlas() / spacing).log2() as f32;
    let n = BLOCK * blocks + 1;
    let heights = (0..n * n)
        .map(|v| {
            let p = DVec2::new((v % n) as f64, (v / n) as f64) * spacing;
            atlas.sample_texel(p.x / atlas.dx, p.y / atlas.dy, 0.0) + detail.height_world(p, o, o).0
        })
        .collect();
    Grid {
        n,
        cells: BLOCK,
        spacing,
        origin: DVec2::ZERO,
        heights,
    }
}

fn camera(eye: [f64; 3], at: [f64; 3]) -> Camera {
    Camera::new(DVec3::from(eye), DVec3::from(at), 60.0, 512, 512, 20_000.0).unwrap()
}

/// Pixel position of a world point, or `None` behind the camera.
fn project(cam: &Camera, p: DVec3) -> Option<DVec2> {
    let origin = cam.eye.truncate();
    let c = view_proj(cam, origin) * DVec4::from((p - origin.extend(0.0), 1.0));
    (c.w > 1e-6).then(|| {
        DVec2::new(c.x / c.w, c.y / c.w) * DVec2::new(cam.width as f64, cam.height as f64) * 0.5
    })
}

/// Like [`project`], but only for points inside the image.
fn on_screen(cam: &Camera, p: DVec3) -> Option<DVec2> {
    let half = DVec2::new(cam.width as f64, cam.height as f64) * 0.5;
    project(cam, p).filter(|s| s.x.abs() <= half.x && s.y.abs() <= half.y)
}

proptest! {
    #[test]
    fn level_choice_is_monotone_in_distance(block in 0usize..64, d1 in 1.0f64..20_000.0, factor in 1.0f64..10.0, tau in 0.25f64..16.0) {
        let g = grid("ridges", 8, 30.0);
        let blocks = Blocks::new(&g);
        let near = choose_level(&blocks, block, d1, 443.0, tau);
        let far = choose_level(&blocks, block, d1 * factor, 443.0, tau);
        prop_assert!(near <= far, "block {} level {} at {} but {} at {}", block, near, d1, far, d1 * factor);
    }
}

/// The largest projected error of the chosen levels: each vertex against the level's surface
/// under it, both projected exactly.
fn worst_projected_error(g: &Grid, blocks: &Blocks, sel: &Selection, cam: &Camera) -> f64 {
    let mut worst = 0.0f64;
    for &k in &sel.visible {
        let l = sel.level[k] as usize;
        let (bx, by) = ((k % blocks.per_side) * BLOCK, (k / blocks.per_side) * BLOCK);
        for j in by..=by + BLOCK {
            for i in bx..=bx + BLOCK {
                let fine = g.world(i, j);
                let coarse = fine.truncate().extend(g.level_height(i, j, l) as f64);
                if let (Some(a), Some(b)) = (project(cam, fine), project(cam, coarse)) {
                    worst = worst.max((a - b).length());
                }
            }
        }
    }
    worst
}

#[test]
fn tau_is_honoured_with_exact_projection() {
    let g = grid("ridges", 8, 15.0);
    let blocks = Blocks::new(&g);
    let mut sel = Selection::default();
    let views = [
        ([1920.0, -300.0, 700.0], [1920.0, 3000.0, 200.0]),
        ([1000.0, 1000.0, 2500.0], [1900.0, 1900.0, 0.0]),
    ];
    for (eye, at) in views {
        let cam = camera(eye, at);
        for tau in [0.5, 2.0, 8.0] {
            let exact = LodParams {
                tau,
                exact: true,
                morph: false,
                reach_m: 0.0,
            };
            sel.select(&g, &blocks, &cam, &exact);
            assert!(!sel.visible.is_empty());
            let worst = worst_projected_error(&g, &blocks, &sel, &cam);
            assert!(
                worst <= tau * (1.0 + 1e-6),
                "τ {tau}: a chosen level shows {worst:.2} px of error"
            );
            if tau >= 8.0 {
                assert!(
                    sel.visible.iter().any(|&k| sel.level[k] > 0),
                    "τ {tau}: every block at level 0"
                );
            }
            // De Boer's distance-based choice is a simplification: report what it allows.
            let de_boer = LodParams {
                exact: false,
                ..exact
            };
            sel.select(&g, &blocks, &cam, &de_boer);
            let approx = worst_projected_error(&g, &blocks, &sel, &cam);
            eprintln!(
                "view {eye:?}, τ {tau}: largest error {worst:.2} px exact, {approx:.2} px de Boer"
            );
        }
    }
}

/// The block-local vertices a block's triangles use on one side (S, E, N, W) as global (i, j).
fn edge_vertices(
    t: &Templates,
    g: &terrain_engine::geomipmap::BlockGpu,
    side: usize,
) -> Vec<(usize, usize)> {
    let mut idx = Vec::new();
    t.append(std::slice::from_ref(g), &mut idx);
    let mut v: Vec<(usize, usize)> = idx
        .iter()
        .map(|&v| ((v as usize) % (BLOCK + 1), (v as usize) / (BLOCK + 1)))
        .filter(|&(i, j)| match side {
            0 => j == 0,
            1 => i == BLOCK,
            2 => j == BLOCK,
            _ => i == 0,
        })
        .map(|(i, j)| (g.origin[0] as usize + i, g.origin[1] as usize + j))
        .collect();
    v.sort_unstable();
    v.dedup();
    v
}

#[test]
fn shared_edges_use_the_same_vertices_at_the_same_heights() {
    let g = grid("ridges", 8, 15.0);
    let blocks = Blocks::new(&g);
    let t = Templates::new(&g);
    let mut sel = Selection::default();
    let cam = camera([1920.0, -200.0, 500.0], [1920.0, 3000.0, 150.0]);
    let lod = LodParams {
        tau: 4.0,
        exact: false,
        morph: true,
        reach_m: 0.0,
    };
    sel.select(&g, &blocks, &cam, &lod);
    // Force neighbours 1, 2 and 3 levels apart as well as what the camera chose.
    let mut patterns = vec![sel.level.clone()];
    for d in 1..=3u8 {
        patterns.push(
            (0..blocks.per_side.pow(2))
                .map(|k| if (k % 8 + k / 8) % 2 == 0 { 1 } else { 1 + d })
                .collect(),
        );
    }
    let mut checked = 0;
    for levels in patterns {
        sel.level = levels;
        sel.visible = (0..blocks.per_side.pow(2))
            .filter(|&k| sel.level[k] != u8::MAX)
            .collect();
        sel.fill_gpu(&blocks, cam.f_px(), &lod);
        let slot: std::collections::HashMap<usize, usize> = sel
            .visible
            .iter()
            .enumerate()
            .map(|(s, &k)| (k, s))
            .collect();
        for (s, &k) in sel.visible.iter().enumerate() {
            let (bx, by) = (k % 8, k / 8);
            for (side, other, opposite) in [
                (1usize, (bx + 1 < 8).then(|| k + 1), 3usize),
                (2, (by + 1 < 8).then(|| k + 8), 0),
            ] {
                let Some(&o) = other.and_then(|n| slot.get(&n)) else {
                    continue;
                };
                let (a, b) = (&sel.gpu[s], &sel.gpu[o]);
                let ea = edge_vertices(&t, a, side);
                let eb = edge_vertices(&t, b, opposite);
                assert_eq!(
                    ea, eb,
                    "blocks {k} (level {}) and {} (level {}) disagree on their edge's vertices",
                    a.level, sel.visible[o], b.level
                );
                for &(gi, gj) in &ea {
                    let local = |g: &terrain_engine::geomipmap::BlockGpu| {
                        (gi - g.origin[0] as usize, gj - g.origin[1] as usize)
                    };
                    let (ia, ja) = local(a);
                    let (ib, jb) = local(b);
                    let (za, _) = morphed_height(&g, a, ia, ja, cam.eye);
                    let (zb, _) = morphed_height(&g, b, ib, jb, cam.eye);
                    assert_eq!(
                        za, zb,
                        "vertex ({gi}, {gj}) at {za} in one block, {zb} in the other"
                    );
                    checked += 1;
                }
            }
        }
    }
    assert!(checked > 1000, "{checked}");
}

/// The drawn surface's height at vertex (i, j) of a block: morphed where the level draws it, else
/// interpolated inside its level cell from the morphed corners. `None` for cells on the block's
/// edge ring, which the stitching strips draw differently.
fn surface(
    g: &Grid,
    b: &terrain_engine::geomipmap::BlockGpu,
    i: usize,
    j: usize,
    eye: DVec3,
) -> Option<f32> {
    let s = 1usize << b.level;
    let (ci, cj) = ((i / s) * s, (j / s) * s);
    if ci == 0 || cj == 0 || ci + s >= BLOCK || cj + s >= BLOCK {
        return None;
    }
    let z = |a: usize, c: usize| morphed_height(g, b, a, c, eye).0;
    let (fx, fy) = ((i - ci) as f32 / s as f32, (j - cj) as f32 / s as f32);
    if fx == 0.0 && fy == 0.0 {
        return Some(z(i, j));
    }
    let (z00, z11) = (z(ci, cj), z(ci + s, cj + s));
    Some(if fx >= fy {
        let z10 = z(ci + s, cj);
        z00 + fx * (z10 - z00) + fy * (z11 - z10)
    } else {
        let z01 = z(ci, cj + s);
        z00 + fy * (z01 - z00) + fx * (z11 - z01)
    })
}

/// Largest screen jump of the surface between consecutive frames along a 60-step path of 10 m,
/// at every vertex inside the edge ring of blocks drawn in both frames and on screen, projected
/// with the later camera (the geometry's change, not the camera's motion). τ = 8 px, so that a
/// level switch without morphing shows.
fn largest_jump(morph: bool) -> f64 {
    let g = grid("ridges", 8, 15.0);
    let blocks = Blocks::new(&g);
    let lod = LodParams {
        tau: 8.0,
        exact: false,
        morph,
        reach_m: 0.0,
    };
    let mut prev: Option<(Selection, Camera)> = None;
    let mut worst = 0.0f64;
    for step in 0..60 {
        let y = -800.0 + 10.0 * step as f64;
        let cam = camera([1920.0, y, 600.0], [1920.0, y + 3000.0, 100.0]);
        let mut sel = Selection::default();
        sel.select(&g, &blocks, &cam, &lod);
        if let Some((p, pcam)) = &prev {
            for (s, &k) in sel.visible.iter().enumerate() {
                let Some(ps) = p.visible.iter().position(|&q| q == k) else {
                    continue;
                };
                let (bx, by) = ((k % 8) * BLOCK, (k / 8) * BLOCK);
                for j in 1..BLOCK {
                    for i in 1..BLOCK {
                        let (Some(before), Some(after)) = (
                            surface(&g, &p.gpu[ps], i, j, pcam.eye),
                            surface(&g, &sel.gpu[s], i, j, cam.eye),
                        ) else {
                            continue;
                        };
                        let xy = g.world(bx + i, by + j).truncate();
                        let (a, b) = (
                            on_screen(&cam, xy.extend(before as f64)),
                            on_screen(&cam, xy.extend(after as f64)),
                        );
                        if let (Some(a), Some(b)) = (a, b) {
                            worst = worst.max((a - b).length());
                        }
                    }
                }
            }
        }
        prev = Some((sel, cam));
    }
    worst
}

#[test]
fn geomorphing_turns_pops_into_sub_pixel_steps() {
    let with = largest_jump(true);
    let without = largest_jump(false);
    eprintln!("largest jump between frames: {with:.2} px with morphing, {without:.2} px without");
    assert!(with < 1.0, "{with} px with morphing");
    assert!(
        without > 3.0,
        "{without} px without morphing: the path shows no popping to remove"
    );
}
