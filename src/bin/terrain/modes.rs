//! `terrain modes`: the level-of-detail modes as the mode table holds them (`scene::MODES`), for
//! a user choosing `--mode` and for scripts that run every mode a scene draws
//! (`scripts/gpu-bench.sh`).

use anyhow::Result;
use serde::Serialize;
use terrain_engine::scene::{MODES, ModeRow, Scenes};

#[derive(clap::Args)]
pub struct Args {
    /// Prints one JSON object on stdout instead of the table: `modes`, a row per mode.
    #[arg(long)]
    json: bool,
}

/// `--json`: every mode, in the table's order.
#[derive(Serialize)]
struct Report {
    modes: Vec<Row>,
}

/// `--json`'s row of one mode.
#[derive(Serialize)]
struct Row {
    /// `render.mode`'s value, `--mode`'s choice.
    name: &'static str,
    /// As the papers write it, in charts and summaries.
    display: &'static str,
    /// `flat`, `planet` or `both`.
    scenes: &'static str,
    /// Whether `compare` runs it by default (the reference is what it measures against).
    compared: bool,
    /// The key that switches `view` and the web page to it.
    key: Option<char>,
    /// The scene keys `compare`'s rows of it set.
    sweep: Vec<&'static str>,
}

impl Row {
    fn of(r: &ModeRow) -> Row {
        Row {
            name: r.mode.name(),
            display: r.display,
            scenes: match r.scenes {
                Scenes::Flat => "flat",
                Scenes::Planet => "planet",
                Scenes::Both => "both",
            },
            compared: r.compared,
            key: r.key,
            sweep: r.sweep.iter().map(|&(key, _)| key).collect(),
        }
    }
}

pub fn run(a: Args) -> Result<()> {
    let rows: Vec<Row> = MODES.iter().map(Row::of).collect();
    if a.json {
        return crate::print_json(&Report { modes: rows });
    }
    outln!(
        "{:<11} {:<19} {:<7} {:<9} {:<4} compare sweeps",
        "mode",
        "name",
        "scenes",
        "compared",
        "key"
    );
    for r in rows {
        let key = r.key.map_or("-".to_string(), String::from);
        let compared = if r.compared { "yes" } else { "no" };
        let sweep = if r.sweep.is_empty() {
            "-".to_string()
        } else {
            r.sweep.join(", ")
        };
        outln!(
            "{:<11} {:<19} {:<7} {:<9} {:<4} {sweep}",
            r.name,
            r.display,
            r.scenes,
            compared,
            key
        );
    }
    Ok(())
}
