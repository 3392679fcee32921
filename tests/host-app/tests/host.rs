//! The library as an application outside the repository's workspace uses it: a frame drawn with
//! the application's own device, its geometry drawn before and after the terrain, a pixel picked
//! back to the world, and views of the wrong size refused.

use host_app::{Host, Order, RED, Wall, frame};
use terrain::glam::{DVec2, DVec3, UVec2};
use terrain::readback::{depths, read_texture};
use terrain::scene::Mode;
use terrain::{Camera, Description, Error, Scene, Terrain};

const SIZE: u32 = 96;

fn jacksboro() -> Description {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../sketches/jacksboro.toml");
    Description::new(Scene::load(path.as_ref()).unwrap()).unwrap()
}

/// The ray through pixel (x, y)'s centre and the footprint scale the reference marches it with.
fn ray(camera: &Camera, x: u32, y: u32) -> (DVec3, f64) {
    let dir = camera.pixel_ray(DVec2::new(x as f64 + 0.5, y as f64 + 0.5));
    (
        dir.normalize(),
        2.0 * camera.tan_half_y() / camera.height as f64,
    )
}

/// A wall across the valley (y = 12 km, x 5–25 km, 0–3 km up), drawn before the terrain and
/// after it: either way it shows where it is nearer than the ground along a pixel's ray and is
/// hidden where the ground is nearer, and the two pictures agree.
#[test]
fn host_geometry_drawn_before_or_after_the_terrain_hides_and_is_hidden_by_depth() {
    let description = jacksboro();
    let host = Host::new(&description, SIZE, SIZE);
    let camera = description.camera(SIZE, SIZE).unwrap();
    let mut terrain =
        Terrain::new(&host.device, &host.queue, host_app::TARGETS, description).unwrap();
    let wall = Wall::new(
        &host.device,
        [
            DVec3::new(5e3, 12e3, 0.0),
            DVec3::new(25e3, 12e3, 0.0),
            DVec3::new(25e3, 12e3, 3e3),
            DVec3::new(5e3, 12e3, 3e3),
        ],
    );
    let mut pictures = Vec::new();
    for order in [Order::BeforeTheTerrain, Order::AfterTheTerrain] {
        frame(&host, &mut terrain, &camera, Some((&wall, order))).unwrap();
        let image = read_texture(&host.device, &host.queue, &host.colour).unwrap();
        let ground = terrain.ground();
        let (mut hidden, mut shown, mut wrong) = (0, 0, Vec::new());
        for y in 0..SIZE {
            for x in 0..SIZE {
                let (dir, _) = ray(&camera, x, y);
                if dir.y <= 0.0 {
                    continue;
                }
                let t_wall = (12e3 - camera.eye.y) / dir.y;
                let at = camera.eye + dir * t_wall;
                if !(5e3..=25e3).contains(&at.x) || !(0.0..=3e3).contains(&at.z) {
                    continue;
                }
                let hit = ground.ray_cast(camera.eye, dir, 0.0).unwrap();
                let t_ground = hit.map_or(f64::INFINITY, |h| h.distance(camera.eye));
                let px = &image[((y * SIZE + x) * 4) as usize..][..4];
                if t_ground < 0.95 * t_wall {
                    hidden += 1;
                    if px == RED {
                        wrong.push(format!("({x}, {y}) red behind the ground"));
                    }
                } else if t_ground > 1.05 * t_wall {
                    shown += 1;
                    if px != RED {
                        wrong.push(format!("({x}, {y}) {px:?}, the wall in front"));
                    }
                }
            }
        }
        println!("{order:?}: {shown} pixels show the wall, {hidden} hide it");
        assert!(
            hidden > 100 && shown > 100,
            "hidden {hidden}, shown {shown}"
        );
        assert!(
            wrong.len() <= (hidden + shown) / 100,
            "{order:?}: {} of {} wrong:\n{}",
            wrong.len(),
            hidden + shown,
            wrong.join("\n")
        );
        pictures.push(image);
    }
    let differing = pictures[0]
        .chunks_exact(4)
        .zip(pictures[1].chunks_exact(4))
        .filter(|(a, b)| a != b)
        .count();
    assert!(
        differing <= (SIZE * SIZE / 100) as usize,
        "drawn before and after, {differing} pixels differ"
    );
}

/// Every 5th pixel of the reference's frame picked back from its depth lies within 0.5 m of
/// where `ground().ray_cast` meets the pixel's ray; sky is picked as nothing.
#[test]
fn a_picked_pixel_is_where_the_ray_meets_the_ground() {
    let description = jacksboro().with_mode(Mode::Reference);
    let host = Host::new(&description, SIZE, SIZE);
    let camera = description.camera(SIZE, SIZE).unwrap();
    let mut terrain =
        Terrain::new(&host.device, &host.queue, host_app::TARGETS, description).unwrap();
    frame(&host, &mut terrain, &camera, None).unwrap();
    let depth = depths(&read_texture(&host.device, &host.queue, &host.depth).unwrap());
    let ground = terrain.ground();
    let (mut picked, mut sky, mut worst) = (0, 0, 0.0f64);
    for y in (0..SIZE).step_by(5) {
        for x in (0..SIZE).step_by(5) {
            let d = depth[(y * SIZE + x) as usize];
            let (dir, scale) = ray(&camera, x, y);
            let hit = ground.ray_cast(camera.eye, dir, scale).unwrap();
            match Terrain::pick(&camera, UVec2::new(x, y), d) {
                Some(p) => {
                    let hit = hit.unwrap_or_else(|| panic!("({x}, {y}) picked {p}, no hit"));
                    worst = worst.max(p.distance(hit));
                    picked += 1;
                }
                None => {
                    assert!(hit.is_none_or(|h| h.distance(camera.eye) > 0.5 * camera.far));
                    sky += 1;
                }
            }
        }
    }
    println!("{picked} pixels picked, {sky} sky; the farthest from ray_cast {worst:.3} m");
    assert!(picked > 100, "{picked} pixels show ground");
    assert!(worst <= 0.5, "a picked point {worst:.3} m from ray_cast's");
}

/// Views of another size than the prepared camera's image, or another sample count, are an
/// error naming the view and both sizes; nothing is recorded.
#[test]
fn views_of_another_size_are_an_error() {
    let description = jacksboro();
    let host = Host::new(&description, SIZE, SIZE);
    let camera = description.camera(64, 48).unwrap();
    let mut terrain =
        Terrain::new(&host.device, &host.queue, host_app::TARGETS, description).unwrap();
    let err = frame(&host, &mut terrain, &camera, None).unwrap_err();
    assert!(matches!(err, Error::Target { view: "colour", .. }), "{err}");
    let message = err.to_string();
    assert!(
        message.contains("96×96") && message.contains("64×48"),
        "{message}"
    );
    // The right colour view, a depth view of the wrong size.
    let colour = host_app::target(&host.device, host_app::TARGETS.colour, 64, 48);
    let view = colour.create_view(&Default::default());
    let (_, depth) = host.views();
    let mut encoder = host.device.create_command_encoder(&Default::default());
    let err = terrain.record(&mut encoder, &view, &depth).unwrap_err();
    assert!(matches!(err, Error::Target { view: "depth", .. }), "{err}");
}
