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
mod camera;
mod check;
mod detail;
mod parse;
pub(crate) mod place;
mod random;
mod render;
mod starter;
mod surface;

pub(crate) use build::stream_config;
pub use build::{
    camera_of, detail_for, detail_of, ground_under, light_of, load_atlas, load_atlas_from,
    scene_load_options, warnings,
};
pub use parse::{Fault, is_sketch_path, scene_text};
pub use place::{
    CameraReport, DEFAULT_PATH_S, camera_report, default_path, map_of_world, off_map_warning,
    off_map_warnings, pose, report, resolve_key, world_of_map,
};
pub use starter::starter;
pub use surface::{Style, SurfaceSection};

pub(crate) use camera::Placement;
pub use camera::{AIM_KEYS, CameraSection, PLACE_KEYS, PathKey, PathSection, lay_camera};
pub use detail::{
    DetailSection, GeoMipMapSection, ImportanceSection, Triangulation, WarpMethod, WarpSection,
    default_bias,
};
pub(crate) use detail::{FINEST_WAVELENGTH_M, MAX_OCTAVES};
pub use random::{RANDOM_HEIGHT_M, RANDOM_PLANET_ALTITUDE_M, random_camera};
pub use render::{
    LightSection, MODES, Mode, ModeRow, Msaa, PlanetSection, ReferenceSection, RenderSection,
    Scenes, StreamSection,
};

use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// A scene file's contents: which sketch to draw, from where and how, one section per table of
/// `docs/scene.md`. Read with [`Scene::load`] (a file) or [`Scene::parse`] (text), which check
/// every key's range; an absent section takes its defaults.
///
/// ```
/// use terrain::{Mode, Scene};
///
/// let text = r#"
///     [sketch]
///     synthetic = "hills"
///     [camera]
///     width = 320
///     height = 200
///     [render]
///     mode = "geomipmap"
/// "#;
/// let scene = Scene::parse(text, ".".into()).unwrap();
/// assert_eq!(scene.render.mode, Mode::Geomipmap);
/// assert_eq!((scene.camera.width, scene.camera.height), (320, 200));
/// assert_eq!(scene.detail.gain, 0.5, "an absent key takes its default");
///
/// // A key out of range is refused, naming it.
/// let fault = Scene::parse("[sketch]\nsynthetic = \"hills\"\n[detail]\ngain = 3.0\n", ".".into());
/// assert!(fault.unwrap_err().to_string().contains("detail.gain"));
/// ```
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// `[sketch]`: the height map, or a synthetic one, and what lies beyond it.
    pub sketch: SketchSection,
    /// Without it, the default view of the whole sketch (`scene::place`).
    #[serde(default)]
    pub camera: CameraSection,
    /// `[detail]`: the procedural octaves added to the sketch.
    #[serde(default)]
    pub detail: DetailSection,
    /// `[warp]`: the warped mode's sketch map, warp and mesh.
    #[serde(default)]
    pub warp: WarpSection,
    /// `[importance]`: how densely the warped mesh samples the ground where.
    #[serde(default)]
    pub importance: ImportanceSection,
    /// `[render]`: the level-of-detail mode and the picture's options.
    #[serde(default)]
    pub render: RenderSection,
    /// `[geomipmap]`: de Boer's GeoMipMap baseline.
    #[serde(default)]
    pub geomipmap: GeoMipMapSection,
    /// `[reference]`: the ray-marched reference.
    #[serde(default)]
    pub reference: ReferenceSection,
    /// `[light]`: the sun, the air and the exposure.
    #[serde(default)]
    pub light: LightSection,
    /// `[stream]`: the tile cache of a sketch streamed from a tile pyramid.
    #[serde(default)]
    pub stream: StreamSection,
    /// `[surface]`: the ground's colour: natural surface types, a colour ramp or imagery.
    #[serde(default)]
    pub surface: SurfaceSection,
    /// `[path]`: the camera path `fly` and `compare` follow; without it, a default one.
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

/// `[sketch]`: the height map to draw. Exactly one of `path` and `synthetic` is given.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SketchSection {
    /// The height map file, a glob of tiles or a tile pyramid's folder, relative to the scene
    /// file (`docs/formats.md` lists the formats).
    pub path: Option<PathBuf>,
    /// A generated sketch of 30 m cells instead of a file: `gaussian`, `hills`, `ridges`,
    /// `cliff`, `flat`, `spike` or `planet`.
    pub synthetic: Option<String>,
    /// Cell size in metres, overriding the file's (> 0; PNG files carry none: 1 m).
    pub spacing_m: Option<f64>,
    /// World position of the sketch's south-west node, metres (default: the origin).
    pub origin_m: Option<[f64; 2]>,
    /// Multiplies every height (> 0; default 1).
    pub height_scale: Option<f64>,
    /// Nodes per side of a synthetic sketch, 2 to 4097 (default 257); a planet's width, 8 to
    /// 16384 (default 1024, its height half that).
    pub size: Option<usize>,
    /// For 8/16-bit PNG sketches: the heights that pixel value 0 and the maximum stand for.
    pub height_range_m: Option<[f64; 2]>,
    /// The world beyond the sketch's edges; without it, the sea where most of the sketch's edge
    /// nodes lie below `water_level_m`, else the plain ([`Scene::outside`]).
    pub outside: Option<Outside>,
    /// Ground below this height lies under flat water.
    #[serde(default)]
    pub water_level_m: f64,
}

impl Scene {
    /// What lies beyond `atlas`, the scene's sketch: `sketch.outside`, or where the scene does not
    /// say, what the sketch's edge continues into: the sea where most of its nodes lie under
    /// water, else the plain.
    pub fn outside(&self, atlas: &crate::sketch::Atlas) -> Outside {
        self.sketch
            .outside
            .unwrap_or(if atlas.edge_under_water() > 0.5 {
                Outside::Ocean
            } else {
                Outside::Plain
            })
    }
}

crate::names::named_enum! {
    /// What lies beyond the sketch (`sketch.outside`): drawn by the sky pass and the reference
    /// alike, and never counted as terrain by the image metrics.
    pub enum Outside ("outside") {
        /// Nothing: the sketch floats in the sky.
        Void = "void",
        /// A plain at the mean height of the sketch's edges, to the horizon, joined to the edge
        /// by a margin (no step at the border).
        Plain = "plain",
        /// The sea at `water_level_m`, to the horizon, the edge running down into it through the
        /// margin.
        Ocean = "ocean",
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

impl Scene {
    /// `p`, a path the scene names, relative to the scene file's folder (`base_dir`).
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
