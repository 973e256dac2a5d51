//! The quality the energy is built on, and the validity of one quad.

use imesh_geom::predicates::orient2d;
use imesh_geom::Point;
use imesh_quality::quad;

/// The quality `s` the energy is built on.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Metric {
    /// Verdict's shape-and-size against the mesh's (fixed) average quad area: shape and
    /// uniform size (the paper's choice).
    #[default]
    ShapeAndSize,
    /// Verdict's shape alone: size is left free.
    Shape,
}

impl Metric {
    /// The metric's value for the quad `p` (counter-clockwise corners), `average_area` being the
    /// mesh's mean quad area.
    ///
    /// ```
    /// use imesh_geom::Point;
    /// use imesh_optim::Metric;
    /// let square = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)].map(Point::from);
    /// assert_eq!(Metric::Shape.value(&square, 4.0), 1.0);
    /// assert_eq!(Metric::ShapeAndSize.value(&square, 4.0), 1.0 / 16.0);
    /// ```
    pub fn value(self, p: &[Point; 4], average_area: f64) -> f64 {
        let q = p.map(|p| [p.x, p.y]);
        match self {
            Metric::ShapeAndSize => quad::shape_and_size(&q, average_area),
            Metric::Shape => quad::shape(&q),
        }
    }
}

/// True when the quad `p` has a positive Jacobian at all four corners (exact orientation).
#[inline]
pub fn is_valid(p: &[Point; 4]) -> bool {
    (0..4).all(|i| orient2d(p[(i + 3) % 4], p[i], p[(i + 1) % 4]) > 0.0)
}

/// The signed (shoelace) area of the quad `p`.
#[inline]
pub(crate) fn area(p: &[Point; 4]) -> f64 {
    0.5 * ((p[2].x - p[0].x) * (p[3].y - p[1].y) - (p[3].x - p[1].x) * (p[2].y - p[0].y))
}

/// Verdict's shape and the signed [`area`] of `N` quads at once, as the optimiser computes them
/// millions of times. The shape: for a counter-clockwise quad the same operations in the same
/// order as [`imesh_quality::quad::shape`], so the same bits, without the tests only a
/// degenerate or clockwise quad needs (an edge under 10⁻⁷ of the quad's size, where this gives
/// a shape under 10⁻⁷ and Verdict 0; a clockwise quad, which this scores 0 and Verdict by its
/// mirror image: the optimiser rejects both). Each lane has the same operations in the same
/// order whatever `N` (so the same bits as one by one), written over arrays of `N` so that the
/// compiler puts the lanes side by side in vector registers (its divisions become `divpd`): a
/// local solve scores several quads per trial point.
#[inline]
pub(crate) fn shapes_and_areas<const N: usize>(p: &[[Point; 4]; N]) -> ([f64; N], [f64; N]) {
    // The corners' coordinates lane by lane.
    let mut px = [[0.0; N]; 4];
    let mut py = [[0.0; N]; 4];
    for (l, quad) in p.iter().enumerate() {
        for k in 0..4 {
            px[k][l] = quad[k].x;
            py[k][l] = quad[k].y;
        }
    }
    let mut shape = [0.0; N];
    let mut area = [0.0; N];
    for l in 0..N {
        let e = |k: usize| {
            let j = (k + 1) % 4;
            (px[j][l] - px[k][l], py[j][l] - py[k][l])
        };
        let (e0, e1, e2, e3) = (e(0), e(1), e(2), e(3));
        let len2 = |v: (f64, f64)| v.0 * v.0 + v.1 * v.1;
        let (l0, l1, l2, l3) = (len2(e0), len2(e1), len2(e2), len2(e3));
        let cross = |a: (f64, f64), b: (f64, f64)| a.0 * b.1 - a.1 * b.0;
        let mut worst = cross(e3, e0) / (l0 + l3);
        worst = least(worst, cross(e0, e1) / (l1 + l0));
        worst = least(worst, cross(e1, e2) / (l2 + l1));
        worst = least(worst, cross(e2, e3) / (l3 + l2));
        let q = 2.0 * worst;
        // Verdict's floor (its DBL_MIN); false for NaN (a quad with two zero edges) too.
        shape[l] = if q >= 2.220_446_049_250_313e-15 {
            q
        } else {
            0.0
        };
        area[l] = self::area(&p[l]);
    }
    (shape, area)
}

/// Verdict's scaled Jacobian of the quad `p` (see [`imesh_quality::quad::scaled_jacobian`]).
#[inline]
pub(crate) fn verdict_jacobian(p: &[Point; 4]) -> f64 {
    quad::scaled_jacobian(&p.map(|p| [p.x, p.y]))
}

/// Under this a quick scaled Jacobian decides nothing: so thin a quad can have Verdict's centre
/// normal, and so the sign of its corners, turned by rounding.
const QUICK_JACOBIAN_FLOOR: f64 = 1e-6;

/// How far apart, relative to their size, the quick and Verdict's scaled Jacobians may be: both
/// compute `α / (|a| |b|)` at every corner with the same `α`, Verdict on coordinates divided by
/// the bounding box's diagonal, each in under ten roundings (some 10⁻¹⁵ apart).
const QUICK_JACOBIAN_SLACK: f64 = 1e-9;

/// The scaled Jacobian of a counter-clockwise quad `p` the quick way: `α / √(|a|² |b|²)` at
/// each corner on the raw coordinates, without Verdict's bounding box (a square root and
/// four divisions fewer, and no `hypot`). Equal to Verdict's up to rounding where it is at least
/// [`QUICK_JACOBIAN_FLOOR`]; NaN where a corner is not finite (a zero edge, or lengths out of
/// the floating-point range), which leaves the decision to Verdict.
#[inline]
fn quick_jacobian(p: &[Point; 4]) -> f64 {
    let e = [p[1] - p[0], p[2] - p[1], p[3] - p[2], p[0] - p[3]];
    let len2 = e.map(|v| v.x * v.x + v.y * v.y);
    let corner = [0, 1, 2, 3].map(|k| {
        let (a, b) = (e[(k + 3) % 4], e[k]);
        (a.x * b.y - a.y * b.x) / (len2[(k + 3) % 4] * len2[k]).sqrt()
    });
    if corner.iter().all(|c| c.is_finite()) {
        least(least(least(corner[0], corner[1]), corner[2]), corner[3])
    } else {
        f64::NAN
    }
}

/// Whether the quick scaled Jacobian `quick` says on which side of `bound` Verdict's is: `Some`
/// with the answer to "at least `bound`" when they are far enough apart, `None` otherwise.
#[inline]
fn quick_side(quick: f64, bound: f64) -> Option<bool> {
    let slack = QUICK_JACOBIAN_SLACK * quick.abs();
    if quick.is_nan() || quick < QUICK_JACOBIAN_FLOOR {
        None
    } else if quick > bound + slack {
        Some(true)
    } else if quick < bound - slack {
        Some(false)
    } else {
        None
    }
}

/// Whether Verdict's scaled Jacobian of the valid (counter-clockwise) quad `p` is at least
/// `bound`: the same answer as [`verdict_jacobian`], which is computed only where the quick
/// one is too close to `bound` to tell.
#[inline]
pub(crate) fn jacobian_at_least(p: &[Point; 4], bound: f64) -> bool {
    quick_side(quick_jacobian(p), bound).unwrap_or_else(|| verdict_jacobian(p) >= bound)
}

/// Verdict's scaled Jacobian of the valid (counter-clockwise) quad `p` where it is under `cap`,
/// else `cap` or Verdict's value: `min(cap, ·)` of it is `min(cap, Verdict's)` to the bit, and
/// Verdict's is computed only where the quick one cannot tell it is above `cap`.
#[inline]
pub(crate) fn jacobian_under(p: &[Point; 4], cap: f64) -> f64 {
    match quick_side(quick_jacobian(p), cap) {
        Some(true) => cap,
        _ => verdict_jacobian(p),
    }
}

/// The lesser of `a` and `b`, without `f64::min`'s care for NaN (its NaN test cost 6 % of the
/// optimiser's time). A corner is NaN only between two zero edges, which give the next corner
/// a zero cross product: the least of the four is then NaN or at most 0, and the shape's floor
/// turns either into 0, as Verdict does.
#[inline]
fn least(a: f64, b: f64) -> f64 {
    if b < a {
        b
    } else {
        a
    }
}

/// Verdict's shape at corner `k` of `p`: `2 α / (|a|² + |b|²)`, `α = a × b`, with
/// `a = p_k − p_{k−1}` and `b = p_{k+1} − p_k`; the quad's shape is the least over its corners.
#[inline]
pub(crate) fn corner_shape(p: &[Point; 4], k: usize) -> f64 {
    let (a, b) = (p[k] - p[(k + 3) % 4], p[(k + 1) % 4] - p[k]);
    2.0 * (a.x * b.y - a.y * b.x) / (a.x * a.x + a.y * a.y + b.x * b.x + b.y * b.y)
}

/// The corner of `p` with the least [`corner_shape`] (the first of equals).
#[inline]
pub(crate) fn worst_corner(p: &[Point; 4]) -> usize {
    (1..4).fold(0, |k, j| {
        if corner_shape(p, j) < corner_shape(p, k) {
            j
        } else {
            k
        }
    })
}
