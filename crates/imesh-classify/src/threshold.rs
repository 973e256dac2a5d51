//! Luminance thresholds: explicit levels, Otsu, multi-level Otsu.

use image::{DynamicImage, GrayImage};
use rayon::prelude::*;

use crate::grid::{palette_colour, Region};
use crate::LabelGrid;

/// The 8-bit luminance of the image (Rec. 709 weights, as the `image` crate computes it); of an
/// image deeper than 8 bits, of its values stretched over 0–255 ([`crate::eight_bit`]), so that
/// explicit levels (`threshold:T1,T2`) are then levels of that stretch.
pub fn luminance(image: &DynamicImage) -> GrayImage {
    crate::eight_bit(image).to_luma8()
}

/// Labels by luminance level: `v ≤ levels[0]` → 0, `levels[0] < v ≤ levels[1]` → 1, … (levels
/// increasing).
pub fn threshold(grey: &GrayImage, levels: &[u8]) -> LabelGrid {
    // One lookup table for all 256 values.
    let mut lut = [0u32; 256];
    for (v, l) in lut.iter_mut().enumerate() {
        *l = levels.iter().filter(|&&t| usize::from(t) < v).count() as u32;
    }
    let labels: Vec<u32> = grey
        .as_raw()
        .par_iter()
        .map(|&v| lut[usize::from(v)])
        .collect();
    let regions = (0..=levels.len())
        .map(|i| {
            let lo = if i == 0 {
                0
            } else {
                u32::from(levels[i - 1]) + 1
            };
            let hi = if i == levels.len() {
                255
            } else {
                u32::from(levels[i])
            };
            Region {
                name: format!("luminance {lo}–{hi}"),
                colour: palette_colour(i),
            }
        })
        .collect();
    let full = LabelGrid::new(grey.width(), grey.height(), labels, regions)
        .expect("levels index the regions");
    // A class no pixel falls in is not a region.
    full.with_labels(full.labels().to_vec())
}

/// Otsu levels for `classes` classes: the thresholds maximising the between-class variance of the
/// histogram (dynamic programming over the 256 bins; `classes = 2` is the classic Otsu level).
///
/// ```
/// use image::GrayImage;
/// let img = GrayImage::from_fn(8, 1, |x, _| image::Luma([if x < 3 { 10 } else if x < 6 { 120 } else { 240 }]));
/// let levels = imesh_classify::multi_otsu_levels(&img, 3);
/// assert!(levels[0] >= 10 && levels[0] < 120 && levels[1] >= 120 && levels[1] < 240);
/// ```
pub fn multi_otsu_levels(grey: &GrayImage, classes: usize) -> Vec<u8> {
    let mut hist = [0f64; 256];
    for &v in grey.as_raw() {
        hist[usize::from(v)] += 1.0;
    }
    // Prefix sums of weight and intensity: a class (i, j] has weight W[j] − W[i], sum S[j] − S[i].
    let (mut w, mut s) = ([0f64; 257], [0f64; 257]);
    for v in 0..256 {
        w[v + 1] = w[v] + hist[v];
        s[v + 1] = s[v] + hist[v] * v as f64;
    }
    let score = |i: usize, j: usize| {
        let (wi, si) = (w[j] - w[i], s[j] - s[i]);
        if wi > 0.0 {
            si * si / wi
        } else {
            0.0
        }
    };
    let classes = classes.clamp(2, 256);
    // best[k][j]: the best score for bins [0, j) split into k classes; from[k][j] the last cut.
    let mut best = vec![vec![f64::NEG_INFINITY; 257]; classes + 1];
    let mut from = vec![vec![0usize; 257]; classes + 1];
    for (j, b) in best[1].iter_mut().enumerate().skip(1) {
        *b = score(0, j);
    }
    for k in 2..=classes {
        for j in k..=256 {
            for i in (k - 1)..j {
                let v = best[k - 1][i] + score(i, j);
                // Strictly better only: the first maximum wins, as in the classic Otsu loop.
                if v > best[k][j] {
                    best[k][j] = v;
                    from[k][j] = i;
                }
            }
        }
    }
    let mut cuts = Vec::with_capacity(classes - 1);
    let mut j = 256;
    for k in (2..=classes).rev() {
        j = from[k][j];
        cuts.push((j - 1) as u8);
    }
    cuts.reverse();
    cuts
}
