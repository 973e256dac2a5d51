//! Running the `imesh` program from the tests that drive it (`cli.rs`, `interop.rs`).

use std::path::Path;
use std::process::{Command, Output};

/// `imesh args`, run in `dir`.
pub fn imesh(args: &[&str], dir: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_imesh"))
        .args(args)
        .current_dir(dir)
        .output()
        .expect("the imesh binary runs")
}

/// [`imesh`], which must succeed (its stderr shown if not).
pub fn imesh_ok(args: &[&str], dir: &Path) -> Output {
    let out = imesh(args, dir);
    assert!(
        out.status.success(),
        "imesh {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// The JSON report `r.json` a run wrote in `dir`.
pub fn read_report(dir: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("r.json")).unwrap()).unwrap()
}

/// What `imesh quality FILE --json` prints, run in `dir`.
pub fn quality_json(dir: &Path, file: &str) -> serde_json::Value {
    serde_json::from_slice(&imesh_ok(&["quality", file, "--json"], dir).stdout).unwrap()
}

/// The block of `imesh quality --json` with the statistics of `elements` (`quad` or `tri`).
pub fn quality_block(elements: &str) -> &'static str {
    if elements == "quad" {
        "quad_quality"
    } else {
        "triangle_quality"
    }
}

/// Asserts that the minimum and mean shape, scaled Jacobian and smallest angle of `measured`
/// (metric blocks as `imesh quality --json` and the report give them) are `reference`'s, to
/// `tolerance` relatively.
pub fn assert_same_statistics(
    measured: &serde_json::Value,
    reference: &serde_json::Value,
    tolerance: f64,
    what: &str,
) {
    for metric in ["shape", "scaled_jacobian", "min_angle_deg"] {
        for s in ["min", "mean"] {
            let (a, b) = (
                measured[metric][s].as_f64().unwrap(),
                reference[metric][s].as_f64().unwrap(),
            );
            assert!(
                (a - b).abs() <= tolerance * b.abs().max(1.0),
                "{what} {metric} {s}: {a} vs {b}"
            );
        }
    }
}
