//! The warped mode (Dachsbacher & Stamminger): the CPU stage places the geometry image, then a
//! frame is named passes: warp & zoom, mesh split (with `warp.triangulation = "adaptive"`),
//! normals (unless lit per pixel), terrain (with the sky). Sky-only frames run the terrain pass
//! alone.

pub mod mesh_split;
#[cfg(test)]
mod tests;

use super::{CpuTimes, Lod, Shared};
use crate::camera::Camera;
use crate::error::Result;
use crate::gpu::alloc::Buffer;
use crate::gpu::context::GpuContext;
use crate::gpu::counters::Probe;
use crate::gpu::frame_io::{read_pod, read_vec4};
use crate::gpu::normals::NormalsPass;
use crate::gpu::shaders::Key;
use crate::gpu::terrain::{TerrainPass, Variant};
use crate::gpu::uniforms::{FrameInputs, View};
use crate::gpu::warp_zoom::WarpZoomPass;
use crate::scene::{Mode, Scene, Triangulation};
use crate::sketch::Atlas;
use crate::stage::Budget;
use crate::stage::CpuStage;
use mesh_split::MeshSplitPass;
use std::any::Any;

/// The passes of a warped frame, in order, for each choice of (adaptive triangulation, mesh
/// normals): the mesh split runs only for the first, the normals pass only for the second.
const PASSES: [&[&str]; 4] = [
    &[WarpZoomPass::NAME, TerrainPass::NAME],
    &[WarpZoomPass::NAME, NormalsPass::NAME, TerrainPass::NAME],
    &[WarpZoomPass::NAME, MeshSplitPass::NAME, TerrainPass::NAME],
    &[
        WarpZoomPass::NAME,
        MeshSplitPass::NAME,
        NormalsPass::NAME,
        TerrainPass::NAME,
    ],
];

/// The warped mode's scheme.
pub(crate) const SCHEME: super::Scheme = super::Scheme {
    build: |s| Ok(Box::new(Warped::new(s)?)),
    needs: <Warped as Lod>::needs,
    flags: |s, key| {
        super::mesh_flags(s, key);
        let adaptive = s.scene.warp.triangulation == Triangulation::Adaptive;
        key.set(Key::CENTRES, adaptive);
        key.set(Key::IMPORTANCE_VIEW, s.view == View::Importance);
    },
    sweep,
    shaders: &[mesh_split::SHADER],
    setting: |scene, _| Some(own_setting(scene)),
};

/// The values of the warped row's swept keys the scene draws with.
fn own_setting(scene: &Scene) -> Vec<f64> {
    let w = &scene.warp;
    vec![w.quad_px, w.mesh as f64, w.budget as u8 as f64]
}

/// The largest mesh `compare` sweeps: 2M triangles.
const SWEEP_MAX_MESH: u32 = 1024;
/// The most triangles a pixel the sweep draws: GeoMipMap's τ = 0.5 reaches 6.4 on the bundled
/// views at 256².
const SWEEP_MAX_TRIANGLES_PER_PX: f64 = 8.0;
/// The smallest: 450 triangles, below GeoMipMap's fewest on the bundled views from high up (512
/// and 874 at 256²), where the budget's own smallest (`warp.min_mesh`, 32) would start at 1,922.
const SWEEP_MIN_MESH: u32 = 16;

/// `compare`'s warped rows (`warp.quad_px`, `warp.mesh`, `warp.budget`): meshes of fixed size
/// (`warp.budget` off) on the budget's ladder (`stage::budget`: rungs about 2^(1/4) apart from
/// 16², so triangles about half an octave apart) up to 8 triangles a pixel, and the scene's own
/// setting, the mesh its view asks for (the rung it draws is not repeated as a fixed row).
///
/// Rejected: a fixed list of mesh bounds (every bound above the view's own demand draws the same
/// mesh, and its steps are too coarse to tell whether warped beats GeoMipMap between them);
/// `quad_px` ÷√2, ÷2, ÷2√2 above the view's mesh (with the geometric-error term the rows jump by
/// octaves of triangles); the product of `quad_px` and mesh size (at a fixed mesh `quad_px`
/// changes Φ only where the surface bound or the floor clip the importance). docs/decisions.md,
/// “Warped sweep”.
fn sweep(scene: &Scene, atlas: &Atlas, camera: &Camera) -> Result<super::Settings> {
    let w = &scene.warp;
    let drawn = if w.budget {
        view_mesh(scene, atlas, camera)?.min(w.mesh)
    } else {
        w.mesh
    };
    let pixels = camera.width as f64 * camera.height as f64;
    let fits = |m: u32| 2.0 * (m as f64 - 1.0).powi(2) <= SWEEP_MAX_TRIANGLES_PER_PX * pixels;
    let mut out: Vec<Vec<f64>> = Budget::new(SWEEP_MIN_MESH, SWEEP_MAX_MESH)
        .rungs()
        .iter()
        .filter(|&&m| m != drawn && (m == SWEEP_MIN_MESH || fits(m)))
        .map(|&mesh| vec![w.quad_px, mesh as f64, 0.0])
        .collect();
    out.push(own_setting(scene));
    Ok(out)
}

/// The mesh side the view asks for at the scene's `quad_px`, up to [`SWEEP_MAX_MESH`].
fn view_mesh(scene: &Scene, atlas: &Atlas, camera: &Camera) -> Result<u32> {
    let mut s = scene.clone();
    s.warp.mesh = SWEEP_MAX_MESH.max(s.warp.mesh);
    let detail = crate::scene::detail_for(&s, atlas, Mode::Warped);
    let mut stage = CpuStage::new(&s, &detail)?;
    stage.run(atlas, camera);
    Ok(stage.mesh)
}

/// Geometry image warping (Dachsbacher & Stamminger, *Rendering Procedural Terrain by Geometry
/// Image Warping*, 2004): the CPU stage's Φ upsampled to the mesh, split, lit and drawn.
pub struct Warped {
    /// The CPU stage: sketch map, importance, warp.
    pub stage: CpuStage,
    warp_zoom: WarpZoomPass,
    /// Each cell's diagonal, with an adaptive triangulation (`warp.triangulation`).
    mesh_split: Option<MeshSplitPass>,
    /// The mesh's normals, unless the terrain is lit per pixel (`render.pixel_normals`).
    normals: Option<NormalsPass>,
    terrain: TerrainPass,
    importance: Option<Buffer>,
    /// Whether the GPU's Φ (and importance) buffers hold the stage's current warp.
    phi_on_gpu: bool,
}

impl Warped {
    /// The largest mesh side `compare` sweeps (2M triangles).
    pub const SWEEP_MAX_MESH: u32 = SWEEP_MAX_MESH;

    /// The scheme of the scene: its stage and passes, sized for `warp.size` and `warp.mesh`.
    pub fn new(s: &Shared) -> Result<Warped> {
        let device = &s.alloc;
        let (n, mesh) = (s.scene.warp.size, s.scene.warp.mesh);
        let (width, height) = (s.scene.camera.width, s.scene.camera.height);
        let stage = CpuStage::new(s.scene, s.detail)?;
        let key = super::shader_key(s, Mode::Warped);
        let warp_zoom = WarpZoomPass::new(device, s.frame, s.atlas_binding, n, mesh, key)?;
        let normals = if s.scene.render.pixel_normals {
            None
        } else {
            Some(NormalsPass::new(
                device,
                s.frame,
                &warp_zoom.detailed,
                mesh,
            )?)
        };
        // The importance map goes to the GPU only for the view that shows it.
        let importance = (s.view == View::Importance).then(|| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("importance"),
                size: (n * n) as u64 * 4,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        });
        let variant = Variant {
            key,
            normals: normals
                .as_ref()
                .map(|pass| wgpu::Buffer::clone(&pass.normals)),
            importance: importance.as_ref().map(|b| wgpu::Buffer::clone(b)),
            geomipmap: None,
            atlas: s.atlas_binding.clone(),
            samples: s.samples,
        };
        let terrain = TerrainPass::new(
            device,
            s.frame,
            Some(&warp_zoom.detailed),
            mesh,
            width,
            height,
            &variant,
        )?;
        let mesh_split = match &warp_zoom.centres {
            Some(centres) => Some(MeshSplitPass::new(
                device,
                s.frame,
                &warp_zoom.detailed,
                centres,
                terrain.quad_mesh_indices(),
                mesh,
            )?),
            None => None,
        };
        Ok(Warped {
            stage,
            warp_zoom,
            mesh_split,
            normals,
            terrain,
            importance,
            phi_on_gpu: false,
        })
    }

    /// The detailed geometry image of the last frame, read back (for tests).
    pub fn read_detailed(&self, ctx: &GpuContext) -> Result<Vec<[f32; 4]>> {
        read_vec4(ctx, &self.warp_zoom.detailed)
    }

    /// The cell centres' heights of the last frame, read back (for tests); none with a fixed
    /// triangulation.
    pub fn read_centres(&self, ctx: &GpuContext) -> Result<Option<Vec<f32>>> {
        self.warp_zoom
            .centres
            .as_ref()
            .map(|b| read_pod(ctx, b))
            .transpose()
    }

    /// The quad mesh's indices of the last frame, read back (for tests).
    pub fn read_indices(&self, ctx: &GpuContext) -> Result<Vec<u32>> {
        read_pod(ctx, self.terrain.quad_mesh_indices())
    }

    /// The normals of the last frame, read back (for tests); none when lit per pixel.
    pub fn read_normals(&self, ctx: &GpuContext) -> Result<Option<Vec<[f32; 4]>>> {
        self.normals
            .as_ref()
            .map(|pass| read_vec4(ctx, &pass.normals))
            .transpose()
    }
}

impl Lod for Warped {
    fn passes(&self) -> &'static [&'static str] {
        PASSES[2 * self.mesh_split.is_some() as usize + self.normals.is_some() as usize]
    }

    /// The detailed geometry image, a vec4 per vertex; with an adaptive triangulation the quad
    /// indices are bound too (`mesh_split`), six u32 a cell, 1.5× as large.
    fn needs(scene: &crate::scene::Scene) -> u64 {
        let m = scene.warp.mesh as u64;
        let indices = match scene.warp.triangulation {
            Triangulation::Adaptive => m.saturating_sub(1).pow(2) * 24,
            Triangulation::Fixed => 0,
        };
        (m * m * 16).max(indices)
    }

    fn resize(&mut self, alloc: &crate::gpu::alloc::Alloc, width: u32, height: u32) -> Result<()> {
        self.terrain.resize(alloc, width, height)?;
        Ok(())
    }

    fn prepare(&mut self, atlas: &Atlas, camera: &Camera) -> CpuTimes {
        let stage = self.stage.run(atlas, camera);
        self.phi_on_gpu &= self.stage.held;
        CpuTimes {
            stage,
            us: stage.total_us(),
        }
    }

    fn frame_inputs<'a>(&'a self, f: &mut FrameInputs<'a>) {
        f.map = Some(&self.stage.sketch_map);
        f.mesh = self.stage.mesh;
        // Only the importance view reads its scale.
        if self.importance.is_some() {
            f.importance_max = self
                .stage
                .importance
                .importance
                .iter()
                .copied()
                .fold(0.0, f32::max);
        }
    }

    fn record(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        probe: Probe,
    ) -> &'static [&'static str] {
        let visible = self.stage.sketch_map.visible;
        if visible {
            let queue = &ctx.queue;
            // A held warp is on the GPU already once a frame has drawn it.
            if !self.phi_on_gpu {
                queue.write_buffer(
                    &self.warp_zoom.phi,
                    0,
                    bytemuck::cast_slice(&self.stage.warp.phi),
                );
                if let Some(buffer) = &self.importance {
                    let values = &self.stage.importance.importance;
                    queue.write_buffer(buffer, 0, bytemuck::cast_slice(values));
                }
                self.phi_on_gpu = true;
            }
            let m = self.stage.mesh;
            self.warp_zoom.record(encoder, m, probe);
            match &self.mesh_split {
                Some(split) => {
                    self.terrain.use_split_mesh(m);
                    split.record(encoder, m, probe);
                }
                None => self.terrain.use_quad_mesh(queue, m),
            }
            if let Some(normals) = &self.normals {
                normals.record(encoder, m, probe);
            }
        }
        self.terrain.record(encoder, visible, probe);
        // A sky-only frame runs the terrain pass alone (for the sky).
        let passes = self.passes();
        if visible {
            passes
        } else {
            &passes[passes.len() - 1..]
        }
    }

    fn output(&self) -> crate::gpu::output::Source<'_> {
        self.terrain.output()
    }

    fn read_positions(&self, ctx: &GpuContext, camera: &Camera) -> Result<Vec<[f32; 4]>> {
        self.terrain.read_positions(ctx, camera)
    }

    fn triangles(&self) -> u64 {
        if self.stage.sketch_map.visible {
            self.terrain.triangles()
        } else {
            0
        }
    }

    fn visible(&self) -> bool {
        self.stage.sketch_map.visible
    }

    fn forget(&mut self) {
        self.stage.forget();
    }

    fn as_any(&self) -> &dyn Any {
        self
    }

    fn as_any_mut(&mut self) -> &mut dyn Any {
        self
    }
}
