//! A seeded mutation fuzzer on stable Rust, over every sketch reader and the scene and jobs
//! parsers. `cargo run --release --example fuzz -- [--execs N] [--target NAME] [--seed S]` runs it
//! (see docs/formats.md); `tests/fuzz.rs` runs a short pass of every target in CI.
//!
//! Rules:
//! - Each execution takes a seed input (the GDAL fixtures in tests/data/formats, fuzz/seeds and
//!   the bundled scenes), applies 1 to 8 havoc mutations (bit flips, interesting integers in either
//!   byte order, block deletion, duplication and insertion, truncation, splicing with another seed,
//!   and for text targets interesting numbers in place of a token) and runs the target under
//!   `catch_unwind`.
//! - A panic is a crash: its input is written to `target/fuzz/crashes/` and counted. An error
//!   whose message spans more than one line, or is empty, is counted as a bad message: a user
//!   must see exactly one line.
//! - Grids are limited to 2²² cells while fuzzing ([`terrain_engine::sketch::limit_cells`]), so a
//!   mutated size field costs milliseconds, not a gigabyte; the limit itself is tested apart
//!   (`tests/formats.rs`, a 2³¹-cell header under a memory limit).
//!
//! Rejected alternatives: bolero and cargo-fuzz drive libFuzzer or AFL, which need a nightly
//! compiler or a C++ toolchain this project does not install; bolero's stable mode generates
//! inputs from nothing. Measured with this harness's `--random` switch (uniform random bytes of a
//! seed's length, 50,000 executions each), 100 % of random TIFF inputs stop at the header ("not a
//! readable TIFF"), against 28 % of mutated fixtures, and 14 % of mutants are read whole: seeds are
//! what reach the decoders.

use std::panic::AssertUnwindSafe;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};
use terrain_engine::sketch::{LoadOptions, parse_grid, parse_world_file};

/// One fuzz target: a name, its seeds and the function that runs one input.
pub struct Target {
    pub name: &'static str,
    pub seeds: Vec<Vec<u8>>,
    pub text: bool,
    run: fn(&[u8]) -> Outcome,
}

/// What one execution did.
#[derive(Clone, Debug, PartialEq)]
pub enum Outcome {
    Read,
    /// Refused, with the first words of the message (its class).
    Refused(String),
    /// Refused with a message that is empty or spans lines.
    BadMessage(String),
}

fn outcome<T, E: std::fmt::Display>(r: Result<T, E>) -> Outcome {
    match r {
        Ok(_) => Outcome::Read,
        Err(e) => {
            let msg = e.to_string();
            if msg.trim().is_empty() || msg.contains('\n') {
                Outcome::BadMessage(msg)
            } else {
                // The class: the message up to its first colon after the file name.
                let class = msg.split(':').nth(1).unwrap_or(&msg).trim();
                Outcome::Refused(class.chars().take(40).collect())
            }
        }
    }
}

pub fn fixtures_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/formats")
}

fn seeds_in(dir: &Path, ext: &[&str]) -> Vec<Vec<u8>> {
    let mut paths: Vec<PathBuf> = std::fs::read_dir(dir)
        .map(|d| d.filter_map(|e| e.ok()).map(|e| e.path()).collect())
        .unwrap_or_default();
    paths.sort();
    paths
        .iter()
        .filter(|p| {
            let name = p.to_string_lossy().to_ascii_lowercase();
            ext.iter().any(|e| name.ends_with(e))
        })
        .filter_map(|p| std::fs::read(p).ok())
        .collect()
}

/// Parses as a sketch of the given file name, in the fixtures folder (a VRT's sources lie there).
fn sketch(name: &str, bytes: &[u8]) -> Outcome {
    outcome(parse_grid(
        &fixtures_dir().join(name),
        bytes,
        &LoadOptions::default(),
    ))
}

pub fn targets() -> Vec<Target> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let fx = fixtures_dir();
    let own = root.join("fuzz/seeds");
    let cat = |a: Vec<Vec<u8>>, b: Vec<Vec<u8>>| a.into_iter().chain(b).collect::<Vec<_>>();
    vec![
        Target {
            name: "geotiff",
            seeds: seeds_in(&fx, &[".tif"]),
            text: false,
            run: |b| sketch("fuzz.tif", b),
        },
        Target {
            name: "png",
            seeds: seeds_in(&fx, &[".png"]),
            text: false,
            // With its CRCs mended, a mutant reaches the decoder instead of the checksum.
            run: |b| {
                let mut b = b.to_vec();
                mend_png_crcs(&mut b);
                sketch("fuzz.png", &b)
            },
        },
        Target {
            name: "world-file",
            seeds: seeds_in(&fx, &[".pgw"]),
            text: true,
            run: |b| outcome(parse_world_file(Path::new("fuzz.pgw"), b)),
        },
        Target {
            name: "hgt-zip",
            seeds: cat(seeds_in(&own, &[".hgt.zip"]), seeds_in(&fx, &[".hgt.zip"])),
            text: false,
            run: |b| sketch("N36W084.hgt.zip", b),
        },
        Target {
            name: "hgt",
            seeds: vec![vec![0u8; 64], vec![0u8; 1201 * 1201 * 2]],
            text: false,
            run: |b| sketch("N36W084.hgt", b),
        },
        Target {
            name: "esri-ascii",
            seeds: cat(seeds_in(&fx, &[".asc"]), seeds_in(&own, &[".asc"])),
            text: true,
            run: |b| sketch("fuzz.asc", b),
        },
        Target {
            name: "xyz",
            seeds: cat(xyz_head(&fx), seeds_in(&own, &[".xyz"])),
            text: true,
            run: |b| sketch("fuzz.xyz", b),
        },
        Target {
            name: "vrt",
            seeds: seeds_in(&fx, &[".vrt"]),
            text: true,
            run: |b| sketch("fuzz.vrt", b),
        },
        Target {
            name: "scene",
            seeds: seeds_in(&root.join("sketches"), &[".toml"]),
            text: true,
            run: |b| match std::str::from_utf8(b) {
                Ok(t) => outcome(
                    terrain_engine::scene::Scene::parse(t, root_dir().join("sketches"))
                        .map_err(|f| f.into_error(Path::new("fuzz.toml"))),
                ),
                Err(_) => Outcome::Refused("not UTF-8".into()),
            },
        },
        Target {
            name: "jobs",
            seeds: seeds_in(&root.join("sketches"), &["random-snapshots.toml"]),
            text: true,
            run: |b| match std::str::from_utf8(b) {
                Ok(t) => {
                    match terrain_cli::app::batch::Jobs::parse(
                        &root_dir().join("sketches/fuzz.toml"),
                        t,
                    ) {
                        Err(e) => outcome::<(), _>(Err(e)),
                        // Each job's scene is where a job's keys are checked.
                        Ok(j) => (0..j.explicit_jobs().min(8))
                            .map(|k| outcome(j.job_scene(k)))
                            .find(|o| *o != Outcome::Read)
                            .unwrap_or(Outcome::Read),
                    }
                }
                Err(_) => Outcome::Refused("not UTF-8".into()),
            },
        },
    ]
}

/// Rewrites the CRC of every whole chunk after the PNG signature.
fn mend_png_crcs(b: &mut [u8]) {
    let mut k = 8;
    while k + 12 <= b.len() {
        let len = u32::from_be_bytes([b[k], b[k + 1], b[k + 2], b[k + 3]]) as usize;
        let Some(end) = (k + 8).checked_add(len).filter(|&e| e + 4 <= b.len()) else {
            return;
        };
        let crc = crc32fast::hash(&b[k + 4..end]);
        b[end..end + 4].copy_from_slice(&crc.to_be_bytes());
        k = end + 4;
    }
}

fn root_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The XYZ fixture's first 120 lines: the whole file takes 40× longer per execution and its
/// later lines exercise nothing the first ones do not.
fn xyz_head(fx: &Path) -> Vec<Vec<u8>> {
    seeds_in(fx, &[".xyz"])
        .into_iter()
        .map(|s| {
            let text = String::from_utf8_lossy(&s).into_owned();
            text.lines()
                .take(120)
                .collect::<Vec<_>>()
                .join("\n")
                .into_bytes()
        })
        .collect()
}

/// SplitMix64: a deterministic stream per worker, so a run is repeatable from its seed.
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Rng {
        Rng(seed)
    }
    pub fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    pub fn below(&mut self, n: usize) -> usize {
        if n == 0 {
            0
        } else {
            (self.next() % n as u64) as usize
        }
    }
}

const INTERESTING: [u64; 14] = [
    0,
    1,
    2,
    0x7f,
    0x80,
    0xff,
    0x7fff,
    0x8000,
    0xffff,
    0x1_0000,
    0x7fff_ffff,
    0x8000_0000,
    0xffff_ffff,
    u64::MAX,
];
const NUMBERS: [&str; 16] = [
    "0",
    "-1",
    "1",
    "2",
    "65536",
    "4294967296",
    "1e308",
    "-1e308",
    "1e-300",
    "nan",
    "inf",
    "-inf",
    "-0",
    "0.5",
    "99999999999999999999",
    "",
];

/// Bytes a text target's random writes draw from, so most mutants stay UTF-8 and reach the
/// parser rather than its encoding check.
const TEXT_BYTES: &[u8] = b" \n\t\r0123456789.-+eE,;:=#[]{}\"'<>/xyzXYZnaif_";

/// A random byte: any for binary targets, from [`TEXT_BYTES`] mostly for text ones.
fn random_byte(rng: &mut Rng, text: bool) -> u8 {
    if text && rng.below(16) != 0 {
        TEXT_BYTES[rng.below(TEXT_BYTES.len())]
    } else {
        rng.next() as u8
    }
}

/// Applies one havoc mutation.
fn mutate_once(data: &mut Vec<u8>, rng: &mut Rng, other: &[u8], text: bool) {
    let len = data.len();
    // Text targets trade the binary integer writes (2, 3) for more number tokens (9).
    let op = match rng.below(10) {
        2 | 3 if text => 9,
        9 if !text => 8,
        op => op,
    };
    match op {
        0 if len > 0 => {
            let k = rng.below(len);
            data[k] ^= 1 << rng.below(if text { 7 } else { 8 });
        }
        1 if len > 0 => {
            let k = rng.below(len);
            data[k] = random_byte(rng, text);
        }
        2 | 3 if len >= 8 => {
            let width = [1, 2, 4, 8][rng.below(4)];
            let k = rng.below(len - width + 1);
            let v = INTERESTING[rng.below(INTERESTING.len())];
            let bytes = if rng.below(2) == 0 {
                v.to_le_bytes()
            } else {
                v.to_be_bytes()
            };
            let bytes = if bytes[0] == 0 && width < 8 {
                &bytes[8 - width..]
            } else {
                &bytes[..width]
            };
            data[k..k + width].copy_from_slice(bytes);
        }
        4 if len > 1 => {
            let k = rng.below(len);
            let n = 1 + rng.below((len - k).min(256));
            data.drain(k..k + n);
        }
        5 if len > 1 => {
            let k = rng.below(len);
            let n = 1 + rng.below((len - k).min(256));
            let block: Vec<u8> = data[k..k + n].to_vec();
            let at = rng.below(len + 1);
            data.splice(at..at, block);
        }
        6 if len > 0 => data.truncate(rng.below(len)),
        7 if !other.is_empty() && len > 0 => {
            let cut = rng.below(len);
            let from = rng.below(other.len());
            data.truncate(cut);
            data.extend_from_slice(&other[from..]);
        }
        8 if len > 0 => {
            let k = rng.below(len);
            let n = 1 + rng.below(16);
            let at = k.min(data.len());
            let bytes: Vec<u8> = (0..n).map(|_| random_byte(rng, text)).collect();
            data.splice(at..at, bytes);
        }
        9 => {
            // Replace a numeric token by an interesting number.
            let starts: Vec<usize> = (0..len)
                .filter(|&k| {
                    (data[k].is_ascii_digit() || data[k] == b'-')
                        && (k == 0 || !data[k - 1].is_ascii_alphanumeric())
                })
                .collect();
            if let Some(&k) = starts.get(rng.below(starts.len().max(1))) {
                let end = (k + 1..len)
                    .find(|&e| !(data[e].is_ascii_alphanumeric() || b".-+".contains(&data[e])))
                    .unwrap_or(len);
                let n = NUMBERS[rng.below(NUMBERS.len())].as_bytes();
                data.splice(k..end, n.iter().copied());
            }
        }
        _ => {}
    }
}

/// A mutated copy of one of the target's seeds.
pub fn mutant(target: &Target, rng: &mut Rng) -> Vec<u8> {
    let seed = &target.seeds[rng.below(target.seeds.len())];
    let other = &target.seeds[rng.below(target.seeds.len())];
    let mut data = seed.clone();
    for _ in 0..1 + rng.below(8) {
        mutate_once(&mut data, rng, other, target.text);
    }
    data
}

/// What a run of one target found.
#[derive(Debug, Default)]
pub struct Report {
    pub execs: u64,
    pub read: u64,
    pub refused: u64,
    pub crashes: Vec<(String, PathBuf)>,
    pub bad_messages: Vec<String>,
    pub classes: std::collections::BTreeMap<String, u64>,
    pub slowest: Duration,
    pub elapsed: Duration,
}

/// Runs `execs` mutated inputs of `target` (or uniform random bytes of a seed's length when
/// `random`), writing crashing inputs under `crash_dir`.
pub fn fuzz(target: &Target, execs: u64, seed: u64, random: bool, crash_dir: &Path) -> Report {
    let mut rng = Rng::new(seed ^ fnv(target.name));
    let mut report = Report::default();
    let start = Instant::now();
    for _ in 0..execs {
        let input = if random {
            let n = target.seeds[rng.below(target.seeds.len())].len();
            (0..n).map(|_| rng.next() as u8).collect()
        } else {
            mutant(target, &mut rng)
        };
        let t = Instant::now();
        let result = std::panic::catch_unwind(AssertUnwindSafe(|| (target.run)(&input)));
        report.slowest = report.slowest.max(t.elapsed());
        report.execs += 1;
        match result {
            Ok(Outcome::Read) => report.read += 1,
            Ok(Outcome::Refused(class)) => {
                report.refused += 1;
                *report.classes.entry(class).or_default() += 1;
            }
            Ok(Outcome::BadMessage(msg)) => {
                report.refused += 1;
                if report.bad_messages.len() < 10 {
                    report.bad_messages.push(msg);
                }
            }
            Err(panic) => {
                let msg = panic
                    .downcast_ref::<String>()
                    .cloned()
                    .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
                    .unwrap_or_default();
                let _ = std::fs::create_dir_all(crash_dir);
                let path =
                    crash_dir.join(format!("{}-{:016x}.bin", target.name, fnv_bytes(&input)));
                let _ = std::fs::write(&path, &input);
                report.crashes.push((msg, path));
            }
        }
    }
    report.elapsed = start.elapsed();
    report
}

fn fnv(s: &str) -> u64 {
    fnv_bytes(s.as_bytes())
}

fn fnv_bytes(b: &[u8]) -> u64 {
    b.iter().fold(0xcbf2_9ce4_8422_2325, |h, &x| {
        (h ^ x as u64).wrapping_mul(0x100_0000_01b3)
    })
}

/// Silences the default panic message (a crash is reported with its input instead).
pub fn quiet_panics() {
    std::panic::set_hook(Box::new(|_| {}));
}
