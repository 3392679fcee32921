//! `scripts/evaluate.sh` and docs/evaluation.md name the same tables, and a table the script
//! prints carries the figures of the command it runs: the density ratio of every bundled view,
//! against `terrain warp --json` of the same scene and method.

mod common;

use common::{manifest_dir, scratch, terrain};
use std::collections::BTreeSet;
use std::process::Command;

fn script() -> std::path::PathBuf {
    manifest_dir().join("scripts/evaluate.sh")
}

/// The script's output, panicking with its stderr when it fails.
fn evaluate(args: &[&str]) -> String {
    let out = Command::new("bash")
        .arg(script())
        .args(args)
        .current_dir(manifest_dir())
        .output()
        .expect("run scripts/evaluate.sh");
    assert!(
        out.status.success(),
        "scripts/evaluate.sh {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).expect("UTF-8")
}

/// Every `scripts/evaluate.sh NAME` the text names (NAME in lower-case kebab case: not
/// `--list`, not a placeholder).
fn names_in(text: &str) -> BTreeSet<String> {
    const CALL: &str = "scripts/evaluate.sh ";
    text.match_indices(CALL)
        .map(|(i, _)| {
            text[i + CALL.len()..]
                .chars()
                .take_while(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || *c == '-')
                .collect::<String>()
        })
        .filter(|n| n.starts_with(|c: char| c.is_ascii_lowercase()))
        .collect()
}

#[test]
fn the_script_and_the_report_name_the_same_tables() {
    let listed: BTreeSet<String> = evaluate(&["--list"])
        .lines()
        .filter_map(|l| l.split_whitespace().next())
        .map(str::to_owned)
        .collect();
    assert!(listed.len() >= 20, "--list names {} tables", listed.len());
    let doc = std::fs::read_to_string(manifest_dir().join("docs/evaluation.md")).unwrap();
    let named = names_in(&doc);
    let unnamed: Vec<_> = listed.difference(&named).collect();
    assert!(
        unnamed.is_empty(),
        "docs/evaluation.md heads no table with `scripts/evaluate.sh NAME` for {unnamed:?}"
    );
    let unlisted: Vec<_> = named.difference(&listed).collect();
    assert!(
        unlisted.is_empty(),
        "docs/evaluation.md names tables the script does not list: {unlisted:?}"
    );
    // Each table's header line in the report gives a date and a commit.
    for name in &listed {
        let at = doc
            .find(&format!("*{name}: "))
            .unwrap_or_else(|| panic!("no header line `*{name}: …` in docs/evaluation.md"));
        let header = &doc[at..at + doc[at + 1..].find('*').unwrap() + 2];
        assert!(
            header.contains("commit") && header.contains("2026-"),
            "{name}'s header gives no date or commit: {header}"
        );
    }
}

fn jq_missing() -> bool {
    Command::new("jq").arg("--version").output().is_err()
}

/// A Markdown table's body rows, as trimmed cells.
fn table_rows(text: &str) -> Vec<Vec<String>> {
    let lines: Vec<&str> = text.lines().filter(|l| l.starts_with('|')).collect();
    assert!(lines.len() >= 3, "no Markdown table in:\n{text}");
    assert!(
        lines[1].split('|').all(|c| c.is_empty() || c == "---"),
        "the second line is not a separator: {}",
        lines[1]
    );
    let width = lines[0].matches('|').count();
    lines[2..]
        .iter()
        .map(|l| {
            assert_eq!(l.matches('|').count(), width, "a ragged row: {l}");
            l.trim_matches('|')
                .split('|')
                .map(|c| c.trim().to_owned())
                .collect()
        })
        .collect()
}

#[test]
fn the_density_ratio_table_gives_terrain_warps_figures() {
    if jq_missing() {
        eprintln!("skipped: jq is not on the PATH (scripts/evaluate.sh needs it)");
        return;
    }
    let out = scratch("evaluate-density-ratio");
    let bin = env!("CARGO_BIN_EXE_terrain");
    let table = evaluate(&[
        "--bin",
        bin,
        "--out",
        out.to_str().unwrap(),
        "density-ratio",
    ]);
    assert!(
        table.contains("`scripts/evaluate.sh density-ratio`"),
        "no header line naming the table:\n{table}"
    );
    let rows = table_rows(&table);
    assert_eq!(rows.len(), 12, "six views, two methods:\n{table}");
    for row in &rows {
        let (scene, method) = (&row[0], &row[1]);
        let dir = out.join("check").join(format!("{scene}-{method}"));
        let (code, json, err) = terrain(&[
            "warp",
            &format!("sketches/{scene}.toml"),
            "--out-dir",
            dir.to_str().unwrap(),
            "--method",
            method,
            "--no-figures",
            "--json",
        ]);
        assert_eq!(code, 0, "terrain warp {scene} {method}: {err}");
        let w: serde_json::Value = serde_json::from_str(&json).unwrap();
        let f = |k: &str| w[k].as_f64().unwrap_or_else(|| panic!("{k} in {json}"));
        // The script rounds half away from zero, Rust's formatting half to even: compare the
        // figures within half a unit of the last digit printed.
        let near = |cell: &str, value: f64, half_unit: f64| {
            let printed: f64 = cell
                .trim_end_matches(" %")
                .parse()
                .unwrap_or_else(|_| panic!("{scene} {method}: {cell:?} is not a number"));
            assert!(
                (printed - value).abs() <= half_unit + 1e-9,
                "{scene} {method}: the table reads {cell}, terrain warp gives {value}"
            );
        };
        assert_eq!(
            row[2],
            w["cells_visible"].to_string(),
            "{scene} {method}: cells"
        );
        near(&row[3], f("demand_met"), 0.0005);
        near(&row[4], 100.0 * f("ratio_within_0_5_2"), 0.05);
        near(&row[5], 100.0 * f("ratio_within_0_5_1"), 0.05);
        assert_eq!(
            row[6],
            w["flipped_cells"].to_string(),
            "{scene} {method}: flipped"
        );
        let guarded = if method == "plain" {
            "—".to_owned()
        } else {
            w["guarded_columns"].to_string()
        };
        assert_eq!(row[7], guarded, "{scene} {method}: guarded columns");
    }
}
