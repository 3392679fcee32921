//! The warped mode (Dachsbacher & Stamminger): the CPU stage places the geometry image, then a
//! frame is three named passes: warp & zoom, normals, terrain (with the sky). Sky-only frames
//! skip the first two and the terrain draw.

use super::{CpuTimes, Lod, Shared};
use crate::camera::Camera;
use crate::error::Result;
use crate::gpu::alloc::Buffer;
use crate::gpu::context::GpuContext;
use crate::gpu::frame_io::{ColourReadback, Timer, read_vec4};
use crate::gpu::normals::NormalsPass;
use crate::gpu::terrain::{Shading, TerrainPass, Variant};
use crate::gpu::uniforms::{FrameInputs, View};
use crate::gpu::warp_zoom::WarpZoomPass;
use crate::sketch::Atlas;
use crate::stage::CpuStage;
use std::any::Any;

/// The passes of a warped frame, in order.
const PASSES: [&str; 3] = [WarpZoomPass::NAME, NormalsPass::NAME, TerrainPass::NAME];
/// With pixel normals the mesh's normals are never read: no normals pass.
const PASSES_PIXEL_NORMALS: [&str; 2] = [WarpZoomPass::NAME, TerrainPass::NAME];

pub struct Warped {
    pub stage: CpuStage,
    warp_zoom: WarpZoomPass,
    /// The mesh's normals, unless the terrain is lit per pixel (`render.pixel_normals`).
    normals: Option<NormalsPass>,
    terrain: TerrainPass,
    importance: Option<Buffer>,
    readback: ColourReadback,
    /// Whether the GPU's Φ (and importance) buffers hold the stage's current warp.
    phi_on_gpu: bool,
}

impl Warped {
    pub fn new(s: &Shared) -> Result<Warped> {
        let device = &s.alloc;
        let (n, mesh) = (s.scene.warp.size, s.scene.warp.mesh);
        let (width, height) = (s.scene.camera.width, s.scene.camera.height);
        let stage = CpuStage::new(s.scene, s.detail)?;
        let noise = s.detail.octaves > 0;
        let warp_zoom = WarpZoomPass::new(device, s.frame, s.atlas_binding, n, mesh, noise)?;
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
            noise,
            bump: noise && s.scene.detail.bump,
            shading: match &normals {
                Some(pass) => Shading::MeshNormals(wgpu::Buffer::clone(&pass.normals)),
                None => Shading::PixelNormals,
            },
            importance: importance.as_ref().map(|b| wgpu::Buffer::clone(b)),
            geomipmap: None,
            positions: s.positions,
            atlas: s.atlas_binding.clone(),
            shadows: s.scene.render.shadows,
            detail_shadows: s.scene.render.detail_shadows,
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
        let readback = ColourReadback::new(device, width, height);
        Ok(Warped {
            stage,
            warp_zoom,
            normals,
            terrain,
            importance,
            readback,
            phi_on_gpu: false,
        })
    }

    /// The detailed geometry image of the last frame, read back (for tests).
    pub fn read_detailed(&self, ctx: &GpuContext) -> Result<Vec<[f32; 4]>> {
        read_vec4(ctx, &self.warp_zoom.detailed)
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
        if self.normals.is_some() {
            &PASSES
        } else {
            &PASSES_PIXEL_NORMALS
        }
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
        t: Option<&Timer>,
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
            self.terrain.use_quad_mesh(queue, m);
            let warp_zoom = t.map(|t| t.compute(WarpZoomPass::NAME));
            self.warp_zoom.record(encoder, m, warp_zoom);
            if let Some(normals) = &self.normals {
                normals.record(encoder, m, t.map(|t| t.compute(NormalsPass::NAME)));
            }
        }
        let terrain = t.map(|t| t.render(TerrainPass::NAME));
        self.terrain.record(encoder, visible, terrain);
        self.readback.record(encoder, &self.terrain.colour);
        // A sky-only frame runs the terrain pass alone (for the sky).
        let passes = self.passes();
        if visible {
            passes
        } else {
            &passes[passes.len() - 1..]
        }
    }

    fn read_image(&self, ctx: &GpuContext) -> Result<Vec<u8>> {
        self.readback.read(ctx)
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
