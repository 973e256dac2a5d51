//! Imesh on an image: classify, sample, partition, refine, and print what each stage did.
//!
//! `cargo run --release -p imesh-segment --example imesh_triangles -- fixtures/images/skimage-coins.png [t_e] [min angle]`

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

use imesh_classify::{classify, load_image, Classifier, ClassifyOptions, DEFAULT_MAX_PIXELS};
use imesh_geom::RefineOptions;
use imesh_quality::{validate, Domain, Element, MeshView, TriangleQuality};
use imesh_segment::{SampleOptions, SegmentedMesh, DEFAULT_MIN_ANGLE};

fn main() -> ExitCode {
    let mut args = std::env::args().skip(1);
    let Some(path) = args.next().map(PathBuf::from) else {
        eprintln!("usage: imesh_triangles IMAGE [t_e] [min angle]");
        return ExitCode::from(2);
    };
    let te = args.next().and_then(|a| a.parse().ok()).unwrap_or(0.1);
    let angle = args
        .next()
        .and_then(|a| a.parse().ok())
        .unwrap_or(DEFAULT_MIN_ANGLE);
    match run(&path, te, angle) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(2)
        }
    }
}

fn run(path: &Path, te: f64, angle: f64) -> Result<(), Box<dyn std::error::Error>> {
    let start = Instant::now();
    let image = load_image(path, DEFAULT_MAX_PIXELS)?;
    let grid = classify(&image, &Classifier::Auto, &ClassifyOptions::default())?;
    let classified = start.elapsed().as_secs_f64();
    let options = SampleOptions {
        te,
        ..Default::default()
    };
    let mut mesh = SegmentedMesh::from_grid(&grid, &options)?;
    let sampled = start.elapsed().as_secs_f64();
    let agreement = mesh.label_agreement(&grid);
    let report = mesh.refine(&RefineOptions {
        min_angle_deg: angle,
        ..Default::default()
    })?;
    let refined = start.elapsed().as_secs_f64();
    let (vertices, triangles, labels) = mesh.arrays();
    let elements: Vec<Element> = triangles.iter().map(|&t| Element::Triangle(t)).collect();
    let view = MeshView {
        vertices: &vertices,
        elements: &elements,
        labels: &labels,
    };
    let domain = Domain::image(f64::from(grid.width()), f64::from(grid.height()));
    let valid = validate(&view, &domain);
    let quality = TriangleQuality::of(&vertices, &triangles);
    println!(
        "{}: {}×{} px, {} labels",
        path.display(),
        grid.width(),
        grid.height(),
        grid.num_labels()
    );
    println!(
        "classify {classified:.3} s; sample + partition {:.3} s: {} vertices in {} rounds, {} c-edges, label agreement {agreement:.4}",
        sampled - classified,
        mesh.inserted,
        mesh.rounds,
        mesh.c_edges.len()
    );
    println!(
        "refine to {angle}°: {:.3} s, {} points inserted, {} triangles left below ({:?})",
        refined - sampled,
        report.inserted,
        report.bad_left,
        report.stopped
    );
    println!(
        "{} vertices, {} triangles; smallest angle: worst {:.2}°, mean {:.2}°; invariants hold: {}",
        vertices.len(),
        triangles.len(),
        quality.min_angle_deg.min,
        quality.min_angle_deg.mean,
        valid.is_valid()
    );
    if !valid.is_valid() {
        return Err(format!("invalid mesh: {valid:?}").into());
    }
    Ok(())
}
