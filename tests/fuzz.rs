//! A short pass of the fuzz harness (fuzz/harness.rs) over every target, so CI runs each reader
//! and parser on a few thousand mutated inputs: no panic, every refusal one line. The 10-million
//! execution campaign is `fuzz/campaign.sh` (docs/formats.md).

#[path = "../fuzz/harness.rs"]
mod harness;

#[test]
fn every_target_survives_a_short_mutation_pass() {
    terrain_engine::sketch::limit_cells(1 << 22);
    harness::quiet_panics();
    let crash_dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("target/fuzz/ci-crashes");
    let mut failures = Vec::new();
    for t in harness::targets() {
        assert!(!t.seeds.is_empty(), "{}: no seeds", t.name);
        // The SRTM targets inflate or copy a 2.9 MB tile per execution.
        let execs = if t.name.starts_with("hgt") { 300 } else { 4000 };
        let r = harness::fuzz(&t, execs, 2026, false, &crash_dir);
        // A target that reads nothing or refuses nothing is not exercising its parser.
        if r.read == 0 || r.refused == 0 {
            failures.push(format!(
                "{}: {} read, {} refused",
                t.name, r.read, r.refused
            ));
        }
        for (msg, path) in &r.crashes {
            failures.push(format!("{}: panic `{msg}` on {}", t.name, path.display()));
        }
        for msg in &r.bad_messages {
            failures.push(format!(
                "{}: message of more than one line: {msg:?}",
                t.name
            ));
        }
    }
    std::panic::set_hook(Box::new(|info| eprintln!("{info}")));
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
