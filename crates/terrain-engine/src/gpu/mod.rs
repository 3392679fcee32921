//! The GPU plumbing (device and its ledger, bindings, shader composition, read-back, counters,
//! the tile cache's binding) and the passes more than one mode runs: warp & zoom, normals, the
//! terrain pass (with the sky), the sun map and the output pass. A mode's own passes live in its
//! folder under `lod/` (mesh split, the reference, clipmaps and the planet pass). Each pass is a
//! struct owning its pipeline, bind-group layout and resources, with a WGSL file of the same name
//! in `shaders/` and its bindings listed once ([`bindings`]), both in its [`Shader`];
//! [`crate::render::Renderer`] runs the passes as a flat list.

pub mod alloc;
pub mod bindings;
pub mod context;
pub mod counters;
pub mod formats;
pub mod frame_io;
pub mod normals;
pub mod output;
pub mod shaders;
pub mod shared;
pub mod snapshot;
pub mod stream;
pub mod sun_map;
pub mod terrain;
pub mod uniforms;
pub mod warp_zoom;
pub mod work;

use crate::error::Result;
use alloc::Alloc;
use bindings::Binding;
use shaders::Key;

/// A pass's shader: the name its timer, its `passes_ms` key and its WGSL file share, the
/// WGSL's text, and the bindings it declares ([`bindings`]).
pub struct Shader {
    pub name: &'static str,
    pub source: &'static str,
    /// Read by the check that holds them to the WGSL's declarations (a pass binds its own).
    #[cfg_attr(not(test), allow(dead_code))]
    pub bindings: &'static [Binding],
}

/// The shaders of the passes every mode may run, a row a pass; each scheme lists its own
/// (`lod::Scheme::shaders`), and the naga checks run over both (`lod::shaders`).
#[cfg(test)]
pub const SHADERS: [Shader; 5] = [
    warp_zoom::SHADER,
    normals::SHADER,
    terrain::SHADER,
    output::SHADER,
    sun_map::SHADER,
];

/// A compute pipeline for `shader`'s pass in variant `key`, entry point `main`, over `layout`
/// (the pass's shared layout of that variant): made once per device.
pub(crate) fn compute_pipeline(
    device: &Alloc,
    shader: &Shader,
    key: Key,
    layout: &wgpu::BindGroupLayout,
) -> Result<wgpu::ComputePipeline> {
    let name = shader.name;
    device.shared.compute(format!("{name} {key:?}"), || {
        let module = shader_module(device, shader, key)?;
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some(name),
            bind_group_layouts: &[Some(layout)],
            immediate_size: 0,
        });
        Ok(
            device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(name),
                layout: Some(&pipeline_layout),
                module: &module,
                entry_point: Some("main"),
                compilation_options: Default::default(),
                cache: None,
            }),
        )
    })
}

/// A pass's shader module of one variant, made the first time a pipeline not yet shared on the
/// device needs it: a renderer whose pipelines are all shared parses no WGSL.
pub(crate) struct Module<'a> {
    device: &'a wgpu::Device,
    shader: &'a Shader,
    key: Key,
    made: std::cell::OnceCell<wgpu::ShaderModule>,
}

impl<'a> Module<'a> {
    pub fn new(device: &'a wgpu::Device, shader: &'a Shader, key: Key) -> Module<'a> {
        Module {
            device,
            shader,
            key,
            made: std::cell::OnceCell::new(),
        }
    }

    /// The module, made on first use.
    pub fn get(&self) -> Result<&wgpu::ShaderModule> {
        if let Some(m) = self.made.get() {
            return Ok(m);
        }
        let m = shader_module(self.device, self.shader, self.key)?;
        Ok(self.made.get_or_init(|| m))
    }

    /// What it is made from (the WGSL file and the variant), keying the pipelines made with it.
    pub fn made_from(&self) -> String {
        format!("{} {:?}", self.shader.name, self.key)
    }
}

pub(crate) fn shader_module(
    device: &wgpu::Device,
    shader: &Shader,
    key: Key,
) -> Result<wgpu::ShaderModule> {
    let source = shaders::compose(shader, &key.defs())?;
    Ok(device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(shader.name),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    }))
}

/// Records a compute pass running `pipeline` once per cell of a `size[0]` × `size[1]` grid
/// (mesh vertices or pixels; 8×8 workgroups), as pass `name` (its label, timer and counters key).
pub(crate) fn dispatch_grid(
    encoder: &mut wgpu::CommandEncoder,
    name: &str,
    pipeline: &wgpu::ComputePipeline,
    bind_group: &wgpu::BindGroup,
    size: [u32; 2],
    probe: counters::Probe,
) {
    let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
        label: Some(name),
        timestamp_writes: probe.compute(name),
    });
    probe.begin_compute(&mut pass, name, 0);
    pass.set_pipeline(pipeline);
    pass.set_bind_group(0, bind_group, &[]);
    pass.dispatch_workgroups(size[0].div_ceil(8), size[1].div_ceil(8), 1);
    probe.end_compute(&mut pass);
}
