//! The scene file (TOML): DESIGN.md's keys and this project's additions, read strictly.
//!
//! Rules: an unknown key is an error naming it (serde's `deny_unknown_fields`), a value of the
//! wrong type names its full dotted key (`detail.octaves`, through `serde_path_to_error`), every
//! number is range-checked after parsing with the key's full dotted name in the message, and
//! relative paths resolve against the scene file's folder. An error caused by a `--set` override
//! blames the override, not the file. Defaults live in the `Default` impls, one place each; keys
//! whose default follows the sketch are `Option`s resolved in `scene::detail_of`.
//! `docs/scene.md` documents every key; a test (`tests/scene_doc.rs`) checks it against these
//! structs, their defaults included.

mod build;

pub use build::{camera_of, detail_of, ground_under, load_atlas, scene_load_options};

use crate::error::{Error, Result, Role};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    pub sketch: SketchSection,
    pub camera: CameraSection,
    #[serde(default)]
    pub detail: DetailSection,
    #[serde(default)]
    pub warp: WarpSection,
    #[serde(default)]
    pub importance: ImportanceSection,
    #[serde(default)]
    pub render: RenderSection,
    #[serde(default)]
    pub geomipmap: GeoMipMapSection,
    #[serde(default)]
    pub reference: ReferenceSection,
    pub path: Option<PathSection>,
    /// The folder relative paths resolve against; not a key.
    #[serde(skip)]
    pub base_dir: PathBuf,
}

#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SketchSection {
    pub path: Option<PathBuf>,
    pub synthetic: Option<String>,
    pub spacing_m: Option<f64>,
    pub origin_m: Option<[f64; 2]>,
    pub height_scale: Option<f64>,
    pub size: Option<usize>,
    /// For 8/16-bit PNG sketches: the heights that pixel value 0 and the maximum stand for.
    pub height_range_m: Option<[f64; 2]>,
}

#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct CameraSection {
    pub position: [f64; 3],
    pub look_at: [f64; 3],
    #[serde(default = "default_fov")]
    pub fov_y_deg: f64,
    #[serde(default = "default_size")]
    pub width: u32,
    #[serde(default = "default_size")]
    pub height: u32,
    /// Far distance in metres; by default the farthest corner of the sketch.
    pub far_m: Option<f64>,
}
fn default_fov() -> f64 {
    60.0
}
fn default_size() -> u32 {
    512
}

/// The most octaves a scene may ask for.
pub const MAX_OCTAVES: u32 = 24;
/// The finest noise wavelength the default octave count reaches, metres: below a decimetre
/// no camera this renderer places (at least a metre above the ground) resolves a change.
pub const FINEST_WAVELENGTH_M: f64 = 0.1;

#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct DetailSection {
    /// Noise octaves; by default those whose wavelength is at least [`FINEST_WAVELENGTH_M`].
    pub octaves: Option<u32>,
    /// Octave 1's amplitude; by default the sketch's own finest relief carried one octave on.
    pub amplitude_m: Option<f64>,
    pub gain: f64,
    pub seed: u32,
    /// Octaves subtracted from the split octave: the paper's "more conservative estimate".
    pub bias: f64,
    /// Per-pixel bump detail past the split octave; off leaves its code out of the shader.
    pub bump: bool,
}
impl Default for DetailSection {
    fn default() -> Self {
        DetailSection {
            octaves: None,
            amplitude_m: None,
            gain: 0.5,
            seed: 7,
            bias: 0.5,
            bump: true,
        }
    }
}

crate::named_enum! {
    /// How the warp keeps cells from folding; see `warp.rs`.
    pub enum WarpMethod ("warp method") {
        /// The paper's single row pass then column pass, nothing more.
        Plain = "plain",
        /// Row then column pass, with the column warps relaxed toward their common mean where
        /// cells fold.
        Guarded = "guarded",
    }
}

#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct WarpSection {
    pub quad_px: f64,
    pub mesh: u32,
    /// Sketch map and warp size (128 in the paper).
    pub size: u32,
    pub method: WarpMethod,
    /// Largest change of log2(importance) between neighbouring texels; 0 turns the limit off.
    pub max_log2_step: f64,
}
impl Default for WarpSection {
    fn default() -> Self {
        WarpSection {
            quad_px: 2.0,
            mesh: 512,
            size: 128,
            method: WarpMethod::Guarded,
            max_log2_step: 0.0,
        }
    }
}

#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct ImportanceSection {
    /// I_v: view distance. Off: uniform.
    pub view: bool,
    /// S_f: the frustum with its safety margin.
    pub frustum: bool,
    /// S_b: back-facing slopes.
    pub backface: bool,
    /// I_s: the surface's upper bound, samples per metre, scene-wide.
    pub max_per_m: Option<f64>,
    /// I_s from a map over the sketch (any sketch format; values in samples per metre).
    pub max_map: Option<PathBuf>,
    /// I_floor as a fraction of the least importance of a visible texel.
    pub floor: f64,
    /// S_b's floor on back-facing slopes.
    pub backface_floor: f64,
}
impl Default for ImportanceSection {
    fn default() -> Self {
        ImportanceSection {
            view: true,
            frustum: true,
            backface: true,
            max_per_m: None,
            max_map: None,
            floor: 0.1,
            backface_floor: 0.15,
        }
    }
}

#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct GeoMipMapSection {
    /// τ: the largest projected vertex error allowed, pixels.
    pub tau: f64,
    /// Octaves baked into the grid (spacing d_atlas / 2^k); by default the finest within 2^22
    /// vertices, up to 3.
    pub k: Option<u32>,
    /// Choose levels by the blocks' least depth (τ guaranteed) rather than de Boer's distance.
    pub exact: bool,
    /// Geomorphing (trilinear GeoMipMapping).
    pub morph: bool,
    /// Vertices per block side: 17, 33, 65 or 129.
    pub block: u32,
}
impl Default for GeoMipMapSection {
    fn default() -> Self {
        GeoMipMapSection {
            tau: 1.0,
            k: None,
            exact: false,
            morph: true,
            block: 33,
        }
    }
}

#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct ReferenceSection {
    /// March step as a fraction of the height above the ground (and at least of the pixel's
    /// footprint); halving it must not change the image (the convergence test).
    pub step: f64,
}
impl Default for ReferenceSection {
    fn default() -> Self {
        ReferenceSection { step: 0.25 }
    }
}

crate::named_enum! {
    /// The level-of-detail scheme that draws the terrain (`render.mode`, `--mode`).
    pub enum Mode ("mode") {
        Warped = "warped",
        Geomipmap = "geomipmap",
        Bruteforce = "bruteforce",
        Reference = "reference",
    }
}

impl Mode {
    /// The modes that draw a mesh (every one but the ray-marched reference).
    pub const MESHES: [Mode; 3] = [Mode::Warped, Mode::Geomipmap, Mode::Bruteforce];
}

#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct RenderSection {
    pub mode: Mode,
}
impl Default for RenderSection {
    fn default() -> Self {
        RenderSection { mode: Mode::Warped }
    }
}

#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct PathSection {
    #[serde(default = "default_speed")]
    pub speed_mps: f64,
    pub keys: Vec<PathKey>,
}
fn default_speed() -> f64 {
    150.0
}

#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct PathKey {
    pub position: [f64; 3],
    pub look_at: Option<[f64; 3]>,
}

/// Where a scene's fault lies: in its text, or in a `--set` override given with it.
#[derive(Clone, Debug, PartialEq)]
pub enum Fault {
    /// In the scene's text; the reason names the key (and the line, where the parser knows it).
    Text(String),
    /// In the override `arg` (`key.path=value`).
    Override { arg: String, reason: String },
}

impl std::fmt::Display for Fault {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Fault::Text(reason) => f.write_str(reason),
            Fault::Override { arg, reason } => write!(f, "--set {arg}: {reason}"),
        }
    }
}

impl Fault {
    /// The error of a scene read from `path`.
    pub fn into_error(self, path: &Path) -> Error {
        match self {
            Fault::Text(reason) => Error::scene(path, reason),
            Fault::Override { arg, reason } => Error::Override { arg, reason },
        }
    }
}

impl Scene {
    pub fn load(path: &Path) -> Result<Scene> {
        Scene::load_with(path, &[])
    }

    /// Parses and checks a scene; the error is one line naming the key.
    pub fn parse(text: &str, base_dir: PathBuf) -> std::result::Result<Scene, Fault> {
        Scene::parse_with(text, base_dir, &[])
    }

    /// Like [`Scene::load`], with `key.path=value` overrides (TOML values; bare words are strings)
    /// applied before the scene is checked, as `--set` gives them.
    pub fn load_with(path: &Path, overrides: &[String]) -> Result<Scene> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(Role::Scene, path, e))?;
        let base = path.parent().unwrap_or(Path::new("")).to_path_buf();
        Scene::parse_with(&text, base, overrides).map_err(|f| f.into_error(path))
    }

    pub fn parse_with(
        text: &str,
        base_dir: PathBuf,
        overrides: &[String],
    ) -> std::result::Result<Scene, Fault> {
        let mut scene = if overrides.is_empty() {
            deserialize_text(text).map_err(Fault::Text)?
        } else {
            let mut table: toml::Table = toml::from_str(text)
                .map_err(|e| Fault::Text(one_line(e.message(), e.span(), text)))?;
            for o in overrides {
                apply_override(&mut table, o).map_err(|reason| Fault::Override {
                    arg: o.clone(),
                    reason,
                })?;
            }
            match serde_path_to_error::deserialize::<_, Scene>(toml::Value::Table(table)) {
                Ok(scene) => scene,
                Err(e) => {
                    let key = e.path().to_string();
                    let message = e.inner().message().replace('\n', " ");
                    return Err(match overrides.iter().find(|o| blames(o, &key, &message)) {
                        Some(o) => Fault::Override {
                            arg: o.clone(),
                            reason: message,
                        },
                        // The file's own fault, with its line where the file alone shows it.
                        None => Fault::Text(
                            deserialize_text(text)
                                .err()
                                .unwrap_or_else(|| keyed(&key, &message)),
                        ),
                    });
                }
            }
        };
        scene.base_dir = base_dir;
        scene.check().map_err(|reason| {
            match overrides
                .iter()
                .find(|o| reason.starts_with(override_key(o)))
            {
                Some(o) => Fault::Override {
                    arg: o.clone(),
                    // The argument names the key and value already.
                    reason: reason
                        .split_once(": ")
                        .map_or(reason.clone(), |(_, r)| r.to_string()),
                },
                None => Fault::Text(reason),
            }
        })?;
        Ok(scene)
    }

    pub fn resolve(&self, p: &Path) -> PathBuf {
        self.base_dir.join(p)
    }

    fn check(&self) -> std::result::Result<(), String> {
        let s = &self.sketch;
        match (&s.path, &s.synthetic) {
            (Some(_), Some(_)) => return Err("sketch: give `path` or `synthetic`, not both".into()),
            (None, None) => return Err("sketch: give `path` or `synthetic`".into()),
            (None, Some(name)) if !crate::sketch::synthetic::NAMES.contains(&name.as_str()) => {
                return Err(format!(
                    "sketch.synthetic = \"{name}\": one of {}",
                    crate::sketch::synthetic::NAMES.join(", ")
                ));
            }
            (Some(_), None) if s.size.is_some() => {
                return Err("sketch.size applies to synthetic sketches only".into());
            }
            _ => {}
        }
        positive("sketch.spacing_m", s.spacing_m)?;
        positive("sketch.height_scale", s.height_scale)?;
        if let Some(size) = s.size {
            within("sketch.size", size as f64, 2.0, 4097.0)?;
        }
        if let Some(o) = s.origin_m {
            finite_all("sketch.origin_m", &o)?;
        }
        if let Some(r) = s.height_range_m {
            finite_all("sketch.height_range_m", &r)?;
        }
        let c = &self.camera;
        finite_all("camera.position", &c.position)?;
        finite_all("camera.look_at", &c.look_at)?;
        if c.position == c.look_at {
            return Err("camera.look_at equals camera.position: no view direction".into());
        }
        open_range("camera.fov_y_deg", c.fov_y_deg, 0.0, 180.0)?;
        within("camera.width", c.width as f64, 1.0, 16384.0)?;
        within("camera.height", c.height as f64, 1.0, 16384.0)?;
        positive("camera.far_m", c.far_m)?;
        let d = &self.detail;
        if let Some(o) = d.octaves {
            within("detail.octaves", o as f64, 0.0, MAX_OCTAVES as f64)?;
        }
        if let Some(a) = d.amplitude_m {
            within("detail.amplitude_m", a, 0.0, 1e5)?;
        }
        within("detail.gain", d.gain, 0.0, 1.0)?;
        within("detail.bias", d.bias, -4.0, 8.0)?;
        let w = &self.warp;
        open_range("warp.quad_px", w.quad_px, 0.0, 1e4)?;
        within("warp.mesh", w.mesh as f64, 2.0, 4096.0)?;
        within("warp.size", w.size as f64, 2.0, 4096.0)?;
        within("warp.max_log2_step", w.max_log2_step, 0.0, 64.0)?;
        let g = &self.geomipmap;
        open_range("geomipmap.tau", g.tau, 0.0, 1e6)?;
        if ![17, 33, 65, 129].contains(&g.block) {
            return Err(format!(
                "geomipmap.block = {}: one of 17, 33, 65, 129",
                g.block
            ));
        }
        if let Some(k) = g.k {
            within("geomipmap.k", k as f64, 0.0, 6.0)?;
        }
        open_range(
            "reference.step",
            self.reference.step,
            0.0,
            1.0 + f64::EPSILON,
        )?;
        let i = &self.importance;
        positive("importance.max_per_m", i.max_per_m)?;
        open_range("importance.floor", i.floor, 0.0, 1.0 + f64::EPSILON)?;
        open_range(
            "importance.backface_floor",
            i.backface_floor,
            0.0,
            1.0 + f64::EPSILON,
        )?;
        if let Some(p) = &self.path {
            positive("path.speed_mps", Some(p.speed_mps))?;
            if p.keys.len() < 2 {
                return Err(format!(
                    "path.keys: {} given, a path needs at least 2",
                    p.keys.len()
                ));
            }
            for (k, key) in p.keys.iter().enumerate() {
                finite_all(&format!("path.keys[{k}].position"), &key.position)?;
                if let Some(l) = key.look_at {
                    finite_all(&format!("path.keys[{k}].look_at"), &l)?;
                }
            }
        }
        Ok(())
    }
}

/// Deserialises a scene's text; the error names the line and the key's full dotted path.
fn deserialize_text(text: &str) -> std::result::Result<Scene, String> {
    let de = toml::Deserializer::parse(text).map_err(|e| one_line(e.message(), e.span(), text))?;
    serde_path_to_error::deserialize(de).map_err(|e| {
        let key = e.path().to_string();
        let inner = e.into_inner();
        one_line(&keyed(&key, inner.message()), inner.span(), text)
    })
}

/// `key: message`, unless the key is the root or the message names it already.
fn keyed(key: &str, message: &str) -> String {
    if key.is_empty() || key == "." || message.contains(key) {
        message.to_string()
    } else {
        format!("{key}: {message}")
    }
}

/// The message on one line, after `line N: ` where the span says.
fn one_line(message: &str, span: Option<std::ops::Range<usize>>, text: &str) -> String {
    let line = span
        .map(|s| {
            format!(
                "line {}: ",
                text[..s.start.min(text.len())].matches('\n').count() + 1
            )
        })
        .unwrap_or_default();
    format!("{line}{}", message.replace('\n', " "))
}

fn override_key(o: &str) -> &str {
    o.split_once('=').map_or(o, |(k, _)| k).trim()
}

/// Whether the override `o` caused serde's error at `path`: the path is its key, or the error is
/// an unknown field of the table the override's key names.
fn blames(o: &str, path: &str, message: &str) -> bool {
    let key = override_key(o);
    if key == path {
        return true;
    }
    let (table, last) = key.rsplit_once('.').unwrap_or(("", key));
    let path = if path == "." { "" } else { path };
    table == path && message.contains(&format!("`{last}`"))
}

/// Sets `a.b.c=value` in a TOML table, creating the tables on the way.
fn apply_override(table: &mut toml::Table, o: &str) -> std::result::Result<(), String> {
    let (key, value) = o
        .split_once('=')
        .ok_or_else(|| "expected key.path=value".to_string())?;
    let value = toml::from_str::<toml::Table>(&format!("v = {value}"))
        .ok()
        .and_then(|mut t| t.remove("v"))
        .unwrap_or_else(|| toml::Value::String(value.trim().to_string()));
    let parts: Vec<&str> = key.trim().split('.').collect();
    let (last, path) = parts.split_last().ok_or_else(|| "empty key".to_string())?;
    let mut here = table;
    for p in path {
        here = here
            .entry(p.to_string())
            .or_insert_with(|| toml::Value::Table(toml::Table::new()))
            .as_table_mut()
            .ok_or_else(|| format!("`{p}` is not a table"))?;
    }
    here.insert(last.to_string(), value);
    Ok(())
}

fn finite_all(key: &str, v: &[f64]) -> std::result::Result<(), String> {
    match v.iter().find(|x| !x.is_finite()) {
        Some(x) => Err(format!("{key}: {x} is not a finite number")),
        None => Ok(()),
    }
}

fn within(key: &str, v: f64, lo: f64, hi: f64) -> std::result::Result<(), String> {
    if v.is_finite() && (lo..=hi).contains(&v) {
        Ok(())
    } else {
        Err(format!("{key} = {v}: must be in [{lo}, {hi}]"))
    }
}

fn open_range(key: &str, v: f64, lo: f64, hi: f64) -> std::result::Result<(), String> {
    if v.is_finite() && v > lo && v < hi {
        Ok(())
    } else {
        Err(format!("{key} = {v}: must be in ({lo}, {hi})"))
    }
}

fn positive(key: &str, v: Option<f64>) -> std::result::Result<(), String> {
    match v {
        Some(x) if !(x.is_finite() && x > 0.0) => {
            Err(format!("{key} = {x}: must be a positive number"))
        }
        _ => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const MIN: &str = "[sketch]\nsynthetic = \"gaussian\"\n[camera]\nposition = [0.0, 0.0, 900.0]\nlook_at = [100.0, 100.0, 0.0]\n";

    fn err(extra: &str) -> String {
        Scene::parse(&format!("{MIN}{extra}"), PathBuf::new())
            .unwrap_err()
            .to_string()
    }

    #[test]
    fn defaults_follow_design() {
        let s = Scene::parse(MIN, PathBuf::new()).unwrap();
        assert_eq!((s.warp.quad_px, s.warp.mesh, s.warp.size), (2.0, 512, 128));
        assert_eq!((s.detail.octaves, s.detail.gain), (None, 0.5));
        assert_eq!(s.render.mode, Mode::Warped);
    }

    #[test]
    fn unknown_keys_and_bad_values_name_the_key() {
        assert!(err("[warp]\nquadpx = 2\n").contains("quadpx"));
        assert!(err("[detail]\ngain = 2.0\n").contains("detail.gain"));
        assert!(err("[warp]\nquad_px = -1\n").contains("warp.quad_px"));
        assert!(err("[render]\nmode = \"fast\"\n").contains("fast"));
        assert!(err("[warp]\nmethod = \"magic\"\n").contains("magic"));
        let nan = Scene::parse(&MIN.replace("900.0", "nan"), PathBuf::new())
            .unwrap_err()
            .to_string();
        assert!(nan.contains("camera.position"), "{nan}");
        let same = MIN.replace("[100.0, 100.0, 0.0]", "[0.0, 0.0, 900.0]");
        assert!(
            Scene::parse(&same, PathBuf::new())
                .unwrap_err()
                .to_string()
                .contains("look_at")
        );
        let fov = format!("{MIN}fov_y_deg = 180.0\n");
        assert!(
            Scene::parse(&fov, PathBuf::new())
                .unwrap_err()
                .to_string()
                .contains("camera.fov_y_deg")
        );
        assert!(err("[path]\nkeys = [{ position = [0.0, 0.0, 1.0] }]\n").contains("path.keys"));
    }

    #[test]
    fn overrides_set_keys_and_are_checked() {
        let set = |o: &[&str]| {
            let o: Vec<String> = o.iter().map(|s| s.to_string()).collect();
            Scene::parse_with(MIN, PathBuf::new(), &o)
        };
        let s = set(&["detail.octaves=0", "warp.method=plain", "camera.width = 64"]).unwrap();
        let blamed = |o: &[&str]| set(o).unwrap_err().to_string();
        assert_eq!(
            blamed(&["detail.octaves=many"]),
            "--set detail.octaves=many: invalid type: string \"many\", expected u32"
        );
        assert_eq!(
            blamed(&["warp.mesh=64", "detail.gain=3"]),
            "--set detail.gain=3: must be in [0, 1]"
        );
        assert!(blamed(&["detail.octave=3"]).starts_with("--set detail.octave=3: unknown field"));
        // A fault of the file itself is still the file's, with its line, beside an override.
        let bad = format!("{MIN}[detail]\nseed = \"x\"\n");
        let e = Scene::parse_with(&bad, PathBuf::new(), &["warp.mesh=64".into()]).unwrap_err();
        assert!(
            matches!(&e, Fault::Text(r) if r.starts_with("line 7: detail.seed")),
            "{e}"
        );
        assert_eq!(
            (s.detail.octaves, s.warp.method, s.camera.width),
            (Some(0), WarpMethod::Plain, 64)
        );

        assert!(
            set(&["nonsense"])
                .unwrap_err()
                .to_string()
                .contains("key.path=value")
        );
    }
}
