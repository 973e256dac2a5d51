//! Label-map passthrough: every distinct grey value or colour is a label.

use std::collections::{HashMap, HashSet};

use image::DynamicImage;
use rayon::prelude::*;

use crate::grid::{palette_colour, Region};
use crate::{ClassifyError, LabelGrid};

/// Whether the image is grey (its values, not colours, are the labels).
pub(crate) fn is_grey(image: &DynamicImage) -> bool {
    matches!(
        image,
        DynamicImage::ImageLuma8(_)
            | DynamicImage::ImageLumaA8(_)
            | DynamicImage::ImageLuma16(_)
            | DynamicImage::ImageLumaA16(_)
    )
}

/// Label `i`'s region, named by its grey value (drawn in the palette's `i`-th colour) or, with
/// no grey value, by its colour `rgb` (drawn in it).
pub(crate) fn named_region(i: usize, grey: Option<u16>, rgb: [u8; 3]) -> Region {
    match grey {
        Some(v) => Region {
            name: format!("value {v}"),
            colour: palette_colour(i),
        },
        None => Region {
            name: format!("#{:02x}{:02x}{:02x}", rgb[0], rgb[1], rgb[2]),
            colour: rgb,
        },
    }
}

/// One `u64` per pixel that is equal exactly when the pixels are (16 bits per channel).
fn pixel_keys(image: &DynamicImage) -> Vec<u64> {
    if is_grey(image) {
        image
            .to_luma_alpha16()
            .pixels()
            .map(|p| u64::from(p[0]) | (u64::from(p[1]) << 16))
            .collect()
    } else {
        image
            .to_rgba16()
            .pixels()
            .map(|p| {
                u64::from(p[0])
                    | (u64::from(p[1]) << 16)
                    | (u64::from(p[2]) << 32)
                    | (u64::from(p[3]) << 48)
            })
            .collect()
    }
}

/// The distinct keys, in increasing order, or `None` when there are more than `limit`.
fn distinct_keys(keys: &[u64], limit: usize) -> Option<Vec<u64>> {
    let sets: Vec<Option<HashSet<u64>>> = keys
        .par_chunks(1 << 16)
        .map(|chunk| {
            let mut set = HashSet::new();
            let mut last = None;
            for &k in chunk {
                // Label maps come in long runs: skip the hash for a repeat.
                if last != Some(k) {
                    set.insert(k);
                    last = Some(k);
                    if set.len() > limit {
                        return None;
                    }
                }
            }
            Some(set)
        })
        .collect();
    let mut all = HashSet::new();
    for s in sets {
        all.extend(s?);
        if all.len() > limit {
            return None;
        }
    }
    let mut v: Vec<u64> = all.into_iter().collect();
    v.sort_unstable();
    Some(v)
}

/// Labels each distinct value: grey images by their grey value, colour images by their colour
/// (alpha included). Labels are numbered in increasing value order.
///
/// # Errors
/// [`ClassifyError::TooManyLabels`] when there are more than `max_labels` distinct values.
pub fn label_map(image: &DynamicImage, max_labels: usize) -> Result<LabelGrid, ClassifyError> {
    let keys = pixel_keys(image);
    let distinct = distinct_keys(&keys, max_labels)
        .ok_or(ClassifyError::TooManyLabels { limit: max_labels })?;
    let grey = is_grey(image);
    let deep = matches!(
        image.color().bytes_per_pixel() / image.color().channel_count(),
        2
    );
    let regions = distinct
        .iter()
        .enumerate()
        .map(|(i, &k)| {
            let channel = |c: u32| ((k >> (16 * c)) & 0xffff) as u16;
            let to8 = |v: u16| (v >> 8) as u8;
            let value = if deep { channel(0) } else { channel(0) / 257 };
            let rgb = [to8(channel(0)), to8(channel(1)), to8(channel(2))];
            named_region(i, grey.then_some(value), rgb)
        })
        .collect();
    let index: HashMap<u64, u32> = distinct
        .iter()
        .enumerate()
        .map(|(i, &k)| (k, i as u32))
        .collect();
    let index = &index;
    let labels: Vec<u32> = keys
        .par_chunks(1 << 16)
        .flat_map_iter(|chunk| {
            let mut last = (u64::MAX, 0u32);
            chunk.iter().map(move |&k| {
                if k != last.0 {
                    last = (k, index[&k]);
                }
                last.1
            })
        })
        .collect();
    Ok(
        LabelGrid::new(image.width(), image.height(), labels, regions)
            .expect("labels index the regions built from them"),
    )
}

/// True when the image looks like a label map: at most `max_labels` distinct values, and at least
/// 90% of horizontally adjacent pixels equal (large flat regions, unlike a photograph).
pub fn looks_like_label_map(image: &DynamicImage, max_labels: usize) -> bool {
    let keys = pixel_keys(image);
    let w = image.width() as usize;
    if distinct_keys(&keys, max_labels).is_none() {
        return false;
    }
    let pairs = keys.len() - keys.len() / w.max(1);
    if pairs == 0 {
        return true;
    }
    let equal = keys
        .par_chunks(w.max(1))
        .map(|row| row.windows(2).filter(|p| p[0] == p[1]).count())
        .sum::<usize>();
    equal as f64 >= 0.9 * pairs as f64
}
