//! The scene file (TOML): the keys of `docs/design.md` (Scene and jobs
//! files) and this project's additions, read strictly.
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
mod check;
mod parse;
pub mod place;
mod starter;

pub use build::{
    camera_of, detail_for, detail_of, ground_under, light_of, load_atlas, scene_load_options,
    stream_config,
};
pub use parse::{Fault, is_sketch_path, scene_text};
pub use starter::starter;

use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    pub sketch: SketchSection,
    /// Without it, the default view of the whole sketch (`scene::place`).
    #[serde(default)]
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
    #[serde(default)]
    pub light: LightSection,
    #[serde(default)]
    pub stream: StreamSection,
    pub path: Option<PathSection>,
    /// A planet: the sketch is global and wraps a sphere (`sketch.synthetic = "planet"` implies
    /// one with the defaults).
    pub planet: Option<PlanetSection>,
    /// The folder relative paths resolve against; not a key.
    #[serde(skip)]
    pub base_dir: PathBuf,
    /// The file the scene was read from (a scene file, or a sketch standing for a scene), for
    /// messages about it; not a key.
    #[serde(skip)]
    pub source: Option<PathBuf>,
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
    /// The world beyond the sketch's edges.
    #[serde(default = "default_outside")]
    pub outside: Outside,
    /// Ground below this height lies under flat water.
    #[serde(default)]
    pub water_level_m: f64,
}

fn default_outside() -> Outside {
    Outside::Plain
}

crate::named_enum! {
    /// What lies beyond the sketch (`sketch.outside`): drawn by the sky pass and the reference
    /// alike, and never counted as terrain by the image metrics.
    pub enum Outside ("outside") {
        /// Nothing: the sketch floats in the sky.
        Void = "void",
        /// A plain at the mean height of the sketch's edges, to the horizon.
        Plain = "plain",
        /// The sea, at 0 m, to the horizon.
        Ocean = "ocean",
    }
}

/// Where the camera stands and looks. A planar scene places it by `position` (world metres), by
/// `map_xy` (the sketch file's own coordinates) or by `lat_deg` and `lon_deg`, each of the last
/// two with `altitude_m`, and aims it by `look_at` or by `heading_deg` and `pitch_deg`; without a
/// place it frames the whole sketch (`scene::place`). A planet's camera takes `lat_deg`,
/// `lon_deg`, `altitude_m`, `heading_deg` and `pitch_deg`.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct CameraSection {
    /// The eye in world metres (z the height above sea level, not above the ground).
    pub position: Option<[f64; 3]>,
    /// The point looked at, world metres.
    pub look_at: Option<[f64; 3]>,
    /// The eye's x and y in the sketch file's own coordinate system (what `terrain info` prints
    /// as its georeference), with `altitude_m`.
    pub map_xy: Option<[f64; 2]>,
    /// The eye's (a planet's: its nadir's) latitude and longitude, degrees; on a projected sketch
    /// WGS 84, converted through the file's coordinate system.
    pub lat_deg: Option<f64>,
    pub lon_deg: Option<f64>,
    /// Height above the ground or water under the eye, metres.
    pub altitude_m: Option<f64>,
    /// View direction: 0 north, 90 east (0 unless given; the default view: the side it looks from).
    pub heading_deg: Option<f64>,
    /// View direction: 0 level, −90 straight down (0 unless given; the default view: −35).
    pub pitch_deg: Option<f64>,
    #[serde(default = "default_fov")]
    pub fov_y_deg: f64,
    #[serde(default = "default_size")]
    pub width: u32,
    #[serde(default = "default_size")]
    pub height: u32,
    /// Far distance in metres; by default the farthest corner of the sketch.
    pub far_m: Option<f64>,
}
impl Default for CameraSection {
    fn default() -> Self {
        CameraSection {
            position: None,
            look_at: None,
            map_xy: None,
            lat_deg: None,
            lon_deg: None,
            altitude_m: None,
            heading_deg: None,
            pitch_deg: None,
            fov_y_deg: default_fov(),
            width: default_size(),
            height: default_size(),
            far_m: None,
        }
    }
}
impl CameraSection {
    /// Places a planar scene's camera at `eye` looking at `target`, in place of whatever keys
    /// placed it before.
    pub fn aim(&mut self, eye: glam::DVec3, target: glam::DVec3) {
        *self = CameraSection {
            position: Some(eye.to_array()),
            look_at: Some(target.to_array()),
            ..CameraSection {
                fov_y_deg: self.fov_y_deg,
                width: self.width,
                height: self.height,
                far_m: self.far_m,
                ..CameraSection::default()
            }
        };
    }
    /// `position`, for a camera placed by it (the origin otherwise; `scene::place::pose` places
    /// every camera).
    pub fn eye(&self) -> glam::DVec3 {
        glam::DVec3::from(self.position.unwrap_or_default())
    }
    /// `look_at`, for a camera aimed by it (the origin otherwise).
    pub fn target(&self) -> glam::DVec3 {
        glam::DVec3::from(self.look_at.unwrap_or_default())
    }
    /// `heading_deg`, 0 (north) unless given.
    pub fn heading(&self) -> f64 {
        self.heading_deg.unwrap_or(0.0)
    }
    /// `pitch_deg`, 0 (level) unless given.
    pub fn pitch(&self) -> f64 {
        self.pitch_deg.unwrap_or(0.0)
    }
    /// The keys that place and aim it.
    pub(crate) fn placement(&self) -> Placement {
        Placement {
            position: self.position,
            look_at: self.look_at,
            map_xy: self.map_xy,
            lat_deg: self.lat_deg,
            lon_deg: self.lon_deg,
            altitude_m: self.altitude_m,
            heading_deg: self.heading_deg,
            pitch_deg: self.pitch_deg,
        }
    }
    /// Whether the keys place the camera (a planar scene without a place frames the sketch).
    pub fn is_placed(&self) -> bool {
        self.position.is_some()
            || self.map_xy.is_some()
            || self.lat_deg.is_some()
            || self.lon_deg.is_some()
    }
}

/// The keys a planar camera and a path key share to place and aim it, checked by
/// `Scene::check` and resolved by `scene::place`.
pub(crate) struct Placement {
    pub position: Option<[f64; 3]>,
    pub look_at: Option<[f64; 3]>,
    pub map_xy: Option<[f64; 2]>,
    pub lat_deg: Option<f64>,
    pub lon_deg: Option<f64>,
    pub altitude_m: Option<f64>,
    pub heading_deg: Option<f64>,
    pub pitch_deg: Option<f64>,
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

/// `detail.bias` when the scene does not set it: −1 in the warped mode and the reference (which
/// draws every octave whatever the bias) on either storage, so a sketch and the tile pyramid
/// converted from it draw one picture, the mesh carrying as geometry the octave whose wavelength
/// is its vertex spacing (the split octave one above `log2(d_atlas / d_max)`); 0.5 on a planet.
/// The baselines are the exception: GeoMipMap over a tile pyramid draws the sketch's own nodes
/// (`geomipmap.k` 0), whose δ, measured on the sketch alone, would not see an octave a negative
/// bias puts into it, so it takes 0 there, and −1 with its finer bake in memory.
///
/// Why −1: sampling an octave at its own wavelength aliases between vertices, but the vertices
/// are then exact, and that outweighs it; with the geometric-error term a bias of 0 (the Nyquist
/// octave) finds the ground flatter and asks for too few triangles (docs/decisions.md, “Detail
/// bias”).
///
/// Rejected: one GeoMipMap default for both storages (k 0, bias 0 in memory too): a sketch and
/// its pyramid would then draw one picture in GeoMipMap as well, but the baseline every
/// comparison measures the warped mode against grows weaker in memory (docs/decisions.md,
/// “Detail bias”). For planets, −1: the clipmap rings slide with the nadir every frame, and
/// −1 swims more for little PSNR.
pub fn default_bias(scene: &Scene, atlas: &crate::sketch::Atlas, mode: Mode) -> f64 {
    if scene.planet().is_some() {
        0.5
    } else if mode == Mode::Geomipmap && atlas.pyramid.is_some() {
        0.0
    } else {
        -1.0
    }
}

#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct DetailSection {
    /// Noise octaves; by default those whose wavelength is at least [`FINEST_WAVELENGTH_M`].
    pub octaves: Option<u32>,
    /// Octave 1's amplitude; by default the sketch's own finest relief carried one octave on.
    pub amplitude_m: Option<f64>,
    pub gain: f64,
    pub seed: u32,
    /// Octaves subtracted from the split octave: the paper's "more conservative estimate". By
    /// default [`default_bias`]'s.
    pub bias: Option<f64>,
    /// Per-pixel bump detail past the split octave; off leaves its code out of the shader.
    pub bump: bool,
    /// Each bump octave weighted by a fitted power of its expected correlation with the surface
    /// the ray meets (`shaders/shared/fade.wgsl`); off draws every bump octave whole.
    pub bump_fade: bool,
}
impl Default for DetailSection {
    fn default() -> Self {
        DetailSection {
            octaves: None,
            amplitude_m: None,
            gain: 0.5,
            seed: 7,
            bias: None,
            bump: true,
            bump_fade: true,
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

crate::named_enum! {
    /// Which diagonal each cell of the warped mesh is split along; see `gpu::mesh_split`.
    pub enum Triangulation ("triangulation") {
        /// Every cell along (s, t)–(s+1, t+1).
        Fixed = "fixed",
        /// Each convex cell along the diagonal whose midpoint lies nearer the surface.
        Adaptive = "adaptive",
    }
}

#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct WarpSection {
    pub quad_px: f64,
    /// The largest mesh side; with `budget`, a frame draws what its importance asks for, up to it.
    pub mesh: u32,
    /// The mesh follows the demanded density (`stage::budget`); `false`: always `mesh`².
    pub budget: bool,
    /// The smallest mesh side a budgeted frame draws.
    pub min_mesh: u32,
    /// Frames keep the last warp while their demand stays within `hold_drift` of it (`stage::hold`).
    pub hold: bool,
    /// Octaves the demand may drift, on all but 5 % of the texels in view, before a held warp is redone.
    pub hold_drift: f64,
    /// Sketch map and warp size (128 in the paper).
    pub size: u32,
    pub method: WarpMethod,
    /// Largest change of log2(importance) between neighbouring texels; 0 turns the limit off.
    pub max_log2_step: f64,
    /// A view whose heading lies within 15° of a diagonal turns the sketch map's region by
    /// 45° (`stage::sketch_map`); false: the region's axes are always x and y.
    pub diagonal: bool,
    /// How each cell of the mesh is split into two triangles.
    pub triangulation: Triangulation,
}
impl Default for WarpSection {
    fn default() -> Self {
        WarpSection {
            quad_px: 2.0,
            mesh: 512,
            budget: true,
            min_mesh: 32,
            hold: true,
            hold_drift: 0.5,
            size: 128,
            method: WarpMethod::Guarded,
            max_log2_step: 0.0,
            diagonal: true,
            triangulation: Triangulation::Adaptive,
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
    /// The geometric-error term: flat ground asks for fewer samples than I_v, down to
    /// `error_flat_share` of it; curved ground keeps I_v.
    pub error: bool,
    /// The projected error the term aims at, pixels.
    pub error_px: f64,
    /// The least share of I_v the error term leaves on flat ground.
    pub error_flat_share: f64,
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
            error: true,
            error_px: 0.5,
            error_flat_share: 0.125,
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
    /// Over a tile pyramid: the most blocks a frame draws (the GPU holds 144 bytes for each,
    /// its record and 16 indices); past that the farthest are left out.
    pub max_blocks: u32,
}
impl Default for GeoMipMapSection {
    fn default() -> Self {
        GeoMipMapSection {
            tau: 1.0,
            k: None,
            exact: false,
            morph: true,
            block: 33,
            max_blocks: 524_288,
        }
    }
}

/// A sketch read from a tile pyramid (`terrain tiles`) streams through the tile cache (see
/// [`crate::tiles::cache`]); these are its budgets.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct StreamSection {
    /// GPU memory for the tile pages and the page table, MiB (less where the adapter's largest
    /// storage binding is smaller).
    pub gpu_mb: f64,
    /// Main memory for the coarse levels the CPU stage reads, MiB.
    pub cpu_mb: f64,
    /// Tiles placed on the GPU per frame at most.
    pub loads_per_frame: u32,
    /// Frames a newly loaded tile takes to blend in over the coarser level that stood in.
    pub fade_frames: u32,
    /// Threads reading and decoding tiles.
    pub threads: u32,
}
impl Default for StreamSection {
    fn default() -> Self {
        StreamSection {
            gpu_mb: 128.0,
            cpu_mb: 256.0,
            loads_per_frame: 32,
            fade_frames: 8,
            threads: 2,
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

/// The sun and the air (see [`crate::light`]).
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct LightSection {
    /// Degrees clockwise from north: 0 north, 90 east (150 unless the time is given).
    pub sun_azimuth_deg: Option<f64>,
    /// Degrees above the horizon; below 0 the sun has set (35 unless the time is given).
    pub sun_elevation_deg: Option<f64>,
    /// The sun from the time instead: the place's latitude, the day of the year (1–366) and
    /// the local solar time in hours (12 at solar noon).
    pub latitude_deg: Option<f64>,
    pub day_of_year: Option<u32>,
    pub solar_time_h: Option<f64>,
    /// Meteorological visibility at sea level, km: the haze's density.
    pub haze_visibility_km: f64,
    /// Scale height of the haze, metres: how fast it thins with height.
    pub haze_height_m: f64,
    /// Exposure compensation in stops: light is scaled by 2^exposure_ev before the tone map.
    pub exposure_ev: f64,
}
impl Default for LightSection {
    fn default() -> Self {
        LightSection {
            sun_azimuth_deg: None,
            sun_elevation_deg: None,
            latitude_deg: None,
            day_of_year: None,
            solar_time_h: None,
            haze_visibility_km: 100.0,
            haze_height_m: 1200.0,
            exposure_ev: 0.0,
        }
    }
}

impl LightSection {
    /// The sun's azimuth and elevation, degrees: from the time where it is given (checked whole
    /// by `Scene::check`), else the keys, else 150° and 35°.
    pub fn sun_deg(&self) -> (f64, f64) {
        match (self.latitude_deg, self.day_of_year, self.solar_time_h) {
            (Some(lat), Some(day), Some(time)) => crate::light::sun_position(lat, day, time),
            _ => (
                self.sun_azimuth_deg.unwrap_or(150.0),
                self.sun_elevation_deg.unwrap_or(35.0),
            ),
        }
    }
}

crate::named_enum! {
    /// The level-of-detail scheme that draws the terrain (`render.mode`, `--mode`).
    pub enum Mode ("mode") {
        Warped = "warped",
        Geomipmap = "geomipmap",
        Bruteforce = "bruteforce",
        Reference = "reference",
        /// Spherical clipmaps (Clasen & Hege 2006): planet scenes only.
        Clipmaps = "clipmaps",
    }
}

impl Mode {
    /// The modes that draw a mesh (every one but the ray-marched reference).
    pub const MESHES: [Mode; 4] = [
        Mode::Warped,
        Mode::Geomipmap,
        Mode::Bruteforce,
        Mode::Clipmaps,
    ];

    /// Brute force: it draws every vertex of a grid baked whole, so a streamed sketch (a tile
    /// pyramid) cannot feed it. (GeoMipMap over a pyramid reads its blocks' vertices through the
    /// tile cache instead.)
    pub fn bakes_whole_sketch(self) -> bool {
        self == Mode::Bruteforce
    }

    /// The modes that draw the sketch as a mesh in the terrain pass (warped, GeoMipMap, brute
    /// force).
    pub fn is_mesh(self) -> bool {
        matches!(self, Mode::Warped | Mode::Geomipmap | Mode::Bruteforce)
    }
}

#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct RenderSection {
    pub mode: Mode,
    /// The mesh modes shade with the terrain function's normal at each pixel, as the reference
    /// does; `false`: the mesh's normals plus bump detail (`detail.bump`).
    pub pixel_normals: bool,
    /// The sketch shadows itself from the sun; `false` compiles the shadow ray out.
    pub shadows: bool,
    /// With `shadows`, the procedural detail shadows itself too.
    pub detail_shadows: bool,
    /// Anti-aliasing: the mesh modes multisampled and the reference supersampled alike.
    pub msaa: Msaa,
    /// Single-sampled frames of the mesh modes shade each pixel once, from a G-buffer the mesh
    /// writes (`gpu::terrain`'s `Deferred`); `false`: forward, once per triangle touching it.
    pub deferred: bool,
}
impl Default for RenderSection {
    fn default() -> Self {
        RenderSection {
            mode: Mode::Warped,
            pixel_normals: false,
            shadows: true,
            detail_shadows: false,
            msaa: Msaa::Auto,
            deferred: true,
        }
    }
}

crate::named_enum! {
    /// Anti-aliasing (`render.msaa`): 4 samples per pixel, multisampled in the mesh modes (where
    /// the adapter's targets allow it) and four rays per pixel in the reference.
    pub enum Msaa ("msaa") {
        /// 4× on a hardware GPU; off on a software rasterizer, where it costs several times
        /// the terrain pass (docs/decisions.md, “Multisampling”).
        Auto = "auto",
        Off = "off",
        X4 = "4x",
    }
}

/// A planet and its spherical clipmaps (Clasen & Hege, *Terrain Rendering using Spherical
/// Clipmaps*, 2006).
///
/// The defaults split the paper's triangles (512 × 20) the other way, 256 bearings × 40 rings a
/// level: a ring's vertices a level apart matter more than its bearings (docs/decisions.md,
/// “Clipmap rings”).
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct PlanetSection {
    pub radius_m: f64,
    /// Bearing steps of every clipmap ring (the paper's n).
    pub phi_steps: u32,
    /// Rings per clipmap level (the paper's m).
    pub rings_per_level: u32,
}
impl Default for PlanetSection {
    fn default() -> Self {
        PlanetSection {
            radius_m: crate::planet::EARTH_RADIUS_M,
            phi_steps: 256,
            rings_per_level: 40,
        }
    }
}

impl Scene {
    /// The planet, when the scene is one.
    pub fn planet(&self) -> Option<PlanetSection> {
        match &self.planet {
            Some(p) => Some(p.clone()),
            None if self.sketch.synthetic.as_deref() == Some("planet") => {
                Some(PlanetSection::default())
            }
            None => None,
        }
    }
}

#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct PathSection {
    #[serde(default = "default_speed")]
    pub speed_mps: f64,
    /// A planet's flight: how long it takes, seconds (each key to the next in equal time).
    pub duration_s: Option<f64>,
    pub keys: Vec<PathKey>,
}
fn default_speed() -> f64 {
    150.0
}

#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct PathKey {
    /// A point of a planar path (required there), world metres.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub position: Option<[f64; 3]>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub look_at: Option<[f64; 3]>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub map_xy: Option<[f64; 2]>,
    /// Where the camera stands and looks, as the camera's keys of the same names.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lat_deg: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lon_deg: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub altitude_m: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub heading_deg: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pitch_deg: Option<f64>,
}

impl PathKey {
    /// The keys that place and aim it.
    pub(crate) fn placement(&self) -> Placement {
        Placement {
            position: self.position,
            look_at: self.look_at,
            map_xy: self.map_xy,
            lat_deg: self.lat_deg,
            lon_deg: self.lon_deg,
            altitude_m: self.altitude_m,
            heading_deg: self.heading_deg,
            pitch_deg: self.pitch_deg,
        }
    }

    /// A planar key at `position`.
    pub fn at(position: [f64; 3], look_at: Option<[f64; 3]>) -> PathKey {
        PathKey {
            position: Some(position),
            look_at,
            map_xy: None,
            lat_deg: None,
            lon_deg: None,
            altitude_m: None,
            heading_deg: None,
            pitch_deg: None,
        }
    }
}

impl Scene {
    pub fn resolve(&self, p: &Path) -> PathBuf {
        self.base_dir.join(p)
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
        assert!(err("[render]\nmsaa = \"8x\"\n").contains("8x"));
        assert!(err("[light]\nexposure_ev = 40.0\n").contains("light.exposure_ev"));
        let flooded = MIN.replace("gaussian\"\n", "gaussian\"\nwater_level_m = inf\n");
        let e = Scene::parse(&flooded, PathBuf::new())
            .unwrap_err()
            .to_string();
        assert!(e.contains("sketch.water_level_m"), "{e}");
    }

    #[test]
    fn the_sun_comes_from_its_position_or_from_the_time_not_both() {
        let light = |extra: &str| Scene::parse(&format!("{MIN}[light]\n{extra}"), PathBuf::new());
        let by_default = light("").unwrap().light.sun_deg();
        assert_eq!(by_default, (150.0, 35.0));
        let noon = light("latitude_deg = 45.0\nday_of_year = 172\nsolar_time_h = 12.0\n")
            .unwrap()
            .light
            .sun_deg();
        assert!(
            (noon.0 - 180.0).abs() < 1e-9 && (noon.1 - 68.44).abs() < 0.05,
            "{noon:?}"
        );
        let part = light("latitude_deg = 45.0\nsolar_time_h = 12.0\n").unwrap_err();
        assert!(part.to_string().contains("day_of_year"), "{part}");
        let both = light(
            "sun_elevation_deg = 5.0\nlatitude_deg = 45.0\nday_of_year = 1\nsolar_time_h = 9.0\n",
        )
        .unwrap_err();
        assert!(both.to_string().contains("not both"), "{both}");
        let late =
            light("latitude_deg = 45.0\nday_of_year = 1\nsolar_time_h = 25.0\n").unwrap_err();
        assert!(late.to_string().contains("light.solar_time_h"), "{late}");
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
        // A share may be whole (1 passes) but not more, and its range reads as one.
        assert!(set(&["importance.floor=1"]).is_ok());
        assert_eq!(
            blamed(&["importance.floor=1.01"]),
            "--set importance.floor=1.01: must be in (0, 1]"
        );
        assert!(blamed(&["importance.floor=0"]).ends_with("must be in (0, 1]"));
        assert!(blamed(&["importance.floor=nan"]).ends_with("must be in (0, 1]"));
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
