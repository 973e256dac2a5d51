//! Criterion benchmark: classification throughput on a 2048 × 2048 image, per classifier.
//!
//! `cargo bench -p imesh-classify` (throughput is reported in elements = pixels per second).
//! Goals on 2 cores: ≥ 50 MP/s for threshold and label map, ≥ 5 MP/s for k-means and texture.
//! The clean-up group times the majority filter against imageproc's median filter of the same
//! window (a sliding histogram too, on one grey channel) in the same run.

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use image::{DynamicImage, GrayImage, Luma, Rgb, RgbImage};
use imesh_classify::{
    classify, majority_filter, Classifier, ClassifyOptions, LabelGrid, Region, SampleLabel,
    TextureClassifier, TextureSamples,
};

const SIDE: u32 = 2048;

fn noise(x: u32, y: u32) -> u8 {
    let mut h = x.wrapping_mul(0x9e37_79b1) ^ y.wrapping_mul(0x85eb_ca77);
    h ^= h >> 15;
    h = h.wrapping_mul(0x2c1b_3c6d);
    (h >> 24) as u8
}

/// A colour photograph stand-in: smooth blobs of four hues with noise.
fn photo() -> DynamicImage {
    DynamicImage::ImageRgb8(RgbImage::from_fn(SIDE, SIDE, |x, y| {
        let blob = ((x / 300 + y / 200) % 4) as u8;
        let n = noise(x, y) / 8;
        Rgb([
            40 + 50 * blob + n,
            200 - 40 * blob + n,
            90 + 30 * (blob % 2) + n,
        ])
    }))
}

/// A label map: 12 values in rectangles.
fn labels() -> DynamicImage {
    DynamicImage::ImageLuma8(GrayImage::from_fn(SIDE, SIDE, |x, y| {
        Luma([((x / 256 + 3 * (y / 341)) % 12) as u8])
    }))
}

/// Two textures: fine noise on the left, coarse stripes on the right.
fn textures() -> DynamicImage {
    DynamicImage::ImageLuma8(GrayImage::from_fn(SIDE, SIDE, |x, y| {
        Luma([if x < SIDE / 2 {
            noise(x, y)
        } else if (y / 6) % 2 == 0 {
            60 + noise(x, y) / 8
        } else {
            180 + noise(x, y) / 8
        }])
    }))
}

fn bench(c: &mut Criterion) {
    let options = ClassifyOptions::default();
    let mut g = c.benchmark_group("classify_2048x2048");
    g.sample_size(10);
    g.throughput(Throughput::Elements(u64::from(SIDE) * u64::from(SIDE)));
    let photo = photo();
    let labels = labels();
    g.bench_function("label_map", |b| {
        b.iter(|| classify(black_box(&labels), &Classifier::Labels, &options))
    });
    g.bench_function("threshold", |b| {
        b.iter(|| {
            classify(
                black_box(&photo),
                &Classifier::Threshold {
                    levels: vec![80, 170],
                },
                &options,
            )
        })
    });
    g.bench_function("otsu_3", |b| {
        b.iter(|| {
            classify(
                black_box(&photo),
                &Classifier::Otsu { classes: 3 },
                &options,
            )
        })
    });
    g.bench_function("kmeans_4", |b| {
        b.iter(|| classify(black_box(&photo), &Classifier::KMeans { k: 4 }, &options))
    });
    let tex = textures();
    let samples = TextureSamples {
        window: 15,
        levels: 4,
        offsets: 8,
        labels: vec![
            SampleLabel {
                name: "fine".into(),
                colour: [0, 0, 0],
                rectangles: vec![[100, 100, 200, 200]],
            },
            SampleLabel {
                name: "stripes".into(),
                colour: [255, 255, 255],
                rectangles: vec![[1500, 100, 200, 200]],
            },
        ],
    };
    let trained = TextureClassifier::train(&tex, &samples).expect("rectangles inside");
    g.bench_function("texture_classify", |b| {
        b.iter(|| trained.classify(black_box(&tex)))
    });
    g.finish();
    c.bench_function("texture_train_2x200x200", |b| {
        b.iter(|| TextureClassifier::train(black_box(&tex), &samples))
    });
}

/// A label grid of `kinds` labels in 64 × 64 tiles, one pixel in seven a speckle of another.
fn speckled(kinds: u32) -> LabelGrid {
    let labels = (0..SIDE * SIDE)
        .map(|i| {
            let (x, y) = (i % SIDE, i / SIDE);
            let tile = (x / 64 + 7 * (y / 64)) % kinds;
            if noise(x, y) % 7 == 0 {
                (tile + 1) % kinds
            } else {
                tile
            }
        })
        .collect();
    let regions = (0..kinds)
        .map(|k| Region {
            name: k.to_string(),
            colour: [0, 0, 0],
        })
        .collect();
    LabelGrid::new(SIDE, SIDE, labels, regions).expect("one label per pixel")
}

/// The pipeline's clean-up at a radius of 4 px (its automatic radius for quads about 4 px wide).
fn clean_up(c: &mut Criterion) {
    const RADIUS: u32 = 4;
    let mut g = c.benchmark_group("cleanup_2048x2048");
    g.sample_size(10);
    g.throughput(Throughput::Elements(u64::from(SIDE) * u64::from(SIDE)));
    for kinds in [2, 12, 300] {
        let grid = speckled(kinds);
        g.bench_function(format!("majority_filter r={RADIUS}, {kinds} labels"), |b| {
            b.iter(|| majority_filter(black_box(&grid), RADIUS, 1))
        });
    }
    let grey = GrayImage::from_fn(SIDE, SIDE, |x, y| Luma([noise(x, y)]));
    g.bench_function(format!("imageproc median_filter r={RADIUS} (peer)"), |b| {
        b.iter(|| imageproc::filter::median_filter(black_box(&grey), RADIUS, RADIUS))
    });
    g.finish();
}

criterion_group!(benches, bench, clean_up);
criterion_main!(benches);
