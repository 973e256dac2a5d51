//! Thin parts of regions pressed against the image's border.
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
    let (w, h) = (grid.width() as usize, grid.height() as usize);
    let labels = grid.labels();
    // Under a pixel every disk is its pixel alone: nothing is pinched.
    if labels.is_empty() || half_width.is_nan() || half_width < 1.0 {
        return grid.clone();
    }
    let half_width = half_width.min(MAX_SLIVER_HALF_WIDTH);
    let mut removed = pinched_by_border(labels, [w, h], half_width);
    if !removed.contains(&true) {
        return grid.clone();
    }
    keep_small_parts(&mut removed, labels, [w, h], min_pixels);
    grid.with_labels(hand_over(labels, [w, h], &removed))
}

/// The largest `half_width` [`remove_border_slivers`] uses (a larger one is taken as this): its
/// work along the border grows as the cube of the half-width.
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
        /// `2r` wide along the border is looked at.
        #[test]
        fn the_pinched_pixels_are_the_definitions((w, h, labels) in blobs(), r in 1.0f64..3.5) {
            let pinched = pinched_by_border(&labels, [w, h], r);
            for y in 0..h {
                for x in 0..w {
                    let (free, inside) = covered(&labels, w, h, r, (x, y));
                    prop_assert_eq!(pinched[y * w + x], free && !inside, "pixel ({}, {})", x, y);
                }
            }
        }

        /// Only pinched pixels change, each to a label one of its 4-neighbours ends with and
        /// that is not its own, and no label is made.
        #[test]
        fn slivers_go_to_their_neighbours((w, h, labels) in blobs(), r in 1.0f64..3.5) {
            let g = grid(w as u32, h as u32, labels.clone());
            let clean = remove_border_slivers(&g, r, 2);
            let pinched = pinched_by_border(&labels, [w, h], r);
            let name = |grid: &LabelGrid, l: u32| grid.regions()[l as usize].name.clone();
            let out: Vec<String> = clean.labels().iter().map(|&l| name(&clean, l)).collect();
            for i in 0..w * h {
                let before = name(&g, labels[i]);
                if out[i] != before {
                    prop_assert!(pinched[i]);
                    let (x, y) = (i % w, i / w);
                    prop_assert!(x.min(w - 1 - x).min(y).min(h - 1 - y) < (2.0 * r).ceil() as usize);
                    prop_assert!(four_neighbours(i, w, h).into_iter().flatten().any(|j| out[j] == out[i]));
                }
            }
        }
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
