//! Criterion benchmark: our bulk Delaunay construction against spade's, on the same inputs.
//!
//! `cargo bench -p imesh-geom` (the full 10^6-point comparison with a ratio table is
//! `cargo xtask bench delaunay`).

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use imesh_geom::{Point, Triangulation};

fn uniform(n: usize) -> Vec<Point> {
    imesh_geom::sample::uniform_points(n, 0x2545_f491_4f6c_dd1d, 1000.0)
}

fn grid(side: u32) -> Vec<Point> {
    imesh_geom::sample::pixel_centres(side, side)
}

fn bulk(c: &mut Criterion) {
    let mut group = c.benchmark_group("delaunay_bulk");
    group.sample_size(20);
    for (name, pts) in [
        ("uniform_1e4", uniform(10_000)),
        ("uniform_1e5", uniform(100_000)),
        ("grid_316", grid(316)),
    ] {
        group.bench_with_input(BenchmarkId::new("imesh", name), &pts, |b, pts| {
            b.iter(|| Triangulation::from_points(black_box(pts)).map(|(t, _)| t.num_triangles()))
        });
        let sp: Vec<spade::Point2<f64>> =
            pts.iter().map(|p| spade::Point2::new(p.x, p.y)).collect();
        group.bench_with_input(BenchmarkId::new("spade", name), &sp, |b, sp| {
            b.iter_batched(
                || sp.clone(),
                |v| {
                    use spade::Triangulation as _;
                    spade::DelaunayTriangulation::<spade::Point2<f64>>::bulk_load(v)
                        .map(|t| t.num_inner_faces())
                },
                criterion::BatchSize::LargeInput,
            )
        });
    }
    group.finish();
}

fn incremental(c: &mut Criterion) {
    // The Imesh sampler's pattern: one point at a time, each followed by a look at the new triangles.
    let pts = uniform(20_000);
    c.bench_function("delaunay_incremental_2e4", |b| {
        b.iter(|| {
            let mut t = Triangulation::new();
            let mut created = 0;
            for &p in &pts {
                if t.insert(p).is_ok() {
                    created += t.created_triangles().len();
                }
            }
            black_box(created)
        })
    });
}

criterion_group!(benches, bulk, incremental);
criterion_main!(benches);
