//! k-means colour clustering in CIE Lab with k-means++ seeding.
//!
//! Clustering runs on the *distinct* colours weighted by their pixel counts, in sorted colour order:
//! identical to clustering every pixel, much faster, and independent of the order of the pixels.

use image::DynamicImage;
use palette::{IntoColor, Lab, Srgb};
use rand_chacha::rand_core::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use crate::colours;
use crate::grid::Region;
use crate::LabelGrid;

/// The fixed seed: the same image always gives the same clusters.
const SEED: u64 = 0x1_3e54;
const MAX_ITERATIONS: usize = 100;

fn lab_of(rgb: u32) -> [f32; 3] {
    let [r, g, b] = colours::channels(rgb);
    let c = Srgb::new(r, g, b).into_format::<f32>();
    let lab: Lab = c.into_linear().into_color();
    [lab.l, lab.a, lab.b]
}

fn dist2(a: &[f32; 3], b: &[f32; 3]) -> f32 {
    (a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)
}

fn nearest(p: &[f32; 3], centres: &[[f32; 3]]) -> (usize, f32) {
    let mut best = (0, f32::INFINITY);
    for (i, c) in centres.iter().enumerate() {
        let d = dist2(p, c);
        if d < best.1 {
            best = (i, d);
        }
    }
    best
}

/// A uniform draw in `[0, 1)`.
fn uniform(rng: &mut ChaCha8Rng) -> f64 {
    (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64
}

/// k-means++: each new centre drawn with probability ∝ count × squared distance to the nearest centre.
fn seed_centres(points: &[[f32; 3]], weights: &[f64], k: usize) -> Vec<[f32; 3]> {
    let mut rng = ChaCha8Rng::seed_from_u64(SEED);
    let pick = |rng: &mut ChaCha8Rng, w: &[f64]| {
        let total: f64 = w.iter().sum();
        let mut target = uniform(rng) * total;
        for (i, &x) in w.iter().enumerate() {
            target -= x;
            if target < 0.0 {
                return i;
            }
        }
        w.iter().rposition(|&x| x > 0.0).unwrap_or(0)
    };
    let mut centres = vec![points[pick(&mut rng, weights)]];
    let mut d2: Vec<f64> = points
        .iter()
        .map(|p| f64::from(dist2(p, &centres[0])))
        .collect();
    while centres.len() < k {
        let w: Vec<f64> = d2.iter().zip(weights).map(|(d, c)| d * c).collect();
        if w.iter().all(|&x| x == 0.0) {
            break; // fewer distinct colours than k
        }
        let c = points[pick(&mut rng, &w)];
        for (d, p) in d2.iter_mut().zip(points) {
            *d = d.min(f64::from(dist2(p, &c)));
        }
        centres.push(c);
    }
    centres
}

/// Clusters the image's colours into `k` clusters (fewer when it has fewer distinct colours).
/// Labels are ordered by the clusters' lightness; each label's colour is its cluster's mean colour.
/// An image deeper than 8 bits is clustered in its values stretched over 0–255
/// ([`crate::eight_bit`]).
pub fn kmeans(image: &DynamicImage, k: usize) -> LabelGrid {
    let rgb = crate::eight_bit(image).to_rgb8();
    let keys = colours::packed(&rgb);
    let (colours, weights): (Vec<u32>, Vec<f64>) = colours::distinct(&keys)
        .into_iter()
        .map(|(c, n)| (c, n as f64))
        .unzip();
    let points: Vec<[f32; 3]> = colours.par_iter().map(|&c| lab_of(c)).collect();
    let mut centres = seed_centres(&points, &weights, k);
    let mut assign: Vec<usize> = vec![usize::MAX; points.len()];
    for _ in 0..MAX_ITERATIONS {
        let next: Vec<usize> = points.par_iter().map(|p| nearest(p, &centres).0).collect();
        let changed = next != assign;
        assign = next;
        if !changed {
            break;
        }
        let mut sum = vec![[0f64; 4]; centres.len()];
        for ((p, &a), &w) in points.iter().zip(&assign).zip(&weights) {
            for d in 0..3 {
                sum[a][d] += f64::from(p[d]) * w;
            }
            sum[a][3] += w;
        }
        for (c, s) in centres.iter_mut().zip(&sum) {
            if s[3] > 0.0 {
                *c = [
                    (s[0] / s[3]) as f32,
                    (s[1] / s[3]) as f32,
                    (s[2] / s[3]) as f32,
                ];
            }
        }
    }
    // Order clusters by lightness (then a, b) so that label ids do not depend on seeding details.
    let mut order: Vec<usize> = (0..centres.len()).collect();
    order.sort_by(|&a, &b| {
        centres[a]
            .partial_cmp(&centres[b])
            .unwrap_or(std::cmp::Ordering::Equal)
    });
    let mut rank = vec![0u32; centres.len()];
    for (r, &c) in order.iter().enumerate() {
        rank[c] = r as u32;
    }
    // Mean sRGB colour of each cluster, for display.
    let mut mean = vec![[0f64; 4]; centres.len()];
    for ((&c, &a), &w) in colours.iter().zip(&assign).zip(&weights) {
        for (d, v) in colours::channels(c).into_iter().enumerate() {
            mean[a][d] += f64::from(v) * w;
        }
        mean[a][3] += w;
    }
    let regions: Vec<Region> = order
        .iter()
        .enumerate()
        .map(|(r, &c)| {
            let m = mean[c];
            let colour = [0, 1, 2].map(|d| {
                if m[3] > 0.0 {
                    (m[d] / m[3]).round() as u8
                } else {
                    0
                }
            });
            Region {
                name: format!("cluster {r}"),
                colour,
            }
        })
        .collect();
    let labels: Vec<u32> = keys
        .par_iter()
        .map(|k| {
            let i = colours
                .binary_search(k)
                .expect("every pixel colour is a distinct colour");
            rank[assign[i]]
        })
        .collect();
    let grid = LabelGrid::new(image.width(), image.height(), labels, regions)
        .expect("ranks index the regions");
    grid.with_labels(grid.labels().to_vec())
}
