//! Planets in clipmaps mode on the machine's adapter (llvmpipe without a GPU): pictures from orbit, from 10 km and from 2 m; determinism; refusals.

mod common;
use common::*;
use terrain_engine::Renderer;
use terrain_engine::View;
use terrain_engine::planet::Planet;
use terrain_engine::scene::{Mode, Scene};

fn planet_scene(lat: f64, lon: f64, altitude: f64, pitch: f64, size: u32) -> Scene {
    scene(
        &format!(
            "[sketch]\nsynthetic = \"planet\"\nsize = 256\n[planet]\nphi_steps = 128\nrings_per_level = 8\n\
             [camera]\nlat_deg = {lat}\nlon_deg = {lon}\naltitude_m = {altitude}\npitch_deg = {pitch}\n\
             heading_deg = 30.0\nwidth = {size}\nheight = {size}\n"
        ),
        manifest_dir(),
    )
}

fn render(s: &Scene) -> (Renderer, terrain_engine::Frame) {
    let mut r = Renderer::new(s, Mode::Clipmaps, View::Shaded).expect("renderer");
    let camera = terrain_engine::scene::camera_of(s, &r.atlas).expect("camera");
    let frame = r.render(&camera).expect("frame");
    (r, frame)
}

fn pixels(frame: &terrain_engine::Frame) -> impl Iterator<Item = [u8; 3]> + '_ {
    frame.rgba.chunks(4).map(|p| [p[0], p[1], p[2]])
}

/// From orbit the planet is a disc: ground in the middle, black space in the corners, and a
/// bright limb of air between. From 10 km and from 2 m the ground fills the lower half and the
/// sky the upper.
#[test]
fn planet_views_from_orbit_10_km_and_2_m() {
    let orbit = render(&planet_scene(30.0, 10.0, 2e7, -90.0, 96)).1;
    let at = |f: &terrain_engine::Frame, x: u32, y: u32| {
        let i = ((y * f.width + x) * 4) as usize;
        [f.rgba[i], f.rgba[i + 1], f.rgba[i + 2]]
    };
    assert_eq!(at(&orbit, 0, 0), [0, 0, 0], "space in the corner");
    let centre = at(&orbit, 48, 48);
    assert!(
        centre.iter().map(|&c| c as u32).sum::<u32>() > 60,
        "the disc's centre is lit: {centre:?}"
    );
    // The disc of a planet 20,000 km away under a 60° field: radius atan(R / (R + h)) / 30°.
    let r = (6371.0f64 / 26371.0).asin().to_degrees() / 30.0 * 48.0;
    let inside = at(&orbit, 48 + (0.8 * r) as u32, 48);
    let outside = at(&orbit, 48 + (1.15 * r) as u32, 48);
    assert!(
        inside.iter().any(|&c| c > 20) && outside.iter().all(|&c| c < 20),
        "{inside:?} {outside:?}"
    );
    for altitude in [10_000.0, 2.0] {
        let f = render(&planet_scene(30.0, 10.0, altitude, 0.0, 64)).1;
        let sky = at(&f, 32, 2);
        let ground = at(&f, 32, 61);
        assert!(
            sky[2] > sky[0] && sky[2] > 80,
            "{altitude} m: the sky is blue: {sky:?}"
        );
        assert_ne!(sky, ground, "{altitude} m");
    }
}

/// The coverage view (ground white, sky black) shows no gap: looking straight down from 2 m and
/// from 10 km, over the north pole and on the date line, every pixel is ground; looking straight
/// up, none is.
#[test]
fn the_rings_leave_no_crack_anywhere() {
    for (lat, lon, altitude, pitch) in [
        (30.0, 10.0, 2.0, -90.0),
        (30.0, 10.0, 10_000.0, -90.0),
        (90.0, 0.0, 5.0, -90.0),
        (89.99, 77.0, 300.0, -90.0),
        (-5.0, 180.0, 50.0, -90.0),
        (-5.0, -179.9999, 3.0, -90.0),
    ] {
        let mut s = planet_scene(lat, lon, altitude, pitch, 64);
        s.camera.fov_y_deg = 90.0;
        let mut r = Renderer::new(&s, Mode::Clipmaps, View::Coverage).expect("renderer");
        let camera = terrain_engine::scene::camera_of(&s, &r.atlas).expect("camera");
        let f = r.render(&camera).expect("frame");
        let holes = pixels(&f).filter(|p| p[0] < 128).count();
        assert_eq!(
            holes, 0,
            "{lat}°, {lon}°, {altitude} m: {holes} pixels without ground"
        );
    }
    let mut up = planet_scene(30.0, 10.0, 2.0, 90.0, 64);
    up.camera.fov_y_deg = 90.0;
    let mut r = Renderer::new(&up, Mode::Clipmaps, View::Coverage).expect("renderer");
    let camera = terrain_engine::scene::camera_of(&up, &r.atlas).expect("camera");
    let f = r.render(&camera).expect("frame");
    assert_eq!(
        pixels(&f).filter(|p| p[0] > 128).count(),
        0,
        "ground seen straight up"
    );
}

/// A still camera 2 m above the ground renders the same bytes twice, from a fresh renderer and
/// from the same one.
#[test]
fn a_still_camera_renders_the_same_bytes() {
    let s = planet_scene(46.5, 9.8, 2.0, -10.0, 64);
    let (mut r, a) = render(&s);
    let camera = terrain_engine::scene::camera_of(&s, &r.atlas).expect("camera");
    let b = r.render(&camera).expect("frame");
    let c = render(&s).1;
    assert!(a.rgba == b.rgba && a.rgba == c.rgba);
}

/// A camera inside the planet, a planar mode on a planet, and clipmaps on a planar sketch are
/// refused in one line naming the key.
#[test]
fn impossible_planet_scenes_are_refused() {
    let under = Scene::parse(
        "[sketch]\nsynthetic = \"planet\"\n[camera]\nlat_deg = 0.0\nlon_deg = 0.0\naltitude_m = -5.0\n",
        manifest_dir(),
    )
    .unwrap_err()
    .to_string();
    assert!(
        under.contains("camera.altitude_m") && !under.contains('\n'),
        "{under}"
    );
    let s = planet_scene(0.0, 0.0, 100.0, 0.0, 16);
    let warped = Renderer::new(&s, Mode::Warped, View::Shaded)
        .err()
        .expect("refused")
        .to_string();
    assert!(
        warped.contains("render.mode") && warped.contains("clipmaps"),
        "{warped}"
    );
    let planar = scene(
        "[sketch]\nsynthetic = \"hills\"\n[camera]\nposition = [0.0, 0.0, 900.0]\nlook_at = [100.0, 100.0, 0.0]\n",
        manifest_dir(),
    );
    let clip = Renderer::new(&planar, Mode::Clipmaps, View::Shaded)
        .err()
        .expect("refused")
        .to_string();
    assert!(clip.contains("planet"), "{clip}");
}

/// The reference ray-marches the same planet: from orbit the clipmaps agree with it closely,
/// from 10 km within what the mesh leaves out; and it writes ground positions where it hits.
#[test]
fn the_reference_marches_the_same_planet() {
    for (altitude, pitch, at_least) in [(2e7, -90.0, 38.0), (10_000.0, -20.0, 25.0)] {
        let s = planet_scene(30.0, 10.0, altitude, pitch, 64);
        let (r, mesh) = render(&s);
        let camera = terrain_engine::scene::camera_of(&s, &r.atlas).expect("camera");
        drop(r);
        let mut reference = Renderer::new(&s, Mode::Reference, View::Shaded).expect("reference");
        let image = reference.render(&camera).expect("frame");
        let db = psnr(&mesh.rgba, &image.rgba);
        eprintln!("{altitude} m: clipmaps against the reference {db:.1} dB");
        assert!(db >= at_least, "{altitude} m: {db:.1} dB");
        let hits = reference.read_positions(&camera).expect("positions");
        let ground = hits.iter().filter(|p| p[3] > 0.5).count();
        assert!(
            ground > 0 && ground < hits.len(),
            "{altitude} m: {ground} of {} on ground",
            hits.len()
        );
    }
}

/// World positions (f64, metres from the planet's centre) of a planet frame's ground pixels.
fn world_hits(r: &Renderer, camera: &terrain_engine::Camera) -> Vec<Option<glam::DVec3>> {
    let geo = camera.geo.expect("a planet camera");
    let t = terrain_engine::planet::Tangent::at(geo.lat, geo.lon);
    let radius = terrain_engine::planet::EARTH_RADIUS_M;
    r.read_positions(camera)
        .expect("positions")
        .iter()
        .map(|p| {
            (p[3] > 0.5)
                .then(|| t.up * radius + t.world(glam::Vec3::new(p[0], p[1], p[2]).as_dvec3()))
        })
        .collect()
}

/// Moving the camera 1 m moves the picture by what the geometry predicts: each ground point a
/// pixel saw before, projected into the moved camera, is what the moved frame shows there, to a
/// median of 0.1 px (the distance between the two points, as pixels at their distance). The
/// rings move with the camera and resample the ground; this measures that and any float jitter
/// together. At 2 m over the ground, at the Earth's radius.
#[test]
fn moving_the_camera_a_metre_moves_the_picture_as_the_geometry_predicts() {
    let size = 96u32;
    let s = planet_scene(46.5, 9.8, 2.0, -35.0, size);
    let mut moved = s.clone();
    // One metre north.
    moved.camera.lat_deg =
        Some(46.5 + (1.0f64 / terrain_engine::planet::EARTH_RADIUS_M).to_degrees());
    let shot = |scene: &Scene| {
        let mut r = Renderer::new(scene, Mode::Clipmaps, View::Shaded).expect("renderer");
        let camera = terrain_engine::scene::camera_of(scene, &r.atlas).expect("camera");
        r.render(&camera).expect("frame");
        let hits = world_hits(&r, &camera);
        (camera, hits)
    };
    let (a, hits_a) = shot(&s);
    let (b, hits_b) = shot(&moved);
    // The moved camera's eye and directions in world axes, to project into.
    let frame_of = |c: &terrain_engine::Camera| {
        let geo = c.geo.unwrap();
        let t = terrain_engine::planet::Tangent::at(geo.lat, geo.lon);
        (
            t.up * terrain_engine::planet::EARTH_RADIUS_M + t.world(c.eye),
            t.world(c.forward),
            t.world(c.right),
            t.world(c.up),
        )
    };
    let (eye_a, ..) = frame_of(&a);
    let (eye_b, fwd, right, up) = frame_of(&b);
    assert!(
        ((eye_b - eye_a).length() - 1.0).abs() < 0.3,
        "moved {} m",
        (eye_b - eye_a).length()
    );
    let f = b.f_px();
    let project = |x: glam::DVec3| {
        let d = x - eye_b;
        let z = d.dot(fwd);
        glam::DVec2::new(
            size as f64 / 2.0 + f * d.dot(right) / z,
            size as f64 / 2.0 - f * d.dot(up) / z,
        )
    };
    let mut errors = Vec::new();
    for hit in &hits_a {
        let Some(x) = hit else { continue };
        let q = project(*x);
        // Where the moved frame sees that pixel's neighbourhood: the bilinear of its four hits.
        let (i, j) = ((q.x - 0.5).floor(), (q.y - 0.5).floor());
        if i < 1.0 || j < 1.0 || i >= size as f64 - 2.0 || j >= size as f64 - 2.0 {
            continue;
        }
        let at = |di: usize, dj: usize| hits_b[(j as usize + dj) * size as usize + i as usize + di];
        let (Some(p00), Some(p10), Some(p01), Some(p11)) = (at(0, 0), at(1, 0), at(0, 1), at(1, 1))
        else {
            continue;
        };
        let (fx, fy) = (q.x - 0.5 - i, q.y - 0.5 - j);
        let seen = p00.lerp(p10, fx).lerp(p01.lerp(p11, fx), fy);
        // How far the ground the moved frame shows there lies from the point, as pixels at its
        // distance: 0 if the ground stood still.
        errors.push((seen - *x).length() * f / (*x - eye_b).length());
    }
    errors.sort_by(f64::total_cmp);
    assert!(
        errors.len() > (size * size / 3) as usize,
        "{} pixels compared",
        errors.len()
    );
    let median = errors[errors.len() / 2];
    let p90 = errors[errors.len() * 9 / 10];
    eprintln!(
        "1 m north at 2 m: reprojection error median {median:.3} px, p90 {p90:.3} px over {} pixels",
        errors.len()
    );
    assert!(median <= 0.1, "median {median} px");
}

/// A global GeoTIFF as GDAL writes it (north row first, 5.625° cells; made by
/// scripts/make-planet-fixture.sh) is a planet's sketch, read the right way up: the sketch's
/// bicubic at a cell's centre is the formula's value there. A regional file is refused.
#[test]
fn a_global_geotiff_is_a_planet_and_a_regional_one_is_refused() {
    let global = |path: &str| {
        scene(
            &format!(
                "[sketch]\npath = \"{path}\"\n[planet]\n[camera]\nlat_deg = 10.0\nlon_deg = 45.0\n\
                 altitude_m = 10000000.0\npitch_deg = -90.0\nwidth = 32\nheight = 32\n"
            ),
            manifest_dir(),
        )
    };
    let s = global("tests/data/planet/global-64x32.tif");
    let atlas = terrain_engine::scene::load_atlas(&s).expect("a global sketch");
    let planet = Planet {
        radius: terrain_engine::planet::EARTH_RADIUS_M,
        sketch: &atlas,
    };
    for (i, j) in [(0usize, 0usize), (10, 5), (40, 20), (63, 31)] {
        let lon = (-180.0 + (i as f64 + 0.5) * 5.625f64).to_radians();
        let lat = (90.0 - (j as f64 + 0.5) * 5.625f64).to_radians();
        let want = 3000.0 * lat.cos() * (2.0 * lon).sin() + 1000.0 * (3.0 * lat).sin() - 500.0;
        let got = planet.sketch_height(lat, lon, 0.0).unwrap();
        assert!((got - want).abs() < 0.1, "cell ({i}, {j}): {got} vs {want}");
    }
    let (_, frame) = render(&s);
    let centre = ((16 * 32 + 16) * 4) as usize;
    assert!(
        frame.rgba[centre..centre + 3].iter().any(|&c| c > 20),
        "the disc's centre is dark"
    );
    let regional = global("tests/data/formats/bigendian-lzw-pred1-Float32.tif");
    let err = terrain_engine::scene::load_atlas(&regional)
        .expect_err("refused")
        .to_string();
    assert!(err.contains("global") && !err.contains('\n'), "{err}");
}

/// Drawing with the last frame's rings (`render_held`, what `compare` measures swimming by)
/// re-expresses the moved camera in the held nadir's frame: the held frame of a still camera is
/// the frame itself, and after a move it shows what the moved camera sees, far closer to the
/// updated frame than the unmoved picture is.
#[test]
fn held_rings_are_seen_from_where_the_camera_moved() {
    let a = planet_scene(46.5, 9.8, 3000.0, -25.0, 64);
    let mut b = a.clone();
    b.camera.lon_deg = Some(9.8 + 0.03); // 2.3 km east
    b.camera.heading_deg = Some(70.0);
    let mut r = Renderer::new(&a, Mode::Clipmaps, View::Shaded).expect("renderer");
    let (ca, cb) = (
        terrain_engine::scene::camera_of(&a, &r.atlas).expect("camera"),
        terrain_engine::scene::camera_of(&b, &r.atlas).expect("camera"),
    );
    let first = r.render(&ca).expect("frame");
    assert_eq!(r.render_held(&ca).expect("held").rgba, first.rgba);
    let held = r.render_held(&cb).expect("held");
    let updated = r.render(&cb).expect("frame");
    let (moved, unmoved) = (
        psnr(&held.rgba, &updated.rgba),
        psnr(&first.rgba, &updated.rgba),
    );
    eprintln!("held against updated {moved:.1} dB; the unmoved frame {unmoved:.1} dB");
    assert!(
        moved >= 30.0 && moved >= unmoved + 10.0,
        "{moved:.1} / {unmoved:.1} dB"
    );
}

/// Reversed-Z with an infinite far plane into a 32-bit float depth buffer (0..1, as Vulkan, Metal
/// and D3D clip): along the view ray of a camera 1 m above the ground and of one 20,000 km up,
/// every point from 1 m (or the near plane) to 30,000 km gets a depth that the f32 projection,
/// as uploaded, tells from a point 1e-5 farther: 1 cm at 1 km, 10 m at 1,000 km. Surfaces that
/// close cannot z-fight.
#[test]
fn depth_resolves_a_hundred_thousandth_from_a_metre_to_20000_km() {
    for (altitude, pitch) in [(1.0, 0.0), (1.0, 5.0), (2e7, -90.0)] {
        let s = planet_scene(46.5, 9.8, altitude, pitch, 64);
        let atlas = terrain_engine::scene::load_atlas(&s).expect("atlas");
        let camera = terrain_engine::scene::camera_of(&s, &atlas).expect("camera");
        let origin = terrain_engine::Terrain::frame_origin(&camera);
        let vp = terrain_engine::Terrain::view_proj(&camera);
        let eye = (camera.eye - origin).as_vec3();
        let depth = |d: f64| {
            let p = eye + (camera.forward * d).as_vec3();
            let clip = vp * p.extend(1.0);
            clip.z / clip.w
        };
        // From orbit nothing lies nearer than half the height over the highest ground.
        let mut d = camera.near.max(1.0);
        let mut checked = 0;
        while d < 3e7 {
            let (near, far) = (depth(d), depth(d * (1.0 + 1e-5)));
            assert!(
                near > far && far > 0.0 && near <= 1.0,
                "{altitude} m up: depth {near} at {d} m, {far} 1e-5 farther"
            );
            d *= 1.05;
            checked += 1;
        }
        assert!(checked >= 10, "{checked}");
    }
}
