//! The GPU context: a headless device on whatever adapter the machine has (`WGPU_BACKEND` chooses
//! among backends; without a GPU, Mesa's lavapipe through Vulkan where it is installed, else
//! llvmpipe through GL), its limits checked up front.

use crate::error::{Error, Result};

/// Cheap to clone (wgpu's handles are reference counted): renderers of several modes and settings
/// share one device, as `compare` and `batch` do.
#[derive(Clone)]
pub struct GpuContext {
    /// The device, opened with the adapter's own limits and, where offered, timestamp queries.
    pub device: wgpu::Device,
    /// The device's queue.
    pub queue: wgpu::Queue,
    /// The adapter's name, backend and kind, as reports print them.
    pub adapter: wgpu::AdapterInfo,
    /// Whether passes can be timed with timestamp queries.
    pub timestamps: bool,
    /// The adapter's limits, which the device was opened with.
    pub limits: wgpu::Limits,
    /// The most samples per pixel the terrain pass's targets allow: 4, or 1 where they cannot
    /// be multisampled.
    pub msaa: u32,
    /// A software rasterizer (llvmpipe, lavapipe, WARP): no hardware to multisample for free.
    pub software: bool,
    /// The first error wgpu raised outside any call that returns one (an allocation out of
    /// memory) or the device's loss, on a device this context opened: [`GpuContext::wait`]
    /// returns it (shared by the context's clones).
    /// wgpu's own handler panics; a host's device keeps the host's handler (empty then).
    raised: Raised,
    /// What every renderer on this device shares: pipelines, layouts, the sketch (shared by the
    /// context's clones).
    pub shared: crate::gpu::shared::OnDevice,
}

/// The first error a device raised outside a call: what happened ("the device refused", "the
/// device was lost") and wgpu's words for it, as text (wgpu's errors are not `Clone`).
type Raised = std::sync::Arc<std::sync::Mutex<Option<(&'static str, String)>>>;

/// What the renderer needs of a device, checked before anything is created.
pub struct Needs {
    /// The largest storage buffer: the atlas pyramid or the detailed geometry image.
    pub storage_bytes: u64,
}

impl GpuContext {
    /// Opens a device on the best adapter `WGPU_BACKEND` allows and checks it against `needs`:
    /// [`Error::Device`] where there is no adapter or device, [`Error::Limit`] where a limit is
    /// too low.
    pub fn new(needs: &Needs) -> Result<GpuContext> {
        let instance =
            wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
        let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            force_fallback_adapter: false,
            compatible_surface: None,
            apply_limit_buckets: false,
        }))
        .map_err(|e| {
            Error::device(
                "no adapter (without a GPU, install Mesa; Debian: apt-get install libegl1 libgl1-mesa-dri, or mesa-vulkan-drivers)",
                e,
            )
        })?;
        let info = adapter.get_info();
        let limits = adapter.limits();
        check(&info.name, &limits, needs)?;
        let name = &info.name;
        // Lavapipe (Mesa's CPU Vulkan) stamps compute passes as they are queued, not as they run:
        // warp & zoom read 0.1 ms there against 64 ms from llvmpipe's GL driver on the same
        // machine, whose wall time both agree with. Its frames are timed by wall time instead.
        let lavapipe =
            info.backend == wgpu::Backend::Vulkan && info.device_type == wgpu::DeviceType::Cpu;
        let timestamps = adapter.features().contains(wgpu::Features::TIMESTAMP_QUERY) && !lavapipe;
        let mut required_features = if timestamps {
            wgpu::Features::TIMESTAMP_QUERY
        } else {
            wgpu::Features::empty()
        };
        // GeoMipMap over a tile pyramid reads the sketch in its vertex shader, which marks the
        // tiles it reads; where the adapter cannot, that mode says so and the others do not care.
        required_features |= adapter.features() & wgpu::Features::VERTEX_WRITABLE_STORAGE;
        // Each pass's work counted (`gpu::counters`), where the adapter counts it.
        required_features |= adapter.features() & wgpu::Features::PIPELINE_STATISTICS_QUERY;
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("terrain"),
            required_features,
            required_limits: limits.clone(),
            experimental_features: wgpu::ExperimentalFeatures::disabled(),
            memory_hints: wgpu::MemoryHints::Performance,
            trace: wgpu::Trace::Off,
        }))
        .map_err(|e| Error::device(format!("{name}: cannot open the device"), e))?;
        use super::formats::{COLOUR, DEPTH, DEPTH_COPY};
        let x4 = [COLOUR, DEPTH, DEPTH_COPY].iter().all(|&f| {
            adapter
                .get_texture_format_features(f)
                .flags
                .sample_count_supported(4)
        });
        let raised = Raised::default();
        let first = raised.clone();
        device.on_uncaptured_error(std::sync::Arc::new(move |e: wgpu::Error| {
            if let Ok(mut first) = first.lock() {
                first.get_or_insert_with(|| ("the device refused", e.to_string()));
            }
        }));
        // A lost device (a driver reset, a GPU removed) fails every call after it, each in its
        // own words (a buffer that cannot be mapped, say): the loss itself is the error to tell.
        let lost = raised.clone();
        device.set_device_lost_callback(move |reason, message| {
            if let Ok(mut first) = lost.lock() {
                let why = if message.is_empty() {
                    format!("{reason:?}")
                } else {
                    message
                };
                *first = Some(("the device was lost", why));
            }
        });
        Ok(GpuContext {
            device,
            queue,
            timestamps,
            limits,
            software: info.device_type == wgpu::DeviceType::Cpu,
            msaa: if x4 { 4 } else { 1 },
            adapter: info,
            raised,
            shared: Default::default(),
        })
    }

    /// A context on a host's device: its adapter, features and limits as the device reports
    /// them, refused in one error where they cannot hold what `needs` asks for. The host's
    /// targets fix multisampling, so the renderer's own frame is multisampled only on hardware
    /// (the formats it draws are multisampled wherever WebGPU runs).
    pub fn from_device(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        needs: &Needs,
    ) -> Result<GpuContext> {
        let info = device.adapter_info();
        let limits = device.limits();
        check(&info.name, &limits, needs)?;
        let software = info.device_type == wgpu::DeviceType::Cpu;
        let lavapipe = info.backend == wgpu::Backend::Vulkan && software;
        Ok(GpuContext {
            device: device.clone(),
            queue: queue.clone(),
            timestamps: device.features().contains(wgpu::Features::TIMESTAMP_QUERY) && !lavapipe,
            limits,
            software,
            msaa: if software { 1 } else { 4 },
            adapter: info,
            raised: Raised::default(),
            shared: Default::default(),
        })
    }

    /// Whether this device can hold what `needs` asks for (before anything is created: a buffer
    /// over a limit would otherwise be a validation error, which wgpu reports by panicking).
    pub fn check(&self, needs: &Needs) -> Result<()> {
        check(&self.adapter.name, &self.limits, needs)
    }

    /// Samples per pixel for `msaa` on this device.
    pub fn samples(&self, msaa: crate::scene::Msaa) -> u32 {
        use crate::scene::Msaa;
        match msaa {
            Msaa::Off => 1,
            Msaa::Auto if self.software => 1,
            Msaa::Auto | Msaa::X4 => self.msaa,
        }
    }

    /// Whether the mesh modes shade deferred (`render.deferred` asks; `gpu::terrain`'s
    /// `Deferred`): single-sampled frames, on an adapter that draws the G-buffer's targets at once.
    pub fn deferred(&self, asked: bool, samples: u32) -> bool {
        let targets = super::formats::GBUFFER.len() as u32;
        asked
            && samples == 1
            && self.limits.max_color_attachments >= targets
            && self.limits.max_color_attachment_bytes_per_sample >= 16 * targets
    }

    /// "name (backend)", for reports.
    pub fn adapter_name(&self) -> String {
        format!("{} ({:?})", self.adapter.name, self.adapter.backend)
    }

    /// Blocks until the queue is idle; the first error the device raised since it was opened
    /// (out of memory, a lost device), if any, as [`Error::Device`].
    pub fn wait(&self) -> Result<()> {
        let polled = self.device.poll(wgpu::PollType::wait_indefinitely());
        // The loss, where the device reported one, says more than the poll's failure.
        self.raised()?;
        polled
            .map(|_| ())
            .map_err(|e| Error::device("device lost while waiting", e))
    }

    /// The first error the device raised outside a call that returns one since the last
    /// asked, if any: returned once, so that a batch's next item on the same device starts clean.
    pub fn raised(&self) -> Result<()> {
        let first = self.raised.lock().ok().and_then(|mut f| f.take());
        match first {
            Some((what, e)) => Err(Error::device(what, Refused(e))),
            None => Ok(()),
        }
    }
}

fn check(name: &str, limits: &wgpu::Limits, needs: &Needs) -> Result<()> {
    if limits.max_storage_buffer_binding_size < needs.storage_bytes {
        return Err(Error::Limit {
            what: format!("{name}: the sketch's pyramid or the mesh"),
            limit: "max_storage_buffer_binding_size",
            needed: needs.storage_bytes >> 20,
            allowed: limits.max_storage_buffer_binding_size >> 20,
            unit: " MiB",
            advice: "",
        });
    }
    if limits.max_storage_buffers_per_shader_stage < 3 {
        return Err(Error::Limit {
            what: name.to_string(),
            limit: "max_storage_buffers_per_shader_stage",
            needed: 3,
            allowed: limits.max_storage_buffers_per_shader_stage.into(),
            unit: "",
            advice: " (the vertex stage reads 3)",
        });
    }
    Ok(())
}

/// An uncaptured wgpu error kept as its text, as the source of an [`Error::Device`]: on one
/// line, its kind and its innermost cause (wgpu's validation errors go on over several).
#[derive(Debug)]
struct Refused(String);

impl std::fmt::Display for Refused {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        // "Validation Error", then where and why, innermost last: the kind and the cause.
        let lines: Vec<&str> = self
            .0
            .lines()
            .map(str::trim)
            .filter(|l| !l.is_empty())
            .collect();
        match lines.as_slice() {
            [] => f.write_str("an error without a message"),
            [only] => f.write_str(only),
            [kind, .., cause] => write!(f, "{kind}: {cause}"),
        }
    }
}

impl std::error::Error for Refused {}

#[cfg(test)]
mod tests {
    use super::*;

    /// An allocation the device refuses (here a buffer over its limit; out of memory alike) is
    /// an error from `wait`, once, in one line, where wgpu's own handler panics.
    #[test]
    #[allow(clippy::disallowed_methods)]
    fn a_refused_allocation_is_one_error_not_a_panic() {
        let ctx = GpuContext::new(&Needs { storage_bytes: 0 }).unwrap();
        let _too_big = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("too big"),
            size: (ctx.limits.max_buffer_size + 4) & !3,
            usage: wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        });
        let err = ctx.wait().unwrap_err().to_string();
        assert!(
            err.starts_with("GPU: the device refused: Validation Error: ") && !err.contains('\n'),
            "{err}"
        );
        assert!(ctx.wait().is_ok(), "the error is returned once");
    }
}
