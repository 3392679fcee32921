//! The host API: a test opens its own device, creates its own colour and depth textures, and
//! draws a bundled scene into them through `terrain::Terrain`, the front door; the bytes equal `terrain
//! render`'s. A host's own geometry around the terrain, picking and size errors are tested as an
//! application outside the workspace meets them, in `tests/host-app`.

// The test is the host: it creates its own textures and buffers, outside the library's ledger.
#![allow(clippy::disallowed_methods)]

mod common;
use common::*;
use terrain::scene::Scene;
use terrain::{Description, Targets, Terrain, clear};
use terrain_engine::scene;

const SIZE: u32 = 96;
const TARGETS: Targets = Targets {
    colour: wgpu::TextureFormat::Rgba8UnormSrgb,
    depth: wgpu::TextureFormat::Depth32Float,
    samples: 1,
};

/// The host's own device, made as the host API asks.
fn host_device(description: &Description) -> (wgpu::Device, wgpu::Queue) {
    let instance =
        wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
    let adapter = pollster::block_on(instance.request_adapter(&Default::default()))
        .expect("an adapter (llvmpipe where there is no GPU)");
    pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
        label: Some("host"),
        required_features: Description::optional_features(adapter.features()),
        required_limits: description.required_limits(),
        ..Default::default()
    }))
    .expect("a device")
}

fn target(device: &wgpu::Device, format: wgpu::TextureFormat) -> wgpu::Texture {
    device.create_texture(&wgpu::TextureDescriptor {
        label: Some("host target"),
        size: wgpu::Extent3d {
            width: SIZE,
            height: SIZE,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    })
}

/// RGBA8 of `texture`, rows top first.
fn read(device: &wgpu::Device, queue: &wgpu::Queue, texture: &wgpu::Texture) -> Vec<u8> {
    terrain::readback::read_texture(device, queue, texture).unwrap()
}

fn jacksboro() -> Scene {
    Scene::load(&manifest_dir().join("sketches/jacksboro.toml")).unwrap()
}

#[test]
fn a_host_texture_holds_the_bytes_terrain_render_writes() {
    let scene = manifest_dir().join("sketches/jacksboro.toml");
    let rendered = rendered_rgba(&scene, &scratch("host-bytes"), SIZE);

    let description = Description::new(jacksboro()).unwrap();
    let (device, queue) = host_device(&description);
    let camera = description.camera(SIZE, SIZE).unwrap();
    let mut terrain = Terrain::new(&device, &queue, TARGETS, description).unwrap();
    let colour = target(&device, TARGETS.colour);
    let depth = target(&device, TARGETS.depth);
    terrain.prepare(&camera).unwrap();
    let mut encoder = device.create_command_encoder(&Default::default());
    let view = |t: &wgpu::Texture| t.create_view(&Default::default());
    let (cv, dv) = (view(&colour), view(&depth));
    clear(&mut encoder, &cv, &dv);
    terrain.record(&mut encoder, &cv, &dv).unwrap();
    queue.submit([encoder.finish()]);
    let drawn = read(&device, &queue, &colour);
    assert_eq!(drawn.len(), rendered.len());
    let differing = drawn.iter().zip(&rendered).filter(|(a, b)| a != b).count();
    assert_eq!(
        differing, 0,
        "{differing} bytes differ from terrain render's"
    );
    // And the read-back helper gives the same.
    assert_eq!(terrain.render_to_image(&camera).unwrap(), drawn);
    // As does the read-back that does not wait (a browser's), once the device is polled.
    let readback = terrain::readback::Readback::new(&device, &colour).unwrap();
    let mut encoder = device.create_command_encoder(&Default::default());
    readback.record(&mut encoder, &colour).unwrap();
    queue.submit([encoder.finish()]);
    let (send, got) = std::sync::mpsc::channel();
    readback.read_rgba_later(move |texels| send.send(texels).unwrap());
    device.poll(wgpu::PollType::wait_indefinitely()).unwrap();
    assert_eq!(got.recv().unwrap().unwrap(), drawn);
}

/// A planet through the same API: the clipmaps' frame in the host's texture is `terrain render`'s.
#[test]
fn a_planet_draws_through_the_host_api_as_terrain_render_draws_it() {
    let path = manifest_dir().join("sketches/planet-10km.toml");
    let rendered = rendered_rgba(&path, &scratch("host-planet"), SIZE);
    let description = Description::new(Scene::load(&path).unwrap()).unwrap();
    let (device, queue) = host_device(&description);
    let camera = description.camera(SIZE, SIZE).unwrap();
    let mut terrain = Terrain::new(&device, &queue, TARGETS, description).unwrap();
    let drawn = terrain.render_to_image(&camera).unwrap();
    let differing = drawn.iter().zip(&rendered).filter(|(a, b)| a != b).count();
    assert_eq!(
        differing, 0,
        "{differing} bytes differ from terrain render's"
    );
}

/// A streamed tile pyramid through the same API: frame after frame the tiles the shaders marked
/// arrive, and the host's image settles on the one `terrain render` waits for.
#[test]
fn a_streamed_pyramid_settles_through_the_host_api_on_terrain_renders_image() {
    let dir = scratch("host-pyramid");
    // A pool too small to pin the whole pyramid: level 0 streams.
    let scene_path = streamed_jacksboro(&dir, "\n[stream]\ngpu_mb = 8\n");
    let settled = rendered_rgba(&scene_path, &dir, SIZE);

    let description = Description::new(Scene::load(&scene_path).unwrap()).unwrap();
    let (device, queue) = host_device(&description);
    let camera = description.camera(SIZE, SIZE).unwrap();
    let mut terrain = Terrain::new(&device, &queue, TARGETS, description).unwrap();
    let first = terrain.render_to_image(&camera).unwrap();
    let mut frames = 1;
    let mut last = first.clone();
    while last != settled && frames < 400 {
        last = terrain.render_to_image(&camera).unwrap();
        frames += 1;
    }
    assert_ne!(first, settled, "the first frame had every tile already");
    assert_eq!(last, settled, "not settled after {frames} frames");
}

/// A new image size remakes the frame's targets alone: in every mode, forward multisampled and
/// deferred, the frame at the new size equals a fresh renderer's at that size, the baselines'
/// baked grid is not baked again, and going back to the first size holds the GPU memory it held
/// then (the old targets are freed). Through the host API the same: its image at the new size is
/// a fresh terrain's.
#[test]
fn a_new_size_remakes_the_targets_alone() {
    use terrain::View;
    use terrain::scene::{Mode, Msaa};
    use terrain_engine::Renderer;
    let planet = Scene::load(&manifest_dir().join("sketches/planet-10km.toml")).unwrap();
    let mut cases = vec![(planet, Mode::Clipmaps)];
    for msaa in [Msaa::Off, Msaa::X4] {
        for mode in [Mode::Warped, Mode::Geomipmap, Mode::Reference] {
            let mut s = jacksboro();
            s.render.msaa = msaa;
            cases.push((s, mode));
        }
    }
    let sized = |s: &Scene, (w, h): (u32, u32)| {
        let mut s = s.clone();
        (s.camera.width, s.camera.height) = (w, h);
        s
    };
    for (scene, mode) in cases {
        let (first, second) = (sized(&scene, (64, 64)), sized(&scene, (72, 40)));
        let mut r = Renderer::new(&first, mode, View::Shaded).unwrap();
        let camera_of = |s: &Scene| scene::camera_of(s, &r.atlas).unwrap();
        let (camera_1, camera_2) = (camera_of(&first), camera_of(&second));
        r.render(&camera_1).unwrap();
        let (bytes, baked) = (r.gpu_bytes(), r.precompute());
        // The warped mode's stage holds its warp for a still camera; a fresh one has none.
        r.forget();
        let resized = r.render(&camera_2).unwrap().rgba;
        let mut fresh = Renderer::new(&second, mode, View::Shaded).unwrap();
        let expected = fresh.render(&camera_2).unwrap().rgba;
        assert_eq!(resized.len(), 72 * 40 * 4, "{mode}");
        let differing = resized
            .iter()
            .zip(&expected)
            .filter(|(a, b)| a != b)
            .count();
        assert_eq!(
            differing, 0,
            "{mode}, msaa {}: {differing} bytes differ",
            r.samples
        );
        assert_eq!(r.precompute(), baked, "{mode}");
        r.render(&camera_1).unwrap();
        assert_eq!(
            r.gpu_bytes(),
            bytes,
            "{mode}: memory back at the first size"
        );
    }

    let description = Description::new(jacksboro())
        .unwrap()
        .with_mode(Mode::Geomipmap);
    let (device, queue) = host_device(&description);
    let camera = |w, h| description.camera(w, h).unwrap();
    let (camera_1, camera_2) = (camera(64, 64), camera(72, 40));
    let fresh_description = description.clone();
    let mut terrain = Terrain::new(&device, &queue, TARGETS, description).unwrap();
    terrain.render_to_image(&camera_1).unwrap();
    let resized = terrain.render_to_image(&camera_2).unwrap();
    let mut fresh = Terrain::new(&device, &queue, TARGETS, fresh_description).unwrap();
    assert_eq!(resized, fresh.render_to_image(&camera_2).unwrap());
}
