//! The jobs users run unattended: `fly` along a path (frames, animation, CSV) and `batch`
//! (shards that together are the whole batch, byte for byte; a killed batch resumed with nothing
//! lost or listed twice; bad jobs failing alone with their cause).

mod common;
use common::*;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// A small, quick base scene over the synthetic hills.
fn base_scene(dir: &Path, size: u32) -> PathBuf {
    let path = dir.join("base.toml");
    std::fs::write(
        &path,
        format!(
            "[sketch]\nsynthetic = \"hills\"\n\n[camera]\nposition = [500.0, 300.0, 900.0]\nlook_at = [3800.0, 4000.0, 200.0]\nwidth = {size}\nheight = {size}\n\n[detail]\namplitude_m = 8.0\ngain = 0.45\n\n[warp]\nmesh = 128\n"
        ),
    )
    .unwrap();
    path
}

fn jobs_file(dir: &Path, body: &str) -> PathBuf {
    let path = dir.join("jobs.toml");
    std::fs::write(&path, format!("scene = \"base.toml\"\n{body}")).unwrap();
    path
}

fn manifest(path: &Path) -> Vec<serde_json::Value> {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap_or_else(|e| panic!("{e}: {l}")))
        .collect()
}

#[test]
fn fly_writes_frames_animation_and_csv_along_the_path() {
    let dir = scratch("fly");
    let scene = dir.join("path.toml");
    std::fs::write(
        &scene,
        "[sketch]\nsynthetic = \"hills\"\n[camera]\nposition = [500.0, 300.0, 900.0]\nlook_at = [3800.0, 4000.0, 200.0]\nwidth = 40\nheight = 32\n[warp]\nmesh = 128\n[path]\nspeed_mps = 200.0\nkeys = [\n  { position = [1000.0, 1000.0, 700.0], look_at = [4000.0, 4000.0, 100.0] },\n  { position = [2000.0, 1500.0, 650.0] },\n  { position = [3000.0, 1200.0, 700.0] },\n]\n",
    )
    .unwrap();
    let out = dir.join("out");
    let (code, stdout, err) = terrain(&[
        "fly",
        scene.to_str().unwrap(),
        "--out-dir",
        out.to_str().unwrap(),
        "--frames",
        "7",
        "--fps",
        "10",
        "--no-mp4",
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(
        stdout.contains("7 frames") && stdout.contains("p95/median"),
        "{stdout}"
    );
    for k in 0..7 {
        assert!(out.join(format!("frame-{k:05}.png")).is_file(), "frame {k}");
    }
    let decoder = png::Decoder::new(std::io::BufReader::new(
        std::fs::File::open(out.join("animation.png")).unwrap(),
    ));
    let reader = decoder.read_info().unwrap();
    assert_eq!(
        reader.info().animation_control().map(|a| a.num_frames),
        Some(7)
    );
    assert_eq!((reader.info().width, reader.info().height), (40, 32));

    let csv = std::fs::read_to_string(out.join("frames.csv")).unwrap();
    let rows: Vec<Vec<f64>> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').take(9).map(|c| c.parse().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), 7);
    // The path starts and ends at its keys, and frames are equal distances apart.
    let eye = |r: &Vec<f64>| glam::DVec3::new(r[2], r[3], r[4]);
    assert!((eye(&rows[0]) - glam::DVec3::new(1000.0, 1000.0, 700.0)).length() < 0.5);
    assert!((eye(&rows[6]) - glam::DVec3::new(3000.0, 1200.0, 700.0)).length() < 0.5);
    let steps: Vec<f64> = rows
        .windows(2)
        .map(|w| (eye(&w[1]) - eye(&w[0])).length())
        .collect();
    let (lo, hi) = steps
        .iter()
        .fold((f64::MAX, 0.0f64), |(a, b), &s| (a.min(s), b.max(s)));
    assert!(hi / lo < 1.05, "frame steps {steps:?}");
    for r in &rows {
        assert!(r[7] > 0.0 && r[8] > 0.0, "frame time and triangles: {r:?}");
    }
}

#[test]
fn shards_together_are_the_whole_batch_byte_for_byte() {
    let dir = scratch("batch-shards");
    base_scene(&dir, 32);
    let jobs = jobs_file(
        &dir,
        "[random]\ncount = 10\nseed = 3\n\n[[job]]\nname = \"given\"\ncamera = { position = [2000.0, 500.0, 800.0], look_at = [2000.0, 3000.0, 100.0] }\n",
    );
    let whole = dir.join("whole");
    let (code, _, err) = terrain(&[
        "batch",
        jobs.to_str().unwrap(),
        "--out-dir",
        whole.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    let sharded = dir.join("sharded");
    for i in 0..4 {
        let shard = format!("{i}/4");
        let (code, _, err) = terrain(&[
            "batch",
            jobs.to_str().unwrap(),
            "--out-dir",
            sharded.to_str().unwrap(),
            "--shard",
            &shard,
        ]);
        assert_eq!(code, 0, "shard {shard}: {err}");
        let lines = manifest(&sharded.join(format!("manifest-{i}-of-4.jsonl")));
        assert!(
            lines.iter().all(|l| l["index"].as_u64().unwrap() % 4 == i),
            "shard {i}"
        );
    }
    let (code, stdout, err) = terrain(&[
        "batch",
        jobs.to_str().unwrap(),
        "--out-dir",
        sharded.to_str().unwrap(),
        "--merge",
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(stdout.contains("11 items, 0 missing, 0 failed"), "{stdout}");
    assert_eq!(
        std::fs::read(sharded.join("manifest.inputs.json")).unwrap(),
        std::fs::read(sharded.join("manifest-0-of-4.inputs.json")).unwrap(),
        "the merged manifest records the shards' inputs"
    );
    let (a, b) = (pngs(&whole), pngs(&sharded));
    assert_eq!(a.len(), 11);
    assert_eq!(a.keys().collect::<Vec<_>>(), b.keys().collect::<Vec<_>>());
    for (name, bytes) in &a {
        assert!(
            bytes == &b[name],
            "{name} differs between the sharded and the whole batch"
        );
    }
    let merged = manifest(&sharded.join("manifest.jsonl"));
    let indices: Vec<u64> = merged
        .iter()
        .map(|l| l["index"].as_u64().unwrap())
        .collect();
    assert_eq!(indices, (0..11).collect::<Vec<u64>>());
    // Random cameras stand above the ground and see terrain.
    for name in a.keys().filter(|n| n.starts_with("random-")) {
        let (_, _, img) = read_png(&whole.join(name)).unwrap();
        let sky = img
            .chunks(4)
            .filter(|p| p[2] > p[0] + 40 && p[2] > 150)
            .count();
        assert!(sky < img.len() / 4 * 9 / 10, "{name} shows almost only sky");
    }
}

/// A scheduler's job script passes `--resume` from the first run on (docs/batch.md's Slurm and
/// Kubernetes examples): with no manifest yet, it renders everything.
#[test]
fn resume_on_a_fresh_folder_starts_the_batch() {
    let dir = scratch("batch-resume-fresh");
    base_scene(&dir, 24);
    let jobs = jobs_file(&dir, "[random]\ncount = 3\nseed = 2\n");
    let out = dir.join("out");
    let (code, stdout, err) = terrain(&[
        "batch",
        jobs.to_str().unwrap(),
        "--out-dir",
        out.to_str().unwrap(),
        "--shard",
        "1/2",
        "--resume",
    ]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(
        manifest(&out.join("manifest-1-of-2.jsonl")).len(),
        1,
        "{stdout}"
    );
    assert!(out.join("random-1.png").is_file());
}

#[test]
fn a_killed_batch_resumes_with_nothing_lost_or_listed_twice() {
    let dir = scratch("batch-resume");
    base_scene(&dir, 48);
    let jobs = jobs_file(&dir, "[random]\ncount = 14\nseed = 9\n");
    let out = dir.join("out");
    let mut child = Command::new(env!("CARGO_BIN_EXE_terrain"))
        .args([
            "batch",
            jobs.to_str().unwrap(),
            "--out-dir",
            out.to_str().unwrap(),
        ])
        .env("TERRAIN_QUIET", "1")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let start = Instant::now();
    let lines = |p: &Path| {
        std::fs::read_to_string(p)
            .map(|t| t.lines().count())
            .unwrap_or(0)
    };
    while lines(&out.join("manifest.jsonl")) < 3 {
        assert!(
            start.elapsed() < Duration::from_secs(120),
            "batch made no progress"
        );
        assert!(
            child.try_wait().unwrap().is_none(),
            "batch ended before it was killed"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    let before = lines(&out.join("manifest.jsonl"));
    assert!(
        before < 14,
        "the batch finished before it was killed ({before} lines)"
    );

    // What a kill mid-write leaves (the kill above may or may not have), and a file of someone
    // else's that resuming must not touch.
    let torn = out.join(".random-13.png.4194303.tmp");
    let foreign = out.join(".notes.txt.12.tmp");
    std::fs::write(&torn, b"half a png").unwrap();
    std::fs::write(&foreign, b"not ours").unwrap();
    let (code, stdout, err) = terrain(&[
        "batch",
        jobs.to_str().unwrap(),
        "--out-dir",
        out.to_str().unwrap(),
        "--resume",
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(stdout.contains("already done"), "{stdout}");
    assert!(!torn.exists() && foreign.exists());
    std::fs::remove_file(&foreign).unwrap();
    let m = manifest(&out.join("manifest.jsonl"));
    let mut names: Vec<&str> = m.iter().map(|l| l["name"].as_str().unwrap()).collect();
    names.sort();
    names.dedup();
    assert_eq!(
        (m.len(), names.len()),
        (14, 14),
        "lines {} names {}",
        m.len(),
        names.len()
    );
    assert!(m.iter().all(|l| l["status"] == "ok"));
    let images = pngs(&out);
    assert_eq!(images.len(), 14);
    // Resumed images are the ones an uninterrupted run makes.
    let fresh = dir.join("fresh");
    let (code, _, err) = terrain(&[
        "batch",
        jobs.to_str().unwrap(),
        "--out-dir",
        fresh.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(images, pngs(&fresh));
    // No temporary file is left behind.
    let stray: Vec<_> = std::fs::read_dir(&out)
        .unwrap()
        .flatten()
        .filter(|e| e.file_name().to_string_lossy().ends_with(".tmp"))
        .collect();
    assert!(stray.is_empty(), "{stray:?}");
}

#[test]
fn bad_jobs_fail_alone_with_their_cause() {
    let dir = scratch("batch-bad");
    // A base scene over a sketch file, so a job can point it at one that is not there.
    let heights: Vec<String> = (0..33 * 33)
        .map(|k| format!("{}", 100 + (k % 33) * 3 + (k / 33) * 2))
        .collect();
    std::fs::write(
        dir.join("small.asc"),
        format!(
            "ncols 33\nnrows 33\nxllcorner 0\nyllcorner 0\ncellsize 30\nNODATA_value -9999\n{}\n",
            heights.join(" ")
        ),
    )
    .unwrap();
    std::fs::write(
        dir.join("base.toml"),
        "[sketch]\npath = \"small.asc\"\n[camera]\nposition = [100.0, 50.0, 400.0]\nlook_at = [500.0, 900.0, 100.0]\nwidth = 32\nheight = 32\n[warp]\nmesh = 128\n",
    )
    .unwrap();
    let jobs = jobs_file(
        &dir,
        "[random]\ncount = 2\nseed = 1\n\n\
         [[job]]\nname = \"ok\"\n\n\
         [[job]]\nname = \"missing-sketch\"\nsketch = { path = \"nowhere.asc\" }\n\n\
         [[job]]\nname = \"underground\"\ncamera = { position = [500.0, 500.0, -50.0] }\n\n\
         [[job]]\nname = \"malformed\"\ncamera = { position = \"up\" }\n\n\
         [[job]]\nname = \"../escape\"\n",
    );
    let out = dir.join("out");
    let (code, _, err) = terrain(&[
        "batch",
        jobs.to_str().unwrap(),
        "--out-dir",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 1, "{err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(err.contains("4 of 7 snapshots failed"), "{err}");
    let m = manifest(&out.join("manifest.jsonl"));
    let by_name = |n: &str| m.iter().filter(|l| l["name"] == n).collect::<Vec<_>>();
    assert_eq!(by_name("ok")[0]["status"], "ok");
    assert_eq!(by_name("random-0")[0]["status"], "ok");
    assert_eq!(by_name("random-1")[0]["status"], "ok");
    let cause = |n: &str, i: usize| by_name(n)[i]["error"].as_str().unwrap_or("").to_string();
    assert!(
        cause("missing-sketch", 0).contains("nowhere.asc: No such file"),
        "{}",
        cause("missing-sketch", 0)
    );
    assert!(
        cause("underground", 0).contains("below the surface"),
        "{}",
        cause("underground", 0)
    );
    assert!(
        cause("malformed", 0).contains("camera.position")
            && cause("malformed", 0).matches("camera.position").count() == 1,
        "{}",
        cause("malformed", 0)
    );
    assert!(
        cause("../escape", 0).contains("name"),
        "{}",
        cause("../escape", 0)
    );
    assert!(!out.join("escape.png").exists() && !dir.join("escape.png").exists());

    // A jobs file that is not TOML, an unknown key, two items of one name and a bad shard fail
    // whole, in one line, before anything renders.
    for (body, cause) in [
        ("[[job]\n", "jobs.toml"),
        (
            "[[job]]\nname = \"a\"\n[[job]]\n[[job]]\nname = \"a\"\n",
            "job[2].name = \"a\": job[0] has that name already",
        ),
        (
            "[random]\ncount = 3\n[[job]]\nname = \"random-2\"\n",
            "random camera 2 has that name",
        ),
        ("colour = 3\n", "colour"),
        ("[random]\ncount = 100000000000\n", "random.count"),
        ("", "--shard"),
    ] {
        let jobs = jobs_file(&dir, body);
        let mut args = vec![
            "batch",
            jobs.to_str().unwrap(),
            "--out-dir",
            out.to_str().unwrap(),
        ];
        if body.is_empty() {
            args.extend(["--shard", "4/4"]);
        }
        let (code, _, err) = terrain(&args);
        assert_ne!(code, 0);
        assert_eq!(err.trim_end().lines().count(), 1, "{err}");
        assert!(err.contains(cause), "{err}");
    }
}

/// Runs `terrain batch JOBS --out-dir OUT` with `more` arguments.
fn batch(jobs: &Path, out: &Path, more: &[&str]) -> (i32, String, String) {
    let mut args = vec![
        "batch",
        jobs.to_str().unwrap(),
        "--out-dir",
        out.to_str().unwrap(),
    ];
    args.extend(more);
    terrain(&args)
}

/// One line on stderr, exit 1, and `out` as it was.
fn refused(r: (i32, String, String), out: &Path, before: &BTreeMap<String, Vec<u8>>, why: &str) {
    let (code, _, err) = r;
    assert_eq!(code, 1, "{err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(err.contains(why), "{err}");
    assert_eq!(
        &files(out),
        before,
        "the refused run changed {}",
        out.display()
    );
}

/// Every file of `dir`, by name.
fn files(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    std::fs::read_dir(dir)
        .unwrap()
        .flatten()
        .map(|e| {
            let name = e.file_name().to_string_lossy().into_owned();
            (name, std::fs::read(e.path()).unwrap())
        })
        .collect()
}

/// `--resume` from other inputs (the seed, the base scene, the options) would keep the first
/// batch's images as this one's: it is refused, saying what changed, for a shard too.
#[test]
fn resume_refuses_a_manifest_made_from_other_inputs() {
    let dir = scratch("batch-resume-other");
    base_scene(&dir, 16);
    let jobs = jobs_file(&dir, "[random]\ncount = 2\nseed = 1\n");
    let out = dir.join("out");
    let (code, _, err) = batch(&jobs, &out, &[]);
    assert_eq!(code, 0, "{err}");
    assert!(out.join("manifest.inputs.json").is_file());
    let before = files(&out);
    jobs_file(&dir, "[random]\ncount = 2\nseed = 2\n");
    refused(
        batch(&jobs, &out, &["--resume"]),
        &out,
        &before,
        "manifest.jsonl: was made from another jobs file (",
    );
    jobs_file(&dir, "[random]\ncount = 2\nseed = 1\n");
    base_scene(&dir, 20);
    refused(
        batch(&jobs, &out, &["--resume"]),
        &out,
        &before,
        "another base scene (",
    );
    base_scene(&dir, 16);
    refused(
        batch(&jobs, &out, &["--resume", "--size", "8"]),
        &out,
        &before,
        "--size 8x8",
    );
    // The same inputs again: nothing left to render.
    let (code, stdout, err) = batch(&jobs, &out, &["--resume"]);
    assert_eq!(code, 0, "{err}");
    assert!(stdout.contains("0 of 2 items rendered") && stdout.contains("2 already done"));

    let sharded = dir.join("sharded");
    let (code, _, err) = batch(&jobs, &sharded, &["--shard", "1/2"]);
    assert_eq!(code, 0, "{err}");
    assert!(sharded.join("manifest-1-of-2.inputs.json").is_file());
    let before = files(&sharded);
    jobs_file(&dir, "[random]\ncount = 2\nseed = 2\n");
    refused(
        batch(&jobs, &sharded, &["--shard", "1/2", "--resume"]),
        &sharded,
        &before,
        "manifest-1-of-2.jsonl: was made from another jobs file",
    );
}

/// A second batch into a folder would replace the first one's manifest and leave its images
/// unlisted: a run of other inputs is refused without `--resume` too; the same inputs render
/// again.
#[test]
fn a_batch_never_replaces_another_batchs_manifest() {
    let dir = scratch("batch-other-manifest");
    base_scene(&dir, 16);
    let first = jobs_file(&dir, "[[job]]\nname = \"first\"\n");
    let other = dir.join("other.toml");
    std::fs::write(
        &other,
        "scene = \"base.toml\"\n[[job]]\nname = \"second\"\n",
    )
    .unwrap();
    let out = dir.join("out");
    let (code, _, err) = batch(&first, &out, &[]);
    assert_eq!(code, 0, "{err}");
    let before = files(&out);
    refused(batch(&other, &out, &[]), &out, &before, "jobs.toml, now ");
    // A manifest that records no inputs is not known to be this batch's.
    std::fs::remove_file(out.join("manifest.inputs.json")).unwrap();
    let before = files(&out);
    refused(
        batch(&first, &out, &[]),
        &out,
        &before,
        "no manifest.inputs.json",
    );
    std::fs::write(out.join("manifest.jsonl"), "").unwrap();
    let (code, _, err) = batch(&first, &out, &[]);
    assert_eq!(code, 0, "{err}");
    let (code, _, err) = batch(&first, &out, &[]);
    assert_eq!(code, 0, "{err}");
    let m = manifest(&out.join("manifest.jsonl"));
    assert_eq!((m.len(), m[0]["name"].as_str()), (1, Some("first")));
}

#[test]
fn set_size_and_mode_apply_to_every_item() {
    let dir = scratch("batch-overrides");
    base_scene(&dir, 16);
    let jobs = jobs_file(
        &dir,
        "[random]\ncount = 1\nseed = 4\n[[job]]\nname = \"given\"\n",
    );
    let out = dir.join("out");
    let args = [
        "--set",
        "camera.fov_y_deg=40",
        "--set",
        "detail.octaves=0",
        "--size",
        "20x12",
        "--mode",
        "geomipmap",
    ];
    let (code, _, err) = batch(&jobs, &out, &args);
    assert_eq!(code, 0, "{err}");
    let m = manifest(&out.join("manifest.jsonl"));
    assert_eq!(m.len(), 2);
    for l in &m {
        assert_eq!(
            (l["width"].as_u64(), l["height"].as_u64()),
            (Some(20), Some(12)),
            "{l}"
        );
        assert_eq!(l["mode"], "geomipmap", "{l}");
    }
    assert!((m[0]["camera"]["fov_y_deg"].as_f64().unwrap() - 40.0).abs() < 1e-9);
    // The options are part of the batch's inputs.
    let before = files(&out);
    refused(
        batch(&jobs, &out, &["--resume"]),
        &out,
        &before,
        "other options (--set camera.fov_y_deg=40 --set detail.octaves=0 --size 20x12 --mode geomipmap, now no --set",
    );
    let (code, stdout, err) = batch(&jobs, &out, &[&args[..], &["--resume"]].concat());
    assert_eq!(code, 0, "{err}");
    assert!(stdout.contains("2 already done"), "{stdout}");
    // A bad override is a usage error, as in `render`.
    let (code, _, err) = batch(&jobs, &out, &["--set", "detail.octaves=many"]);
    assert_eq!(code, 2, "{err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(err.contains("--set detail.octaves=many"), "{err}");
    assert_eq!(files(&out), before);
}

/// A job's `sketch.path` is relative to the jobs file, as docs/scene.md says of every path, not
/// to the base scene's folder; and the sketch is part of the batch's inputs.
#[test]
fn a_jobs_sketch_is_relative_to_the_jobs_file() {
    let dir = scratch("batch-job-paths");
    let heights: Vec<String> = (0..33 * 33)
        .map(|k| format!("{}", 100 + (k % 33) * 3 + (k / 33) * 2))
        .collect();
    let asc = format!(
        "ncols 33\nnrows 33\nxllcorner 0\nyllcorner 0\ncellsize 30\nNODATA_value -9999\n{}\n",
        heights.join(" ")
    );
    for sub in ["scenes", "jobs"] {
        std::fs::create_dir_all(dir.join(sub)).unwrap();
    }
    std::fs::write(dir.join("scenes/small.asc"), &asc).unwrap();
    std::fs::write(dir.join("jobs/mine.asc"), &asc).unwrap();
    std::fs::write(
        dir.join("scenes/base.toml"),
        "[sketch]\npath = \"small.asc\"\n[camera]\nposition = [100.0, 50.0, 400.0]\nlook_at = [500.0, 900.0, 100.0]\nwidth = 16\nheight = 16\n[warp]\nmesh = 64\n",
    )
    .unwrap();
    let jobs = dir.join("jobs/jobs.toml");
    std::fs::write(
        &jobs,
        "scene = \"../scenes/base.toml\"\n[[job]]\nname = \"mine\"\nsketch = { path = \"mine.asc\" }\n",
    )
    .unwrap();
    let out = dir.join("out");
    let (code, _, err) = batch(&jobs, &out, &[]);
    assert_eq!(
        code,
        0,
        "{err}: {:?}",
        std::fs::read_to_string(out.join("manifest.jsonl"))
    );
    assert!(out.join("mine.png").is_file());
    // A sketch written since is another input.
    let later = std::time::SystemTime::now() + Duration::from_secs(60);
    std::fs::File::options()
        .append(true)
        .open(dir.join("jobs/mine.asc"))
        .unwrap()
        .set_modified(later)
        .unwrap();
    let before = files(&out);
    refused(
        batch(&jobs, &out, &["--resume"]),
        &out,
        &before,
        "mine.asc changed",
    );
}

#[test]
fn the_bundled_jobs_file_and_flight_load() {
    let jobs =
        terrain_cli::app::batch::Jobs::load(&manifest_dir().join("sketches/random-snapshots.toml"))
            .unwrap();
    let items = jobs.items();
    assert_eq!(items.len(), 202);
    assert_eq!(
        (items[0].name.as_str(), items[201].name.as_str()),
        ("valley-north", "random-199")
    );
    let scene =
        terrain_engine::scene::Scene::load(&manifest_dir().join("sketches/jacksboro-flight.toml"))
            .unwrap();
    let path = terrain_engine::flight::path::CameraPath::of_scene(
        &scene,
        &terrain_engine::scene::load_atlas(&scene).unwrap(),
    )
    .unwrap();
    assert!(
        (9000.0..10000.0).contains(&path.length_m()),
        "{}",
        path.length_m()
    );
}

#[test]
fn a_long_path_without_frames_is_spread_over_the_default_count_and_says_so() {
    let dir = scratch("fly-slow");
    let scene = dir.join("slow.toml");
    std::fs::write(
        &scene,
        "[sketch]\nsynthetic = \"hills\"\n[camera]\nposition = [500.0, 300.0, 900.0]\nlook_at = [3800.0, 4000.0, 200.0]\n[warp]\nmesh = 16\n[detail]\noctaves = 0\n[path]\nspeed_mps = 1e-9\nkeys = [{ position = [0.0, 0.0, 900.0] }, { position = [1000.0, 0.0, 900.0] }]\n",
    )
    .unwrap();
    let out = dir.join("out");
    let (code, stdout, err) = terrain(&[
        "fly",
        scene.to_str().unwrap(),
        "--out-dir",
        out.to_str().unwrap(),
        "--size",
        "8",
        "--no-mp4",
    ]);
    assert_eq!(code, 0, "{err}");
    let n = terrain_cli::app::fly::DEFAULT_MAX_FRAMES;
    assert!(stdout.contains(&format!("{n} frames")), "{stdout}");
    // Said before the first frame: how many frames, spread over the path, and what is written.
    assert!(
        err.contains(&format!("{n} frames spread over it")) && err.contains("--frames N"),
        "{err}"
    );
    assert!(err.contains(&format!("writing {n} frames of 8×8")), "{err}");
    assert!(out.join(format!("frame-{:05}.png", n - 1)).is_file());
    assert!(!out.join(format!("frame-{n:05}.png")).exists());
}

/// Random cameras over a planet stand anywhere on it, from 2 m to orbit, and the manifest gives
/// each one's camera keys: rendering the scene with them makes the same image, byte for byte.
#[test]
fn random_cameras_cover_a_planet_and_the_manifest_reproduces_them() {
    let dir = scratch("batch-planet");
    std::fs::write(
        dir.join("base.toml"),
        "[sketch]\nsynthetic = \"planet\"\nsize = 128\n[planet]\nphi_steps = 64\nrings_per_level = 6\n\
         [camera]\nlat_deg = 0.0\nlon_deg = 0.0\naltitude_m = 100.0\nwidth = 24\nheight = 24\n",
    )
    .unwrap();
    let jobs = jobs_file(&dir, "[random]\ncount = 6\nseed = 11\n");
    let out = dir.join("out");
    let (code, _, err) = terrain(&[
        "batch",
        jobs.to_str().unwrap(),
        "--out-dir",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    let m = manifest(&out.join("manifest.jsonl"));
    assert_eq!(m.len(), 6);
    let keys: Vec<&serde_json::Value> = m.iter().map(|l| &l["camera"]["planet"]).collect();
    let altitudes: Vec<f64> = keys
        .iter()
        .map(|k| k["altitude_m"].as_f64().unwrap())
        .collect();
    assert!(
        altitudes.iter().all(|a| (1.99..=2.0001e7).contains(a)),
        "{altitudes:?}"
    );
    let k = keys[0];
    let set = |key: &str| format!("camera.{key}={}", k[key].as_f64().unwrap());
    let again = dir.join("again.png");
    let (code, _, err) = terrain(&[
        "render",
        dir.join("base.toml").to_str().unwrap(),
        "--output",
        again.to_str().unwrap(),
        "--set",
        &set("lat_deg"),
        "--set",
        &set("lon_deg"),
        "--set",
        &set("altitude_m"),
        "--set",
        &set("heading_deg"),
        "--set",
        &set("pitch_deg"),
    ]);
    assert_eq!(code, 0, "{err}");
    let name = m[0]["name"].as_str().unwrap();
    assert_eq!(
        std::fs::read(&again).unwrap(),
        std::fs::read(out.join(format!("{name}.png"))).unwrap(),
        "{k}"
    );
}

/// Over a planet without a `[path]`, `fly` makes its pass straight ahead: the nadirs in
/// `frames.csv` move along the camera's heading (100°: east, a little south), at its altitude.
#[test]
fn fly_over_a_planet_passes_straight_ahead() {
    let dir = scratch("fly-planet");
    let scene = dir.join("planet.toml");
    std::fs::write(
        &scene,
        "[sketch]\nsynthetic = \"planet\"\nsize = 128\n[planet]\nphi_steps = 64\nrings_per_level = 6\n\
         [camera]\nlat_deg = 27.8\nlon_deg = -47.8\naltitude_m = 10000.0\nheading_deg = 100.0\n\
         pitch_deg = -20.0\nwidth = 24\nheight = 24\n",
    )
    .unwrap();
    let out = dir.join("out");
    let (code, _, err) = terrain(&[
        "fly",
        scene.to_str().unwrap(),
        "--out-dir",
        out.to_str().unwrap(),
        "--frames",
        "3",
        "--no-mp4",
    ]);
    assert_eq!(code, 0, "{err}");
    let csv = std::fs::read_to_string(out.join("frames.csv")).unwrap();
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let nadirs: Vec<(f64, f64)> = csv
        .lines()
        .skip(1)
        .map(|l| {
            let c: Vec<&str> = l.split(',').collect();
            (
                c[col("lat_deg")].parse().unwrap(),
                c[col("lon_deg")].parse().unwrap(),
            )
        })
        .collect();
    assert_eq!(nadirs.len(), 3);
    let (first, last) = (nadirs[0], nadirs[2]);
    assert!(
        (first.0 - 27.8).abs() < 1e-6 && (first.1 + 47.8).abs() < 1e-6,
        "{nadirs:?}"
    );
    // 10 km of ground east-south-east: 0.10° of longitude at 27.8° N.
    let (north, east) = (last.0 - first.0, last.1 - first.1);
    assert!(
        east > 0.09 && east < 0.11 && north < 0.0 && -north < east / 4.0,
        "{nadirs:?}"
    );
}

/// A job's camera is one camera laid over the base's: an explicit `position` and `look_at` over a
/// starter scene (placed by heading and pitch), a `look_at` over a `map_xy` camera, and
/// `--set camera.…` alike; a job's own conflict names both files.
#[test]
fn a_jobs_camera_replaces_the_base_cameras_place_and_aim() {
    let dir = scratch("jobs-camera");
    let dem = manifest_dir().join("tests/data/formats/utm-metres-Float32.tif");
    let (code, _, err) = terrain(&[
        "scene",
        dem.to_str().unwrap(),
        "-o",
        dir.join("starter.toml").to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    // The starter's camera by map_xy and altitude (its commented place given), aimed by heading
    // and pitch.
    let starter = std::fs::read_to_string(dir.join("starter.toml")).unwrap();
    let placed = starter
        .replace("# map_xy = ", "map_xy = ")
        .replace("# altitude_m = ", "altitude_m = ");
    assert!(placed.contains("\nmap_xy = ") && placed.contains("\naltitude_m = "));
    std::fs::write(dir.join("mine.toml"), &placed).unwrap();
    let jobs = dir.join("jobs.toml");
    std::fs::write(
        &jobs,
        "scene = \"mine.toml\"\n\
         [[job]]\nname = \"explicit\"\n\
         camera = { position = [500.0, 200.0, 1500.0], look_at = [1500.0, 1500.0, 500.0] }\n\
         [[job]]\nname = \"aimed\"\ncamera = { look_at = [1400.0, 1400.0, 550.0] }\n\
         [[job]]\nname = \"two-places\"\n\
         camera = { position = [500.0, 200.0, 1500.0], map_xy = [747000.0, 4057500.0] }\n",
    )
    .unwrap();
    let out = dir.join("out");
    let (code, _, _) = batch(&jobs, &out, &["--size", "32"]);
    assert_eq!(code, 1, "one job fails");
    let lines = manifest(&out.join("manifest.jsonl"));
    let by_name = |n: &str| lines.iter().find(|l| l["name"] == n).unwrap().clone();
    let explicit = by_name("explicit");
    assert_eq!(explicit["status"], "ok", "{explicit}");
    assert_eq!(
        explicit["camera"]["position"],
        serde_json::json!([500.0, 200.0, 1500.0])
    );
    let aimed = by_name("aimed");
    assert_eq!(aimed["status"], "ok", "{aimed}");
    // It kept the base's place: the eye over the base's map_xy (the sketch's south-west node is
    // at 746130.58, 4056850.80).
    let map_xy: Vec<f64> = placed
        .lines()
        .find(|l| l.starts_with("map_xy = "))
        .map(|l| {
            let v = l.split('[').nth(1).unwrap().split(']').next().unwrap();
            v.split(',').map(|x| x.trim().parse().unwrap()).collect()
        })
        .unwrap();
    let eye = &aimed["camera"]["position"];
    assert!(
        (eye[0].as_f64().unwrap() - (map_xy[0] - 746130.58)).abs() < 1.0,
        "{eye}"
    );
    let bad = by_name("two-places");
    let why = bad["error"].as_str().unwrap();
    assert!(
        why.contains("give one place") && why.contains("jobs.toml") && why.contains("mine.toml"),
        "{why}"
    );
    // `--set camera.…` on the command line is one camera too.
    let (code, _, err) = terrain(&[
        "render",
        dir.join("mine.toml").to_str().unwrap(),
        "-o",
        dir.join("set.png").to_str().unwrap(),
        "--size",
        "32",
        "--set",
        "camera.position=[500.0, 200.0, 1500.0]",
        "--set",
        "camera.look_at=[1500.0, 1500.0, 500.0]",
    ]);
    assert_eq!(code, 0, "{err}");
}
