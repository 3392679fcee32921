//! The report: one row per mode and setting (`report.csv`, `report.json`) and the Pareto fronts
//! of error against frame time; the acceptance summary (`summary.md`) is [`super::summary`]'s.
//!
//! Rules: every CSV cell is filled; a PSNR of identical images (infinite) is written as
//! [`PSNR_CAP_DB`]. A row is on a front when no other row is both faster and better in that error.
//! "Frame time to reach" a target is the least frame time among a mode's rows that reach it;
//! "error at equal frame time" is each mode's best error among its rows no slower than the
//! common budget, the slowest of the modes' fastest rows (so every mode has a row within it).

use crate::output::Fixed;
use serde::{Deserialize, Serialize};
use terrain_engine::PassTimes;
use terrain_engine::stage::quality::Bin;

/// PSNR written for identical images.
pub const PSNR_CAP_DB: f64 = 100.0;
pub const TARGET_PSNR_DB: f64 = 30.0;
pub const TARGET_SSE_PX: f64 = 1.0;

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Row {
    pub mode: String,
    pub setting: String,
    pub triangles: u64,
    /// Triangles drawn per pixel of the image: the hardware-independent cost.
    #[serde(default)]
    pub triangles_per_px: f64,
    pub cpu_stage_us: f64,
    pub gpu_ms: f64,
    pub frame_ms: f64,
    /// The lower and upper quartile of the timed frames' times (each frame's CPU stage plus GPU
    /// passes): two rows whose ranges overlap differ by less than this machine's spread from
    /// frame to frame. `None` in a report written before they were kept.
    #[serde(default)]
    pub frame_ms_p25: Option<f64>,
    #[serde(default)]
    pub frame_ms_p75: Option<f64>,
    pub psnr_db: f64,
    pub ssim: f64,
    pub flip_mean: f64,
    pub sse_mean_px: f64,
    pub sse_p95_px: f64,
    pub sse_max_px: f64,
    pub precompute_ms: f64,
    pub precompute_bytes: u64,
    pub gpu_memory_bytes: u64,
    pub frames: u32,
    pub pareto_psnr: bool,
    pub pareto_sse: bool,
    /// Mean change per frame from the level-of-detail update alone along the camera path (8-bit
    /// levels; `None` without a path).
    #[serde(default)]
    pub lod_change_levels: Option<f64>,
    /// Per-pass GPU medians by pass name (JSON only; empty where the adapter has no timestamp
    /// queries). Read back by `--replot`: `summary.md` splits a frame-time miss by them.
    #[serde(default)]
    pub passes_ms: PassTimes,
    /// Pixels of the measured frame showing ground.
    #[serde(default)]
    pub covered_px: u64,
    /// Every pass's fragment shader invocations per pixel showing ground, where the adapter
    /// counts them (`None` otherwise, and in a report written before they were kept).
    #[serde(default)]
    pub fragments_per_covered_px: Option<f64>,
    /// What the shading evaluated per pixel showing ground, where counted (`compare --work`).
    #[serde(default)]
    pub work_per_px: Option<terrain_engine::WorkPerPx>,
    /// What each pass asked of the GPU in the measured frame, by pass name (JSON only; empty
    /// where the adapter has no pipeline statistics queries).
    #[serde(default)]
    pub counters: std::collections::BTreeMap<String, terrain_engine::PassCounters>,
}

pub const CSV_COLUMNS: [&str; 27] = [
    "mode",
    "setting",
    "triangles",
    "triangles_per_px",
    "cpu_stage_us",
    "gpu_ms",
    "frame_ms",
    "frame_ms_p25",
    "frame_ms_p75",
    "psnr_db",
    "ssim",
    "flip_mean",
    "sse_mean_px",
    "sse_p95_px",
    "sse_max_px",
    "precompute_ms",
    "precompute_bytes",
    "gpu_memory_bytes",
    "frames",
    "pareto_psnr",
    "pareto_sse",
    "lod_change_levels",
    "covered_px",
    "fragments_per_covered_px",
    "octaves_per_px",
    "shadow_steps_per_px",
    "atlas_taps_per_px",
];

/// A row of `report.csv`: [`Row`] without the per-pass times, each figure to the decimals it can
/// tell (a tenth of a µs of CPU, a µs of GPU, a thousandth of a dB).
#[derive(Serialize)]
struct CsvRow<'a> {
    mode: &'a str,
    setting: &'a str,
    triangles: u64,
    triangles_per_px: Fixed<4>,
    cpu_stage_us: Fixed<1>,
    gpu_ms: Fixed<3>,
    frame_ms: Fixed<3>,
    frame_ms_p25: Option<Fixed<3>>,
    frame_ms_p75: Option<Fixed<3>>,
    psnr_db: Fixed<3>,
    ssim: Fixed<4>,
    flip_mean: Fixed<4>,
    sse_mean_px: Fixed<3>,
    sse_p95_px: Fixed<3>,
    sse_max_px: Fixed<3>,
    precompute_ms: Fixed<1>,
    precompute_bytes: u64,
    gpu_memory_bytes: u64,
    frames: u32,
    pareto_psnr: bool,
    pareto_sse: bool,
    lod_change_levels: Option<Fixed<4>>,
    covered_px: u64,
    fragments_per_covered_px: Option<Fixed<3>>,
    octaves_per_px: Option<Fixed<3>>,
    shadow_steps_per_px: Option<Fixed<3>>,
    atlas_taps_per_px: Option<Fixed<3>>,
}

impl Row {
    fn csv_row(&self) -> CsvRow<'_> {
        CsvRow {
            mode: &self.mode,
            setting: &self.setting,
            triangles: self.triangles,
            triangles_per_px: Fixed(self.triangles_per_px),
            cpu_stage_us: Fixed(self.cpu_stage_us),
            gpu_ms: Fixed(self.gpu_ms),
            frame_ms: Fixed(self.frame_ms),
            frame_ms_p25: self.frame_ms_p25.map(Fixed),
            frame_ms_p75: self.frame_ms_p75.map(Fixed),
            psnr_db: Fixed(self.psnr_db.min(PSNR_CAP_DB)),
            ssim: Fixed(self.ssim),
            flip_mean: Fixed(self.flip_mean),
            sse_mean_px: Fixed(self.sse_mean_px),
            sse_p95_px: Fixed(self.sse_p95_px),
            sse_max_px: Fixed(self.sse_max_px),
            precompute_ms: Fixed(self.precompute_ms),
            precompute_bytes: self.precompute_bytes,
            gpu_memory_bytes: self.gpu_memory_bytes,
            frames: self.frames,
            pareto_psnr: self.pareto_psnr,
            pareto_sse: self.pareto_sse,
            lod_change_levels: self.lod_change_levels.map(Fixed),
            covered_px: self.covered_px,
            fragments_per_covered_px: self.fragments_per_covered_px.map(Fixed),
            octaves_per_px: self.work_per_px.map(|w| Fixed(w.octaves)),
            shadow_steps_per_px: self.work_per_px.map(|w| Fixed(w.shadow_steps)),
            atlas_taps_per_px: self.work_per_px.map(|w| Fixed(w.atlas_taps)),
        }
    }
}

/// `report.csv`: a header of [`CSV_COLUMNS`], then one line per row.
pub fn csv(rows: &[Row]) -> String {
    let rows: Vec<CsvRow> = rows.iter().map(Row::csv_row).collect();
    String::from_utf8(crate::output::csv_bytes(&rows)).expect("CSV of UTF-8 cells")
}

/// Whether each row is on the front: no other row is at least as fast and at least as good in
/// `error`, and strictly better in one of them.
fn front(rows: &[Row], error: impl Fn(&Row) -> f64, lower_is_better: bool) -> Vec<bool> {
    let better = |a: f64, b: f64| if lower_is_better { a < b } else { a > b };
    rows.iter()
        .map(|r| {
            !rows.iter().any(|o| {
                let (eo, er) = (error(o), error(r));
                o.frame_ms <= r.frame_ms
                    && !better(er, eo)
                    && (o.frame_ms < r.frame_ms || better(eo, er))
            })
        })
        .collect()
}

pub use super::summary::{ModeSummary, Summary, summarise, summary_markdown};

pub fn mark_fronts(rows: &mut [Row]) {
    let p = front(rows, |r| r.psnr_db.min(PSNR_CAP_DB), false);
    let s = front(rows, |r| r.sse_mean_px, true);
    for (k, r) in rows.iter_mut().enumerate() {
        r.pareto_psnr = p[k];
        r.pareto_sse = s[k];
    }
}

/// `report.json`: everything one run measured. The keys `docs/design.md` (Command line
/// outputs) and the README name stay.
#[derive(Debug, Serialize)]
pub struct Report {
    pub scene: String,
    /// The detail used, defaults resolved from the sketch included.
    pub detail: DetailUsed,
    pub adapter: String,
    /// Image width and height, pixels.
    pub size: [u32; 2],
    pub gpu_timing: &'static str,
    pub timed_frames: u32,
    /// The settings timed alone, their frames one after another, for want of room to keep
    /// their renderers for the rounds (`compare::rounds`); the rest were timed side by side.
    /// The two are not alike: frames one after another find the caches warm.
    pub timed_alone: Vec<String>,
    pub reference: ReferenceFigures,
    pub rows: Vec<Row>,
    pub summary: Summary,
    pub path: Option<PathReport>,
    pub density_ratio: Option<RatioReport>,
    /// Settings that failed, with their cause; the rest were measured. A row whose timing
    /// rounds failed is here too, its times those of the frame it was measured by.
    pub skipped: Vec<Skipped>,
    pub elapsed_s: f64,
}

/// What `--replot` reads back of a `report.json`.
#[derive(Deserialize)]
pub(super) struct Replot {
    pub scene: String,
    pub adapter: String,
    pub size: [u32; 2],
    pub rows: Vec<Row>,
}

#[derive(Debug, Serialize)]
pub struct DetailUsed {
    pub octaves: u32,
    pub amplitude_m: f64,
    pub gain: f64,
    pub bias: f64,
}

/// The reference's march step and how far halving it moves the image.
#[derive(Debug, Serialize)]
pub struct ReferenceFigures {
    pub step: f32,
    pub ms: f64,
    pub psnr_halving_step_db: f64,
    pub converged_db: f64,
}

#[derive(Debug, Serialize)]
pub struct Skipped {
    pub mode: &'static str,
    pub setting: String,
    pub error: String,
}

/// The warped mode's density ratio over the visible cells.
#[derive(Debug, Serialize)]
pub struct RatioReport {
    pub cells_visible: usize,
    pub ratio_within_0_5_2: f64,
    pub ratio_within_0_5_1: f64,
    pub demand_met: f64,
    pub histogram: Vec<Bin>,
}

/// The camera path's statistics, per mode.
#[derive(Debug, Serialize)]
pub struct PathReport {
    pub frames: usize,
    pub fps: f64,
    pub length_m: f64,
    pub source: &'static str,
    pub modes: Vec<PathMode>,
}

#[derive(Debug, Serialize)]
pub struct PathMode {
    pub mode: &'static str,
    pub setting: String,
    pub psnr_db: Option<Stats>,
    pub sse_mean_px: Option<Stats>,
    pub lod_change_levels: Option<Stats>,
    pub lod_changed_share: Option<Stats>,
}

/// Mean, 95th percentile and maximum of a series.
#[derive(Debug, Serialize)]
pub struct Stats {
    pub mean: f64,
    pub p95: f64,
    pub max: f64,
}

impl Stats {
    /// `None` for an empty series (a path of one frame has no LOD change).
    pub(super) fn of(mut v: Vec<f64>) -> Option<Stats> {
        if v.is_empty() {
            return None;
        }
        v.sort_by(f64::total_cmp);
        Some(Stats {
            mean: v.iter().sum::<f64>() / v.len() as f64,
            p95: v[((v.len() as f64 * 0.95) as usize).min(v.len() - 1)],
            max: v[v.len() - 1],
        })
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    #[test]
    fn the_csv_header_is_the_documented_columns() {
        let text = csv(&[row("warped", 5.0, 30.0, 0.5)]);
        let mut lines = text.lines();
        assert_eq!(lines.next(), Some(CSV_COLUMNS.join(",").as_str()));
        assert_eq!(lines.next().unwrap().split(',').count(), CSV_COLUMNS.len());
    }

    pub(crate) fn row(mode: &str, ms: f64, db: f64, px: f64) -> Row {
        Row {
            mode: mode.into(),
            setting: format!("{ms}"),
            triangles: 1,
            triangles_per_px: 0.5,
            cpu_stage_us: 0.0,
            gpu_ms: ms,
            frame_ms: ms,
            frame_ms_p25: Some(ms),
            frame_ms_p75: Some(ms),
            psnr_db: db,
            ssim: 0.5,
            flip_mean: 0.1,
            sse_mean_px: px,
            sse_p95_px: px,
            sse_max_px: px,
            precompute_ms: 0.0,
            precompute_bytes: 0,
            gpu_memory_bytes: 1,
            frames: 1,
            pareto_psnr: false,
            pareto_sse: false,
            lod_change_levels: Some(0.25),
            passes_ms: PassTimes::default(),
            covered_px: 100,
            fragments_per_covered_px: Some(1.5),
            work_per_px: Some(terrain_engine::WorkPerPx {
                octaves: 4.0,
                shadow_steps: 0.5,
                atlas_taps: 24.0,
            }),
            counters: Default::default(),
        }
    }

    #[test]
    fn fronts_keep_only_undominated_rows() {
        let mut rows = vec![
            row("a", 10.0, 25.0, 2.0),
            row("a", 20.0, 31.0, 0.5),
            row("b", 15.0, 24.0, 3.0), // slower and worse than the first
            row("b", 40.0, 31.0, 0.4), // slower, same PSNR: off the PSNR front; better px: on it
        ];
        mark_fronts(&mut rows);
        let p: Vec<bool> = rows.iter().map(|r| r.pareto_psnr).collect();
        let s: Vec<bool> = rows.iter().map(|r| r.pareto_sse).collect();
        assert_eq!(p, [true, true, false, false]);
        assert_eq!(s, [true, true, false, true]);
    }

    #[test]
    fn csv_has_every_column_in_every_row() {
        let text = csv(&[row("a", 1.0, f64::INFINITY, 0.0), row("b", 2.0, 20.0, 1.0)]);
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines.len(), 3);
        for l in &lines {
            let cells: Vec<&str> = l.split(',').collect();
            assert_eq!(cells.len(), CSV_COLUMNS.len());
            assert!(cells.iter().all(|c| !c.is_empty()));
        }
        assert!(lines[1].contains(",100.000,"));
    }
}
