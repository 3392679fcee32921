//! The acceptance summary (`summary.md`): per mode, the least frame time reaching the targets
//! ([`TARGET_PSNR_DB`], [`TARGET_SSE_PX`]), and each mode's best error at the common budget — the
//! slowest of the modes' fastest rows, so every mode has a row within it.

use super::report::{PSNR_CAP_DB, Row, TARGET_PSNR_DB, TARGET_SSE_PX};
use serde::Serialize;
use std::fmt::Write;

#[derive(Clone, Debug, Serialize)]
pub struct ModeSummary {
    pub mode: String,
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
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::eval::compare::report::tests::row;

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
    }
}
