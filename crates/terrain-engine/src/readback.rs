//! Textures read back to the CPU: the one copy that snapshots, the window's screenshots, the
//! example host and the tests all go through.
//!
//! Rules: the copy is recorded into the caller's encoder, so it reads what that encoder drew, and
//! is read after the caller submits. Texels come back rows top first without wgpu's row padding,
//! as the texture stores them, for formats of four bytes a texel (RGBA8 and BGRA8 colour,
//! `Depth32Float`, `R32Float`); [`Readback::read_rgba`] swaps BGRA into RGBA. A depth texture is
//! copied by its depth aspect. Rejected: a read-back that submits an encoder of its own, which
//! cannot read a frame in the host's encoder before the host submits it.
//!
//! ```no_run
//! # fn f(device: &wgpu::Device, queue: &wgpu::Queue, colour: &wgpu::Texture) -> terrain::Result<()> {
//! let readback = terrain::readback::Readback::new(device, colour)?;
//! let mut encoder = device.create_command_encoder(&Default::default());
//! // … draw into `colour` …
//! readback.record(&mut encoder, colour)?;
//! queue.submit([encoder.finish()]);
//! let rgba = readback.read_rgba(device)?;
//! assert_eq!(rgba.len(), (colour.width() * colour.height() * 4) as usize);
//! # Ok(())
//! # }
//! ```

use crate::error::{Error, Result};
use crate::gpu::alloc::{Alloc, Buffer, Ledger};

/// A staging buffer for one texture size and format, and the copy into it.
pub struct Readback {
    buffer: Buffer,
    width: u32,
    height: u32,
    format: wgpu::TextureFormat,
}

impl Readback {
    /// A read-back for textures of `texture`'s size and format (four bytes a texel, one sample).
    pub fn new(device: &wgpu::Device, texture: &wgpu::Texture) -> Result<Readback> {
        let alloc = Alloc {
            device,
            ledger: &Ledger::default(),
            shared: &Default::default(),
        };
        Readback::counted(&alloc, texture.width(), texture.height(), texture.format())
    }

    /// As [`Readback::new`], its staging buffer counted in `alloc`'s ledger.
    pub(crate) fn counted(
        alloc: &Alloc,
        width: u32,
        height: u32,
        format: wgpu::TextureFormat,
    ) -> Result<Readback> {
        if texel_bytes(format) != Some(4) {
            return Err(Error::Internal(
                "read-backs copy textures of four bytes a texel (RGBA8, BGRA8, Depth32Float, R32Float)",
            ));
        }
        let buffer = alloc.create_buffer(&wgpu::BufferDescriptor {
            label: Some("readback"),
            size: padded_row(width) as u64 * height as u64,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        Ok(Readback {
            buffer,
            width,
            height,
            format,
        })
    }

    /// Records the copy of `texture` (of this read-back's size and format, one sample) into
    /// `encoder`, after whatever the encoder drew into it.
    pub fn record(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        texture: &wgpu::Texture,
    ) -> Result<()> {
        let (w, h) = (texture.width(), texture.height());
        if (w, h) != (self.width, self.height)
            || texture.format() != self.format
            || texture.sample_count() != 1
        {
            return Err(Error::Internal(
                "a read-back given a texture of another size, format or sample count",
            ));
        }
        let aspect = match self.format.has_depth_aspect() {
            true => wgpu::TextureAspect::DepthOnly,
            false => wgpu::TextureAspect::All,
        };
        encoder.copy_texture_to_buffer(
            wgpu::TexelCopyTextureInfo {
                aspect,
                ..texture.as_image_copy()
            },
            wgpu::TexelCopyBufferInfo {
                buffer: &self.buffer,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(padded_row(self.width)),
                    rows_per_image: None,
                },
            },
            wgpu::Extent3d {
                width: w,
                height: h,
                depth_or_array_layers: 1,
            },
        );
        Ok(())
    }

    /// The texels of the submitted copy, four bytes each, rows top first, as the texture
    /// stores them (a depth texture's as little-endian f32). Waits for the device.
    pub fn read(&self, device: &wgpu::Device) -> Result<Vec<u8>> {
        read_buffer(device, &self.buffer, |bytes| self.unpad(bytes))
    }

    /// As [`Readback::read`], a BGRA texture's texels swapped into RGBA.
    pub fn read_rgba(&self, device: &wgpu::Device) -> Result<Vec<u8>> {
        let mut texels = self.read(device)?;
        self.swap_bgra(&mut texels);
        Ok(texels)
    }

    /// As [`Readback::read_rgba`] without waiting: `done` gets the texels once the device has
    /// mapped the copy. For a browser, whose page cannot block on the GPU: the mapping completes
    /// between its tasks. The read-back is spent.
    pub fn read_rgba_later(self, done: impl FnOnce(Result<Vec<u8>>) + wgpu::WasmNotSend + 'static) {
        let buffer = (*self.buffer).clone();
        buffer
            .clone()
            .slice(..)
            .map_async(wgpu::MapMode::Read, move |mapped| {
                let texels = mapped
                    .map_err(|e| Error::device("readback failed", e))
                    .and_then(|()| {
                        let view = buffer
                            .slice(..)
                            .get_mapped_range()
                            .map_err(|e| Error::device("readback mapping", e))?;
                        let mut texels = self.unpad(&view);
                        self.swap_bgra(&mut texels);
                        Ok(texels)
                    });
                buffer.unmap();
                done(texels)
            });
    }

    /// The rows of a mapped copy without wgpu's padding.
    fn unpad(&self, bytes: &[u8]) -> Vec<u8> {
        let padded = padded_row(self.width) as usize;
        let row = self.width as usize * 4;
        (0..self.height as usize)
            .flat_map(|y| bytes[y * padded..y * padded + row].iter().copied())
            .collect()
    }

    fn swap_bgra(&self, texels: &mut [u8]) {
        if matches!(
            self.format,
            wgpu::TextureFormat::Bgra8Unorm | wgpu::TextureFormat::Bgra8UnormSrgb
        ) {
            texels.chunks_exact_mut(4).for_each(|px| px.swap(0, 2));
        }
    }
}

/// `texture`'s texels read back at once: the copy recorded into an encoder of its own and
/// submitted on `queue`, after everything submitted before. See [`Readback::read`].
pub fn read_texture(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    texture: &wgpu::Texture,
) -> Result<Vec<u8>> {
    let readback = Readback::new(device, texture)?;
    let mut encoder = device.create_command_encoder(&Default::default());
    readback.record(&mut encoder, texture)?;
    queue.submit([encoder.finish()]);
    readback.read(device)
}

/// A depth texture's texels (`Depth32Float`, as [`read_texture`] returns them) as depths.
pub fn depths(texels: &[u8]) -> Vec<f32> {
    texels
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect()
}

fn texel_bytes(format: wgpu::TextureFormat) -> Option<u32> {
    match format.has_depth_aspect() {
        true => format.block_copy_size(Some(wgpu::TextureAspect::DepthOnly)),
        false => format.block_copy_size(None),
    }
}

/// A row of `width` four-byte texels, padded to wgpu's copy alignment.
pub(crate) fn padded_row(width: u32) -> u32 {
    (width * 4).div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT
}

/// `buffer` mapped once the device is done with it, and `f` of its bytes.
pub(crate) fn read_buffer<T>(
    device: &wgpu::Device,
    buffer: &wgpu::Buffer,
    f: impl FnOnce(&[u8]) -> T,
) -> Result<T> {
    let slice = buffer.slice(..);
    let (tx, rx) = std::sync::mpsc::channel();
    slice.map_async(wgpu::MapMode::Read, move |r| {
        let _ = tx.send(r);
    });
    device
        .poll(wgpu::PollType::wait_indefinitely())
        .map_err(|e| Error::device("device lost while waiting", e))?;
    // A web page cannot wait for its GPU (`poll` returns at once there, and the callback runs
    // only once the page yields): blocking on it would freeze the page, so there it is an error.
    #[cfg(target_arch = "wasm32")]
    let answer = rx.try_recv().map_err(|e| {
        Error::device(
            "a readback that waits for the GPU, which a web page cannot do",
            e,
        )
    })?;
    #[cfg(not(target_arch = "wasm32"))]
    let answer = rx
        .recv()
        .map_err(|e| Error::device("readback callback never ran", e))?;
    answer.map_err(|e| Error::device("readback failed", e))?;
    let out = {
        let view = slice
            .get_mapped_range()
            .map_err(|e| Error::device("readback mapping", e))?;
        f(&view)
    };
    buffer.unmap();
    Ok(out)
}
