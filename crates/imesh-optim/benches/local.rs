//! Criterion benchmark of the optimiser on a real label image's quad mesh (PyVista's channels
//! slice, 250 × 250, 4 labels, smoothed by a majority filter of radius 2 and its small regions
//! merged; DT' spacing 4 px as the command line's automatic size picks for it: about 1.5 · 10^4
//! quads), in the default `local` mode and its `vertex` and `laplacian` baselines, on the
//! threads rayon gives it.
//!
//! `cargo bench -p imesh-optim`.

use std::hint::black_box;
use std::path::Path;

use criterion::{criterion_group, criterion_main, BatchSize, Criterion, Throughput};
use imesh_classify::{label_map, majority_filter, remove_small_regions};
use imesh_optim::{optimise, Method, OptimOptions};
use imesh_quad::{remesh, DensityOptions, Pairing, QuadOptions};

// The c-edge graph of a label grid, as imesh-curves' tests build it.
#[path = "../../imesh-curves/tests/support/mod.rs"]
mod support;

fn bench(c: &mut Criterion) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures/images/pyvista-channels_z050_labels.png");
    let image = imesh_classify::load_image(&path, imesh_classify::DEFAULT_MAX_PIXELS)
        .expect("the fixture pyvista-channels_z050_labels.png loads");
    let labels = label_map(&image, 64).expect("the fixture is a label map");
    let grid = remove_small_regions(&majority_filter(&labels, 2, 1), 16);
    let (_, s, curves) = support::simplified_with_curves(&grid);
    let options = QuadOptions {
        density: DensityOptions {
            spacing: Some(4.0),
            ..DensityOptions::default()
        },
        pairing: Pairing::Matching,
        ..QuadOptions::default()
    };
    let start = remesh(&s.graph, &curves, &options).expect("the quad stage works");
    let quads = start.mesh.quads.len();
    let mut group = c.benchmark_group("optimise pyvista");
    group.sample_size(10);
    group.throughput(Throughput::Elements(quads as u64));
    for method in [Method::Local, Method::Vertex, Method::Laplacian] {
        let options = OptimOptions {
            method,
            ..OptimOptions::default()
        };
        let report = optimise(&mut start.clone(), &options).expect("the optimiser works");
        eprintln!(
            "{method:?}: {quads} quads, shape-and-size mean {:.4} -> {:.4}, worst {:.4} -> {:.4}",
            report.before.shape_and_size.mean,
            report.after.shape_and_size.mean,
            report.before.shape_and_size.min,
            report.after.shape_and_size.min,
        );
        group.bench_function(format!("{method:?}, {quads} quads"), |b| {
            b.iter_batched(
                || start.clone(),
                |mut r| black_box(optimise(&mut r, &options)),
                BatchSize::LargeInput,
            )
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
