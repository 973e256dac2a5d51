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

#[test]
fn read_regressions() {
    assert!(replay("read", harness::read) >= 1);
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
    // A valid file of every format the readers take, and the same bytes as the others.
    let files: [&[u8]; 4] = [
        b"$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n3\n1 0 0 0\n2 1 0 0\n3 0 1 0\n$EndNodes\n$Elements\n1\n1 2 0 1 2 3\n$EndElements\n",
        b"# vtk DataFile Version 3.0\nx\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 3 double\n0 0 0 1 0 0 0 1 0\nCELLS 1 4\n3 0 1 2\nCELL_TYPES 1\n5\n",
        br#"<VTKFile type="UnstructuredGrid"><Piece><Points><DataArray NumberOfComponents="3" format="ascii">0 0 0 1 0 0 0 1 0</DataArray></Points><Cells><DataArray Name="connectivity" format="ascii">0 1 2</DataArray><DataArray Name="offsets" format="ascii">3</DataArray><DataArray Name="types" format="ascii">5</DataArray></Cells></Piece></VTKFile>"#,
        b"*Node\n1, 0, 0\n2, 1, 0\n3, 0, 1\n*Element, type=CPS3\n1, 1, 2, 3\n",
    ];
    for format in 0..4u8 {
        for file in files {
            harness::read(&[&[format][..], file].concat());
        }
    }
}
