//! Warped mode on a planet, tried: the planet's terrain resampled onto the tangent plane of the
//! camera's nadir (the sphere's curvature baked into the heights), drawn by the planar warped
//! mode, and measured beside clipmaps against the planet's reference (every octave) by
//! screen-space error and triangles. The planar passes' octaves are planar noise, not the
//! planet's 3-D lattice, so the warped mode draws with its own octaves off and the map holds the
//! planet's terrain function (the sketch and the octaves) band-limited to the map's node spacing:
//! what a tangent-plane sketch map can carry without the warped passes learning the sphere.
//!
//! The tangent-plane map is orthographic: node (x, y) holds the height above the tangent plane of
//! the ground point that projects onto it (found by fixed-point iteration on the angle from the
//! nadir), so a planar vertex at (x, y, z) is exactly that ground point, wherever the ground is
//! single-valued over the plane (it is for views that see less than a hemisphere and have no
//! overhang past the tilt). The map covers the square around the nadir that holds every ground
//! pixel of the reference, at `NODES` nodes a side.
//!
//! `cargo run --release --example planet_tangent_warp [SCENE] [SIZE]` (default: the bundled
//! planet-10km scene, 256²).

use anyhow::Context;
use glam::DVec2;
use std::path::PathBuf;
use terrain_cli::eval::metrics::{ScreenError, screen_space_error};
use terrain_engine::Renderer;
use terrain_engine::View;
use terrain_engine::planet::Planet;
use terrain_engine::scene::{Mode, Scene};
use terrain_engine::sketch::{Atlas, LoadOptions, RawGrid};
use terrain_engine::{GpuContext, Needs};

/// Nodes a side of the tangent-plane sketch map.
const NODES: usize = 1025;
/// The screen-space error's search window, pixels (as `compare`'s).
const WINDOW: usize = 16;

fn main() -> anyhow::Result<()> {
    let mut args = std::env::args().skip(1);
    let path = args.next().map(PathBuf::from).unwrap_or_else(|| {
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("sketches/planet-10km.toml")
    });
    let size: u32 = args.next().map_or(Ok(256), |s| s.parse())?;
    let mut scene = Scene::load(&path).with_context(|| path.display().to_string())?;
    (scene.camera.width, scene.camera.height) = (size, size);
    let planet_section = scene.planet().context("not a planet scene")?;
    let atlas = terrain_engine::scene::load_atlas(&scene)?;
    let camera = terrain_engine::scene::camera_of(&scene, &atlas)?;
    let geo = camera.geo.context("a planet camera")?;

    let ctx = GpuContext::new(&Needs {
        storage_bytes: 1 << 27,
    })?;
    let positions = |mode: Mode, scene: &Scene, atlas: &Atlas, cam: &terrain_engine::Camera| {
        let mut r = Renderer::with_context(ctx.clone(), scene, atlas.clone(), mode, View::Shaded)?;
        let frame = r.render(cam)?;
        anyhow::Ok((r.read_positions(cam)?, frame.gpu.triangles))
    };
    let (truth, _) = positions(Mode::Reference, &scene, &atlas, &camera)?;
    let half = truth
        .iter()
        .filter(|p| p[3] > 0.5)
        .map(|p| p[0].abs().max(p[1].abs()) as f64)
        .fold(0.0, f64::max)
        * 1.02
        + 1.0;
    let planet = Planet {
        radius: planet_section.radius_m,
        sketch: &atlas,
    };
    println!("{}: {size}²", path.display());
    println!("| mode | setting | triangles | mean screen-space error | p95 |");
    println!("|---|---|---|---|---|");
    let row = |mode: &str, setting: String, e: &ScreenError, triangles: u64| {
        println!(
            "| {mode} | {setting} | {triangles} | {:.3} px | {:.3} px |",
            e.mean_px, e.p95_px
        )
    };
    for (phi, m) in [(128, 20), (256, 20), (256, 40)] {
        let mut s = scene.clone();
        let mut p = planet_section.clone();
        (p.phi_steps, p.rings_per_level) = (phi, m);
        s.planet = Some(p);
        let (got, triangles) = positions(Mode::Clipmaps, &s, &atlas, &camera)?;
        let e = screen_space_error(&got, &truth, size as usize, WINDOW);
        row("clipmaps", format!("{phi} × {m}"), &e, triangles);
    }
    let detail = terrain_engine::scene::detail_of(&scene, &atlas);
    let spacing = 2.0 * half / (NODES - 1) as f64;
    let started = std::time::Instant::now();
    let tangent = tangent_plane_map(&planet, &detail, geo, half, atlas.water_m as f64);
    let bake_s = started.elapsed().as_secs_f64();
    let tangent = match tangent {
        Ok(t) => t,
        Err(e) => {
            println!("| warped, tangent plane | the map is refused: {e} | | | |");
            return Ok(());
        }
    };
    println!(
        "| warped, tangent plane | the map: ±{:.1} km, {NODES}² nodes at {spacing:.1} m, baked in \
         {bake_s:.1} s, heights {:.0} … {:.0} m | | | |",
        half / 1e3,
        tangent.min_m,
        tangent.max_m
    );
    let mut flat = scene.clone();
    flat.planet = None;
    flat.sketch.synthetic = None;
    flat.detail.octaves = Some(0);
    let mut planar = camera.clone();
    planar.geo = None;
    // Fixed meshes, then the mesh the view's importance asks for within the largest bound.
    for (mesh, budget) in [(128, false), (256, false), (512, false), (1024, true)] {
        flat.warp.mesh = mesh;
        flat.warp.budget = budget;
        let (got, triangles) = positions(Mode::Warped, &flat, &tangent, &planar)?;
        let e = screen_space_error(&got, &truth, size as usize, WINDOW);
        let setting = if budget {
            format!("its budget, mesh ≤ {mesh}")
        } else {
            format!("mesh={mesh} fixed")
        };
        row("warped, tangent plane", setting, &e, triangles);
    }
    Ok(())
}

/// The ground around the nadir `geo` over the square ±`half` metres of its tangent plane: each
/// node the height above the plane of the ground point projecting onto it (the terrain function
/// at the node spacing's footprint, the sea where it lies below `water_m`), with no water of its
/// own.
fn tangent_plane_map(
    planet: &Planet,
    detail: &terrain_engine::Detail,
    geo: terrain_engine::Geo,
    half: f64,
    water_m: f64,
) -> anyhow::Result<Atlas> {
    let (r, lat, lon) = (planet.radius, geo.lat, geo.lon);
    let step = 2.0 * half / (NODES - 1) as f64;
    let mut data = vec![0f32; NODES * NODES];
    for (j, row) in data.chunks_mut(NODES).enumerate() {
        for (i, z) in row.iter_mut().enumerate() {
            let p = DVec2::new(-half + i as f64 * step, -half + j as f64 * step);
            let (rho, bearing) = (p.length(), p.x.atan2(p.y));
            let ground = |theta: f64| {
                let (la, lo, _) = terrain_engine::planet::travel(lat, lon, bearing, theta);
                planet
                    .ground(detail, la, lo, step)
                    .expect("an in-memory sketch")
                    .max(water_m)
            };
            let mut theta = (rho / r).min(1.0).asin();
            let mut h = ground(theta);
            for _ in 0..4 {
                theta = (rho / (r + h)).min(1.0).asin();
                h = ground(theta);
            }
            *z = ((r + h) * theta.cos() - r) as f32;
        }
    }
    let raw = RawGrid::new(NODES, NODES, data, None);
    let mut atlas = Atlas::from_raw(
        raw,
        &LoadOptions {
            spacing_m: Some(step),
            origin_m: Some(DVec2::splat(-half)),
            ..Default::default()
        },
    )?;
    atlas.water_m = f32::MIN;
    Ok(atlas)
}
