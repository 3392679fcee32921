//! A snapshot: a finished frame written by the output pass into colour and depth textures of its
//! own and its colour read back. Every command's image comes this way, as does
//! [`crate::host::Terrain::render_to_image`], so what a command writes is what a host's targets
//! hold.
//!
//! Rules: the textures are the frame's size and one sample; the colour's format is four bytes a
//! pixel (what the read-back copies). Rejected: each scheme reading back its own colour target,
//! a second path whose image no host ever sees.

use super::alloc::{Alloc, Texture};
use super::context::GpuContext;
use super::output::{OutputPass, Targets};
use crate::error::{Error, Result};
use crate::readback::Readback;

/// The textures a snapshot is drawn into, and the read-back of its colour.
pub struct Snapshot {
    colour: Texture,
    depth: Texture,
    readback: Readback,
    size: (u32, u32),
}

impl Snapshot {
    /// Textures of `targets`' formats for a `width` × `height` frame.
    pub fn new(device: &Alloc, targets: Targets, width: u32, height: u32) -> Result<Snapshot> {
        if targets.samples != 1 || targets.colour.block_copy_size(None) != Some(4) {
            return Err(Error::Internal(
                "snapshots read back single-sampled targets of four bytes a pixel",
            ));
        }
        let texture = |format, label| {
            device.create_texture(&wgpu::TextureDescriptor {
                label: Some(label),
                size: wgpu::Extent3d {
                    width,
                    height,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
                view_formats: &[],
            })
        };
        Ok(Snapshot {
            colour: texture(targets.colour, "snapshot colour"),
            depth: texture(targets.depth, "snapshot depth"),
            readback: Readback::counted(device, width, height, targets.colour)?,
            size: (width, height),
        })
    }

    /// The frame size the textures have.
    pub fn size(&self) -> (u32, u32) {
        self.size
    }

    /// Clears the textures, writes the frame `group` holds into them with `output`, and copies
    /// the colour out for [`Snapshot::read`].
    pub fn record(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        output: &OutputPass,
        group: &wgpu::BindGroup,
    ) -> Result<()> {
        let view = |t: &Texture| t.create_view(&Default::default());
        let (colour, depth) = (view(&self.colour), view(&self.depth));
        super::output::clear(encoder, &colour, &depth);
        output.record(encoder, group, &colour, &depth);
        self.readback.record(encoder, &self.colour)
    }

    /// The colour of the submitted snapshot: four bytes a pixel, rows top first.
    pub fn read(&self, ctx: &GpuContext) -> Result<Vec<u8>> {
        let rgba = self.readback.read(&ctx.device)?;
        // No picture where the device refused part of the frame (a target out of memory).
        ctx.raised()?;
        Ok(rgba)
    }
}
