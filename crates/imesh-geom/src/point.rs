//! Points of the plane.

use std::ops::{Add, Mul, Sub};

/// A point (or vector) of the plane with `f64` coordinates.
///
/// imesh uses image coordinates: `x` grows to the right and `y` grows downwards, and the pixel
/// `(col, row)` covers `[col, col + 1] × [row, row + 1]`. The predicates do not care: "counter-clockwise"
/// always means a positive signed area in the `(x, y)` frame.
///
/// ```
/// use imesh_geom::Point;
/// let p = Point::new(1.0, 2.0);
/// assert_eq!(p + Point::new(0.5, 0.5), Point::new(1.5, 2.5));
/// ```
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Point {
    /// Horizontal coordinate.
    pub x: f64,
    /// Vertical coordinate (downwards in image space).
    pub y: f64,
}

impl Point {
    /// The point `(x, y)`.
    pub const fn new(x: f64, y: f64) -> Self {
        Self { x, y }
    }

    /// True when both coordinates are finite (neither NaN nor infinite).
    pub fn is_finite(self) -> bool {
        self.x.is_finite() && self.y.is_finite()
    }

    /// Squared Euclidean distance to `other`.
    pub fn distance_squared(self, other: Point) -> f64 {
        let d = self - other;
        d.x * d.x + d.y * d.y
    }

    /// The midpoint of the segment from `self` to `other`.
    pub fn midpoint(self, other: Point) -> Point {
        Point::new(0.5 * (self.x + other.x), 0.5 * (self.y + other.y))
    }

    /// The centre of the pixel `(col, row)`.
    ///
    /// ```
    /// use imesh_geom::Point;
    /// assert_eq!(Point::pixel_centre(3, 0), Point::new(3.5, 0.5));
    /// ```
    pub fn pixel_centre(col: u32, row: u32) -> Point {
        Point::new(f64::from(col) + 0.5, f64::from(row) + 0.5)
    }

    /// The largest coordinate magnitude of `self` and `other`, at least 1: the scale of the
    /// rounding errors of arithmetic on them.
    pub(crate) fn magnitude_with(self, other: Point) -> f64 {
        self.x
            .abs()
            .max(self.y.abs())
            .max(other.x.abs())
            .max(other.y.abs())
            .max(1.0)
    }

    pub(crate) fn to_robust(self) -> robust::Coord<f64> {
        robust::Coord {
            x: self.x,
            y: self.y,
        }
    }
}

impl Add for Point {
    type Output = Point;
    fn add(self, rhs: Point) -> Point {
        Point::new(self.x + rhs.x, self.y + rhs.y)
    }
}

impl Sub for Point {
    type Output = Point;
    fn sub(self, rhs: Point) -> Point {
        Point::new(self.x - rhs.x, self.y - rhs.y)
    }
}

impl Mul<f64> for Point {
    type Output = Point;
    fn mul(self, rhs: f64) -> Point {
        Point::new(self.x * rhs, self.y * rhs)
    }
}

impl From<(f64, f64)> for Point {
    fn from((x, y): (f64, f64)) -> Self {
        Point::new(x, y)
    }
}
