//! The fuzz harness (fuzz/harness.rs) from the command line:
//!
//! ```text
//! cargo run --release --example fuzz -- --execs 1000000            # every target
//! cargo run --release --example fuzz -- --target geotiff --execs 5000000 --seed 7
//! cargo run --release --example fuzz -- --target geotiff --random  # random bytes, for comparison
//! ```
//!
//! Targets run on two threads (this machine's cores); each prints executions, inputs read,
//! inputs refused, crashes (inputs written to target/fuzz/crashes/), multi-line messages, the
//! slowest execution and the refusal classes. Exits 1 if anything crashed or a message spans lines.

#[path = "../fuzz/harness.rs"]
mod harness;

use std::path::PathBuf;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let value = |flag: &str| {
        args.iter()
            .position(|a| a == flag)
            .and_then(|k| args.get(k + 1))
            .cloned()
    };
    let execs: u64 = value("--execs").map_or(100_000, |v| v.parse().expect("--execs N"));
    let seed: u64 = value("--seed").map_or(1, |v| v.parse().expect("--seed S"));
    let only = value("--target");
    let random = args.iter().any(|a| a == "--random");
    let threads: usize = value("--threads").map_or(2, |v| v.parse().expect("--threads N"));
    terrain_engine::sketch::limit_cells(1 << 22);
    harness::quiet_panics();
    let crash_dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("target/fuzz/crashes");
    let targets: Vec<_> = harness::targets()
        .into_iter()
        .filter(|t| only.as_deref().is_none_or(|o| o == t.name))
        .collect();
    if targets.is_empty() {
        eprintln!("no target named {only:?}");
        std::process::exit(2);
    }
    let failed = std::sync::atomic::AtomicBool::new(false);
    let next = std::sync::atomic::AtomicUsize::new(0);
    let print = std::sync::Mutex::new(());
    std::thread::scope(|s| {
        for _ in 0..threads {
            let (targets, next, failed, print, crash_dir) =
                (&targets, &next, &failed, &print, &crash_dir);
            s.spawn(move || {
                loop {
                    let k = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                    let Some(t) = targets.get(k) else { break };
                    let r = harness::fuzz(t, execs, seed, random, crash_dir);
                    let _guard = print.lock();
                    println!(
                        "{:<11} {:>10} execs  {:>9} read  {:>10} refused  {} crashes  {} multi-line  slowest {:.1} ms  {:.0} execs/s",
                        t.name,
                        r.execs,
                        r.read,
                        r.refused,
                        r.crashes.len(),
                        r.bad_messages.len(),
                        r.slowest.as_secs_f64() * 1e3,
                        r.execs as f64 / r.elapsed.as_secs_f64()
                    );
                    let mut classes: Vec<_> = r.classes.iter().collect();
                    classes.sort_by(|a, b| b.1.cmp(a.1));
                    for (class, n) in classes.iter().take(6) {
                        println!("    {:>5.1} %  {class}", 100.0 * **n as f64 / r.execs as f64);
                    }
                    for (msg, path) in r.crashes.iter().take(5) {
                        println!("    CRASH {msg} ({})", path.display());
                    }
                    for msg in &r.bad_messages {
                        println!("    MULTI-LINE {msg:?}");
                    }
                    if !r.crashes.is_empty() || !r.bad_messages.is_empty() {
                        failed.store(true, std::sync::atomic::Ordering::Relaxed);
                    }
                }
            });
        }
    });
    if failed.load(std::sync::atomic::Ordering::Relaxed) {
        std::process::exit(1);
    }
}
