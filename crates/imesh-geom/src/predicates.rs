//! Exact geometric predicates.
//!
//! Every orientation and in-circle decision in imesh goes through this module, which wraps
//! Shewchuk's adaptive-precision predicates (the `robust` crate): the sign of each result is exact
//! for any finite input. Pixel centres are massively collinear and cocircular, so a floating-point
//! determinant that is "almost zero" would be wrong most of the time here.
//!
//! Each predicate is evaluated in up to three stages, each exact in what it returns:
//! 1. the plain floating-point determinant, returned when it exceeds Shewchuk's a-priori error bound
//!    (the sign is then certain);
//! 2. when the points lie on the dyadic lattice `2^-8 · Z²` (pixel centres, corners, midpoints — the
//!    usual case on images) and are close together, the determinant in integer arithmetic, which is
//!    exact and an order of magnitude cheaper than stage 3 on the cocircular quadruples of a pixel grid;
//! 3. otherwise Shewchuk's adaptive-precision evaluation (`robust`).

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
    let detleft = (a.x - c.x) * (b.y - c.y);
    let detright = (a.y - c.y) * (b.x - c.x);
    let det = detleft - detright;
    let bound = CCW_ERRBOUND_A * (detleft.abs() + detright.abs());
    if det > bound || -det > bound {
        return det;
    }
    match lattice_orient2d(a, b, c) {
        Some(det) => det,
        None => robust::orient2d(a.to_robust(), b.to_robust(), c.to_robust()),
    }
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
    let (adx, ady) = (a.x - d.x, a.y - d.y);
    let (bdx, bdy) = (b.x - d.x, b.y - d.y);
    let (cdx, cdy) = (c.x - d.x, c.y - d.y);
    let (bdxcdy, cdxbdy) = (bdx * cdy, cdx * bdy);
    let (cdxady, adxcdy) = (cdx * ady, adx * cdy);
    let (adxbdy, bdxady) = (adx * bdy, bdx * ady);
    let alift = adx * adx + ady * ady;
    let blift = bdx * bdx + bdy * bdy;
    let clift = cdx * cdx + cdy * cdy;
    let det = alift * (bdxcdy - cdxbdy) + blift * (cdxady - adxcdy) + clift * (adxbdy - bdxady);
    let permanent = (bdxcdy.abs() + cdxbdy.abs()) * alift
        + (cdxady.abs() + adxcdy.abs()) * blift
        + (adxbdy.abs() + bdxady.abs()) * clift;
    let bound = ICC_ERRBOUND_A * permanent;
    if det > bound || -det > bound {
        return det;
    }
    match lattice_incircle(a, b, c, d) {
        Some(det) => det,
        None => robust::incircle(a.to_robust(), b.to_robust(), c.to_robust(), d.to_robust()),
    }
}

/// Half an ulp of 1: the unit roundoff of `f64` arithmetic.
const EPS: f64 = f64::EPSILON * 0.5;
/// Shewchuk's bound on the error of the plain orientation determinant, relative to its permanent.
const CCW_ERRBOUND_A: f64 = (3.0 + 16.0 * EPS) * EPS;
/// Shewchuk's bound on the error of the plain in-circle determinant, relative to its permanent.
const ICC_ERRBOUND_A: f64 = (10.0 + 96.0 * EPS) * EPS;

/// Lattice points are multiples of `2^-LATTICE_BITS`.
const LATTICE_BITS: i32 = 8;
/// Coordinate differences (in lattice units) below this keep every integer product in range:
/// orientation terms stay below 2^61 in `i64`, in-circle terms below 2^124 in `i128`.
const LATTICE_SPAN: i64 = 1 << 30;

/// `v` in lattice units, when it is a lattice coordinate of moderate size.
#[inline]
fn lattice(v: f64) -> Option<i64> {
    let s = v * f64::from(1 << LATTICE_BITS);
    // `as` truncates toward zero inline (`trunc` is a libm call on baseline x86-64); the range
    // test first keeps the conversion exact (and rejects NaN).
    if s.abs() < 4.0e15 {
        let i = s as i64;
        (i as f64 == s).then_some(i)
    } else {
        None
    }
}

/// `p − o` in lattice units, when both are lattice points close enough together.
#[inline]
fn lattice_offset(p: Point, o: (i64, i64)) -> Option<(i64, i64)> {
    let (x, y) = (lattice(p.x)? - o.0, lattice(p.y)? - o.1);
    (x.abs() < LATTICE_SPAN && y.abs() < LATTICE_SPAN).then_some((x, y))
}

fn lattice_orient2d(a: Point, b: Point, c: Point) -> Option<f64> {
    let o = (lattice(c.x)?, lattice(c.y)?);
    let (ax, ay) = lattice_offset(a, o)?;
    let (bx, by) = lattice_offset(b, o)?;
    let det = ax * by - ay * bx;
    // Back to coordinate units: an exact power-of-two scaling, so the sign is kept.
    Some(det as f64 * f64::powi(2.0, -2 * LATTICE_BITS))
}

fn lattice_incircle(a: Point, b: Point, c: Point, d: Point) -> Option<f64> {
    let o = (lattice(d.x)?, lattice(d.y)?);
    let (ax, ay) = lattice_offset(a, o)?;
    let (bx, by) = lattice_offset(b, o)?;
    let (cx, cy) = lattice_offset(c, o)?;
    let lift = |x: i64, y: i64| i128::from(x * x + y * y);
    let cross = |px: i64, py: i64, qx: i64, qy: i64| i128::from(px * qy - qx * py);
    let det = lift(ax, ay) * cross(bx, by, cx, cy)
        + lift(bx, by) * cross(cx, cy, ax, ay)
        + lift(cx, cy) * cross(ax, ay, bx, by);
    Some(det as f64 * f64::powi(2.0, -4 * LATTICE_BITS))
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
