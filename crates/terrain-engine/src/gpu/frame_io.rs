//! What every renderer does around its passes: the uniform buffer, the atlas upload, timing with
//! timestamp queries, and reading the image back.

use super::alloc::{Alloc, Buffer, Tracked};
use super::context::GpuContext;
use super::uniforms::FrameUniforms;
use crate::error::Result;
use crate::readback::Readback;
use crate::scene::Scene;
use crate::sketch::Atlas;
use serde::de::{Deserializer, MapAccess, Visitor};
use serde::{Deserialize, Serialize};
use std::borrow::Cow;

/// Milliseconds of each pass that ran, by the pass's name, in the order they ran; empty where
/// the adapter cannot time passes. JSON: an object `{ "warp_zoom": 1.2, … }`, read back in its
/// order (`compare --replot`). A name is the pass's own `NAME` when timed, owned when read back.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PassTimes(pub Vec<(Cow<'static, str>, f64)>);

impl PassTimes {
    /// The time of the pass called `name`, if it ran and was timed.
    pub fn get(&self, name: &str) -> Option<f64> {
        self.0.iter().find(|(n, _)| n == name).map(|&(_, ms)| ms)
    }

    /// The sum of the passes' times, milliseconds.
    pub fn total(&self) -> f64 {
        self.0.iter().map(|&(_, ms)| ms).sum()
    }

    /// Per pass (those of the last frame), the median over `frames`.
    pub fn median(frames: &[&PassTimes]) -> PassTimes {
        let Some(last) = frames.last() else {
            return PassTimes::default();
        };
        let median = |name: &str| {
            let mut v: Vec<f64> = frames.iter().filter_map(|p| p.get(name)).collect();
            v.sort_by(f64::total_cmp);
            v[v.len() / 2]
        };
        PassTimes(last.0.iter().map(|(n, _)| (n.clone(), median(n))).collect())
    }
}

impl Serialize for PassTimes {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let mut map = s.serialize_map(Some(self.0.len()))?;
        for (name, ms) in &self.0 {
            map.serialize_entry(name, ms)?;
        }
        map.end()
    }
}

impl<'de> Deserialize<'de> for PassTimes {
    fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<PassTimes, D::Error> {
        struct Passes;
        impl<'de> Visitor<'de> for Passes {
            type Value = PassTimes;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("an object of pass names and milliseconds")
            }
            fn visit_map<M: MapAccess<'de>>(
                self,
                mut m: M,
            ) -> std::result::Result<PassTimes, M::Error> {
                let mut passes = Vec::new();
                while let Some((name, ms)) = m.next_entry::<String, f64>()? {
                    passes.push((Cow::Owned(name), ms));
                }
                Ok(PassTimes(passes))
            }
        }
        d.deserialize_map(Passes)
    }
}

#[derive(Clone, Debug, Serialize)]
pub struct FrameStats {
    /// GPU time of the frame: the passes' sum with timestamps, else submit-to-idle wall time.
    pub gpu_ms: f64,
    /// Submit to readback done, always measured (it includes the readback copy and the wait).
    pub gpu_wall_ms: f64,
    pub passes: PassTimes,
    pub triangles: u64,
}

impl FrameStats {
    pub fn new(passes: PassTimes, timed: bool, wall_ms: f64, triangles: u64) -> FrameStats {
        FrameStats {
            gpu_ms: if timed { passes.total() } else { wall_ms },
            gpu_wall_ms: wall_ms,
            passes,
            triangles,
        }
    }
}

pub fn uniform_buffer(device: &Alloc) -> Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("frame"),
        size: std::mem::size_of::<FrameUniforms>() as u64,
        usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

/// The atlas pyramid in a read-only storage buffer (see `shaders/shared/atlas.wgsl` for why not
/// a texture).
pub fn upload_atlas(device: &Alloc, atlas: &Atlas) -> std::sync::Arc<Buffer> {
    use std::hash::{Hash, Hasher};
    let texels = super::uniforms::atlas_texels(atlas);
    let bytes: &[u8] = bytemuck::cast_slice(&texels);
    // Renderers of one sketch on one device share its upload (`gpu::shared`).
    let mut hasher = std::collections::hash_map::DefaultHasher::new();
    bytes.hash(&mut hasher);
    device.shared.sketch(hasher.finish(), || {
        device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("sketch atlas"),
            contents: bytes,
            usage: wgpu::BufferUsages::STORAGE,
        })
    })
}

/// The scene's colour ramp as the shading reads it (`ramp` in `shaders/shared/shading.wgsl`):
/// each stop's encoded colour (0–1) and its height in metres, percentages resolved against the
/// sketch's range; `None` for a scene drawn without one, or a planet (its own surface types).
pub fn upload_ramp(device: &Alloc, scene: &Scene, atlas: &Atlas) -> Result<Option<Buffer>> {
    if scene.planet().is_some() {
        return Ok(None);
    }
    let Some(ramp) = scene.color_ramp()? else {
        return Ok(None);
    };
    let stops: Vec<[f32; 4]> = ramp
        .stops(atlas.min_m as f64, atlas.max_m as f64)
        .iter()
        .map(|s| {
            let [r, g, b, _] = s.rgba.map(|c| c as f32 / 255.0);
            [r, g, b, s.height_m as f32]
        })
        .collect();
    Ok(Some(device.create_buffer_init(
        &wgpu::util::BufferInitDescriptor {
            label: Some("colour ramp"),
            contents: bytemuck::cast_slice(&stops),
            usage: wgpu::BufferUsages::STORAGE,
        },
    )))
}

/// The scene's imagery as the shading reads it (`drape` in `shaders/shared/shading.wgsl`): its
/// grid's width and height, its texel size in metres (f32 bits), then its RGBA8 texels; `None`
/// for a scene drawn without one, or a planet.
pub fn upload_drape(device: &Alloc, scene: &Scene, atlas: &Atlas) -> Result<Option<Buffer>> {
    if scene.planet().is_some() {
        return Ok(None);
    }
    let Some(d) = scene.drape(atlas)? else {
        return Ok(None);
    };
    let mut words = vec![
        d.width as u32,
        d.height as u32,
        (d.texel.x as f32).to_bits(),
        (d.texel.y as f32).to_bits(),
    ];
    words.extend(
        d.rgba
            .chunks_exact(4)
            .map(|p| u32::from_le_bytes([p[0], p[1], p[2], p[3]])),
    );
    Ok(Some(device.create_buffer_init(
        &wgpu::util::BufferInitDescriptor {
            label: Some("surface image"),
            contents: bytemuck::cast_slice(&words),
            usage: wgpu::BufferUsages::STORAGE,
        },
    )))
}

/// A mappable buffer for one read-back, dropped before the call that made it returns; the only
/// allocation outside the ledger, which counts what a renderer keeps.
#[allow(clippy::disallowed_methods)]
fn staging(ctx: &GpuContext, label: &str, size: u64) -> wgpu::Buffer {
    ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

/// Timestamp queries for a renderer's passes, a pair each, keyed by the pass's name: the passes
/// a frame may record, in the order it records them (a frame may skip leading ones, as a sky-only
/// frame skips the warped mode's compute passes).
pub struct Timer {
    names: &'static [&'static str],
    queries: Tracked<wgpu::QuerySet>,
    resolve: Buffer,
    read: Buffer,
    period_ns: f64,
}

impl Timer {
    /// `None` where the adapter has no timestamp queries.
    pub fn new(ctx: &GpuContext, device: &Alloc, names: &'static [&'static str]) -> Option<Timer> {
        let passes = names.len() as u64;
        let buffer = |label, usage| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: 16 * passes,
                usage,
                mapped_at_creation: false,
            })
        };
        ctx.timestamps.then(|| Timer {
            names,
            queries: device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("pass times"),
                ty: wgpu::QueryType::Timestamp,
                count: 2 * passes as u32,
            }),
            resolve: buffer(
                "timestamps",
                wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
            ),
            read: buffer(
                "timestamps read",
                wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            ),
            period_ns: ctx.queue.get_timestamp_period() as f64,
        })
    }

    /// The slot of pass `name`; the names are the renderer's own constants.
    fn slot(&self, name: &str) -> u32 {
        self.names
            .iter()
            .position(|n| *n == name)
            .unwrap_or_else(|| panic!("pass {name} is not one of the timer's {:?}", self.names))
            as u32
    }

    pub fn compute(&self, name: &str) -> wgpu::ComputePassTimestampWrites<'_> {
        let pass = self.slot(name);
        wgpu::ComputePassTimestampWrites {
            query_set: &self.queries,
            beginning_of_pass_write_index: Some(2 * pass),
            end_of_pass_write_index: Some(2 * pass + 1),
        }
    }

    pub fn render(&self, name: &str) -> wgpu::RenderPassTimestampWrites<'_> {
        let pass = self.slot(name);
        wgpu::RenderPassTimestampWrites {
            query_set: &self.queries,
            beginning_of_pass_write_index: Some(2 * pass),
            end_of_pass_write_index: Some(2 * pass + 1),
        }
    }

    /// The slot of the first of the passes that ran; those after it ran too.
    fn first(&self, ran: &[&str]) -> u32 {
        ran.iter().map(|n| self.slot(n)).min().unwrap_or(0)
    }

    /// Resolves the pairs of the passes that ran (a tail of the timer's passes) to the start of
    /// the buffer; resolve offsets must be aligned, so skipped passes cannot keep their slots.
    pub fn resolve(&self, encoder: &mut wgpu::CommandEncoder, ran: &[&str]) {
        let (first, passes) = (self.first(ran), self.names.len() as u32);
        encoder.resolve_query_set(&self.queries, 2 * first..2 * passes, &self.resolve, 0);
        encoder.copy_buffer_to_buffer(&self.resolve, 0, &self.read, 0, 16 * passes as u64);
    }

    /// Milliseconds of the passes that ran, after the frame's submission completed.
    pub fn read(&self, ctx: &GpuContext, ran: &[&'static str]) -> Result<PassTimes> {
        let ticks: Vec<u64> = read_buffer(ctx, &self.read, |b| bytemuck::cast_slice(b).to_vec())?;
        let first = self.first(ran);
        let ms = |name: &str| {
            let k = 2 * (self.slot(name) - first) as usize;
            ticks[k + 1].saturating_sub(ticks[k]) as f64 * self.period_ns * 1e-6
        };
        Ok(PassTimes(ran.iter().map(|&n| (n.into(), ms(n))).collect()))
    }
}

/// Each pixel's ground position from its view depth (clip w, metres: its f32 bits in an
/// Rgba8Unorm copy, low byte first, as `raster.wgsl` writes them): the pixel centre at
/// reversed-Z depth `near / w`, computed and unprojected in f64 with `view_proj` (metres from its
/// origin), w = 1; sky (depth 0) is all 0.
pub fn positions_from_depth(
    ctx: &GpuContext,
    depth: &wgpu::Texture,
    view_proj: glam::DMat4,
    near: f64,
) -> Result<Vec<[f32; 4]>> {
    let (width, height) = (depth.width(), depth.height());
    let alloc = Alloc {
        device: &ctx.device,
        ledger: &Default::default(),
        shared: &ctx.shared,
    };
    let readback = Readback::counted(&alloc, width, height, depth.format())?;
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    readback.record(&mut encoder, depth)?;
    ctx.queue.submit([encoder.finish()]);
    let texels = readback.read(&ctx.device)?;
    let inverse = view_proj.inverse();
    let mut out = Vec::with_capacity((width * height) as usize);
    for (y, row) in texels.chunks_exact(width as usize * 4).enumerate() {
        for (x, b) in row.chunks_exact(4).enumerate() {
            let w = f32::from_le_bytes([b[0], b[1], b[2], b[3]]);
            // Sky, and anything but a finite depth in front of the eye.
            if !(w > 0.0 && w.is_finite()) {
                out.push([0.0; 4]);
                continue;
            }
            let ndc = glam::DVec4::new(
                (x as f64 + 0.5) / width as f64 * 2.0 - 1.0,
                1.0 - (y as f64 + 0.5) / height as f64 * 2.0,
                near / w as f64,
                1.0,
            );
            let p = inverse * ndc;
            out.push([
                (p.x / p.w) as f32,
                (p.y / p.w) as f32,
                (p.z / p.w) as f32,
                1.0,
            ]);
        }
    }
    Ok(out)
}

/// A storage buffer of vec4 f32 copied back (tests, and the baseline's δ computation).
pub fn read_vec4(ctx: &GpuContext, source: &wgpu::Buffer) -> Result<Vec<[f32; 4]>> {
    read_pod(ctx, source)
}

/// A whole buffer (with COPY_SRC use) read back as values of `T`.
pub fn read_pod<T: bytemuck::Pod>(ctx: &GpuContext, source: &wgpu::Buffer) -> Result<Vec<T>> {
    let size = source.size();
    let staging = staging(ctx, "readback", size);
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    encoder.copy_buffer_to_buffer(source, 0, &staging, 0, size);
    ctx.queue.submit([encoder.finish()]);
    read_buffer(ctx, &staging, |b| bytemuck::cast_slice(b).to_vec())
}

/// As [`read_pod`] without waiting: `done` gets the values once the device has mapped the copy
/// (natively at the next `poll`; in a browser between the page's tasks, as a page cannot block
/// on its GPU).
pub fn read_pod_later<T: bytemuck::Pod>(
    ctx: &GpuContext,
    source: &wgpu::Buffer,
    done: impl FnOnce(Result<Vec<T>>) + wgpu::WasmNotSend + 'static,
) {
    let size = source.size();
    let staging = staging(ctx, "readback", size);
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    encoder.copy_buffer_to_buffer(source, 0, &staging, 0, size);
    ctx.queue.submit([encoder.finish()]);
    let mapped = staging.clone();
    staging
        .slice(..)
        .map_async(wgpu::MapMode::Read, move |result| {
            let values = result
                .map_err(|e| crate::Error::device("readback failed", e))
                .and_then(|()| {
                    let view = mapped
                        .slice(..)
                        .get_mapped_range()
                        .map_err(|e| crate::Error::device("readback mapping", e))?;
                    Ok(bytemuck::cast_slice(&view).to_vec())
                });
            mapped.unmap();
            done(values)
        });
}

pub(crate) fn read_buffer<T>(
    ctx: &GpuContext,
    buffer: &wgpu::Buffer,
    f: impl FnOnce(&[u8]) -> T,
) -> Result<T> {
    let out = crate::readback::read_buffer(&ctx.device, buffer, f)?;
    // What the frame read back is no frame where the device refused part of it.
    ctx.raised()?;
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `compare --replot` reads `report.json`'s pass times back: the same names, times and order,
    /// not the alphabetical order of a map.
    #[test]
    fn pass_times_read_back_as_written() {
        let timed = PassTimes(vec![
            ("warp_zoom".into(), 0.156),
            ("mesh_split".into(), 0.054),
            ("normals".into(), 0.038),
            ("terrain".into(), 21.97),
        ]);
        let json = serde_json::to_string(&timed).unwrap();
        assert_eq!(
            json,
            r#"{"warp_zoom":0.156,"mesh_split":0.054,"normals":0.038,"terrain":21.97}"#
        );
        let back: PassTimes = serde_json::from_str(&json).unwrap();
        assert_eq!(back, timed);
        assert_eq!(back.get("terrain"), Some(21.97));
        let none: PassTimes = serde_json::from_str("{}").unwrap();
        assert_eq!(none, PassTimes::default());
        assert!(serde_json::from_str::<PassTimes>(r#"{"terrain":"slow"}"#).is_err());
    }
}
