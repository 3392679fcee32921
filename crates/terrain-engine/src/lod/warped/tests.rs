//! The warped mode's passes against their CPU twins: warp & zoom, mesh split and normals, on the
//! machine's adapter (lavapipe or llvmpipe without a GPU).

use glam::IVec2;
use std::path::Path;
use terrain_engine::gpu::warp_zoom::{centre_cpu, sketch_rect, vertex_cpu};
use terrain_engine::lod::warped::mesh_split::split_cpu;
use terrain_engine::scene::{Mode, Scene};
use terrain_engine::{Frame, Renderer, View, Warped};

fn bundled(name: &str, size: u32, mesh: u32) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../sketches")
        .join(format!("{name}.toml"));
    let mut s = Scene::load(&path).unwrap();
    s.camera.width = size;
    s.camera.height = size;
    s.warp.mesh = mesh;
    s
}

/// The warped scheme inside a renderer built in warped mode.
fn warped(r: &Renderer) -> &Warped {
    r.lod::<Warped>().expect("warped mode")
}

fn render(scene: &Scene, view: View) -> (Renderer, Frame) {
    let mut r = Renderer::new(scene, Mode::Warped, view).expect("renderer");
    let camera = terrain_engine::scene::camera_of(scene, &r.atlas).unwrap();
    let frame = r.render(&camera).expect("frame");
    (r, frame)
}

#[test]
fn gpu_warp_and_zoom_matches_its_cpu_twin() {
    for (name, budget) in [
        ("jacksboro", false),
        ("gaussian-high", false),
        ("hills", true),
        // Its region reaches past the sketch: vertices on the edge (`drawn_xy`).
        ("hills-high", false),
    ] {
        // The full 512² mesh, and one frame at the mesh its budget chose.
        let mut scene = bundled(name, 64, 512);
        scene.warp.budget = budget;
        // The normals pass runs only for shading with the mesh's normals.
        scene.render.pixel_normals = false;
        let (r, _) = render(&scene, View::Shaded);
        let camera = terrain_engine::scene::camera_of(&scene, &r.atlas).unwrap();
        let uniforms = r.uniforms(&camera);
        let gpu = warped(&r).read_detailed(&r.ctx).unwrap();
        let range = (r.atlas.max_m - r.atlas.min_m) as f64;
        let m = uniforms.mesh.mesh as i32;
        assert_eq!(m < 512, budget, "{name}: mesh {m}");
        let (mut worst_z, mut worst_xy, mut checked) = (0.0f64, 0.0f64, 0);
        let (lo, hi) = sketch_rect(&uniforms);
        let mut on_edge = 0;
        for j in (0..m).step_by(7).chain([m - 1]) {
            for i in (0..m).step_by(7).chain([m - 1]) {
                let cpu = vertex_cpu(
                    &uniforms,
                    &warped(&r).stage.warp.phi,
                    &r.atlas,
                    true,
                    IVec2::new(i, j),
                );
                let g = gpu[(j * m + i) as usize];
                worst_z = worst_z.max((g[2] - cpu[2]).abs() as f64);
                // Φ interpolates coordinates as large as the region: f32 rounding (fused or not)
                // scales with the region's extent.
                let extent = warped(&r).stage.sketch_map.extent();
                worst_xy =
                    worst_xy.max((g[0] - cpu[0]).abs().max((g[1] - cpu[1]).abs()) as f64 / extent);
                // The split octave is log2 of d_atlas / d_max: the rounding of Φ above, a few
                // ulps of the region's extent, moves it by that over d_max (where the warp
                // crowds vertices a metre apart, a region 25 km wide: a few thousandths). Where
                // the split octave stops at the pixel octave, d_max below is the spacing it stands
                // for, larger than the mesh's: the allowance is then smaller, not larger.
                let d_max = r.atlas.d_atlas() * (-(cpu[3] as f64 + r.detail.bias)).exp2();
                let allowed = 1e-3 + 8.0 * f32::EPSILON as f64 * extent / (d_max * 2f64.ln());
                assert!(
                    ((g[3] - cpu[3]).abs() as f64) < allowed,
                    "{name} ({i}, {j}): split octave {} vs {} (allowed {allowed})",
                    g[3],
                    cpu[3]
                );
                checked += 1;
                let p = glam::Vec2::new(cpu[0], cpu[1]);
                on_edge += usize::from(p.cmpeq(lo).any() || p.cmpeq(hi).any());
            }
        }
        if name == "hills-high" {
            assert!(
                on_edge > 0,
                "{name}: no vertex checked lies on the sketch's edge"
            );
        }
        // The centres against their twin, and the mesh split against its twin fed the GPU's
        // own vertices and centres.
        let centres = warped(&r)
            .read_centres(&r.ctx)
            .unwrap()
            .expect("an adaptive triangulation");
        let mut worst_c = 0.0f64;
        for j in (0..m - 1).step_by(7) {
            for i in (0..m - 1).step_by(7) {
                let cpu = centre_cpu(
                    &uniforms,
                    &warped(&r).stage.warp.phi,
                    &r.atlas,
                    true,
                    IVec2::new(i, j),
                );
                worst_c = worst_c.max((centres[(j * m + i) as usize] - cpu).abs() as f64);
            }
        }
        assert!(
            worst_c <= 1e-4 * range,
            "{name}: centres differ by {worst_c} m"
        );
        let indices = warped(&r).read_indices(&r.ctx).unwrap();
        let (mut across, mut ties) = (0, 0);
        for t in 0..m as u32 - 1 {
            for s in 0..m as u32 - 1 {
                let at = 6 * (t * (m as u32 - 1) + s) as usize;
                let cpu = split_cpu(&gpu, &centres, m as u32, s, t);
                let got = &indices[at..at + 6];
                across += (cpu[2] != cpu[0] + m as u32 + 1) as usize;
                if got != cpu {
                    // The heights' midpoints are exact (a sum, then a half), so both sides
                    // compare the same numbers; the GPU may fuse the other diagonal's cross
                    // products, so only a cell whose b–d triangles are within rounding of
                    // degenerate may go the other way.
                    let v = |k: u32| glam::Vec2::new(gpu[k as usize][0], gpu[k as usize][1]);
                    let (a, c) = (t * m as u32 + s, (t + 1) * m as u32 + s + 1);
                    let (b, d) = (a + 1, c - 1);
                    let slack = |p: glam::Vec2, q: glam::Vec2, r: glam::Vec2| {
                        let (u, w) = (q - p, r - p);
                        (u.perp_dot(w)).abs() <= 1e-5 * u.length() * w.length()
                    };
                    assert!(
                        slack(v(a), v(b), v(d)) || slack(v(b), v(c), v(d)),
                        "{name} cell ({s}, {t}): {got:?} against {cpu:?}"
                    );
                    ties += 1;
                }
            }
        }
        let cells = (m as usize - 1).pow(2);
        // Measured: about half the cells take the other diagonal (49–53 % on these three).
        assert!(
            across > cells / 10 && across < cells * 9 / 10,
            "{name}: {across} of {cells} cells split across"
        );
        assert!(
            ties * 1000 <= cells,
            "{name}: {ties} degenerate cells split apart"
        );
        // The normals pass against its twin, fed the GPU's own vertices.
        let normals = warped(&r)
            .read_normals(&r.ctx)
            .unwrap()
            .expect("lit by the mesh's normals");
        let mut worst_n = 0.0f32;
        for j in (0..m).step_by(7) {
            for i in (0..m).step_by(7) {
                let cpu =
                    terrain_engine::gpu::normals::normal_cpu(&gpu, m as u32, IVec2::new(i, j));
                let g = normals[(j * m + i) as usize];
                worst_n = worst_n.max((0..3).map(|c| (g[c] - cpu[c]).abs()).fold(0.0, f32::max));
            }
        }
        assert!(worst_n < 1e-4, "{name}: normals differ by {worst_n}");
        eprintln!(
            "{name}: {checked} vertices, worst height difference {worst_z:.2e} m = {:.2e} of the range; centres {worst_c:.2e} m; normals {worst_n:.1e}; {across} of {cells} cells split across, {ties} degenerate ones apart",
            worst_z / range
        );
        assert!(
            worst_z <= 1e-4 * range,
            "{name}: heights differ by {worst_z} m"
        );
        assert!(
            worst_xy <= 1e-6,
            "{name}: positions differ by {worst_xy} of the region"
        );
    }
}
