//! Images the pipeline tests share: degenerate and hostile label images, and the fixtures.

#![allow(dead_code)]

use std::path::{Path, PathBuf};

use image::{DynamicImage, GrayImage, ImageBuffer, Luma, LumaA, Rgba};

pub mod program;

/// A grey image from a function of the pixel.
pub fn grey(w: u32, h: u32, f: impl Fn(u32, u32) -> u8) -> DynamicImage {
    DynamicImage::ImageLuma8(GrayImage::from_fn(w, h, |x, y| Luma([f(x, y)])))
}

/// A deterministic pseudo-random number per pixel, below `levels`.
pub fn noise(x: u32, y: u32, levels: u32) -> u32 {
    let mut s = x.wrapping_mul(73_856_093) ^ y.wrapping_mul(19_349_663) ^ 0x9e37_79b9;
    s ^= s >> 13;
    s = s.wrapping_mul(0x5bd1_e995);
    s ^= s >> 15;
    s % levels
}

/// A grey level per class of `levels` evenly spread over 0–255.
fn level(class: u32, levels: u32) -> u8 {
    (class * (255 / (levels - 1).max(1))) as u8
}

/// Small degenerate images: each stresses one special case of the pipeline.
pub fn degenerate_images() -> Vec<(&'static str, DynamicImage)> {
    vec![
        ("one pixel", grey(1, 1, |_, _| 0)),
        (
            "two pixels",
            grey(2, 1, |x, _| if x == 0 { 0 } else { 255 }),
        ),
        ("flat", grey(20, 20, |_, _| 7)),
        (
            "checkerboard",
            grey(16, 16, |x, y| if (x + y) % 2 == 0 { 0 } else { 255 }),
        ),
        (
            "2-pixel checkerboard",
            grey(
                40,
                30,
                |x, y| if (x / 2 + y / 2) % 2 == 0 { 0 } else { 255 },
            ),
        ),
        (
            "binary noise",
            grey(64, 64, |x, y| level(noise(x, y, 2), 2)),
        ),
        (
            "three-level noise",
            grey(50, 40, |x, y| level(noise(x, y, 3), 3)),
        ),
        (
            "1-pixel line",
            grey(32, 32, |x, _| if x == 16 { 255 } else { 0 }),
        ),
        (
            "1-pixel diagonal",
            grey(32, 32, |x, y| if x == y { 255 } else { 0 }),
        ),
        (
            "corner-touching pixels",
            grey(10, 10, |x, y| {
                if (x, y) == (3, 3) || (x, y) == (4, 4) {
                    255
                } else {
                    0
                }
            }),
        ),
        (
            "thin strip",
            grey(200, 3, |_, y| if y == 1 { 255 } else { 0 }),
        ),
    ]
}

/// Nested square rings of alternating labels, `width` pixels wide each.
fn rings(side: u32, width: u32) -> DynamicImage {
    grey(side, side, |x, y| {
        let d = x.min(y).min(side - 1 - x).min(side - 1 - y);
        if (d / width) % 2 == 0 {
            0
        } else {
            255
        }
    })
}

/// The hostile images of issue 11: extreme shapes, label counts and topologies. Names that say
/// "label map" are to be read with `--classify labels`.
pub fn hostile_images() -> Vec<(&'static str, DynamicImage)> {
    let disc_with_holes = grey(96, 96, |x, y| {
        let (dx, dy) = (f64::from(x) - 47.5, f64::from(y) - 47.5);
        let hole = (x % 10 >= 4 && x % 10 <= 6) && (y % 10 >= 4 && y % 10 <= 6);
        if dx * dx + dy * dy < 44.0 * 44.0 && !hole {
            255
        } else {
            0
        }
    });
    // 15 × 17 blocks of 12 × 12 pixels, each its own grey value: flat enough to be read as a
    // label map.
    let blocks_255 = grey(180, 204, |x, y| (x / 12 + 15 * (y / 12)) as u8);
    vec![
        ("1 × 1", grey(1, 1, |_, _| 9)),
        ("1 × 50", grey(1, 50, |_, y| if y < 20 { 0 } else { 255 })),
        (
            "50 × 1",
            grey(50, 1, |x, _| if x % 7 < 3 { 0 } else { 255 }),
        ),
        ("single label", grey(40, 30, |_, _| 128)),
        (
            "64 × 64 noise label map (4096 labels)",
            DynamicImage::ImageLuma16(ImageBuffer::from_fn(64, 64, |x, y| {
                Luma([(y * 64 + x) as u16 * 13])
            })),
        ),
        (
            "1-pixel checkerboard",
            grey(24, 24, |x, y| level((x + y) % 2, 2)),
        ),
        (
            "1-pixel lines both ways",
            grey(
                40,
                40,
                |x, y| if x % 4 == 0 || y % 5 == 0 { 255 } else { 0 },
            ),
        ),
        (
            "diagonal chains",
            grey(
                40,
                40,
                |x, y| if (x + y) % 6 == 0 || x == y { 255 } else { 0 },
            ),
        ),
        (
            "a label touching only one image corner",
            grey(30, 20, |x, y| if x == 0 && y == 0 { 255 } else { 0 }),
        ),
        (
            "labels touching only at a corner",
            grey(12, 12, |x, y| if (x < 6) == (y < 6) { 255 } else { 0 }),
        ),
        ("nested rings", rings(64, 3)),
        ("nested 1-pixel rings", rings(31, 1)),
        ("a region with many holes", disc_with_holes),
        (
            "16-bit grey",
            DynamicImage::ImageLuma16(ImageBuffer::from_fn(48, 32, |x, y| {
                Luma([if (x as i32 - 24).pow(2) + (y as i32 - 16).pow(2) < 150 {
                    65_000
                } else {
                    300
                }])
            })),
        ),
        (
            "grey with alpha",
            DynamicImage::ImageLumaA8(ImageBuffer::from_fn(40, 40, |x, y| {
                LumaA([if x > y { 200 } else { 20 }, if x < 20 { 255 } else { 128 }])
            })),
        ),
        (
            "RGBA with a transparent hole",
            DynamicImage::ImageRgba8(ImageBuffer::from_fn(40, 40, |x, y| {
                let a = if (10..30).contains(&x) && (10..30).contains(&y) {
                    0
                } else {
                    255
                };
                Rgba([200, (x * 6) as u8 & 0x80, 40, a])
            })),
        ),
        ("255 labels", blocks_255),
        (
            "4096 × 64 strip",
            grey(4096, 64, |x, y| {
                let wave = 32.0 + 20.0 * (f64::from(x) / 90.0).sin();
                if f64::from(y) < wave {
                    0
                } else {
                    255
                }
            }),
        ),
    ]
}

/// The fixture image `name` (a file of `fixtures/images`).
pub fn fixture(name: &str) -> PathBuf {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures/images")
        .join(name);
    assert!(path.is_file(), "no fixture {}", path.display());
    path
}

/// The fixture images, sorted.
pub fn fixtures() -> Vec<PathBuf> {
    let folder = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/images");
    let mut images: Vec<_> = std::fs::read_dir(&folder)
        .expect("fixtures/images exists")
        .map(|e| e.expect("a directory entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "png"))
        .collect();
    images.sort();
    images
}
