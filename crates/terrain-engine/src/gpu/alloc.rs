//! GPU memory as allocated: every buffer and texture a renderer keeps is created through its
//! [`Alloc`], which counts the bytes in the renderer's [`Ledger`] while they live, so the
//! `gpu_memory_bytes` of `render --json` and `compare` is read from the allocations themselves
//! rather than from a sum written beside them that can drift from them.
//!
//! Rules: sizes are the descriptors' — a buffer's `size`, a texture's format footprint (block
//! size × extent × samples, mip levels summed; wgpu's `theoretical_memory_footprint`). Drivers
//! pad and align beyond that, differently on each adapter, so this is the floor every adapter
//! agrees on. `clippy.toml` disallows wgpu's own `create_buffer`, `create_buffer_init` and
//! `create_texture`, so an allocation that bypasses the ledger fails the lint; the only
//! exceptions are read-back staging buffers that live within one call (`frame_io`).
//!
//! Rejected alternative: wgpu's `counters` feature (`HalCounters::buffer_memory`). Only its
//! Vulkan and DX12 backends set it; on GL — llvmpipe, where CI and most servers render — it
//! reads 0. It also counts the whole device, which `compare` shares between renderers.

pub use super::shared::OnDevice;
use std::ops::Deref;
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

/// The bytes a renderer's buffers and textures hold now. Cheap to clone (shared count).
#[derive(Clone, Debug, Default)]
pub struct Ledger(Arc<AtomicU64>);

impl Ledger {
    /// The bytes counted now: the sum over the live [`Tracked`] objects.
    pub fn bytes(&self) -> u64 {
        self.0.load(Ordering::Relaxed)
    }

    /// `value`, counted as `bytes` until it is dropped.
    pub fn track<T>(&self, value: T, bytes: u64) -> Tracked<T> {
        self.0.fetch_add(bytes, Ordering::Relaxed);
        Tracked {
            value,
            bytes,
            ledger: self.clone(),
        }
    }
}

/// A GPU object counted in a [`Ledger`]; derefs to the object.
#[derive(Debug)]
pub struct Tracked<T> {
    value: T,
    bytes: u64,
    ledger: Ledger,
}

impl<T> Tracked<T> {
    /// The bytes this object is counted as (its descriptor's size).
    pub fn bytes(&self) -> u64 {
        self.bytes
    }
}

impl<T> Deref for Tracked<T> {
    type Target = T;
    fn deref(&self) -> &T {
        &self.value
    }
}

impl<T> Drop for Tracked<T> {
    fn drop(&mut self) {
        self.ledger.0.fetch_sub(self.bytes, Ordering::Relaxed);
    }
}

/// A buffer counted in its renderer's [`Ledger`].
pub type Buffer = Tracked<wgpu::Buffer>;
/// A texture counted in its renderer's [`Ledger`].
pub type Texture = Tracked<wgpu::Texture>;

/// The device, with what it allocates counted in `ledger`. Derefs to the device for everything
/// that holds no memory of its own (pipelines, bind groups, encoders).
#[derive(Clone, Copy)]
pub struct Alloc<'a> {
    /// The device that creates the objects.
    pub device: &'a wgpu::Device,
    /// The ledger that counts them.
    pub ledger: &'a Ledger,
    /// What everything drawn on the device shares: pipelines, layouts, the sketch.
    pub shared: &'a OnDevice,
}

impl Deref for Alloc<'_> {
    type Target = wgpu::Device;
    fn deref(&self) -> &wgpu::Device {
        self.device
    }
}

impl Alloc<'_> {
    /// `wgpu::Device::create_buffer`, counted at `desc.size` bytes.
    #[allow(clippy::disallowed_methods)]
    pub fn create_buffer(&self, desc: &wgpu::BufferDescriptor) -> Buffer {
        self.ledger
            .track(self.device.create_buffer(desc), desc.size)
    }

    /// `wgpu::util::DeviceExt::create_buffer_init`, counted at the buffer's size (the contents
    /// padded to the copy alignment).
    #[allow(clippy::disallowed_methods)]
    pub fn create_buffer_init(&self, desc: &wgpu::util::BufferInitDescriptor) -> Buffer {
        let buffer = wgpu::util::DeviceExt::create_buffer_init(self.device, desc);
        let bytes = buffer.size();
        self.ledger.track(buffer, bytes)
    }

    /// `wgpu::Device::create_texture`, counted at its format footprint, mip levels and samples
    /// included.
    #[allow(clippy::disallowed_methods)]
    pub fn create_texture(&self, desc: &wgpu::TextureDescriptor) -> Texture {
        let bytes = texture_bytes(desc);
        self.ledger.track(self.device.create_texture(desc), bytes)
    }
}

impl Alloc<'_> {
    /// Counted at 8 bytes a query, the size of the timestamp each resolves to.
    #[allow(clippy::disallowed_methods)]
    pub fn create_query_set(&self, desc: &wgpu::QuerySetDescriptor) -> Tracked<wgpu::QuerySet> {
        // A query's result: one u64, or one for each statistic a statistics query counts.
        let words = match desc.ty {
            wgpu::QueryType::PipelineStatistics(kinds) => kinds.bits().count_ones(),
            _ => 1,
        };
        let bytes = 8 * u64::from(words) * u64::from(desc.count);
        self.ledger.track(self.device.create_query_set(desc), bytes)
    }
}

/// A texture's footprint: each mip level's extent in the format's blocks, times the samples.
pub(crate) fn texture_bytes(desc: &wgpu::TextureDescriptor) -> u64 {
    (0..desc.mip_level_count)
        .filter_map(|level| desc.mip_level_size(level))
        .map(|size| desc.format.theoretical_memory_footprint(size))
        .sum::<u64>()
        * u64::from(desc.sample_count)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_ledger_counts_what_lives_and_forgets_what_is_dropped() {
        let ledger = Ledger::default();
        let a = ledger.track("a", 1000);
        let b = ledger.track("b", 24);
        assert_eq!(ledger.bytes(), 1024);
        assert_eq!(*a, "a");
        drop(a);
        assert_eq!(ledger.bytes(), 24);
        let shared = ledger.clone();
        drop(b);
        assert_eq!(shared.bytes(), 0);
    }

    #[test]
    fn a_texture_counts_its_format_samples_and_mip_levels() {
        let desc = |format, mips, samples| wgpu::TextureDescriptor {
            label: None,
            size: wgpu::Extent3d {
                width: 64,
                height: 32,
                depth_or_array_layers: 1,
            },
            mip_level_count: mips,
            sample_count: samples,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            view_formats: &[],
        };
        let rgba = wgpu::TextureFormat::Rgba8UnormSrgb;
        assert_eq!(texture_bytes(&desc(rgba, 1, 1)), 64 * 32 * 4);
        assert_eq!(texture_bytes(&desc(rgba, 1, 4)), 64 * 32 * 4 * 4);
        // 64×32, 32×16, 16×8: the chain of levels, each a quarter of the one before.
        let chain = (64 * 32 + 32 * 16 + 16 * 8) * 8;
        assert_eq!(
            texture_bytes(&desc(wgpu::TextureFormat::Rgba16Float, 3, 1)),
            chain
        );
        assert_eq!(
            texture_bytes(&desc(wgpu::TextureFormat::Depth32Float, 1, 1)),
            64 * 32 * 4
        );
    }
}
