//! The label grid: one label per pixel, with a name and a display colour per label.

use std::path::Path;

use image::RgbImage;
use serde::Serialize;

use crate::ClassifyError;

/// What a label stands for.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Region {
    /// A human-readable name ("value 3", "#ff8800", "class 2", or the user's name).
    pub name: String,
    /// The colour used when drawing the label.
    pub colour: [u8; 3],
}

/// A W×H grid of labels (row-major; pixel `(col, row)` at `row * width + col`), and what each
/// label means. Labels are dense: `0..regions.len()`.
///
/// ```
/// use imesh_classify::{LabelGrid, Region};
/// let regions = vec![
///     Region { name: "air".into(), colour: [0, 0, 0] },
///     Region { name: "bone".into(), colour: [255, 255, 255] },
/// ];
/// let grid = LabelGrid::new(2, 2, vec![0, 1, 1, 1], regions).unwrap();
/// assert_eq!(grid.label(1, 0), 1);
/// assert_eq!(grid.counts(), vec![1, 3]);
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct LabelGrid {
    width: u32,
    height: u32,
    labels: Vec<u32>,
    regions: Vec<Region>,
}

impl LabelGrid {
    /// A grid from its labels; `None` when the sizes disagree or a label has no region.
    pub fn new(width: u32, height: u32, labels: Vec<u32>, regions: Vec<Region>) -> Option<Self> {
        let ok = labels.len() as u64 == u64::from(width) * u64::from(height)
            && labels.iter().all(|&l| (l as usize) < regions.len());
        ok.then_some(Self {
            width,
            height,
            labels,
            regions,
        })
    }

    /// Width in pixels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in pixels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// The label of pixel `(col, row)`.
    pub fn label(&self, col: u32, row: u32) -> u32 {
        self.labels[row as usize * self.width as usize + col as usize]
    }

    /// All labels, row-major.
    pub fn labels(&self) -> &[u32] {
        &self.labels
    }

    /// What each label means.
    pub fn regions(&self) -> &[Region] {
        &self.regions
    }

    /// Number of labels.
    pub fn num_labels(&self) -> usize {
        self.regions.len()
    }

    /// Pixels per label.
    pub fn counts(&self) -> Vec<usize> {
        let mut c = vec![0; self.regions.len()];
        for &l in &self.labels {
            c[l as usize] += 1;
        }
        c
    }

    /// Replaces the labels (same size), dropping labels no pixel uses any more and renumbering the
    /// rest in their previous order.
    pub(crate) fn with_labels(&self, labels: Vec<u32>) -> Self {
        self.resized(self.width, self.height, labels)
    }

    /// [`LabelGrid::with_labels`] for a grid of another size (`labels` holds `width × height`).
    pub(crate) fn resized(&self, width: u32, height: u32, labels: Vec<u32>) -> Self {
        let mut used = vec![false; self.regions.len()];
        for &l in &labels {
            used[l as usize] = true;
        }
        let mut new_id = vec![u32::MAX; self.regions.len()];
        let mut regions = Vec::new();
        for (old, region) in self.regions.iter().enumerate() {
            if used[old] {
                new_id[old] = regions.len() as u32;
                regions.push(region.clone());
            }
        }
        let labels = labels.into_iter().map(|l| new_id[l as usize]).collect();
        Self {
            width,
            height,
            labels,
            regions,
        }
    }

    /// The grid drawn with each label's colour.
    pub fn to_rgb_image(&self) -> RgbImage {
        RgbImage::from_fn(self.width, self.height, |c, r| {
            image::Rgb(self.regions[self.label(c, r) as usize].colour)
        })
    }

    /// Writes the grid as a colour PNG, atomically (a temporary file renamed into place).
    ///
    /// # Errors
    /// [`ClassifyError::Write`] when the file cannot be written.
    pub fn save_png(&self, path: &Path) -> Result<(), ClassifyError> {
        let write_err = |reason: String| ClassifyError::Write {
            path: path.to_path_buf(),
            reason,
        };
        let mut tmp = path.as_os_str().to_owned();
        tmp.push(".tmp");
        let tmp = std::path::PathBuf::from(tmp);
        self.to_rgb_image()
            .save_with_format(&tmp, image::ImageFormat::Png)
            .map_err(|e| write_err(e.to_string()))?;
        std::fs::rename(&tmp, path).map_err(|e| {
            let _ = std::fs::remove_file(&tmp);
            write_err(e.to_string())
        })
    }
}

/// A qualitative palette for labels that have no colour of their own (well separated first).
pub(crate) fn palette_colour(i: usize) -> [u8; 3] {
    const BASE: [[u8; 3]; 12] = [
        [31, 119, 180],
        [255, 127, 14],
        [44, 160, 44],
        [214, 39, 40],
        [148, 103, 189],
        [140, 86, 75],
        [227, 119, 194],
        [127, 127, 127],
        [188, 189, 34],
        [23, 190, 207],
        [255, 221, 87],
        [0, 0, 0],
    ];
    if i < BASE.len() {
        return BASE[i];
    }
    // Beyond the base set: golden-angle hues, so that neighbours in id still differ.
    let h = (i as f64 * 137.507_764) % 360.0;
    let (s, v) = (0.65, if i % 2 == 0 { 0.9 } else { 0.6 });
    let c = v * s;
    let x = c * (1.0 - ((h / 60.0) % 2.0 - 1.0).abs());
    let (r, g, b) = match (h / 60.0) as u32 {
        0 => (c, x, 0.0),
        1 => (x, c, 0.0),
        2 => (0.0, c, x),
        3 => (0.0, x, c),
        4 => (x, 0.0, c),
        _ => (c, 0.0, x),
    };
    let m = v - c;
    [r, g, b].map(|u| ((u + m) * 255.0).round() as u8)
}
