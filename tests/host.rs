//! The host API: a test opens its own device, creates its own colour and depth textures, and
//! draws a bundled scene into them through `terrain::Terrain`; the bytes equal `terrain
//! render`'s. Then a host object of its own, drawn after the terrain with the terrain's
//! view-projection and depth, shows only where the terrain does not hide it.

// The test is the host: it creates its own textures and buffers, outside the library's ledger.
#![allow(clippy::disallowed_methods)]

mod common;
use common::*;
use glam::DVec3;
use terrain::Ground;
use terrain::scene::{self, Scene};
use terrain::{Description, Targets, Terrain, clear};

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
    let row = (SIZE * 4).div_ceil(256) * 256;
    let buffer = device.create_buffer(&wgpu::BufferDescriptor {
        label: None,
        size: (row * SIZE) as u64,
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    let mut encoder = device.create_command_encoder(&Default::default());
    encoder.copy_texture_to_buffer(
        texture.as_image_copy(),
        wgpu::TexelCopyBufferInfo {
            buffer: &buffer,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(row),
                rows_per_image: None,
            },
        },
        texture.size(),
    );
    queue.submit([encoder.finish()]);
    buffer
        .slice(..)
        .map_async(wgpu::MapMode::Read, |r| r.unwrap());
    device.poll(wgpu::PollType::wait_indefinitely()).unwrap();
    let bytes = buffer.slice(..).get_mapped_range().unwrap();
    (0..SIZE as usize)
        .flat_map(|y| bytes[y * row as usize..][..SIZE as usize * 4].to_vec())
        .collect()
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
}

/// A host's wall standing across the valley, beyond the near ridges: red, flat.
const WALL: &str = r#"
@group(0) @binding(0) var<uniform> view_proj: mat4x4<f32>;
@vertex
fn vs(@location(0) p: vec3<f32>) -> @builtin(position) vec4<f32> {
    return view_proj * vec4<f32>(p, 1.0);
}
@fragment
fn fs() -> @location(0) vec4<f32> {
    return vec4<f32>(1.0, 0.0, 0.0, 1.0);
}
"#;

#[test]
fn the_terrains_depth_hides_a_host_object_where_the_terrain_is_nearer() {
    let scene = jacksboro();
    let description = Description::new(scene.clone()).unwrap();
    let (device, queue) = host_device(&description);
    let camera = description.camera(SIZE, SIZE).unwrap();
    let mut terrain = Terrain::new(&device, &queue, TARGETS, description).unwrap();
    let colour = target(&device, TARGETS.colour);
    let depth = target(&device, TARGETS.depth);

    // The wall: y = 12 km, x 5–25 km, from 0 to 3 km up, relative to the frame's origin.
    let origin = Terrain::frame_origin(&camera);
    let corner = |x: f64, z: f64| (DVec3::new(x, 12_000.0, z) - origin).as_vec3().to_array();
    let quad: [[f32; 3]; 6] = [
        corner(5e3, 0.0),
        corner(25e3, 0.0),
        corner(25e3, 3e3),
        corner(5e3, 0.0),
        corner(25e3, 3e3),
        corner(5e3, 3e3),
    ];
    let vertices = wgpu::util::DeviceExt::create_buffer_init(
        &device,
        &wgpu::util::BufferInitDescriptor {
            label: Some("wall"),
            contents: bytemuck::cast_slice(&quad),
            usage: wgpu::BufferUsages::VERTEX,
        },
    );
    let matrix = Terrain::view_proj(&camera).to_cols_array();
    let uniform = wgpu::util::DeviceExt::create_buffer_init(
        &device,
        &wgpu::util::BufferInitDescriptor {
            label: Some("view_proj"),
            contents: bytemuck::cast_slice(&matrix),
            usage: wgpu::BufferUsages::UNIFORM,
        },
    );
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("wall"),
        source: wgpu::ShaderSource::Wgsl(WALL.into()),
    });
    let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some("wall"),
        layout: None,
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some("vs"),
            compilation_options: Default::default(),
            buffers: &[Some(wgpu::VertexBufferLayout {
                array_stride: 12,
                step_mode: wgpu::VertexStepMode::Vertex,
                attributes: &wgpu::vertex_attr_array![0 => Float32x3],
            })],
        },
        fragment: Some(wgpu::FragmentState {
            module: &module,
            entry_point: Some("fs"),
            compilation_options: Default::default(),
            targets: &[Some(TARGETS.colour.into())],
        }),
        primitive: Default::default(),
        depth_stencil: Some(wgpu::DepthStencilState {
            format: TARGETS.depth,
            depth_write_enabled: Some(true),
            depth_compare: Some(wgpu::CompareFunction::GreaterEqual),
            stencil: Default::default(),
            bias: Default::default(),
        }),
        multisample: Default::default(),
        multiview_mask: None,
        cache: None,
    });
    let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &pipeline.get_bind_group_layout(0),
        entries: &[wgpu::BindGroupEntry {
            binding: 0,
            resource: uniform.as_entire_binding(),
        }],
    });

    terrain.prepare(&camera).unwrap();
    let mut encoder = device.create_command_encoder(&Default::default());
    let (cv, dv) = (
        colour.create_view(&Default::default()),
        depth.create_view(&Default::default()),
    );
    clear(&mut encoder, &cv, &dv);
    terrain.record(&mut encoder, &cv, &dv).unwrap();
    {
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("host geometry"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &cv,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Load,
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &dv,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Load,
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &bind_group, &[]);
        pass.set_vertex_buffer(0, vertices.slice(..));
        pass.draw(0..6, 0..1);
    }
    queue.submit([encoder.finish()]);
    let image = read(&device, &queue, &colour);

    // Each pixel's ray: where the terrain (the reference's surface) and the wall lie along it.
    let atlas = scene::load_atlas(&scene).unwrap();
    let detail = scene::detail_of(&scene, &atlas);
    let ground = Ground::new(&scene, &atlas, &detail);
    let (mut hidden, mut shown, mut wrong) = (0, 0, Vec::new());
    for y in 0..SIZE {
        for x in 0..SIZE {
            let ndc = [
                (x as f64 + 0.5) / SIZE as f64 * 2.0 - 1.0,
                1.0 - (y as f64 + 0.5) / SIZE as f64 * 2.0,
            ];
            let dir = (camera.forward
                + camera.right * ndc[0] * camera.tan_half_x()
                + camera.up * ndc[1] * camera.tan_half_y())
            .normalize();
            if dir.y <= 0.0 {
                continue;
            }
            let t_wall = (12_000.0 - camera.eye.y) / dir.y;
            let at = camera.eye + dir * t_wall;
            if !(5e3..=25e3).contains(&at.x) || !(0.0..=3e3).contains(&at.z) {
                continue;
            }
            let hit = ground.ray_cast(camera.eye, dir, 0.0).unwrap();
            let t_ground = hit.map_or(f64::INFINITY, |h| h.distance(camera.eye));
            let px = &image[((y * SIZE + x) * 4) as usize..][..4];
            let red = px[0] == 255 && px[1] == 0 && px[2] == 0;
            if t_ground < 0.95 * t_wall {
                hidden += 1;
                if red {
                    wrong.push(format!(
                        "({x}, {y}) red, the terrain {t_ground:.0} m, the wall {t_wall:.0} m"
                    ));
                }
            } else if t_ground > 1.05 * t_wall {
                shown += 1;
                if !red {
                    wrong.push(format!(
                        "({x}, {y}) not red: {px:?}, the wall {t_wall:.0} m in front"
                    ));
                }
            }
        }
    }
    assert!(
        hidden > 100 && shown > 100,
        "hidden {hidden}, shown {shown}: move the wall"
    );
    assert!(
        wrong.len() <= (hidden + shown) / 100,
        "{} of {}:\n{}",
        wrong.len(),
        hidden + shown,
        wrong.join("\n")
    );
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
    use terrain::scene::{Mode, Msaa};
    use terrain::{Renderer, View};
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
