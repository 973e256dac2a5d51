//! Replays every input under `fuzz/regressions/` through its fuzz harness (`fuzz/harness.rs`, the
//! code the cargo-fuzz targets run): each is an input that once broke an invariant, kept so that
//! the bug stays fixed. A harness panics when an invariant breaks, failing this test.

#[allow(clippy::all, clippy::pedantic)]
#[path = "../../../fuzz/harness.rs"]
mod harness;

use std::path::Path;

fn replay(target: &str, harness: fn(&[u8])) -> usize {
    let folder = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../fuzz/regressions")
        .join(target);
    // Git keeps no empty folder: a target without regressions has none.
    let Ok(entries) = std::fs::read_dir(&folder) else {
        return 0;
    };
    let mut inputs: Vec<_> = entries
        .map(|e| e.expect("a directory entry").path())
        .filter(|p| p.is_file())
        .collect();
    inputs.sort();
    for input in &inputs {
        let data = std::fs::read(input).expect("a readable input");
        eprintln!("{target}: {}", input.display());
        harness(&data);
    }
    inputs.len()
}

#[test]
fn delaunay_regressions() {
    assert!(replay("delaunay", harness::delaunay) >= 3);
}

#[test]
fn refine_regressions() {
    replay("refine", harness::refine);
}

#[test]
fn simplify_regressions() {
    replay("simplify", harness::simplify);
}

#[test]
fn pipeline_regressions() {
    replay("pipeline", harness::pipeline);
}

#[test]
fn decode_regressions() {
    replay("decode", harness::decode);
}

/// The harnesses on a few fixed inputs of every kind: they accept them (a harness that panics on
/// valid input would make the fuzzers useless) and reject nothing silently.
#[test]
fn harnesses_accept_ordinary_inputs() {
    let lattice: Vec<u8> = std::iter::once(0)
        .chain((0..200).map(|i| (i * 37 % 251) as u8))
        .collect();
    harness::delaunay(&lattice);
    harness::delaunay(&[1, 0, 0, 0, 1, 16, 0, 0, 0, 0, 0, 16, 0]);
    harness::refine(&lattice);
    harness::simplify(&lattice);
    harness::pipeline(&lattice);
    let mut png = Vec::new();
    image::GrayImage::from_fn(12, 9, |x, y| {
        image::Luma([if x * y > 20 { 255 } else { 0 }])
    })
    .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
    .unwrap();
    harness::decode(&png);
    harness::decode(b"GIF89a not really");
}
