//! Criterion benchmark: quality metrics over 10^6 quads (goal: ≥ 50 M quads/s for shape on 2 cores).
//!
//! `cargo bench -p imesh-quality`

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use imesh_quality::{quad, QuadQuality};
use rayon::prelude::*;

/// A 1000 × 1000 grid of unit quads with every vertex jittered (fixed seed).
fn perturbed_grid(side: u32) -> (Vec<[f64; 2]>, Vec<[u32; 4]>) {
    let mut s = 0x9e37_79b9_7f4a_7c15u64;
    let mut jitter = move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        ((s >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 0.4
    };
    let v: Vec<[f64; 2]> = (0..=side)
        .flat_map(|r| (0..=side).map(move |c| (c, r)))
        .map(|(c, r)| [f64::from(c) + jitter(), f64::from(r) + jitter()])
        .collect();
    let id = |c: u32, r: u32| r * (side + 1) + c;
    let q = (0..side)
        .flat_map(|r| {
            (0..side).map(move |c| [id(c, r), id(c + 1, r), id(c + 1, r + 1), id(c, r + 1)])
        })
        .collect();
    (v, q)
}

fn metrics(c: &mut Criterion) {
    let (vertices, quads) = perturbed_grid(1000);
    let corners = imesh_quality::quad_corners(&vertices, &quads);
    let mut g = c.benchmark_group("quad_metrics_1e6");
    g.sample_size(20);
    g.throughput(Throughput::Elements(corners.len() as u64));
    g.bench_function("shape_sequential", |b| {
        b.iter(|| {
            black_box(&corners)
                .iter()
                .map(quad::shape)
                .fold(f64::INFINITY, f64::min)
        })
    });
    g.bench_function("shape_parallel", |b| {
        b.iter(|| {
            black_box(&corners)
                .par_iter()
                .map(quad::shape)
                .reduce(|| f64::INFINITY, f64::min)
        })
    });
    g.bench_function("shape_and_size_parallel", |b| {
        b.iter(|| {
            black_box(&corners)
                .par_iter()
                .map(|q| quad::shape_and_size(q, 1.0))
                .reduce(|| f64::INFINITY, f64::min)
        })
    });
    g.bench_function("scaled_jacobian_parallel", |b| {
        b.iter(|| {
            black_box(&corners)
                .par_iter()
                .map(quad::scaled_jacobian)
                .reduce(|| f64::INFINITY, f64::min)
        })
    });
    g.bench_function("report_all_metrics_from_indices", |b| {
        b.iter(|| QuadQuality::of(black_box(&vertices), black_box(&quads)))
    });
    g.finish();
}

criterion_group!(benches, metrics);
criterion_main!(benches);
