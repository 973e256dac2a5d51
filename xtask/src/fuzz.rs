//! `cargo xtask fuzz`: coverage-guided fuzzing of the harnesses in `fuzz/harness.rs` with
//! cargo-fuzz (libFuzzer, on the nightly toolchain), one target after the other, each for a
//! fixed time. Inputs that break an invariant land in `fuzz/artifacts/TARGET/`; once the bug is
//! fixed, copy them to `fuzz/regressions/TARGET/`, where `cargo test` replays them.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

/// The harnesses, in the order they run.
pub const TARGETS: [&str; 6] = [
    "delaunay", "refine", "simplify", "pipeline", "decode", "read",
];

/// Options of `cargo xtask fuzz`.
pub struct Options {
    /// Targets to run (all when empty).
    pub targets: Vec<String>,
    /// Seconds of fuzzing per target.
    pub seconds: u64,
}

fn fuzz_dir() -> Result<PathBuf, String> {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .map(|root| root.join("fuzz"))
        .ok_or_else(|| "xtask is not inside the workspace".to_string())
}

/// The files of a folder (none if it does not exist).
fn files(dir: &Path) -> Vec<PathBuf> {
    std::fs::read_dir(dir)
        .map(|entries| {
            entries
                .filter_map(Result::ok)
                .map(|e| e.path())
                .filter(|p| p.is_file())
                .collect()
        })
        .unwrap_or_default()
}

/// Runs each target for `options.seconds`, then lists what each found.
pub fn run(options: &Options) -> Result<(), String> {
    let targets: Vec<&str> = if options.targets.is_empty() {
        TARGETS.to_vec()
    } else {
        options.targets.iter().map(String::as_str).collect()
    };
    if let Some(bad) = targets.iter().find(|t| !TARGETS.contains(t)) {
        return Err(format!(
            "unknown fuzz target '{bad}': the targets are {}",
            TARGETS.join(", ")
        ));
    }
    let found = Command::new("cargo")
        .args(["+nightly", "fuzz", "--version"])
        .output();
    if !found.is_ok_and(|o| o.status.success()) {
        return Err(
            "cargo-fuzz on the nightly toolchain is needed: `rustup toolchain install \
                    nightly` and `cargo install cargo-fuzz`"
                .into(),
        );
    }
    let dir = fuzz_dir()?;
    let mut rows = Vec::new();
    for target in targets {
        let corpus = dir.join("corpus").join(target);
        let artifacts = dir.join("artifacts").join(target);
        for d in [&corpus, &artifacts] {
            std::fs::create_dir_all(d)
                .map_err(|e| format!("cannot create {}: {e}", d.display()))?;
        }
        let before = files(&artifacts).len();
        println!("== fuzzing {target} for {} s", options.seconds);
        let clock = Instant::now();
        // Fork mode with crashes ignored: a bug found early does not end the run; every input
        // that broke an invariant is kept in the artifacts folder.
        let status = Command::new("cargo")
            .current_dir(&dir)
            .args(["+nightly", "fuzz", "run", "-O", target])
            .arg(&corpus)
            .arg("--")
            .args([
                format!("-max_total_time={}", options.seconds),
                "-timeout=20".into(),
                "-rss_limit_mb=2048".into(),
                "-fork=1".into(),
                "-ignore_crashes=1".into(),
                "-ignore_timeouts=1".into(),
                "-ignore_ooms=1".into(),
            ])
            .status()
            .map_err(|e| format!("cannot run cargo fuzz: {e}"))?;
        // libFuzzer exits non-zero when it found failing inputs (the table below counts them);
        // a build failure leaves no corpus to speak of and shows in cargo's output above.
        if !status.success() {
            println!("cargo fuzz run {target}: {status}");
        }
        rows.push((
            target,
            clock.elapsed().as_secs(),
            files(&corpus).len(),
            files(&artifacts).len() - before,
        ));
    }
    println!("\n| target | seconds | corpus | new artifacts |\n|---|---|---|---|");
    for (target, seconds, corpus, new) in &rows {
        println!("| {target} | {seconds} | {corpus} | {new} |");
    }
    if rows.iter().any(|r| r.3 > 0) {
        println!(
            "\nNew inputs under fuzz/artifacts/: reproduce one with `cargo +nightly fuzz run TARGET \
             FILE` (from fuzz/), fix the bug, then copy the file to fuzz/regressions/TARGET/."
        );
    }
    Ok(())
}
