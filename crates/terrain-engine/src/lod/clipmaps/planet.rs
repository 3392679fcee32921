//! The planet pass (`shaders/planet.wgsl`): the clipmap rings drawn from the clipmaps pass's
//! vertices (vertex pulling, one static index buffer: the drawn levels' quads and the fill's fan
//! are two ranges of it), then the sky or space as one full-screen triangle behind them
//! (`terrain::SKY_TEST`). Reversed-Z depth
//! with an infinite far plane, so a view holds ground from a metre to 20,000 km away without
//! z-fighting. Owns the colour and depth targets.

use crate::error::Result;
use crate::gpu::alloc::{Alloc, Buffer};
use crate::gpu::bindings::{Binding, bind_group, buffer, layout};
use crate::gpu::formats::{COLOUR, DEPTH_COPY};
use crate::gpu::pipeline::Module;
use crate::gpu::shaders::Key;
use crate::gpu::stream::AtlasBinding;
use crate::gpu::terrain::RasterPipeline;
use crate::gpu::terrain::targets::{Sizing, Targets, make};
use crate::planet::rings::{Rings, Span};
use wgpu::ShaderStages as S;

/// The pass's shader, `shaders/planet.wgsl`.
pub const SHADER: crate::gpu::pipeline::Shader = shader!("planet", BINDINGS);

/// `shaders/planet.wgsl`'s bindings.
pub const BINDINGS: &[Binding] = &[
    Binding::frame(S::VERTEX_FRAGMENT),
    Binding::atlas(S::VERTEX_FRAGMENT),
    Binding::wanted(S::VERTEX_FRAGMENT),
    Binding::work(S::FRAGMENT),
    Binding::sun_seen(S::FRAGMENT),
    // Declared where the shading it imports draws a ramp (never set for this pass's scenes).
    Binding::ramp(S::FRAGMENT),
    Binding::drape(S::FRAGMENT),
    Binding::uniform(2, "planet", S::VERTEX_FRAGMENT),
    Binding::storage(3, "hemisphere", S::VERTEX),
    Binding::storage(4, "vertices", S::VERTEX),
];

pub struct PlanetPass {
    sky: wgpu::RenderPipeline,
    planet: wgpu::RenderPipeline,
    bind_group: wgpu::BindGroup,
    index: Buffer,
    sizing: Sizing,
    /// The colour, the depth, and each pixel's view distance as a colour target.
    targets: Targets,
}

impl PlanetPass {
    /// The pass's name: its timer key, its `passes_ms` key, its WGSL file.
    /// The frame's colour and view distances.
    pub fn output(&self) -> crate::gpu::output::Source<'_> {
        self.targets.output()
    }

    pub const NAME: &'static str = SHADER.name;

    #[allow(clippy::too_many_arguments)]
    pub fn new(
        device: &Alloc,
        frame: &wgpu::Buffer,
        atlas: &AtlasBinding,
        planet: &wgpu::Buffer,
        hemisphere: &wgpu::Buffer,
        vertices: &wgpu::Buffer,
        rings: &Rings,
        (width, height): (u32, u32),
        key: Key,
    ) -> Result<PlanetPass> {
        // The view distances the output pass reads (`POSITIONS`, always set for a planet).
        let targets = [Some(COLOUR.into()), Some(DEPTH_COPY.into())];
        let layout = layout(device, Self::NAME, BINDINGS, 0, key);
        let module = Module::new(device, &SHADER, key);
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("planet"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline_of = |entry, depth| {
            RasterPipeline {
                layout: &pipeline_layout,
                module: &module,
                entry,
                targets: &targets,
                samples: 1,
                depth: Some(depth),
            }
            .build(device)
        };
        let sky = pipeline_of(("sky_vs", "sky_fs"), (false, crate::gpu::terrain::SKY_TEST))?;
        let planet_pipeline = pipeline_of(
            ("planet_vs", "planet_fs"),
            (true, wgpu::CompareFunction::Greater),
        )?;
        let mut resources = atlas.resources();
        resources.extend([
            ("frame", buffer(frame)),
            ("planet", buffer(planet)),
            ("hemisphere", buffer(hemisphere)),
            ("vertices", buffer(vertices)),
        ]);
        let bind_group = bind_group(device, Self::NAME, &layout, BINDINGS, 0, key, &resources)?;
        let index = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("clipmap indices"),
            contents: bytemuck::cast_slice(&rings.indices),
            usage: wgpu::BufferUsages::INDEX,
        });
        let sizing = Sizing {
            key,
            samples: 1,
            depth_pipeline: None,
            gbuffer: None,
        };
        let targets = make(device, (width, height), &sizing)?;
        Ok(PlanetPass {
            sky,
            planet: planet_pipeline,
            bind_group,
            index,
            sizing,
            targets,
        })
    }

    /// Makes the targets for frames of `width` × `height` (nothing else depends on the size).
    pub fn resize(&mut self, device: &Alloc, width: u32, height: u32) -> Result<()> {
        self.targets = make(device, (width, height), &self.sizing)?;
        Ok(())
    }

    /// Ground positions of the last frame's pixels, drawn from `camera` (metres in its nadir's
    /// tangent frame, w = 1 on ground), from the depth copy.
    pub fn read_positions(
        &self,
        ctx: &crate::gpu::context::GpuContext,
        camera: &crate::camera::Camera,
    ) -> Result<Vec<[f32; 4]>> {
        let depth = &self.targets.depth_copy;
        let view_proj =
            crate::gpu::uniforms::view_proj(camera, crate::gpu::uniforms::frame_origin(camera));
        crate::gpu::frame_io::positions_from_depth(ctx, depth, view_proj, camera.near)
    }

    /// Records the rings of `span` with their fill, then the sky.
    pub fn record(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        rings: &Rings,
        span: Span,
        probe: crate::gpu::counters::Probe,
    ) {
        let attach = |view| {
            Some(wgpu::RenderPassColorAttachment {
                view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                    store: wgpu::StoreOp::Store,
                },
            })
        };
        let t = &self.targets;
        let attachments = [attach(&t.colour_view), attach(&t.depth_copy_view)];
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some(Self::NAME),
            color_attachments: &attachments,
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &t.depth_view,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(0.0),
                    store: wgpu::StoreOp::Discard,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: probe.render(Self::NAME),
            occlusion_query_set: None,
            multiview_mask: None,
        });
        probe.begin_render(&mut pass, Self::NAME, 0);
        pass.set_bind_group(0, &self.bind_group, &[]);
        pass.set_pipeline(&self.planet);
        pass.set_index_buffer(self.index.slice(..), wgpu::IndexFormat::Uint32);
        for range in rings.draw_ranges(span) {
            pass.draw_indexed(range, 0, 0..1);
        }
        // After the ground, where it left the depth cleared (`SKY_TEST`).
        pass.set_pipeline(&self.sky);
        pass.draw(0..3, 0..1);
        probe.end_render(&mut pass);
    }
}
