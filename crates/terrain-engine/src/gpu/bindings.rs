//! Each pass's bind groups, declared once: a list of [`Binding`]s (group, index, the WGSL
//! variable's name, kind, stages, and the variants that declare it) from which the pass makes both
//! its bind-group layout and its bind group, the bind group given its resources by name.
//!
//! Rules: a binding's index is written once in Rust and once in its WGSL declaration, and
//! `checks/bindings.rs` (a unit test) holds every pass's list ([`super::SHADERS`]) to the `@group @binding` declarations naga
//! reflects from every variant of the pass's WGSL (index, name and kind), so a binding renumbered
//! on one side fails there; a declared binding given no resource is an error, not a panic in wgpu.
//! Rejected alternative: reflecting the layout from the WGSL with naga when a pass is built, which
//! puts a WGSL front end in every renderer for what a test checks once, and still leaves the
//! stages and the resources to Rust.

use super::alloc::Alloc;
use super::shaders::Key;
use crate::error::{Error, Result};
use wgpu::ShaderStages as S;

/// What a binding holds, as the WGSL declares it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Kind {
    /// `var<uniform>`.
    Uniform,
    /// `var<storage, read>`.
    Storage,
    /// `var<storage, read_write>`.
    StorageRw,
    /// `texture_2d<u32>`, single-sampled.
    UintTexture,
    /// `texture_2d<f32>`, single-sampled, read with `textureLoad` (not filtered).
    FloatTexture,
}

impl Kind {
    fn ty(self) -> wgpu::BindingType {
        let texture = |sample_type| wgpu::BindingType::Texture {
            sample_type,
            view_dimension: wgpu::TextureViewDimension::D2,
            multisampled: false,
        };
        let buffer = |ty| wgpu::BindingType::Buffer {
            ty,
            has_dynamic_offset: false,
            min_binding_size: None,
        };
        match self {
            Kind::Uniform => buffer(wgpu::BufferBindingType::Uniform),
            Kind::Storage => buffer(wgpu::BufferBindingType::Storage { read_only: true }),
            Kind::StorageRw => buffer(wgpu::BufferBindingType::Storage { read_only: false }),
            Kind::UintTexture => texture(wgpu::TextureSampleType::Uint),
            Kind::FloatTexture => texture(wgpu::TextureSampleType::Float { filterable: false }),
        }
    }
}

/// One binding of a pass.
#[derive(Clone, Copy, Debug)]
pub struct Binding {
    pub group: u32,
    pub index: u32,
    /// The WGSL variable's name; the bind group's resource is given under it.
    pub name: &'static str,
    pub kind: Kind,
    pub stages: wgpu::ShaderStages,
    /// Whether the variant with this key declares it.
    pub when: fn(Key) -> bool,
}

fn always(_: Key) -> bool {
    true
}

impl Binding {
    pub const fn new(index: u32, name: &'static str, kind: Kind, stages: S) -> Binding {
        Binding {
            group: 0,
            index,
            name,
            kind,
            stages,
            when: always,
        }
    }

    pub const fn uniform(index: u32, name: &'static str, stages: S) -> Binding {
        Binding::new(index, name, Kind::Uniform, stages)
    }

    pub const fn storage(index: u32, name: &'static str, stages: S) -> Binding {
        Binding::new(index, name, Kind::Storage, stages)
    }

    pub const fn storage_rw(index: u32, name: &'static str, stages: S) -> Binding {
        Binding::new(index, name, Kind::StorageRw, stages)
    }

    /// In bind group `group` instead of 0.
    pub const fn in_group(self, group: u32) -> Binding {
        Binding { group, ..self }
    }

    /// Declared only by the variants `when` accepts.
    pub const fn when(self, when: fn(Key) -> bool) -> Binding {
        Binding { when, ..self }
    }

    /// The frame's uniform block (`shaders/shared/frame.wgsl`'s users).
    pub const fn frame(stages: S) -> Binding {
        Binding::uniform(0, "frame", stages)
    }

    /// The sketch's heights, whole or the tile cache's pages and page table
    /// (`shaders/shared/atlas.wgsl`).
    pub const fn atlas(stages: S) -> Binding {
        Binding::storage(1, "atlas", stages)
    }

    /// A streamed sketch's marks of the tiles read (`shaders/shared/atlas.wgsl`).
    pub const fn wanted(stages: S) -> Binding {
        Binding::storage_rw(7, "wanted", stages).when(|k| k.contains(Key::STREAMED))
    }

    /// The counting variant's tallies (`shaders/shared/work.wgsl`, [`super::work`]), declared
    /// wherever the sketch is read.
    pub const fn work(stages: S) -> Binding {
        Binding::storage_rw(8, "work", stages).when(|k| k.contains(Key::COUNT_WORK))
    }

    /// The sketch's sun visibility map (`shaders/shared/shading.wgsl`, [`super::sun_map`]),
    /// declared wherever the shadow is.
    pub const fn sun_seen(stages: S) -> Binding {
        Binding::storage(9, "sun_seen", stages)
            .when(|k| k.contains(Key::SHADOWS.union(Key::SUN_MAP)))
    }

    /// The colour ramp's stops (`shaders/shared/shading.wgsl`, [`crate::surface::ramp`]),
    /// declared wherever the ground is lit with `surface.style = "ramp"`.
    pub const fn ramp(stages: S) -> Binding {
        Binding::storage(10, "ramp", stages).when(|k| k.contains(Key::RAMP))
    }

    /// The user's imagery on the sketch's grid (`shaders/shared/shading.wgsl`,
    /// [`crate::surface::image`]), declared wherever the ground is lit with `surface.image`.
    pub const fn drape(stages: S) -> Binding {
        Binding::storage(11, "drape", stages).when(|k| k.contains(Key::IMAGE))
    }

    /// Whether variant `key` declares it.
    pub fn declared(&self, key: Key) -> bool {
        (self.when)(key)
    }
}

/// The bindings of `group` that variant `key` declares.
fn declared(bindings: &[Binding], group: u32, key: Key) -> impl Iterator<Item = &Binding> {
    bindings
        .iter()
        .filter(move |b| b.group == group && b.declared(key))
}

/// The layout of bind group `group` of variant `key`.
pub(crate) fn layout(
    device: &Alloc,
    label: &str,
    bindings: &[Binding],
    group: u32,
    key: Key,
) -> wgpu::BindGroupLayout {
    // One pass's bindings under one label: the label, group and variant key the layout.
    let shared = format!("{label} {group} {key:?}");
    device.shared.layout(shared, || {
        let entries: Vec<_> = declared(bindings, group, key)
            .map(|b| wgpu::BindGroupLayoutEntry {
                binding: b.index,
                visibility: b.stages,
                ty: b.kind.ty(),
                count: None,
            })
            .collect();
        device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some(label),
            entries: &entries,
        })
    })
}

/// Bind group `group` of variant `key`, each declared binding given the resource `resources`
/// names it by (resources no binding of the variant declares are left out).
pub(crate) fn bind_group(
    device: &wgpu::Device,
    label: &str,
    layout: &wgpu::BindGroupLayout,
    bindings: &[Binding],
    group: u32,
    key: Key,
    resources: &[(&str, wgpu::BindingResource)],
) -> Result<wgpu::BindGroup> {
    let entries = declared(bindings, group, key)
        .map(|b| {
            let (_, resource) =
                resources
                    .iter()
                    .find(|(name, _)| *name == b.name)
                    .ok_or(Error::Internal(
                        "a pass's shader declares a binding it was given nothing for",
                    ))?;
            Ok(wgpu::BindGroupEntry {
                binding: b.index,
                resource: resource.clone(),
            })
        })
        .collect::<Result<Vec<_>>>()?;
    Ok(device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some(label),
        layout,
        entries: &entries,
    }))
}

/// A whole buffer as a binding's resource.
pub(crate) fn buffer(buffer: &wgpu::Buffer) -> wgpu::BindingResource<'_> {
    buffer.as_entire_binding()
}
