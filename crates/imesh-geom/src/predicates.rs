//! Exact geometric predicates.
//!
//! Every orientation and in-circle decision in imesh goes through this module, which wraps
//! Shewchuk's adaptive-precision predicates (the `robust` crate): the sign of each result is exact
//! for any finite input. Pixel centres are massively collinear and cocircular, so a floating-point
//! determinant that is "almost zero" would be wrong most of the time here.

use crate::Point;

/// Twice the signed area of the triangle `a b c`, with an exact sign.
///
/// Positive when `a b c` turn counter-clockwise (`c` left of the directed line `a → b`), negative
/// when clockwise, exactly zero when collinear. Only the sign is exact; the magnitude is an
/// approximation.
///
/// ```
/// use imesh_geom::{predicates::orient2d, Point};
/// let (a, b) = (Point::new(0.0, 0.0), Point::new(1.0, 0.0));
/// assert!(orient2d(a, b, Point::new(0.5, 1.0)) > 0.0);
/// assert_eq!(orient2d(a, b, Point::new(3.0, 0.0)), 0.0);
/// ```
#[inline]
pub fn orient2d(a: Point, b: Point, c: Point) -> f64 {
    robust::orient2d(a.to_robust(), b.to_robust(), c.to_robust())
}

/// In-circle test with an exact sign.
///
/// For `a b c` counter-clockwise: positive when `d` lies strictly inside their circumcircle,
/// negative when strictly outside, zero when the four points are cocircular. (For `a b c` clockwise
/// the sign flips.)
///
/// ```
/// use imesh_geom::{predicates::incircle, Point};
/// let (a, b, c) = (Point::new(0.0, 0.0), Point::new(1.0, 0.0), Point::new(1.0, 1.0));
/// assert!(incircle(a, b, c, Point::new(0.5, 0.5)) > 0.0);
/// assert_eq!(incircle(a, b, c, Point::new(0.0, 1.0)), 0.0); // the square's fourth corner
/// ```
#[inline]
pub fn incircle(a: Point, b: Point, c: Point, d: Point) -> f64 {
    robust::incircle(a.to_robust(), b.to_robust(), c.to_robust(), d.to_robust())
}

/// The turn made by three points.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Orientation {
    /// Positive signed area.
    CounterClockwise,
    /// Negative signed area.
    Clockwise,
    /// Zero signed area (including coincident points).
    Collinear,
}

/// The exact orientation of `a b c`.
///
/// ```
/// use imesh_geom::{predicates::{orientation, Orientation}, Point};
/// let o = orientation(Point::new(0.0, 0.0), Point::new(1.0, 0.0), Point::new(1.0, -1.0));
/// assert_eq!(o, Orientation::Clockwise);
/// ```
pub fn orientation(a: Point, b: Point, c: Point) -> Orientation {
    let d = orient2d(a, b, c);
    if d > 0.0 {
        Orientation::CounterClockwise
    } else if d < 0.0 {
        Orientation::Clockwise
    } else {
        Orientation::Collinear
    }
}

/// For `p` known to be collinear with `a` and `b`: true when `p` lies strictly between them.
///
/// Exact, because on a common line the order of the points is the order of one coordinate.
///
/// ```
/// use imesh_geom::{predicates::strictly_between, Point};
/// let (a, b) = (Point::new(0.0, 0.0), Point::new(2.0, 2.0));
/// assert!(strictly_between(a, b, Point::new(1.0, 1.0)));
/// assert!(!strictly_between(a, b, b));
/// ```
#[inline]
pub fn strictly_between(a: Point, b: Point, p: Point) -> bool {
    if a.x != b.x {
        (a.x < p.x && p.x < b.x) || (b.x < p.x && p.x < a.x)
    } else {
        (a.y < p.y && p.y < b.y) || (b.y < p.y && p.y < a.y)
    }
}
