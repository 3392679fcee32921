//! `terrain compare`: every mode over a sweep of its quality setting, each measured against the
//! reference image for the scene's camera, then each mode's scene setting along a camera path.
//!
//! Rules:
//! - One device for the whole run. The reference is ray-marched once per camera and its
//!   convergence shown: the image at half the step differs from it by at least
//!   [`REFERENCE_CONVERGED_DB`] PSNR, the step halved (up to three times) until it does.
//! - Per setting: a warm-up frame, then a frame whose image and positions are measured. The times
//!   are the medians of `repeat` frames (`docs/design.md`, Frame time: CPU stage plus GPU passes)
//!   taken side by side once all are measured, a frame of every setting a round ([`rounds`]); a
//!   setting whose renderer does not fit [`Options::keep_bytes`] has its frames timed one after
//!   another as it is measured.
//! - Every renderer is built with its position attachment on, so all modes carry the same one
//!   extra RGBA8 write per pixel. GeoMipMap settings of one block size share one baked grid.
//! - The default sweep's warped rows at GeoMipMap's budgets (`sweep::at_geomipmap_budgets`) run
//!   last, once GeoMipMap's triangles are known, and the report lists them with the other
//!   warped rows.
//! - A setting that fails (a grid too large for the device, say) is recorded in `report.json`'s
//!   `skipped` and the rest carry on.
//!
//! Outputs in the out dir, each written atomically: `report.csv`, `report.json`, `summary.md`,
//! `error_vs_time.svg`/`.png`, `error_vs_triangles.svg`/`.png`, `lod_change_vs_psnr.svg`/`.png`, `ratio_histogram.svg`/`.png`, `path.csv`, `path_error.svg`/`.png`,
//! `strip.png`, `reference.png`, `reference_positions.npy` (world x, y, z and ground flag per
//! pixel, f64).
//!
//! Positions come from the frame each setting is timed with: every renderer keeps its pixels'
//! view distances (the output pass reads them for snapshots and hosts), a cost all modes share
//! alike. Rejected alternative: a second renderer per setting for its image, which would bake
//! every baseline grid twice (over a second each on llvmpipe).

pub mod figures;
mod measure;
mod path;
pub mod report;
pub mod rounds;
pub mod summary;
pub mod sweep;
pub mod temporal;

use crate::error::REPORT;
use crate::output::{write_atomic, write_image};
use crate::progress::Progress;
use measure::{measure_lod, renderer};
use path::{Out, path_series};
use report::{DetailUsed, RatioReport, ReferenceFigures, Replot, Report, Row, Skipped};
use rounds::{Rounds, RowTimes};
use std::path::Path;
use sweep::Setting;
use terrain_engine::Camera;
use terrain_engine::flight::path::Flight;
use terrain_engine::scene;
use terrain_engine::scene::{MODES, Mode, Scene};
use terrain_engine::sketch::Atlas;
use terrain_engine::stage::CpuStage;
use terrain_engine::{Error, Result, Role};
use terrain_engine::{GpuContext, Needs};

/// PSNR between the reference at its step and at half of it that counts as converged: finer
/// than any difference between modes worth reporting (mode images differ from it by 20–45 dB).
pub const REFERENCE_CONVERGED_DB: f64 = 50.0;
/// The fewest steps along the camera path over which each setting's LOD change per frame is
/// measured; it takes the whole path (`--path-frames`) when that is longer. A warp held over
/// several frames (`warp.hold`) changes nothing on most of them, so a few steps say little.
const LOD_STEPS: usize = 3;
/// How many times the reference's step may be halved to get there.
const MAX_REFERENCE_HALVINGS: usize = 3;

pub struct Options {
    /// Image width and height, pixels.
    pub size: (u32, u32),
    pub modes: Vec<Mode>,
    /// Timed frames per setting: the timing rounds ([`rounds`]), or frames one after another
    /// for a setting timed alone.
    pub repeat: u32,
    /// Frames along the camera path (0: no path).
    pub path_frames: usize,
    pub path_fps: f64,
    /// Search window of the screen-space error, pixels.
    pub window: usize,
    /// The settings to run; `None`: the default sweep.
    pub settings: Option<Vec<Setting>>,
    /// The GPU memory the renderers kept for timing in rounds may hold ([`rounds::KEEP_BYTES`];
    /// 0: every setting timed alone).
    pub keep_bytes: u64,
    /// Each row's work per pixel counted too (`--work`, [`terrain_engine::Renderer::counting_work`]).
    pub work: bool,
}

impl Default for Options {
    fn default() -> Options {
        Options {
            size: (256, 256),
            modes: vec![Mode::Warped, Mode::Geomipmap, Mode::Bruteforce],
            repeat: 15,
            path_frames: 24,
            path_fps: 15.0,
            window: 16,
            settings: None,
            keep_bytes: rounds::KEEP_BYTES,
            work: false,
        }
    }
}

/// The modes `compare` runs on `scene` by default: the compared modes
/// ([`terrain_engine::scene::ModeRow::compared`])
/// that draw its kind of scene, less those that bake the whole sketch on a tile pyramid.
pub fn default_modes(scene: &Scene) -> Vec<Mode> {
    let (planet, streamed) = (scene.planet().is_some(), streamed(scene));
    MODES
        .iter()
        .filter(|r| r.compared && r.mode.draws(planet) && !(streamed && r.bakes_whole_sketch))
        .map(|r| r.mode)
        .collect()
}

/// Whether `scene`'s sketch is a tile pyramid, streamed through the tile cache.
fn streamed(scene: &Scene) -> bool {
    let path = scene.sketch.path.as_ref();
    path.is_some_and(|p| terrain_engine::sketch::tiles::is_pyramid(&scene.resolve(p)))
}

/// Refuses modes that cannot draw `scene`, in one line, before any work.
fn check_modes(scene: &Scene, modes: &[Mode]) -> Result<()> {
    let planet = scene.planet().is_some();
    match modes.iter().find(|&&m| !m.draws(planet)) {
        Some(m) if planet => Err(Error::value(
            "--modes",
            format!("a planet scene compares clipmaps, not {m} (it draws planar sketches)"),
        )),
        Some(_) => Err(Error::value(
            "--modes",
            "clipmaps draws planet scenes; this scene is a planar sketch",
        )),
        None => match modes.iter().find(|&&m| m.bakes_whole_sketch()) {
            Some(m) if streamed(scene) => Err(Error::value(
                "--modes",
                format!(
                    "{m} bakes the whole sketch, and this scene's is a tile pyramid, streamed: \
                     compare warped and geomipmap"
                ),
            )),
            _ => Ok(()),
        },
    }
}

pub struct Outcome {
    pub rows: Vec<Row>,
    pub summary: report::Summary,
    pub report: Report,
}

/// The rows measured so far, each with its image, and the settings that failed.
#[derive(Default)]
struct Runs {
    rows: Vec<Row>,
    images: Vec<(Setting, Vec<u8>)>,
    skipped: Vec<Skipped>,
}

impl Runs {
    fn record(&mut self, s: &Setting, result: Result<(Row, Vec<u8>)>, progress: &mut Progress) {
        match result {
            Ok((row, rgba)) => {
                self.rows.push(row);
                self.images.push((s.clone(), rgba));
            }
            Err(e) => self.skipped.push(Skipped {
                mode: s.mode_name(),
                setting: s.label(),
                error: e.to_string(),
            }),
        }
        progress.advance(1.0, &format!("{} {}", s.mode_name(), s.label()));
    }

    /// Gives the rows timed in rounds their rounds' times; a row the rounds stopped timing is
    /// listed in `skipped` with the cause. Returns the settings timed alone.
    fn time(&mut self, timed: Vec<RowTimes>) -> Vec<String> {
        let mut alone = vec![true; self.rows.len()];
        for RowTimes {
            row,
            setting,
            timed,
            failure,
        } in timed
        {
            alone[row] = false;
            // The rounds kept only frames that drew the row's own triangles.
            if !timed.is_empty() {
                timed.apply(&mut self.rows[row]);
            }
            if let Some(error) = failure {
                self.skipped.push(Skipped {
                    mode: setting.mode_name(),
                    setting: setting.label(),
                    error: format!("{error}; its times are its measured frame's"),
                });
            }
        }
        let rows = self.rows.iter().zip(alone);
        rows.filter(|(_, a)| *a)
            .map(|(r, _)| format!("{} {}", r.mode, r.setting))
            .collect()
    }

    /// Each mode's rows together, in the order the modes first ran (a stable sort, so the rows
    /// run late at GeoMipMap's budgets follow the other warped rows).
    fn group_by_mode(&mut self) {
        let mut modes: Vec<String> = Vec::new();
        for r in &self.rows {
            if !modes.contains(&r.mode) {
                modes.push(r.mode.clone());
            }
        }
        let rank = |m: &str| modes.iter().position(|x| x == m);
        let mut both: Vec<(Row, (Setting, Vec<u8>))> = std::mem::take(&mut self.rows)
            .into_iter()
            .zip(std::mem::take(&mut self.images))
            .collect();
        both.sort_by_key(|(r, _)| rank(&r.mode));
        (self.rows, self.images) = both.into_iter().unzip();
    }
}

/// Runs the comparison of `scene` (named `name` in titles) and writes its outputs to `out_dir`.
pub fn run(scene: &Scene, name: &str, o: &Options, out_dir: &Path) -> Result<Outcome> {
    let mut scene = scene.clone();
    (scene.camera.width, scene.camera.height) = o.size;
    std::fs::create_dir_all(out_dir).map_err(|e| Error::io(Role::OutputFolder, out_dir, e))?;
    let atlas = scene::load_atlas(&scene)?;
    let camera = scene::camera_of(&scene, &atlas)?;
    check_modes(&scene, &o.modes)?;
    let settings = match &o.settings {
        Some(s) => s.clone(),
        None => sweep::default_sweep(&o.modes, &scene, &atlas, &camera)?,
    };
    let storage_bytes = settings
        .iter()
        .map(|s| Ok(terrain_engine::needs(&s.apply(&scene)?, s.mode(), &atlas).storage_bytes))
        .collect::<Result<Vec<u64>>>()?
        .into_iter()
        .max()
        .unwrap_or(0)
        .max(atlas.bytes());
    let ctx = GpuContext::new(&Needs { storage_bytes })?;
    let path_frames = o.path_frames * o.modes.len().min(1);
    // Warped rows at GeoMipMap's budgets: at most one per GeoMipMap row, known once those ran.
    let at_budgets = if o.settings.is_none() && o.modes.contains(&Mode::Warped) {
        settings
            .iter()
            .filter(|s| s.mode() == Mode::Geomipmap)
            .count()
    } else {
        0
    };
    let mut progress = Progress::new(
        &format!("compare {name}"),
        (2 + settings.len() + at_budgets + o.repeat.max(1) as usize + path_frames + 1) as f64,
    );

    let converged = measure::converged_reference(&ctx, &scene, &atlas, &camera)?;
    progress.advance(2.0, "reference, and at half its step");
    let measure::Converged {
        mut reference,
        truth: truth0,
        frame: ref_frame,
        step,
        halving_db,
    } = converged;

    // The camera path once: each setting's LOD change per frame along it, and the path series.
    let flight = if path_frames > 0 {
        let path = Flight::of_scene(&scene, &atlas)?;
        let frames = o.path_frames.max(LOD_STEPS + 1);
        let cameras = path.cameras(frames, o.path_fps, &scene, &atlas)?;
        Some((path, cameras))
    } else {
        None
    };
    let steps = flight.as_ref().map_or(&[][..], |(_, c)| &c[..]);
    let mut rounds = Rounds::new(o.keep_bytes);
    let mut run_setting = |s: &Setting, row: usize| -> Result<(Row, Vec<u8>)> {
        let (mut row, rgba) = rounds.measure(
            s,
            row,
            o.repeat,
            || renderer(&ctx, &scene, &atlas, s),
            |r, frames| measure_lod(r, s, &camera, &truth0, o, frames, steps),
        )?;
        if o.work {
            let (scene, view) = (s.apply(&scene)?, terrain_engine::View::Shaded);
            let work = crate::eval::counted_work(&ctx, &scene, &atlas, s.mode(), view, &camera)?;
            row.work_per_px = Some(work.per_px(row.covered_px));
        }
        Ok((row, rgba))
    };
    let mut runs = Runs::default();
    for s in &settings {
        runs.record(s, run_setting(s, runs.rows.len()), &mut progress);
    }
    if at_budgets > 0 {
        let extra = sweep::at_geomipmap_budgets(scene.warp.quad_px, &runs.rows);
        progress.forgo((at_budgets - extra.len()) as f64);
        for s in &extra {
            runs.record(s, run_setting(s, runs.rows.len()), &mut progress);
        }
    }
    rounds.drop_spare();
    let timed = rounds.run(&camera, o.repeat.max(1), |round| {
        progress.advance(1.0, &format!("timing round {}", round + 1))
    });
    let timed_alone = runs.time(timed);
    drop(rounds);
    if at_budgets > 0 {
        runs.group_by_mode();
    }
    let Runs {
        mut rows,
        images,
        skipped,
    } = runs;
    report::mark_fronts(&mut rows);
    let summary = report::summarise(&rows);

    let (w, h) = o.size;
    let title = format!("{name}: {w}×{h} px on {}", ctx.adapter_name());
    let path = if let Some((path, cameras)) = &flight {
        let out = Out {
            dir: out_dir,
            title: &title,
            path,
            cameras: &cameras[..o.path_frames],
        };
        Some(path_series(
            &ctx,
            &scene,
            &atlas,
            &mut reference,
            o,
            &mut progress,
            &out,
        )?)
    } else {
        None
    };
    write_outputs(out_dir, &rows, &summary, &title)?;
    write_image(&out_dir.join("reference.png"), w, h, &truth0.rgba)?;
    crate::output::write_npy_f64(
        &out_dir.join("reference_positions.npy"),
        &[h as usize, w as usize, 4],
        &terrain_engine::world_positions(&truth0.positions, &camera),
    )?;
    let strip_modes: Vec<(String, String, Vec<u8>)> = o
        .modes
        .iter()
        .filter_map(|&m| {
            let want = Setting::of_scene(m, &scene, &atlas)?;
            let (s, img) = images
                .iter()
                .find(|(s, _)| *s == want)
                .or_else(|| images.iter().find(|(s, _)| s.mode() == m))?;
            Some((
                figures::display(s.mode_name()).to_string(),
                s.label(),
                img.clone(),
            ))
        })
        .collect();
    figures::strip(&out_dir.join("strip.png"), w, h, &truth0.rgba, &strip_modes)?;
    let histogram = if o.modes.contains(&Mode::Warped) {
        Some(ratio_histogram(&scene, &atlas, &camera, out_dir, name)?)
    } else {
        None
    };
    progress.advance(1.0, "figures");
    progress.finish();

    let report = Report {
        scene: name.to_string(),
        detail: DetailUsed {
            octaves: reference.detail.octaves,
            amplitude_m: reference.detail.amplitude_m,
            gain: reference.detail.gain,
            bias: reference.detail.bias,
        },
        adapter: ctx.adapter_name(),
        size: [w, h],
        gpu_timing: if ctx.timestamps {
            "timestamp queries"
        } else {
            "wall time around submit"
        },
        timed_frames: o.repeat.max(1),
        timed_alone,
        reference: ReferenceFigures {
            step,
            ms: ref_frame.gpu.gpu_ms,
            psnr_halving_step_db: halving_db.min(report::PSNR_CAP_DB),
            converged_db: REFERENCE_CONVERGED_DB,
        },
        rows: rows.clone(),
        summary: summary.clone(),
        path,
        density_ratio: histogram,
        skipped,
        elapsed_s: progress.elapsed().as_secs_f64(),
    };
    write_atomic(
        &out_dir.join("report.json"),
        serde_json::to_string_pretty(&report)
            .map_err(|e| Error::encode("compare report", e))?
            .as_bytes(),
    )?;
    Ok(Outcome {
        rows,
        summary,
        report,
    })
}

/// Redraws `error_vs_time` and `summary.md` in `out_dir` from its `report.json` (after a change
/// to the figures, without measuring again). Returns the rows' count.
pub fn replot(out_dir: &Path) -> Result<usize> {
    let path = out_dir.join("report.json");
    let text = std::fs::read_to_string(&path).map_err(|e| Error::io(REPORT, &path, e))?;
    let bad = |why: String| Error::file(REPORT, &path, why);
    let report: Replot = serde_json::from_str(&text).map_err(|e| bad(e.to_string()))?;
    let mut rows = report.rows;
    report::mark_fronts(&mut rows);
    let [w, h] = report.size;
    let title = format!("{}: {w}×{h} px on {}", report.scene, report.adapter);
    write_outputs(out_dir, &rows, &report::summarise(&rows), &title)?;
    Ok(rows.len())
}

fn write_outputs(
    out_dir: &Path,
    rows: &[Row],
    summary: &report::Summary,
    title: &str,
) -> Result<()> {
    write_atomic(&out_dir.join("report.csv"), report::csv(rows).as_bytes())?;
    write_atomic(
        &out_dir.join("summary.md"),
        report::summary_markdown(title, summary).as_bytes(),
    )?;
    figures::error_vs_time(rows, &format!("Error against frame time: {title}"))
        .write(&out_dir.join("error_vs_time"))?;
    figures::error_vs_triangles(rows, &format!("Error against triangles: {title}"))
        .write(&out_dir.join("error_vs_triangles"))?;
    if rows.iter().any(|r| r.lod_change_levels.is_some()) {
        figures::lod_change_vs_psnr(rows, &format!("Swimming against image error: {title}"))
            .write(&out_dir.join("lod_change_vs_psnr"))?;
    }
    Ok(())
}

/// The warped mode's density-ratio histogram at the scene's camera.
fn ratio_histogram(
    scene: &Scene,
    atlas: &Atlas,
    camera: &Camera,
    out_dir: &Path,
    title: &str,
) -> Result<RatioReport> {
    let detail = scene::detail_for(scene, atlas, Mode::Warped);
    let mut stage = CpuStage::new(scene, &detail)?;
    stage.run(atlas, camera);
    let mut ratios = Vec::new();
    let q = terrain_engine::stage::quality::measure(
        &stage.warp.phi,
        stage.sketch_map.n,
        stage.sketch_map.spacing,
        &stage.importance,
        &mut ratios,
    );
    figures::ratio_histogram(
        &q.histogram,
        q.cells_visible,
        &format!(
            "Warped density ratio, {title}: {:.1} % of {} visible cells in [1/2, 2]",
            100.0 * q.ratio_within_0_5_2,
            q.cells_visible
        ),
    )
    .write(&out_dir.join("ratio_histogram"))?;
    Ok(RatioReport {
        cells_visible: q.cells_visible,
        ratio_within_0_5_2: q.ratio_within_0_5_2,
        ratio_within_0_5_1: q.ratio_within_0_5_1,
        demand_met: q.demand_met,
        histogram: q.histogram,
    })
}
