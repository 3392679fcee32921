//! What the raster passes (terrain, planet) build their pipelines and passes with: vertices
//! pulled from storage (no vertex buffers), triangle lists, reversed-Z depth into [`DEPTH`].

use super::DEPTH;

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
    pub module: &'a wgpu::ShaderModule,
    /// Vertex and fragment entry points.
    pub entry: (&'a str, &'a str),
    pub targets: &'a [Option<wgpu::ColorTargetState>],
    pub samples: u32,
    /// Whether it writes the depth, and its test; `None`: drawn without a depth attachment.
    pub depth: Option<(bool, wgpu::CompareFunction)>,
}

impl RasterPipeline<'_> {
    pub fn build(&self, device: &wgpu::Device) -> wgpu::RenderPipeline {
        let (vs, fs) = self.entry;
        device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some(fs),
            layout: Some(self.layout),
            vertex: wgpu::VertexState {
                module: self.module,
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
                module: self.module,
                entry_point: Some(fs),
                compilation_options: Default::default(),
                targets: self.targets,
            }),
            multiview_mask: None,
            cache: None,
        })
    }
}
