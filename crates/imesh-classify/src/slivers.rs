//! Thin parts of regions: pressed against the image's border ([`remove_border_slivers`]), and
//! anywhere else ([`remove_thin_parts`]). Both are read off the morphological opening of each
//! region by a disk: what no disk of one label covers is thin.
//!
//! The majority filter ([`crate::majority_filter`]) judges a pixel by the labels in its window,
//! and at the image's border that window is cut off: a strip of one label between another
//! region and the border keeps its pixels where, inside the image, a strip as thin between two
//! regions would lose them, and where a region nearly touches the border (a disc a pixel or two
//! from it) the tapering gap between them keeps its pixels down to no width at all, each
//! pixel's window seeing the wider gap above and below it. The mesh then fills that gap with
//! quads a fraction of the mean area. Here the border counts as a boundary like any other.

use crate::cleanup::four_neighbours;
use crate::LabelGrid;

/// Gives the parts of regions that are thinner than `2 · half_width` pixels only because they
/// lie against the image's border to the regions beside them.
///
/// A pixel is *covered* when a disk of radius `half_width` holding it has one label throughout
/// (the morphological opening of its region). A pixel covered while the image's outside may lie
/// in the disk, but not once the disk must stay inside the image, is in a part of its region
/// that the border pinches: a strip along the border narrower than `2 · half_width`, or the
/// gap where a region nearly touches the border. Such pixels lie within `2 · half_width` of the
/// border; each 4-connected part of them (of one label) of at least `min_pixels` pixels is
/// handed over from its rim inwards to the other labels it touches, and keeps its label if it
/// touches none. Parts thin away from the border are left to the majority filter and to the
/// thin-region merge, which judge them alike.
///
/// ```
/// use imesh_classify::{remove_border_slivers, LabelGrid, Region};
/// let r = |n: &str| Region { name: n.into(), colour: [0, 0, 0] };
/// // Label 1 fills a 12 × 12 image but for its top three rows and a strip two pixels wide
/// // along its left side, both of label 0.
/// let labels = (0..144).map(|i| u32::from(i % 12 > 1 && i / 12 >= 3)).collect();
/// let g = LabelGrid::new(12, 12, labels, vec![r("a"), r("b")]).unwrap();
/// let clean = remove_border_slivers(&g, 1.5, 9);
/// // The strip, thinner than 3 px against the border, goes to label 1; the top rows stay.
/// assert!((3..12).all(|y| clean.label(0, y) == 1 && clean.label(1, y) == 1));
/// assert!((0..12).all(|x| (0..3).all(|y| clean.label(x, y) == 0)));
/// // Inside the image, the same strip between two regions is the majority filter's to judge.
/// let labels = (0..144).map(|i| u32::from(i % 12 != 5 && i % 12 != 6)).collect();
/// let g = LabelGrid::new(12, 12, labels, vec![r("a"), r("b")]).unwrap();
/// assert_eq!(remove_border_slivers(&g, 1.5, 9).labels(), g.labels());
/// ```
pub fn remove_border_slivers(grid: &LabelGrid, half_width: f64, min_pixels: usize) -> LabelGrid {
    give_away(grid, half_width, min_pixels, pinched_by_border)
}

/// `grid` with the pixels that `thin` finds at disks of radius `half_width` (at most
/// [`MAX_SLIVER_HALF_WIDTH`]) given to the labels beside them, part by part ([`hand_over`]),
/// parts under `min_pixels` kept.
fn give_away(
    grid: &LabelGrid,
    half_width: f64,
    min_pixels: usize,
    thin: fn(&[u32], [usize; 2], f64) -> Vec<bool>,
) -> LabelGrid {
    let (w, h) = (grid.width() as usize, grid.height() as usize);
    let labels = grid.labels();
    // Under a pixel every disk is its pixel alone: nothing is thin.
    if labels.is_empty() || half_width.is_nan() || half_width < 1.0 {
        return grid.clone();
    }
    let mut removed = thin(labels, [w, h], half_width.min(MAX_SLIVER_HALF_WIDTH));
    if !removed.contains(&true) {
        return grid.clone();
    }
    keep_small_parts(&mut removed, labels, [w, h], min_pixels);
    grid.with_labels(hand_over(labels, [w, h], &removed))
}

/// The largest `half_width` [`remove_border_slivers`] and [`remove_thin_parts`] use (a larger
/// one is taken as this): the first's work along the border grows as the cube of the
/// half-width, the second's near the label changes as the square.
pub const MAX_SLIVER_HALF_WIDTH: f64 = 16.0;

/// Per pixel: whether it is covered by a disk of radius `r` of one label when the outside may
/// lie in the disk, but not when the disk must stay inside the image. The disks are centred on
/// pixel centres, those just outside the image too (where the outside may lie in the disk, only
/// its pixels in the image need one label).
fn pinched_by_border(labels: &[u32], [w, h]: [usize; 2], r: f64) -> Vec<bool> {
    let reach = r.floor() as i64;
    let disk: Vec<(i64, i64)> = (-reach..=reach)
        .flat_map(|dy| (-reach..=reach).map(move |dx| (dx, dy)))
        .filter(|&(dx, dy)| (dx * dx + dy * dy) as f64 <= r * r)
        .collect();
    let at = |x: i64, y: i64| {
        (x >= 0 && y >= 0 && (x as usize) < w && (y as usize) < h)
            .then(|| y as usize * w + x as usize)
    };
    // Per disk centre (on a grid padded by `reach` on every side), computed once: one label
    // throughout the disk's pixels in the image, and the disk wholly inside the image. A
    // centre is only asked about for a pixel its disk holds, so the disk is never all outside.
    const KNOWN: u8 = 1;
    const ONE_LABEL: u8 = 2;
    const INSIDE: u8 = 4;
    let pad = reach as usize;
    let padded_w = w + 2 * pad;
    let mut centre = vec![0u8; padded_w * (h + 2 * pad)];
    let mut status = |cx: i64, cy: i64| {
        let c = (cy + reach) as usize * padded_w + (cx + reach) as usize;
        if centre[c] == 0 {
            let (mut flags, mut label) = (KNOWN | ONE_LABEL | INSIDE, None);
            for &(dx, dy) in &disk {
                match at(cx + dx, cy + dy) {
                    None => flags &= !INSIDE,
                    Some(q) => match label {
                        None => label = Some(labels[q]),
                        Some(l) if l != labels[q] => {
                            flags = KNOWN;
                            break;
                        }
                        Some(_) => {}
                    },
                }
            }
            centre[c] = flags;
        }
        centre[c]
    };
    // A pixel covered only by disks that reach outside is within `r` of such a disk's centre,
    // which is within `r` of the outside: only the band `2r` wide along the border is looked at.
    let band = (2.0 * r).ceil() as usize;
    let mut pinched = vec![false; labels.len()];
    for y in 0..h {
        // A row inside the band's top and bottom: only its two ends.
        let ends = if y < band || y + band >= h {
            [0..w, 0..0]
        } else {
            [0..band.min(w), w.saturating_sub(band).max(band)..w]
        };
        for x in ends.into_iter().flatten() {
            let (mut any, mut inside) = (false, false);
            for &(dx, dy) in &disk {
                let s = status(x as i64 + dx, y as i64 + dy);
                any |= s & ONE_LABEL != 0;
                inside |= s & ONE_LABEL != 0 && s & INSIDE != 0;
            }
            pinched[y * w + x] = any && !inside;
        }
    }
    pinched
}

/// Gives the parts of regions thinner than `2 · half_width` pixels (strips, necks, the arms
/// between two wider parts of a region) to the regions beside them.
///
/// A pixel is *covered* when a disk of radius `half_width` holding it has one label over its
/// pixels in the image (the morphological opening of its region, the image's outside free:
/// thin parts against the border are [`remove_border_slivers`]'). Each 4-connected part of
/// uncovered pixels of one label, of at least `min_pixels` pixels, is handed over from its rim
/// inwards to the other labels it touches, and keeps its label if it touches none.
///
/// ```
/// use imesh_classify::{remove_thin_parts, LabelGrid, Region};
/// let r = |n: &str| Region { name: n.into(), colour: [0, 0, 0] };
/// // Two 6 × 6 squares of label 1 joined by an arm one pixel wide, on label 0.
/// let labels = (0..20 * 8)
///     .map(|i| {
///         let (x, y) = (i % 20, i / 20);
///         u32::from((1..7).contains(&y) && ((1..7).contains(&x) || (13..19).contains(&x) || y == 3))
///     })
///     .collect();
/// let g = LabelGrid::new(20, 8, labels, vec![r("a"), r("b")]).unwrap();
/// let clean = remove_thin_parts(&g, 1.5, 4);
/// // The arm goes to the background; the squares stay.
/// assert!((8..12).all(|x| clean.label(x, 3) == 0));
/// assert!(clean.label(3, 3) == 1 && clean.label(15, 3) == 1);
/// ```
pub fn remove_thin_parts(grid: &LabelGrid, half_width: f64, min_pixels: usize) -> LabelGrid {
    give_away(grid, half_width, min_pixels, uncovered)
}

/// Per pixel: whether no disk of radius `r` centred on a pixel centre (in the image or up to
/// `r` outside it) holds it with one label over the disk's pixels in the image.
///
/// A disk is a stack of row segments, so both steps go row by row: a centre's disk has one
/// label when each of its rows lies within one run of that label, and a pixel is covered when
/// some row of the disk around it holds such a centre close enough along that row. `O(r)` per
/// pixel rather than the disk's `O(r²)`, and a centre far from every label change
/// ([`far_from_edges`]) is one label without a look at its rows.
fn uncovered(labels: &[u32], [w, h]: [usize; 2], r: f64) -> Vec<bool> {
    use rayon::prelude::*;
    let reach = r.floor() as i64;
    // The disk's half-length in each row `dy` from its centre, `-reach..=reach`.
    let half: Vec<i64> = (-reach..=reach)
        .map(|dy| {
            let mut a = (r * r - (dy * dy) as f64).max(0.0).sqrt().floor() as i64;
            // Integer check: the float root may land a hair under an exact square.
            while (a + 1) * (a + 1) + dy * dy <= (r * r).floor() as i64 {
                a += 1;
            }
            a
        })
        .collect();
    let (wi, hi) = (w as i64, h as i64);
    // Per pixel, the last column of its row's run of its label.
    let run_end: Vec<u32> = labels
        .par_chunks(w)
        .flat_map_iter(|row| {
            let mut end = vec![0u32; row.len()];
            for x in (0..row.len()).rev() {
                end[x] = if x + 1 < row.len() && row[x + 1] == row[x] {
                    end[x + 1]
                } else {
                    x as u32
                };
            }
            end
        })
        .collect();
    // Per centre of the grid padded by `reach`: one label throughout its disk's pixels in the
    // image (and at least one such pixel).
    let padded_w = (w as i64 + 2 * reach) as usize;
    let padded_h = (h as i64 + 2 * reach) as usize;
    let far = far_from_edges(labels, [w, h], reach as u32);
    let one_label: Vec<bool> = (0..padded_w * padded_h)
        .into_par_iter()
        .map(|c| {
            let (cx, cy) = ((c % padded_w) as i64 - reach, (c / padded_w) as i64 - reach);
            if cx >= 0 && cy >= 0 && cx < wi && cy < hi && far[cy as usize * w + cx as usize] {
                return true;
            }
            let mut label = None;
            for (dy, &a) in (-reach..=reach).zip(&half) {
                let y = cy + dy;
                let (x0, x1) = ((cx - a).max(0), (cx + a).min(wi - 1));
                if y < 0 || y >= hi || x0 > x1 {
                    continue;
                }
                let i = y as usize * w + x0 as usize;
                if *label.get_or_insert(labels[i]) != labels[i] || i64::from(run_end[i]) < x1 {
                    return false;
                }
            }
            label.is_some()
        })
        .collect();
    // Per padded centre: the first one-label centre at or after it in its row (`padded_w`
    // for none).
    let next_one: Vec<u32> = one_label
        .par_chunks(padded_w)
        .flat_map_iter(|row| {
            let mut next = vec![padded_w as u32; row.len()];
            for x in (0..row.len()).rev() {
                next[x] = if row[x] {
                    x as u32
                } else if x + 1 < row.len() {
                    next[x + 1]
                } else {
                    padded_w as u32
                };
            }
            next
        })
        .collect();
    (0..w * h)
        .into_par_iter()
        .map(|i| {
            // In padded coordinates.
            let (x, y) = ((i % w) as i64 + reach, (i / w) as i64 + reach);
            !(-reach..=reach).zip(&half).any(|(dy, &a)| {
                let row = (y + dy) as usize * padded_w;
                let from = (x - a) as usize;
                i64::from(next_one[row + from]) <= x + a
            })
        })
        .collect()
}

/// Per pixel: whether no *edge* pixel (one with a 4-neighbour of another label) lies within
/// `reach` of it in both coordinates. The square of side `2 reach + 1` around such a pixel has
/// one label over its pixels in the image (two labels in it would put two 4-adjacent pixels of
/// different labels, both edge pixels, in it), and so has its disk of radius under
/// `reach + 1`: most centres far inside their regions are settled without looking at their
/// disk. The chessboard distance to the edges, by the two sequential passes of a chamfer
/// transform (capped at `reach + 1`).
fn far_from_edges(labels: &[u32], [w, h]: [usize; 2], reach: u32) -> Vec<bool> {
    use rayon::prelude::*;
    let cap = reach + 1;
    let mut d: Vec<u32> = (0..labels.len())
        .into_par_iter()
        .map(|i| {
            let edge = four_neighbours(i, w, h)
                .into_iter()
                .flatten()
                .any(|j| labels[j] != labels[i]);
            if edge {
                0
            } else {
                cap
            }
        })
        .collect();
    // Forward: the neighbours before a pixel in reading order (left, and the three above).
    for y in 0..h {
        for x in 0..w {
            let i = y * w + x;
            let mut best = d[i];
            if x > 0 {
                best = best.min(d[i - 1] + 1);
            }
            if y > 0 {
                let up = i - w;
                best = best.min(d[up] + 1);
                if x > 0 {
                    best = best.min(d[up - 1] + 1);
                }
                if x + 1 < w {
                    best = best.min(d[up + 1] + 1);
                }
            }
            d[i] = best.min(cap);
        }
    }
    // Backward: right, and the three below.
    for y in (0..h).rev() {
        for x in (0..w).rev() {
            let i = y * w + x;
            let mut best = d[i];
            if x + 1 < w {
                best = best.min(d[i + 1] + 1);
            }
            if y + 1 < h {
                let down = i + w;
                best = best.min(d[down] + 1);
                if x + 1 < w {
                    best = best.min(d[down + 1] + 1);
                }
                if x > 0 {
                    best = best.min(d[down - 1] + 1);
                }
            }
            d[i] = best.min(cap);
        }
    }
    d.into_par_iter().map(|d| d > reach).collect()
}

/// Clears the parts of `pinched` (4-connected, one label) smaller than `min_pixels`.
fn keep_small_parts(pinched: &mut [bool], labels: &[u32], [w, h]: [usize; 2], min_pixels: usize) {
    let mut seen = vec![false; labels.len()];
    let (mut stack, mut part) = (Vec::new(), Vec::new());
    for start in 0..labels.len() {
        if !pinched[start] || seen[start] {
            continue;
        }
        seen[start] = true;
        stack.push(start);
        part.clear();
        while let Some(i) = stack.pop() {
            part.push(i);
            for j in four_neighbours(i, w, h).into_iter().flatten() {
                if pinched[j] && !seen[j] && labels[j] == labels[i] {
                    seen[j] = true;
                    stack.push(j);
                }
            }
        }
        if part.len() < min_pixels {
            for &i in &part {
                pinched[i] = false;
            }
        }
    }
}

/// `labels` with every `removed` pixel given the label of the nearest pixel of another label
/// (grown from the parts' rims, through removed pixels only, 4-connected, in pixel order);
/// a part that touches no other label keeps its own.
fn hand_over(labels: &[u32], [w, h]: [usize; 2], removed: &[bool]) -> Vec<u32> {
    let mut out = labels.to_vec();
    let mut done = vec![false; labels.len()];
    let mut queue = std::collections::VecDeque::new();
    for j in (0..labels.len()).filter(|&j| removed[j]) {
        let across = four_neighbours(j, w, h)
            .into_iter()
            .flatten()
            .find(|&s| !removed[s] && labels[s] != labels[j]);
        if let Some(s) = across {
            out[j] = labels[s];
            done[j] = true;
            queue.push_back(j);
        }
    }
    while let Some(i) = queue.pop_front() {
        for j in four_neighbours(i, w, h).into_iter().flatten() {
            if removed[j] && !done[j] && labels[j] != out[i] {
                out[j] = out[i];
                done[j] = true;
                queue.push_back(j);
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Region;
    use proptest::prelude::*;

    fn grid(w: u32, h: u32, labels: Vec<u32>) -> LabelGrid {
        let kinds = labels.iter().max().map_or(1, |&m| m + 1);
        let regions = (0..kinds)
            .map(|k| Region {
                name: format!("r{k}"),
                colour: [0, 0, 0],
            })
            .collect();
        LabelGrid::new(w, h, labels, regions).expect("a valid grid")
    }

    /// The opening's definition, pixel by pixel and over the whole grid: `(free, inside)`, whether
    /// some disk of radius `r` centred on a pixel centre (in the image or up to `r` outside it),
    /// holding `p` and of one label over its pixels in the image, exists, and whether one wholly
    /// inside the image does.
    fn covered(labels: &[u32], w: usize, h: usize, r: f64, p: (usize, usize)) -> (bool, bool) {
        let (mut free, mut inside) = (false, false);
        let reach = r.floor() as i64;
        for cy in -reach..h as i64 + reach {
            for cx in -reach..w as i64 + reach {
                let (dx, dy) = (cx - p.0 as i64, cy - p.1 as i64);
                if (dx * dx + dy * dy) as f64 > r * r {
                    continue;
                }
                let mut seen = Vec::new();
                let mut within = true;
                for y in cy - reach..=cy + reach {
                    for x in cx - reach..=cx + reach {
                        if ((x - cx).pow(2) + (y - cy).pow(2)) as f64 > r * r {
                            continue;
                        }
                        if x < 0 || y < 0 || x >= w as i64 || y >= h as i64 {
                            within = false;
                        } else {
                            seen.push(labels[y as usize * w + x as usize]);
                        }
                    }
                }
                // `p` itself is in the disk, so `seen` is never empty.
                let one = seen.iter().all(|&l| l == seen[0]);
                free |= one;
                inside |= one && within;
            }
        }
        (free, inside)
    }

    fn blobs() -> impl Strategy<Value = (usize, usize, Vec<u32>)> {
        // Few labels in runs, so that regions have some width.
        (1usize..18, 1usize..18, 1u32..4).prop_flat_map(|(w, h, kinds)| {
            let cells = prop::collection::vec(0..kinds, w.div_ceil(3) * h.div_ceil(3));
            (Just(w), Just(h), cells).prop_map(|(w, h, cells)| {
                let labels = (0..w * h)
                    .map(|i| cells[(i / w / 3) * w.div_ceil(3) + (i % w) / 3])
                    .collect();
                (w, h, labels)
            })
        })
    }

    proptest! {
        /// The pinched pixels are those the opening's definition gives, though only a band
        /// `2r` wide along the border is looked at; the uncovered pixels are those no disk of
        /// the definition holds, though they are found row by row and most centres without a
        /// look at their disk.
        #[test]
        fn the_pinched_and_uncovered_pixels_are_the_definitions(
            (w, h, labels) in blobs(),
            r in 1.0f64..4.5,
        ) {
            let pinched = pinched_by_border(&labels, [w, h], r);
            let thin = uncovered(&labels, [w, h], r);
            for y in 0..h {
                for x in 0..w {
                    let (free, inside) = covered(&labels, w, h, r, (x, y));
                    prop_assert_eq!(pinched[y * w + x], free && !inside, "pixel ({}, {})", x, y);
                    prop_assert_eq!(thin[y * w + x], !free, "pixel ({}, {})", x, y);
                }
            }
        }

        /// The chamfer passes give the chessboard distance to the edge pixels: a pixel is far
        /// exactly when no edge pixel lies within `reach` in both coordinates.
        #[test]
        fn far_pixels_are_the_definitions((w, h, labels) in blobs(), reach in 0u32..5) {
            let far = far_from_edges(&labels, [w, h], reach);
            let edge = |i: usize| four_neighbours(i, w, h).into_iter().flatten().any(|j| labels[j] != labels[i]);
            for y in 0..h {
                for x in 0..w {
                    let r = reach as usize;
                    let near = (y.saturating_sub(r)..=(y + r).min(h - 1)).any(|yy| {
                        (x.saturating_sub(r)..=(x + r).min(w - 1)).any(|xx| edge(yy * w + xx))
                    });
                    prop_assert_eq!(far[y * w + x], !near, "pixel ({}, {})", x, y);
                }
            }
        }

        /// Only pinched pixels change, each to a label one of its 4-neighbours ends with and
        /// that is not its own, and no label is made; they lie in the band along the border.
        #[test]
        fn slivers_go_to_their_neighbours((w, h, labels) in blobs(), r in 1.0f64..3.5) {
            let g = grid(w as u32, h as u32, labels.clone());
            let changed = changed_where_thin(&g, &remove_border_slivers(&g, r, 2), &pinched_by_border(&labels, [w, h], r))?;
            for i in changed {
                let (x, y) = (i % w, i / w);
                prop_assert!(x.min(w - 1 - x).min(y).min(h - 1 - y) < (2.0 * r).ceil() as usize);
            }
        }
    }

    proptest! {
        /// Only uncovered pixels change, each to a label that one of its 4-neighbours ends
        /// with and that is not its own; no label is made, and a covered pixel keeps its own.
        #[test]
        fn thin_parts_go_to_their_neighbours((w, h, labels) in blobs(), r in 1.0f64..3.5) {
            let g = grid(w as u32, h as u32, labels.clone());
            changed_where_thin(&g, &remove_thin_parts(&g, r, 2), &uncovered(&labels, [w, h], r))?;
        }
    }

    /// The pixels whose region `clean` changed from `g`'s, after checking that each is `thin`
    /// and has a 4-neighbour of its new region (regions compared by name: no label is made).
    fn changed_where_thin(
        g: &LabelGrid,
        clean: &LabelGrid,
        thin: &[bool],
    ) -> Result<Vec<usize>, TestCaseError> {
        let (w, h) = (g.width() as usize, g.height() as usize);
        let name = |grid: &LabelGrid, l: u32| grid.regions()[l as usize].name.clone();
        let out: Vec<String> = clean.labels().iter().map(|&l| name(clean, l)).collect();
        let mut changed = Vec::new();
        for i in 0..w * h {
            if out[i] != name(g, g.labels()[i]) {
                prop_assert!(thin[i]);
                prop_assert!(four_neighbours(i, w, h)
                    .into_iter()
                    .flatten()
                    .any(|j| out[j] == out[i]));
                changed.push(i);
            }
        }
        Ok(changed)
    }

    /// A strip two pixels wide across a region splits it: the strip goes to the region on both
    /// sides, a strip three pixels wide stays at a radius of 1.5 px and goes at 2 px; a
    /// notch shorter than `min_pixels` stays.
    #[test]
    fn a_thin_strip_goes_and_a_wider_one_stays() {
        let strip = |width: usize| {
            let (w, h) = (24usize, 16usize);
            let labels = (0..w * h)
                .map(|i| u32::from((10..10 + width).contains(&(i % w))))
                .collect();
            grid(w as u32, h as u32, labels)
        };
        let two = remove_thin_parts(&strip(2), 1.5, 4);
        assert!((1..15).all(|y| (0..24).all(|x| two.label(x, y) == 0)));
        let three = strip(3);
        assert_eq!(remove_thin_parts(&three, 1.5, 4).labels(), three.labels());
        // Disks reaching out of the image cover the strip's ends at the border (thin parts
        // against the border are `remove_border_slivers`'); its inside goes.
        let wider = remove_thin_parts(&three, 2.0, 4);
        assert!((2..14).all(|y| (0..24).all(|x| wider.label(x, y) == 0)));
        // A stub one pixel wide and three long on a wide region: under 4 pixels, it stays.
        let (w, h) = (16usize, 16usize);
        let labels: Vec<u32> = (0..w * h)
            .map(|i| {
                let (x, y) = (i % w, i / w);
                u32::from(y >= 8 || (x == 7 && y >= 5))
            })
            .collect();
        let stub = grid(w as u32, h as u32, labels.clone());
        assert_eq!(remove_thin_parts(&stub, 1.5, 4).labels(), &labels[..]);
        let gone = remove_thin_parts(&stub, 1.5, 3);
        assert!((5..8).all(|y| gone.label(7, y) == 0));
    }

    /// A disc whose edge comes within two pixels of the image's left side: the tapering gap
    /// between them goes to the disc where it is thinner than 4 px, the rest of the background
    /// keeps its label.
    #[test]
    fn the_gap_where_a_disc_nearly_touches_the_border_goes_to_the_disc() {
        let (w, h) = (120usize, 100usize);
        let labels: Vec<u32> = (0..w * h)
            .map(|i| {
                let (x, y) = ((i % w) as f64, (i / w) as f64);
                u32::from((x - 46.5).powi(2) + (y - 50.0).powi(2) < 45.0 * 45.0)
            })
            .collect();
        assert_eq!((0..h).filter(|&y| labels[y * w + 2] == 1).count(), 13);
        assert!((0..h).all(|y| labels[y * w] == 0 && labels[y * w + 1] == 0));
        let g = grid(w as u32, h as u32, labels.clone());
        let clean = remove_border_slivers(&g, 2.0, 16);
        // At the tangent, the gap (columns 0 and 1) is the disc's now; far from it, not.
        assert!((45..56).all(|y| clean.label(0, y) == 1 && clean.label(1, y) == 1));
        assert!((0..30).all(|y| clean.label(0, y) == 0));
        // Nothing changes farther than 4 px from the border.
        for y in 0..h {
            for x in 0..w {
                if x.min(w - 1 - x).min(y).min(h - 1 - y) >= 4 {
                    assert_eq!(clean.label(x as u32, y as u32), labels[y * w + x]);
                }
            }
        }
    }

    /// A pinched part smaller than `min_pixels` stays; a longer one goes.
    #[test]
    fn a_small_pinched_part_stays() {
        // Label 1 everywhere but a strip of label 0 two rows deep along the top border, from
        // column 4 to column 3 + length.
        let strip = |length: usize| {
            let (w, h) = (16usize, 10usize);
            let labels = (0..w * h)
                .map(|i| u32::from(!((4..4 + length).contains(&(i % w)) && i / w < 2)))
                .collect();
            grid(w as u32, h as u32, labels)
        };
        let short = strip(4);
        assert!(pinched_by_border(short.labels(), [16, 10], 1.5).contains(&true));
        assert_eq!(
            remove_border_slivers(&short, 1.5, 9).labels(),
            short.labels()
        );
        let long = strip(6);
        let clean = remove_border_slivers(&long, 1.5, 9);
        assert!(clean
            .labels()
            .iter()
            .all(|&l| clean.regions()[l as usize].name == "r1"));
        // At a half-width under 1 every disk is a single pixel: nothing is ever pinched.
        assert_eq!(remove_border_slivers(&long, 0.9, 1).labels(), long.labels());
    }
}
