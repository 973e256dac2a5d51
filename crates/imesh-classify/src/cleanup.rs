//! Clean-up of a label grid: small regions and isolated pixels.

use std::collections::HashMap;

use rayon::prelude::*;

use crate::LabelGrid;

/// Merges every 4-connected region smaller than `min_pixels` into the neighbouring region it shares
/// the longest border with (smallest regions first, so that a merged region grows before its own
/// turn comes). A region with no neighbour (the whole image) is kept.
///
/// ```
/// use imesh_classify::{remove_small_regions, LabelGrid, Region};
/// let r = |n: &str| Region { name: n.into(), colour: [0, 0, 0] };
/// // A single pixel of label 1 inside label 0.
/// let g = LabelGrid::new(3, 3, vec![0, 0, 0, 0, 1, 0, 0, 0, 0], vec![r("a"), r("b")]).unwrap();
/// let clean = remove_small_regions(&g, 2);
/// assert!(clean.labels().iter().all(|&l| l == 0));
/// assert_eq!(clean.num_labels(), 1);
/// ```
pub fn remove_small_regions(grid: &LabelGrid, min_pixels: usize) -> LabelGrid {
    let (w, h) = (grid.width() as usize, grid.height() as usize);
    let comp = four_connected_components(grid.labels(), w, h);
    let n = comp.iter().copied().max().unwrap_or(0) as usize + 1;
    let mut size = vec![0usize; n];
    let mut label = vec![0u32; n];
    let mut border: Vec<HashMap<u32, usize>> = vec![HashMap::new(); n];
    for (i, &c) in comp.iter().enumerate() {
        size[c as usize] += 1;
        label[c as usize] = grid.labels()[i];
        let (x, y) = (i % w, i / w);
        for j in [(x + 1 < w).then(|| i + 1), (y + 1 < h).then(|| i + w)]
            .into_iter()
            .flatten()
        {
            let d = comp[j];
            if d != c {
                *border[c as usize].entry(d).or_default() += 1;
                *border[d as usize].entry(c).or_default() += 1;
            }
        }
    }
    let mut parent: Vec<u32> = (0..n as u32).collect();
    fn find(parent: &mut [u32], mut c: u32) -> u32 {
        while parent[c as usize] != c {
            parent[c as usize] = parent[parent[c as usize] as usize];
            c = parent[c as usize];
        }
        c
    }
    let mut small: Vec<u32> = (1..n as u32)
        .filter(|&c| size[c as usize] < min_pixels)
        .collect();
    small.sort_by_key(|&c| (size[c as usize], c));
    for c in small {
        if find(&mut parent, c) != c || size[c as usize] >= min_pixels {
            continue;
        }
        // Borders to current roots (earlier merges may have joined some neighbours).
        let mut by_root: HashMap<u32, usize> = HashMap::new();
        for (&d, &len) in &border[c as usize] {
            let r = find(&mut parent, d);
            if r != c {
                *by_root.entry(r).or_default() += len;
            }
        }
        let Some((&target, _)) = by_root
            .iter()
            .max_by_key(|(&r, &len)| (len, std::cmp::Reverse((label[r as usize], r))))
        else {
            continue;
        };
        parent[c as usize] = target;
        size[target as usize] += size[c as usize];
        let moved = std::mem::take(&mut border[c as usize]);
        for (d, len) in moved {
            *border[target as usize].entry(d).or_default() += len;
        }
    }
    let root_label: Vec<u32> = (0..n as u32)
        .map(|c| label[find(&mut parent, c) as usize])
        .collect();
    grid.with_labels(comp.iter().map(|&c| root_label[c as usize]).collect())
}

/// One 4-connected region of a label grid: its label, its pixel count and the length of its
/// boundary in pixel edges (against other regions and the image border).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PixelRegion {
    /// Its label.
    pub label: u32,
    /// Its pixels.
    pub pixels: usize,
    /// Pixel edges on its boundary, the image border included.
    pub perimeter: usize,
}

impl PixelRegion {
    /// `2 · area / perimeter` in pixels, with the staircase perimeter shortened by π/4 (the
    /// average ratio of a curve's length to its staircase's): about a strip's width, a disc's
    /// radius.
    ///
    /// ```
    /// use imesh_classify::PixelRegion;
    /// // A 10 × 2 strip: 20 pixels, 24 edges.
    /// let r = PixelRegion { label: 0, pixels: 20, perimeter: 24 };
    /// assert!((r.width() - 40.0 / (24.0 * std::f64::consts::FRAC_PI_4)).abs() < 1e-12);
    /// ```
    pub fn width(&self) -> f64 {
        if self.perimeter == 0 {
            return 0.0;
        }
        2.0 * self.pixels as f64 / (self.perimeter as f64 * std::f64::consts::FRAC_PI_4)
    }
}

/// The 4-connected regions of `grid`, with their sizes and perimeters.
///
/// ```
/// use imesh_classify::{pixel_regions, LabelGrid, Region};
/// let r = |n: &str| Region { name: n.into(), colour: [0, 0, 0] };
/// // A single pixel of label 1 inside label 0.
/// let g = LabelGrid::new(3, 3, vec![0, 0, 0, 0, 1, 0, 0, 0, 0], vec![r("a"), r("b")]).unwrap();
/// let regions = pixel_regions(&g);
/// assert_eq!(regions.len(), 2);
/// assert_eq!((regions[0].pixels, regions[0].perimeter), (8, 16));
/// assert_eq!((regions[1].pixels, regions[1].perimeter), (1, 4));
/// ```
pub fn pixel_regions(grid: &LabelGrid) -> Vec<PixelRegion> {
    let (w, h) = (grid.width() as usize, grid.height() as usize);
    let comp = four_connected_components(grid.labels(), w, h);
    let n = comp.iter().copied().max().map_or(0, |m| m as usize + 1);
    let mut regions = vec![
        PixelRegion {
            label: 0,
            pixels: 0,
            perimeter: 0,
        };
        n
    ];
    for (i, &c) in comp.iter().enumerate() {
        let r = &mut regions[c as usize];
        r.label = grid.labels()[i];
        r.pixels += 1;
        // A side on the image's border or against another region.
        r.perimeter += four_neighbours(i, w, h)
            .into_iter()
            .filter(|j| j.is_none_or(|j| comp[j] != c))
            .count();
    }
    regions
}

/// Replaces each label by the most frequent label in its `(2r+1)²` window (ties keep the pixel's
/// own label), `iterations` times: removes speckle from pixel classifiers.
///
/// ```
/// use imesh_classify::{majority_filter, LabelGrid, Region};
/// let r = |n: &str| Region { name: n.into(), colour: [0, 0, 0] };
/// let g = LabelGrid::new(3, 3, vec![0, 0, 0, 0, 1, 0, 0, 0, 0], vec![r("a"), r("b")]).unwrap();
/// assert_eq!(majority_filter(&g, 1, 1).label(1, 1), 0);
/// ```
pub fn majority_filter(grid: &LabelGrid, radius: u32, iterations: u32) -> LabelGrid {
    let (w, h) = (grid.width() as usize, grid.height() as usize);
    let r = radius as usize;
    let mut labels = grid.labels().to_vec();
    if labels.is_empty() {
        return grid.clone();
    }
    let kinds = labels.iter().max().map_or(0, |&m| m as usize + 1);
    for _ in 0..iterations {
        let src = &labels;
        let mut next = vec![0u32; src.len()];
        // Bands of rows, each worker with one count per label (left at zero after each row).
        next.par_chunks_mut(w * MAJORITY_BAND_ROWS)
            .enumerate()
            .for_each_init(
                || vec![0u32; kinds],
                |counts, (band, out)| {
                    for (k, row) in out.chunks_mut(w).enumerate() {
                        let y = band * MAJORITY_BAND_ROWS + k;
                        majority_row(src, [w, h], y, r, counts, row);
                    }
                },
            );
        labels = next;
    }
    grid.with_labels(labels)
}

/// Rows per parallel task of [`majority_filter`].
const MAJORITY_BAND_ROWS: usize = 8;

/// Row `y` of the majority filter of radius `r` into `out`: a count per label slides along the
/// row (a step adds one window column and drops another, 2 (2r + 1) updates), and `counts`
/// (zero on entry, one slot per label) is zero again on return. A label holding more than half
/// the window keeps its pixel, as most pixels away from the boundaries do; elsewhere the
/// labels are compared by their counts (all labels, or the window's pixels when there are
/// fewer of those): a strictly larger count than the pixel's own replaces it, ties to the
/// smaller label.
fn majority_row(
    src: &[u32],
    [w, h]: [usize; 2],
    y: usize,
    r: usize,
    counts: &mut [u32],
    out: &mut [u32],
) {
    let (y0, y1) = (y.saturating_sub(r), (y + r).min(h - 1));
    let column = |counts: &mut [u32], x: usize, add: bool| {
        for yy in y0..=y1 {
            let c = &mut counts[src[yy * w + x] as usize];
            if add {
                *c += 1;
            } else {
                *c -= 1;
            }
        }
    };
    for x in 0..=r.min(w - 1) {
        column(counts, x, true);
    }
    for x in 0..w {
        let (x0, x1) = (x.saturating_sub(r), (x + r).min(w - 1));
        let window = (y1 - y0 + 1) * (x1 - x0 + 1);
        let own = src[y * w + x];
        let (mut best, mut most) = (own, counts[own as usize]);
        if 2 * most as usize <= window {
            if counts.len() <= window {
                for (l, &c) in counts.iter().enumerate() {
                    if c > most {
                        (best, most) = (l as u32, c);
                    }
                }
            } else {
                for yy in y0..=y1 {
                    for &l in &src[yy * w + x0..=yy * w + x1] {
                        let c = counts[l as usize];
                        if c > most || (c == most && best != own && l < best) {
                            (best, most) = (l, c);
                        }
                    }
                }
            }
        }
        out[x] = best;
        if x >= r {
            column(counts, x - r, false);
        }
        if x + r + 1 < w {
            column(counts, x + r + 1, true);
        }
    }
    // The last window's columns.
    for x in w.saturating_sub(r)..w {
        column(counts, x, false);
    }
}

/// A component id (from 0) per pixel: 4-connected pixels of one label share it. (imageproc's
/// `connected_components` sizes its union-find too small when nearly every pixel is its own
/// component, and panics on a 1 × 1 image or a label map of single pixels; a flood fill has no
/// such limit.)
fn four_connected_components(labels: &[u32], w: usize, h: usize) -> Vec<u32> {
    let mut comp = vec![u32::MAX; labels.len()];
    let mut stack = Vec::new();
    let mut next = 0u32;
    for start in 0..labels.len() {
        if comp[start] != u32::MAX {
            continue;
        }
        comp[start] = next;
        stack.push(start);
        while let Some(i) = stack.pop() {
            for j in four_neighbours(i, w, h).into_iter().flatten() {
                if comp[j] == u32::MAX && labels[j] == labels[i] {
                    comp[j] = next;
                    stack.push(j);
                }
            }
        }
        next += 1;
    }
    comp
}

/// The 4-neighbours of pixel `i` of a `w × h` grid (left, right, up, down; `None` off the grid).
pub(crate) fn four_neighbours(i: usize, w: usize, h: usize) -> [Option<usize>; 4] {
    let (x, y) = (i % w, i / w);
    [
        (x > 0).then(|| i - 1),
        (x + 1 < w).then(|| i + 1),
        (y > 0).then(|| i - w),
        (y + 1 < h).then(|| i + w),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Region;
    use proptest::prelude::*;

    /// One row of the majority filter by counting each pixel's whole window: the definition
    /// [`majority_row`] is checked against.
    fn tally_majority_row(src: &[u32], w: usize, h: usize, y: usize, r: usize) -> Vec<u32> {
        (0..w)
            .map(|x| {
                let mut tally: Vec<(u32, u32)> = Vec::new();
                for yy in y.saturating_sub(r)..=(y + r).min(h - 1) {
                    for xx in x.saturating_sub(r)..=(x + r).min(w - 1) {
                        let l = src[yy * w + xx];
                        match tally.iter_mut().find(|(t, _)| *t == l) {
                            Some((_, c)) => *c += 1,
                            None => tally.push((l, 1)),
                        }
                    }
                }
                let own = src[y * w + x];
                let own_count = tally.iter().find(|(t, _)| *t == own).map_or(0, |&(_, c)| c);
                tally
                    .iter()
                    .filter(|&&(_, c)| c > own_count)
                    .max_by_key(|&&(l, c)| (c, std::cmp::Reverse(l)))
                    .map_or(own, |&(l, _)| l)
            })
            .collect()
    }

    proptest! {
        /// The sliding count gives the whole-window tally's labels, at every radius and on
        /// every edge of the image, with fewer labels than a window holds and with more (the
        /// two ways of comparing counts), and leaves its counts at zero.
        #[test]
        fn the_sliding_majority_is_the_window_majority(
            (w, h, kinds, src) in (1usize..24, 1usize..24, 1u32..40).prop_flat_map(|(w, h, kinds)| {
                let pixels = prop::collection::vec(0..kinds, w * h);
                (Just(w), Just(h), Just(kinds), pixels)
            }),
            r in 0usize..7,
        ) {
            let mut counts = vec![0u32; kinds as usize];
            let mut row = vec![0u32; w];
            for y in 0..h {
                majority_row(&src, [w, h], y, r, &mut counts, &mut row);
                prop_assert_eq!(&row, &tally_majority_row(&src, w, h, y, r));
                prop_assert!(counts.iter().all(|&c| c == 0));
            }
        }
    }

    /// Grids where every pixel is its own region (imageproc's labelling panicked on these): the
    /// small regions merge until one is big enough, whatever the shape.
    #[test]
    fn single_pixel_regions_of_tiny_grids_merge() {
        let r = |n: u32| Region {
            name: n.to_string(),
            colour: [0, 0, 0],
        };
        for (w, h) in [(1u32, 1u32), (1, 5), (5, 1), (2, 2), (3, 3)] {
            let labels: Vec<u32> = (0..w * h).collect();
            let g = LabelGrid::new(w, h, labels, (0..w * h).map(r).collect()).unwrap();
            let clean = remove_small_regions(&g, 4);
            let kept = clean.num_labels();
            assert!(
                kept >= 1 && kept <= ((w * h) as usize / 4).max(1),
                "{w}×{h}: {kept} labels"
            );
            assert_eq!(
                four_connected_components(clean.labels(), w as usize, h as usize)
                    .iter()
                    .max()
                    .map(|&m| m as usize + 1),
                Some(kept),
                "{w}×{h}: a label in two pieces"
            );
        }
    }
}
