//! Pipelines and bind group layouts made once per device: every renderer on a device (compare's
//! dozens of settings, view's one per mode) shares them.
//!
//! Rules: an object is keyed by everything its descriptor depends on besides the device — the
//! pass's name, the shader variant, and for render pipelines the targets' formats, samples and
//! depth state — written as text, so a key that leaves something out shows in the key's
//! construction beside the descriptor. Layouts are shared as well as pipelines, so a renderer's
//! bind groups are made from the very layout the shared pipeline was made with.
//!
//! Why: a software rasterizer compiles each pipeline to machine code that stays resident as long
//! as the pipeline, so renderers with pipelines of their own cost more than their buffers
//! (docs/decisions.md, “Pipelines shared on a device”). Rejected: wgpu's `PipelineCache`, which
//! caches the driver's compilation on some backends but still makes one resident pipeline per
//! call.

use std::collections::HashMap;
use std::sync::{Arc, Mutex};

/// The shared objects of one device. Cheap to clone (shared map).
#[derive(Clone, Default)]
pub struct Pipelines(Arc<Mutex<HashMap<String, Shared>>>);

/// One shared object.
#[derive(Clone)]
enum Shared {
    Compute(wgpu::ComputePipeline),
    Render(wgpu::RenderPipeline),
    Layout(wgpu::BindGroupLayout),
}

impl Pipelines {
    /// The compute pipeline keyed `key`, made by `make` the first time.
    pub(crate) fn compute<E>(
        &self,
        key: String,
        make: impl FnOnce() -> Result<wgpu::ComputePipeline, E>,
    ) -> Result<wgpu::ComputePipeline, E> {
        match self.get_or(format!("compute {key}"), || make().map(Shared::Compute))? {
            Shared::Compute(p) => Ok(p),
            _ => unreachable!("each kind keys with its own prefix"),
        }
    }

    /// The render pipeline keyed `key`, made by `make` the first time.
    pub(crate) fn render(
        &self,
        key: String,
        make: impl FnOnce() -> wgpu::RenderPipeline,
    ) -> wgpu::RenderPipeline {
        let made = self.get_or(format!("render {key}"), || {
            Ok::<_, ()>(Shared::Render(make()))
        });
        match made {
            Ok(Shared::Render(p)) => p,
            _ => unreachable!("each kind keys with its own prefix"),
        }
    }

    /// The bind group layout keyed `key`, made by `make` the first time.
    pub(crate) fn layout(
        &self,
        key: String,
        make: impl FnOnce() -> wgpu::BindGroupLayout,
    ) -> wgpu::BindGroupLayout {
        let made = self.get_or(format!("layout {key}"), || {
            Ok::<_, ()>(Shared::Layout(make()))
        });
        match made {
            Ok(Shared::Layout(l)) => l,
            _ => unreachable!("each kind keys with its own prefix"),
        }
    }

    /// How many objects are shared now.
    pub fn len(&self) -> usize {
        self.lock().len()
    }

    /// Whether none is.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    fn get_or<E>(
        &self,
        key: String,
        make: impl FnOnce() -> Result<Shared, E>,
    ) -> Result<Shared, E> {
        if let Some(found) = self.lock().get(&key) {
            return Ok(found.clone());
        }
        // Made outside the lock: a pipeline compiles for a while, and two renderers built on
        // two threads at once make it twice at worst, the first kept.
        let made = make()?;
        Ok(self.lock().entry(key).or_insert(made).clone())
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, HashMap<String, Shared>> {
        // A panic while the map was held leaves it whole (inserts are single calls).
        self.0.lock().unwrap_or_else(|e| e.into_inner())
    }
}
