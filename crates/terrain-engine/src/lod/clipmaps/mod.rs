//! Spherical clipmaps (Clasen & Hege, *Terrain Rendering using Spherical Clipmaps* (2006)): a
//! planet drawn from the static hemisphere of rings around the camera's nadir. A frame: choose the
//! levels the view needs (§4.5), fill the planet's uniforms, then two named passes: `clipmaps`
//! carries the drawn rings' vertices to the terrain, `planet` draws the sky and them.
//!
//! Rules: the hemisphere is built once per renderer and never uploaded again; the sun stands
//! still in the world (where the scene's camera sees it at `light.sun_azimuth_deg` and
//! `light.sun_elevation_deg`), so a flight across the planet meets the terminator; a frame's
//! positions are metres in the nadir's tangent frame, never a planet-sized f32.

pub mod pass;
pub mod planet;
#[cfg(test)]
mod tests;

use super::{CpuTimes, Lod, Shared};
use crate::camera::{Camera, Geo};
use crate::detail::Detail;
use crate::error::{Error, Result};
use crate::gpu::alloc::Buffer;
use crate::gpu::context::GpuContext;
use crate::gpu::counters::Probe;
use crate::gpu::shaders::Key;
use crate::gpu::uniforms::FrameInputs;
use crate::planet::rings::{Rings, Span, visible_span};
use crate::planet::{Planet, Tangent};
use crate::sketch::Atlas;
use glam::DVec3;
use pass::{ClipmapsPass, PlanetUniforms};
use planet::PlanetPass;
use std::any::Any;
use web_time::Instant;

const PASSES: [&str; 2] = [ClipmapsPass::NAME, PlanetPass::NAME];

/// Spherical clipmaps (Clasen & Hege, *Terrain Rendering using Spherical Clipmaps*, 2006): a
/// planet drawn with rings of vertices around the camera's nadir.
pub struct Clipmaps {
    /// The rings of vertices around the nadir, built once (`planet.phi_steps`,
    /// `planet.rings_per_level`).
    pub rings: Rings,
    radius: f64,
    detail: Detail,
    /// Toward the sun, world axes.
    sun_world: DVec3,
    planet_uniforms: Buffer,
    clipmaps: ClipmapsPass,
    pass: PlanetPass,
    /// The last frame's levels and uniforms.
    pub span: Span,
    /// The last frame's planet uniform block; `None` before the first frame.
    pub uniforms: Option<PlanetUniforms>,
    /// The nadir the last frame's rings stand around.
    geo: Option<Geo>,
}

/// Spherical clipmaps' scheme. `compare` sweeps φ steps 128, 256, 512, 1024 at 20 rings per
/// level, rings per level 10 and 40 at 512 φ steps (the paper's n and m, 8× and 4× triangles end
/// to end), and the paper's triangles split the other ways, 256 × 40 and 128 × 80
/// (`planet.phi_steps`, `planet.rings_per_level`).
pub(crate) const SCHEME: super::Scheme = super::Scheme {
    build: |s| Ok(Box::new(Clipmaps::new(s)?)),
    needs: <Clipmaps as Lod>::needs,
    flags: |s, key| {
        super::bump_flags(s, key, super::bump(s));
        // Its view distances, for the output pass, in the frame's own pass.
        key.set(Key::POSITIONS, true);
    },
    sweep: |_, _, _| {
        let paper = [128, 256, 512, 1024].map(|phi| (phi, 20));
        let other = [(512, 10), (512, 40), (256, 40), (128, 80)];
        Ok(paper
            .into_iter()
            .chain(other)
            .map(|(phi, rings)| vec![phi as f64, rings as f64])
            .collect())
    },
    shaders: &[pass::SHADER, planet::SHADER],
    setting: |scene, _| {
        let p = scene.planet()?;
        Some(vec![p.phi_steps as f64, p.rings_per_level as f64])
    },
};

impl Clipmaps {
    /// The scheme of a planet scene; [`crate::Error::Value`] where the scene is no planet.
    pub fn new(s: &Shared) -> Result<Clipmaps> {
        let p = s.scene.planet().ok_or(Error::value(
            "render.mode",
            "clipmaps draws planet scenes (add [planet])",
        ))?;
        s.atlas_binding.check_vertex_marks(
            s.ctx,
            "sketch.path",
            "a planet",
            "give the file it was converted from",
        )?;
        let rings = Rings::new(p.phi_steps, p.rings_per_level);
        let device = &s.alloc;
        let planet_uniforms = PlanetUniforms::buffer(device);
        let key = super::shader_key(s, crate::scene::Mode::Clipmaps);
        let clipmaps = ClipmapsPass::new(
            device,
            s.frame,
            s.atlas_binding,
            &planet_uniforms,
            &rings,
            key,
        )?;
        let size = (s.scene.camera.width, s.scene.camera.height);
        let pass = PlanetPass::new(
            device,
            s.frame,
            s.atlas_binding,
            &planet_uniforms,
            &clipmaps.hemisphere,
            &clipmaps.vertices,
            &rings,
            size,
            key,
        )?;
        Ok(Clipmaps {
            rings,
            radius: p.radius_m,
            detail: s.detail.clone(),
            sun_world: sun_world(s.scene),
            planet_uniforms,
            clipmaps,
            pass,
            span: Span {
                first_level: 0,
                last_level: 0,
            },
            uniforms: None,
            geo: None,
        })
    }

    /// The planet's vertices of the last frame, read back (for tests).
    pub fn read_vertices(&self, ctx: &GpuContext) -> Result<Vec<[f32; 4]>> {
        crate::gpu::frame_io::read_vec4(ctx, &self.clipmaps.vertices)
    }
}

/// Toward the sun in world axes: where the scene's camera sees it at `light.sun_azimuth_deg`
/// and `light.sun_elevation_deg` (or the time's), fixed for the whole planet.
pub fn sun_world(scene: &crate::scene::Scene) -> DVec3 {
    let c = &scene.camera;
    let (lat, lon) = (
        c.lat_deg.unwrap_or(0.0).to_radians(),
        c.lon_deg.unwrap_or(0.0).to_radians(),
    );
    let (az, el) = scene.light.sun_deg();
    let (az, el) = (az.to_radians(), el.to_radians());
    let local = DVec3::new(el.cos() * az.sin(), el.cos() * az.cos(), el.sin());
    Tangent::at(lat, lon).world(local)
}

/// The planet's uniforms for `camera` (at `geo`) over `atlas`, the planet's global sketch; the
/// rings' fields are the clipmaps' to fill.
pub fn plan(
    atlas: &Atlas,
    radius: f64,
    detail: &Detail,
    sun_world: DVec3,
    camera: &Camera,
    geo: &Geo,
) -> PlanetUniforms {
    let planet = Planet {
        radius,
        sketch: atlas,
    };
    let sun = Tangent::at(geo.lat, geo.lon).local(sun_world);
    PlanetUniforms::new(&planet, detail, geo, camera.eye.z, sun)
}

/// `camera` expressed in the tangent frame of the nadir at `geo` instead of its own: how the
/// rings built around `geo` look from where the camera is now. f64 throughout: the two nadirs'
/// frames meet at the planet's scale.
pub fn reframed(camera: &Camera, geo: Geo, radius: f64) -> Camera {
    let Some(own) = camera.geo else {
        return camera.clone();
    };
    let (from, to) = (Tangent::at(own.lat, own.lon), Tangent::at(geo.lat, geo.lon));
    let origin =
        (crate::planet::unit(own.lat, own.lon) - crate::planet::unit(geo.lat, geo.lon)) * radius;
    let direction = |d: DVec3| to.local(from.world(d));
    Camera {
        eye: to.local(origin + from.world(camera.eye)),
        forward: direction(camera.forward),
        right: direction(camera.right),
        up: direction(camera.up),
        geo: Some(geo),
        ..camera.clone()
    }
}

/// The levels `camera` (at `geo`) sees of the planet (Clasen & Hege 2006, §4.5).
fn levels(atlas: &Atlas, radius: f64, detail: &Detail, camera: &Camera, geo: &Geo) -> Span {
    let planet = Planet {
        radius,
        sketch: atlas,
    };
    let eye_m = camera.eye.z;
    // The lowest surface is the sea's where the sketch dips below it.
    let low = (atlas.min_m as f64 - detail.reach_m()).max(atlas.water_m as f64);
    // A streamed sketch's tile that cannot be read fails the tile cache's loads, which end the
    // frame with its error; until then the levels take the lowest surface.
    let ground = planet.ground(detail, geo.lat, geo.lon, 0.01).unwrap_or(low);
    let high = atlas.max_m as f64 + detail.reach_m();
    let pixel_rad = camera.fov_y / camera.height as f64;
    visible_span(radius, eye_m - low, high - low, eye_m - ground, pixel_rad)
}

impl Lod for Clipmaps {
    fn passes(&self) -> &'static [&'static str] {
        &PASSES
    }

    /// The hemisphere's vertices carried to the terrain: a vec4 each.
    fn needs(scene: &crate::scene::Scene) -> u64 {
        scene.planet().map_or(0, |p| {
            crate::planet::rings::vertex_count(p.phi_steps, p.rings_per_level) * 16
        })
    }

    fn resize(&mut self, alloc: &crate::gpu::alloc::Alloc, width: u32, height: u32) -> Result<()> {
        self.pass.resize(alloc, width, height)?;
        Ok(())
    }

    fn prepare(&mut self, atlas: &Atlas, camera: &Camera) -> CpuTimes {
        let start = Instant::now();
        if let Some(geo) = &camera.geo {
            let mut u = plan(
                atlas,
                self.radius,
                &self.detail,
                self.sun_world,
                camera,
                geo,
            );
            let span = levels(atlas, self.radius, &self.detail, camera, geo);
            u.draw(&self.rings, span, self.radius);
            self.span = span;
            self.uniforms = Some(u);
        } else {
            self.uniforms = None;
        }
        self.geo = camera.geo;
        CpuTimes {
            us: start.elapsed().as_secs_f64() * 1e6,
            ..Default::default()
        }
    }

    fn frame_inputs<'a>(&'a self, _inputs: &mut FrameInputs<'a>) {}

    fn record(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        probe: Probe,
    ) -> &'static [&'static str] {
        let Some(u) = &self.uniforms else {
            return &[];
        };
        ctx.queue
            .write_buffer(&self.planet_uniforms, 0, bytemuck::bytes_of(u));
        self.clipmaps.record(encoder, u.vertex_count, probe);
        self.pass.record(encoder, &self.rings, self.span, probe);
        &PASSES
    }

    fn output(&self) -> crate::gpu::output::Source<'_> {
        self.pass.output()
    }

    fn read_positions(&self, ctx: &GpuContext, camera: &Camera) -> Result<Vec<[f32; 4]>> {
        self.pass.read_positions(ctx, camera)
    }

    fn relight(&mut self, scene: &crate::scene::Scene) {
        self.sun_world = sun_world(scene);
    }

    fn held_camera(&self, camera: &Camera) -> Camera {
        match (self.geo, camera.geo) {
            (Some(held), Some(_)) => reframed(camera, held, self.radius),
            _ => camera.clone(),
        }
    }

    fn triangles(&self) -> u64 {
        self.rings.triangles(self.span)
    }

    fn visible(&self) -> bool {
        self.uniforms.is_some()
    }

    fn as_any(&self) -> &dyn Any {
        self
    }

    fn as_any_mut(&mut self) -> &mut dyn Any {
        self
    }
}
