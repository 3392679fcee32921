//! The warped-mode renderer on the machine's adapter (llvmpipe without a GPU): snapshots against committed references, a scene
//! moved 4,000 km, determinism, and extreme cameras.
//!
//! Snapshot metric: PSNR over RGB ≥ 40 dB against `tests/snapshots/<name>.png`, made on llvmpipe,
//! which renders them bit-identically run to run. Measured against the jacksboro reference, small
//! mistakes fall well below: no detail 24.9 dB, fov 58° instead of 60° 26.9 dB, another noise seed
//! 22.4 dB. Bump detail off reads 40.2 dB there (the bump fade leaves little of the bump on its
//! grazing ground) and 37.2 dB against hills'; the fade itself, off, 44.5 dB against jacksboro's,
//! so `the_bump_fades_where_the_mesh_cannot_hold_its_place` holds it. A GPU rounds differently
//! from llvmpipe and may need its own
//! references (`UPDATE_SNAPSHOTS=1`). On failure
//! the actual image and a ×4 difference image are written to `target/test-scratch/snapshots/`.
//! `UPDATE_SNAPSHOTS=1 cargo test --release --test gpu` rewrites the references.

mod common;
use common::*;
use terrain_engine::Renderer;
use terrain_engine::View;
use terrain_engine::Warped;
use terrain_engine::scene::Scene;
use terrain_engine::scene::{Mode, Msaa};

fn bundled(name: &str, size: u32, mesh: u32) -> Scene {
    let path = manifest_dir().join("sketches").join(format!("{name}.toml"));
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

fn render(scene: &Scene, view: View) -> (Renderer, terrain_engine::Frame) {
    let mut r = Renderer::new(scene, Mode::Warped, view).expect("renderer");
    let camera = terrain_engine::scene::camera_of(scene, &r.atlas).unwrap();
    let frame = r.render(&camera).expect("frame");
    (r, frame)
}

/// A shaded frame of `s` in `mode` from its own camera: its pixels (RGBA).
fn shot(s: &Scene, mode: Mode) -> Vec<u8> {
    let mut r = Renderer::new(s, mode, View::Shaded).unwrap();
    let camera = terrain_engine::scene::camera_of(s, &r.atlas).unwrap();
    r.render(&camera).unwrap().rgba
}

/// A frame of `scene` in `mode` with its pixels' world positions (x, y, z, 1 on ground / 0 on
/// sky, f64, row-major), and the renderer that drew it.
fn render_with_positions(scene: &Scene, mode: Mode) -> (Renderer, Vec<u8>, Vec<f64>) {
    let mut r = Renderer::new(scene, mode, View::Shaded).expect("renderer");
    let camera = terrain_engine::scene::camera_of(scene, &r.atlas).unwrap();
    let frame = r.render(&camera).expect("frame");
    let world = terrain_engine::world_positions(&r.read_positions(&camera).unwrap(), &camera);
    (r, frame.rgba, world)
}

#[test]
fn snapshots_match_their_references() {
    let dir = manifest_dir().join("tests").join("snapshots");
    let out = scratch("snapshots");
    let update = std::env::var_os("UPDATE_SNAPSHOTS").is_some();
    for name in ["jacksboro", "gaussian-high", "hills"] {
        let (_, frame) = render(&bundled(name, 192, 256), View::Shaded);
        let reference = dir.join(format!("{name}.png"));
        if update {
            std::fs::create_dir_all(&dir).unwrap();
            terrain_cli::output::write_image(&reference, frame.width, frame.height, &frame.rgba)
                .unwrap();
            continue;
        }
        let (w, h, expected) = read_png(&reference).unwrap_or_else(|| {
            panic!(
                "{}: missing; run with UPDATE_SNAPSHOTS=1",
                reference.display()
            )
        });
        assert_eq!((w, h), (frame.width, frame.height), "{name}: size");
        let db = psnr(&frame.rgba, &expected);
        eprintln!("{name}: {db:.1} dB");
        if db < 40.0 {
            let actual = out.join(format!("{name}.png"));
            terrain_cli::output::write_image(&actual, w, h, &frame.rgba).unwrap();
            terrain_cli::output::write_image(
                &out.join(format!("{name}-diff.png")),
                w,
                h,
                &difference(&frame.rgba, &expected),
            )
            .unwrap();
            panic!(
                "{name}: {db:.1} dB < 40 dB against {}; actual and difference in {}",
                reference.display(),
                out.display()
            );
        }
    }
}

#[test]
fn a_scene_moved_4000_km_renders_the_same() {
    let near = bundled("hills", 160, 256);
    let mut far = near.clone();
    let off = 4_000_000.0;
    far.sketch.origin_m = Some([off, off]);
    let shift = glam::DVec3::new(off, off, 0.0);
    let (eye, target) = (far.camera.eye(), far.camera.target());
    far.camera.aim(eye + shift, target + shift);
    let (_, a) = render(&near, View::Shaded);
    let (_, b) = render(&far, View::Shaded);
    let db = psnr(&a.rgba, &b.rgba);
    eprintln!("moved 4000 km: {db:.1} dB");
    assert!(db >= 40.0, "{db:.1} dB");
}

#[test]
fn two_renders_are_identical() {
    let scene = bundled("gaussian", 128, 256);
    let (mut r, a) = render(&scene, View::Shaded);
    let camera = terrain_engine::scene::camera_of(&scene, &r.atlas).unwrap();
    let b = r.render(&camera).unwrap();
    assert!(a.rgba == b.rgba, "PSNR {:.1} dB", psnr(&a.rgba, &b.rgba));
}

#[test]
fn extreme_cameras_render_without_holes() {
    let cases = [
        (
            "cliff",
            "[sketch]\nsynthetic = \"cliff\"\n[camera]\nposition = [3841.0, 3000.0, 501.0]\nlook_at = [1841.0, 4000.0, 100.0]\n",
        ),
        (
            "down",
            "[sketch]\nsynthetic = \"hills\"\n[camera]\nposition = [3840.0, 3840.0, 3000.0]\nlook_at = [3840.0, 3840.0, 0.0]\n",
        ),
        (
            "high",
            "[sketch]\nsynthetic = \"hills\"\n[camera]\nposition = [3840.0, 3000.0, 50000.0]\nlook_at = [3840.0, 3100.0, 0.0]\n",
        ),
        (
            "sky",
            "[sketch]\nsynthetic = \"hills\"\n[camera]\nposition = [3000.0, 3000.0, 2000.0]\nlook_at = [3000.0, 3100.0, 5000.0]\n",
        ),
    ];
    for (name, toml) in cases {
        let scene = scene(
            &format!("{toml}width = 128\nheight = 128\n[warp]\nmesh = 256\n"),
            manifest_dir(),
        );
        let (r, frame) = render(&scene, View::Shaded);
        let detailed = warped(&r).read_detailed(&r.ctx).unwrap();
        if name == "sky" {
            assert_eq!(frame.gpu.triangles, 0, "sky view drew terrain");
            assert_eq!(frame.gpu.passes.get("warp_zoom").unwrap_or(0.0), 0.0);
            if r.ctx.timestamps {
                // The sky pass still ran and was timed from its own pair of timestamps.
                assert!(
                    frame.gpu.passes.get("terrain").is_some_and(|ms| ms > 0.0),
                    "{:?}",
                    frame.gpu.passes
                );
            }
            continue;
        }
        assert!(
            detailed.iter().all(|v| v.iter().all(|c| c.is_finite())),
            "{name}: non-finite vertex"
        );
        assert!(frame.gpu.triangles > 0);
        if name == "down" {
            // Straight down from 3 km the 7.7 km sketch fills the view: no sky may show through.
            let sky = frame
                .rgba
                .chunks_exact(4)
                .filter(|p| p[2] > p[1] + 25 && p[2] > 150)
                .count();
            assert_eq!(sky, 0, "{name}: {sky} sky pixels inside the terrain");
        }
    }
}

/// Deferred shading (`render.deferred`, single-sampled frames) shades each pixel from the
/// G-buffer with the values a forward frame interpolates, so it draws the same bytes: the picture,
/// the positions, the sky where no ground is, and the wireframe's lines (found where the mesh is
/// rasterised). A field packed into the wrong place, or the sky drawn over the ground, breaks it.
/// Single-sampled by the scene, as a hardware GPU would multisample by default and draw both
/// forward; an adapter that cannot draw the G-buffer fails the test rather than pass it forward.
#[test]
fn deferred_shading_draws_what_forward_draws() {
    for (name, mode, view) in [
        ("jacksboro", Mode::Warped, View::Shaded),
        ("hills-high", Mode::Geomipmap, View::Shaded),
        ("gaussian", Mode::Warped, View::Wireframe),
        ("jacksboro", Mode::Warped, View::Importance),
    ] {
        let frame = |deferred: bool| {
            let mut scene = bundled(name, 64, 128);
            scene.render.mode = mode;
            scene.render.deferred = deferred;
            scene.render.msaa = Msaa::Off;
            let mut r = Renderer::new(&scene, mode, view).expect("renderer");
            assert_eq!(r.deferred, deferred, "{name}: shaded deferred as asked");
            let camera = terrain_engine::scene::camera_of(&scene, &r.atlas).unwrap();
            let rgba = r.render(&camera).expect("frame").rgba;
            (rgba, r.read_positions(&camera).unwrap())
        };
        let (forward, deferred) = (frame(false), frame(true));
        let sky = forward.1.iter().filter(|p| p[3] == 0.0).count();
        assert!(
            sky > 0 && sky < forward.1.len(),
            "{name}: sky and ground in view"
        );
        assert!(
            forward.0 == deferred.0,
            "{name} {mode:?} {view:?}: the pictures differ"
        );
        assert!(
            forward.1 == deferred.1,
            "{name} {mode:?} {view:?}: the positions differ"
        );
    }
}

#[test]
fn every_debug_view_renders() {
    let scene = bundled("hills", 64, 128);
    let mut last: Option<Vec<u8>> = None;
    for view in [
        View::Shaded,
        View::Wireframe,
        View::SplitOctave,
        View::Importance,
        View::Normals,
    ] {
        let (_, frame) = render(&scene, view);
        assert_eq!(frame.rgba.len(), 64 * 64 * 4);
        if let Some(prev) = &last {
            assert!(
                prev != &frame.rgba,
                "{view:?} looks like the view before it"
            );
        }
        last = Some(frame.rgba);
    }
}

/// GPU memory is what the renderer holds: growing the mesh from 64² to 128² adds exactly the
/// larger detailed geometry image and normals (16 bytes a vertex each), cell centres (4 bytes a
/// vertex) and quad indices (6 per cell, 4 bytes each), and a renderer's bytes are returned when
/// it is dropped.
#[test]
fn gpu_memory_is_counted_from_the_allocations() {
    let small = Renderer::new(&bundled("hills", 64, 64), Mode::Warped, View::Shaded).unwrap();
    let large = Renderer::new(&bundled("hills", 64, 128), Mode::Warped, View::Shaded).unwrap();
    let per_mesh = |m: u64| 2 * m * m * 16 + m * m * 4 + (m - 1) * (m - 1) * 6 * 4;
    assert_eq!(
        large.gpu_bytes() - small.gpu_bytes(),
        per_mesh(128) - per_mesh(64)
    );
    // At least the 64×64 colour and depth targets and the colour's read-back.
    assert!(small.gpu_bytes() > 3 * 64 * 64 * 4, "{}", small.gpu_bytes());
    // The importance view adds its n² f32 map, and nothing else.
    let importance =
        Renderer::new(&bundled("hills", 64, 64), Mode::Warped, View::Importance).unwrap();
    let n = bundled("hills", 64, 64).warp.size as u64;
    assert_eq!(importance.gpu_bytes() - small.gpu_bytes(), n * n * 4);
    // Lit per pixel, the mesh has no normals: the 64² of them (16 bytes each) are never made,
    // nor the normals pass's timer slots (two 8-byte queries, 16 bytes each to resolve and read),
    // nor its counter slots (three queries of four u64, 256 bytes each to resolve and read).
    let mut lit = bundled("hills", 64, 64);
    lit.render.pixel_normals = true;
    let lit = Renderer::new(&lit, Mode::Warped, View::Shaded).unwrap();
    let timer = if small.ctx.timestamps {
        2 * 8 + 16 + 16
    } else {
        0
    };
    let counting = small.ctx.device.features();
    let counters = if counting.contains(wgpu::Features::PIPELINE_STATISTICS_QUERY) {
        3 * (4 * 8 + 2 * 256)
    } else {
        0
    };
    assert_eq!(
        small.gpu_bytes() - lit.gpu_bytes(),
        64 * 64 * 16 + timer + counters
    );
}

/// Where the mesh samples the sketch at twice its cells or coarser its facets would point-sample
/// the sketch's relief, so the mesh modes shade there with the terrain function's normal, as
/// `render.pixel_normals` does everywhere: a 16² mesh of the hills draws the same image either
/// way. A 256² mesh samples the sketch finer than its cells near the camera and keeps its own
/// normals there, so its two images differ. With pixel normals the light comes from the terrain
/// function, not the mesh: the coarse and the fine mesh differ only where the surface's position
/// does.
#[test]
fn a_mesh_coarser_than_the_sketch_shades_with_the_terrain_function() {
    let image = |mesh: u32, pixel_normals: bool| {
        let mut s = bundled("hills", 96, mesh);
        s.warp.budget = false;
        s.detail.octaves = Some(0);
        s.render.pixel_normals = pixel_normals;
        // Shadows fall where each mesh puts the surface, whichever normals light it.
        s.render.shadows = false;
        render(&s, View::Shaded).1.rgba
    };
    assert!(
        image(16, false) == image(16, true),
        "the coarse mesh kept its facets' normals"
    );
    let fine = psnr(&image(256, false), &image(256, true));
    eprintln!("mesh 256², its own normals against pixel normals: {fine:.1} dB");
    assert!(
        fine.is_finite(),
        "the fine mesh took pixel normals everywhere"
    );
    let positions = psnr(&image(16, true), &image(256, true));
    eprintln!("pixel normals, mesh 16² against 256²: {positions:.1} dB");
    assert!(positions > 25.0, "{positions:.1} dB");
}

/// A low sun from the east behind the synthetic cliff (a 400 m step at x = 3840 m) shadows the
/// plain at its foot, 400 m / tan 10° = 2.3 km of it, in the mesh modes and the reference alike,
/// and leaves the plain beyond the shadow as it was; `render.shadows = false` lights it all.
#[test]
fn a_low_sun_behind_a_cliff_shadows_the_plain_at_its_foot() {
    let scene = |shadows: bool| {
        let mut s = common::scene(
            "[sketch]\nsynthetic = \"cliff\"\n\n[camera]\nposition = [2000.0, 3840.0, 9000.0]\n\
             look_at = [2000.0, 3841.0, 0.0]\nfov_y_deg = 60.0\nwidth = 128\nheight = 128\n\n\
             [detail]\noctaves = 0\n\n[light]\nsun_azimuth_deg = 90.0\nsun_elevation_deg = 10.0\n",
            manifest_dir(),
        );
        s.render.shadows = shadows;
        s
    };
    // Mean linear luminance of the pixels whose ground lies between x0 and x1 (metres).
    let band = |rgba: &[u8], positions: &[f64], x0: f64, x1: f64| {
        let ground = positions
            .chunks_exact(4)
            .map(|q| q[3] > 0.5 && (x0..x1).contains(&q[0]));
        terrain_cli::eval::metrics::terrain_luminance(rgba, ground)
            .expect("ground in the band")
            .0
    };
    for mode in [Mode::Warped, Mode::Geomipmap, Mode::Reference] {
        let shot = |shadows: bool| {
            let (_, rgba, world) = render_with_positions(&scene(shadows), mode);
            (rgba, world)
        };
        let (lit_rgba, lit_pos) = shot(false);
        let (shaded_rgba, shaded_pos) = shot(true);
        let foot = (1900.0, 3600.0);
        let beyond = (300.0, 1300.0);
        let (foot_lit, foot_shaded) = (
            band(&lit_rgba, &lit_pos, foot.0, foot.1),
            band(&shaded_rgba, &shaded_pos, foot.0, foot.1),
        );
        let (beyond_lit, beyond_shaded) = (
            band(&lit_rgba, &lit_pos, beyond.0, beyond.1),
            band(&shaded_rgba, &shaded_pos, beyond.0, beyond.1),
        );
        eprintln!(
            "{mode:?}: the cliff's foot {foot_lit:.4} lit, {foot_shaded:.4} shadowed; beyond {beyond_lit:.4}, {beyond_shaded:.4}"
        );
        assert!(
            foot_shaded < 0.85 * foot_lit,
            "{mode:?}: no shadow at the foot"
        );
        assert!(
            (beyond_shaded - beyond_lit).abs() < 0.01 * beyond_lit,
            "{mode:?}: shadow beyond its reach"
        );
    }
}

/// Beyond the sketch the sky pass and the reference draw the same plain (or sea), to the horizon;
/// its pixels stay sky in the positions, so the image metrics measure the mesh alone; `void`
/// leaves the sky.
#[test]
fn the_world_beyond_the_sketch_is_drawn_alike_and_counted_as_sky() {
    let corner = |mode: Mode, outside: &str| {
        let mut s = bundled("hills-high", 64, 64);
        s.sketch.outside = Some(terrain_engine::scene::Outside::parse(outside).unwrap());
        let (_, rgba, world) = render_with_positions(&s, mode);
        // The top-left pixel lies beyond the sketch in this view.
        assert_eq!(
            world[3], 0.0,
            "{mode:?} {outside}: the corner is not sky in the positions"
        );
        [rgba[0], rgba[1], rgba[2]]
    };
    let void = corner(Mode::Warped, "void");
    for outside in ["plain", "ocean"] {
        let mesh = corner(Mode::Warped, outside);
        let reference = corner(Mode::Reference, outside);
        assert_ne!(mesh, void, "{outside}: the corner still shows the sky");
        let most = mesh
            .iter()
            .zip(&reference)
            .map(|(a, b)| a.abs_diff(*b))
            .max();
        assert!(
            most <= Some(2),
            "{outside}: mesh {mesh:?}, reference {reference:?}"
        );
    }
}

/// Multisampling (`render.msaa = "4x"`) brings the mesh modes' edges toward the reference
/// supersampled alike (four rays per pixel at the same sample positions), and leaves each
/// pixel's recovered ground position as it was (llvmpipe, 128²: warped 29.06 -> 29.70 dB,
/// GeoMipMap 28.25 -> 28.64 dB; the rest of the difference is the surface, not its edges).
#[test]
fn multisampling_smooths_edges_toward_the_supersampled_reference_and_keeps_positions() {
    let shot = |mode: Mode, msaa: &str| {
        let mut s = bundled("jacksboro", 128, 256);
        s.render.msaa = terrain_engine::scene::Msaa::parse(msaa).unwrap();
        let mut r = Renderer::new(&s, mode, View::Shaded).unwrap();
        let camera = terrain_engine::scene::camera_of(&s, &r.atlas).unwrap();
        let frame = r.render(&camera).unwrap();
        let positions = r.read_positions(&camera).unwrap();
        (r.samples, frame.rgba, positions)
    };
    let (samples, reference, _) = shot(Mode::Reference, "4x");
    if samples == 1 {
        eprintln!("skipped: this adapter's targets cannot be multisampled");
        return;
    }
    for mode in [Mode::Warped, Mode::Geomipmap] {
        let (_, aliased, flat) = shot(mode, "off");
        let (_, smooth, resolved) = shot(mode, "4x");
        let (before, after) = (psnr(&aliased, &reference), psnr(&smooth, &reference));
        eprintln!(
            "{mode:?}: against the 4x reference {before:.2} dB aliased, {after:.2} dB multisampled"
        );
        assert!(
            after > before + 0.2,
            "{mode:?}: {before:.2} -> {after:.2} dB"
        );
        // The depth copy comes from a single-sampled pass: the pixel centres' positions.
        let same = flat.iter().zip(&resolved).filter(|(a, b)| a == b).count();
        let share = same as f64 / flat.len() as f64;
        assert!(share > 0.999, "{mode:?}: {share:.4} of positions unchanged");
    }
}

/// A low sun (10° from the east) beside the gaussian mountain: the flank facing away lies in its
/// shadow, under half the luminance of the sunward flank, in the mesh modes and the reference
/// alike.
#[test]
fn a_low_sun_leaves_the_lee_of_a_mountain_under_half_the_lit_side() {
    let text = r#"
        [sketch]
        synthetic = "gaussian"
        [camera]
        position = [3840.0, -3000.0, 2500.0]
        look_at = [3840.0, 3840.0, 300.0]
        width = 96
        height = 96
        [detail]
        amplitude_m = 8.0
        gain = 0.45
        [light]
        sun_azimuth_deg = 90.0
        sun_elevation_deg = 10.0
    "#;
    let s = Scene::parse(text, manifest_dir()).unwrap();
    let mut ratios = Vec::new();
    for mode in [Mode::Warped, Mode::Geomipmap, Mode::Reference] {
        let (_, rgba, world) = render_with_positions(&s, mode);
        // The flanks: more than 300 m either side of the summit, above 200 m.
        let flank = |west: bool| {
            let ground = world.chunks_exact(4).map(move |q| {
                let side = if west { q[0] < 3540.0 } else { q[0] > 4140.0 };
                q[3] > 0.5 && q[2] > 200.0 && side
            });
            terrain_cli::eval::metrics::terrain_luminance(&rgba, ground)
                .expect("the flank in view")
                .0
        };
        let (lee, lit) = (flank(true), flank(false));
        eprintln!(
            "{mode:?}: lee {lee:.4}, lit {lit:.4}, ratio {:.3}",
            lee / lit
        );
        assert!(lee < 0.5 * lit, "{mode:?}: lee {lee:.4}, lit {lit:.4}");
        ratios.push(lee / lit);
    }
    let spread = ratios.iter().cloned().fold(f64::NEG_INFINITY, f64::max)
        - ratios.iter().cloned().fold(f64::INFINITY, f64::min);
    assert!(spread < 0.05, "the modes disagree: {ratios:?}");
}

/// Under a 6° sun from the side the procedural detail on a flat sketch shadows itself
/// (`render.detail_shadows`), by nearly the same share in the warped mode (which carries most
/// octaves as bump) and the reference (which marches them all as geometry); `false` compiles the
/// shadow out. Measured on llvmpipe: warped keeps 0.61 of its light, the reference 0.70; the
/// reference's rays see less of the dips, which are the most shadowed, than a bump-mapped mesh.
#[test]
fn the_detail_shadows_itself_alike_in_mesh_and_reference() {
    let scene = |detail_shadows: bool| {
        let text = r#"
            [sketch]
            synthetic = "flat"
            [camera]
            position = [3840.0, 3000.0, 150.0]
            look_at = [3840.0, 3600.0, 0.0]
            width = 96
            height = 96
            [detail]
            amplitude_m = 12.0
            gain = 0.5
            [light]
            sun_azimuth_deg = 90.0
            sun_elevation_deg = 6.0
        "#;
        let mut s = Scene::parse(text, manifest_dir()).unwrap();
        s.render.detail_shadows = detail_shadows;
        s
    };
    let mut shares = Vec::new();
    for mode in [Mode::Warped, Mode::Reference] {
        let mean = |detail_shadows: bool| {
            let (_, rgba, world) = render_with_positions(&scene(detail_shadows), mode);
            let ground = world.chunks_exact(4).map(|q| q[3] > 0.5);
            terrain_cli::eval::metrics::terrain_luminance(&rgba, ground)
                .expect("ground in view")
                .0
        };
        let (lit, shadowed) = (mean(false), mean(true));
        eprintln!("{mode:?}: {lit:.4} without the detail's shadow, {shadowed:.4} with it");
        assert!(shadowed < 0.9 * lit, "{mode:?}: {lit:.4} -> {shadowed:.4}");
        shares.push(shadowed / lit);
    }
    assert!(
        (shares[0] - shares[1]).abs() < 0.12,
        "mesh and reference disagree: {shares:?}"
    );
}

/// The sky the terrain pass draws is its CPU twin's (`terrain_engine::light`): the single-scattering
/// integral along the pixel's ray, exposed and tone-mapped, within 2 of 255 levels once sRGB
/// encoded, for a high sun, a low one and one below the horizon.
#[test]
fn the_sky_matches_its_cpu_twin() {
    for elevation in [35.0, 4.0, -3.0] {
        let text = format!(
            r#"
            [sketch]
            synthetic = "flat"
            outside = "void"
            [camera]
            position = [3840.0, 3840.0, 300.0]
            look_at = [3840.0, 4840.0, 1300.0]
            width = 33
            height = 33
            [light]
            sun_azimuth_deg = 160.0
            sun_elevation_deg = {elevation}
        "#
        );
        let s = Scene::parse(&text, manifest_dir()).unwrap();
        let mut r = Renderer::new(&s, Mode::Warped, View::Shaded).unwrap();
        let camera = terrain_engine::scene::camera_of(&s, &r.atlas).unwrap();
        let frame = r.render(&camera).unwrap();
        // The centre pixel looks along the camera's axis, 45° up to the north.
        let k = (16 * 33 + 16) * 4;
        let gpu = &frame.rgba[k..k + 3];
        let light = terrain_engine::scene::light_of(&s);
        let dir = glam::DVec3::new(0.0, 1.0, 1.0).normalize();
        let srgb = |c: f64| {
            let c = c.clamp(0.0, 1.0);
            let v = if c <= 0.0031308 {
                12.92 * c
            } else {
                1.055 * c.powf(1.0 / 2.4) - 0.055
            };
            (v * 255.0).round()
        };
        let cpu = light.display(light.sky(300.0, dir)).map(srgb);
        for (g, c) in gpu.iter().zip(cpu) {
            assert!(
                (*g as f64 - c).abs() <= 2.0,
                "sun at {elevation}°: GPU {gpu:?}, CPU {cpu:?}"
            );
        }
    }
}

/// From 12 km up GeoMipMap draws coarse blocks; each lights its vertices with the normal of the
/// surface its level draws, not the baked fine grid's point-sampled one, so its shading agrees with
/// the reference instead of aliasing (llvmpipe, 96²: 62.3 dB on 2026-11-25, where the fine grid's
/// normals read 34.2 dB). Its fine blocks (τ 0.5, blocks of 17), whose baked octaves run past the
/// pixel's, take the terrain function's normal (`shading_normal`); the bounds lie between their own
/// normals' PSNR and the terrain function's (docs/decisions.md, “Terrain function's normal on
/// coarse ground”).
#[test]
fn geomipmap_from_afar_shades_like_the_reference() {
    let s = bundled("gaussian-high", 96, 64);
    let db = psnr(&shot(&s, Mode::Geomipmap), &shot(&s, Mode::Reference));
    eprintln!("gaussian-high at 96²: GeoMipMap {db:.1} dB against the reference");
    assert!(db > 40.0, "{db:.1} dB");
    for (view, least) in [("hills-high", 47.0), ("gaussian-high", 55.0)] {
        let mut s = bundled(view, 256, 64);
        s.geomipmap.tau = 0.5;
        s.geomipmap.block = 17;
        let db = psnr(&shot(&s, Mode::Geomipmap), &shot(&s, Mode::Reference));
        eprintln!("{view} at 256², GeoMipMap τ 0.5, blocks of 17: {db:.2} dB");
        assert!(db > least, "{view}: {db:.2} dB against the reference");
    }
}

/// Bump detail has no parallax, so at grazing angles a bump octave drawn whole is the reference's
/// pattern shifted by a fraction of its wavelength or more; weighted by its expected correlation
/// (`detail.bump_fade`) it errs less than drawn whole, and less than left out where the ground is
/// seen steeply enough to hold it. The octaves of the terrain function's normal, which shades
/// ground where the mesh samples the sketch at twice its cells or coarser (blended in between
/// once and twice), are faded alike. The gaussian mountain and the hills from their foot, against
/// the reference, in the warped mode and in GeoMipMap (τ 4, blocks of 17), which shares the bump.
#[test]
fn the_bump_fades_where_the_mesh_cannot_hold_its_place() {
    // (view, mode, warped mesh, least gain over the bump drawn whole, over no bump), dB, about
    // half of what was measured: on gaussian, warped mesh 24 +6.11 and +5.98 (nearly all its
    // ground shaded with the terrain function's normal), mesh 96 +4.52 and +1.14 (its near
    // ground all grazing), mesh 264 +0.31 and +0.24 (the bump kept where the ground is seen
    // steeply enough), GeoMipMap +1.89 and +0.98; on hills, warped mesh 96 +0.94 and +0.38.
    // There the terrain function's octaves faded as strongly as the bump's (its fitted factor,
    // not the model's) read 23.90 dB, which fails both bounds.
    let cases = [
        ("gaussian", Mode::Warped, 24, 3.0, 3.0),
        ("gaussian", Mode::Warped, 96, 2.2, 0.55),
        ("gaussian", Mode::Warped, 264, 0.15, 0.12),
        ("gaussian", Mode::Geomipmap, 96, 0.9, 0.45),
        ("hills", Mode::Warped, 96, 0.45, 0.15),
    ];
    let scene = |view: &str| {
        let mut s = bundled(view, 256, 96);
        s.warp.budget = false;
        s.geomipmap.tau = 4.0;
        s.geomipmap.block = 17;
        s
    };
    // The reference draws no mesh: one per view.
    let references = ["gaussian", "hills"].map(|view| (view, shot(&scene(view), Mode::Reference)));
    for (view, mode, mesh, over_whole, over_none) in cases {
        let s = scene(view);
        let reference = &references
            .iter()
            .find(|(v, _)| *v == view)
            .expect("a view's reference")
            .1;
        let db = |bump: bool, fade: bool| {
            let mut s = s.clone();
            s.warp.mesh = mesh;
            s.detail.bump = bump;
            s.detail.bump_fade = fade;
            psnr(&shot(&s, mode), reference)
        };
        let (none, whole, faded) = (db(false, false), db(true, false), db(true, true));
        eprintln!(
            "{view} at 256², {mode:?} (mesh {mesh}): no bump {none:.2} dB, whole {whole:.2}, \
             faded {faded:.2}"
        );
        assert!(
            faded > whole + over_whole,
            "{view}, {mode:?}, mesh {mesh}: whole {whole:.2} → faded {faded:.2} dB"
        );
        assert!(
            faded > none + over_none,
            "{view}, {mode:?}, mesh {mesh}: none {none:.2}, faded {faded:.2} dB"
        );
    }
}

/// The warped region is a square on a lattice and reaches past the sketch; warp & zoom puts the
/// vertices beyond the edge on it, and the terrain pass leaves out the cells between them (the
/// edge's vertical plane), so the mesh ends where the reference's surface does. hills-high sees
/// the whole sketch, its edges against the ground beyond, at 256²; PSNR against the reference,
/// measured: warped mesh 33 41.26 dB with the vertices beyond the edge where Φ put them (88 % of
/// the squared error in 100 pixels along the far edge, whose heights were a line to a vertex
/// beyond), 48.15 with them on it; mesh 96 52.36 and 55.87. With the vertices on the edge but
/// the cells between them drawn (chords of the near edge's profile, standing in the edge's
/// plane), mesh 33 read 48.32 and mesh 96 49.34. The bounds lie between. A region turned by 45°
/// keeps its vertices beyond the edge (`drawn_xy` in warp_zoom.wgsl): the same hills from 9 km
/// up, looking north-east, warped mesh 48 read 40.80 dB with them beyond, 39.55 with them on the
/// edge (cells turned over), 40.77 now.
#[test]
fn the_mesh_ends_at_the_sketchs_edge() {
    let mut high = bundled("hills-high", 256, 33);
    high.warp.budget = false;
    let mut turned = high.clone();
    turned.camera.position = Some([-1500.0, -1500.0, 9000.0]);
    turned.camera.look_at = Some([3500.0, 3500.0, 0.0]);
    for (s, name, cases) in [
        (high, "hills-high", &[(33, 45.0), (96, 54.0)][..]),
        (turned, "hills from 9 km, north-east", &[(48, 40.3)][..]),
    ] {
        let reference = shot(&s, Mode::Reference);
        let (r, _) = render(&s, View::Shaded);
        let camera = terrain_engine::scene::camera_of(&s, &r.atlas).unwrap();
        let along_axes = r.uniforms(&camera).mesh.phi_s[1] == 0.0;
        assert_eq!(
            along_axes,
            name == "hills-high",
            "{name}: the region's turn"
        );
        drop(r);
        for &(mesh, least) in cases {
            let mut s = s.clone();
            s.warp.mesh = mesh;
            let db = psnr(&shot(&s, Mode::Warped), &reference);
            eprintln!("{name} at 256², warped mesh {mesh}: {db:.2} dB");
            assert!(
                db > least,
                "{name}, mesh {mesh}: {db:.2} dB against the reference"
            );
        }
    }
}

/// `sketch.water_level_m` floods the ground below it with flat water, in the terrain function
/// itself: no mesh vertex lies below it, the reference's rays stop on it, and both shade it as
/// water alike.
#[test]
fn water_floods_the_ground_below_its_level_alike_in_mesh_and_reference() {
    let text = r#"
        [sketch]
        synthetic = "gaussian"
        water_level_m = 600.0
        [camera]
        position = [3840.0, -1500.0, 2200.0]
        look_at = [3840.0, 3840.0, 400.0]
        width = 80
        height = 80
        [detail]
        amplitude_m = 8.0
        gain = 0.45
    "#;
    let s = Scene::parse(text, manifest_dir()).unwrap();
    let (r, mesh_rgba, mesh_pos) = render_with_positions(&s, Mode::Warped);
    // The vertices of this frame's mesh (the buffer is sized for the largest).
    let camera = terrain_engine::scene::camera_of(&s, &r.atlas).unwrap();
    let mesh = r.uniforms(&camera).mesh.mesh as usize;
    let lowest = warped(&r).read_detailed(&r.ctx).unwrap()[..mesh * mesh]
        .iter()
        .map(|v| v[2])
        .fold(f32::INFINITY, f32::min);
    assert!(lowest >= 600.0, "a vertex at {lowest} m, under the water");
    drop(r);
    let (_, ref_rgba, ref_pos) = render_with_positions(&s, Mode::Reference);
    let water = |pos: &[f64]| {
        pos.chunks_exact(4)
            .map(|q| q[3] > 0.5 && q[2] < 600.05)
            .collect::<Vec<bool>>()
    };
    // The reference's positions say where the water is: the mesh's, recovered from its depth,
    // are metres off at a few kilometres, so both images are read on the reference's pixels.
    let ref_water = water(&ref_pos);
    assert!(
        mesh_pos.chunks_exact(4).any(|q| q[3] > 0.5),
        "the mesh drew nothing"
    );
    let share = ref_water.iter().filter(|w| **w).count() as f64 / ref_water.len() as f64;
    assert!(
        share > 0.2,
        "{share:.2} of the reference's pixels on the water"
    );
    let deepest = ref_pos
        .chunks_exact(4)
        .filter(|q| q[3] > 0.5)
        .map(|q| q[2])
        .fold(f64::INFINITY, f64::min);
    assert!(deepest > 599.9, "the reference's ray reached {deepest} m");
    let mean = |rgba: &[u8], on: &[bool]| {
        terrain_cli::eval::metrics::terrain_luminance(rgba, on.iter().copied())
            .expect("water in view")
            .0
    };
    let (m, r) = (mean(&mesh_rgba, &ref_water), mean(&ref_rgba, &ref_water));
    eprintln!("water: {share:.2} of the view; luminance mesh {m:.4}, reference {r:.4}");
    assert!((m - r).abs() < 0.1 * r, "mesh {m:.4}, reference {r:.4}");
}

/// Along a held warp the mesh keeps its cells, and their diagonals too but for the few whose two
/// diagonals lie about equally near the surface: a camera 10 m further along jacksboro's view (a
/// frame at 150 m/s and 15 fps) changes the vertices' heights only through their pixel octave.
/// Measured: 2 of 30,625 cells (the 176² mesh the budget gives at 128²).
#[test]
fn a_held_warp_keeps_almost_every_cells_diagonal() {
    let mut scene = bundled("jacksboro", 128, 512);
    let mut r = Renderer::new(&scene, Mode::Warped, View::Shaded).expect("renderer");
    let first = terrain_engine::scene::camera_of(&scene, &r.atlas).unwrap();
    r.render(&first).expect("frame");
    let before = warped(&r).read_indices(&r.ctx).unwrap();
    let m = warped(&r).stage.mesh as usize;
    let cells = (m - 1) * (m - 1);
    // The split pass ran: many cells take the other diagonal.
    let across = (0..cells)
        .filter(|&c| before[6 * c + 2] != before[6 * c] + m as u32 + 1)
        .count();
    assert!(across * 5 > cells, "{across} of {cells} cells split across");
    let (eye, target) = (scene.camera.eye(), scene.camera.target());
    let step = (target - eye).normalize() * 10.0;
    scene.camera.aim(eye + step, target + step);
    let second = terrain_engine::scene::camera_of(&scene, &r.atlas).unwrap();
    r.render(&second).expect("frame");
    assert!(warped(&r).stage.held, "the warp is held");
    assert_eq!(warped(&r).stage.mesh as usize, m);
    let after = warped(&r).read_indices(&r.ctx).unwrap();
    let changed = (0..cells)
        .filter(|c| before[6 * c..6 * c + 6] != after[6 * c..6 * c + 6])
        .count();
    eprintln!("{changed} of {cells} cells changed their diagonal");
    assert!(
        changed * 1000 <= cells,
        "{changed} of {cells} cells changed"
    );
}

/// A device lost under a renderer (here destroyed, as a driver reset or an unplugged GPU loses
/// it) makes the next frame one error of one line, not a panic, in the mesh modes and the
/// reference alike; the frame before it drew.
#[test]
fn a_lost_device_is_one_error_not_a_panic() {
    for mode in [Mode::Warped, Mode::Geomipmap, Mode::Reference] {
        let scene = bundled("hills", 48, 32);
        let atlas = terrain_engine::scene::load_atlas(&scene).unwrap();
        let needs = terrain_engine::needs(&scene, mode, &atlas);
        let ctx = terrain_engine::GpuContext::new(&needs).unwrap();
        let mut r = Renderer::with_context(ctx.clone(), &scene, atlas, mode, View::Shaded).unwrap();
        let camera = terrain_engine::scene::camera_of(&scene, &r.atlas).unwrap();
        r.render(&camera).expect("the frame before the loss");
        ctx.device.destroy();
        let err = r.render(&camera).map(|_| ()).unwrap_err().to_string();
        assert!(
            err.starts_with("GPU: the device was lost: ") && !err.contains('\n'),
            "{mode}: {err}"
        );
    }
}
