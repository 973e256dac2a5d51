//! The supervised texture classifier of Imesh: a W-operator learned from sample rectangles.
//!
//! Each pixel is described by its *pattern*: the quantised values of a few (offset, channel) pairs
//! inside a window around it, channels taken from RGB, HSV, and three window statistics of the
//! luminance (local mean, standard deviation and edge density), which carry the texture's scale and
//! grain that a handful of single pixels cannot. The pairs are chosen on the training
//! pixels by sequential floating forward search (SFFS), minimising the mean conditional entropy of
//! the label given the pattern, with the usual penalty for patterns seen once (they count as
//! maximally uncertain, so the search does not reward memorising the samples). A pixel then gets the
//! most frequent training label of its pattern; an unseen pattern votes among the training patterns
//! one quantisation step away (Hamming distance 1), and failing that takes the label whose centroid
//! of window statistics (mean colour, luminance spread) is nearest.

use std::collections::HashMap;
use std::path::Path;

use image::DynamicImage;
use rayon::prelude::*;
use serde::Deserialize;

use crate::grid::{palette_colour, Region};
use crate::{ClassifyError, LabelGrid};

/// Channels a pattern can read: R, G, B, H, S, V, and over the window around the pixel the mean
/// of V, its standard deviation, and the mean gradient magnitude of V (local brightness, contrast
/// and edge density).
const CHANNELS: usize = 9;
/// Training pixels used by the offset search at most (an even subsample beyond).
const MAX_TRAINING_PIXELS: usize = 10_000;
/// Candidate offsets lie on a lattice of at most this many positions per axis across the window.
const OFFSET_POSITIONS: i32 = 7;

/// One label's samples.
#[derive(Clone, Debug, PartialEq)]
pub struct SampleLabel {
    /// The label's name.
    pub name: String,
    /// Its display colour.
    pub colour: [u8; 3],
    /// Sample rectangles `[x, y, w, h]` in pixels.
    pub rectangles: Vec<[u32; 4]>,
}

/// A texture training set: labelled sample rectangles and the operator's parameters.
///
/// The TOML form:
/// ```toml
/// window = 15       # odd window side (default 15)
/// levels = 4        # quantisation levels per channel, 2–16 (default 4)
/// offsets = 8       # most (offset, channel) pairs in a pattern, 1–16 (default 8)
///
/// [[label]]
/// name = "brick"
/// colour = "#a0522d"               # optional
/// rectangles = [[0, 0, 120, 120]]  # x, y, w, h
///
/// [[label]]
/// name = "grass"
/// rectangles = [[200, 0, 120, 120], [200, 150, 60, 60]]
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct TextureSamples {
    /// Window side (odd).
    pub window: u32,
    /// Quantisation levels per channel.
    pub levels: u8,
    /// Maximum number of (offset, channel) pairs.
    pub offsets: usize,
    /// The labels, at least two.
    pub labels: Vec<SampleLabel>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SamplesFile {
    window: Option<u32>,
    levels: Option<u8>,
    offsets: Option<usize>,
    #[serde(default)]
    label: Vec<LabelEntry>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct LabelEntry {
    name: String,
    colour: Option<String>,
    rectangles: Vec<[u32; 4]>,
}

fn parse_colour(s: &str) -> Option<[u8; 3]> {
    let hex = s.strip_prefix('#')?;
    if hex.len() != 6 {
        return None;
    }
    let v = u32::from_str_radix(hex, 16).ok()?;
    Some([(v >> 16) as u8, (v >> 8) as u8, v as u8])
}

impl TextureSamples {
    /// Reads a sample file.
    ///
    /// # Errors
    /// [`ClassifyError::Io`] or [`ClassifyError::Samples`] (syntax, missing or invalid fields,
    /// fewer than two labels, a label without rectangles, parameters out of range).
    pub fn load(path: &Path) -> Result<Self, ClassifyError> {
        let text = std::fs::read_to_string(path).map_err(|source| ClassifyError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        Self::parse(&text, path)
    }

    /// Parses the TOML text of a sample file (`path` only names it in errors).
    ///
    /// ```
    /// use imesh_classify::TextureSamples;
    /// let s = TextureSamples::parse("[[label]]\nname = \"a\"\nrectangles = [[0, 0, 4, 4]]\n[[label]]\nname = \"b\"\nrectangles = [[4, 0, 4, 4]]\n", "s.toml".as_ref()).unwrap();
    /// assert_eq!((s.window, s.levels, s.offsets, s.labels.len()), (15, 4, 8, 2));
    /// assert!(TextureSamples::parse("[[label]]\nname = \"a\"\nrectangles = [[0, 0, 4, 4]]\n", "s.toml".as_ref()).is_err());
    /// ```
    pub fn parse(text: &str, path: &Path) -> Result<Self, ClassifyError> {
        let err = |reason: String| ClassifyError::Samples {
            path: path.to_path_buf(),
            reason,
        };
        let file: SamplesFile =
            toml::from_str(text).map_err(|e| err(e.to_string().trim().replace('\n', " ")))?;
        let window = file.window.unwrap_or(15);
        if window % 2 == 0 || !(1..=31).contains(&window) {
            return Err(err(format!(
                "window must be odd, from 1 to 31, not {window}"
            )));
        }
        let levels = file.levels.unwrap_or(4);
        if !(2..=16).contains(&levels) {
            return Err(err(format!("levels must be from 2 to 16, not {levels}")));
        }
        let offsets = file.offsets.unwrap_or(8);
        if !(1..=16).contains(&offsets) {
            return Err(err(format!("offsets must be from 1 to 16, not {offsets}")));
        }
        if file.label.len() < 2 {
            return Err(err(format!(
                "found {} label(s): give samples of at least two labels, each as a [[label]] table with a name and rectangles",
                file.label.len()
            )));
        }
        let mut labels = Vec::new();
        for (i, l) in file.label.into_iter().enumerate() {
            if l.rectangles.is_empty() || l.rectangles.iter().any(|r| r[2] == 0 || r[3] == 0) {
                return Err(err(format!(
                    "label '{}' needs at least one rectangle [x, y, w, h] with w, h > 0",
                    l.name
                )));
            }
            let colour = match l.colour {
                Some(c) => parse_colour(&c).ok_or_else(|| {
                    err(format!("colour '{c}' of label '{}' is not #rrggbb", l.name))
                })?,
                None => palette_colour(i),
            };
            labels.push(SampleLabel {
                name: l.name,
                colour,
                rectangles: l.rectangles,
            });
        }
        Ok(Self {
            window,
            levels,
            offsets,
            labels,
        })
    }

    /// Checks that every rectangle lies inside a `width × height` image.
    ///
    /// # Errors
    /// [`ClassifyError::RectangleOutside`] for the first one that does not.
    pub fn check_inside(&self, width: u32, height: u32) -> Result<(), ClassifyError> {
        for l in &self.labels {
            for r in &l.rectangles {
                let inside = u64::from(r[0]) + u64::from(r[2]) <= u64::from(width)
                    && u64::from(r[1]) + u64::from(r[3]) <= u64::from(height);
                if !inside {
                    return Err(ClassifyError::RectangleOutside {
                        label: l.name.clone(),
                        rect: *r,
                        width,
                        height,
                    });
                }
            }
        }
        Ok(())
    }
}

/// The six channels of every pixel, 8 bits each, plane by plane.
struct Planes {
    width: usize,
    height: usize,
    data: Vec<[u8; CHANNELS]>,
}

impl Planes {
    fn of(image: &DynamicImage, half: i32) -> Self {
        // A deep image's own stretch over 8 bits: training and classifying one image agree.
        let rgb = crate::eight_bit(image).to_rgb8();
        let mut data: Vec<[u8; CHANNELS]> = rgb
            .as_raw()
            .par_chunks_exact(3)
            .map(|p| {
                let (r, g, b) = (p[0], p[1], p[2]);
                let max = r.max(g).max(b);
                let min = r.min(g).min(b);
                let delta = f32::from(max - min);
                let s = if max == 0 {
                    0
                } else {
                    (255.0 * delta / f32::from(max)).round() as u8
                };
                let h = if delta == 0.0 {
                    0.0
                } else if max == r {
                    60.0 * ((f32::from(g) - f32::from(b)) / delta).rem_euclid(6.0)
                } else if max == g {
                    60.0 * ((f32::from(b) - f32::from(r)) / delta + 2.0)
                } else {
                    60.0 * ((f32::from(r) - f32::from(g)) / delta + 4.0)
                };
                [r, g, b, (h * 255.0 / 360.0).round() as u8, s, max, 0, 0, 0]
            })
            .collect();
        let (width, height) = (image.width() as usize, image.height() as usize);
        window_moments(&mut data, width, height, half);
        Self {
            width,
            height,
            data,
        }
    }

    /// Channel values at `(x + dx, y + dy)`, clamped to the image (replicated border).
    #[inline]
    fn at(&self, x: usize, y: usize, dx: i32, dy: i32) -> &[u8; CHANNELS] {
        let xx = (x as i64 + i64::from(dx)).clamp(0, self.width as i64 - 1) as usize;
        let yy = (y as i64 + i64::from(dy)).clamp(0, self.height as i64 - 1) as usize;
        &self.data[yy * self.width + xx]
    }
}

/// One pattern element: a channel read at an offset from the pixel.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Feature {
    dx: i32,
    dy: i32,
    channel: usize,
}

/// A trained texture classifier.
pub struct TextureClassifier {
    features: Vec<Feature>,
    /// Per channel: the upper edges of the quantisation bins (value ≤ cut[i] → level i).
    cuts: Vec<Vec<u8>>,
    levels: u8,
    half: i32,
    /// Pattern → (most frequent label, its count).
    table: HashMap<u64, (u32, u32)>,
    /// Per label: mean window statistics, and the statistics' spread for scaling.
    centroids: Vec<[f64; 4]>,
    spread: [f64; 4],
    regions: Vec<Region>,
}

/// Penalised mean conditional entropy of the label given the pattern, in bits.
fn criterion(patterns: &[u64], labels: &[u32], num_labels: usize) -> f64 {
    let mut counts: HashMap<u64, Vec<u32>> = HashMap::with_capacity(patterns.len() / 2);
    for (&p, &l) in patterns.iter().zip(labels) {
        counts.entry(p).or_insert_with(|| vec![0; num_labels])[l as usize] += 1;
    }
    let n = patterns.len() as f64;
    let max_entropy = (num_labels as f64).log2();
    counts
        .values()
        .map(|c| {
            let total: u32 = c.iter().sum();
            if total == 1 {
                return max_entropy / n;
            }
            let t = f64::from(total);
            let h: f64 = c
                .iter()
                .filter(|&&k| k > 0)
                .map(|&k| -(f64::from(k) / t) * (f64::from(k) / t).log2())
                .sum();
            t / n * h
        })
        .sum()
}

impl TextureClassifier {
    /// Trains the operator on the sample rectangles of `image`.
    ///
    /// # Errors
    /// [`ClassifyError::RectangleOutside`] when a rectangle does not fit in the image.
    pub fn train(image: &DynamicImage, samples: &TextureSamples) -> Result<Self, ClassifyError> {
        samples.check_inside(image.width(), image.height())?;
        let half = (samples.window / 2) as i32;
        let planes = Planes::of(image, half);
        // Training pixels (label, x, y), evenly subsampled when there are many.
        let mut train: Vec<(u32, usize, usize)> = Vec::new();
        for (l, s) in samples.labels.iter().enumerate() {
            for r in &s.rectangles {
                for y in r[1]..r[1] + r[3] {
                    for x in r[0]..r[0] + r[2] {
                        train.push((l as u32, x as usize, y as usize));
                    }
                }
            }
        }
        // The offset search evaluates its criterion hundreds of times: it works on an even subsample.
        // The final pattern table uses every training pixel.
        let all_train = std::mem::take(&mut train);
        train = if all_train.len() > MAX_TRAINING_PIXELS {
            let step = all_train.len() as f64 / MAX_TRAINING_PIXELS as f64;
            (0..MAX_TRAINING_PIXELS)
                .map(|i| all_train[(i as f64 * step) as usize])
                .collect()
        } else {
            all_train.clone()
        };
        let cuts = quantile_cuts(&planes, &train, samples.levels);
        let levels_of =
            |x, y, f: &Feature| quantise(planes.at(x, y, f.dx, f.dy)[f.channel], &cuts[f.channel]);
        // Candidate features: offsets on a lattice spanning the window (at most 7 × 7 positions,
        // so that wide windows stay cheap to search), on every informative channel.
        let channels = informative_channels(&planes, &train);
        let step = ((2 * half + 1) + OFFSET_POSITIONS - 1) / OFFSET_POSITIONS;
        let axis: Vec<i32> = (-half..=half).filter(|d| d % step == 0).collect();
        let candidates: Vec<Feature> = axis
            .iter()
            .flat_map(|&dy| axis.iter().map(move |&dx| (dx, dy)))
            .flat_map(|(dx, dy)| {
                channels
                    .iter()
                    .map(move |&channel| Feature { dx, dy, channel })
            })
            .collect();
        let labels: Vec<u32> = train.iter().map(|t| t.0).collect();
        let num_labels = samples.labels.len();
        let pattern_of = |set: &[Feature], t: &(u32, usize, usize)| {
            set.iter().enumerate().fold(0u64, |k, (i, f)| {
                k | (u64::from(levels_of(t.1, t.2, f)) << (4 * i))
            })
        };
        let evaluate = |set: &[Feature]| {
            let p: Vec<u64> = train.iter().map(|t| pattern_of(set, t)).collect();
            criterion(&p, &labels, num_labels)
        };
        let features = sffs(&candidates, samples.offsets, &evaluate);

        let mut counts: HashMap<u64, Vec<u32>> = HashMap::new();
        for t in &all_train {
            counts
                .entry(pattern_of(&features, t))
                .or_insert_with(|| vec![0; num_labels])[t.0 as usize] += 1;
        }
        let table = counts
            .into_iter()
            .map(|(p, c)| {
                let (best, &n) = c
                    .iter()
                    .enumerate()
                    .max_by_key(|&(l, &n)| (n, std::cmp::Reverse(l)))
                    .expect("num_labels ≥ 2");
                (p, (best as u32, n))
            })
            .collect();
        let stats: Vec<[f64; 4]> = train
            .par_iter()
            .map(|t| window_stats(&planes, t.1, t.2, half))
            .collect();
        let mut centroids = vec![[0.0f64; 4]; num_labels];
        let mut per_label = vec![0.0f64; num_labels];
        let mut mean = [0.0f64; 4];
        for (t, s) in train.iter().zip(&stats) {
            per_label[t.0 as usize] += 1.0;
            for d in 0..4 {
                centroids[t.0 as usize][d] += s[d];
                mean[d] += s[d] / stats.len() as f64;
            }
        }
        for (c, n) in centroids.iter_mut().zip(&per_label) {
            c.iter_mut().for_each(|v| *v /= n.max(1.0));
        }
        let mut spread = [0.0f64; 4];
        for s in &stats {
            for d in 0..4 {
                spread[d] += (s[d] - mean[d]).powi(2) / stats.len() as f64;
            }
        }
        let spread = spread.map(|v: f64| v.sqrt().max(1e-6));
        let regions = samples
            .labels
            .iter()
            .map(|l| Region {
                name: l.name.clone(),
                colour: l.colour,
            })
            .collect();
        Ok(Self {
            features,
            cuts,
            levels: samples.levels,
            half,
            table,
            centroids,
            spread,
            regions,
        })
    }

    /// The (offset, channel) pairs chosen, as `(dx, dy, channel)` with channels R, G, B, H, S, V,
    /// window mean, standard deviation and gradient magnitude of V = 0–8.
    pub fn features(&self) -> Vec<(i32, i32, usize)> {
        self.features
            .iter()
            .map(|f| (f.dx, f.dy, f.channel))
            .collect()
    }

    /// Labels every pixel of `image`.
    pub fn classify(&self, image: &DynamicImage) -> LabelGrid {
        let planes = Planes::of(image, self.half);
        let (w, h) = (planes.width, planes.height);
        let labels: Vec<u32> = (0..w * h)
            .into_par_iter()
            .map(|i| self.label_pixel(&planes, i % w, i / w))
            .collect();
        LabelGrid::new(image.width(), image.height(), labels, self.regions.clone())
            .expect("labels come from the regions")
    }

    fn label_pixel(&self, planes: &Planes, x: usize, y: usize) -> u32 {
        let levels: Vec<u8> = self
            .features
            .iter()
            .map(|f| {
                quantise(
                    planes.at(x, y, f.dx, f.dy)[f.channel],
                    &self.cuts[f.channel],
                )
            })
            .collect();
        let key = |lv: &[u8]| {
            lv.iter()
                .enumerate()
                .fold(0u64, |k, (i, &v)| k | (u64::from(v) << (4 * i)))
        };
        if let Some(&(label, _)) = self.table.get(&key(&levels)) {
            return label;
        }
        // Unseen: vote among the training patterns one quantisation step away.
        let mut votes = vec![0u32; self.regions.len()];
        let mut neighbour = levels.clone();
        for i in 0..levels.len() {
            for v in 0..self.levels {
                if v == levels[i] {
                    continue;
                }
                neighbour[i] = v;
                if let Some(&(label, n)) = self.table.get(&key(&neighbour)) {
                    votes[label as usize] += n;
                }
            }
            neighbour[i] = levels[i];
        }
        if let Some((best, _)) = votes
            .iter()
            .enumerate()
            .filter(|(_, &v)| v > 0)
            .max_by_key(|&(l, &v)| (v, std::cmp::Reverse(l)))
        {
            return best as u32;
        }
        // Nothing close: the nearest centroid of window statistics.
        let s = window_stats(planes, x, y, self.half);
        let dist = |c: &[f64; 4]| {
            (0..4)
                .map(|d| ((s[d] - c[d]) / self.spread[d]).powi(2))
                .sum::<f64>()
        };
        (0..self.centroids.len())
            .min_by(|&a, &b| dist(&self.centroids[a]).total_cmp(&dist(&self.centroids[b])))
            .unwrap_or(0) as u32
    }
}

/// Fills channels 6, 7 and 8 with the mean, the standard deviation and the mean gradient magnitude
/// (`|∂V/∂x| + |∂V/∂y|`, forward differences) of V over the `(2·half+1)²` window (clamped at the
/// border), from integral images.
fn window_moments(data: &mut [[u8; CHANNELS]], width: usize, height: usize, half: i32) {
    let stride = width + 1;
    let mut sum = vec![0u64; stride * (height + 1)];
    let mut sq = vec![0u64; stride * (height + 1)];
    let mut grad = vec![0u64; stride * (height + 1)];
    let v_at = |x: usize, y: usize| i64::from(data[y * width + x][5]);
    for y in 0..height {
        let (mut row_sum, mut row_sq, mut row_grad) = (0u64, 0u64, 0u64);
        for x in 0..width {
            let v = v_at(x, y);
            let gx = if x + 1 < width {
                (v_at(x + 1, y) - v).unsigned_abs()
            } else {
                0
            };
            let gy = if y + 1 < height {
                (v_at(x, y + 1) - v).unsigned_abs()
            } else {
                0
            };
            row_sum += v as u64;
            row_sq += (v * v) as u64;
            row_grad += gx + gy;
            let (i, up) = ((y + 1) * stride + x + 1, y * stride + x + 1);
            sum[i] = sum[up] + row_sum;
            sq[i] = sq[up] + row_sq;
            grad[i] = grad[up] + row_grad;
        }
    }
    let h = half as usize;
    data.par_chunks_mut(width).enumerate().for_each(|(y, row)| {
        let (y0, y1) = (y.saturating_sub(h), (y + h + 1).min(height));
        for (x, px) in row.iter_mut().enumerate() {
            let (x0, x1) = (x.saturating_sub(h), (x + h + 1).min(width));
            let area = |t: &[u64]| {
                t[y1 * stride + x1] + t[y0 * stride + x0]
                    - t[y0 * stride + x1]
                    - t[y1 * stride + x0]
            };
            let n = ((y1 - y0) * (x1 - x0)) as f64;
            let mean = area(&sum) as f64 / n;
            let var = (area(&sq) as f64 / n - mean * mean).max(0.0);
            px[6] = mean.round() as u8;
            px[7] = var.sqrt().round().min(255.0) as u8;
            px[8] = (area(&grad) as f64 / n).round().min(255.0) as u8;
        }
    });
}

/// Mean R, G, B and the standard deviation of V over the window around `(x, y)`.
fn window_stats(planes: &Planes, x: usize, y: usize, half: i32) -> [f64; 4] {
    let (mut sum, mut sq, mut n) = ([0.0; 3], 0.0, 0.0);
    let mut sum_v = 0.0;
    for dy in -half..=half {
        for dx in -half..=half {
            let p = planes.at(x, y, dx, dy);
            for c in 0..3 {
                sum[c] += f64::from(p[c]);
            }
            let v = f64::from(p[5]);
            sum_v += v;
            sq += v * v;
            n += 1.0;
        }
    }
    let mean_v = sum_v / n;
    [
        sum[0] / n,
        sum[1] / n,
        sum[2] / n,
        (sq / n - mean_v * mean_v).max(0.0).sqrt(),
    ]
}

#[inline]
fn quantise(v: u8, cuts: &[u8]) -> u8 {
    cuts.iter().take_while(|&&c| v > c).count() as u8
}

/// Equal-frequency bins per channel over the training pixels.
fn quantile_cuts(planes: &Planes, train: &[(u32, usize, usize)], levels: u8) -> Vec<Vec<u8>> {
    (0..CHANNELS)
        .map(|c| {
            let mut v: Vec<u8> = train.iter().map(|t| planes.at(t.1, t.2, 0, 0)[c]).collect();
            v.sort_unstable();
            let mut cuts: Vec<u8> = (1..levels)
                .map(|i| v[(v.len() * usize::from(i) / usize::from(levels)).min(v.len() - 1)])
                .collect();
            cuts.dedup();
            cuts
        })
        .collect()
}

/// Channels that carry information on the training pixels: not constant, and not identical to an
/// earlier channel (a grey image keeps one of R = G = B = V, and neither H nor S).
fn informative_channels(planes: &Planes, train: &[(u32, usize, usize)]) -> Vec<usize> {
    let column = |c: usize| {
        train
            .iter()
            .map(|t| planes.at(t.1, t.2, 0, 0)[c])
            .collect::<Vec<u8>>()
    };
    let cols: Vec<Vec<u8>> = (0..CHANNELS).map(column).collect();
    let mut keep: Vec<usize> = Vec::new();
    for c in 0..CHANNELS {
        let constant = cols[c].iter().all(|&v| v == cols[c][0]);
        if !constant && !keep.iter().any(|&k| cols[k] == cols[c]) {
            keep.push(c);
        }
    }
    if keep.is_empty() {
        keep.push(5);
    }
    keep
}

/// Sequential floating forward search: add the best feature, then drop features while dropping one
/// beats the best subset of that size seen so far. Returns the best subset of any size ≤ `max`.
fn sffs(
    candidates: &[Feature],
    max: usize,
    evaluate: &(dyn Fn(&[Feature]) -> f64 + Sync),
) -> Vec<Feature> {
    let mut best: Vec<Option<(f64, Vec<Feature>)>> = vec![None; max + 1];
    let mut current: Vec<Feature> = Vec::new();
    let mut steps = 0;
    while current.len() < max && steps < 4 * max {
        steps += 1;
        let scored: Vec<(f64, Feature)> = candidates
            .par_iter()
            .filter(|f| !current.contains(f))
            .map(|&f| {
                let mut s = current.clone();
                s.push(f);
                (evaluate(&s), f)
            })
            .collect();
        let Some(&(score, f)) = scored.iter().min_by(|a, b| a.0.total_cmp(&b.0)) else {
            break;
        };
        current.push(f);
        let k = current.len();
        if best[k].as_ref().is_none_or(|(b, _)| score < *b) {
            best[k] = Some((score, current.clone()));
        }
        // Conditional exclusion.
        while current.len() > 2 {
            let (score, i) = (0..current.len())
                .into_par_iter()
                .map(|i| {
                    let mut s = current.clone();
                    s.remove(i);
                    (evaluate(&s), i)
                })
                .min_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)))
                .expect("at least three features");
            let k = current.len() - 1;
            if best[k].as_ref().is_some_and(|(b, _)| score < *b) {
                current.remove(i);
                best[k] = Some((score, current.clone()));
            } else {
                break;
            }
        }
    }
    best.into_iter()
        .flatten()
        .min_by(|a, b| a.0.total_cmp(&b.0).then(a.1.len().cmp(&b.1.len())))
        .map(|(_, s)| s)
        .unwrap_or_default()
}
