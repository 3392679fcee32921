//! Spherical clipmaps (`shaders/clipmaps.wgsl`): the static hemisphere's drawn rings carried to
//! the terrain each frame. [`PlanetUniforms`] is the WGSL `Planet` block (shared with
//! `shaders/planet.wgsl`); [`vertex_cpu`] is the pass's CPU twin, which the tests hold the GPU
//! to and the f64 terrain function ([`crate::planet::Planet::ground`]) holds in turn.

use crate::camera::Geo;
use crate::detail::Detail;
use crate::error::Result;
use crate::gpu::alloc::{Alloc, Buffer};
use crate::gpu::bindings::{Binding, bind_group, buffer, layout};
use crate::gpu::pipeline::compute_pipeline;
use crate::gpu::shaders::Key;
use crate::gpu::stream::AtlasBinding;
use crate::gpu::uniforms::MAX_OCTAVES;
#[cfg(test)]
use crate::planet::noise::gradient_noise3;
use crate::planet::noise::{SphereOctave, lattice_scale};
use crate::planet::rings::{Rings, Span};
use crate::planet::{Planet, Tangent};
#[cfg(test)]
use crate::sketch::cubic::catmull_rom;
use bytemuck::{Pod, Zeroable};
use glam::{DVec3, IVec2};
#[cfg(test)]
use glam::{Vec2, Vec3, Vec4};
#[cfg(test)]
use std::f64::consts::FRAC_PI_2;
use std::f64::consts::{PI, TAU};
use wgpu::ShaderStages as S;

/// One octave of the sphere's noise for one frame (WGSL `SphereOctave`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct SphereOctaveUniforms {
    pub lattice: [i32; 3],
    pub seed: u32,
    pub phase: [f32; 3],
    pub scale: f32,
    pub weight: f32,
    pub pad0: u32,
    pub pad1: u32,
    pub pad2: u32,
}

/// The planet's part of a frame (WGSL `Planet`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct PlanetUniforms {
    pub east: [f32; 3],
    pub radius: f32,
    pub north: [f32; 3],
    pub eye_m: f32,
    pub up: [f32; 3],
    pub sin_lat: f32,
    pub sun: [f32; 3],
    pub cos_lat: f32,
    pub texel_origin: [i32; 2],
    pub texel_frac: [f32; 2],
    pub texels_per_rad: [f32; 2],
    pub phi_steps: u32,
    pub rings_per_level: u32,
    pub first_vertex: u32,
    pub vertex_count: u32,
    pub nadir: u32,
    pub inner_ring: u32,
    pub levels: u32,
    pub octaves: u32,
    pub min_spacing: f32,
    pub bias: f32,
    pub water_m: f32,
    pub pad0: u32,
    pub pad1: u32,
    pub pad2: u32,
    pub octave: [SphereOctaveUniforms; MAX_OCTAVES],
}

impl PlanetUniforms {
    /// The uniform buffer a pass reads the block from (the clipmaps' and the reference's).
    pub fn buffer(alloc: &Alloc) -> Buffer {
        alloc.create_buffer(&wgpu::BufferDescriptor {
            label: Some("planet uniforms"),
            size: std::mem::size_of::<PlanetUniforms>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        })
    }

    /// The block for a camera at `geo`, the sun toward `sun` (the nadir's east, north, up); the
    /// rings' fields stay 0 until [`draw`](PlanetUniforms::draw) (the reference reads none).
    pub fn new(
        planet: &Planet,
        detail: &Detail,
        geo: &Geo,
        eye_m: f64,
        sun: DVec3,
    ) -> PlanetUniforms {
        let t = Tangent::at(geo.lat, geo.lon);
        let texel = planet.texel(geo.lat, geo.lon);
        // Longitude's texel wraps: keep the nadir's whole texel within the sketch's width.
        let w = planet.sketch.width() as f64;
        let whole = texel.floor();
        let origin = IVec2::new(whole.x.rem_euclid(w) as i32, whole.y as i32);
        let mut octave = [SphereOctaveUniforms::default(); MAX_OCTAVES];
        let anchor = t.up * planet.radius;
        for (k, o) in (1..=detail.octaves).zip(octave.iter_mut()) {
            let s = SphereOctave::split(
                anchor,
                lattice_scale(detail.d_atlas, k),
                detail.weight(k),
                detail.octave_seed(k),
            );
            *o = SphereOctaveUniforms {
                lattice: s.lattice.to_array(),
                seed: s.seed,
                phase: s.phase.to_array(),
                scale: s.scale,
                weight: s.weight,
                ..Default::default()
            };
        }
        PlanetUniforms {
            east: t.east.as_vec3().to_array(),
            radius: planet.radius as f32,
            north: t.north.as_vec3().to_array(),
            eye_m: eye_m as f32,
            up: t.up.as_vec3().to_array(),
            sin_lat: geo.lat.sin() as f32,
            sun: sun.normalize().as_vec3().to_array(),
            cos_lat: geo.lat.cos() as f32,
            texel_origin: origin.to_array(),
            texel_frac: (texel - whole).as_vec2().to_array(),
            texels_per_rad: [
                (w / TAU) as f32,
                (planet.sketch.height() as f64 / PI) as f32,
            ],
            phi_steps: 0,
            rings_per_level: 0,
            first_vertex: 0,
            vertex_count: 0,
            nadir: 0,
            inner_ring: 0,
            levels: planet.usable_levels() as u32,
            octaves: detail.octaves.min(24),
            min_spacing: 0.0,
            bias: detail.bias as f32,
            water_m: planet.sketch.water_m,
            pad0: 0,
            pad1: 0,
            pad2: 0,
            octave,
        }
    }

    /// The rings' fields for drawing `span` of `rings` with a planet of `radius` metres.
    pub fn draw(&mut self, rings: &Rings, span: Span, radius: f64) {
        let range = rings.vertex_range(span);
        let m = rings.rings_per_level;
        let inner_ring = (span.last_level + 1) * m;
        let a = crate::planet::rings::ring_angle(inner_ring, m);
        let spacing = radius
            * (a * ((1.0 / m as f64).exp2() - 1.0)).max(a.sin() * TAU / rings.phi_steps as f64);
        self.phi_steps = rings.phi_steps;
        self.rings_per_level = m;
        self.first_vertex = range.start;
        self.vertex_count = range.end - range.start;
        self.nadir = rings.nadir();
        self.inner_ring = inner_ring;
        self.min_spacing = spacing as f32;
    }
}

/// The pass's shader, `shaders/clipmaps.wgsl`.
pub const SHADER: crate::gpu::pipeline::Shader = shader!("clipmaps", BINDINGS);

/// `shaders/clipmaps.wgsl`'s bindings.
pub const BINDINGS: &[Binding] = &[
    Binding::frame(S::COMPUTE),
    Binding::atlas(S::COMPUTE),
    Binding::wanted(S::COMPUTE),
    Binding::work(S::COMPUTE),
    Binding::sun_seen(S::COMPUTE),
    // Declared where the shading it imports draws a ramp (never set for this pass's scenes).
    Binding::ramp(S::COMPUTE),
    Binding::drape(S::COMPUTE),
    Binding::uniform(2, "planet", S::COMPUTE),
    Binding::storage(3, "hemisphere", S::COMPUTE),
    Binding::storage_rw(4, "vertices", S::COMPUTE),
];

pub struct ClipmapsPass {
    pipeline: wgpu::ComputePipeline,
    bind_group: wgpu::BindGroup,
    /// The static hemisphere, per vertex (sin θ̃ sin φ̃, sin θ̃ cos φ̃, 1 − cos θ̃, θ̃).
    pub hemisphere: Buffer,
    /// The frame's vertices: (x, y, z) in the nadir's tangent frame and the height before the
    /// sea covers it.
    pub vertices: Buffer,
}

impl ClipmapsPass {
    /// The pass's name: its timer key, its `passes_ms` key, its WGSL file.
    pub const NAME: &'static str = SHADER.name;

    pub fn new(
        device: &Alloc,
        frame: &wgpu::Buffer,
        atlas: &AtlasBinding,
        planet: &wgpu::Buffer,
        rings: &Rings,
        key: Key,
    ) -> Result<ClipmapsPass> {
        let name = Self::NAME;
        let layout = layout(device, name, BINDINGS, 0, key);
        let pipeline = compute_pipeline(device, &SHADER, key, &layout)?;
        let points: Vec<[f32; 4]> = rings.vertices.iter().map(|v| v.to_array()).collect();
        let hemisphere = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("hemisphere"),
            contents: bytemuck::cast_slice(&points),
            usage: wgpu::BufferUsages::STORAGE,
        });
        let vertices = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("clipmap vertices"),
            size: rings.vertices.len() as u64 * 16,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let mut resources = atlas.resources();
        resources.extend([
            ("frame", buffer(frame)),
            ("planet", buffer(planet)),
            ("hemisphere", buffer(&hemisphere)),
            ("vertices", buffer(&vertices)),
        ]);
        let bind_group = bind_group(device, name, &layout, BINDINGS, 0, key, &resources)?;
        Ok(ClipmapsPass {
            pipeline,
            bind_group,
            hemisphere,
            vertices,
        })
    }

    /// Records the pass for `count` ring vertices and the nadir.
    pub fn record(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        count: u32,
        probe: crate::gpu::counters::Probe,
    ) {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(Self::NAME),
            timestamp_writes: probe.compute(Self::NAME),
        });
        probe.begin_compute(&mut pass, Self::NAME, 0);
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &self.bind_group, &[]);
        pass.dispatch_workgroups((count + 1).div_ceil(64), 1, 1);
        probe.end_compute(&mut pass);
    }
}

#[cfg(test)]
/// `map_offset` and `planet_texel_of` in the shader: the hemisphere point's level-0 texel
/// relative to the nadir's whole texel.
fn texel_of(u: &PlanetUniforms, v: Vec4) -> Vec2 {
    let d = crate::planet::map_offset(u.sin_lat, u.cos_lat, v);
    Vec2::from(u.texel_frac) + Vec2::new(d.y, d.x) * Vec2::from(u.texels_per_rad)
}

#[cfg(test)]
/// `planet_level` in the shader.
fn planet_level(planet: &Planet, u: &PlanetUniforms, t: Vec2, l: usize) -> Result<f32> {
    let s = (1u32 << l) as f32;
    let origin = IVec2::from(u.texel_origin);
    let mask = IVec2::splat((1 << l) - 1);
    let base = origin >> IVec2::splat(l as i32);
    let x = ((origin & mask).as_vec2() + t - Vec2::splat((s - 1.0) * 0.5)) / s;
    let c = x.floor();
    let f = x - c;
    let i = base + c.as_ivec2();
    let (wx, wy) = (catmull_rom(f.x), catmull_rom(f.y));
    let mut h = 0.0;
    for (r, wyr) in wy.iter().enumerate() {
        let j = i.y - 1 + r as i32;
        let mut row = 0.0;
        for (c, wxc) in wx.iter().enumerate() {
            row += wxc * planet.texel_value((i.x - 1 + c as i32) as i64, j as i64, l)?;
        }
        h += wyr * row;
    }
    Ok(h)
}

#[cfg(test)]
/// `ring_spacing` in the shader.
fn ring_spacing(u: &PlanetUniforms, a: f32) -> f32 {
    let across = a * ((1.0 / u.rings_per_level as f32).exp2() - 1.0);
    let along = a.sin() * std::f32::consts::TAU / u.phi_steps as f32;
    (u.radius * across.max(along)).max(u.min_spacing)
}

#[cfg(test)]
/// The clipmaps pass's vertex for hemisphere point `v` (CPU twin of `clipmaps.wgsl`'s `main`).
pub fn vertex_cpu(planet: &Planet, atlas_d: f32, u: &PlanetUniforms, v: Vec4) -> Result<Vec4> {
    let spacing = ring_spacing(u, v.w);
    let t = texel_of(u, v);
    let lod = (spacing.max(1e-6) / atlas_d)
        .log2()
        .clamp(0.0, (u.levels - 1) as f32);
    let l0 = lod as usize;
    let a = planet_level(planet, u, t, l0)?;
    let f = lod - l0 as f32;
    let mut h = if f <= 0.0 || l0 + 1 >= u.levels as usize {
        a
    } else {
        a + (planet_level(planet, u, t, l0 + 1)? - a) * f
    };
    let o = (atlas_d / spacing).log2() - u.bias;
    let rel =
        u.radius * (v.x * Vec3::from(u.east) + v.y * Vec3::from(u.north) - v.z * Vec3::from(u.up));
    let last = u.octaves.min(o.ceil().max(0.0) as u32);
    for k in 1..=last {
        let oc = &u.octave[k as usize - 1];
        let g = (o - k as f32 + 1.0).clamp(0.0, 1.0);
        let q = rel * oc.scale + Vec3::from(oc.phase);
        let c = q.floor();
        let (n, _) = gradient_noise3(glam::IVec3::from(oc.lattice) + c.as_ivec3(), q - c, oc.seed);
        h += oc.weight * g * n;
    }
    let ground = h.max(u.water_m);
    let rh = u.radius + ground;
    Ok(Vec4::new(rh * v.x, rh * v.y, ground - rh * v.z, h))
}

#[cfg(test)]
/// The geographic position of hemisphere point (angle `a`, bearing `b`) seen from `geo`
/// (radians), in f64: where [`vertex_cpu`]'s point should lie.
pub fn lat_lon_of(geo: &Geo, a: f64, b: f64) -> (f64, f64) {
    let t = Tangent::at(geo.lat, geo.lon);
    let (sa, ca) = a.sin_cos();
    let u = t.up * ca + (t.north * b.cos() + t.east * b.sin()) * sa;
    let (lat, lon) = crate::planet::lat_lon(u);
    (lat.clamp(-FRAC_PI_2, FRAC_PI_2), lon)
}
