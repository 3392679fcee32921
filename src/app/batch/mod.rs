//! `terrain batch`: many snapshots from a jobs file (DESIGN.md), unattended, on one device.
//!
//! Rules:
//! - Items are the file's `[[job]]` tables in order, then `[random].count` random cameras named
//!   `random-<i>`; item k belongs to shard i of n when k mod n = i, so shards are deterministic and
//!   together are exactly the unsharded set. A random camera depends only on the seed and its own
//!   index, never on which shard or run draws it.
//! - A job's keys are merged into the base scene's TOML and the result is checked like any scene
//!   file, so a bad key fails that job naming the key. A job that fails (bad keys, a missing
//!   sketch, a camera under the ground, a device error) is recorded with its cause and the rest
//!   carry on; the command exits non-zero at the end if any failed.
//! - One device for the batch, and one renderer (pipelines, atlas, baked grid) kept while
//!   consecutive items share everything but the camera.
//! - Each snapshot is written atomically, then its line is appended to the manifest
//!   (`manifest.jsonl`, or `manifest-<i>-of-<n>.jsonl` for a shard) and flushed. `--resume` keeps
//!   the manifest's complete `ok` lines whose image exists, drops the rest (failed items, a line
//!   torn by a kill) and renders what is missing, so nothing is lost or listed twice.
//!
//! Rejected alternative: one process per snapshot (a shell loop over `terrain render`). Every
//! launch opens the device and compiles the pipelines again; `batch` measures what that costs.

use crate::app::output::{write_atomic, write_image};
use crate::app::progress::Progress;
use crate::camera::Camera;
use crate::error::{Error, Result, Role};
use crate::gpu::context::{GpuContext, Needs};
use crate::gpu::uniforms::View;
use crate::render::Renderer;

use crate::scene::{self, Scene, ground_under};
use crate::sketch::Atlas;
use glam::{DVec2, DVec3};
mod manifest;

pub use manifest::{ManifestLine, Snapshot, SnapshotCamera, Status};
use serde::{Deserialize, Serialize};
use std::collections::HashSet;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The most random cameras one jobs file asks for.
pub const MAX_RANDOM: usize = 10_000_000;

/// Random cameras stand this far above the sketch's ground, plus the detail's reach (metres).
pub const RANDOM_HEIGHT_M: (f64, f64) = (30.0, 3000.0);

#[derive(Clone, Debug)]
pub struct Random {
    pub count: usize,
    pub seed: u64,
}

/// A parsed jobs file.
pub struct Jobs {
    pub scene_path: PathBuf,
    base: toml::Table,
    explicit: Vec<toml::Value>,
    pub random: Option<Random>,
}

/// One snapshot to take.
#[derive(Clone, Debug)]
pub struct Item {
    pub index: usize,
    pub name: String,
    pub kind: ItemKind,
}

#[derive(Clone, Debug)]
pub enum ItemKind {
    /// `[[job]]` number k of the file.
    Explicit(usize),
    /// Random camera number i.
    Random(usize),
}

fn bad(path: &Path, reason: impl Into<String>) -> Error {
    Error::file(Role::JobsFile, path, reason)
}

/// The jobs file as written (docs/scene.md, "Jobs file"); unknown keys are refused by name.
#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct JobsFile {
    /// The base scene every job starts from, relative to the jobs file.
    pub scene: PathBuf,
    pub random: Option<RandomSection>,
    /// Explicit jobs: `name`, and any scene keys, which override the base scene's.
    #[serde(default)]
    pub job: Vec<toml::Table>,
}

#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct RandomSection {
    /// How many random cameras.
    pub count: u64,
    /// The seed of the cameras (each a function of the seed and its index alone).
    #[serde(default)]
    pub seed: u64,
}

impl Jobs {
    pub fn load(path: &Path) -> Result<Jobs> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(Role::JobsFile, path, e))?;
        let de = toml::Deserializer::parse(&text).map_err(|e| bad(path, e.message()))?;
        let file: JobsFile = serde_path_to_error::deserialize(de).map_err(|e| {
            let key = e.path().to_string();
            let message = e.into_inner().message().replace('\n', " ");
            if key.is_empty() || key == "." || message.contains(&key) {
                bad(path, message)
            } else {
                bad(path, format!("{key}: {message}"))
            }
        })?;
        let random = match file.random {
            Some(r) if r.count > MAX_RANDOM as u64 => {
                return Err(bad(
                    path,
                    format!("random.count = {}: at most {MAX_RANDOM}", r.count),
                ));
            }
            Some(r) => Some(Random {
                count: r.count as usize,
                seed: r.seed,
            }),
            None => None,
        };
        let base_dir = path.parent().unwrap_or(Path::new(""));
        let scene_path = base_dir.join(&file.scene);
        let base_text = std::fs::read_to_string(&scene_path)
            .map_err(|e| Error::io(Role::Scene, &scene_path, e))?;
        let base: toml::Table = base_text
            .parse()
            .map_err(|e: toml::de::Error| Error::scene(&scene_path, e.message()))?;
        Ok(Jobs {
            scene_path,
            base,
            explicit: file.job.into_iter().map(toml::Value::Table).collect(),
            random,
        })
    }

    /// Every item of the batch, in order.
    pub fn items(&self) -> Vec<Item> {
        let mut out: Vec<Item> = self
            .explicit
            .iter()
            .enumerate()
            .map(|(k, job)| Item {
                index: k,
                name: job
                    .get("name")
                    .and_then(|n| n.as_str())
                    .map(str::to_string)
                    .unwrap_or_else(|| format!("job-{k}")),
                kind: ItemKind::Explicit(k),
            })
            .collect();
        let n = out.len();
        if let Some(r) = &self.random {
            out.extend((0..r.count).map(|i| Item {
                index: n + i,
                name: format!("random-{i}"),
                kind: ItemKind::Random(i),
            }));
        }
        out
    }

    /// The scene of item `k` of the explicit jobs: the base with the job's keys merged in.
    fn job_scene(&self, k: usize) -> std::result::Result<Scene, String> {
        let job = self.explicit[k]
            .as_table()
            .ok_or_else(|| format!("job {k}: expected a table"))?;
        let mut merged = self.base.clone();
        for (key, value) in job {
            if key == "name" {
                if !value.is_str() {
                    return Err("name: expected a string".into());
                }
                continue;
            }
            merge(&mut merged, key, value.clone());
        }
        let text = toml::to_string(&merged).map_err(|e| e.to_string())?;
        let dir = self
            .scene_path
            .parent()
            .unwrap_or(Path::new(""))
            .to_path_buf();
        Scene::parse(&text, dir).map_err(|fault| name_the_key(&text, &fault.to_string()))
    }

    pub fn base_scene(&self) -> Result<Scene> {
        let text = toml::to_string(&self.base).map_err(|e| Error::encode("base scene", e))?;
        let dir = self
            .scene_path
            .parent()
            .unwrap_or(Path::new(""))
            .to_path_buf();
        Scene::parse(&text, dir).map_err(|fault| fault.into_error(&self.scene_path))
    }
}

/// Merges `value` into `table[key]`, tables key by key, anything else replaced.
fn merge(table: &mut toml::Table, key: &str, value: toml::Value) {
    match (table.get_mut(key), value) {
        (Some(toml::Value::Table(old)), toml::Value::Table(new)) => {
            for (k, v) in new {
                merge(old, &k, v);
            }
        }
        (_, v) => {
            table.insert(key.to_string(), v);
        }
    }
}

/// A scene error about `line N` of the merged TOML (which the user never sees) restated with the
/// key on that line, `section.key: …`.
fn name_the_key(text: &str, reason: &str) -> String {
    let Some((n, rest)) = reason
        .strip_prefix("line ")
        .and_then(|r| r.split_once(": "))
        .and_then(|(n, rest)| Some((n.parse::<usize>().ok()?, rest)))
    else {
        return reason.to_string();
    };
    let mut section = String::new();
    for (k, line) in text.lines().enumerate() {
        let line = line.trim();
        if let Some(h) = line.strip_prefix('[').and_then(|h| h.strip_suffix(']')) {
            section = h.trim_matches(['[', ']']).to_string();
        }
        if k + 1 == n {
            let key = line
                .split_once('=')
                .map(|(key, _)| key.trim())
                .unwrap_or(line);
            let path = if section.is_empty() {
                key.to_string()
            } else {
                format!("{section}.{key}")
            };
            // The scene reader names the key itself where serde knows it.
            if rest.starts_with(&path) {
                return rest.to_string();
            }
            return format!("{path}: {rest}");
        }
    }
    rest.to_string()
}

/// SplitMix64: a tiny, well-mixed generator, so a random camera is a pure function of
/// (seed, index).
struct SplitMix(u64);

impl SplitMix {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Random camera `i` over `atlas`: above the ground by 30 m to 3 km (log-uniform) plus the
/// detail's reach, looking at a point of the sketch 2 to 8 heights away in a random heading.
pub fn random_camera(
    scene: &Scene,
    atlas: &Atlas,
    reach_m: f64,
    seed: u64,
    i: usize,
) -> Result<Camera> {
    let mut rng = SplitMix(seed ^ (i as u64).wrapping_mul(0xd1b5_4a32_d192_ed03));
    for _ in 0..3 {
        rng.next();
    }
    let (lo, hi) = (atlas.origin, atlas.max_corner());
    let inside = |u: f64, v: f64| DVec2::new(lo.x + (hi.x - lo.x) * u, lo.y + (hi.y - lo.y) * v);
    let ground = inside(0.1 + 0.8 * rng.next(), 0.1 + 0.8 * rng.next());
    let (h0, h1) = RANDOM_HEIGHT_M;
    let above = (h0.ln() + (h1.ln() - h0.ln()) * rng.next()).exp();
    let z = ground_under(atlas, ground).unwrap_or(atlas.max_m as f64);
    let eye = ground.extend(z + reach_m + above);
    let heading = std::f64::consts::TAU * rng.next();
    let distance = above * (2.0 + 6.0 * rng.next());
    let aim = ground + DVec2::new(heading.cos(), heading.sin()) * distance;
    let aim = aim.clamp(lo, hi);
    let target = aim.extend(ground_under(atlas, aim).unwrap_or(z));
    let mut s = scene.clone();
    s.camera.position = eye.to_array();
    s.camera.look_at = if (target - eye).truncate().length() < 1.0 {
        (target - DVec3::Y).to_array()
    } else {
        target.to_array()
    };
    scene::camera_of(&s, atlas)
}

pub struct Options {
    /// (i, n): this run renders items k with k mod n = i.
    pub shard: (usize, usize),
    pub resume: bool,
}

pub struct Summary {
    pub total: usize,
    pub rendered: usize,
    pub skipped: usize,
    pub failed: usize,
    pub seconds: f64,
    pub manifest: PathBuf,
}

pub fn manifest_name(shard: (usize, usize)) -> String {
    if shard.1 == 1 {
        "manifest.jsonl".into()
    } else {
        format!("manifest-{}-of-{}.jsonl", shard.0, shard.1)
    }
}

/// The names done according to `manifest` (complete `ok` lines whose image exists); rewrites it
/// with only those lines, first of each name.
fn resume_from(manifest: &Path, out_dir: &Path) -> Result<HashSet<String>> {
    let Ok(text) = std::fs::read_to_string(manifest) else {
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
        if out_dir.join(format!("{name}.png")).is_file() && done.insert(name) {
            kept += line;
            kept.push('\n');
        }
    }
    write_atomic(manifest, kept.as_bytes())?;
    Ok(done)
}

fn plain_name(name: &str) -> bool {
    !name.is_empty()
        && !name.starts_with('.')
        && name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || "-_.".contains(c))
}

/// The renderer kept across items: rebuilt when an item's scene differs from the last in
/// anything but the camera.
struct Cache {
    ctx: Option<GpuContext>,
    key: String,
    renderer: Option<Renderer>,
}

fn scene_key(scene: &Scene) -> String {
    let mut s = scene.clone();
    s.camera.position = [0.0; 3];
    s.camera.look_at = [0.0; 3];
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
            let r =
                Renderer::with_context(ctx, scene, atlas, scene.render.mode, View::Shaded, false)?;
            self.renderer = Some(r);
            self.key = key;
        }
        Ok(self.renderer.as_mut().expect("just built"))
    }
}

/// Renders item `item`: its scene, its camera, the snapshot written to `out_dir`.
fn render_item(jobs: &Jobs, item: &Item, cache: &mut Cache, out_dir: &Path) -> Result<Snapshot> {
    if !plain_name(&item.name) {
        return Err(Error::Job {
            name: item.name.clone(),
            reason: "use letters, digits, '-', '_' and '.' in its name (it names the output file)"
                .into(),
        });
    }
    let (scene, camera) = match item.kind {
        ItemKind::Explicit(k) => {
            let scene = jobs.job_scene(k).map_err(|reason| Error::Job {
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
            let camera = random_camera(&scene, r.atlas(), reach, seed, i)?;
            (scene, camera)
        }
    };
    let r = cache.renderer(&scene)?;
    let frame = r.render(&camera)?;
    let output = out_dir.join(format!("{}.png", item.name));
    write_image(&output, frame.width, frame.height, &frame.rgba)?;
    Ok(Snapshot {
        output: output.file_name().map(|n| n.to_string_lossy().into_owned()),
        mode: scene.render.mode,
        camera: SnapshotCamera {
            position: camera.eye.to_array(),
            look_at: (camera.eye + camera.forward * 100.0).to_array(),
            fov_y_deg: camera.fov_y.to_degrees(),
        },
        width: frame.width,
        height: frame.height,
        triangles: frame.gpu.triangles,
        cpu_stage_us: frame.cpu_us,
        gpu_ms: frame.gpu.gpu_ms,
        frame_ms: frame.gpu.gpu_ms + frame.cpu_us * 1e-3,
    })
}

pub fn run(jobs_path: &Path, out_dir: &Path, o: &Options) -> Result<Summary> {
    let jobs = Jobs::load(jobs_path)?;
    std::fs::create_dir_all(out_dir).map_err(|e| Error::io(Role::OutputFolder, out_dir, e))?;
    let manifest = out_dir.join(manifest_name(o.shard));
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
    let mut file = std::fs::OpenOptions::new()
        .append(true)
        .open(&manifest)
        .map_err(|e| Error::io(Role::Manifest, &manifest, e))?;
    let mut names = HashSet::new();
    let mut cache = Cache {
        ctx: None,
        key: String::new(),
        renderer: None,
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
        let result = if names.insert(item.name.clone()) {
            render_item(&jobs, item, &mut cache, out_dir)
        } else {
            Err(Error::Job {
                name: item.name.clone(),
                reason: "its name is used by an earlier job".into(),
            })
        };
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
            }
        }
        let text = serde_json::to_string(&line).map_err(|e| Error::encode("manifest line", e))?;
        writeln!(file, "{text}")
            .and_then(|_| file.flush())
            .map_err(|e| Error::io(Role::Manifest, &manifest, e))?;
        progress.advance(1.0, &item.name);
    }
    progress.finish();
    Ok(Summary {
        total: items.len(),
        rendered,
        skipped: items.len() - todo,
        failed,
        seconds: start.elapsed().as_secs_f64(),
        manifest,
    })
}

/// Merges the shard manifests in `out_dir` into `manifest.jsonl`, one line per item in item
/// order. Returns (lines, items missing, items failed).
pub fn merge_manifests(jobs_path: &Path, out_dir: &Path) -> Result<(usize, Vec<String>, usize)> {
    let jobs = Jobs::load(jobs_path)?;
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
            .map_err(|e| Error::io(Role::Manifest, entry.path(), e))?;
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
    write_atomic(&out_dir.join("manifest.jsonl"), text.as_bytes())?;
    Ok((lines.iter().flatten().count(), missing, failed))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn merge_replaces_leaves_and_merges_tables() {
        let mut base: toml::Table = "[camera]\nwidth = 5\nheight = 6\n[detail]\noctaves = 3\n"
            .parse()
            .unwrap();
        let job: toml::Table = "camera = { width = 7 }\nrender = { mode = \"geomipmap\" }\n"
            .parse()
            .unwrap();
        for (k, v) in job {
            merge(&mut base, &k, v);
        }
        assert_eq!(base["camera"]["width"].as_integer(), Some(7));
        assert_eq!(base["camera"]["height"].as_integer(), Some(6));
        assert_eq!(base["render"]["mode"].as_str(), Some("geomipmap"));
    }

    #[test]
    fn generator_is_uniform_enough_and_deterministic() {
        let mut a = SplitMix(7);
        let v: Vec<f64> = (0..10000).map(|_| a.next()).collect();
        let mean = v.iter().sum::<f64>() / v.len() as f64;
        assert!((mean - 0.5).abs() < 0.01 && v.iter().all(|x| (0.0..1.0).contains(x)));
        assert_eq!(SplitMix(7).next(), v[0]);
    }

    #[test]
    fn errors_name_the_key_not_a_line_of_the_merged_text() {
        let text = "[camera]\nwidth = 5\nposition = \"x\"\n";
        assert_eq!(
            name_the_key(text, "line 3: invalid type"),
            "camera.position: invalid type"
        );
        assert_eq!(
            name_the_key(text, "camera.fov_y_deg: out of range"),
            "camera.fov_y_deg: out of range"
        );
    }

    #[test]
    fn names_must_be_plain_file_names() {
        assert!(plain_name("random-3") && plain_name("north_ridge.v2"));
        assert!(
            !plain_name("../x") && !plain_name("a/b") && !plain_name("") && !plain_name(".hidden")
        );
    }
}
