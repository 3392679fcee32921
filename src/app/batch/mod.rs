//! `terrain batch`: many snapshots from a jobs file (`docs/design.md`, Scene and jobs files),
//! unattended, on one device.
//!
//! Rules:
//! - Items are the file's `[[job]]` tables in order, then `[random].count` random cameras named
//!   `random-<i>`; item k belongs to shard i of n when k mod n = i, so shards are deterministic and
//!   together are exactly the unsharded set. A random camera depends only on the seed and its own
//!   index, never on which shard or run draws it.
//! - A job's keys are merged into the base scene's TOML (its camera laid over the base's as one
//!   camera, `scene::lay_camera`) and the result is checked like any scene file, so a bad key
//!   fails that job naming the key. A job that fails (bad keys, a missing
//!   sketch, a camera under the ground, a device error) is recorded with its cause and the rest
//!   carry on; the command exits non-zero at the end if any failed.
//! - One device for the batch, and one renderer (pipelines, atlas, baked grid) kept while
//!   consecutive items share everything but the camera.
//! - Each snapshot and its ground truth (`--outputs`, [`crate::ground_truth`]) are written
//!   atomically together, then its line is appended to the manifest (`manifest.jsonl`, or
//!   `manifest-<i>-of-<n>.jsonl` for a shard) and flushed. `--resume` keeps the manifest's
//!   complete `ok` lines whose image and listed files exist, drops the rest (failed items, a line
//!   torn by a kill) and renders what is missing, so nothing is lost or listed twice; it also
//!   removes the temporary files a kill left mid-write for this shard's files.
//! - `--export` writes the cameras of the manifest's `ok` lines for NeRF or COLMAP once the
//!   items are done (`export`).
//! - Beside each manifest, a record of what its items were made from (the `inputs` module): a
//!   folder whose manifest was made from other inputs is refused, with `--resume` or without, so
//!   a resumed batch never keeps another batch's images and no run replaces another's manifest.
//! - Item names are unique, checked when the jobs file is read: two items of one name would
//!   write one file.
//!
//! Rejected alternative: one process per snapshot (a shell loop over `terrain render`). Every
//! launch opens the device and compiles the pipelines again; `batch` measures what that costs.

use crate::error::MANIFEST;
use crate::ground_truth;
use crate::output::{Staged, add_image, write_atomic};
use crate::progress::Progress;
use terrain_engine::Camera;
use terrain_engine::Renderer;
use terrain_engine::View;
use terrain_engine::scene::{self, Scene};
use terrain_engine::sketch::Atlas;
use terrain_engine::truth::{Extrinsics, Intrinsics, Output, Truth};
use terrain_engine::{Error, Result, Role};
use terrain_engine::{GpuContext, Needs};

mod export;
mod inputs;
mod jobs;
mod manifest;

pub use export::{Export, export};

pub use inputs::{Inputs, Stamp, record_path};
pub use jobs::{Item, ItemKind, Jobs, JobsFile, MAX_RANDOM, Overrides, Random, RandomSection};
pub use manifest::{ManifestLine, PlanetKeys, Snapshot, SnapshotCamera, Status};
use std::collections::HashSet;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;
pub use terrain_engine::scene::{RANDOM_HEIGHT_M, random_camera};

pub struct Options {
    /// (i, n): this run renders items k with k mod n = i.
    pub shard: (usize, usize),
    pub resume: bool,
    /// `--set`, `--size` and `--mode`, for every item.
    pub overrides: Overrides,
    /// What each item writes (`--outputs`): the image and the ground truth beside it.
    pub outputs: Vec<Output>,
    /// The cameras written for other tools once the items are done (`--export`).
    pub export: Option<Export>,
}

pub struct Summary {
    pub total: usize,
    pub rendered: usize,
    pub skipped: usize,
    pub failed: usize,
    pub seconds: f64,
    pub manifest: PathBuf,
    /// The files `--export` wrote.
    pub exported: Vec<PathBuf>,
}

pub fn manifest_name(shard: (usize, usize)) -> String {
    if shard.1 == 1 {
        "manifest.jsonl".into()
    } else {
        format!("manifest-{}-of-{}.jsonl", shard.0, shard.1)
    }
}

/// The names done according to `manifest` (complete `ok` lines whose image and every other
/// file they list exist); rewrites it with only those lines, first of each name.
fn resume_from(manifest: &Path, out_dir: &Path) -> Result<HashSet<String>> {
    let Ok(text) = std::fs::read_to_string(manifest) else {
        // Nothing to resume: a first run with `--resume`, as a scheduler's job script always
        // passes it, starts the manifest.
        write_atomic(manifest, b"")?;
        return Ok(HashSet::new());
    };
    let mut done = HashSet::new();
    let mut kept = String::new();
    for line in text.lines() {
        let Ok(v) = serde_json::from_str::<ManifestLine>(line) else {
            continue;
        };
        if v.status != Status::Ok {
            continue;
        }
        let name = v.name;
        let files_exist = v
            .snapshot
            .as_ref()
            .is_some_and(|s| s.outputs.values().all(|f| out_dir.join(f).is_file()));
        if files_exist && out_dir.join(format!("{name}.png")).is_file() && done.insert(name) {
            kept += line;
            kept.push('\n');
        }
    }
    write_atomic(manifest, kept.as_bytes())?;
    Ok(done)
}

/// Removes the temporary files a killed run left while writing this shard's images or manifest
/// (`.NAME.png.PID.tmp`, see `output::write_atomic`). Only this shard's names: another shard
/// writing into the same folder may be alive. Best effort: a file that will not go is harmless.
fn remove_torn_writes(out_dir: &Path, items: &[Item], outputs: &[Output], manifest: &Path) {
    let Ok(entries) = std::fs::read_dir(out_dir) else {
        return;
    };
    let mut ours: HashSet<String> = HashSet::new();
    for it in items {
        let image = PathBuf::from(format!("{}.png", it.name));
        for f in std::iter::once(image.clone()).chain(ground_truth::files(&image, outputs)) {
            ours.insert(f.to_string_lossy().into_owned());
        }
    }
    for m in [manifest.to_path_buf(), record_path(manifest)] {
        if let Some(m) = m.file_name() {
            ours.insert(m.to_string_lossy().into_owned());
        }
    }
    for e in entries.flatten() {
        let file = e.file_name().to_string_lossy().into_owned();
        let target = file
            .strip_prefix('.')
            .and_then(|f| f.strip_suffix(".tmp"))
            .and_then(|f| f.rsplit_once('.'))
            .filter(|(_, pid)| !pid.is_empty() && pid.bytes().all(|b| b.is_ascii_digit()))
            .map(|(target, _)| target);
        if target.is_some_and(|t| ours.contains(t)) {
            let _ = std::fs::remove_file(e.path());
        }
    }
}

fn plain_name(name: &str) -> bool {
    !name.is_empty()
        && !name.starts_with('.')
        && name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || "-_.".contains(c))
}

/// The renderer kept across items: rebuilt when an item's scene differs from the last in
/// anything but the camera (its size included: a renderer makes its targets for each size).
struct Cache {
    ctx: Option<GpuContext>,
    key: String,
    renderer: Option<Renderer>,
    /// The surface classes' renderer of the same scene, made when an item first asks for them.
    classes: Option<Renderer>,
}

fn scene_key(scene: &Scene) -> String {
    let mut s = scene.clone();
    s.camera.aim(glam::DVec3::ZERO, glam::DVec3::ZERO);
    let c = &mut s.camera;
    (c.lat_deg, c.lon_deg, c.altitude_m) = (None, None, None);
    (c.heading_deg, c.pitch_deg) = (None, None);
    (c.width, c.height) = (0, 0);
    format!("{s:?}")
}

impl Cache {
    fn renderer(&mut self, scene: &Scene) -> Result<&mut Renderer> {
        let key = scene_key(scene);
        if self.renderer.is_none() || self.key != key {
            self.renderer = None;
            let atlas = scene::load_atlas(scene)?;
            let ctx = match &self.ctx {
                Some(c) => c.clone(),
                None => {
                    let c = GpuContext::new(&Needs { storage_bytes: 0 })?;
                    self.ctx = Some(c.clone());
                    c
                }
            };
            let r = Renderer::with_context(ctx, scene, atlas, scene.render.mode, View::Shaded)?;
            self.renderer = Some(r);
            self.classes = None;
            self.key = key;
        }
        Ok(self.renderer.as_mut().expect("just built"))
    }

    /// The class renderer of `scene` (made on first use, on the same device and sketch).
    fn classes(&mut self, scene: &Scene) -> Result<&mut Renderer> {
        self.renderer(scene)?;
        if self.classes.is_none() {
            let r = self.renderer.as_ref().expect("just built");
            let made = terrain_engine::truth::surface_renderer(r, scene, scene.render.mode)?;
            self.classes = Some(made);
        }
        Ok(self.classes.as_mut().expect("just built"))
    }
}

/// Renders item `item`: its scene, its camera, the snapshot and its ground truth written to
/// `out_dir`.
fn render_item(
    jobs: &Jobs,
    item: &Item,
    cache: &mut Cache,
    out_dir: &Path,
    outputs: &[Output],
) -> crate::Result<Snapshot> {
    if !plain_name(&item.name) {
        return Err(crate::Error::Job {
            name: item.name.clone(),
            reason: "use letters, digits, '-', '_' and '.' in its name (it names the output file)"
                .into(),
        });
    }
    let (scene, camera) = match item.kind {
        ItemKind::Explicit(k) => {
            let scene = jobs.job_scene(k).map_err(|reason| crate::Error::Job {
                name: item.name.clone(),
                reason,
            })?;
            let r = cache.renderer(&scene)?;
            let camera = scene::camera_of(&scene, r.atlas())?;
            (scene, camera)
        }
        ItemKind::Random(i) => {
            let scene = jobs.base_scene()?;
            let seed = jobs.random.as_ref().map_or(0, |r| r.seed);
            let r = cache.renderer(&scene)?;
            let reach = scene::detail_of(&scene, r.atlas()).reach_m();
            random_camera(&scene, r.atlas(), reach, seed, i)?
        }
    };
    let r = cache.renderer(&scene)?;
    // Each snapshot as if alone: a resumed or sharded run makes the same images, and a planet's
    // sun stands where this camera sees it, as `render` of the item's scene would put it.
    r.forget();
    r.relight(&scene);
    let frame = r.render_settled(&camera)?;
    let planet = planet_keys(&scene, r.atlas(), &camera)?;
    ground_truth::check(outputs, r.atlas(), planet.is_some(), false)?;
    let output = out_dir.join(format!("{}.png", item.name));
    let mut staged = Staged::default();
    add_image(&mut staged, &output, frame.width, frame.height, &frame.rgba)?;
    let written = if outputs.iter().any(|&o| o != Output::Rgb) {
        let truth = Truth::new(&camera, &r.read_positions(&camera)?)?;
        let classes = match outputs.contains(&Output::Surface) {
            true => Some(terrain_engine::truth::surface_classes(
                cache.classes(&scene)?,
                &camera,
            )?),
            false => None,
        };
        let r = cache.renderer(&scene)?;
        let ground = terrain_engine::Ground::new(&scene, r.atlas(), &r.detail);
        let atlas = r.atlas();
        ground_truth::stage(
            &mut staged,
            &output,
            outputs,
            &truth,
            classes.as_deref(),
            atlas,
            &ground,
        )?
    } else {
        ground_truth::Written::from([(Output::Rgb.name().into(), output.clone())])
    };
    staged.commit()?;
    let r = cache.renderer(&scene)?;
    let place = match planet {
        Some(_) => None,
        None => Some(scene::report(
            &scene,
            r.atlas(),
            camera.eye,
            camera.eye + camera.forward,
        )?),
    };
    let relative = |p: &PathBuf| {
        p.file_name()
            .unwrap_or_default()
            .to_string_lossy()
            .into_owned()
    };
    Ok(Snapshot {
        output: output.file_name().map(|n| n.to_string_lossy().into_owned()),
        mode: scene.render.mode,
        camera: SnapshotCamera {
            position: camera.eye.to_array(),
            look_at: (camera.eye + camera.forward * 100.0).to_array(),
            fov_y_deg: camera.fov_y.to_degrees(),
            planet,
            lat_deg: place.as_ref().and_then(|p| p.lat_deg),
            lon_deg: place.as_ref().and_then(|p| p.lon_deg),
            altitude_m: place
                .as_ref()
                .filter(|p| p.lat_deg.is_some())
                .map(|p| p.altitude_m),
        },
        intrinsics: Intrinsics::of(&camera),
        extrinsics: Extrinsics::of(&camera),
        outputs: written
            .iter()
            .map(|(k, p)| (k.clone(), relative(p)))
            .collect(),
        width: frame.width,
        height: frame.height,
        triangles: frame.gpu.triangles,
        cpu_stage_us: frame.cpu_us,
        gpu_ms: frame.gpu.gpu_ms,
        frame_ms: frame.gpu.gpu_ms + frame.cpu_us * 1e-3,
    })
}

/// A planet camera's keys (its altitude above the ground as `[camera]` measures it); `None` off
/// a planet. Fails where a streamed sketch's tile under the camera cannot be read.
fn planet_keys(scene: &Scene, atlas: &Atlas, camera: &Camera) -> Result<Option<PlanetKeys>> {
    let (Some(p), Some(geo)) = (scene.planet(), camera.geo) else {
        return Ok(None);
    };
    let planet = terrain_engine::planet::Planet {
        radius: p.radius_m,
        sketch: atlas,
    };
    let ground = planet
        .ground(&scene::detail_of(scene, atlas), geo.lat, geo.lon, 0.01)?
        .max(atlas.water_m as f64);
    let f = camera.forward;
    Ok(Some(PlanetKeys {
        lat_deg: geo.lat.to_degrees(),
        lon_deg: geo.lon.to_degrees(),
        altitude_m: camera.eye.z - ground,
        heading_deg: f.x.atan2(f.y).to_degrees().rem_euclid(360.0),
        pitch_deg: f.z.clamp(-1.0, 1.0).asin().to_degrees(),
    }))
}

/// The inputs of `jobs`'s items. Fails only on a bad `--set` (a usage error, as in `render`): a
/// scene fault of the base or of a job fails the items that have it.
fn inputs_of(jobs: &Jobs, outputs: &[Output]) -> Result<Inputs> {
    let base = match jobs.base_scene() {
        Err(e @ Error::Override { .. }) => return Err(e),
        base => base.ok(),
    };
    let scenes: Vec<Scene> = base
        .into_iter()
        .chain((0..jobs.explicit_jobs()).filter_map(|k| jobs.job_scene(k).ok()))
        .collect();
    Ok(Inputs::of(jobs, &scenes, outputs))
}

pub fn run(jobs_path: &Path, out_dir: &Path, o: &Options) -> Result<Summary> {
    let mut jobs = Jobs::load(jobs_path)?;
    jobs.overrides = o.overrides.clone();
    let inputs = inputs_of(&jobs, &o.outputs)?;
    std::fs::create_dir_all(out_dir).map_err(|e| Error::io(Role::OutputFolder, out_dir, e))?;
    inputs::check_folder(out_dir, &inputs)?;
    let manifest = out_dir.join(manifest_name(o.shard));
    // The record first: a manifest with lines always has one.
    inputs.write(&record_path(&manifest))?;
    let done = if o.resume {
        resume_from(&manifest, out_dir)?
    } else {
        write_atomic(&manifest, b"")?;
        HashSet::new()
    };
    let items: Vec<Item> = jobs
        .items()
        .into_iter()
        .filter(|it| it.index % o.shard.1 == o.shard.0)
        .collect();
    if o.resume {
        remove_torn_writes(out_dir, &items, &o.outputs, &manifest);
    }
    let mut file = std::fs::OpenOptions::new()
        .append(true)
        .open(&manifest)
        .map_err(|e| Error::io(MANIFEST, &manifest, e))?;
    let mut cache = Cache {
        ctx: None,
        key: String::new(),
        renderer: None,
        classes: None,
    };
    let todo = items.iter().filter(|it| !done.contains(&it.name)).count();
    let mut progress = Progress::new("batch", todo as f64);
    let (mut rendered, mut failed) = (0, 0);
    let start = Instant::now();
    for item in &items {
        if done.contains(&item.name) {
            continue;
        }
        let t0 = Instant::now();
        let result = render_item(&jobs, item, &mut cache, out_dir, &o.outputs);
        let mut line = ManifestLine {
            index: item.index,
            name: item.name.clone(),
            shard: format!("{}/{}", o.shard.0, o.shard.1),
            seconds: t0.elapsed().as_secs_f64(),
            status: Status::Ok,
            error: None,
            snapshot: None,
        };
        match result {
            Ok(snapshot) => {
                line.snapshot = Some(snapshot);
                rendered += 1;
            }
            Err(e) => {
                line.status = Status::Failed;
                line.error = Some(e.to_string());
                failed += 1;
                // A device error may leave the renderer unusable; the next item builds a new one.
                cache.renderer = None;
                cache.classes = None;
            }
        }
        let text = serde_json::to_string(&line).map_err(|e| Error::encode("manifest line", e))?;
        writeln!(file, "{text}")
            .and_then(|_| file.flush())
            .map_err(|e| Error::io(MANIFEST, &manifest, e))?;
        progress.advance(1.0, &item.name);
    }
    progress.finish();
    let seconds = start.elapsed().as_secs_f64();
    let exported = match o.export {
        Some(format) => export(format, &manifest)?,
        None => Vec::new(),
    };
    Ok(Summary {
        total: items.len(),
        rendered,
        skipped: items.len() - todo,
        failed,
        seconds,
        manifest,
        exported,
    })
}

/// Merges the shard manifests in `out_dir` into `manifest.jsonl`, one line per item in item
/// order, with the inputs they record (which must be one batch's). Returns (lines, items
/// missing, items failed).
pub fn merge_manifests(jobs_path: &Path, out_dir: &Path) -> Result<(usize, Vec<String>, usize)> {
    let jobs = Jobs::load(jobs_path)?;
    let inputs = inputs::shards_inputs(out_dir)?;
    if let Some(i) = &inputs {
        inputs::check_folder(out_dir, i)?;
    }
    let items = jobs.items();
    let mut lines: Vec<Option<ManifestLine>> = (0..items.len()).map(|_| None).collect();
    let entries =
        std::fs::read_dir(out_dir).map_err(|e| Error::io(Role::OutputFolder, out_dir, e))?;
    for entry in entries.flatten() {
        let name = entry.file_name().to_string_lossy().into_owned();
        if !(name.starts_with("manifest-") && name.ends_with(".jsonl")) {
            continue;
        }
        let text = std::fs::read_to_string(entry.path())
            .map_err(|e| Error::io(MANIFEST, entry.path(), e))?;
        for v in text
            .lines()
            .filter_map(|l| serde_json::from_str::<ManifestLine>(l).ok())
        {
            let k = v.index;
            if k >= items.len() {
                continue;
            }
            // An ok line wins over a failed one for the same item.
            if lines[k].as_ref().is_none_or(|old| old.status != Status::Ok) {
                lines[k] = Some(v);
            }
        }
    }
    let missing: Vec<String> = items
        .iter()
        .zip(&lines)
        .filter(|(_, l)| l.is_none())
        .map(|(it, _)| it.name.clone())
        .collect();
    let failed = lines
        .iter()
        .flatten()
        .filter(|v| v.status != Status::Ok)
        .count();
    let mut text = String::new();
    for v in lines.iter().flatten() {
        text += &serde_json::to_string(v).map_err(|e| Error::encode("manifest line", e))?;
        text.push('\n');
    }
    let merged = out_dir.join("manifest.jsonl");
    if let Some(i) = &inputs {
        i.write(&record_path(&merged))?;
    }
    write_atomic(&merged, text.as_bytes())?;
    Ok((lines.iter().flatten().count(), missing, failed))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_must_be_plain_file_names() {
        assert!(plain_name("random-3") && plain_name("north_ridge.v2"));
        assert!(
            !plain_name("../x") && !plain_name("a/b") && !plain_name("") && !plain_name(".hidden")
        );
    }
}
