//! Criterion benchmark of the median-error sampler on a 1024 × 1024 real image (a crop of the
//! Middlebury "Aloe" disparity map in `fixtures/images/`, in four depth bands by multi-level
//! Otsu), on 1 and 2 threads. Throughput is in vertices inserted per second.
//!
//! `cargo bench -p imesh-segment`. Goal: the 1-megapixel image sampled in < 0.2 s on 2 cores.

use std::hint::black_box;
use std::path::Path;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use imesh_classify::{luminance, multi_otsu_levels, threshold, LabelGrid};
use imesh_segment::{sample, SampleOptions};

fn aloe_bands() -> LabelGrid {
    let path =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/images/opencv-aloeGT.png");
    let image = imesh_classify::load_image(&path, imesh_classify::DEFAULT_MAX_PIXELS)
        .expect("the fixture opencv-aloeGT.png loads");
    let grey = image::imageops::crop_imm(&luminance(&image), 0, 0, 1024, 1024).to_image();
    threshold(&grey, &multi_otsu_levels(&grey, 4))
}

fn bench(c: &mut Criterion) {
    let grid = aloe_bands();
    let options = SampleOptions::default();
    let inserted = sample(&grid, &options).expect("sampling works").inserted;
    let mut group = c.benchmark_group("sample aloe 1024x1024");
    group.sample_size(10);
    group.throughput(Throughput::Elements(inserted as u64));
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("a thread pool");
        group.bench_function(format!("{threads} thread(s), {inserted} vertices"), |b| {
            b.iter(|| pool.install(|| black_box(sample(&grid, &options).expect("sampling works"))))
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
