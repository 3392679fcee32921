//! The level-of-detail keys: `[detail]` (the procedural octaves), `[warp]`, `[importance]` and
//! `[geomipmap]`.
//!
//! Rule: a key whose default follows the sketch or the mode is an `Option`, resolved in
//! `scene::detail_of` and [`default_bias`], never here.

use super::{Mode, Scene};
use serde::{Deserialize, Serialize};
use std::path::PathBuf;

/// The most octaves a scene may ask for.
pub(crate) const MAX_OCTAVES: u32 = 24;
/// The finest noise wavelength the default octave count reaches, metres: below a decimetre
/// no camera this renderer places (at least a metre above the ground) resolves a change.
pub(crate) const FINEST_WAVELENGTH_M: f64 = 0.1;

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

/// `[detail]`: the procedural octaves added to the sketch (`docs/scene.md`, `[detail]`).
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct DetailSection {
    /// Noise octaves, 0 to 24; by default those whose wavelength is at least 0.1 m.
    pub octaves: Option<u32>,
    /// Octave 1's amplitude; by default the sketch's own finest relief carried one octave on.
    pub amplitude_m: Option<f64>,
    /// Amplitude ratio of each octave to the one before, 0 to 1 (default 0.5).
    pub gain: f64,
    /// The noise's seed (default 7).
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

crate::names::named_enum! {
    /// How the warp keeps cells from folding; see `warp.rs`.
    pub enum WarpMethod ("warp method") {
        /// The paper's single row pass then column pass, nothing more.
        Plain = "plain",
        /// Row then column pass, with the column warps relaxed toward their common mean where
        /// cells fold.
        Guarded = "guarded",
    }
}

crate::names::named_enum! {
    /// Which diagonal each cell of the warped mesh is split along; see `lod::warped::mesh_split`.
    pub enum Triangulation ("triangulation") {
        /// Every cell along (s, t)–(s+1, t+1).
        Fixed = "fixed",
        /// Each convex cell along the diagonal whose midpoint lies nearer the surface.
        Adaptive = "adaptive",
    }
}

/// `[warp]`: the warped mode's sketch map, warp and mesh (`docs/scene.md`, `[warp]`).
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct WarpSection {
    /// Target on-screen size of a mesh quad, pixels: C in the importance `f_px / (C · d)`
    /// (default 2).
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
    /// How the warp keeps cells from folding (default `guarded`).
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

/// `[importance]`: the terms of the importance, samples per metre, that the warp spaces the
/// mesh by (`docs/scene.md`, `[importance]`).
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

/// `[geomipmap]`: the GeoMipMap baseline (de Boer, *Fast Terrain Rendering Using Geometrical
/// MipMapping*, 2000).
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
