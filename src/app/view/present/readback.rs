//! The screenshot's read-back: a copy of the presented texture, rows padded to the copy alignment,
//! mapped once the frame is done.
//!
//! Rule: a screenshot is the pixels presented, never a second rendering of the frame.

use terrain::alloc::Alloc;
use terrain::{Error, Result};

/// A copy of the presented texture for a screenshot, four bytes a pixel, rows padded to the
/// copy alignment.
pub(super) struct Readback {
    buffer: terrain::alloc::Buffer,
    width: u32,
    height: u32,
    row: u32,
    bgra: bool,
}

impl Readback {
    pub(super) fn record(
        alloc: &Alloc,
        encoder: &mut wgpu::CommandEncoder,
        texture: &wgpu::Texture,
    ) -> Self {
        let (width, height) = (texture.width(), texture.height());
        let row = (width * 4).div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT)
            * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
        let buffer = alloc.create_buffer(&wgpu::BufferDescriptor {
            label: Some("screenshot"),
            size: row as u64 * height as u64,
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        encoder.copy_texture_to_buffer(
            texture.as_image_copy(),
            wgpu::TexelCopyBufferInfo {
                buffer: &buffer,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(row),
                    rows_per_image: None,
                },
            },
            texture.size(),
        );
        let bgra = matches!(
            texture.format(),
            wgpu::TextureFormat::Bgra8Unorm | wgpu::TextureFormat::Bgra8UnormSrgb
        );
        Readback {
            buffer,
            width,
            height,
            row,
            bgra,
        }
    }

    /// RGBA rows, top first (BGRA swapped), opaque.
    pub(super) fn read(self, device: &wgpu::Device) -> Result<Vec<u8>> {
        let (sender, receiver) = std::sync::mpsc::channel();
        self.buffer
            .slice(..)
            .map_async(wgpu::MapMode::Read, move |r| {
                let _ = sender.send(r);
            });
        device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| Error::device("reading the screenshot back", e))?;
        receiver
            .recv()
            .map_err(|_| Error::Internal("the screenshot's mapping never finished"))?
            .map_err(|e| Error::device("reading the screenshot back", e))?;
        let bytes = self
            .buffer
            .slice(..)
            .get_mapped_range()
            .map_err(|e| Error::device("reading the screenshot back", e))?;
        let mut rgba = Vec::with_capacity(self.width as usize * self.height as usize * 4);
        for y in 0..self.height as usize {
            let row = &bytes[y * self.row as usize..][..self.width as usize * 4];
            for px in row.chunks_exact(4) {
                let (r, b) = if self.bgra {
                    (px[2], px[0])
                } else {
                    (px[0], px[2])
                };
                rgba.extend([r, px[1], b, 255]);
            }
        }
        Ok(rgba)
    }
}
