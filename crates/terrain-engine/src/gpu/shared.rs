//! What every renderer on one device shares: pipelines and bind group layouts, made once, and the
//! sketch uploaded whole, once per sketch while a renderer holds it (compare's dozens of
//! settings, view's one renderer per mode).
//!
//! Rules: an object is keyed by everything its descriptor depends on besides the device — the
//! pass's name, the shader variant, and for render pipelines the targets' formats, samples and
//! depth state — written as text, so a key that leaves something out shows in the key's
//! construction beside the descriptor. Layouts are shared as well as pipelines, so a renderer's
//! bind groups are made from the very layout the shared pipeline was made with. A sketch is
//! keyed by a hash of its texels and held weakly: it is freed with the last renderer drawing it,
//! and counted in the ledger of the renderer that uploaded it.
//!
//! Why: a software rasterizer compiles each pipeline to machine code that stays resident as long
//! as the pipeline, so renderers with pipelines of their own cost more than their buffers
//! (docs/decisions.md, “Pipelines shared on a device”). Rejected: wgpu's `PipelineCache`, which
//! caches the driver's compilation on some backends but still makes one resident pipeline per
//! call.

use super::alloc::Buffer;
use std::collections::HashMap;
use std::sync::{Arc, Mutex, MutexGuard, Weak};

/// The shared objects of one device. Cheap to clone (shared maps).
#[derive(Clone, Default)]
pub struct OnDevice {
    objects: Arc<Mutex<HashMap<String, Object>>>,
    sketches: Arc<Mutex<HashMap<u64, Weak<Buffer>>>>,
}

/// One shared pipeline or layout.
#[derive(Clone)]
enum Object {
    Compute(wgpu::ComputePipeline),
    Render(wgpu::RenderPipeline),
    Layout(wgpu::BindGroupLayout),
}

impl OnDevice {
    /// The compute pipeline keyed `key`, made by `make` the first time.
    pub(crate) fn compute<E>(
        &self,
        key: String,
        make: impl FnOnce() -> Result<wgpu::ComputePipeline, E>,
    ) -> Result<wgpu::ComputePipeline, E> {
        match self.get_or(format!("compute {key}"), || make().map(Object::Compute))? {
            Object::Compute(p) => Ok(p),
            _ => unreachable!("each kind keys with its own prefix"),
        }
    }

    /// The render pipeline keyed `key`, made by `make` the first time.
    pub(crate) fn render<E>(
        &self,
        key: String,
        make: impl FnOnce() -> Result<wgpu::RenderPipeline, E>,
    ) -> Result<wgpu::RenderPipeline, E> {
        match self.get_or(format!("render {key}"), || make().map(Object::Render))? {
            Object::Render(p) => Ok(p),
            _ => unreachable!("each kind keys with its own prefix"),
        }
    }

    /// The bind group layout keyed `key`, made by `make` the first time.
    pub(crate) fn layout(
        &self,
        key: String,
        make: impl FnOnce() -> wgpu::BindGroupLayout,
    ) -> wgpu::BindGroupLayout {
        match self.get_or(format!("layout {key}"), || {
            Ok::<_, ()>(Object::Layout(make()))
        }) {
            Ok(Object::Layout(l)) => l,
            _ => unreachable!("each kind keys with its own prefix"),
        }
    }

    /// The sketch whose texels hash to `key`, uploaded by `make` where no renderer holds it.
    pub(crate) fn sketch(&self, key: u64, make: impl FnOnce() -> Buffer) -> Arc<Buffer> {
        let mut sketches = lock(&self.sketches);
        if let Some(held) = sketches.get(&key).and_then(Weak::upgrade) {
            return held;
        }
        sketches.retain(|_, w| w.strong_count() > 0);
        let made = Arc::new(make());
        sketches.insert(key, Arc::downgrade(&made));
        made
    }

    fn get_or<E>(
        &self,
        key: String,
        make: impl FnOnce() -> Result<Object, E>,
    ) -> Result<Object, E> {
        if let Some(found) = lock(&self.objects).get(&key) {
            return Ok(found.clone());
        }
        // Made outside the lock: a pipeline compiles for a while, and two renderers built on
        // two threads at once make it twice at worst, the first kept.
        let made = make()?;
        Ok(lock(&self.objects).entry(key).or_insert(made).clone())
    }
}

/// The map behind `m`; a panic while it was held leaves it whole (inserts are single calls).
fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|e| e.into_inner())
}
