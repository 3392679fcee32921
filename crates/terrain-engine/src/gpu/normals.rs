//! Normals of the detailed geometry image (`shaders/normals.wgsl`).

use super::alloc::{Alloc, Buffer};
use super::bindings::{Binding, bind_group, buffer, layout};
use super::pipeline::{compute_pipeline, dispatch_grid};
use super::shaders::Key;
use crate::error::Result;
use wgpu::ShaderStages as S;

/// The pass's shader, `shaders/normals.wgsl`.
pub const SHADER: crate::gpu::pipeline::Shader = shader!("normals", BINDINGS);

/// `shaders/normals.wgsl`'s bindings.
pub const BINDINGS: &[Binding] = &[
    Binding::frame(S::COMPUTE),
    Binding::storage(3, "detailed", S::COMPUTE),
    Binding::storage_rw(4, "normals", S::COMPUTE),
];

pub struct NormalsPass {
    pipeline: wgpu::ComputePipeline,
    bind_group: wgpu::BindGroup,
    /// mesh² vec4 (unit normal, 0).
    pub normals: Buffer,
    mesh: u32,
}

impl NormalsPass {
    /// The pass's name: its timer key, its `passes_ms` key, its WGSL file.
    pub const NAME: &'static str = SHADER.name;

    pub fn new(
        device: &Alloc,
        frame: &wgpu::Buffer,
        detailed: &wgpu::Buffer,
        mesh: u32,
    ) -> Result<NormalsPass> {
        let (name, key) = (Self::NAME, Key::NONE);
        let layout = layout(device, name, BINDINGS, 0, key);
        let pipeline = compute_pipeline(device, &SHADER, key, &layout)?;
        let normals = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("normals"),
            size: (mesh * mesh) as u64 * 16,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let resources = [
            ("frame", buffer(frame)),
            ("detailed", buffer(detailed)),
            ("normals", buffer(&normals)),
        ];
        let bind_group = bind_group(device, name, &layout, BINDINGS, 0, key, &resources)?;
        Ok(NormalsPass {
            pipeline,
            bind_group,
            normals,
            mesh,
        })
    }

    /// Records the pass for a `mesh`² geometry image (at most the size it was built for).
    pub fn record(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        mesh: u32,
        probe: super::counters::Probe,
    ) {
        let (p, b) = (&self.pipeline, &self.bind_group);
        let m = mesh.min(self.mesh);
        dispatch_grid(encoder, Self::NAME, p, b, [m; 2], probe);
    }
}

#[cfg(test)]
/// The CPU twin of one invocation of `normals.wgsl`: the normal of vertex `ij` of `detailed`
/// (mesh², row-major).
pub fn normal_cpu(detailed: &[[f32; 4]], mesh: u32, ij: glam::IVec2) -> [f32; 3] {
    let m = mesh as i32;
    let vertex = |p: glam::IVec2| {
        let c = p.clamp(glam::IVec2::ZERO, glam::IVec2::splat(m - 1));
        let v = detailed[(c.y * m + c.x) as usize];
        glam::Vec3::new(v[0], v[1], v[2])
    };
    let ds = vertex(ij + glam::IVec2::X) - vertex(ij - glam::IVec2::X);
    let dt = vertex(ij + glam::IVec2::Y) - vertex(ij - glam::IVec2::Y);
    let c = ds.cross(dt);
    let len = c.length();
    if len > 0.0 {
        (c / len).to_array()
    } else {
        [0.0, 0.0, 1.0]
    }
}

impl NormalsPass {
    pub fn into_normals(self) -> Buffer {
        self.normals
    }
}
