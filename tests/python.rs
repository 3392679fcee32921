//! `import terrain` as a user meets it: the package (`python/`) built into a wheel for this
//! platform by pip (maturin, from the package registry, builds its native module), the wheel
//! installed into a fresh virtual environment, then its pytest suite (`python/tests`, pytest from
//! the registry) run against the bundled sketches and a GDAL GeoTIFF, and the dataset example run
//! as its docstring says.
//!
//! Own harness (libtest-mimic): without a Python 3 with `venv` it reports itself skipped with
//! the reason, and fails where `TERRAIN_REQUIRE_PYTHON_TESTS` is set (`.ci/run` sets it).

mod common;
use common::*;
use libtest_mimic::Arguments;
use std::path::{Path, PathBuf};
use std::process::Command;

fn main() {
    let args = Arguments::from_args();
    let why_not = python().is_none().then(|| {
        "no Python 3 with venv and pip on the PATH (Debian: apt-get install python3-venv)"
            .to_string()
    });
    let trial = skippable_trial(
        "the_package_installs_in_a_fresh_venv_and_passes_its_pytest_suite",
        the_package_installs_in_a_fresh_venv_and_passes_its_pytest_suite,
        why_not,
        "TERRAIN_REQUIRE_PYTHON_TESTS",
    );
    libtest_mimic::run(&args, vec![trial]).exit();
}

/// A Python 3 that can make a virtual environment with pip in it.
fn python() -> Option<&'static str> {
    ["python3", "python"].into_iter().find(|p| {
        Command::new(p)
            .args([
                "-c",
                "import sys, venv, ensurepip; assert sys.version_info >= (3, 9)",
            ])
            .output()
            .is_ok_and(|o| o.status.success())
    })
}

fn run(what: &str, cmd: &mut Command) {
    let out = cmd.output().unwrap_or_else(|e| panic!("{what}: {e}"));
    assert!(
        out.status.success(),
        "{what} failed ({}):\n{}\n{}",
        out.status,
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
}

fn the_package_installs_in_a_fresh_venv_and_passes_its_pytest_suite() {
    let root = manifest_dir();
    let dir = scratch("python");
    let venv = dir.join("venv");
    run(
        "python -m venv",
        Command::new(python().unwrap())
            .args(["-m", "venv"])
            .arg(&venv),
    );
    let bin = |name: &str| -> PathBuf { venv.join("bin").join(name) };
    // The wheel `pip install ./python` builds (docs/python.md), kept in `target/wheels/`; its
    // native module builds into the workspace's target folder, beside what `cargo test` built.
    let wheels = target_dir(&root).join("wheels");
    let _ = std::fs::remove_dir_all(&wheels);
    run(
        "pip wheel ./python",
        Command::new(bin("pip"))
            .args([
                "wheel",
                "--quiet",
                "--disable-pip-version-check",
                "--no-deps",
                "-w",
            ])
            .arg(&wheels)
            .arg(root.join("python"))
            .env("CARGO_TARGET_DIR", target_dir(&root))
            .current_dir(&dir),
    );
    let wheel = std::fs::read_dir(&wheels)
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .find(|p| p.extension().is_some_and(|e| e == "whl"))
        .expect("a wheel");
    let name = wheel.file_name().unwrap().to_string_lossy().into_owned();
    assert!(name.starts_with("terrain_renderer-"), "{name}");
    run(
        "pip install the wheel and pytest",
        Command::new(bin("pip"))
            .args(["install", "--quiet", "--disable-pip-version-check"])
            .arg(&wheel)
            .arg("pytest")
            .current_dir(&dir),
    );
    // From outside the repository, so `import terrain` is the installed package.
    run(
        "pytest python/tests",
        Command::new(bin("python"))
            .args(["-m", "pytest", "-q", "-p", "no:cacheprovider"])
            .arg(root.join("python/tests"))
            .current_dir(&dir),
    );
    let example = Command::new(bin("python"))
        .arg(root.join("python/examples/dataset.py"))
        .arg(root.join("sketches/jacksboro.toml"))
        .current_dir(&dir)
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&example.stdout);
    assert!(
        example.status.success(),
        "dataset.py: {text}{}",
        String::from_utf8_lossy(&example.stderr)
    );
    assert_eq!(
        text.lines().filter(|l| l.starts_with("item ")).count(),
        4,
        "{text}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// The target folder `cargo test` builds in.
fn target_dir(root: &Path) -> PathBuf {
    std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| root.join("target"))
}
