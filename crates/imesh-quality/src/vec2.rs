//! The few 2D vector operations the metrics are written in.

use crate::Point2;

/// `a − b`.
#[inline]
pub(crate) fn sub(a: Point2, b: Point2) -> Point2 {
    [a[0] - b[0], a[1] - b[1]]
}

/// The scalar cross product `a × b`.
#[inline]
pub(crate) fn cross(a: Point2, b: Point2) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}

/// The dot product.
#[inline]
pub(crate) fn dot(a: Point2, b: Point2) -> f64 {
    a[0] * b[0] + a[1] * b[1]
}
