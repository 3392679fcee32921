//! The host API: a terrain drawn with a host application's own device and queue, recorded into
//! the host's encoder, into the host's colour and depth views, in the manner of vello, terra and
//! glyphon.
//!
//! Rules:
//! - The host owns the device, the queue and the targets. [`Description::required_limits`] and
//!   [`Description::optional_features`] say what to create the device with; [`Terrain::new`]
//!   refuses a device without them in one error.
//! - A frame: [`Terrain::prepare`] with the camera in f64 world metres (the CPU stage, the
//!   uniforms), or [`Terrain::prepare_held`] (the camera drawn with the last frame's level of
//!   detail, no CPU stage), then [`Terrain::record`] into the host's encoder; the host submits.
//!   The next `prepare` comes after that submission (a streamed sketch then reads what the frame
//!   marked).
//! - The terrain is drawn shaded unless [`Description::with_view`] asks for a debug view
//!   (wireframe, split octave, importance, normals, coverage); its depth is the same.
//! - Depth is reversed-Z with an infinite far plane, written for every pixel (0 where there is
//!   sky). Host geometry drawn with [`Terrain::view_proj`], positions relative to
//!   [`Terrain::frame_origin`], depth compare `GreaterEqual` on a depth cleared to 0, is hidden
//!   where the terrain is nearer, whether drawn before the terrain or after it.
//! - A frame of another size makes the targets that depend on the size again, nothing else
//!   (pipelines, meshes, the baked grid and the CPU stage stay).
//! - [`Terrain::render_to_image`] is a read-back on top, for snapshots; it is not the frame's path.
//!
//! Rejected: the renderer opening its own device and handing the host pixels, a copy through
//! the CPU every frame.

use crate::camera::Camera;
use crate::detail::Detail;
use crate::error::Result;
use crate::gpu::alloc::{Alloc, Ledger};
use crate::gpu::context::GpuContext;
use crate::gpu::output::OutputPass;
pub use crate::gpu::output::Targets;
pub use crate::gpu::output::clear;
use crate::gpu::snapshot::Snapshot;
pub use crate::gpu::uniforms::View;
use crate::query::Ground;
use crate::render::{Renderer, needs};
use crate::scene::{self, Mode, Scene};
use crate::sketch::Atlas;
use crate::stage::StageTimes;
use glam::{DVec3, Mat4, UVec2};

/// What a terrain is made from: a scene (sketch, detail, light, mode and its settings) with its
/// sketch read.
#[derive(Clone)]
pub struct Description {
    scene: Scene,
    atlas: Atlas,
    mode: Mode,
    view: View,
}

impl Description {
    /// `scene` with its sketch read, drawn in the scene's own mode.
    pub fn new(scene: Scene) -> Result<Description> {
        let atlas = scene::load_atlas(&scene)?;
        Ok(Description::with_atlas(scene, atlas))
    }

    /// `scene` over its sketch file's bytes (`sketch.path` names the file, whose name tells
    /// its format): a page that fetched the sketch, with no file system to read it from.
    pub fn from_bytes(scene: Scene, sketch: &[u8]) -> Result<Description> {
        let atlas = scene::load_atlas_from(&scene, sketch)?;
        Ok(Description::with_atlas(scene, atlas))
    }

    /// `scene` over its sketch already read (a host that builds several terrains of one sketch,
    /// as `terrain view` does for each mode, reads it once).
    pub fn with_atlas(scene: Scene, atlas: Atlas) -> Description {
        let mode = scene.render.mode;
        Description {
            scene,
            atlas,
            mode,
            view: View::Shaded,
        }
    }

    /// The same terrain drawn in `mode`.
    pub fn with_mode(mut self, mode: Mode) -> Description {
        self.mode = mode;
        self
    }

    /// The same terrain drawn in `view` (the importance view is the warped mode's only).
    pub fn with_view(mut self, view: View) -> Description {
        self.view = view;
        self
    }

    /// The scene this terrain was described by.
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// The sketch this terrain is drawn over.
    pub fn atlas(&self) -> &Atlas {
        &self.atlas
    }

    /// The procedural detail as this terrain's mode draws it (the octaves a mesh mode holds,
    /// the reference's footprint rules): with [`Description::atlas`] and [`Description::scene`]
    /// the [`Ground`] a [`Terrain`] of this description answers, without a GPU.
    pub fn detail(&self) -> Detail {
        scene::detail_for(&self.scene, &self.atlas, self.mode)
    }

    /// The limits a device must have to draw this terrain: WebGPU's defaults, raised where the
    /// sketch or the mesh needs larger storage bindings.
    pub fn required_limits(&self) -> wgpu::Limits {
        let storage = needs(&self.scene, self.mode, &self.atlas).storage_bytes;
        let defaults = wgpu::Limits::default();
        wgpu::Limits {
            max_storage_buffer_binding_size: defaults.max_storage_buffer_binding_size.max(storage),
            max_buffer_size: defaults.max_buffer_size.max(storage),
            ..defaults
        }
    }

    /// The features worth enabling where `available` has them: pass timing, and the vertex
    /// stage's writes that GeoMipMap over a tile pyramid marks its tiles with.
    pub fn optional_features(available: wgpu::Features) -> wgpu::Features {
        available & (wgpu::Features::TIMESTAMP_QUERY | wgpu::Features::VERTEX_WRITABLE_STORAGE)
    }

    /// The scene's own camera at `width` × `height`.
    pub fn camera(&self, width: u32, height: u32) -> Result<Camera> {
        let mut scene = self.scene.clone();
        scene.camera.width = width;
        scene.camera.height = height;
        scene::camera_of(&scene, &self.atlas)
    }
}

/// What one prepared frame costs on the CPU and draws.
#[derive(Clone, Copy, Debug, Default)]
pub struct FrameInfo {
    /// The CPU stage, or the baselines' block selection, µs.
    pub cpu_us: f64,
    /// The warped mode's CPU stage by part (zero for the other modes).
    pub stage: StageTimes,
    /// Triangles the last recorded frame drew.
    pub triangles: u64,
}

/// A terrain a host draws with its own device.
pub struct Terrain {
    ctx: GpuContext,
    targets: Targets,
    scene: Scene,
    renderer: Renderer,
    output: OutputPass,
    /// The output pass's reading of the renderer's frame, made with the renderer.
    output_group: wgpu::BindGroup,
    /// What the output pass and read-backs allocate (the renderer counts its own).
    _ledger: Ledger,
    /// Whether a frame was recorded since the renderer was built.
    recorded: bool,
    /// The image size the output pass's bind group reads the renderer's frame at.
    size: (u32, u32),
}

impl Terrain {
    /// A terrain on the host's `device` and `queue`, drawing into targets of `targets`' formats.
    pub fn new(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        targets: Targets,
        description: Description,
    ) -> Result<Terrain> {
        let Description {
            scene,
            atlas,
            mode,
            view,
        } = description;
        let ctx = GpuContext::from_device(device, queue, &needs(&scene, mode, &atlas))?;
        let ledger = Ledger::default();
        let alloc = Alloc {
            device: &ctx.device,
            ledger: &ledger,
            shared: &ctx.shared,
        };
        let renderer = build(&ctx, &scene, atlas, mode, view)?;
        let output = OutputPass::new(&alloc, targets, renderer.shader_key)?;
        let output_group = renderer.bind_output(&output)?;
        Ok(Terrain {
            size: (scene.camera.width, scene.camera.height),
            ctx,
            targets,
            scene,
            renderer,
            output,
            output_group,
            _ledger: ledger,
            recorded: false,
        })
    }

    /// Whether the terrain is drawn yet. Natively always; in a browser GeoMipMap and brute
    /// force read their baked grid back before their first frame, which a page cannot wait
    /// for, so until the read-back arrives (a few of the page's tasks) frames show the sky
    /// alone: a page keeps drawing its last terrain until the new one is ready.
    pub fn ready(&mut self) -> Result<bool> {
        self.renderer.ready()
    }

    /// The formats and samples this terrain draws into.
    pub fn targets(&self) -> Targets {
        self.targets
    }

    /// The CPU's part of a frame of `camera`: the level of detail, the uniforms. A camera of
    /// another size than the last makes the frame's targets again, nothing else.
    pub fn prepare(&mut self, camera: &Camera) -> Result<FrameInfo> {
        let triangles = self.renderer.host_triangles();
        let cpu = self.renderer.host_prepare(camera, self.recorded)?;
        self.fit(camera)?;
        self.output.prepare(&self.ctx.queue, camera);
        Ok(FrameInfo {
            cpu_us: cpu.us,
            stage: cpu.stage,
            triangles,
        })
    }

    /// As [`Terrain::prepare`], but `camera` is drawn with the level of detail of the last frame
    /// (the warped mode's CPU stage, GeoMipMap's selection, clipmaps' rings kept): the mesh seen
    /// from elsewhere. No CPU stage runs.
    pub fn prepare_held(&mut self, camera: &Camera) -> Result<FrameInfo> {
        let triangles = self.renderer.host_triangles();
        let held = self.renderer.host_prepare_held(camera, self.recorded)?;
        self.fit(camera)?;
        self.output.prepare(&self.ctx.queue, &held);
        Ok(FrameInfo {
            triangles,
            ..FrameInfo::default()
        })
    }

    /// Binds the output pass to the renderer's frame again where `camera`'s image is of
    /// another size than the last (the renderer has made its targets for it).
    fn fit(&mut self, camera: &Camera) -> Result<()> {
        let size = (camera.width, camera.height);
        if size != self.size {
            self.output_group = self.renderer.bind_output(&self.output)?;
            self.size = size;
        }
        Ok(())
    }

    /// Records the prepared frame into `encoder`, writing it into `colour` and `depth` (views of
    /// textures of this terrain's [`Targets`], the size of the prepared camera's image; another
    /// size or sample count is an [`Error::Target`](crate::Error::Target)). Each pixel is
    /// depth-tested `GreaterEqual` against what the host drew before, so host geometry nearer
    /// than the terrain stays.
    pub fn record(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        colour: &wgpu::TextureView,
        depth: &wgpu::TextureView,
    ) -> Result<()> {
        self.check("colour", colour)?;
        self.check("depth", depth)?;
        self.renderer.host_record(encoder)?;
        self.output
            .record(encoder, &self.output_group, colour, depth);
        self.recorded = true;
        Ok(())
    }

    /// An error where `view` is not of the prepared frame's size or the targets' sample count.
    fn check(&self, name: &'static str, view: &wgpu::TextureView) -> Result<()> {
        let texture = view.texture();
        let got = (texture.width(), texture.height(), texture.sample_count());
        let expected = (self.size.0, self.size.1, self.targets.samples);
        if got == expected {
            return Ok(());
        }
        let say = |(w, h, n): (u32, u32, u32)| {
            format!("{w}×{h}, {n} sample{}", if n == 1 { "" } else { "s" })
        };
        Err(crate::Error::Target {
            view: name,
            expected: say(expected),
            got: say(got),
        })
    }

    /// The point the frame's positions are relative to, world metres: host geometry is drawn
    /// at its world position less this.
    pub fn frame_origin(camera: &Camera) -> DVec3 {
        crate::gpu::uniforms::frame_origin(camera).extend(0.0)
    }

    /// The view-projection the terrain is drawn with, relative to [`Terrain::frame_origin`]:
    /// right-handed, reversed-Z, infinite far plane.
    pub fn view_proj(camera: &Camera) -> Mat4 {
        let origin = crate::gpu::uniforms::frame_origin(camera);
        crate::gpu::uniforms::view_proj(camera, origin).as_mat4()
    }

    /// The ground this terrain draws, with its own sketch and detail (as resolved for its
    /// mode): heights, normals and ray casts as the reference draws them, for standing things
    /// on the ground and for picking.
    pub fn ground(&self) -> Ground<'_> {
        Ground::new(&self.scene, self.renderer.atlas(), &self.renderer.detail)
    }

    /// The world point a host read at `pixel` of the depth view this terrain drew into:
    /// [`Camera::unproject`] at the pixel's centre (`pixel + ½`). `None` where the depth is 0
    /// (sky). Host geometry drawn there is picked alike.
    pub fn pick(camera: &Camera, pixel: UVec2, depth: f32) -> Option<DVec3> {
        camera.unproject(pixel.as_dvec2() + 0.5, depth as f64)
    }

    /// Draws `camera`'s frame into textures of its own and reads the colour back: rows top
    /// first, in the colour target's format (four bytes a pixel, single-sampled targets). The
    /// commands' snapshots are made the same way.
    pub fn render_to_image(&mut self, camera: &Camera) -> Result<Vec<u8>> {
        let alloc = Alloc {
            device: &self.ctx.device,
            ledger: &self._ledger,
            shared: &self.ctx.shared,
        };
        let snapshot = Snapshot::new(&alloc, self.targets, camera.width, camera.height)?;
        self.prepare(camera)?;
        let mut encoder = self.ctx.device.create_command_encoder(&Default::default());
        self.renderer.host_record(&mut encoder)?;
        self.recorded = true;
        snapshot.record(&mut encoder, &self.output, &self.output_group)?;
        self.ctx.queue.submit([encoder.finish()]);
        snapshot.read(&self.ctx)
    }
}

/// The renderer of `scene` in `mode` and `view` over `atlas` on `ctx`, keeping each frame for
/// the output pass.
fn build(
    ctx: &GpuContext,
    scene: &Scene,
    atlas: Atlas,
    mode: Mode,
    view: View,
) -> Result<Renderer> {
    Renderer::with_context(ctx.clone(), scene, atlas, mode, view)
}
