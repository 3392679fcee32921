//! The baselines on the machine's adapter (llvmpipe without a GPU): no cracks when neighbouring
//! blocks differ by 1, 2 or 3 levels, and GeoMipMap at τ = 0.5 px against brute force.

mod common;
use common::*;
use terrain_engine::Baselines;
use terrain_engine::Renderer;
use terrain_engine::View;
use terrain_engine::scene::Mode;
use terrain_engine::scene::Scene;

/// Background pixels below the first terrain pixel of their column in a coverage image (terrain
/// white, sky black). Over a height field seen from above it, every ray below one that hits the
/// ground hits it too, so each of these is a hole.
fn holes(rgba: &[u8], width: usize) -> usize {
    let height = rgba.len() / 4 / width;
    let terrain = |x: usize, y: usize| rgba[(y * width + x) * 4] > 127;
    (0..width)
        .map(|x| match (0..height).find(|&y| terrain(x, y)) {
            Some(top) => (top..height).filter(|&y| !terrain(x, y)).count(),
            None => 0,
        })
        .sum()
}

#[test]
fn no_cracks_between_blocks_any_levels_apart() {
    let views = [
        (
            "cliff",
            "down",
            [1920.0, 1920.0, 2500.0],
            [1920.0, 1921.0, 0.0],
        ),
        (
            "cliff",
            "grazing",
            [1800.0, 150.0, 520.0],
            [1800.0, 3500.0, 300.0],
        ),
        (
            "ridges",
            "down",
            [1920.0, 1920.0, 3000.0],
            [1920.0, 1921.0, 0.0],
        ),
        (
            "ridges",
            "grazing",
            [1920.0, 150.0, 1300.0],
            [1920.0, 3500.0, 700.0],
        ),
    ];
    for (sketch, what, eye, at) in views {
        let toml = format!(
            "[sketch]\nsynthetic = \"{sketch}\"\nsize = 129\n[camera]\nposition = {eye:?}\nlook_at = {at:?}\nwidth = 160\nheight = 160\n[geomipmap]\nk = 1\n"
        );
        let s = scene(&toml, manifest_dir());
        let mut r = Renderer::new(&s, Mode::Geomipmap, View::Coverage).unwrap();
        let cam = terrain_engine::scene::camera_of(&s, &r.atlas).unwrap();
        let chosen = r.render(&cam).unwrap();
        assert_eq!(
            holes(&chosen.rgba, 160),
            0,
            "{sketch} {what}: holes at the chosen levels"
        );
        let per_side = r.lod::<Baselines>().unwrap().blocks.per_side;
        for d in 1..=3u8 {
            let b = r.lod_mut::<Baselines>().unwrap();
            let sel = &mut b.selection;
            for k in 0..per_side * per_side {
                if sel.level[k] != u8::MAX {
                    let level = 1 + d * ((k % per_side + k / per_side) % 2) as u8;
                    sel.level[k] = level.min(b.blocks.levels as u8 - 1);
                }
            }
            sel.fill_gpu(&b.blocks, cam.f_px(), &b.params);
            let frame = r.render_held(&cam).unwrap();
            let n = holes(&frame.rgba, 160);
            if n > 0 {
                let out = scratch(&format!("cracks-{sketch}-{what}-{d}"));
                terrain_cli::output::write_image(&out.join("coverage.png"), 160, 160, &frame.rgba)
                    .unwrap();
            }
            assert_eq!(
                n, 0,
                "{sketch} {what}: {n} hole pixels with neighbours {d} levels apart"
            );
            let white = frame.rgba.chunks_exact(4).filter(|p| p[0] > 127).count();
            assert!(
                white > 160 * 40,
                "{sketch} {what}: too little terrain in view to test ({white} px)"
            );
        }
    }
}

fn bundled(name: &str) -> Scene {
    let path = manifest_dir().join("sketches").join(format!("{name}.toml"));
    let o: Vec<String> = [
        "camera.width=160",
        "camera.height=160",
        "geomipmap.k=1",
        "geomipmap.tau=0.5",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    Scene::load_with(&path, &o).unwrap()
}

#[test]
fn geomipmap_at_half_a_pixel_matches_brute_force_with_far_fewer_triangles() {
    for name in ["jacksboro", "gaussian", "hills"] {
        let s = bundled(name);
        let mut lod = Renderer::new(&s, Mode::Geomipmap, View::Shaded).unwrap();
        let cam = terrain_engine::scene::camera_of(&s, &lod.atlas).unwrap();
        let a = lod.render(&cam).unwrap();
        drop(lod);
        let mut brute = Renderer::new(&s, Mode::Bruteforce, View::Shaded).unwrap();
        let b = brute.render(&cam).unwrap();
        let db = psnr(&a.rgba, &b.rgba);
        eprintln!(
            "{name}: {db:.1} dB; {} triangles against {}",
            a.gpu.triangles, b.gpu.triangles
        );
        assert!(db >= 35.0, "{name}: {db:.1} dB");
        assert!(
            a.gpu.triangles * 3 < b.gpu.triangles,
            "{name}: {} vs {}",
            a.gpu.triangles,
            b.gpu.triangles
        );
    }
}

/// GeoMipMap's block sizes and brute force of one K on one device bake one grid: the renderer
/// that bakes it first counts it, the others lend it and draw what they draw alone, a renderer of
/// another terrain function bakes its own, and a lent grid outlives the renderer that baked it.
#[test]
fn renderers_of_one_terrain_on_a_device_share_its_baked_grid() {
    let base = |extra: &[&str]| {
        let path = manifest_dir().join("sketches/gaussian.toml");
        let o: Vec<String> = ["camera.width=96", "camera.height=96", "geomipmap.k=1"]
            .iter()
            .chain(extra)
            .map(|s| s.to_string())
            .collect();
        Scene::load_with(&path, &o).unwrap()
    };
    let (s17, s65) = (base(&["geomipmap.block=17"]), base(&["geomipmap.block=65"]));
    let other = base(&["geomipmap.block=65", "detail.amplitude_m=3"]);
    let atlas = terrain_engine::scene::load_atlas(&s17).unwrap();
    let needs = terrain_engine::needs(&s17, Mode::Geomipmap, &atlas);
    // Each device's sketch is uploaded by a warped renderer first, and counted in its ledger.
    let warped = |ctx: &terrain_engine::GpuContext| {
        Renderer::with_context(ctx.clone(), &s17, atlas.clone(), Mode::Warped, View::Shaded)
            .unwrap()
    };
    let alone = |s: &Scene, mode: Mode| {
        let ctx = terrain_engine::GpuContext::new(&needs).unwrap();
        let _sketch = warped(&ctx);
        let mut r = Renderer::with_context(ctx, s, atlas.clone(), mode, View::Shaded).unwrap();
        let bytes = r.gpu_bytes();
        let cam = terrain_engine::scene::camera_of(s, &r.atlas).unwrap();
        (
            bytes,
            r.render(&cam).unwrap().rgba,
            r.precompute().unwrap().1,
        )
    };
    let ctx = terrain_engine::GpuContext::new(&needs).unwrap();
    let _sketch = warped(&ctx);
    let on_ctx = |s: &Scene, mode: Mode| {
        Renderer::with_context(ctx.clone(), s, atlas.clone(), mode, View::Shaded).unwrap()
    };
    let first = on_ctx(&s17, Mode::Geomipmap);
    let mut lent = on_ctx(&s65, Mode::Geomipmap);
    let mut brute = on_ctx(&s65, Mode::Bruteforce);
    let mut own = on_ctx(&other, Mode::Geomipmap);
    let (bytes65, image65, baked) = alone(&s65, Mode::Geomipmap);
    assert!(baked > 0);
    assert_eq!(
        first.precompute().unwrap().1,
        baked,
        "one grid for blocks of 17 and 65"
    );
    assert_eq!(
        lent.gpu_bytes() + baked,
        bytes65,
        "the lent grid is counted once"
    );
    let (brute_bytes, brute_image, _) = alone(&s65, Mode::Bruteforce);
    assert_eq!(brute.gpu_bytes() + baked, brute_bytes);
    let (own_bytes, ..) = alone(&other, Mode::Geomipmap);
    assert_eq!(
        own.gpu_bytes(),
        own_bytes,
        "another terrain function bakes its own grid"
    );
    drop(first);
    let cam = terrain_engine::scene::camera_of(&s65, &lent.atlas).unwrap();
    assert_eq!(lent.render(&cam).unwrap().rgba, image65);
    assert_eq!(brute.render(&cam).unwrap().rgba, brute_image);
    let _ = own.render(&cam).unwrap();
}
