//! What the raster passes (terrain, planet) build their pipelines and passes with: vertices
//! pulled from storage (no vertex buffers), triangle lists, reversed-Z depth into [`DEPTH`].

use super::DEPTH;
use crate::error::Result;
use crate::gpu::alloc::Alloc;
use crate::gpu::pipeline::Module;

/// A render pass of the terrain's: no occlusion queries, one view.
pub(super) fn render_pass<'e>(
    encoder: &'e mut wgpu::CommandEncoder,
    label: &str,
    colour: &[Option<wgpu::RenderPassColorAttachment>],
    depth: Option<wgpu::RenderPassDepthStencilAttachment>,
    timestamps: Option<wgpu::RenderPassTimestampWrites>,
) -> wgpu::RenderPass<'e> {
    encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some(label),
        color_attachments: colour,
        depth_stencil_attachment: depth,
        timestamp_writes: timestamps,
        occlusion_query_set: None,
        multiview_mask: None,
    })
}

/// A render pipeline of the raster passes (terrain, planet): vertices pulled from storage (no
/// vertex buffers), triangle lists, and a reversed-Z depth test into [`DEPTH`] or none.
pub(crate) struct RasterPipeline<'a> {
    pub layout: &'a wgpu::PipelineLayout,
    /// Made only where the device shares no such pipeline yet; what it is made from keys the
    /// pipeline with the rest of this descriptor.
    pub module: &'a Module<'a>,
    /// Vertex and fragment entry points.
    pub entry: (&'a str, &'a str),
    pub targets: &'a [Option<wgpu::ColorTargetState>],
    pub samples: u32,
    /// Whether it writes the depth, and its test; `None`: drawn without a depth attachment.
    pub depth: Option<(bool, wgpu::CompareFunction)>,
}

impl RasterPipeline<'_> {
    pub fn build(&self, device: &Alloc) -> Result<wgpu::RenderPipeline> {
        let shared = format!(
            "{} {:?} {:?} {} {:?}",
            self.module.made_from(),
            self.entry,
            self.targets,
            self.samples,
            self.depth
        );
        device
            .shared
            .render(shared, || Ok(self.make(device, self.module.get()?)))
    }

    fn make(&self, device: &wgpu::Device, module: &wgpu::ShaderModule) -> wgpu::RenderPipeline {
        let (vs, fs) = self.entry;
        device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some(fs),
            layout: Some(self.layout),
            vertex: wgpu::VertexState {
                module,
                entry_point: Some(vs),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive: wgpu::PrimitiveState {
                topology: wgpu::PrimitiveTopology::TriangleList,
                ..Default::default()
            },
            depth_stencil: self.depth.map(|(write, compare)| wgpu::DepthStencilState {
                format: DEPTH,
                depth_write_enabled: Some(write),
                depth_compare: Some(compare),
                stencil: Default::default(),
                bias: Default::default(),
            }),
            multisample: wgpu::MultisampleState {
                count: self.samples,
                ..Default::default()
            },
            fragment: Some(wgpu::FragmentState {
                module,
                entry_point: Some(fs),
                compilation_options: Default::default(),
                targets: self.targets,
            }),
            multiview_mask: None,
            cache: None,
        })
    }
}
