//! The terrain pass's targets at a frame's size: the colour it leaves for read-back and the output
//! pass, the depth, the depth copy for positions, the multisampled colour and the G-buffer with its
//! bind group. Nothing else in the pass depends on the size, so a new size makes these alone. A
//! planet's pass draws into the same targets, single-sampled and forward.

use super::{BINDINGS, COLOUR, DEPTH, DEPTH_COPY, Deferred, GBUFFER, Multisampled};
use crate::error::Result;
use crate::gpu::alloc::{Alloc, Texture};
use crate::gpu::bindings;
use crate::gpu::shaders::Key;

/// What the targets depend on besides the size: kept by the pass for a new size.
pub(crate) struct Sizing {
    pub key: Key,
    pub samples: u32,
    /// Draws the depth copy of a multisampled frame.
    pub depth_pipeline: Option<wgpu::RenderPipeline>,
    /// The G-buffer's layout, when shading is deferred.
    pub gbuffer: Option<wgpu::BindGroupLayout>,
}

/// The targets [`make`] builds, with their views.
pub(crate) struct Targets {
    _colour: Texture,
    pub colour_view: wgpu::TextureView,
    pub depth_view: wgpu::TextureView,
    _depth: Texture,
    /// Each pixel's view distance as a colour target: for the output pass and positions.
    pub depth_copy: Texture,
    pub depth_copy_view: wgpu::TextureView,
    pub(super) multisampled: Option<Multisampled>,
    pub(super) deferred: Option<Deferred>,
}

impl Targets {
    /// The frame's colour and view distances, for the output pass.
    pub fn output(&self) -> crate::gpu::output::Source<'_> {
        crate::gpu::output::Source::Targets {
            colour: &self.colour_view,
            depth: &self.depth_copy_view,
        }
    }
}

/// The targets of a `width` × `height` frame drawn as `sizing` says.
pub(crate) fn make(
    device: &Alloc,
    (width, height): (u32, u32),
    sizing: &Sizing,
) -> Result<Targets> {
    let key = sizing.key;
    let n = sizing.samples;
    let multisampled = n > 1;
    let target_of = |format, usage, label, sample_count| {
        device.create_texture(&wgpu::TextureDescriptor {
            label: Some(label),
            size: wgpu::Extent3d {
                width,
                height,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage,
            view_formats: &[],
        })
    };
    let target = |format, usage, label| target_of(format, usage, label, 1);
    let colour = target(
        COLOUR,
        // Read by the output pass too, for a host's targets.
        wgpu::TextureUsages::RENDER_ATTACHMENT
            | wgpu::TextureUsages::COPY_SRC
            | wgpu::TextureUsages::TEXTURE_BINDING,
        "colour",
    );
    let drawn = wgpu::TextureUsages::RENDER_ATTACHMENT;
    let depth = target_of(DEPTH, drawn, "depth", n);
    let usage = wgpu::TextureUsages::RENDER_ATTACHMENT
        | wgpu::TextureUsages::COPY_SRC
        | wgpu::TextureUsages::TEXTURE_BINDING;
    let depth_copy = target(DEPTH_COPY, usage, "depth copy");
    let multisampled = multisampled.then(|| {
        let colour = target_of(COLOUR, drawn, "colour samples", n);
        let mut ms = Multisampled {
            colour: colour.create_view(&Default::default()),
            depth_pass: None,
            _targets: vec![colour],
        };
        if let Some(pipeline) = sizing.depth_pipeline.clone() {
            let depth = target(DEPTH, drawn, "depth copy's depth");
            ms.depth_pass = Some((pipeline, depth.create_view(&Default::default())));
            ms._targets.push(depth);
        }
        ms
    });
    let deferred = sizing
        .gbuffer
        .as_ref()
        .map(|gbuffer_layout| -> Result<Deferred> {
            let usage = drawn | wgpu::TextureUsages::TEXTURE_BINDING;
            let targets: Vec<_> = GBUFFER
                .iter()
                .map(|&f| target(f, usage, "g-buffer"))
                .collect();
            let views: Vec<_> = targets
                .iter()
                .map(|t| t.create_view(&Default::default()))
                .collect();
            // The targets in the order of their bindings.
            let names = BINDINGS.iter().filter(|b| b.group == 1).map(|b| b.name);
            let resources: Vec<_> = names
                .zip(&views)
                .map(|(name, view)| (name, wgpu::BindingResource::TextureView(view)))
                .collect();
            let label = "terrain g-buffer";
            let bind_group =
                bindings::bind_group(device, label, gbuffer_layout, BINDINGS, 1, key, &resources)?;
            Ok(Deferred {
                bind_group,
                views,
                _targets: targets,
            })
        });
    let deferred = deferred.transpose()?;

    Ok(Targets {
        colour_view: colour.create_view(&Default::default()),
        depth_view: depth.create_view(&Default::default()),
        depth_copy_view: depth_copy.create_view(&Default::default()),
        _colour: colour,
        _depth: depth,
        depth_copy,
        multisampled,
        deferred,
    })
}
