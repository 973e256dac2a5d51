//! Reducing a label grid: a coarser grid whose every cell takes the most frequent label of the
//! pixels it covers.

use rayon::prelude::*;

use crate::LabelGrid;

/// The label grid resampled onto `width × height` cells (each at most the grid's own size, and
/// at least 1): cell `(i, j)` covers the pixel columns `⌊i W / width⌋ ..⌊(i + 1) W / width⌋`
/// and likewise the rows, so that the cells tile the image exactly even when the sizes do not
/// divide, and it takes the label most frequent there (ties to the smaller label). Labels no
/// cell keeps are dropped and the rest renumbered in their order, as [`crate::majority_filter`]
/// does. `None` when a size is 0 or larger than the grid's.
///
/// A mode filter, not an average: a cell never gets a label that none of its pixels had, and a
/// region survives where it fills most of a cell. Meshing with quads many pixels wide, the
/// pixel-level detail of a large image only costs time and small elements.
///
/// ```
/// use imesh_classify::{reduce, LabelGrid, Region};
/// let r = |n: &str| Region { name: n.into(), colour: [0, 0, 0] };
/// // A 4 × 2 grid: a 2 × 2 block of mostly "b" on the left, all "a" on the right.
/// let g = LabelGrid::new(4, 2, vec![1, 1, 0, 0, 0, 1, 0, 0], vec![r("a"), r("b")]).unwrap();
/// let half = reduce(&g, 2, 1).unwrap();
/// assert_eq!(half.labels(), &[1, 0]);
/// // One cell: "a" covers 5 of the 8 pixels.
/// assert_eq!(reduce(&g, 1, 1).unwrap().labels(), &[0]);
/// ```
pub fn reduce(grid: &LabelGrid, width: u32, height: u32) -> Option<LabelGrid> {
    let (w, h) = (grid.width(), grid.height());
    if width == 0 || height == 0 || width > w || height > h {
        return None;
    }
    // The first pixel of cell `i` along a side of `n` pixels split into `cells`.
    let start =
        |i: u32, n: u32, cells: u32| (u64::from(i) * u64::from(n) / u64::from(cells)) as u32;
    let src = grid.labels();
    let labels: Vec<u32> = (0..height)
        .into_par_iter()
        .flat_map_iter(|j| {
            let (y0, y1) = (start(j, h, height), start(j + 1, h, height));
            // (label, count) pairs: a cell holds few labels, so a linear tally beats hashing.
            let mut tally: Vec<(u32, u32)> = Vec::new();
            (0..width)
                .map(|i| {
                    let (x0, x1) = (start(i, w, width), start(i + 1, w, width));
                    tally.clear();
                    for y in y0..y1 {
                        let row = y as usize * w as usize;
                        for &l in &src[row + x0 as usize..row + x1 as usize] {
                            match tally.iter_mut().find(|(t, _)| *t == l) {
                                Some((_, c)) => *c += 1,
                                None => tally.push((l, 1)),
                            }
                        }
                    }
                    tally
                        .iter()
                        .max_by_key(|&&(l, c)| (c, std::cmp::Reverse(l)))
                        .map_or(0, |&(l, _)| l)
                })
                .collect::<Vec<u32>>()
        })
        .collect();
    Some(grid.resized(width, height, labels))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Region;
    use proptest::prelude::*;

    fn grid(w: u32, h: u32, labels: Vec<u32>, kinds: u32) -> LabelGrid {
        let regions = (0..kinds)
            .map(|k| Region {
                name: format!("r{k}"),
                colour: [k as u8, 0, 0],
            })
            .collect();
        LabelGrid::new(w, h, labels, regions).unwrap()
    }

    #[test]
    fn sizes_out_of_range_are_refused() {
        let g = grid(3, 2, vec![0; 6], 1);
        assert!(reduce(&g, 0, 1).is_none());
        assert!(reduce(&g, 4, 2).is_none());
        assert!(reduce(&g, 3, 3).is_none());
        assert_eq!(reduce(&g, 3, 2).unwrap(), g);
    }

    #[test]
    fn a_label_no_cell_keeps_is_dropped_and_names_follow() {
        // A speck of "r1" in "r0" above two rows of "r2".
        let mut labels = vec![0; 16];
        labels[5] = 1;
        labels[8..16].copy_from_slice(&[2; 8]);
        let g = grid(4, 4, labels, 3);
        let r = reduce(&g, 2, 2).unwrap();
        let names: Vec<&str> = r.regions().iter().map(|x| x.name.as_str()).collect();
        assert_eq!(names, ["r0", "r2"]);
        assert_eq!(r.labels(), &[0, 0, 1, 1]);
    }

    #[test]
    fn a_tie_goes_to_the_smaller_label() {
        let g = grid(2, 1, vec![1, 0], 2);
        assert_eq!(reduce(&g, 1, 1).unwrap().regions()[0].name, "r0");
        let g = grid(3, 1, vec![1, 0, 1], 2);
        assert_eq!(reduce(&g, 1, 1).unwrap().regions()[0].name, "r1");
    }

    proptest! {
        /// Every cell's label is one of the most frequent among the pixels it covers, the cells
        /// cover every pixel exactly once, and names survive the renumbering.
        #[test]
        fn each_cell_takes_its_pixels_mode(
            w in 1u32..24, h in 1u32..24, fw in 1u32..24, fh in 1u32..24, seed in any::<u64>(),
        ) {
            let (cw, ch) = (fw.min(w), fh.min(h));
            let mut s = seed | 1;
            let labels: Vec<u32> = (0..w * h)
                .map(|_| {
                    s ^= s << 13;
                    s ^= s >> 7;
                    s ^= s << 17;
                    (s % 4) as u32
                })
                .collect();
            let g = grid(w, h, labels, 4);
            let r = reduce(&g, cw, ch).unwrap();
            prop_assert_eq!((r.width(), r.height()), (cw, ch));
            let mut covered = vec![0u32; (w * h) as usize];
            for j in 0..ch {
                for i in 0..cw {
                    let mut counts = [0u32; 4];
                    for y in j * h / ch..(j + 1) * h / ch {
                        for x in i * w / cw..(i + 1) * w / cw {
                            counts[g.label(x, y) as usize] += 1;
                            covered[(y * w + x) as usize] += 1;
                        }
                    }
                    let name = &r.regions()[r.label(i, j) as usize].name;
                    let kept: usize = name[1..].parse().unwrap();
                    prop_assert_eq!(counts[kept], *counts.iter().max().unwrap());
                }
            }
            prop_assert!(covered.iter().all(|&c| c == 1));
        }
    }
}
