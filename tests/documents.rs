//! The documents hold: every relative link in README.md and docs/ resolves to a file (and a named
//! heading) in the repository, and every command in the README's `sh` blocks runs as written, at
//! a small size, from a folder that sees the checkout's `sketches/` and `tests/`.

mod common;
use common::*;
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::process::Command;

/// README.md and every page of docs/.
fn documents() -> Vec<PathBuf> {
    let mut docs = vec![manifest_dir().join("README.md")];
    let mut pages: Vec<PathBuf> = std::fs::read_dir(manifest_dir().join("docs"))
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|x| x == "md"))
        .collect();
    pages.sort();
    docs.extend(pages);
    docs
}

/// The targets of a page's markdown links and images, `](target)`, outside code blocks.
fn links(text: &str) -> Vec<String> {
    let mut found = Vec::new();
    let mut fenced = false;
    for line in text.lines() {
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
            continue;
        }
        if fenced {
            continue;
        }
        let mut rest = line;
        while let Some(at) = rest.find("](") {
            let tail = &rest[at + 2..];
            let Some(end) = tail.find(')') else { break };
            found.push(tail[..end].to_string());
            rest = &tail[end..];
        }
    }
    found
}

/// GitHub's anchor for a heading: lower case, punctuation dropped, spaces to hyphens.
fn anchor(heading: &str) -> String {
    heading
        .trim()
        .to_lowercase()
        .chars()
        .filter(|c| c.is_alphanumeric() || *c == ' ' || *c == '-' || *c == '_')
        .map(|c| if c == ' ' { '-' } else { c })
        .collect()
}

fn anchors(text: &str) -> BTreeSet<String> {
    let mut fenced = false;
    let mut set = BTreeSet::new();
    for line in text.lines() {
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
        } else if !fenced && line.starts_with('#') {
            set.insert(anchor(line.trim_start_matches('#')));
        }
    }
    set
}

/// Why a link of `page` does not resolve, if it does not.
fn broken(page: &Path, target: &str) -> Option<String> {
    if target.starts_with("http://") || target.starts_with("https://") {
        return None;
    }
    let (file, fragment) = match target.split_once('#') {
        Some((f, a)) => (f, Some(a)),
        None => (target, None),
    };
    let resolved = if file.is_empty() {
        page.to_path_buf()
    } else {
        page.parent().unwrap().join(file)
    };
    let root = manifest_dir().canonicalize().unwrap();
    let Ok(real) = resolved.canonicalize() else {
        return Some(format!("{target}: no such file"));
    };
    if !real.starts_with(&root) {
        return Some(format!("{target}: outside the repository"));
    }
    if let Some(fragment) = fragment {
        let text = std::fs::read_to_string(&real).unwrap_or_default();
        if !anchors(&text).contains(fragment) {
            return Some(format!("{target}: no heading #{fragment}"));
        }
    }
    None
}

#[test]
fn every_relative_link_in_the_readme_and_docs_resolves() {
    let mut bad = Vec::new();
    let mut checked = 0;
    for page in documents() {
        let text = std::fs::read_to_string(&page).unwrap();
        for target in links(&text) {
            checked += 1;
            if let Some(why) = broken(&page, &target) {
                bad.push(format!("{}: {why}", page.display()));
            }
        }
    }
    assert!(
        checked > 40,
        "only {checked} links found: is the parser right?"
    );
    assert!(bad.is_empty(), "broken links:\n{}", bad.join("\n"));
}

#[test]
fn the_link_checker_finds_a_missing_file_and_a_missing_heading() {
    let readme = manifest_dir().join("README.md");
    assert!(broken(&readme, "docs/scene.md").is_none());
    assert!(broken(&readme, "docs/no-such-page.md").is_some());
    assert!(broken(&readme, "#the-two-commands").is_none());
    assert!(broken(&readme, "#no-such-heading").is_some());
    assert_eq!(
        anchor(" `terrain tiles SRC`: big, fast!"),
        "terrain-tiles-src-big-fast"
    );
}

/// README lines not run here, each with the reason.
const NOT_RUN_HERE: [(&str, &str); 5] = [
    ("cargo test --release", "this test runs inside it"),
    (
        "cargo install --path .",
        "installs into ~/.cargo/bin; it builds the same binary the tests run",
    ),
    (
        "terrain view",
        "a window: tests/view.rs runs the README's view commands under Xvfb",
    ),
    (
        "terrain web",
        "serves until interrupted; tests/web.rs exports, serves and opens the page",
    ),
    (
        "cargo run --release --example host",
        "a window: tests/view.rs runs the example under Xvfb",
    ),
];

/// The options a test adds to keep a command small.
fn small(words: &[&str]) -> Vec<&'static str> {
    match words.get(1).copied() {
        Some("render") => vec!["--size", "24"],
        Some("fly") => vec!["--size", "16", "--frames", "3"],
        Some("compare") => vec!["--size", "16", "--repeat", "1", "--path-frames", "3"],
        Some("batch") if words.iter().any(|w| w.contains("random-snapshots")) => {
            vec!["--size", "16", "--shard", "0/25"]
        }
        Some("batch") => vec!["--size", "16"],
        _ => vec![],
    }
}

/// A folder to run the README's commands in: the checkout's sketches and test data linked in,
/// `terrain` on the PATH, and the README's `mine-jobs.toml` written out.
fn readme_folder() -> (PathBuf, String) {
    let dir = scratch("readme-commands");
    for linked in ["sketches", "tests"] {
        std::os::unix::fs::symlink(manifest_dir().join(linked), dir.join(linked)).unwrap();
    }
    let bin = dir.join("bin");
    std::fs::create_dir_all(&bin).unwrap();
    std::os::unix::fs::symlink(env!("CARGO_BIN_EXE_terrain"), bin.join("terrain")).unwrap();
    let readme = std::fs::read_to_string(manifest_dir().join("README.md")).unwrap();
    let jobs = readme
        .split("```toml\n")
        .skip(1)
        .map(|b| b.split("```").next().unwrap())
        .find(|b| b.starts_with("scene = \"mine.toml\""))
        .expect("the README's mine-jobs.toml");
    std::fs::write(dir.join("mine-jobs.toml"), jobs).unwrap();
    let path = format!("{}:{}", bin.display(), std::env::var("PATH").unwrap());
    (dir, path)
}

#[test]
fn every_command_in_the_readme_runs_as_written() {
    let (dir, path) = readme_folder();
    let tif = "tests/data/formats/utm-metres-Float32.tif";
    let mut ran = 0;
    for command in readme_commands() {
        if let Some((_, why)) = NOT_RUN_HERE.iter().find(|(c, _)| command.starts_with(c)) {
            eprintln!("not run here: `{command}`: {why}");
            continue;
        }
        let line = command
            .replace("cargo run --release -- ", "terrain ")
            .replace("my_dem.tif", tif)
            .replace("\"ortho.tif\"", "\"tests/data/surface/ortho-4326.tif\"");
        let words: Vec<&str> = line.split_whitespace().collect();
        assert_eq!(
            words[0], "terrain",
            "a README command that is not terrain's: {command}"
        );
        let full = format!("{line} {}", small(&words).join(" "));
        let out = Command::new("sh")
            .args(["-c", &full])
            .current_dir(&dir)
            .env("PATH", &path)
            .env("TERRAIN_QUIET", "1")
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "`{full}` failed: {err}");
        for made in outputs(&words) {
            assert!(dir.join(made).exists(), "`{full}` wrote no {made}");
        }
        ran += 1;
    }
    assert!(ran >= 15, "only {ran} README commands ran");
}

/// What a command line says it writes: `-o FILE` and `--out-dir DIR`.
fn outputs<'a>(words: &[&'a str]) -> Vec<&'a str> {
    words
        .windows(2)
        .filter(|w| w[0] == "-o" || w[0] == "--out-dir")
        .map(|w| w[1])
        .collect()
}

/// The repository's own text: the README, docs, code, shaders, tests, scripts and scenes (not
/// vendored code, fixtures or snapshots).
fn own_text_files() -> Vec<PathBuf> {
    let root = manifest_dir();
    let mut files = vec![
        root.join("README.md"),
        root.join("Cargo.toml"),
        root.join(".ci/run"),
    ];
    let mut dirs: Vec<PathBuf> = [
        "docs", "src", "crates", "tests", "benches", "examples", "scripts", "sketches", "fuzz",
    ]
    .iter()
    .map(|d| root.join(d))
    .collect();
    let skipped = [
        root.join("tests/data"),
        root.join("tests/snapshots"),
        root.join("fuzz/seeds"),
    ];
    while let Some(dir) = dirs.pop() {
        for entry in std::fs::read_dir(&dir).unwrap().flatten() {
            let path = entry.path();
            if path.is_dir() && !skipped.contains(&path) {
                dirs.push(path);
            } else if path.extension().is_some_and(|x| {
                ["rs", "md", "wgsl", "sh", "py", "toml"].contains(&x.to_str().unwrap_or(""))
            }) {
                files.push(path);
            }
        }
    }
    files
}

/// Where `line` names an internal work step ("st" "op 41") or a document outside the repository
/// (the outside design page in capitals, or a paper by its file's number).
fn outside_reference(line: &str) -> Option<&'static str> {
    let lower = line.to_lowercase();
    let step = ["st", "op"].concat();
    let bytes = lower.as_bytes();
    for (at, _) in lower.match_indices(&step) {
        let before = at.checked_sub(1).map(|i| bytes[i]);
        if before.is_some_and(|b| b.is_ascii_alphanumeric()) {
            continue;
        }
        let rest = &lower[at + step.len()..];
        let rest = rest.strip_prefix('s').unwrap_or(rest);
        if rest
            .strip_prefix(' ')
            .is_some_and(|r| r.starts_with(|c: char| c.is_ascii_digit()))
        {
            return Some("an internal work step");
        }
    }
    if line.contains(&["DES", "IGN.md"].concat()) {
        return Some("a design document outside the repository");
    }
    if lower.contains(&["seed", " 00"].concat()) {
        return Some("a paper by its file's number");
    }
    None
}

#[test]
fn nothing_cites_a_work_step_or_a_document_outside_the_repository() {
    let mut found = Vec::new();
    for file in own_text_files() {
        let Ok(text) = std::fs::read_to_string(&file) else {
            continue;
        };
        for (k, line) in text.lines().enumerate() {
            if let Some(what) = outside_reference(line) {
                found.push(format!("{}:{}: {what}: {line}", file.display(), k + 1));
            }
        }
    }
    assert!(found.is_empty(), "{}", found.join("\n"));
}

#[test]
fn the_reference_check_tells_a_work_step_from_ordinary_words() {
    let step = ["St", "op 43"].concat();
    assert!(outside_reference(&format!("since {step}'s build")).is_some());
    assert!(outside_reference(&format!("two {}s 41", &step[..4])).is_some());
    assert!(outside_reference("they stop when no stand-in is left").is_none());
    assert!(outside_reference("a stopwatch 3 s").is_none());
    assert!(outside_reference("the backstop 3").is_none());
    assert!(outside_reference("docs/design.md, Importance").is_none());
    assert!(outside_reference(&["see DES", "IGN.md"].concat()).is_some());
}

/// The titles that pointers into docs/decisions.md name: the file's name, a comma and the title
/// in curly quotes, a pointer possibly wrapped onto the next comment line.
fn decision_pointers(text: &str) -> Vec<String> {
    let joined: String = text
        .lines()
        .map(|l| {
            let t = l.trim_start();
            let t = ["//!", "///", "//", "#"]
                .iter()
                .find_map(|m| t.strip_prefix(m))
                .unwrap_or(t);
            t.trim().to_string()
        })
        .collect::<Vec<_>>()
        .join(" ");
    let mut titles = Vec::new();
    for (at, _) in joined.match_indices("decisions.md") {
        let rest = &joined[at..];
        let Some(open) = rest.find('“') else {
            continue;
        };
        if open > 40 {
            continue;
        }
        let title = &rest[open + '“'.len_utf8()..];
        if let Some(close) = title.find('”') {
            titles.push(title[..close].to_string());
        }
    }
    titles
}

#[test]
fn every_pointer_into_the_decisions_names_an_entry() {
    let decisions = std::fs::read_to_string(manifest_dir().join("docs/decisions.md")).unwrap();
    let entries: BTreeSet<&str> = decisions
        .lines()
        .filter_map(|l| l.strip_prefix("## "))
        .map(str::trim)
        .collect();
    let mut missing = Vec::new();
    let mut pointers = 0;
    for file in own_text_files() {
        let Ok(text) = std::fs::read_to_string(&file) else {
            continue;
        };
        for title in decision_pointers(&text) {
            pointers += 1;
            if !entries.contains(title.as_str()) {
                missing.push(format!("{}: “{title}”", file.display()));
            }
        }
    }
    assert!(
        pointers > 20,
        "only {pointers} pointers found: is the parser right?"
    );
    assert!(missing.is_empty(), "no such entry:\n{}", missing.join("\n"));
}
