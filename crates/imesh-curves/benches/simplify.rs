//! Criterion benchmark of the topology-preserving simplification on a boundary graph of about
//! 10^5 vertices: the pixel boundaries of scikit-image's "grass" texture (fixture
//! `skimage-grass.png`, 512 × 512, two classes by Otsu: thousands of blades and specks, 108 869
//! pixel sides), and the Bézier fit of the result.
//!
//! `cargo bench -p imesh-curves`. Goal: simplification in < 50 ms.

use std::hint::black_box;
use std::path::Path;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use imesh_classify::{luminance, multi_otsu_levels, threshold};
use imesh_curves::{fit_edges, simplify, FitOptions, SimplifyOptions};

#[path = "../tests/support/mod.rs"]
mod support;

fn bench(c: &mut Criterion) {
    let path =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/images/skimage-grass.png");
    let image = imesh_classify::load_image(&path, imesh_classify::DEFAULT_MAX_PIXELS)
        .expect("the fixture skimage-grass.png loads");
    let grey = luminance(&image);
    let grid = threshold(&grey, &multi_otsu_levels(&grey, 2));
    let g = support::pixel_boundaries(&grid);
    let vertices = g.edges().len(); // one vertex per edge on closed boundaries
    let options = SimplifyOptions::default();
    let s = simplify(&g, &options).expect("simplification works");
    eprintln!(
        "grass pixel boundaries: {} edges → {} simplified edges ({} refused chords)",
        g.edges().len(),
        s.graph.edges().len(),
        s.refused
    );
    let mut group = c.benchmark_group("curves grass");
    group.sample_size(10);
    group.throughput(Throughput::Elements(vertices as u64));
    group.bench_function(format!("simplify {vertices} edges, tolerance 2 px"), |b| {
        b.iter(|| black_box(simplify(&g, &options).expect("simplification works")))
    });
    group.bench_function("fit Béziers to every simplified edge", |b| {
        b.iter(|| black_box(fit_edges(&s, &g, &FitOptions::default())))
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
