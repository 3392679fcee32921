//! Pipelines and shader modules from a pass's [`Shader`] in a variant, made once per device, and
//! the compute dispatch every grid-shaped pass records.

use super::alloc::Alloc;
use super::bindings::Binding;
use super::counters;
use super::shaders::{self, Key};
use crate::error::Result;

/// A pass's shader: the name its timer, its `passes_ms` key and its WGSL file share, the
/// WGSL's text, and the bindings it declares ([`bindings`]).
pub struct Shader {
    pub name: &'static str,
    pub source: &'static str,
    /// Read by the check that holds them to the WGSL's declarations (a pass binds its own).
    #[cfg_attr(not(test), allow(dead_code))]
    pub bindings: &'static [Binding],
}

impl Shader {
    /// Its WGSL combined with `flags` set ([`shaders::compose`]).
    pub fn compose(&self, flags: &[&str]) -> Result<String> {
        shaders::compose(self.name, self.source, flags)
    }

    /// The flags its WGSL or any file it imports tests ([`shaders::tested_flags`]).
    #[cfg(test)]
    pub fn tested_flags(&self) -> Key {
        shaders::tested_flags(self.source)
    }
}

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
    let source = shader.compose(&key.defs())?;
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
