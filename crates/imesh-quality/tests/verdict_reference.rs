//! Our metrics against a table produced by VTK 9.7.2's vtkMeshQuality (Verdict) itself.
//!
//! The table (`fixtures/quality/verdict-*.csv`) holds random convex, nearly degenerate,
//! non-convex, inverted and square elements; `cargo xtask fixtures quality` regenerates it with the
//! committed script `xtask/scripts/verdict_reference.py`.

use imesh_quality::{quad, tri, Point2};

struct Table {
    columns: Vec<String>,
    rows: Vec<(String, Vec<f64>)>,
}

fn read(name: &str) -> Table {
    let path = format!(
        "{}/../../fixtures/quality/{name}",
        env!("CARGO_MANIFEST_DIR")
    );
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path}: {e}"));
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
    let header = lines.next().expect("a header line");
    let columns: Vec<String> = header.split(',').skip(1).map(str::to_string).collect();
    let rows = lines
        .map(|l| {
            let mut f = l.split(',');
            let kind = f.next().expect("a kind").to_string();
            let v: Vec<f64> = f
                .map(|x| x.parse().unwrap_or_else(|_| panic!("bad number {x}")))
                .collect();
            assert_eq!(v.len(), columns.len());
            (kind, v)
        })
        .collect();
    Table { columns, rows }
}

impl Table {
    fn col(&self, name: &str) -> usize {
        self.columns
            .iter()
            .position(|c| c == name)
            .unwrap_or_else(|| panic!("no column {name}"))
    }
}

/// Relative difference, with values below 1e-300 treated as zero.
///
/// The issue asks for 1e-9; replicating Verdict's operation order gets within a few ulps
/// (worst seen: 4.6e-16 on quads, 2.1e-16 on triangles), so the tests hold us to 1e-12.
fn rel_diff(ours: f64, vtk: f64) -> f64 {
    if ours == vtk || (ours.is_nan() && vtk.is_nan()) {
        return 0.0;
    }
    (ours - vtk).abs() / vtk.abs().max(ours.abs()).max(1e-300)
}

type QuadMetric = (&'static str, fn(&quad::Quad, f64) -> f64);

#[test]
fn quad_metrics_match_vtk() {
    let t = read("verdict-quads.csv");
    assert!(t.rows.len() >= 200);
    for kind in [
        "square",
        "convex",
        "near_degenerate",
        "non_convex",
        "inverted",
    ] {
        assert!(
            t.rows.iter().any(|(k, _)| k == kind),
            "no {kind} quads in the table"
        );
    }
    let quads: Vec<quad::Quad> = t
        .rows
        .iter()
        .map(|(_, v)| [0, 1, 2, 3].map(|i| -> Point2 { [v[2 * i], v[2 * i + 1]] }))
        .collect();
    // vtkMeshQuality's average: the mean Verdict area over all quads of the dataset.
    let average = quads.iter().map(quad::area).sum::<f64>() / quads.len() as f64;
    let metrics: [QuadMetric; 11] = [
        ("area", |q, _| quad::area(q)),
        ("shape", |q, _| quad::shape(q)),
        ("relative_size_squared", quad::relative_size_squared),
        ("shape_and_size", quad::shape_and_size),
        ("scaled_jacobian", |q, _| quad::scaled_jacobian(q)),
        ("condition", |q, _| quad::condition(q)),
        ("jacobian", |q, _| quad::jacobian(q)),
        ("minimum_angle", |q, _| quad::minimum_angle(q)),
        ("maximum_angle", |q, _| quad::maximum_angle(q)),
        ("aspect_ratio", |q, _| quad::aspect_ratio(q)),
        ("edge_ratio", |q, _| quad::edge_ratio(q)),
    ];
    let mut worst = 0.0f64;
    for (name, f) in metrics {
        let c = t.col(name);
        for (i, q) in quads.iter().enumerate() {
            let (ours, vtk) = (f(q, average), t.rows[i].1[c]);
            let d = rel_diff(ours, vtk);
            assert!(
                d <= 1e-12,
                "quad {i} ({}) {name}: ours {ours:e}, VTK {vtk:e}, corners {q:?}",
                t.rows[i].0
            );
            worst = worst.max(d);
        }
    }
    println!(
        "worst relative difference over {} quads: {worst:e}",
        quads.len()
    );
}

type TriMetric = (&'static str, fn(&tri::Triangle, f64) -> f64);

#[test]
fn triangle_metrics_match_vtk() {
    let t = read("verdict-triangles.csv");
    assert!(t.rows.len() >= 100);
    let tris: Vec<tri::Triangle> = t
        .rows
        .iter()
        .map(|(_, v)| [0, 1, 2].map(|i| -> Point2 { [v[2 * i], v[2 * i + 1]] }))
        .collect();
    let average = tris.iter().map(tri::area).sum::<f64>() / tris.len() as f64;
    let metrics: [TriMetric; 9] = [
        ("area", |t, _| tri::area(t)),
        ("shape", |t, _| tri::shape(t)),
        ("condition", |t, _| tri::condition(t)),
        ("scaled_jacobian", |t, _| tri::scaled_jacobian(t)),
        ("minimum_angle", |t, _| tri::minimum_angle(t)),
        ("maximum_angle", |t, _| tri::maximum_angle(t)),
        ("aspect_ratio", |t, _| tri::aspect_ratio(t)),
        ("relative_size_squared", tri::relative_size_squared),
        ("shape_and_size", tri::shape_and_size),
    ];
    let mut worst = 0.0f64;
    for (name, f) in metrics {
        let c = t.col(name);
        for (i, tr) in tris.iter().enumerate() {
            let (ours, vtk) = (f(tr, average), t.rows[i].1[c]);
            let d = rel_diff(ours, vtk);
            assert!(
                d <= 1e-12,
                "triangle {i} ({}) {name}: ours {ours:e}, VTK {vtk:e}, corners {tr:?}",
                t.rows[i].0
            );
            worst = worst.max(d);
        }
    }
    println!(
        "worst relative difference over {} triangles: {worst:e}",
        tris.len()
    );
}
