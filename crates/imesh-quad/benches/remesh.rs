//! Criterion benchmark of the quad stage after DT': pairing, patches, templates and boundary
//! adaptation, on the DT' of a real image's simplified boundaries (scikit-image's "grass",
//! 512 × 512, Otsu: thousands of blades; 50 282 triangles, the paper's graded DT').
//!
//! `cargo bench -p imesh-quad`. Goal (issue 7): pairing + templates + adaptation in < 50 ms for
//! 10^5 triangles, so < 25 ms here; the next group is the same boundaries refined to about
//! 10^5 triangles, the last a label image's (stardist's nuclei) refined to about 10^5.

use std::hint::black_box;
use std::path::Path;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use imesh_classify::{luminance, multi_otsu_levels, threshold};
use imesh_curves::{CubicBezier, CurveGraph};
use imesh_quad::{
    adapt, AdaptReport, ControlNet, DensityOptions, ElementMesh, Pairing, QuadMesh,
    RegionTriangulation,
};

// The c-edge graph of a label grid, as imesh-curves' tests build it.
#[path = "../../imesh-curves/tests/support/mod.rs"]
mod support;

fn bench(c: &mut Criterion) {
    let path =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/images/skimage-grass.png");
    let image = imesh_classify::load_image(&path, imesh_classify::DEFAULT_MAX_PIXELS)
        .expect("the fixture skimage-grass.png loads");
    let grey = luminance(&image);
    let grid = threshold(&grey, &multi_otsu_levels(&grey, 2));
    let (g, s, curves) = support::simplified_with_curves(&grid);
    let dt = RegionTriangulation::new(&s.graph, &DensityOptions::default()).expect("DT' builds");
    let triangles = dt.triangulation.num_triangles();
    eprintln!(
        "grass: {} c-edges, {} G' edges, DT' {triangles} triangles",
        g.edges().len(),
        s.graph.edges().len()
    );

    {
        let elements = ElementMesh::pair(&dt.triangulation, Pairing::Greedy);
        let mut net = ControlNet::straight(&dt.triangulation, &elements);
        let mut q = QuadMesh::build(&dt.triangulation, &elements, &net, 1);
        let t0 = std::time::Instant::now();
        let (report, _) = adapt(&dt, &s.graph, &curves, &elements, &mut net, &mut q);
        eprintln!(
            "{} quads, {} unpaired; adaptation {:?} in {:?}",
            q.quads.len(),
            elements.unpaired,
            report,
            t0.elapsed()
        );
    }
    let mut group = c.benchmark_group("quad stage grass");
    group.sample_size(10);
    group.throughput(Throughput::Elements(triangles as u64));
    for pairing in [Pairing::Greedy, Pairing::Matching] {
        group.bench_function(format!("pair {pairing:?}, {triangles} triangles"), |b| {
            b.iter(|| black_box(ElementMesh::pair(&dt.triangulation, pairing)))
        });
    }
    let elements = ElementMesh::pair(&dt.triangulation, Pairing::Greedy);
    group.bench_function("patches + templates k = 1", |b| {
        b.iter(|| {
            let net = ControlNet::straight(&dt.triangulation, &elements);
            black_box(QuadMesh::build(&dt.triangulation, &elements, &net, 1))
        })
    });
    group.bench_function("pair + patches + templates + adaptation (the goal)", |b| {
        b.iter(|| black_box(quad_stage(&dt, &s.graph, &curves)))
    });
    group.finish();

    // The issue's own size: the same boundaries refined to no triangle larger than the
    // equilateral one of 3.2 px, about 10^5 triangles.
    let fine = refined(&s.graph, 3.2);
    bench_whole_stage(
        c,
        "quad stage grass, max size 3.2 px",
        &fine,
        &s.graph,
        &curves,
    );

    // A label image (stardist's nuclei: 123 round regions) at the size: how the stage
    // does where the boundaries are smooth, against grass's thousands of ragged blades.
    let grid = support::fixture("stardist-mask2d_labels.png");
    let (_, s, curves) = support::simplified_with_curves(&grid);
    let fine = refined(&s.graph, STARDIST_MAX_SIZE);
    bench_whole_stage(c, "quad stage stardist", &fine, &s.graph, &curves);
}

/// DT' of `graph` with no triangle larger than the equilateral one of side `max_size` px.
fn refined(graph: &CurveGraph, max_size: f64) -> RegionTriangulation {
    let density = DensityOptions {
        max_size: Some(max_size),
        ..DensityOptions::default()
    };
    RegionTriangulation::new(graph, &density).expect("DT' builds")
}

/// The criterion group `name` timing [`quad_stage`] on `dt`.
fn bench_whole_stage(
    c: &mut Criterion,
    name: &str,
    dt: &RegionTriangulation,
    graph: &CurveGraph,
    curves: &[CubicBezier],
) {
    let triangles = dt.triangulation.num_triangles();
    // One run timed by phase, for the closing notes: where the stage's time goes.
    {
        let t0 = std::time::Instant::now();
        let elements = ElementMesh::pair(&dt.triangulation, Pairing::Greedy);
        let t1 = t0.elapsed();
        let mut net = ControlNet::straight(&dt.triangulation, &elements);
        let t2 = t0.elapsed();
        let mut q = QuadMesh::build(&dt.triangulation, &elements, &net, 1);
        let t3 = t0.elapsed();
        let (report, _) = adapt(dt, graph, curves, &elements, &mut net, &mut q);
        eprintln!(
            "{name}: {triangles} triangles, {} quads, {} unpaired; pairing {t1:?}, patches {:?}, templates {:?}, adaptation {:?} in {:?}",
            q.quads.len(),
            elements.unpaired,
            t2 - t1,
            t3 - t2,
            report,
            t0.elapsed() - t3
        );
    }
    let mut group = c.benchmark_group(name);
    group.sample_size(10);
    group.throughput(Throughput::Elements(triangles as u64));
    group.bench_function(
        format!("pair + patches + templates + adaptation, {triangles} triangles"),
        |b| b.iter(|| black_box(quad_stage(dt, graph, curves))),
    );
    group.finish();
}

/// The largest DT' triangle side on the stardist fixture that gives about 10^5 triangles.
const STARDIST_MAX_SIZE: f64 = 3.05;

/// The measured path: pairing (greedy), straight patches, level-1 templates, adaptation.
fn quad_stage(
    dt: &RegionTriangulation,
    graph: &CurveGraph,
    curves: &[CubicBezier],
) -> (QuadMesh, AdaptReport) {
    let elements = ElementMesh::pair(&dt.triangulation, Pairing::Greedy);
    let mut net = ControlNet::straight(&dt.triangulation, &elements);
    let mut q = QuadMesh::build(&dt.triangulation, &elements, &net, 1);
    let (report, _) = adapt(dt, graph, curves, &elements, &mut net, &mut q);
    (q, report)
}

criterion_group!(benches, bench);
criterion_main!(benches);
