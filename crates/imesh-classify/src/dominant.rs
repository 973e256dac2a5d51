//! Label-like images stored with a lossy codec (JPEG, lossy WebP or AVIF): a flat-coloured
//! picture comes back with dozens of colours, a few levels off its own, rung around every
//! edge and spread over each block. Read as a label map, those become labels of their own,
//! bands a few pixels wide along every boundary. Here every pixel takes the nearest of the
//! picture's dominant colours instead.

use image::DynamicImage;
use rayon::prelude::*;

use crate::colours::{self, channels};
use crate::labels::{is_grey, named_region};
use crate::LabelGrid;

/// Colours this close (in every channel, 8 bits) are one label's: a lossy codec moves flat
/// colours by a few levels, and its ringing by up to a few tens next to strong edges.
pub const COLOUR_SPREAD: u8 = 32;

/// A colour is a label of its own only when at least this share of the pixels has it.
pub const DOMINANT_SHARE: f64 = 0.002;

/// Labels each pixel by the nearest of the image's dominant colours: the most common colour,
/// then, by decreasing count, every colour held by at least [`DOMINANT_SHARE`] of the pixels and
/// farther than [`COLOUR_SPREAD`] from those already taken. Labels are numbered in increasing
/// colour order and named as [`crate::label_map`] names them (`value V`, `#rrggbb`).
///
/// ```
/// use image::{DynamicImage, Rgb, RgbImage};
/// // Two flat colours, with the stray shades a codec leaves along their edge.
/// let img = RgbImage::from_fn(100, 10, |x, _| match x {
///     0..=48 => Rgb([200, 30, 30]),
///     49 => Rgb([190, 40, 35]),
///     50 => Rgb([20, 45, 190]),
///     _ => Rgb([10, 40, 200]),
/// });
/// let grid = imesh_classify::dominant_colours(&DynamicImage::ImageRgb8(img));
/// assert_eq!(grid.num_labels(), 2);
/// assert_eq!((grid.label(49, 0), grid.label(50, 0)), (1, 0));
/// assert_eq!(grid.regions()[0].name, "#0a28c8");
/// ```
pub fn dominant_colours(image: &DynamicImage) -> LabelGrid {
    let rgb = crate::eight_bit(image).to_rgb8();
    let keys = colours::packed(&rgb);
    let distinct = colours::distinct(&keys);
    let mut by_count = distinct.clone();
    by_count.sort_unstable_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(&b.0)));
    let least = (DOMINANT_SHARE * keys.len() as f64).ceil() as usize;
    let mut palette: Vec<u32> = Vec::new();
    for (i, &(c, n)) in by_count.iter().enumerate() {
        if i == 0 || (n >= least && palette.iter().all(|&p| spread(p, c) > COLOUR_SPREAD)) {
            palette.push(c);
        }
    }
    palette.sort_unstable();
    // Per distinct colour (in increasing order), its palette entry.
    let label_of: Vec<u32> = distinct
        .iter()
        .map(|&(c, _)| nearest(&palette, c))
        .collect();
    let labels: Vec<u32> = keys
        .par_iter()
        .map(|k| {
            let i = distinct
                .binary_search_by_key(k, |&(c, _)| c)
                .expect("every pixel colour is a distinct colour");
            label_of[i]
        })
        .collect();
    let grey = is_grey(image);
    let regions = palette
        .iter()
        .enumerate()
        .map(|(i, &c)| {
            let rgb = channels(c);
            named_region(i, grey.then_some(u16::from(rgb[0])), rgb)
        })
        .collect();
    LabelGrid::new(rgb.width(), rgb.height(), labels, regions)
        .expect("every pixel takes a palette entry")
}

/// The largest difference of two colours in one channel.
fn spread(a: u32, b: u32) -> u8 {
    let (a, b) = (channels(a), channels(b));
    (0..3).map(|k| a[k].abs_diff(b[k])).max().unwrap_or(0)
}

/// The palette entry nearest `c` (squared distance in RGB; the first of equals).
fn nearest(palette: &[u32], c: u32) -> u32 {
    let distance = |p: u32| {
        let (a, b) = (channels(p), channels(c));
        (0..3)
            .map(|k| (i32::from(a[k]) - i32::from(b[k])).pow(2))
            .sum::<i32>()
    };
    (0..palette.len() as u32)
        .min_by_key(|&i| distance(palette[i as usize]))
        .unwrap_or(0)
}
