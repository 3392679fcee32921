//! Building a renderer: the sketch on the GPU (whole, or through the tile cache), the scheme of
//! its mode and the timer and counters of its passes.

use super::*;

/// The renderer of `scene` in `mode` drawing `view` over `atlas`, on `ctx`; where `count_work`,
/// in the counting variant (`gpu::work`).
pub(super) fn renderer(
    ctx: GpuContext,
    scene: &Scene,
    atlas: Atlas,
    mode: Mode,
    view: View,
    count_work: bool,
) -> Result<Renderer> {
    ctx.check(&needs(scene, mode, &atlas))?;
    let detail = scene::detail_for(scene, &atlas, mode);
    let ledger = Ledger::default();
    let alloc = Alloc {
        device: &ctx.device,
        ledger: &ledger,
        shared: &ctx.shared,
    };
    let planet = scene.planet().is_some();
    let frame = uniform_buffer(&alloc);
    let sketch = match &atlas.pyramid {
        Some(pyramid) => {
            if mode.bakes_whole_sketch() {
                return Err(crate::Error::value(
                    "render.mode",
                    format!(
                        "{mode} bakes the whole sketch, and {} is a tile pyramid streamed \
                         in tiles: draw it in warped or reference mode",
                        pyramid.dir.display()
                    ),
                ));
            }
            let cfg = scene::stream_config(scene);
            SketchGpu::Streamed(Box::new(Stream::new(&ctx, &alloc, pyramid, cfg)?))
        }
        None => SketchGpu::Whole(upload_atlas(&alloc, &atlas)),
    };
    let work = count_work.then(|| Tally::new(&alloc));
    // The mesh modes sample the sketch's shadow from a map made once per sun direction.
    let sun_map = match &sketch {
        SketchGpu::Whole(b) if mode.is_mesh() && scene.render.shadows && scene.render.sun_map => {
            Some(SunMap::new(&alloc, &frame, &atlas, b)?)
        }
        _ => None,
    };
    let mut atlas_binding = match &sketch {
        SketchGpu::Whole(b) => AtlasBinding {
            atlas: wgpu::Buffer::clone(b),
            marks: None,
            work: None,
            sun_seen: sun_map.as_ref().map(|m| wgpu::Buffer::clone(&m.seen)),
            ramp: None,
            drape: None,
        },
        SketchGpu::Streamed(s) => s.binding(),
    };
    atlas_binding.work = work.as_ref().map(|w| wgpu::Buffer::clone(&w.buffer));
    let ramp = upload_ramp(&alloc, scene, &atlas)?;
    atlas_binding.ramp = ramp.as_ref().map(|b| wgpu::Buffer::clone(b));
    let drape = upload_drape(&alloc, scene, &atlas)?;
    atlas_binding.drape = drape.as_ref().map(|b| wgpu::Buffer::clone(b));
    // Planets are not multisampled (nor supersampled) yet.
    let samples = if planet {
        1
    } else {
        ctx.samples(scene.render.msaa)
    };
    let shared = Shared {
        ctx: &ctx,
        alloc,
        scene,
        atlas: &atlas,
        detail: &detail,
        frame: &frame,
        atlas_binding: &atlas_binding,
        view,
        samples,
        deferred: mode.is_mesh() && ctx.deferred(scene.render.deferred, samples),
    };
    if !mode.draws(planet) {
        return Err(crate::Error::value(
            "render.mode",
            if planet {
                format!("a planet scene draws with clipmaps, not {mode}")
            } else {
                format!(
                    "{mode} draws planet scenes (a [planet] section or sketch.synthetic = \"planet\")"
                )
            },
        ));
    }
    let lod = (crate::lod::of(mode).build)(&shared)?;
    let deferred = shared.deferred;
    let shader_key = crate::lod::shader_key(&shared, mode);
    let outside = scene.outside(&atlas);
    // An allocation the device refused (out of memory) is an error here, not a panic.
    ctx.raised()?;
    Ok(Renderer {
        snapshots: None,
        samples,
        deferred,
        shader_key,
        timer: Timer::new(&ctx, &alloc, lod.passes()),
        counters: Counters::new(&alloc, lod.passes()),
        work,
        sun_map,
        _ramp: ramp,
        _drape: drape,
        ctx,
        atlas,
        detail,
        light: scene::light_of(scene),
        outside,
        mode,
        view,
        frame,
        sketch,
        lod,
        ledger,
        size: (scene.camera.width, scene.camera.height),
    })
}
