//! Distances between points and segments, the measure of every tolerance here.

use imesh_geom::Point;

/// The parameter in `[0, 1]` of the point of the segment `ab` closest to `q` (0 for a segment of
/// no length).
///
/// ```
/// use imesh_curves::segment_parameter;
/// use imesh_geom::Point;
/// let (a, b) = (Point::new(0.0, 0.0), Point::new(4.0, 0.0));
/// assert_eq!(segment_parameter(a, b, Point::new(1.0, 3.0)), 0.25);
/// assert_eq!(segment_parameter(a, b, Point::new(-2.0, 1.0)), 0.0);
/// ```
pub fn segment_parameter(a: Point, b: Point, q: Point) -> f64 {
    let ab = b - a;
    let len2 = ab.x * ab.x + ab.y * ab.y;
    if len2 > 0.0 {
        (((q.x - a.x) * ab.x + (q.y - a.y) * ab.y) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    }
}

/// The squared distance from `q` to the closed segment `ab`.
pub fn segment_distance_squared(a: Point, b: Point, q: Point) -> f64 {
    q.distance_squared(a + (b - a) * segment_parameter(a, b, q))
}

/// The distance from `q` to the closed segment `ab`.
///
/// ```
/// use imesh_curves::segment_distance;
/// use imesh_geom::Point;
/// let (a, b) = (Point::new(0.0, 0.0), Point::new(4.0, 0.0));
/// assert_eq!(segment_distance(a, b, Point::new(1.0, 3.0)), 3.0);
/// assert_eq!(segment_distance(a, b, Point::new(7.0, 4.0)), 5.0);
/// ```
pub fn segment_distance(a: Point, b: Point, q: Point) -> f64 {
    segment_distance_squared(a, b, q).sqrt()
}
