//! The GPU half of a frame: warp & zoom → mesh split → normals → terrain (with the sky), one
//! struct per pass, each owning its pipeline, bind-group layout and resources, each with a WGSL
//! file of the same name in `shaders/`, and its bindings listed once ([`bindings`]).
//! [`crate::render::Renderer`] runs them as a flat list.

/// The [`Shader`] of WGSL file `shaders/<name>.wgsl`.
macro_rules! shader {
    ($name:literal, $bindings:expr) => {
        Shader {
            name: $name,
            source: include_str!(concat!("../../shaders/", $name, ".wgsl")),
            bindings: $bindings,
        }
    };
}

pub mod alloc;
pub mod bindings;
pub mod clipmaps;
pub mod context;
pub mod counters;
pub mod formats;
pub mod frame_io;
pub mod mesh_split;
pub mod normals;
pub mod output;
pub mod planet;
pub mod reference;
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

/// Every pass's shader, a row a pass: the one list `compose` finds a pass's WGSL in and the
/// naga checks run over.
pub const SHADERS: [Shader; 10] = [
    shader!("warp_zoom", warp_zoom::BINDINGS),
    shader!("mesh_split", mesh_split::BINDINGS),
    shader!("normals", normals::BINDINGS),
    shader!("terrain", terrain::BINDINGS),
    shader!("reference", reference::BINDINGS),
    shader!("clipmaps", clipmaps::BINDINGS),
    shader!("planet", planet::BINDINGS),
    shader!("planet_reference", reference::PLANET_BINDINGS),
    shader!("output", output::BINDINGS),
    shader!("sun_map", sun_map::BINDINGS),
];

/// A compute pipeline for pass `name` in variant `key`, entry point `main`, over `layout` (the
/// pass's shared layout of that variant): made once per device.
pub(crate) fn compute_pipeline(
    device: &Alloc,
    name: &str,
    key: Key,
    layout: &wgpu::BindGroupLayout,
) -> Result<wgpu::ComputePipeline> {
    device.shared.compute(format!("{name} {key:?}"), || {
        let module = shader_module(device, name, key)?;
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
    name: &'a str,
    key: Key,
    made: std::cell::OnceCell<wgpu::ShaderModule>,
}

impl<'a> Module<'a> {
    pub fn new(device: &'a wgpu::Device, name: &'a str, key: Key) -> Module<'a> {
        Module {
            device,
            name,
            key,
            made: std::cell::OnceCell::new(),
        }
    }

    /// The module, made on first use.
    pub fn get(&self) -> Result<&wgpu::ShaderModule> {
        if let Some(m) = self.made.get() {
            return Ok(m);
        }
        let m = shader_module(self.device, self.name, self.key)?;
        Ok(self.made.get_or_init(|| m))
    }

    /// What it is made from (the WGSL file and the variant), keying the pipelines made with it.
    pub fn made_from(&self) -> String {
        format!("{} {:?}", self.name, self.key)
    }
}

pub(crate) fn shader_module(
    device: &wgpu::Device,
    name: &str,
    key: Key,
) -> Result<wgpu::ShaderModule> {
    let source = shaders::compose(name, &key.defs())?;
    Ok(device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(name),
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
