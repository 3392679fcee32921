//! The clipmaps pass against its CPU twin and the f64 terrain function, on the machine's adapter
//! (lavapipe or llvmpipe without a GPU).

use terrain_engine::lod::clipmaps::pass::{lat_lon_of, vertex_cpu};
use terrain_engine::planet::noise::{lattice_scale, octave_at};
use terrain_engine::planet::{Planet, unit};
use terrain_engine::scene::{Mode, Scene};
use terrain_engine::{Clipmaps, Frame, Renderer, View};

fn render_in(scene: &Scene, mode: Mode, view: View) -> (Renderer, Frame) {
    let mut r = Renderer::new(scene, mode, view).expect("renderer");
    let camera = terrain_engine::scene::camera_of(scene, &r.atlas).unwrap();
    let frame = r.render(&camera).expect("frame");
    (r, frame)
}

fn planet_scene(lat: f64, lon: f64, altitude: f64, pitch: f64, size: u32) -> Scene {
    let text = format!(
        "[sketch]\nsynthetic = \"planet\"\nsize = 256\n[planet]\nphi_steps = 128\nrings_per_level = 8\n\
         [camera]\nlat_deg = {lat}\nlon_deg = {lon}\naltitude_m = {altitude}\npitch_deg = {pitch}\n\
         heading_deg = 30.0\nwidth = {size}\nheight = {size}\n"
    );
    Scene::parse(&text, env!("CARGO_MANIFEST_DIR").into()).unwrap()
}

/// The GPU's vertices equal the CPU twin's, and the twin's heights equal the f64 terrain
/// function at the vertices' latitude and longitude (the sketch at the vertex's spacing plus its
/// geometric octaves), at the Earth's radius: from orbit, at mid latitudes, a few metres from a
/// pole, on the date line. Whole heights agree to 1e-3 of the detail's amplitude, the sketch's
/// part differing by the last bit of the GPU's and the CPU's atan2 at vertices a radian away,
/// which an ocean floor's texel turns into decimetres. The detail alone (each vertex's height
/// less its height in the same frame drawn without octaves, the same camera and so the same
/// nadir, so the sketch's part cancels) agrees to 1e-4 of the amplitude.
#[test]
fn the_clipmaps_pass_agrees_with_its_twin_and_the_terrain_function() {
    for (lat, lon, altitude) in [
        (31.0, 12.0, 2e7),
        (31.0, 12.0, 10_000.0),
        (89.9999, -40.0, 2.0),
        (-12.0, 180.0, 500.0),
    ] {
        let s = planet_scene(lat, lon, altitude, -30.0, 64);
        let (r, _) = render_in(&s, Mode::Clipmaps, View::Shaded);
        let lod = r.lod::<Clipmaps>().expect("clipmaps");
        let u = lod.uniforms.expect("a planet frame");
        let gpu = lod.read_vertices(r.ctx()).expect("vertices");
        // The same camera drawn without the octaves: the sketch's part of each vertex alone.
        let camera = terrain_engine::scene::camera_of(&s, &r.atlas).expect("camera");
        let mut bare_scene = s.clone();
        bare_scene.detail.octaves = Some(0);
        let mut bare = Renderer::new(&bare_scene, Mode::Clipmaps, View::Shaded).expect("renderer");
        bare.render(&camera).expect("frame");
        let bare_lod = bare.lod::<Clipmaps>().expect("clipmaps");
        let bare_u = bare_lod.uniforms.expect("a planet frame");
        let bare_gpu = bare_lod.read_vertices(bare.ctx()).expect("vertices");
        let bare_range = bare_lod.rings.vertex_range(bare_lod.span);
        let (mut worst_detail, mut compared) = (0.0f32, 0);
        let planet = Planet {
            radius: u.radius as f64,
            sketch: &r.atlas,
        };
        let geo = terrain_engine::Geo {
            lat: lat.to_radians(),
            lon: lon.to_radians(),
        };
        let amplitude = r.detail.amplitude_m as f32;
        let (mut worst_twin, mut worst_exact) = (0.0f32, 0.0f64);
        let range = lod.rings.vertex_range(lod.span);
        let step = ((range.end - range.start) / 997).max(1) as usize;
        for i in (range.start..range.end)
            .step_by(step)
            .chain([lod.rings.nadir()])
        {
            let v = lod.rings.vertices[i as usize];
            let g = glam::Vec4::from(gpu[i as usize]);
            let c = vertex_cpu(&planet, r.atlas.d_atlas() as f32, &u, v).unwrap();
            // Heights before the sea covers them (w); x, y and z are the same products of the
            // radius and the height after it in both.
            worst_twin = worst_twin.max((g.w - c.w).abs() / amplitude);
            // Inside the innermost drawn ring the spacing is clamped to that ring's, which
            // differs between the frames: compare the vertices both draw unclamped.
            let unclamped = i / u.phi_steps < u.inner_ring.min(bare_u.inner_ring);
            if bare_range.contains(&i) && unclamped && i != lod.rings.nadir() {
                let bare_c = vertex_cpu(&planet, r.atlas.d_atlas() as f32, &bare_u, v).unwrap();
                let (gpu_detail, cpu_detail) = (g.w - bare_gpu[i as usize][3], c.w - bare_c.w);
                worst_detail = worst_detail.max((gpu_detail - cpu_detail).abs() / amplitude);
                compared += 1;
            }
            // The f64 terrain function at the vertex's place, with the same octave shares.
            let phi = if v.w > 0.0 {
                v.x.atan2(v.y) as f64
            } else {
                0.0
            };
            let (vlat, vlon) = lat_lon_of(&geo, v.w as f64, phi);
            let spacing = {
                let a = v.w;
                let across = a * ((1.0 / u.rings_per_level as f32).exp2() - 1.0);
                let along = a.sin() * std::f32::consts::TAU / u.phi_steps as f32;
                (u.radius * across.max(along)).max(u.min_spacing) as f64
            };
            let mut h = planet.sketch_height(vlat, vlon, spacing).unwrap();
            let o = (r.atlas.d_atlas() / spacing).log2() - r.detail.bias;
            let p = unit(vlat, vlon) * planet.radius;
            for k in 1..=r.detail.last_octave(o as f32) {
                let share = (o - k as f64 + 1.0).clamp(0.0, 1.0);
                let (n, _) = octave_at(
                    lattice_scale(r.detail.d_atlas, k),
                    r.detail.octave_seed(k),
                    p,
                );
                h += r.detail.weight(k) * share * n as f64;
            }
            // f32 keeps the offset to the vertex to its relative precision: up to 2e-7 of its
            // distance sideways, which a slope of 1 turns into as much height.
            let allowed = 0.02 + 2e-7 * planet.radius * v.w as f64;
            worst_exact = worst_exact.max((c.w as f64 - h).abs() / allowed);
        }
        eprintln!(
            "at {lat}°, {lon}°, {altitude} m: GPU vs twin {worst_twin:.2e} of the amplitude \
             (the detail alone {worst_detail:.2e}), twin vs f64 {worst_exact:.3} of the allowance"
        );
        assert!(worst_twin < 1e-3, "{lat} {lon}: {worst_twin}");
        assert!(
            worst_detail < 1e-4 && compared >= 300,
            "{lat} {lon}: the detail {worst_detail} over {compared} vertices"
        );
        assert!(
            worst_exact < 1.0,
            "{lat} {lon}: {worst_exact} of the allowance"
        );
    }
}
