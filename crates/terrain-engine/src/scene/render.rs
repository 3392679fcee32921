//! The keys of the drawing itself: `[stream]`, `[reference]`, `[light]`, `[render]` (the mode
//! and anti-aliasing) and `[planet]`.
//!
//! Rule: each section's defaults live in its `Default` impl, one place each.

use serde::{Deserialize, Serialize};

/// A sketch read from a tile pyramid (`terrain tiles`) streams through the tile cache (see
/// `tiles::cache`); these are its budgets.
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

/// `[reference]`: the ray-marched reference every mode is compared with.
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

/// The sun and the air (see [`Light`](crate::Light)).
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct LightSection {
    /// Degrees clockwise from north: 0 north, 90 east (150 unless the time is given).
    pub sun_azimuth_deg: Option<f64>,
    /// Degrees above the horizon; below 0 the sun has set (35 unless the time is given).
    pub sun_elevation_deg: Option<f64>,
    /// The sun from the time instead: the place's latitude, degrees, north positive, with
    /// `day_of_year` and `solar_time_h`.
    pub latitude_deg: Option<f64>,
    /// The day of the year, 1 to 366 (172: the June solstice), for the sun from the time.
    pub day_of_year: Option<u32>,
    /// The local solar time in hours, 0 to 24 (12 at solar noon), for the sun from the time.
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

crate::names::named_enum! {
    /// The level-of-detail scheme that draws the terrain (`render.mode`, `--mode`).
    pub enum Mode ("mode") {
        /// Geometry image warping (Dachsbacher & Stamminger 2004): the CPU stage's warped
        /// sketch map upsampled to a mesh on the GPU. The default.
        Warped = "warped",
        /// GeoMipMap (de Boer 2000): a baked grid of blocks, each at the level its projected
        /// error allows.
        Geomipmap = "geomipmap",
        /// Every vertex of the baked grid, every frame.
        Bruteforce = "bruteforce",
        /// The exact surface, ray-marched per pixel: slow, for comparisons.
        Reference = "reference",
        /// Spherical clipmaps (Clasen & Hege 2006): planet scenes only.
        Clipmaps = "clipmaps",
    }
}

/// Which scenes a mode draws.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Scenes {
    /// Planar sketches.
    Flat,
    /// Planets (a `[planet]` section or `sketch.synthetic = "planet"`).
    Planet,
    /// Both.
    Both,
}

/// A mode as everything around it knows it: the renderer, the tools, `compare`, `view` and the
/// charts read its row in [`MODES`] and its scheme, nothing else about it. The scheme behind it
/// is its folder under `lod/`, found by `lod::of` (an exhaustive match the compiler holds to the
/// enum).
#[derive(Clone, Copy, Debug)]
pub struct ModeRow {
    /// The mode (its key's value is [`Named::name`](crate::Named::name)).
    pub mode: Mode,
    /// Its name as the papers write it, for legends, summaries and the window's figures.
    pub display: &'static str,
    /// Whether the terrain pass draws it as a mesh (the G-buffer, multisampling and the sun map
    /// apply).
    pub mesh: bool,
    /// Whether it bakes the whole sketch into a grid, which a tile pyramid, streamed in tiles,
    /// cannot feed.
    pub bakes_whole_sketch: bool,
    /// The scenes it draws.
    pub scenes: Scenes,
    /// Whether `compare` sweeps it by default on the scenes it draws (the reference is what
    /// every mode is measured against).
    pub compared: bool,
    /// Its colour in every chart, RGB.
    pub colour: [u8; 3],
    /// The key that switches `view` to it, if the window switches to it.
    pub key: Option<char>,
    /// The scene keys `compare`'s rows of it set, as its rows' labels name them; its module
    /// gives the values ([`Mode::default_sweep`]).
    pub sweep: &'static [(&'static str, &'static str)],
    /// Those of the swept keys a built renderer takes frame by frame
    /// ([`Renderer::retune`](crate::Renderer::retune)): `compare`'s settings that differ in them
    /// alone share a renderer.
    pub retuned: &'static [&'static str],
}

/// Every mode, one row each.
pub const MODES: [ModeRow; 5] = [
    ModeRow {
        mode: Mode::Warped,
        display: "warped",
        mesh: true,
        bakes_whole_sketch: false,
        scenes: Scenes::Flat,
        compared: true,
        colour: [230, 120, 20],
        key: Some('1'),
        sweep: &[
            ("warp.quad_px", "quad_px"),
            ("warp.mesh", "mesh"),
            ("warp.budget", "fixed"),
        ],
        retuned: &[],
    },
    ModeRow {
        mode: Mode::Geomipmap,
        display: "GeoMipMap",
        mesh: true,
        bakes_whole_sketch: false,
        scenes: Scenes::Flat,
        compared: true,
        colour: [40, 100, 200],
        key: Some('2'),
        sweep: &[("geomipmap.tau", "tau"), ("geomipmap.block", "block")],
        retuned: &["geomipmap.tau"],
    },
    ModeRow {
        mode: Mode::Bruteforce,
        display: "brute force",
        mesh: true,
        bakes_whole_sketch: true,
        scenes: Scenes::Flat,
        compared: true,
        colour: [40, 160, 70],
        key: Some('3'),
        sweep: &[("geomipmap.k", "K")],
        retuned: &[],
    },
    ModeRow {
        mode: Mode::Reference,
        display: "reference",
        mesh: false,
        bakes_whole_sketch: false,
        scenes: Scenes::Both,
        compared: false,
        colour: [120, 120, 120],
        key: None,
        sweep: &[],
        retuned: &[],
    },
    ModeRow {
        mode: Mode::Clipmaps,
        display: "spherical clipmaps",
        mesh: false,
        bakes_whole_sketch: false,
        scenes: Scenes::Planet,
        compared: true,
        colour: [150, 60, 170],
        key: None,
        sweep: &[
            ("planet.phi_steps", "phi_steps"),
            ("planet.rings_per_level", "rings"),
        ],
        retuned: &[],
    },
];

impl Mode {
    /// This mode's row in [`MODES`].
    pub fn row(self) -> &'static ModeRow {
        // Every variant has its row: the table's test holds them in the enum's order.
        &MODES[self as usize]
    }

    /// Whether the mode draws `planet` scenes (true) or planar sketches (false).
    pub fn draws(self, planet: bool) -> bool {
        match self.row().scenes {
            Scenes::Both => true,
            Scenes::Planet => planet,
            Scenes::Flat => !planet,
        }
    }

    /// The modes `compare` sweeps and `view` flies (every one but the ray-marched reference,
    /// which they measure against).
    pub fn compared() -> impl Iterator<Item = Mode> {
        MODES.iter().filter(|r| r.compared).map(|r| r.mode)
    }

    /// [`ModeRow::bakes_whole_sketch`].
    pub fn bakes_whole_sketch(self) -> bool {
        self.row().bakes_whole_sketch
    }

    /// [`ModeRow::mesh`].
    pub fn is_mesh(self) -> bool {
        self.row().mesh
    }

    /// [`ModeRow::display`].
    pub fn display(self) -> &'static str {
        self.row().display
    }
}

#[cfg(test)]
mod modes_tests {
    use super::*;

    /// The table holds one row per mode, in the enum's order, which [`Mode::row`] indexes by.
    #[test]
    fn every_mode_has_its_row_in_order() {
        assert_eq!(MODES.len(), Mode::ALL.len());
        for (i, m) in Mode::ALL.iter().enumerate() {
            assert_eq!(MODES[i].mode, *m);
            assert_eq!(*m as usize, i);
            assert_eq!(m.row().mode, *m);
        }
    }
}

/// `[render]`: the level-of-detail mode and the picture's options.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct RenderSection {
    /// The scheme that draws the terrain (default `warped`; `--mode` overrides).
    pub mode: Mode,
    /// The mesh modes shade with the terrain function's normal at each pixel, as the reference
    /// does; `false`: the mesh's normals plus bump detail (`detail.bump`).
    pub pixel_normals: bool,
    /// The sketch shadows itself from the sun; `false` compiles the shadow ray out.
    pub shadows: bool,
    /// With `shadows`, the procedural detail shadows itself too.
    pub detail_shadows: bool,
    /// With `shadows`, the mesh modes read the sketch's shadow from its sun clearance map, made
    /// once per sun direction (`gpu::sun_map`); `false`: the ray marched at every pixel.
    pub sun_map: bool,
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
            sun_map: true,
            msaa: Msaa::Auto,
            deferred: true,
        }
    }
}

crate::names::named_enum! {
    /// Anti-aliasing (`render.msaa`): 4 samples per pixel, multisampled in the mesh modes (where
    /// the adapter's targets allow it) and four rays per pixel in the reference.
    pub enum Msaa ("msaa") {
        /// 4× on a hardware GPU; off on a software rasterizer, where it costs several times
        /// the terrain pass (docs/decisions.md, “Multisampling”).
        Auto = "auto",
        /// One sample per pixel.
        Off = "off",
        /// 4 samples per pixel, refused on a planet.
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
    /// The planet's radius at height 0, metres, 1000 to 10⁹ (default the Earth's mean, 6371 km).
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
