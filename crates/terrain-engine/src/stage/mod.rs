//! The CPU stage of a frame: sketch map → importance map → row and column warp → Φ.
//!
//! [`CpuStage`] owns every buffer the stage needs, sized once for the scene's `warp.size`, so a
//! frame allocates nothing; its three parts are timed separately (the [`Budget`], a sum over the
//! importance map, counts with the warp).

pub(crate) mod budget;
pub(crate) mod hold;
pub(crate) mod importance;
pub(crate) mod lines;
pub mod quality;
pub(crate) mod simd;
pub(crate) mod sketch_map;
pub(crate) mod transpose;
pub(crate) mod warp;

pub use budget::Budget;
pub use sketch_map::Turn;
pub use warp::{Warp, pair_unfolded};

use crate::camera::Camera;
use crate::detail::Detail;
use crate::error::Result;
use crate::scene::Scene;
use crate::sketch::Atlas;
use glam::DVec2;
use hold::{Hold, ROW_STEP};
use importance::{ErrorTerm, ImportanceMap, ImportanceParams};
use sketch_map::{Resampler, SketchMap};
use web_time::Instant;

/// Microseconds spent in each part of the stage.
#[derive(Clone, Copy, Debug, Default, serde::Serialize)]
pub struct StageTimes {
    /// Cutting the visible region out of the sketch and resampling it to the sketch map, µs.
    pub sketch_map_us: f64,
    /// The importance map over the sketch map, µs.
    pub importance_us: f64,
    /// The row and column warp to Φ (with the mesh budget), µs.
    pub warp_us: f64,
}

impl StageTimes {
    /// The three parts together, µs.
    pub fn total_us(&self) -> f64 {
        self.sketch_map_us + self.importance_us + self.warp_us
    }
}

/// The CPU stage of the warped mode: each frame, sketch map → importance → warp → Φ, into
/// buffers sized once for the scene's `warp.size`.
pub struct CpuStage {
    /// The sketch map: the visible region resampled to `warp.size`² texels.
    pub sketch_map: SketchMap,
    /// The importance the last warp was made for: only a frame that warps anew updates it, and
    /// the held warp's drift check compares against it (`stage::hold`). A caller that updates it
    /// must [`CpuStage::forget`] before the next run.
    pub importance: ImportanceMap,
    /// The importance on a sample of rows, for a held warp's drift check.
    probe: ImportanceMap,
    /// The warp and its Φ.
    pub warp: Warp,
    /// The importance's terms and constants, from the scene's `[importance]` and `[warp]`.
    pub params: ImportanceParams,
    /// The mesh the importance asks for (`warp.budget`); `None`: always `warp.mesh`.
    pub budget: Option<Budget>,
    /// Keeps the last warp while it serves (`warp.hold`); `None`: every frame warps anew.
    pub hold: Option<Hold>,
    /// Whether the last run kept the held warp.
    pub held: bool,
    /// The mesh side the last run chose.
    pub mesh: u32,
    /// I_s as an atlas-like grid, when the scene gives a map.
    surface_max_atlas: Option<Atlas>,
    surface_max: Vec<f32>,
    surface_resampler: Resampler,
    /// The ground position of the camera of the last run (for figures).
    pub last_eye: DVec2,
    /// The heading the last warp was made for ([`heading_of`]); `None` before the first.
    heading: Option<Heading>,
    /// Whether a diagonal heading turns the region (`warp.diagonal`).
    diagonal: bool,
}

/// Without `warp.diagonal`: how much more a view's heading must lie along the other axis before
/// the warp turns: about 51° from the axis it runs along, so that a heading near the diagonal
/// does not flip the mesh from frame to frame. Not 1.2: the bundled flight's last key looks 6000 m along x for 5000
/// along y, and a threshold at its exact ratio would leave the turn to rounding.
const TURN_RATIO: f64 = 1.25;

/// Whether the warp runs across (`Warp::run_across`, columns first): where the view's depth runs
/// along x rather than y (the heading's x over its y), keeping the last choice within
/// [`TURN_RATIO`] of the diagonal. A view straight down keeps the last, or runs rows first.
fn runs_across(camera: &Camera, last: Option<bool>) -> bool {
    let (x, y) = (camera.forward.x.abs(), camera.forward.y.abs());
    if x.max(y) < 1e-9 {
        return last.unwrap_or(false);
    }
    match last {
        Some(true) => y <= TURN_RATIO * x,
        Some(false) => x > TURN_RATIO * y,
        None => x > y,
    }
}

/// The way a view's warp lies: the axis or diagonal nearest the view's heading (a line, so
/// north and south are one), so that the warp's second pass runs along the view's depth
/// (`stage::warp`'s rule on orientation).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Heading {
    /// Rows first over an axis-aligned region.
    North,
    /// Rows first over a region turned to the north-east ([`Turn::NorthEast`]).
    NorthEast,
    /// Across ([`warp::Warp::run_across`]) over an axis-aligned region.
    East,
    /// Rows first over a region turned to the north-west ([`Turn::NorthWest`]).
    NorthWest,
}

impl Heading {
    const ALL: [Heading; 4] = [
        Heading::North,
        Heading::NorthEast,
        Heading::East,
        Heading::NorthWest,
    ];

    /// The region's axes for this heading.
    pub fn turn(self) -> Turn {
        match self {
            Heading::North | Heading::East => Turn::None,
            Heading::NorthEast => Turn::NorthEast,
            Heading::NorthWest => Turn::NorthWest,
        }
    }

    /// Whether the warp runs across.
    pub fn across(self) -> bool {
        self == Heading::East
    }

    /// Degrees from north toward east, modulo 180.
    fn degrees(self) -> f64 {
        match self {
            Heading::North => 0.0,
            Heading::NorthEast => 45.0,
            Heading::East => 90.0,
            Heading::NorthWest => 135.0,
        }
    }
}

/// How far from its centre each heading reaches, in degrees: an axis 30° each way, a diagonal
/// 15°: the turned region gains nothing within 25° of an axis, and equal reaches (22.5° each)
/// turn views that an axis serves better (docs/decisions.md, “Turned region”).
fn reach(h: Heading) -> f64 {
    match h {
        Heading::North | Heading::East => 30.0,
        Heading::NorthEast | Heading::NorthWest => 15.0,
    }
}

/// Degrees past its reach that a view must turn before its warp follows, so that a camera
/// swaying about a boundary keeps its mesh.
const TURN_BAND_DEG: f64 = 2.5;

/// The heading a view's warp lies along: the one whose reach ([`reach`]) holds the view's
/// heading, keeping the last one within [`TURN_BAND_DEG`] past its reach. Without `diagonal`
/// (`warp.diagonal`), north or east only, as [`runs_across`] chooses. A view straight down
/// keeps the last, or north.
fn heading_of(camera: &Camera, last: Option<Heading>, diagonal: bool) -> Heading {
    if !diagonal {
        return match runs_across(camera, last.map(Heading::across)) {
            true => Heading::East,
            false => Heading::North,
        };
    }
    let (x, y) = (camera.forward.x, camera.forward.y);
    if x.abs().max(y.abs()) < 1e-9 {
        return last.unwrap_or(Heading::North);
    }
    let degrees = x.atan2(y).to_degrees().rem_euclid(180.0);
    let off = |h: Heading| {
        let d = (degrees - h.degrees()).rem_euclid(180.0);
        d.min(180.0 - d)
    };
    match last {
        Some(h) if off(h) <= reach(h) + TURN_BAND_DEG => h,
        // The reaches tile the circle, so the least share of its reach is below 1 for one.
        _ => Heading::ALL
            .into_iter()
            .min_by(|a, b| (off(*a) / reach(*a)).total_cmp(&(off(*b) / reach(*b))))
            .unwrap_or(Heading::North),
    }
}

impl CpuStage {
    /// The stage of `scene` with `detail` (whose octaves enter the geometric-error term); reads
    /// `importance.max_map` where the scene gives one.
    pub fn new(scene: &Scene, detail: &Detail) -> Result<CpuStage> {
        let n = scene.warp.size as usize;
        let imp = &scene.importance;
        let surface_max_atlas = match &imp.max_map {
            Some(p) => Some(Atlas::load(
                &scene.resolve(p),
                &crate::scene::scene_load_options(scene),
            )?),
            None => None,
        };
        Ok(CpuStage {
            sketch_map: SketchMap::new(n),
            importance: ImportanceMap::new(n),
            probe: ImportanceMap::new(n),
            warp: Warp::new(n, scene.warp.method, scene.warp.max_log2_step as f32),
            params: ImportanceParams {
                quad_px: scene.warp.quad_px,
                view: imp.view,
                frustum: imp.frustum,
                backface: imp.backface,
                max_per_m: imp.max_per_m,
                floor: imp.floor,
                backface_floor: imp.backface_floor,
                reach_m: detail.reach_m(),
                error: imp.error.then(|| {
                    ErrorTerm::new(
                        detail,
                        imp.error_px,
                        imp.error_flat_share,
                        scene.sketch.water_level_m as f32,
                    )
                }),
            },
            budget: scene
                .warp
                .budget
                .then(|| Budget::new(scene.warp.min_mesh, scene.warp.mesh)),
            hold: scene.warp.hold.then(|| Hold::new(scene.warp.hold_drift)),
            held: false,
            mesh: scene.warp.mesh,
            surface_max: if surface_max_atlas.is_some() {
                vec![0.0; n * n]
            } else {
                Vec::new()
            },
            surface_max_atlas,
            surface_resampler: Resampler::default(),
            last_eye: DVec2::ZERO,
            heading: None,
            diagonal: scene.warp.diagonal,
        })
    }

    /// Runs the stage for `camera`; Φ is then in `self.warp.phi`, in region-local metres
    /// (`SketchMap::world` turns them into world positions).
    pub fn run(&mut self, atlas: &Atlas, camera: &Camera) -> StageTimes {
        let t0 = Instant::now();
        if let Some(e) = self.params.error.as_mut() {
            e.measure_sketch_levels(atlas);
        }
        self.last_eye = camera.eye.truncate();
        let holding = self.hold.is_some();
        // A new turn moves the region, so the held warp is redone with it; a view turning from
        // north to east keeps a held warp while it serves, as it always has.
        let heading = heading_of(camera, self.heading, self.diagonal);
        let moved =
            self.sketch_map
                .update(atlas, camera, self.params.reach_m, holding, heading.turn());
        if let (true, Some(m)) = (moved, &self.surface_max_atlas) {
            self.sketch_map
                .resample_into(m, &mut self.surface_max, &mut self.surface_resampler);
        }
        let t1 = Instant::now();
        let bounds = (atlas.origin, atlas.max_corner());
        let surface = self
            .surface_max_atlas
            .as_ref()
            .map(|_| self.surface_max.as_slice());
        // A held warp that still serves: only a sample of the importance, no warp.
        self.held = match &mut self.hold {
            Some(h) if !moved && h.is_holding() => {
                self.probe.update_rows(
                    &self.sketch_map,
                    bounds,
                    camera,
                    surface,
                    &self.params,
                    ROW_STEP,
                );
                let serves = h.serves(&self.probe, &self.importance);
                h.held_frames += u32::from(serves);
                serves
            }
            _ => false,
        };
        if !self.held {
            self.importance
                .update(&self.sketch_map, bounds, camera, surface, &self.params);
        }
        let t2 = Instant::now();
        if !self.held {
            self.heading = Some(heading);
            let (imp, d0) = (&self.importance.importance, self.sketch_map.spacing as f32);
            if heading.across() {
                self.warp.run_across(imp, d0);
            } else {
                self.warp.run(imp, d0);
            }
            if let Some(b) = &mut self.budget {
                self.mesh = b.update(&self.importance.importance, self.sketch_map.spacing);
            }
            if let Some(h) = &mut self.hold {
                h.made();
            }
        }
        let t3 = Instant::now();
        let us = |a: Instant, b: Instant| (b - a).as_secs_f64() * 1e6;
        StageTimes {
            sketch_map_us: us(t0, t1),
            importance_us: us(t1, t2),
            warp_us: us(t2, t3),
        }
    }

    /// Drops what earlier frames left (the held warp and region, the budget's rung), so the next
    /// run depends on its camera alone.
    pub fn forget(&mut self) {
        self.sketch_map.forget();
        if let Some(h) = &mut self.hold {
            h.forget();
        }
        if let Some(b) = &mut self.budget {
            b.forget();
        }
        self.heading = None;
    }

    /// Φ(s, t) in world metres (f64).
    pub fn phi_world(&self, s: usize, t: usize) -> DVec2 {
        let p = self.warp.phi[t * self.sketch_map.n + s];
        self.sketch_map.world(DVec2::new(p[0] as f64, p[1] as f64))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn heading(x: f64, y: f64) -> Camera {
        let scene = crate::scene::Scene::parse(
            &format!(
                "[sketch]\nsynthetic = \"flat\"\n[camera]\nposition = [0.0, 0.0, 100.0]\n\
                 look_at = [{x}, {y}, 0.0]\n"
            ),
            std::path::PathBuf::from("."),
        )
        .expect("a scene");
        let atlas = crate::scene::load_atlas(&scene).expect("an atlas");
        crate::scene::camera_of(&scene, &atlas).expect("a camera")
    }

    /// The warp runs across where the heading lies along x, and turns only once the heading is
    /// past the diagonal by [`TURN_RATIO`], so a camera swaying about 45° keeps its mesh.
    #[test]
    fn the_warp_turns_past_the_diagonal_only() {
        let along = |x: f64, y: f64, last| runs_across(&heading(x, y), last);
        assert!(along(1000.0, 100.0, None));
        assert!(!along(100.0, 1000.0, None));
        assert!(along(-1000.0, 300.0, None));
        // 48° from x: the last choice stands either way.
        assert!(along(1000.0, 1110.0, Some(true)));
        assert!(!along(1110.0, 1000.0, Some(false)));
        // 55°: past the band.
        assert!(!along(1000.0, 1430.0, Some(true)));
        assert!(along(-1430.0, 1000.0, Some(false)));
    }

    /// With `warp.diagonal`, the heading whose reach holds the view's (an axis 30° each way, a
    /// diagonal 15°; south is north), keeping the last within 2.5° past its reach, so a camera
    /// swaying about a boundary keeps its mesh; without it, [`runs_across`]'s choice.
    #[test]
    fn the_warp_follows_the_heading_whose_reach_holds_the_view() {
        use Heading::*;
        let at = |degrees: f64, last, diagonal| {
            let r = degrees.to_radians();
            heading_of(&heading(1000.0 * r.sin(), 1000.0 * r.cos()), last, diagonal)
        };
        for (degrees, want) in [
            (0.0, North),
            (180.0, North),
            (20.0, North),
            (29.0, North),
            (31.0, NorthEast),
            (45.0, NorthEast),
            (225.0, NorthEast),
            (59.0, NorthEast),
            (61.0, East),
            (-90.0, East),
            (135.0, NorthWest),
            (-40.0, NorthWest),
            (-29.0, North),
            (160.0, North),
        ] {
            assert_eq!(at(degrees, None, true), want, "{degrees}°");
        }
        // Within 2.5° past the last heading's reach it stays; past, it turns.
        assert_eq!(at(32.0, Some(North), true), North);
        assert_eq!(at(33.0, Some(North), true), NorthEast);
        assert_eq!(at(28.0, Some(NorthEast), true), NorthEast);
        assert_eq!(at(27.0, Some(NorthEast), true), North);
        assert_eq!(at(62.0, Some(NorthEast), true), NorthEast);
        assert_eq!(at(63.0, Some(NorthEast), true), East);
        assert_eq!(at(58.0, Some(East), true), East);
        assert_eq!(at(57.0, Some(East), true), NorthEast);
        // Straight down keeps the last.
        let down = heading(0.0, 0.0);
        assert_eq!(heading_of(&down, Some(NorthWest), true), NorthWest);
        assert_eq!(heading_of(&down, None, true), North);
        // Without diagonals: north or east, as before.
        assert_eq!(at(45.0, None, false), North);
        assert_eq!(at(60.0, None, false), East);
        assert_eq!(at(48.0, Some(East), false), East);
    }

    /// A held warp is redone when the view turns past 32.5° (its region turns with it), and
    /// then held again while the camera stays; within the band it is kept.
    #[test]
    fn a_turn_of_the_region_redoes_the_held_warp() {
        let scene = |degrees: f64| {
            let r = degrees.to_radians();
            let (x, y) = (3840.0 + 3000.0 * r.sin(), 2000.0 + 3000.0 * r.cos());
            crate::scene::Scene::parse(
                &format!(
                    "[sketch]\nsynthetic = \"hills\"\n[camera]\nposition = [3840.0, 2000.0, \
                     760.0]\nlook_at = [{x}, {y}, 400.0]\n"
                ),
                std::path::PathBuf::from("."),
            )
            .expect("a scene")
        };
        let first = scene(25.0);
        let atlas = crate::scene::load_atlas(&first).expect("an atlas");
        let detail = crate::scene::detail_of(&first, &atlas);
        let mut stage = CpuStage::new(&first, &detail).expect("a stage");
        let mut run = |degrees: f64| {
            let camera = crate::scene::camera_of(&scene(degrees), &atlas).expect("a camera");
            stage.run(&atlas, &camera);
            (stage.held, stage.sketch_map.turn)
        };
        assert_eq!(run(25.0), (false, Turn::None));
        assert_eq!(run(25.0), (true, Turn::None));
        // 31.5° is in north-east's reach, but within the band about north's: the region keeps
        // its axes (the warp is redone only if the demand drifted).
        assert_eq!(run(31.5).1, Turn::None);
        // 34° is past it: the region turns, and the warp is made anew.
        assert_eq!(run(34.0), (false, Turn::NorthEast));
        assert_eq!(run(34.0), (true, Turn::NorthEast));
    }
}
