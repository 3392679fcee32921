//! What every renderer on one device shares: pipelines and bind group layouts, made once; the
//! sketch uploaded whole, once per sketch while a renderer holds it (compare's dozens of
//! settings, view's one renderer per mode); and the baselines' baked grid, once per terrain
//! function and grid while a renderer holds it (GeoMipMap's block sizes and brute force).
//!
//! Rules: an object is keyed by everything its descriptor depends on besides the device — the
//! pass's name, the shader variant, and for render pipelines the targets' formats, samples and
//! depth state — written as text, so a key that leaves something out shows in the key's
//! construction beside the descriptor. Layouts are shared as well as pipelines, so a renderer's
//! bind groups are made from the very layout the shared pipeline was made with. A sketch is
//! keyed by a hash of its texels, a baked grid by everything its bake reads; both are held
//! weakly: freed with the last renderer drawing them, and counted in the ledger of the renderer
//! that made them.
//!
//! Why: a software rasterizer compiles each pipeline to machine code that stays resident as long
//! as the pipeline, so renderers with pipelines of their own cost more than their buffers
//! (docs/decisions.md, “Pipelines shared on a device”). Rejected: wgpu's `PipelineCache`, which
//! caches the driver's compilation on some backends but still makes one resident pipeline per
//! call.

use super::alloc::Buffer;
use std::collections::HashMap;
use std::convert::Infallible;
use std::sync::{Arc, Mutex, MutexGuard, Weak};

/// The shared objects of one device. Cheap to clone (shared maps).
#[derive(Clone, Default)]
pub struct OnDevice {
    objects: Arc<Mutex<HashMap<String, Object>>>,
    sketches: Held<u64, Buffer>,
    grids: Held<String, BakedGrid>,
}

/// A grid baked by the terrain function: its vertices (and normals, unless the terrain is lit
/// per pixel) on the GPU, their heights on the CPU for the blocks' bounds once read back.
pub struct BakedGrid {
    /// Each vertex's position, split octave and spacing (vec4).
    pub detailed: Buffer,
    /// Each vertex's normal (vec4), unless the terrain is lit per pixel.
    pub normals: Option<Buffer>,
    /// Each vertex's height, rows first, once the device has read them back.
    pub heights: Heights,
}

/// A baked grid's heights on their way back from the GPU: natively there once the bake
/// returns (it waits for the device); in a browser, whose page cannot wait for its GPU, a few
/// of the page's tasks later.
#[derive(Clone, Default)]
pub struct Heights(Arc<Mutex<Option<ReadBack>>>);

/// The heights read back, or why they could not be.
type ReadBack = Result<Arc<[f32]>, String>;

impl Heights {
    /// Sets the heights read back, or why they could not be.
    pub(crate) fn set(&self, read: crate::error::Result<Vec<f32>>) {
        *lock(&self.0) = Some(read.map(Arc::from).map_err(|e| e.to_string()));
    }

    /// The heights, `None` while they are on their way, or the read-back's failure.
    pub fn get(&self) -> crate::error::Result<Option<Arc<[f32]>>> {
        match &*lock(&self.0) {
            None => Ok(None),
            Some(Ok(h)) => Ok(Some(h.clone())),
            Some(Err(e)) => Err(crate::error::Error::device(
                "reading the baked grid back",
                std::io::Error::other(e.clone()),
            )),
        }
    }
}

impl BakedGrid {
    /// GPU bytes the baked grid keeps: its positions, and its normals if it has them.
    pub fn bytes(&self) -> u64 {
        self.detailed.bytes() + self.normals.as_ref().map_or(0, |b| b.bytes())
    }
}

/// Objects held while some renderer holds them, by key.
struct Held<K, T>(Arc<Mutex<HashMap<K, Weak<T>>>>);

impl<K, T> Clone for Held<K, T> {
    fn clone(&self) -> Self {
        Held(self.0.clone())
    }
}

impl<K, T> Default for Held<K, T> {
    fn default() -> Self {
        Held(Default::default())
    }
}

impl<K: std::hash::Hash + Eq, T> Held<K, T> {
    /// The object keyed `key`, made by `make` where no renderer holds it. The lock is held while
    /// `make` runs: two renderers asking at once wait for one object rather than make two.
    fn get_or<E>(&self, key: K, make: impl FnOnce() -> Result<T, E>) -> Result<Arc<T>, E> {
        let mut held = lock(&self.0);
        if let Some(found) = held.get(&key).and_then(Weak::upgrade) {
            return Ok(found);
        }
        held.retain(|_, w| w.strong_count() > 0);
        let made = Arc::new(make()?);
        held.insert(key, Arc::downgrade(&made));
        Ok(made)
    }
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
        let Ok(sketch) = self.sketches.get_or(key, || Ok::<_, Infallible>(make()));
        sketch
    }

    /// The grid baked under `key` (everything the bake reads, written as text), baked by `make`
    /// where no renderer holds it.
    pub(crate) fn baked_grid<E>(
        &self,
        key: String,
        make: impl FnOnce() -> Result<BakedGrid, E>,
    ) -> Result<Arc<BakedGrid>, E> {
        self.grids.get_or(key, make)
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
