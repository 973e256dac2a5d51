//! Insertion orders that keep incremental Delaunay construction local.
//!
//! Inserting points along a space-filling curve makes each point land next to the previous one, so
//! the point-location walk is a few steps long and the touched triangles are hot in cache. A pure
//! curve order can still build long thin intermediate hulls (a new quadrant of the curve starts
//! beside a long straight side of the points inserted so far, and sees all of it). The biased
//! randomised insertion order (BRIO, Amenta–Choi–Rote) avoids that: a random sample of the points,
//! growing geometrically by rounds, fixes the overall shape first, and each round is sorted along the
//! curve for locality.

use crate::Point;

/// Bits per axis of the Hilbert grid (keys fit in a `u32`).
const HILBERT_BITS: u32 = 16;
/// Each BRIO round holds this many times the points of all earlier rounds together.
const BRIO_GROWTH: usize = 7;
/// Rounds smaller than this are not split any further.
const BRIO_FIRST_ROUND: usize = 64;

/// The Hilbert-curve index of the cell `(x, y)` of a `2^16 × 2^16` grid.
fn hilbert_key(mut x: u32, mut y: u32) -> u32 {
    let side = 1u32 << HILBERT_BITS;
    let mut key = 0u64;
    let mut s = side >> 1;
    while s > 0 {
        let rx = u32::from(x & s != 0);
        let ry = u32::from(y & s != 0);
        key += u64::from(s) * u64::from(s) * u64::from((3 * rx) ^ ry);
        // Rotate the sub-square so that the curve enters and leaves it where its parent expects.
        if ry == 0 {
            if rx == 1 {
                x = side - 1 - x;
                y = side - 1 - y;
            }
            std::mem::swap(&mut x, &mut y);
        }
        s >>= 1;
    }
    key as u32
}

/// Hilbert keys of all points, on a grid spanning their bounding box.
fn hilbert_keys(points: &[Point]) -> Vec<u32> {
    let (mut lo, mut hi) = (
        Point::new(f64::MAX, f64::MAX),
        Point::new(f64::MIN, f64::MIN),
    );
    for p in points {
        lo = Point::new(lo.x.min(p.x), lo.y.min(p.y));
        hi = Point::new(hi.x.max(p.x), hi.y.max(p.y));
    }
    let max_cell = f64::from((1u32 << HILBERT_BITS) - 1);
    let span = (hi.x - lo.x).max(hi.y - lo.y);
    let scale = if span > 0.0 { max_cell / span } else { 0.0 };
    points
        .iter()
        .map(|p| {
            // `as` saturates, so even a non-finite span cannot index out of the grid.
            let gx = ((p.x - lo.x) * scale) as u32;
            let gy = ((p.y - lo.y) * scale) as u32;
            hilbert_key(gx.min(max_cell as u32), gy.min(max_cell as u32))
        })
        .collect()
}

/// Sorts `indices` by Hilbert key (stable in the index for equal keys).
fn sort_by_key(indices: &mut [u32], keys: &[u32]) {
    let mut packed: Vec<u64> = indices
        .iter()
        .map(|&i| (u64::from(keys[i as usize]) << 32) | u64::from(i))
        .collect();
    packed.sort_unstable();
    for (slot, k) in indices.iter_mut().zip(packed) {
        *slot = k as u32;
    }
}

/// The indices of `points` in Hilbert-curve order.
///
/// ```
/// use imesh_geom::{spatial_sort::hilbert_order, Point};
/// let pts = [Point::new(0.0, 0.0), Point::new(9.0, 9.0), Point::new(0.0, 1.0)];
/// let order = hilbert_order(&pts);
/// assert_eq!(order.len(), 3);
/// assert_eq!(order[2], 1); // the far corner comes last on this curve
/// ```
pub fn hilbert_order(points: &[Point]) -> Vec<u32> {
    let keys = hilbert_keys(points);
    let mut order: Vec<u32> = (0..points.len() as u32).collect();
    sort_by_key(&mut order, &keys);
    order
}

/// The indices of `points` in a biased randomised insertion order (BRIO) with Hilbert-sorted
/// rounds. Deterministic: the same points always give the same order.
///
/// ```
/// use imesh_geom::{spatial_sort::brio_order, Point};
/// let pts: Vec<Point> = (0..1000).map(|i| Point::new((i % 37) as f64, (i / 37) as f64)).collect();
/// let mut order = brio_order(&pts);
/// order.sort();
/// assert_eq!(order, (0..1000).collect::<Vec<u32>>()); // a permutation
/// ```
pub fn brio_order(points: &[Point]) -> Vec<u32> {
    let keys = hilbert_keys(points);
    let mut order: Vec<u32> = (0..points.len() as u32).collect();
    shuffle(&mut order, 0x9e37_79b9_7f4a_7c15);
    let mut end = order.len();
    while end > 0 {
        let start = if end <= BRIO_FIRST_ROUND {
            0
        } else {
            end / (BRIO_GROWTH + 1)
        };
        sort_by_key(&mut order[start..end], &keys);
        end = start;
    }
    order
}

/// Fisher–Yates shuffle driven by SplitMix64 (fixed seed: the order must be reproducible).
fn shuffle(items: &mut [u32], seed: u64) {
    let mut state = seed;
    let mut next = move || {
        state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    };
    for i in (1..items.len()).rev() {
        // Multiply-shift maps a 64-bit draw onto 0..=i without a division.
        let j = ((u128::from(next()) * (i as u128 + 1)) >> 64) as usize;
        items.swap(i, j);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hilbert_keys_visit_a_grid_cell_by_adjacent_cell() {
        // On a 2^k grid aligned with the key grid, consecutive keys are 4-neighbours.
        let n = 1u32 << HILBERT_BITS;
        let step = n / 8;
        let mut cells: Vec<(u32, u32, u32)> = (0..8)
            .flat_map(|i| (0..8).map(move |j| (i, j)))
            .map(|(i, j)| (hilbert_key(i * step, j * step), i, j))
            .collect();
        cells.sort();
        for w in cells.windows(2) {
            let d = w[0].1.abs_diff(w[1].1) + w[0].2.abs_diff(w[1].2);
            assert_eq!(d, 1, "{:?} -> {:?}", w[0], w[1]);
        }
    }

    #[test]
    fn hilbert_keys_are_a_bijection_on_a_small_grid() {
        let mut keys: Vec<u32> = (0..16u32)
            .flat_map(|i| (0..16u32).map(move |j| hilbert_key(i << 12, j << 12)))
            .collect();
        keys.sort();
        keys.dedup();
        assert_eq!(keys.len(), 256);
    }

    #[test]
    fn brio_rounds_grow_geometrically_and_are_curve_sorted() {
        let pts: Vec<Point> = (0..10_000)
            .map(|i| Point::new(f64::from(i % 100), f64::from(i / 100)))
            .collect();
        let keys = hilbert_keys(&pts);
        let order = brio_order(&pts);
        // The last round holds 7/8 of the points and is sorted by key.
        let last = &order[order.len() / 8..];
        assert!(last
            .windows(2)
            .all(|w| keys[w[0] as usize] <= keys[w[1] as usize]));
        // The order is not a plain curve order: early rounds sample the whole grid.
        let first: Vec<u32> = order[..BRIO_FIRST_ROUND].to_vec();
        let spread = first.iter().map(|&i| pts[i as usize].y).fold(0.0, f64::max);
        assert!(spread > 50.0);
    }

    #[test]
    fn orders_of_degenerate_inputs() {
        assert!(hilbert_order(&[]).is_empty());
        assert_eq!(brio_order(&[Point::new(1.0, 1.0); 5]).len(), 5);
    }
}
