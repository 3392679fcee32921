//! `scripts/gpu-bench.sh` (docs/evaluation.md, GPU costs) with `--quick` on whatever adapter the
//! machine has, llvmpipe standing in for a GPU through `--allow-software`: frames.csv holds a row
//! per view, mode and size with its GPU time and a column per pass, and each view keeps its
//! compare's report. Without the flag a software rasteriser is refused in one line, before any
//! output is written.
//!
//! The views are one planar view in its four modes and the planet from orbit in clipmaps and the
//! reference; the full run's nine views would take minutes on llvmpipe.

mod common;

use common::{manifest_dir, scratch};
use std::collections::BTreeSet;
use std::path::Path;
use std::process::{Command, Output};

const SIZES: [(u32, u32); 2] = [(64, 64), (64, 36)];

fn python3_missing() -> bool {
    Command::new("python3").arg("--version").output().is_err()
}

fn bench(out: &Path, args: &[&str]) -> Output {
    Command::new("bash")
        .arg(manifest_dir().join("scripts/gpu-bench.sh"))
        .args(["--quick", "--out", out.to_str().unwrap()])
        .args(args)
        .env("TERRAIN_BIN", env!("CARGO_BIN_EXE_terrain"))
        .output()
        .expect("run scripts/gpu-bench.sh")
}

/// One CSV line's fields; a field in double quotes may hold commas (the adapter's name does).
fn fields(line: &str) -> Vec<String> {
    let mut out = vec![String::new()];
    let mut quoted = false;
    let mut chars = line.chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            '"' if quoted && chars.peek() == Some(&'"') => {
                chars.next();
                out.last_mut().unwrap().push('"');
            }
            '"' => quoted = !quoted,
            ',' if !quoted => out.push(String::new()),
            _ => out.last_mut().unwrap().push(c),
        }
    }
    out
}

fn number(cell: &str, what: &str) -> f64 {
    cell.parse()
        .unwrap_or_else(|_| panic!("{what}: {cell:?} is not a number"))
}

#[test]
fn the_quick_run_writes_a_row_per_view_mode_and_size_and_a_compare_per_view() {
    if python3_missing() {
        eprintln!("skipped: python3 is not on the PATH (scripts/gpu-bench.sh needs it)");
        return;
    }
    let out = scratch("gpu-bench");
    let run = bench(
        &out,
        &["--allow-software", "--scenes", "jacksboro,planet-orbit"],
    );
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(
        run.status.success(),
        "scripts/gpu-bench.sh failed:\n{stdout}\n{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let adapter = stdout
        .lines()
        .next()
        .and_then(|l| l.strip_prefix("adapter: "))
        .unwrap_or_else(|| panic!("the first line names no adapter:\n{stdout}"));
    assert_eq!(
        std::fs::read_to_string(out.join("failures.txt")).unwrap(),
        ""
    );
    let machine = std::fs::read_to_string(out.join("machine.txt")).unwrap();
    assert!(
        machine.contains(&format!("adapter: {adapter}\n")),
        "{machine}"
    );

    let csv = std::fs::read_to_string(out.join("frames.csv")).unwrap();
    let mut all = csv.lines();
    let header = fields(all.next().expect("a header"));
    let lines: Vec<&str> = all.collect();
    let col = |name: &str| {
        header
            .iter()
            .position(|h| h == name)
            .unwrap_or_else(|| panic!("frames.csv has no column {name}: {header:?}"))
    };
    let fixed = [
        "adapter",
        "scene",
        "mode",
        "width",
        "height",
        "samples",
        "triangles",
        "gpu_ms",
        "frame_ms",
        "cpu_stage_us",
    ]
    .map(col);
    let [
        c_adapter,
        c_scene,
        c_mode,
        c_w,
        c_h,
        c_samples,
        c_tris,
        c_gpu,
        c_frame,
        c_cpu,
    ] = fixed;
    let passes: Vec<(usize, &str)> = header
        .iter()
        .enumerate()
        .filter_map(|(i, h)| Some((i, h.strip_prefix("pass_")?.strip_suffix("_ms")?)))
        .collect();
    // Passes are timed where the adapter has timestamp queries (not lavapipe's: see
    // `GpuContext::new`); their counts are in `fragments_per_covered_px` where it counts.
    let c_timing = col("gpu_timing");
    let timed_here = lines
        .iter()
        .any(|l| fields(l)[c_timing] == "timestamp queries");
    for pass in ["warp_zoom", "terrain", "reference", "clipmaps", "planet"] {
        assert!(
            !timed_here || passes.iter().any(|&(_, p)| p == pass),
            "no pass_{pass}_ms column: {header:?}"
        );
    }
    let c_covered = col("covered_px");

    let mut rows = BTreeSet::new();
    for line in lines {
        let f = fields(line);
        assert_eq!(f.len(), header.len(), "{line}");
        let what = format!("{} {} {}x{}", f[c_scene], f[c_mode], f[c_w], f[c_h]);
        assert_eq!(f[c_adapter], adapter, "{what}");
        assert!(number(&f[c_samples], &what) >= 1.0, "{what}: samples");
        assert!(number(&f[c_gpu], &what) > 0.0, "{what}: gpu_ms");
        assert!(
            number(&f[c_frame], &what) >= number(&f[c_gpu], &what),
            "{what}: frame_ms below gpu_ms"
        );
        assert!(number(&f[c_cpu], &what) >= 0.0, "{what}: cpu_stage_us");
        let triangles = number(&f[c_tris], &what);
        assert_eq!(
            triangles > 0.0,
            f[c_mode] != "reference",
            "{what}: triangles"
        );
        let timed: Vec<&str> = passes
            .iter()
            .filter(|&&(i, _)| !f[i].is_empty())
            .map(|&(i, p)| {
                assert!(number(&f[i], &what) > 0.0, "{what}: pass {p}");
                p
            })
            .collect();
        let drawn = match f[c_mode].as_str() {
            "reference" => "reference",
            "clipmaps" => "planet",
            _ => "terrain",
        };
        if f[c_timing] == "timestamp queries" {
            assert!(timed.contains(&drawn), "{what}: passes {timed:?}");
        }
        let covered = number(&f[c_covered], &what);
        assert!(covered > 0.0 && covered <= number(&f[c_w], &what) * number(&f[c_h], &what));
        let key = (
            f[c_scene].clone(),
            f[c_mode].clone(),
            number(&f[c_w], &what) as u32,
            number(&f[c_h], &what) as u32,
        );
        assert!(rows.insert(key), "{what} twice");
    }
    let mut expected = BTreeSet::new();
    for (scene, modes) in [
        (
            "jacksboro",
            &["warped", "geomipmap", "bruteforce", "reference"][..],
        ),
        ("planet-orbit", &["clipmaps", "reference"][..]),
    ] {
        for mode in modes {
            for (w, h) in SIZES {
                expected.insert((scene.to_string(), mode.to_string(), w, h));
            }
        }
    }
    assert_eq!(rows, expected);

    for (view, mode) in [("jacksboro", "warped"), ("planet-orbit", "clipmaps")] {
        let report = out.join("compare").join(view).join("report.csv");
        let text = std::fs::read_to_string(&report)
            .unwrap_or_else(|e| panic!("{}: {e}", report.display()));
        assert!(text.starts_with("mode,setting,"), "{}", report.display());
        assert!(
            text.lines()
                .skip(1)
                .any(|l| l.starts_with(&format!("{mode},"))),
            "{} has no {mode} row",
            report.display()
        );
    }
}

#[test]
fn a_software_rasteriser_is_refused_in_one_line_without_allow_software() {
    if python3_missing() {
        eprintln!("skipped: python3 is not on the PATH (scripts/gpu-bench.sh needs it)");
        return;
    }
    let out = scratch("gpu-bench-refused");
    let run = bench(&out, &["--scenes", "jacksboro", "--sizes", "64x64"]);
    let stdout = String::from_utf8_lossy(&run.stdout);
    let stderr = String::from_utf8_lossy(&run.stderr);
    let adapter = stdout
        .lines()
        .next()
        .and_then(|l| l.strip_prefix("adapter: "))
        .unwrap_or_else(|| panic!("the first line names no adapter:\n{stdout}\n{stderr}"))
        .to_lowercase();
    let software = ["llvmpipe", "lavapipe", "softpipe", "swiftshader"]
        .iter()
        .any(|s| adapter.contains(s));
    if !software {
        // A GPU: the run goes ahead.
        assert!(run.status.success(), "{stdout}\n{stderr}");
        return;
    }
    assert_eq!(run.status.code(), Some(1), "{stdout}\n{stderr}");
    assert_eq!(stderr.trim().lines().count(), 1, "{stderr}");
    assert!(
        stderr.contains("software rasteriser") && stderr.contains("--allow-software"),
        "{stderr}"
    );
    assert_eq!(
        std::fs::read_dir(&out).unwrap().count(),
        0,
        "output written"
    );
}
