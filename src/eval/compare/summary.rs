//! The acceptance summary (`summary.md`): per mode, the least frame time reaching the targets
//! ([`TARGET_PSNR_DB`], [`TARGET_SSE_PX`]), and each mode's best error at the common budget — the
//! slowest of the modes' fastest rows, so every mode has a row within it; and, where both ran,
//! the warped mode against GeoMipMap row by row ([`Dominance`]).

use super::report::{PSNR_CAP_DB, Row, TARGET_PSNR_DB, TARGET_SSE_PX};
use serde::Serialize;
use std::fmt::Write;
use terrain_engine::pass;

#[derive(Clone, Debug, Serialize)]
pub struct ModeSummary {
    pub mode: String,
    /// The mode's name as the papers write it, its row's in the mode table (for the scripts'
    /// tables and the charts' legends).
    pub display: String,
    /// Least frame time reaching 30 dB PSNR; `None`: no setting reaches it.
    pub ms_to_30db: Option<f64>,
    pub setting_30db: Option<String>,
    /// Least frame time reaching a mean screen-space error of 1 px.
    pub ms_to_1px: Option<f64>,
    pub setting_1px: Option<String>,
    /// Best errors among the mode's rows within the common budget.
    pub psnr_at_budget_db: Option<f64>,
    pub sse_at_budget_px: Option<f64>,
    pub fastest_ms: f64,
}

#[derive(Clone, Debug, Serialize)]
pub struct Summary {
    pub budget_ms: f64,
    pub modes: Vec<ModeSummary>,
    /// Warped against GeoMipMap row by row, when both ran.
    pub dominance: Option<Dominance>,
}

/// For each GeoMipMap row: is there a warped row with no more triangles and no more mean
/// screen-space error (triangles do not depend on the machine), and one with no more frame time
/// and no less PSNR? A row-by-row check and not a comparison of curves: a warped row must exist
/// at or below GeoMipMap's cost, so the sweep's spacing counts.
#[derive(Clone, Debug, Serialize)]
pub struct Dominance {
    pub geomipmap_rows: usize,
    pub matched_on_triangles: usize,
    pub matched_on_time: usize,
    /// The GeoMipMap rows not matched on triangles and error.
    pub misses: Vec<Miss>,
    /// The GeoMipMap rows not matched on frame time and PSNR.
    pub time_misses: Vec<TimeMiss>,
    /// Over every GeoMipMap row that warped's error reaches: the triangles warped needs for the
    /// row's error between its rows ([`Miss::warped_triangles_interpolated`]; where warped's
    /// fewest-triangle row already has no more error, that row's triangles, a bound), as a
    /// multiple of the row's. `None` where warped reaches no row's error.
    pub need: Option<Need>,
}

/// [`Dominance::need`]: its least, its greatest and its geometric mean, over `rows` rows.
#[derive(Clone, Debug, Serialize)]
pub struct Need {
    pub least: f64,
    pub greatest: f64,
    pub geometric_mean: f64,
    pub rows: usize,
}

/// A GeoMipMap row no warped row matches on triangles and error, the least mean error of a
/// warped row within its triangles (`None`: no warped row has so few), and the fewest triangles
/// of a warped row with no more error (`None`: none has so little): by how much warped misses.
#[derive(Clone, Debug, Serialize)]
pub struct Miss {
    pub setting: String,
    pub triangles: u64,
    pub sse_mean_px: f64,
    pub warped_sse_px: Option<f64>,
    pub warped_triangles_needed: Option<u64>,
    /// The triangles at which warped's error reaches the row's between its rows: log-log
    /// interpolation between the two warped rows of its least-error front (by triangles) around
    /// the row's error. The ladder's rungs are about 1.4× apart, so `warped_triangles_needed`
    /// alone can read a miss by a few per cent as up to 1.4× (less where a row at a GeoMipMap
    /// budget lies between them).
    pub warped_triangles_interpolated: Option<f64>,
}

/// A GeoMipMap row no warped row matches on frame time and PSNR: warped's fastest row with as
/// much PSNR and warped's best PSNR within the row's frame time (`None`: no warped row is as
/// fast), by how much warped misses.
#[derive(Clone, Debug, Serialize)]
pub struct TimeMiss {
    pub setting: String,
    pub frame_ms: f64,
    pub psnr_db: f64,
    /// Where the row's frame time goes; `None` where its passes were not timed.
    pub split: Option<FrameSplit>,
    /// `None`: no warped row has as much PSNR.
    pub warped_as_good: Option<AsGood>,
    pub warped_psnr_within_db: Option<f64>,
}

/// [`TimeMiss::warped_as_good`]: warped's fastest row with the missed row's PSNR or more.
#[derive(Clone, Debug, Serialize)]
pub struct AsGood {
    pub setting: String,
    pub frame_ms: f64,
    /// `frame_ms` as a multiple of the missed row's.
    pub time_ratio: f64,
    /// Whether the two rows' interquartile ranges of frame time overlap (`Row::frame_ms_p25`,
    /// `frame_ms_p75`): their medians lie closer than the frames of either spread, and the
    /// machine's spread from frame to frame covers the miss. `None` where either row has no
    /// quartiles.
    pub within_spread: Option<bool>,
    /// Where its frame time goes; `None` where its passes were not timed.
    pub split: Option<FrameSplit>,
}

/// Where a row's frame time goes, so that a miss shows which part of the frame makes it: at
/// the frame's floor both modes' terrain passes shade each pixel once and take about as long,
/// and warped's CPU stage and compute passes are what it pays beyond GeoMipMap's. Each part is
/// its median over the timed frames, so the three need not add up to `frame_ms` exactly.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FrameSplit {
    /// The CPU stage: warped's sketch map, importance and warp; GeoMipMap's block selection.
    pub cpu_ms: f64,
    /// The GPU passes other than the terrain's (warped's warp & zoom, mesh split and normals).
    pub other_passes_ms: f64,
    /// The terrain pass: the mesh drawn and every pixel shaded.
    pub terrain_ms: f64,
}

impl FrameSplit {
    /// `None` where the row's passes were not timed (an adapter without timestamp queries).
    fn of(r: &Row) -> Option<FrameSplit> {
        let terrain_ms = r.passes_ms.get(pass::TERRAIN)?;
        Some(FrameSplit {
            cpu_ms: r.cpu_stage_us / 1000.0,
            other_passes_ms: r.passes_ms.total() - terrain_ms,
            terrain_ms,
        })
    }
}

impl TimeMiss {
    fn of(g: &Row, warped: &[&Row]) -> TimeMiss {
        let quartiles = |r: &Row| r.frame_ms_p25.zip(r.frame_ms_p75);
        let as_good = |w: &Row| AsGood {
            setting: w.setting.clone(),
            frame_ms: w.frame_ms,
            time_ratio: w.frame_ms / g.frame_ms,
            within_spread: quartiles(w)
                .zip(quartiles(g))
                .map(|((w25, w75), (g25, g75))| w25 <= g75 && g25 <= w75),
            split: FrameSplit::of(w),
        };
        TimeMiss {
            setting: g.setting.clone(),
            frame_ms: g.frame_ms,
            psnr_db: g.psnr_db,
            split: FrameSplit::of(g),
            warped_as_good: warped
                .iter()
                .filter(|w| w.psnr_db >= g.psnr_db)
                .min_by(|a, b| a.frame_ms.total_cmp(&b.frame_ms))
                .map(|w| as_good(w)),
            warped_psnr_within_db: warped
                .iter()
                .filter(|w| w.frame_ms <= g.frame_ms)
                .map(|w| w.psnr_db)
                .reduce(f64::max),
        }
    }
}

/// The triangles at which `warped`'s error, interpolated log-log between the rows of its front
/// (each row with less error than every row with fewer triangles), reaches `sse_px`; `None`
/// where no row has so little error, or where the fewest-triangle row already does.
fn interpolated_triangles(warped: &[&Row], sse_px: f64) -> Option<f64> {
    let mut by_triangles: Vec<(f64, f64)> = warped
        .iter()
        .filter(|w| w.triangles > 0 && w.sse_mean_px > 0.0)
        .map(|w| (w.triangles as f64, w.sse_mean_px))
        .collect();
    by_triangles.sort_by(|a, b| a.0.total_cmp(&b.0).then(b.1.total_cmp(&a.1)));
    let mut front: Vec<(f64, f64)> = Vec::new();
    for p in by_triangles {
        if front.last().is_none_or(|last| p.1 < last.1) {
            front.push(p);
        }
    }
    front.windows(2).find_map(|w| {
        let ((t0, e0), (t1, e1)) = (w[0], w[1]);
        (e0 > sse_px && sse_px >= e1).then(|| {
            let f = (e0.ln() - sse_px.ln()) / (e0.ln() - e1.ln());
            (t0.ln() + f * (t1.ln() - t0.ln())).exp()
        })
    })
}

/// [`Dominance`] of `rows`; `None` unless both modes have rows.
pub fn dominance(rows: &[Row]) -> Option<Dominance> {
    let warped: Vec<&Row> = rows_of(rows, "warped").collect();
    let gmm: Vec<&Row> = rows_of(rows, "geomipmap").collect();
    if warped.is_empty() || gmm.is_empty() {
        return None;
    }
    let mut d = Dominance {
        geomipmap_rows: gmm.len(),
        matched_on_triangles: 0,
        matched_on_time: 0,
        misses: Vec::new(),
        time_misses: Vec::new(),
        need: None,
    };
    let fewest = warped
        .iter()
        .filter(|w| w.triangles > 0)
        .min_by_key(|w| w.triangles);
    let needs: Vec<f64> = gmm
        .iter()
        .filter(|g| g.triangles > 0)
        .filter_map(|g| {
            let t = interpolated_triangles(&warped, g.sse_mean_px).or_else(|| {
                fewest
                    .filter(|w| w.sse_mean_px <= g.sse_mean_px)
                    .map(|w| w.triangles as f64)
            })?;
            Some(t / g.triangles as f64)
        })
        .collect();
    if !needs.is_empty() {
        let log_mean = needs.iter().map(|r| r.ln()).sum::<f64>() / needs.len() as f64;
        d.need = Some(Need {
            least: needs.iter().copied().fold(f64::INFINITY, f64::min),
            greatest: needs.iter().copied().fold(0.0, f64::max),
            geometric_mean: log_mean.exp(),
            rows: needs.len(),
        });
    }
    for g in gmm {
        let within = || warped.iter().filter(|w| w.triangles <= g.triangles);
        if within().any(|w| w.sse_mean_px <= g.sse_mean_px) {
            d.matched_on_triangles += 1;
        } else {
            d.misses.push(Miss {
                setting: g.setting.clone(),
                triangles: g.triangles,
                sse_mean_px: g.sse_mean_px,
                warped_sse_px: within().map(|w| w.sse_mean_px).reduce(f64::min),
                warped_triangles_needed: warped
                    .iter()
                    .filter(|w| w.sse_mean_px <= g.sse_mean_px)
                    .map(|w| w.triangles)
                    .min(),
                warped_triangles_interpolated: interpolated_triangles(&warped, g.sse_mean_px),
            });
        }
        let on_time = warped
            .iter()
            .any(|w| w.frame_ms <= g.frame_ms && w.psnr_db >= g.psnr_db);
        d.matched_on_time += usize::from(on_time);
        if !on_time {
            d.time_misses.push(TimeMiss::of(g, &warped));
        }
    }
    Some(d)
}

fn rows_of<'a>(rows: &'a [Row], m: &'a str) -> impl Iterator<Item = &'a Row> + 'a {
    rows.iter().filter(move |r| r.mode == m)
}

pub fn summarise(rows: &[Row]) -> Summary {
    let mut names: Vec<&str> = Vec::new();
    for r in rows {
        if !names.contains(&r.mode.as_str()) {
            names.push(&r.mode);
        }
    }
    let fastest = |m: &str| {
        rows_of(rows, m)
            .map(|r| r.frame_ms)
            .fold(f64::INFINITY, f64::min)
    };
    let budget = names.iter().map(|m| fastest(m)).fold(0.0, f64::max);
    let first = |m: &str, ok: &dyn Fn(&Row) -> bool| {
        rows_of(rows, m)
            .filter(|r| ok(r))
            .min_by(|a, b| a.frame_ms.total_cmp(&b.frame_ms))
            .map(|r| (r.frame_ms, r.setting.clone()))
    };
    let modes = names
        .iter()
        .map(|&m| {
            let db = first(m, &|r| r.psnr_db >= TARGET_PSNR_DB);
            let px = first(m, &|r| r.sse_mean_px <= TARGET_SSE_PX);
            let within = || rows_of(rows, m).filter(|r| r.frame_ms <= budget);
            ModeSummary {
                mode: m.to_string(),
                display: super::figures::display(m).to_string(),
                ms_to_30db: db.as_ref().map(|d| d.0),
                setting_30db: db.map(|d| d.1),
                ms_to_1px: px.as_ref().map(|d| d.0),
                setting_1px: px.map(|d| d.1),
                psnr_at_budget_db: within()
                    .map(|r| r.psnr_db.min(PSNR_CAP_DB))
                    .reduce(f64::max),
                sse_at_budget_px: within().map(|r| r.sse_mean_px).reduce(f64::min),
                fastest_ms: fastest(m),
            }
        })
        .collect();
    Summary {
        budget_ms: budget,
        modes,
        dominance: dominance(rows),
    }
}

/// The summary as a Markdown table (for `summary.md` and the README).
pub fn summary_markdown(title: &str, s: &Summary) -> String {
    let opt = |v: Option<f64>, d: usize, unit: &str| match v {
        Some(v) => format!("{v:.d$} {unit}"),
        None => "not reached".into(),
    };
    let mut out = format!(
        "### {title}\n\n| mode | frame time to 30 dB | frame time to 1 px mean error | PSNR at {b:.1} ms | mean error at {b:.1} ms |\n|---|---|---|---|---|\n",
        b = s.budget_ms
    );
    for m in &s.modes {
        let with = |v: Option<f64>, set: &Option<String>| match (v, set) {
            (Some(v), Some(set)) => format!("{v:.1} ms ({set})"),
            _ => "not reached".into(),
        };
        let _ = writeln!(
            out,
            "| {} | {} | {} | {} | {} |",
            m.mode,
            with(m.ms_to_30db, &m.setting_30db),
            with(m.ms_to_1px, &m.setting_1px),
            opt(m.psnr_at_budget_db, 1, "dB"),
            opt(m.sse_at_budget_px, 2, "px"),
        );
    }
    if let Some(d) = &s.dominance {
        let _ = write!(
            out,
            "\nWarped against GeoMipMap, row by row: {} of {} GeoMipMap rows have a warped row with \
             no more triangles and no more mean screen-space error; {} of {} one with no more \
             frame time and no less PSNR.\n",
            d.matched_on_triangles, d.geomipmap_rows, d.matched_on_time, d.geomipmap_rows
        );
        if let Some(n) = &d.need {
            let _ = writeln!(
                out,
                "Triangles warped needs for each GeoMipMap row's error, between its rows \
                 (log-log), as a multiple of the row's: {:.2}–{:.2}×, geometric mean {:.3} over \
                 {} rows.",
                n.least, n.greatest, n.geometric_mean, n.rows
            );
        }
        for m in &d.misses {
            let best = m
                .warped_sse_px
                .map_or("no warped row has so few".into(), |e| {
                    format!("warped's best {e:.2} px")
                });
            let needed = m.warped_triangles_needed.map_or(
                "; no warped row has as little error".into(),
                |t| {
                    format!(
                        "; warped reaches it at {t} triangles ({:.2}×)",
                        t as f64 / m.triangles.max(1) as f64
                    )
                },
            );
            let between = m.warped_triangles_interpolated.map_or(String::new(), |t| {
                format!(
                    "; between its rows, at {t:.0} ({:.2}×)",
                    t / m.triangles.max(1) as f64
                )
            });
            let _ = writeln!(
                out,
                "- {}: {} triangles at {:.2} px; {best}{needed}{between}",
                m.setting, m.triangles, m.sse_mean_px
            );
        }
        if !d.time_misses.is_empty() {
            out.push_str("\nMissed on frame time and PSNR:\n");
        }
        for m in &d.time_misses {
            let _ = writeln!(out, "{}", time_miss_line(m));
        }
    }
    out
}

/// One line of `summary.md` for a row missed on frame time and PSNR.
fn time_miss_line(m: &TimeMiss) -> String {
    let needed = m
        .warped_as_good
        .as_ref()
        .map_or("no warped row has as much PSNR".into(), |w| {
            let spread = match w.within_spread {
                Some(true) => ", the two rows' frame times' interquartile ranges overlap",
                Some(false) => ", beyond the two rows' interquartile ranges",
                None => "",
            };
            format!(
                "warped's fastest with as much PSNR, {}, takes {:.2} ms ({:.3}×){spread}",
                w.setting, w.frame_ms, w.time_ratio
            )
        });
    let within = m
        .warped_psnr_within_db
        .map_or("no warped row is as fast".into(), |db| {
            format!("warped's best within its time {db:.2} dB")
        });
    let parts = |s: &FrameSplit| {
        format!(
            "{:.2} + {:.2} + {:.2} ms",
            s.cpu_ms, s.other_passes_ms, s.terrain_ms
        )
    };
    let split = match (
        m.warped_as_good.as_ref().and_then(|w| w.split.as_ref()),
        &m.split,
    ) {
        (Some(w), Some(g)) => format!(
            "; CPU stage + other GPU passes + terrain pass: warped {}, GeoMipMap {}",
            parts(w),
            parts(g)
        ),
        _ => String::new(),
    };
    format!(
        "- {}: {:.2} dB at {:.2} ms; {needed}; {within}{split}",
        m.setting, m.psnr_db, m.frame_ms
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::eval::compare::report::tests::row;
    use terrain_engine::PassTimes;

    #[test]
    fn summary_finds_times_to_targets_and_errors_at_the_common_budget() {
        let rows = vec![
            row("a", 10.0, 25.0, 2.0),
            row("a", 20.0, 31.0, 0.5),
            row("b", 15.0, 24.0, 3.0),
            row("b", 40.0, 29.0, 0.9),
        ];
        let s = summarise(&rows);
        assert_eq!(s.budget_ms, 15.0);
        let (a, b) = (&s.modes[0], &s.modes[1]);
        assert_eq!((a.ms_to_30db, a.ms_to_1px), (Some(20.0), Some(20.0)));
        assert_eq!((b.ms_to_30db, b.ms_to_1px), (None, Some(40.0)));
        assert_eq!(
            (a.psnr_at_budget_db, b.psnr_at_budget_db),
            (Some(25.0), Some(24.0))
        );
        let md = summary_markdown("t", &s);
        assert!(
            md.contains("not reached") && md.contains("| a | 20.0 ms (20)"),
            "{md}"
        );
        assert!(s.dominance.is_none(), "no warped or GeoMipMap rows");
    }

    /// Each GeoMipMap row is matched only by a warped row at or below its triangles (or frame
    /// time) with at most its error (or at least its PSNR); the misses name the best warped error
    /// within the row's triangles.
    #[test]
    fn dominance_matches_each_geomipmap_row_by_a_cheaper_warped_row() {
        let at = |mode: &str, triangles: u64, ms: f64, db: f64, px: f64| Row {
            triangles,
            ..row(mode, ms, db, px)
        };
        let rows = vec![
            at("warped", 1000, 10.0, 25.0, 1.0),
            at("warped", 4000, 20.0, 30.0, 0.5),
            // Matched by the 1000-triangle row on both counts.
            at("geomipmap", 1500, 12.0, 24.0, 1.2),
            // Less error than any warped row with as few triangles (0.5 px needs 4000), and
            // faster than every warped row as good.
            at("geomipmap", 3000, 15.0, 28.0, 0.8),
            // Fewer triangles than any warped row.
            at("geomipmap", 500, 30.0, 20.0, 2.0),
        ];
        let d = dominance(&rows).unwrap();
        assert_eq!(
            (d.geomipmap_rows, d.matched_on_triangles, d.matched_on_time),
            (3, 1, 2)
        );
        let misses: Vec<_> = d
            .misses
            .iter()
            .map(|m| (m.triangles, m.warped_sse_px, m.warped_triangles_needed))
            .collect();
        // The 3000-triangle row's 0.8 px takes warped 4000 triangles; the 500-triangle row's
        // 2.0 px, 1000.
        assert_eq!(
            misses,
            [(3000, Some(1.0), Some(4000)), (500, None, Some(1000))]
        );
        let md = summary_markdown("t", &summarise(&rows));
        assert!(md.contains("1 of 3 GeoMipMap rows"), "{md}");
        assert!(md.contains("no warped row has so few"), "{md}");
        assert!(md.contains("at 4000 triangles (1.33×)"), "{md}");
        // Between the rungs: 0.8 px lies 0.32 of the way from 1 to 0.5 px in log, so at
        // 1000·4^0.32 triangles; the 500-triangle row's 2 px, below warped's first row: none.
        let between: Vec<_> = d
            .misses
            .iter()
            .map(|m| m.warped_triangles_interpolated)
            .collect();
        let t = between[0].expect("interpolated");
        assert!((t - 1562.5).abs() < 0.5, "{t}");
        assert_eq!(between[1], None);
        assert!(
            md.contains("between its rows, at 156") && md.contains("(0.52×)"),
            "{md}"
        );
        // Every row's need: 1000/1500 (warped's fewest row already as good), 1562.5/3000,
        // 1000/500.
        let n = d.need.as_ref().expect("a need");
        let want = (1000.0 / 1500.0 * 1562.5 / 3000.0 * 2.0f64).powf(1.0 / 3.0);
        assert_eq!(n.rows, 3);
        assert!(
            (n.least - 1562.5 / 3000.0).abs() < 1e-4 && n.greatest == 2.0,
            "{n:?}"
        );
        assert!(
            (n.geometric_mean - want).abs() < 1e-4,
            "{n:?} against {want}"
        );
        assert!(
            md.contains("0.52–2.00×, geometric mean 0.886 over 3 rows"),
            "{md}"
        );
    }

    /// A row missed on frame time and PSNR names warped's fastest row with as much PSNR, by how
    /// much it is slower, warped's best PSNR within the row's time, and whether the two rows'
    /// interquartile ranges of frame time overlap.
    #[test]
    fn time_misses_say_by_how_much_and_whether_the_spread_covers_it() {
        let at = |mode: &str, ms: f64, db: f64, quartiles: (f64, f64)| Row {
            frame_ms_p25: Some(quartiles.0),
            frame_ms_p75: Some(quartiles.1),
            ..row(mode, ms, db, 1.0)
        };
        let rows = vec![
            at("warped", 10.0, 25.0, (9.5, 10.5)),
            at("warped", 20.4, 30.0, (19.8, 21.0)),
            at("warped", 30.0, 31.0, (29.0, 31.0)),
            // 30 dB takes warped 20.4 ms, 1.02×; the quartiles overlap.
            at("geomipmap", 20.0, 29.5, (19.0, 20.5)),
            // 31 dB takes warped 30 ms, 2×; apart.
            at("geomipmap", 15.0, 30.5, (14.5, 15.5)),
            // Faster than any warped row, and more PSNR than any.
            at("geomipmap", 5.0, 40.0, (4.0, 6.0)),
            // Matched: warped's 10 ms row has as much.
            at("geomipmap", 12.0, 24.0, (11.0, 13.0)),
        ];
        let d = dominance(&rows).unwrap();
        assert_eq!(d.matched_on_time, 1);
        let got: Vec<_> = d
            .time_misses
            .iter()
            .map(|m| {
                let w = m.warped_as_good.as_ref();
                (
                    m.frame_ms,
                    w.map(|w| w.frame_ms),
                    w.map(|w| (w.time_ratio * 1000.0).round() / 1000.0),
                    m.warped_psnr_within_db,
                    w.and_then(|w| w.within_spread),
                )
            })
            .collect();
        assert_eq!(
            got,
            [
                (20.0, Some(20.4), Some(1.02), Some(25.0), Some(true)),
                (15.0, Some(30.0), Some(2.0), Some(25.0), Some(false)),
                (5.0, None, None, None, None),
            ]
        );
        let md = summary_markdown("t", &summarise(&rows));
        assert!(md.contains("Missed on frame time and PSNR:"), "{md}");
        assert!(
            md.contains("takes 20.40 ms (1.020×), the two rows' frame times' interquartile ranges overlap; warped's best within its time 25.00 dB"),
            "{md}"
        );
        assert!(md.contains("(2.000×), beyond the two rows'"), "{md}");
        assert!(
            md.contains("no warped row has as much PSNR; no warped row is as fast"),
            "{md}"
        );
        // Rows without pass times (no timestamp queries) split nothing.
        assert!(d.time_misses.iter().all(|m| m.split.is_none()), "{md}");
        assert!(!md.contains("terrain pass"), "{md}");
        // A report without quartiles (written before they were kept) cannot tell.
        let old: Vec<Row> = rows
            .iter()
            .map(|r| Row {
                frame_ms_p25: None,
                frame_ms_p75: None,
                ..r.clone()
            })
            .collect();
        let d = dominance(&old).unwrap();
        let spread = |m: &TimeMiss| m.warped_as_good.as_ref().and_then(|w| w.within_spread);
        assert!(d.time_misses.iter().all(|m| spread(m).is_none()));
    }

    /// A miss at the frame's floor: warped's terrain pass is no slower than GeoMipMap's, and
    /// the split shows that its CPU stage and compute passes make the miss.
    #[test]
    fn a_time_miss_shows_where_each_rows_frame_goes() {
        let timed =
            |mode: &str, ms: f64, db: f64, cpu_us: f64, passes: &[(&'static str, f64)]| Row {
                cpu_stage_us: cpu_us,
                passes_ms: PassTimes(passes.iter().map(|&(n, ms)| (n.into(), ms)).collect()),
                ..row(mode, ms, db, 1.0)
            };
        let warped_passes = [
            ("warp_zoom", 0.16),
            ("mesh_split", 0.05),
            ("normals", 0.04),
            ("terrain", 21.97),
        ];
        let rows = vec![
            timed("warped", 22.53, 60.3, 304.0, &warped_passes),
            timed("geomipmap", 22.02, 59.3, 23.0, &[("terrain", 22.0)]),
        ];
        let d = dominance(&rows).unwrap();
        let [m] = &d.time_misses[..] else {
            panic!("one miss: {:?}", d.time_misses)
        };
        let w = m.warped_as_good.as_ref().unwrap();
        let close = |s: &FrameSplit, want: [f64; 3]| {
            let got = [s.cpu_ms, s.other_passes_ms, s.terrain_ms];
            got.iter().zip(want).all(|(g, w)| (g - w).abs() < 1e-9)
        };
        let ws = w.split.as_ref().unwrap();
        assert!(close(ws, [0.304, 0.25, 21.97]), "{ws:?}");
        let gs = m.split.as_ref().unwrap();
        assert!(close(gs, [0.023, 0.0, 22.0]), "{gs:?}");
        let md = summary_markdown("t", &summarise(&rows));
        assert!(
            md.contains(
                "; CPU stage + other GPU passes + terrain pass: warped 0.30 + 0.25 + 21.97 ms, \
                 GeoMipMap 0.02 + 0.00 + 22.00 ms"
            ),
            "{md}"
        );
        let json = serde_json::to_value(&d).unwrap();
        assert_eq!(json["time_misses"][0]["split"]["terrain_ms"], 22.0);
        assert_eq!(
            json["time_misses"][0]["warped_as_good"]["split"]["cpu_ms"],
            0.304
        );
    }

    /// The interpolation follows warped's front: a row with more triangles and more error than
    /// one before it is passed over, and an error below every row's has no answer.
    #[test]
    fn the_interpolated_triangles_follow_the_front() {
        let at = |triangles: u64, px: f64| Row {
            triangles,
            ..row("warped", 1.0, 30.0, px)
        };
        let rows = [at(100, 2.0), at(400, 1.0), at(800, 1.5), at(1600, 0.25)];
        let warped: Vec<&Row> = rows.iter().collect();
        // 0.5 px: half-way in log between 1 px at 400 and 0.25 px at 1600: 800 triangles (the
        // 800-triangle row's 1.5 px is not on the front; taken, it would give another answer).
        let t = interpolated_triangles(&warped, 0.5).expect("on the front");
        assert!((t - 800.0).abs() < 1e-6, "{t}");
        let t = interpolated_triangles(&warped, 1.0).expect("a row's own error");
        assert!((t - 400.0).abs() < 1e-6, "{t}");
        assert_eq!(interpolated_triangles(&warped, 0.1), None);
        assert_eq!(interpolated_triangles(&warped, 3.0), None);
    }
}
