//! docs/batch.md's Slurm array job, run as written on a single-node Slurm
//! (`scripts/slurm-single-node.sh`): four shards submitted with `sbatch`, run by Slurm, merged by
//! the dependent job the page's comment gives; the merged manifest and every image equal a
//! one-machine `terrain batch` of the same jobs file. The one change to the page's text is the
//! output folder: `/shared/snapshots` becomes this test's scratch folder.
//!
//! Manifests are compared with the measured fields left out (`cpu_stage_us`, `gpu_ms`,
//! `frame_ms`, `seconds`: timings, which no two runs share) and `shard` (which names where an
//! item ran); every other field, and the order of the lines, must be equal.
//!
//! Own harness (libtest-mimic), like tests/view.rs: without slurm-wlm and munge, or not as root,
//! the test reports itself skipped with the reason; where `TERRAIN_REQUIRE_SLURM_TESTS` is set
//! (`.ci/run` sets it) it fails instead.

mod common;
use common::*;
use libtest_mimic::Arguments;
use std::path::{Path, PathBuf};
use std::process::Command;

fn main() {
    let args = Arguments::from_args();
    let trial = skippable_trial(
        "the_documented_slurm_array_job_merges_to_the_one_machine_batch",
        slurm_array_job,
        missing(),
        "TERRAIN_REQUIRE_SLURM_TESTS",
    );
    libtest_mimic::run(&args, vec![trial]).exit();
}

/// Why the test cannot run here, if it cannot.
fn missing() -> Option<String> {
    let absent: Vec<&str> = ["sbatch", "slurmctld", "slurmd", "munged", "sinfo"]
        .into_iter()
        .filter(|t| {
            !Command::new("sh")
                .args(["-c", &format!("command -v {t}")])
                .output()
                .is_ok_and(|o| o.status.success())
        })
        .collect();
    if !absent.is_empty() {
        return Some(format!(
            "{} not installed (Debian: apt-get install slurm-wlm munge)",
            absent.join(", ")
        ));
    }
    let root = Command::new("id")
        .arg("-u")
        .output()
        .is_ok_and(|o| o.stdout.trim_ascii() == b"0");
    (!root).then(|| "the single-node cluster's daemons need root".into())
}

/// Stops the cluster however the test ends.
struct Cluster(PathBuf);

impl Drop for Cluster {
    fn drop(&mut self) {
        let _ = Command::new(manifest_dir().join("scripts/slurm-single-node.sh"))
            .arg("stop")
            .arg(&self.0)
            .status();
    }
}

/// docs/batch.md's array script and its merge command, out of the page's text.
fn documented_slurm() -> (String, String) {
    let page = std::fs::read_to_string(manifest_dir().join("docs/batch.md")).unwrap();
    let after = page
        .split("A Slurm array job:")
        .nth(1)
        .expect("docs/batch.md has a Slurm array job");
    let block = after
        .split("```sh\n")
        .nth(1)
        .and_then(|b| b.split("```").next())
        .expect("a ```sh block after it");
    let merge = block
        .split("# afterwards: ")
        .nth(1)
        .expect("the script says what to run afterwards")
        .lines()
        .map(|l| {
            l.trim_start_matches('#')
                .trim()
                .trim_end_matches('\\')
                .trim()
        })
        .collect::<Vec<_>>()
        .join(" ");
    (block.to_string(), merge)
}

fn slurm_array_job() {
    // A cluster left by an aborted run of this test is stopped before its folder is emptied.
    drop(Cluster(
        manifest_dir().join("target/test-scratch/slurm/cluster"),
    ));
    let dir = scratch("slurm");
    std::fs::write(
        dir.join("base.toml"),
        "[sketch]\nsynthetic = \"hills\"\n\n[camera]\nposition = [500.0, 300.0, 900.0]\nlook_at = [3800.0, 4000.0, 200.0]\nwidth = 32\nheight = 32\n\n[warp]\nmesh = 64\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("jobs.toml"),
        "scene = \"base.toml\"\n[random]\ncount = 9\nseed = 5\n\n[[job]]\nname = \"given\"\ncamera = { position = [2000.0, 500.0, 800.0], look_at = [2000.0, 3000.0, 100.0] }\nrender = { mode = \"geomipmap\" }\n",
    )
    .unwrap();
    let snapshots = dir.join("snapshots");
    let (script, merge) = documented_slurm();
    let here = |text: &str| text.replace("/shared/snapshots", snapshots.to_str().unwrap());
    std::fs::write(dir.join("array.sh"), here(&script)).unwrap();

    let cluster = Cluster(dir.join("cluster"));
    let up = Command::new(manifest_dir().join("scripts/slurm-single-node.sh"))
        .arg("start")
        .arg(&cluster.0)
        .output()
        .unwrap();
    assert!(
        up.status.success(),
        "cluster: {}",
        String::from_utf8_lossy(&up.stderr)
    );
    // Slurm's jobs inherit the submitter's environment: `terrain` on the PATH, as docs/batch.md assumes.
    let bin = PathBuf::from(env!("CARGO_BIN_EXE_terrain"));
    let path = format!(
        "{}:{}",
        bin.parent().unwrap().display(),
        std::env::var("PATH").unwrap_or_default()
    );
    let sh = |command: &str| {
        let out = Command::new("bash")
            .args(["-c", command])
            .current_dir(&dir)
            .env("SLURM_CONF", cluster.0.join("slurm.conf"))
            .env("PATH", &path)
            .env("TERRAIN_QUIET", "1")
            .output()
            .unwrap();
        let text = String::from_utf8_lossy(&out.stdout).trim().to_string();
        assert!(
            out.status.success(),
            "`{command}`: {text} {}",
            String::from_utf8_lossy(&out.stderr)
        );
        text
    };
    let array = sh("sbatch --parsable array.sh");
    let array_id = array.split(';').next().unwrap().to_string();
    // The page's merge job, waited for: it runs once every shard has finished well, and is
    // cancelled (failing this test rather than hanging it) if one failed.
    let merge = here(&merge).replace("<array job id>", &array_id).replacen(
        "sbatch ",
        "sbatch --wait --parsable ",
        1,
    );
    sh(&merge);

    // Four array tasks ran under Slurm, each writing its shard's manifest.
    for i in 0..4 {
        let log = dir.join(format!("slurm-{array_id}_{i}.out"));
        assert!(log.exists(), "no Slurm output of array task {i}");
        assert!(
            snapshots.join(format!("manifest-{i}-of-4.jsonl")).exists(),
            "shard {i} wrote no manifest"
        );
    }
    let single = dir.join("single");
    let (code, _, err) = terrain(&[
        "batch",
        dir.join("jobs.toml").to_str().unwrap(),
        "--out-dir",
        single.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(
        comparable(&snapshots.join("manifest.jsonl")),
        comparable(&single.join("manifest.jsonl")),
        "the merged manifest differs from the one-machine run's"
    );
    let names = pngs(&single);
    assert_eq!(names.len(), 10);
    assert_eq!(names, pngs(&snapshots), "images differ");
    drop(cluster);
}

/// Manifest lines without the measured fields, in order.
fn comparable(path: &Path) -> Vec<serde_json::Value> {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .map(|l| {
            let mut v: serde_json::Value = serde_json::from_str(l).unwrap();
            let o = v.as_object_mut().unwrap();
            for k in ["cpu_stage_us", "gpu_ms", "frame_ms", "seconds", "shard"] {
                assert!(o.remove(k).is_some(), "manifest line without {k}: {l}");
            }
            v
        })
        .collect()
}
