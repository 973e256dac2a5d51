//! The texture classifier on real textures: train on some rectangles, score on held-out ones.

use image::{DynamicImage, GenericImageView, GrayImage};
use imesh_classify::{
    load_image, majority_filter, SampleLabel, TextureClassifier, TextureSamples, DEFAULT_MAX_PIXELS,
};

fn fixture(name: &str) -> DynamicImage {
    let path = format!(
        "{}/../../fixtures/images/{name}",
        env!("CARGO_MANIFEST_DIR")
    );
    load_image(path.as_ref(), DEFAULT_MAX_PIXELS).unwrap()
}

/// A 510 × 400 mosaic: three 170-pixel-wide strips of brick, grass and gravel.
fn mosaic() -> DynamicImage {
    let src = [
        fixture("skimage-brick.png"),
        fixture("skimage-grass.png"),
        fixture("skimage-gravel.png"),
    ];
    let img = GrayImage::from_fn(510, 400, |x, y| {
        let s = &src[(x / 170) as usize];
        image::Luma([s.get_pixel(x, y).0[0]])
    });
    DynamicImage::ImageLuma8(img)
}

fn samples(window: u32, levels: u8, offsets: usize) -> TextureSamples {
    let names = ["brick", "grass", "gravel"];
    TextureSamples {
        window,
        levels,
        offsets,
        labels: (0..3)
            .map(|i| SampleLabel {
                name: names[i].into(),
                colour: [80 * i as u8, 100, 50],
                // Training: the top half of each strip.
                rectangles: vec![[170 * i as u32 + 10, 10, 150, 180]],
            })
            .collect(),
    }
}

/// Held-out rectangles: the bottom half of each strip, away from the strip borders.
const HELD_OUT: [[u32; 4]; 3] = [
    [15, 220, 140, 170],
    [185, 220, 140, 170],
    [355, 220, 140, 170],
];

fn accuracy(grid: &imesh_classify::LabelGrid) -> Vec<f64> {
    HELD_OUT
        .iter()
        .enumerate()
        .map(|(label, r)| {
            let mut right = 0;
            for y in r[1]..r[1] + r[3] {
                for x in r[0]..r[0] + r[2] {
                    right += usize::from(grid.label(x, y) as usize == label);
                }
            }
            right as f64 / f64::from(r[2] * r[3])
        })
        .collect()
}

#[test]
fn three_textures_are_told_apart_on_held_out_rectangles() {
    let img = mosaic();
    // A 21-pixel window with 3 levels suits these textures' grain (grass and gravel have the same
    // mean and spread; their edge density tells them apart). The majority filter is the clean-up a
    // texture labelling gets in the pipeline.
    let classifier = TextureClassifier::train(&img, &samples(21, 3, 8)).unwrap();
    let raw = classifier.classify(&img);
    let smooth = majority_filter(&raw, 5, 2);
    let (a_raw, a_smooth) = (accuracy(&raw), accuracy(&smooth));
    println!("features {:?}", classifier.features());
    println!("held-out accuracy per texture: raw {a_raw:.3?}, after an 11×11 majority filter (2 passes) {a_smooth:.3?}");
    for a in &a_smooth {
        assert!(*a >= 0.90, "accuracy {a_smooth:?}");
    }
}
