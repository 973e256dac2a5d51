//! Synthetic point sets for tests, examples and benchmarks, reproducible from a seed.

use crate::Point;

/// `n` points uniformly distributed in `[0, side)²` (xorshift64, so the same seed gives the same
/// points on every machine; a zero seed is replaced by a fixed one).
///
/// ```
/// let p = imesh_geom::sample::uniform_points(3, 7, 10.0);
/// assert_eq!(p, imesh_geom::sample::uniform_points(3, 7, 10.0));
/// assert!(p.iter().all(|q| (0.0..10.0).contains(&q.x) && (0.0..10.0).contains(&q.y)));
/// ```
pub fn uniform_points(n: usize, seed: u64, side: f64) -> Vec<Point> {
    let mut s = if seed == 0 {
        0x2545_f491_4f6c_dd1d
    } else {
        seed
    };
    let mut next = move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 11) as f64 / (1u64 << 53) as f64 * side
    };
    (0..n).map(|_| Point::new(next(), next())).collect()
}

/// The centres of the pixels of a `width × height` image, row by row.
///
/// ```
/// let p = imesh_geom::sample::pixel_centres(2, 1);
/// assert_eq!(p, vec![imesh_geom::Point::new(0.5, 0.5), imesh_geom::Point::new(1.5, 0.5)]);
/// ```
pub fn pixel_centres(width: u32, height: u32) -> Vec<Point> {
    (0..height)
        .flat_map(|r| (0..width).map(move |c| Point::pixel_centre(c, r)))
        .collect()
}
