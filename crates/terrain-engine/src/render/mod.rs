//! The one renderer: a device, the frame's uniform block, the sketch's atlas on the GPU, the
//! pass timer and the read-back, driving any level-of-detail scheme ([`crate::lod`]) for one
//! scene; pipelines and buffers are built once and reused across frames and cameras.
//!
//! A frame: the scheme prepares on the CPU for the camera; the renderer fills the uniform block
//! (its shared part, then the scheme's), the scheme records its named passes, the output pass
//! writes the frame into a snapshot's textures (`gpu::snapshot`, as into a host's targets), and
//! the renderer submits, reads the image back, times it (timestamp queries keyed by pass name
//! where the adapter has them, wall time around submit always) and reads what each pass asked of
//! the GPU (`gpu::counters`, where the adapter counts it). A camera of another image size makes
//! the size-dependent targets again, nothing else.

mod build;

use crate::camera::Camera;
use crate::detail::Detail;
use crate::error::Result;
use crate::gpu::alloc::{Alloc, Buffer, Ledger};
use crate::gpu::context::{GpuContext, Needs};
use crate::gpu::counters::{Counters, FrameCounters, Probe};
use crate::gpu::frame_io::{
    FrameStats, PassTimes, Timer, uniform_buffer, upload_atlas, upload_drape, upload_ramp,
};
use crate::gpu::output::{OutputPass, Targets};
use crate::gpu::snapshot::Snapshot;
use crate::gpu::stream::{AtlasBinding, Stream};
use crate::gpu::sun_map::SunMap;
use crate::gpu::uniforms::{FrameInputs, FrameUniforms, View};
use crate::gpu::work::{Tally, Work};
use crate::lod::{CpuTimes, Lod, Shared};
use crate::scene;
use crate::scene::{Mode, Scene};
use crate::sketch::Atlas;
use crate::sketch::tiles::cache::StreamStats;
use crate::stage::StageTimes;
use web_time::Instant;

/// One rendered frame: RGBA8 sRGB pixels, rows top first.
pub struct Frame {
    /// The pixels, 4 bytes each (RGBA8, sRGB), `width` × `height`, rows top first.
    pub rgba: Vec<u8>,
    /// Image width, pixels (the camera's).
    pub width: u32,
    /// Image height, pixels (the camera's).
    pub height: u32,
    /// The warped mode's CPU stage; zero for the other modes.
    pub cpu: StageTimes,
    /// CPU time per frame: the CPU stage, or the baselines' block selection (µs).
    pub cpu_us: f64,
    /// The GPU's side: its time (by pass, where the adapter times passes) and the triangles drawn.
    pub gpu: FrameStats,
    /// Blocks drawn (GeoMipMap and brute force).
    pub blocks: Option<usize>,
    /// A streamed sketch: what the tile cache did for this frame.
    pub stream: Option<StreamStats>,
    /// The tile cache's own CPU time in the frame: placing tiles, writing pages and the page
    /// table, reading the marks back (µs; 0 for a sketch held whole).
    pub stream_us: f64,
    /// What each pass asked of the GPU (`gpu::counters`), where the device counts it: by pass
    /// name, in the order the passes ran.
    pub counters: Option<FrameCounters>,
    /// What the shading evaluated, summed over its pixels, in a renderer made to count it
    /// ([`Renderer::counting_work`]).
    pub work: Option<Work>,
}

/// What a command's snapshots are written with: the output pass, its reading of the scheme's
/// frame at the renderer's size, and the textures of the last snapshot's size.
struct Snapshots {
    pass: OutputPass,
    group: wgpu::BindGroup,
    textures: Snapshot,
}

impl Frame {
    /// Every pass's fragment shader invocations per pixel of `px` (the pixels showing ground,
    /// [`covered_px`]), where the device counts them.
    pub fn fragments_per_px(&self, px: u64) -> Option<f64> {
        let counters = self.counters.as_ref()?;
        let fragments: u64 = counters.iter().map(|(_, c)| c.fragment_invocations).sum();
        Some(fragments as f64 / px.max(1) as f64)
    }
}

/// A frame submitted and not yet read back ([`Renderer::render_each`]).
struct Submitted {
    size: (u32, u32),
    cpu: CpuTimes,
    ran: &'static [&'static str],
    start: Instant,
    /// The tile cache's CPU time so far.
    stream_us: f64,
    triangles: u64,
    blocks: Option<usize>,
}

/// The sketch on the GPU: the whole pyramid, or a tile pyramid through the tile cache.
enum SketchGpu {
    Whole(std::sync::Arc<Buffer>),
    Streamed(Box<Stream>),
}

/// Draws a scene's frames on a device of its own and reads each back: the snapshot path of
/// `render`, `batch` and `compare` (a host drawing into its own targets uses [`crate::Terrain`]).
///
/// ```no_run
/// use std::path::Path;
/// use terrain_engine::{Renderer, Scene, View, scene};
///
/// let scene = Scene::load(Path::new("sketches/jacksboro.toml"))?;
/// let mut renderer = Renderer::new(&scene, scene.render.mode, View::Shaded)?;
/// let camera = scene::camera_of(&scene, renderer.atlas())?;
/// let frame = renderer.render(&camera)?;
/// assert_eq!(frame.rgba.len(), (frame.width * frame.height * 4) as usize);
/// println!("{} triangles, {:.1} ms on the GPU", frame.gpu.triangles, frame.gpu.gpu_ms);
/// # Ok::<(), terrain_engine::Error>(())
/// ```
pub struct Renderer {
    /// The device it draws on, opened for this renderer (or shared, see `with_context`).
    pub ctx: GpuContext,
    /// The sketch, as read on the CPU.
    pub atlas: Atlas,
    /// The procedural detail, resolved for the scene and mode.
    pub detail: Detail,
    /// The sun and the air, from `[light]` ([`Renderer::relight`] changes it).
    pub light: crate::light::Light,
    /// `sketch.outside`, resolved.
    pub outside: crate::scene::Outside,
    /// The level-of-detail scheme it draws with.
    pub mode: Mode,
    /// Samples per pixel the picture was drawn with (`render.msaa` where the adapter allows).
    pub samples: u32,
    /// The ground was shaded deferred (`render.deferred` where the frame and adapter allow).
    pub deferred: bool,
    /// The shader variant of the scheme's passes, and of the output pass for a host.
    pub(crate) shader_key: crate::gpu::shaders::Key,
    view: View,
    frame: Buffer,
    sketch: SketchGpu,
    timer: Option<Timer>,
    /// The passes' pipeline statistics, where the device counts them.
    counters: Option<Counters>,
    /// The counting variant's tallies, in a renderer made to count them.
    work: Option<Tally>,
    /// The sketch's sun visibility map, where the scheme samples it.
    sun_map: Option<SunMap>,
    /// The colour ramp's stops, where the ground is drawn with one (bound by the passes).
    _ramp: Option<Buffer>,
    /// The user's imagery on the sketch's grid, where the ground is drawn with it.
    _drape: Option<Buffer>,
    lod: Box<dyn Lod>,
    /// What snapshots are written with, made at the first (a host's frames need none).
    snapshots: Option<Snapshots>,
    ledger: Ledger,
    /// The image size the scheme's targets are made for: a camera of another size remakes them
    /// alone ([`Lod::resize`]).
    size: (u32, u32),
}

/// The targets of a command's snapshot: what `terrain render` writes.
const SNAPSHOT: Targets = Targets {
    colour: wgpu::TextureFormat::Rgba8UnormSrgb,
    depth: wgpu::TextureFormat::Depth32Float,
    samples: 1,
};

/// The output pass's bind group over the frame `lod` leaves.
fn bind_output(ctx: &GpuContext, output: &OutputPass, lod: &dyn Lod) -> Result<wgpu::BindGroup> {
    output.bind(&ctx.device, lod.output())
}

/// What a scene in `mode` needs of the adapter: the atlas, and the mode's own largest binding
/// (the scheme's `Lod::needs`).
pub fn needs(scene: &Scene, mode: Mode, atlas: &Atlas) -> Needs {
    let largest = (crate::lod::of(mode).needs)(scene);
    // A streamed pyramid's pool fits itself to the adapter's binding limit.
    let sketch = if atlas.pyramid.is_some() {
        0
    } else {
        atlas.bytes()
    };
    Needs {
        storage_bytes: sketch.max(largest),
    }
}

impl Renderer {
    /// A renderer of `scene` in `mode` drawing `view`, on a device of its own: reads the sketch,
    /// opens a device that meets [`needs`], builds the pipelines and buffers once.
    pub fn new(scene: &Scene, mode: Mode, view: View) -> Result<Renderer> {
        let atlas = scene::load_atlas(scene)?;
        let ctx = GpuContext::new(&needs(scene, mode, &atlas))?;
        Renderer::with_context(ctx, scene, atlas, mode, view)
    }

    /// On a device shared with other renderers.
    pub fn with_context(
        ctx: GpuContext,
        scene: &Scene,
        atlas: Atlas,
        mode: Mode,
        view: View,
    ) -> Result<Renderer> {
        build::renderer(ctx, scene, atlas, mode, view, false)
    }

    /// A renderer in the counting variant (`gpu::work`): its passes tally what they evaluate
    /// per pixel, and each frame carries the sums ([`Frame::work`]). The pictures are those of
    /// [`Renderer::with_context`]; the times are not, for the tallies' atomics slow the shading.
    pub fn counting_work(
        ctx: GpuContext,
        scene: &Scene,
        atlas: Atlas,
        mode: Mode,
        view: View,
    ) -> Result<Renderer> {
        build::renderer(ctx, scene, atlas, mode, view, true)
    }

    /// Fits the scheme's targets to `camera`'s image: nothing happens at the same size, and at
    /// another only what depends on it is made again (targets, per-pixel buffers, read-back).
    fn fit(&mut self, camera: &Camera) -> Result<()> {
        // A scheme still waiting for its read-back draws the sky; one that failed is the error.
        self.lod.ready()?;
        let size = (camera.width, camera.height);
        if size != self.size {
            let alloc = Alloc {
                device: &self.ctx.device,
                ledger: &self.ledger,
                shared: &self.ctx.shared,
            };
            self.lod.resize(&alloc, size.0, size.1)?;
            if let Some(s) = &mut self.snapshots {
                s.group = bind_output(&self.ctx, &s.pass, self.lod.as_ref())?;
            }
            self.size = size;
        }
        Ok(())
    }

    /// Whether the terrain is drawn: false only in a browser while the baselines' baked grid is
    /// read back (a page cannot wait for its GPU), when frames show the sky alone. An error is
    /// the read-back's failure.
    pub fn ready(&mut self) -> Result<bool> {
        self.lod.ready()
    }

    /// The next frame's level of detail is chosen as by a fresh renderer, whatever frames came
    /// before (see `Lod::forget`). A streamed sketch keeps its tiles: those of the frames
    /// before stay in the pool.
    pub fn forget(&mut self) {
        self.lod.forget();
    }

    /// The sketch, as read on the CPU.
    pub fn atlas(&self) -> &Atlas {
        &self.atlas
    }

    /// The device it draws on.
    pub fn ctx(&self) -> &GpuContext {
        &self.ctx
    }

    /// The scheme, as its own type (tests look inside: the warped mode's stage, GeoMipMap's
    /// selection).
    pub fn lod<T: Lod>(&self) -> Option<&T> {
        self.lod.as_any().downcast_ref()
    }

    /// The scheme, as its own type, to change (a test's or a tool's setting between frames).
    pub fn lod_mut<T: Lod>(&mut self) -> Option<&mut T> {
        self.lod.as_any_mut().downcast_mut()
    }

    /// Sets the swept keys its mode's scheme takes without being built again (the row's
    /// [`retuned`](crate::scene::ModeRow::retuned) keys, GeoMipMap's τ) from `values`, the
    /// values of the row's [`sweep`](crate::scene::ModeRow::sweep) keys in order: `compare`'s
    /// settings of one renderer. The other keys are left as the renderer was built.
    pub fn retune(&mut self, values: &[f64]) {
        let row = self.mode.row();
        for (&(key, _), &value) in row.sweep.iter().zip(values) {
            if row.retuned.contains(&key) {
                self.lod.retune(key, value);
            }
        }
    }

    /// The CPU work, then the GPU passes, for `camera`.
    /// An error after the device was lost is the loss.
    pub fn render(&mut self, camera: &Camera) -> Result<Frame> {
        self.fit(camera)?;
        let cpu = self.lod.prepare(&self.atlas, camera);
        let frame = self.draw(camera, cpu);
        frame.map_err(|e| self.ctx.raised().err().unwrap_or(e))
    }

    /// A snapshot of `camera`: as [`Renderer::render`], then for a streamed sketch again, each
    /// frame waiting for the tiles the last one missed, until no sample reads a stand-in level.
    /// The image is then the one the sketch held whole gives. Where the view needs more tiles
    /// than the pool holds (or the loader stops delivering), the first frame that placed none is
    /// returned, its stand-ins counted in [`Frame::stream`], and a note through `log` says so
    /// (every snapshot command: `render`, `batch`, `compare`).
    pub fn render_settled(&mut self, camera: &Camera) -> Result<Frame> {
        let SketchGpu::Streamed(s) = &mut self.sketch else {
            return self.render(camera);
        };
        s.settle(true);
        let frame = self.settle_frames(camera);
        if let SketchGpu::Streamed(s) = &mut self.sketch {
            s.settle(false);
        }
        frame
    }

    fn settle_frames(&mut self, camera: &Camera) -> Result<Frame> {
        // Each frame places at least one tile of a finite pyramid for a still camera; the bound
        // only guards against a pool that trades the same tiles back and forth.
        const MOST_FRAMES: usize = 1000;
        let mut frame = self.render(camera)?;
        for _ in 0..MOST_FRAMES {
            if !frame.stream.is_some_and(|s| s.stand_in) {
                break;
            }
            frame = self.render(camera)?;
            if frame.stream.is_some_and(|s| s.loaded == 0) {
                break;
            }
        }
        if let Some(st) = frame.stream.filter(|s| s.stand_in) {
            log::info!(
                "{} tiles this view needs do not fit the {} pages of stream.gpu_mb: \
                 coarser levels stand in for them",
                st.missing,
                self.stream_pages().unwrap_or(0)
            );
        }
        Ok(frame)
    }

    /// `camera` drawn with the level of detail of the last frame (the warped mode's CPU stage
    /// frozen, GeoMipMap's selection kept, clipmaps' rings left around the last nadir): what a
    /// frame would show without the LOD update.
    pub fn render_held(&mut self, camera: &Camera) -> Result<Frame> {
        self.fit(camera)?;
        let camera = self.lod.held_camera(camera);
        self.draw(&camera, CpuTimes::default())
    }

    /// The light of `scene`, which differs from the renderer's own only in the camera (a batch
    /// reusing one renderer): on a planet the sun stands where that camera sees it.
    pub fn relight(&mut self, scene: &Scene) {
        self.light = scene::light_of(scene);
        self.lod.relight(scene);
    }

    /// The uniform block of a frame of `camera`: the shared part, then the scheme's.
    pub fn uniforms(&self, camera: &Camera) -> FrameUniforms {
        let mut inputs = FrameInputs {
            camera,
            map: None,
            mesh_origin: None,
            atlas: &self.atlas,
            detail: &self.detail,
            light: &self.light,
            outside: self.outside,
            mesh: 0,
            view: self.view,
            importance_max: 0.0,
            block: Default::default(),
            step_factor: 0.0,
        };
        self.lod.frame_inputs(&mut inputs);
        let mut u = FrameUniforms::new(&inputs);
        if let SketchGpu::Streamed(s) = &self.sketch {
            s.uniforms(&mut u.atlas);
        }
        u
    }

    fn draw(&mut self, camera: &Camera, cpu: CpuTimes) -> Result<Frame> {
        let submitted = self.submit(camera, cpu)?;
        self.finish(submitted)
    }

    /// Records and submits the frame of `camera`, whose CPU work `cpu` took, without waiting
    /// for it.
    fn submit(&mut self, camera: &Camera, cpu: CpuTimes) -> Result<Submitted> {
        let uniforms = self.uniforms(camera);
        let ctx = &self.ctx;
        ctx.queue
            .write_buffer(&self.frame, 0, bytemuck::bytes_of(&uniforms));
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        let stream_start = Instant::now();
        if let SketchGpu::Streamed(s) = &mut self.sketch {
            s.begin_frame(ctx, &mut encoder)?;
        }
        let stream_us = stream_start.elapsed().as_secs_f64() * 1e6;
        let timer = self.timer.as_ref();
        let probe = Probe {
            timer,
            counters: self.counters.as_ref(),
        };
        if let Some(w) = &self.work {
            w.clear(&mut encoder);
        }
        self.record_sun_map(&mut encoder);
        let ran = self.lod.record(ctx, &mut encoder, probe);
        if let Some(w) = &self.work {
            w.copy(&mut encoder);
        }
        let alloc = Alloc {
            device: &ctx.device,
            ledger: &self.ledger,
            shared: &ctx.shared,
        };
        let (w, h) = self.size;
        let s = match self.snapshots.take() {
            Some(mut s) => {
                if s.textures.size() != self.size {
                    s.textures = Snapshot::new(&alloc, SNAPSHOT, w, h)?;
                }
                s
            }
            None => {
                let pass = OutputPass::new(&alloc, SNAPSHOT, self.shader_key)?;
                Snapshots {
                    group: bind_output(ctx, &pass, self.lod.as_ref())?,
                    pass,
                    textures: Snapshot::new(&alloc, SNAPSHOT, w, h)?,
                }
            }
        };
        s.pass.prepare(&ctx.queue, camera);
        s.textures.record(&mut encoder, &s.pass, &s.group)?;
        self.snapshots = Some(s);
        if let Some(t) = timer {
            t.resolve(&mut encoder, ran);
        }
        if let Some(c) = &self.counters {
            c.resolve(&mut encoder);
        }
        if let SketchGpu::Streamed(s) = &self.sketch {
            s.record_marks(&mut encoder);
        }
        let start = Instant::now();
        ctx.queue.submit([encoder.finish()]);
        Ok(Submitted {
            size: (camera.width, camera.height),
            cpu,
            ran,
            start,
            stream_us,
            triangles: self.lod.triangles(),
            blocks: self.lod.blocks(),
        })
    }

    /// Waits for the submitted frame and reads it back: its image, times and counts.
    fn finish(&mut self, f: Submitted) -> Result<Frame> {
        let ctx = &self.ctx;
        let snapshot = self.snapshots.as_ref().ok_or(crate::Error::Internal(
            "a frame finished that was never submitted",
        ))?;
        let rgba = snapshot.textures.read(ctx)?;
        let wall_ms = f.start.elapsed().as_secs_f64() * 1e3;
        let stream_start = Instant::now();
        let stream = match &mut self.sketch {
            SketchGpu::Streamed(s) => Some(s.end_frame(ctx)?),
            SketchGpu::Whole(_) => None,
        };
        let stream_us = match stream {
            Some(_) => f.stream_us + stream_start.elapsed().as_secs_f64() * 1e6,
            None => 0.0,
        };
        let timer = self.timer.as_ref();
        let passes = match timer {
            Some(t) => t.read(ctx, f.ran)?,
            None => PassTimes::default(),
        };
        let counters = match &self.counters {
            Some(c) => Some(c.read(ctx)?),
            None => None,
        };
        let work = match &self.work {
            Some(w) => Some(w.read(ctx)?),
            None => None,
        };
        Ok(Frame {
            rgba,
            width: f.size.0,
            height: f.size.1,
            cpu: f.cpu.stage,
            cpu_us: f.cpu.us,
            gpu: FrameStats::new(passes, timer.is_some(), wall_ms, f.triangles),
            blocks: f.blocks,
            stream,
            stream_us,
            counters,
            work,
        })
    }

    /// The frames of `cameras` in turn, each handed to `each` as it is read back; each frame's
    /// CPU work (the warped mode's stage, GeoMipMap's selection) runs while the GPU draws the
    /// frame before, so a frame costs the larger of the two, not their sum. `each` returns
    /// whether to go on.
    pub fn render_each(
        &mut self,
        cameras: &[Camera],
        mut each: impl FnMut(usize, Frame) -> Result<bool>,
    ) -> Result<()> {
        let Some(first) = cameras.first() else {
            return Ok(());
        };
        let mut cpu = self.lod.prepare(&self.atlas, first);
        for (k, camera) in cameras.iter().enumerate() {
            self.fit(camera)?;
            let submitted = self.submit(camera, cpu)?;
            // The next frame's CPU work, while the GPU draws this one.
            if let Some(next) = cameras.get(k + 1) {
                cpu = self.lod.prepare(&self.atlas, next);
            }
            let frame = self.finish(submitted)?;
            if !each(k, frame)? {
                break;
            }
        }
        Ok(())
    }

    /// A host's frame, first half: the CPU work for `camera` and the frame's uniforms. Over a
    /// streamed sketch, `after_frame` says a frame was recorded before, whose tile marks are now
    /// read (its encoder must have been submitted) and whose missing tiles are queued.
    pub(crate) fn host_prepare(&mut self, camera: &Camera, after_frame: bool) -> Result<CpuTimes> {
        self.host_end_frame(after_frame)?;
        self.fit(camera)?;
        let cpu = self.lod.prepare(&self.atlas, camera);
        self.host_uniforms(camera);
        Ok(cpu)
    }

    /// As [`Renderer::host_prepare`] with the level of detail of the last frame kept, as
    /// [`Renderer::render_held`] draws: no CPU work. Returns the camera the frame is drawn with.
    pub(crate) fn host_prepare_held(
        &mut self,
        camera: &Camera,
        after_frame: bool,
    ) -> Result<Camera> {
        self.host_end_frame(after_frame)?;
        self.fit(camera)?;
        let camera = self.lod.held_camera(camera);
        self.host_uniforms(&camera);
        Ok(camera)
    }

    /// Over a streamed sketch, reads the marks of the frame recorded before (if any).
    fn host_end_frame(&mut self, after_frame: bool) -> Result<()> {
        if let SketchGpu::Streamed(s) = &mut self.sketch
            && after_frame
        {
            s.end_frame(&self.ctx)?;
        }
        Ok(())
    }

    fn host_uniforms(&self, camera: &Camera) {
        let uniforms = self.uniforms(camera);
        self.ctx
            .queue
            .write_buffer(&self.frame, 0, bytemuck::bytes_of(&uniforms));
    }

    /// Triangles the last recorded frame drew.
    pub(crate) fn host_triangles(&self) -> u64 {
        self.lod.triangles()
    }

    /// A host's frame, second half: the passes, recorded into the host's `encoder`, leaving the
    /// frame in the renderer's own targets ([`Lod::output`]).
    pub(crate) fn host_record(&mut self, encoder: &mut wgpu::CommandEncoder) -> Result<()> {
        if let SketchGpu::Streamed(s) = &mut self.sketch {
            s.begin_frame(&self.ctx, encoder)?;
        }
        self.record_sun_map(encoder);
        self.lod.record(&self.ctx, encoder, Probe::default());
        if let SketchGpu::Streamed(s) = &self.sketch {
            s.record_marks(encoder);
        }
        Ok(())
    }

    /// The sun visibility map made again where the sun moved since it was made (after the
    /// frame's uniforms are written, before the passes that sample it).
    fn record_sun_map(&self, encoder: &mut wgpu::CommandEncoder) {
        if let Some(m) = &self.sun_map {
            m.record(encoder, self.light.sun.as_vec3().to_array());
        }
    }

    /// `output`'s bind group over the frame the scheme leaves (a host's output pass).
    pub(crate) fn bind_output(&self, output: &OutputPass) -> Result<wgpu::BindGroup> {
        bind_output(&self.ctx, output, self.lod.as_ref())
    }

    /// Bytes of GPU memory the renderer holds now: its uniforms, the atlas, the timer's
    /// queries and whatever the scheme allocated, as counted at allocation (see [`crate::gpu::alloc`]).
    pub fn gpu_bytes(&self) -> u64 {
        self.ledger.bytes()
    }

    /// A streamed sketch: the pages its tile pool holds.
    pub fn stream_pages(&self) -> Option<usize> {
        match &self.sketch {
            SketchGpu::Streamed(s) => Some(s.budget().pages),
            SketchGpu::Whole(_) => None,
        }
    }

    /// The baselines' precomputation: milliseconds and bytes of the baked grid.
    pub fn precompute(&self) -> Option<(f64, u64)> {
        self.lod.precompute()
    }

    /// Ground positions of the last frame's pixels, relative to `camera`'s ground point (w = 1
    /// on ground, 0 on sky), from the view distances every frame keeps for the output pass.
    pub fn read_positions(&self, camera: &Camera) -> Result<Vec<[f32; 4]>> {
        self.lod.read_positions(&self.ctx, camera)
    }

    /// Whether any terrain was in view in the last frame.
    pub fn visible(&self) -> bool {
        self.lod.visible()
    }
}

/// Pixels showing ground among `relative` ([`Renderer::read_positions`]: w = 1 on ground).
pub fn covered_px(relative: &[[f32; 4]]) -> u64 {
    relative.iter().filter(|p| p[3] > 0.5).count() as u64
}

/// Positions as the passes write them (f32, relative to `camera`'s ground point, w = 1 on ground)
/// to world metres in f64, four values a pixel: x, y, z (0 on sky), then 1 on ground and 0 on sky.
pub fn world_positions(relative: &[[f32; 4]], camera: &Camera) -> Vec<f64> {
    let origin = camera.eye.truncate();
    relative
        .iter()
        .flat_map(|q| {
            let ground = q[3] > 0.5;
            let at = |v: f32, o: f64| if ground { v as f64 + o } else { 0.0 };
            [
                at(q[0], origin.x),
                at(q[1], origin.y),
                at(q[2], 0.0),
                q[3] as f64,
            ]
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An adaptive triangulation binds the quad indices as storage, 24 bytes a cell: from a
    /// mesh of 6 on they outgrow the detailed geometry image's 16 bytes a vertex, and the
    /// adapter is asked for them.
    #[test]
    fn the_warped_mode_needs_room_for_its_largest_binding() {
        let scene = |triangulation: &str| {
            let text = format!(
                "[sketch]\nsynthetic = \"gaussian\"\n[camera]\nposition = [0.0, 0.0, 900.0]\n\
                 look_at = [100.0, 100.0, 0.0]\n[warp]\nmesh = 2600\ntriangulation = \"{triangulation}\"\n"
            );
            Scene::parse(&text, std::path::PathBuf::from(".")).unwrap()
        };
        let atlas = Atlas::synthetic("gaussian", 64, &Default::default()).unwrap();
        let needs = |s: &Scene| needs(s, Mode::Warped, &atlas).storage_bytes;
        assert_eq!(needs(&scene("fixed")), 2600 * 2600 * 16);
        assert_eq!(needs(&scene("adaptive")), 2599 * 2599 * 24);
    }
}
