//! Quadrilateral metrics, exactly as Verdict (≥ 1.4.4, as in VTK 9.7) computes them.
//!
//! Notation (see `shared/reference/verdict-metrics.md`): corners `P0..P3`, edges
//! `L_k = P_{k+1} − P_k`, corner products `c_k = L_{k−1} × L_k`. Verdict measures every corner
//! against the quad's own centre normal, so `α_k = sign(A) · c_k`: a quad listed clockwise scores
//! exactly like its counter-clockwise twin. Only non-convex and bow-tie quads are penalised.
//! The scale-invariant metrics work on coordinates divided by the bounding-box diagonal, which
//! only moves Verdict's tiny-value thresholds.

use crate::vec2::{cross, dot, sub};
use crate::{Point2, DBL_MAX, DBL_MIN};

/// A quadrilateral: four corners in order (either orientation).
pub type Quad = [Point2; 4];

fn clamp(q: f64) -> f64 {
    q.clamp(-DBL_MAX, DBL_MAX)
}

/// The quantities every quad metric is built from.
struct Corners {
    /// Edges `L_k`, raw.
    edges: [Point2; 4],
    /// Edges divided by the bounding-box diagonal.
    scaled: [Point2; 4],
    /// Signed corner areas `α_k`, raw.
    alpha: [f64; 4],
    /// Signed corner areas from the scaled edges.
    alpha_scaled: [f64; 4],
}

impl Corners {
    fn of(q: &Quad) -> Self {
        let edges = [
            sub(q[1], q[0]),
            sub(q[2], q[1]),
            sub(q[3], q[2]),
            sub(q[0], q[3]),
        ];
        let (mut lo, mut hi) = (q[0], q[0]);
        for p in q {
            lo = [lo[0].min(p[0]), lo[1].min(p[1])];
            hi = [hi[0].max(p[0]), hi[1].max(p[1])];
        }
        let mut h = (hi[0] - lo[0]).hypot(hi[1] - lo[1]);
        if h < DBL_MIN {
            h = 1.0;
        }
        let scaled = edges.map(|l| [l[0] / h, l[1] / h]);
        // Centre normal N_c = X1 × X2 with the principal axes X1 = L0 − L2, X2 = L1 − L3, tested on
        // raw coordinates; a vanishing one makes every corner area zero. The corner areas come from
        // the raw edges and are then divided by h² (the order matters for nearly flat corners).
        let x1 = sub(edges[0], edges[2]);
        let x2 = sub(edges[1], edges[3]);
        let nc = cross(x1, x2);
        let sign = if nc.abs() <= 2.0 * DBL_MIN {
            0.0
        } else {
            nc.signum()
        };
        let alpha = [0, 1, 2, 3].map(|k| sign * cross(edges[(k + 3) % 4], edges[k]));
        let h2 = h * h;
        Self {
            alpha_scaled: alpha.map(|a| a / h2),
            alpha,
            edges,
            scaled,
        }
    }

    fn len2(l: Point2) -> f64 {
        dot(l, l)
    }
}

/// Raw edges `L_k` and signed corner areas `α_k = sign(N_c) · c_k`: what shape, size and area
/// need, without the per-element scaling, which cancels in their ratios (the thresholds are
/// compared against the squared bounding-box diagonal, [`box_diagonal2`], instead).
#[inline]
fn edges_and_alpha(q: &Quad) -> ([Point2; 4], [f64; 4]) {
    let edges = [
        sub(q[1], q[0]),
        sub(q[2], q[1]),
        sub(q[3], q[2]),
        sub(q[0], q[3]),
    ];
    let nc = cross(sub(edges[0], edges[2]), sub(edges[1], edges[3]));
    let sign = if nc.abs() <= 2.0 * DBL_MIN {
        0.0
    } else {
        nc.signum()
    };
    let alpha = [
        sign * cross(edges[3], edges[0]),
        sign * cross(edges[0], edges[1]),
        sign * cross(edges[1], edges[2]),
        sign * cross(edges[2], edges[3]),
    ];
    (edges, alpha)
}

/// The squared diagonal of the bounding box of `q` (1 when it vanishes): Verdict's scale for
/// a tiny edge.
#[inline]
fn box_diagonal2(q: &Quad) -> f64 {
    let (xl, xh) = (
        q[0][0].min(q[1][0]).min(q[2][0].min(q[3][0])),
        q[0][0].max(q[1][0]).max(q[2][0].max(q[3][0])),
    );
    let (yl, yh) = (
        q[0][1].min(q[1][1]).min(q[2][1].min(q[3][1])),
        q[0][1].max(q[1][1]).max(q[2][1].max(q[3][1])),
    );
    let h2 = (xh - xl) * (xh - xl) + (yh - yl) * (yh - yl);
    if h2 < DBL_MIN * DBL_MIN {
        1.0
    } else {
        h2
    }
}

/// Shape from raw corner data, `h2` giving the squared bounding-box diagonal if it is needed.
#[inline]
fn shape_of(edges: &[Point2; 4], alpha: &[f64; 4], h2: impl FnOnce() -> f64) -> f64 {
    let len2 = edges.map(|l| dot(l, l));
    // Verdict calls an edge tiny against the bounding box's diagonal. A closed polygon spans at
    // most half its summed |x| steps across and half its |y| steps up, so the box is needed only
    // when an edge is that short against twice this bound (a margin over rounding).
    let (sx, sy) = (
        edges[0][0].abs() + edges[1][0].abs() + edges[2][0].abs() + edges[3][0].abs(),
        edges[0][1].abs() + edges[1][1].abs() + edges[2][1].abs() + edges[3][1].abs(),
    );
    let shortest = len2[0].min(len2[1]).min(len2[2].min(len2[3]));
    // (False for a NaN coordinate too, which then takes Verdict's own test.)
    let clear_of_the_bar = shortest > DBL_MIN * 0.5 * (sx * sx + sy * sy);
    if !clear_of_the_bar {
        let tiny = DBL_MIN * h2();
        if len2.iter().any(|&l| l <= tiny) {
            return 0.0;
        }
    }
    let mut worst = alpha[0] / (len2[0] + len2[3]);
    worst = worst.min(alpha[1] / (len2[1] + len2[0]));
    worst = worst.min(alpha[2] / (len2[2] + len2[1]));
    worst = worst.min(alpha[3] / (len2[3] + len2[2]));
    let q = 2.0 * worst;
    if q < DBL_MIN {
        0.0
    } else {
        clamp(q)
    }
}

/// Relative size squared from the Verdict area.
#[inline]
fn relative_size_of(area: f64, average_area: f64) -> f64 {
    if average_area <= DBL_MIN {
        return 0.0;
    }
    let w = average_area.sqrt();
    let r = area / (w * w);
    if r <= DBL_MIN {
        return 0.0;
    }
    let m = r.min(1.0 / r);
    clamp(m * m)
}

/// Verdict collapses a quad to the triangle `P0 P1 P2` only when `P3 == P2` exactly.
fn collapsed(q: &Quad) -> Option<[Point2; 3]> {
    (q[3] == q[2]).then_some([q[0], q[1], q[2]])
}

/// Area `¼ Σ α_k` (= |shoelace area| for a planar quad; 0 when degenerate).
///
/// ```
/// assert_eq!(imesh_quality::quad::area(&[[0.0, 0.0], [2.0, 0.0], [2.0, 1.0], [0.0, 1.0]]), 2.0);
/// ```
pub fn area(q: &Quad) -> f64 {
    let (_, alpha) = edges_and_alpha(q);
    0.25 * (alpha[0] + alpha[1] + alpha[2] + alpha[3])
}

/// Shape: `2 · min_k α_k / (|L_k|² + |L_{k−1}|²)`, i.e. 2 / the worst corner condition number.
/// 1 for a square, 0 for a non-convex or degenerate quad.
///
/// ```
/// use imesh_quality::quad::shape;
/// assert_eq!(shape(&[[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]), 1.0);
/// assert_eq!(shape(&[[0.0, 0.0], [2.0, 1.0], [0.0, 2.0], [0.5, 1.0]]), 0.0); // arrow head
/// ```
pub fn shape(q: &Quad) -> f64 {
    let (edges, alpha) = edges_and_alpha(q);
    shape_of(&edges, &alpha, || box_diagonal2(q))
}

/// Relative size squared: `min(R, 1/R)²` with `R = area / average_area`.
///
/// `average_area` is the mean area of all quads of the mesh (as `vtkMeshQuality` uses).
///
/// ```
/// use imesh_quality::quad::relative_size_squared;
/// let square = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
/// assert!((relative_size_squared(&square, 5.0 / 3.0) - 0.36).abs() < 1e-15);
/// ```
pub fn relative_size_squared(q: &Quad, average_area: f64) -> f64 {
    relative_size_of(area(q), average_area)
}

/// Shape and size: [`shape`] × [`relative_size_squared`]. The metric the paper's Table I reports.
///
/// ```
/// use imesh_quality::quad::shape_and_size;
/// let q2 = [[0.0, 1.0], [1.0, 1.0], [2.0, 3.0], [0.0, 2.0]];
/// assert!((shape_and_size(&q2, 5.0 / 3.0) - 5.0 / 12.0).abs() < 1e-15);
/// ```
pub fn shape_and_size(q: &Quad, average_area: f64) -> f64 {
    let (edges, alpha) = edges_and_alpha(q);
    let area = 0.25 * (alpha[0] + alpha[1] + alpha[2] + alpha[3]);
    shape_of(&edges, &alpha, || box_diagonal2(q)) * relative_size_of(area, average_area)
}

/// Scaled Jacobian: the minimum signed sine of the corner angles, `min_k α_k / (|L_k| |L_{k−1}|)`.
///
/// ```
/// use imesh_quality::quad::scaled_jacobian;
/// let (s, c) = (60f64.to_radians().sin(), 60f64.to_radians().cos());
/// let rhombus = [[0.0, 0.0], [1.0, 0.0], [1.0 + c, s], [c, s]];
/// assert!((scaled_jacobian(&rhombus) - s).abs() < 1e-15);
/// ```
pub fn scaled_jacobian(q: &Quad) -> f64 {
    if let Some(t) = collapsed(q) {
        return crate::tri::scaled_jacobian(&t);
    }
    let c = Corners::of(q);
    let len = c.scaled.map(|l| Corners::len2(l).sqrt());
    if len.iter().any(|&l| l < DBL_MIN) {
        return 0.0;
    }
    let q = (0..4)
        .map(|k| c.alpha_scaled[k] / (len[k] * len[(k + 3) % 4]))
        .fold(f64::INFINITY, f64::min);
    clamp(q)
}

/// Condition: `½ · max_k (|L_k|² + |L_{k−1}|²) / α_k` (1 for a square, 1e30 when a corner is flat or
/// reflex).
///
/// ```
/// use imesh_quality::quad::condition;
/// assert!((condition(&[[0.0, 0.0], [2.0, 0.0], [2.0, 1.0], [0.0, 1.0]]) - 1.25).abs() < 1e-15);
/// ```
pub fn condition(q: &Quad) -> f64 {
    if let Some(t) = collapsed(q) {
        return crate::tri::condition(&t);
    }
    let c = Corners::of(q);
    let mut worst: f64 = 0.0;
    for k in 0..4 {
        if c.alpha_scaled[k] < DBL_MIN {
            return DBL_MAX;
        }
        let n = Corners::len2(c.scaled[k]) + Corners::len2(c.scaled[(k + 3) % 4]);
        worst = worst.max(n / c.alpha_scaled[k]);
    }
    clamp(0.5 * worst)
}

/// Jacobian: the minimum signed corner area `min_k α_k`, in squared length units.
///
/// ```
/// assert_eq!(imesh_quality::quad::jacobian(&[[0.0, 0.0], [3.0, 0.0], [3.0, 3.0], [0.0, 3.0]]), 9.0);
/// ```
pub fn jacobian(q: &Quad) -> f64 {
    if let Some(t) = collapsed(q) {
        return cross(sub(t[1], t[0]), sub(t[2], t[0])).abs();
    }
    clamp(
        Corners::of(q)
            .alpha
            .iter()
            .copied()
            .fold(f64::INFINITY, f64::min),
    )
}

/// The smallest and largest unsigned interior angles in degrees, or `None` when an edge has
/// (near-)zero length.
///
/// As in Verdict, the angles are `acos` of the normalised dot product without clamping: on a nearly
/// flat corner rounding can push the argument past ±1, the angle is NaN, and the NaN-ignoring
/// min / max (C's `fmin` / `fmax`, Rust's `f64::min` / `f64::max`) skip that corner. Starting values
/// are Verdict's (360 and 0, in radians before the conversion).
fn min_max_angles(c: &Corners) -> Option<(f64, f64)> {
    let len = c.edges.map(|l| Corners::len2(l).sqrt());
    if len.iter().any(|&l| l <= DBL_MIN) {
        return None;
    }
    let (mut min, mut max) = (360.0f64, 0.0f64);
    for k in 0..4 {
        let (a, b) = (c.edges[k], c.edges[(k + 1) % 4]);
        let angle = (-dot(a, b) / (len[k] * len[(k + 1) % 4])).acos();
        min = min.min(angle);
        max = max.max(angle);
    }
    Some((
        min * 180.0 / std::f64::consts::PI,
        max * 180.0 / std::f64::consts::PI,
    ))
}

/// Minimum and maximum interior angles in degrees, in one pass: `(minimum_angle, maximum_angle)`.
///
/// ```
/// use imesh_quality::quad;
/// let q = [[0.0, 1.0], [1.0, 1.0], [2.0, 3.0], [0.0, 2.0]];
/// assert_eq!(quad::angles(&q), (quad::minimum_angle(&q), quad::maximum_angle(&q)));
/// ```
pub fn angles(q: &Quad) -> (f64, f64) {
    if let Some(t) = collapsed(q) {
        return (crate::tri::minimum_angle(&t), crate::tri::maximum_angle(&t));
    }
    let c = Corners::of(q);
    match min_max_angles(&c) {
        Some((min, max)) if c.alpha.iter().any(|&x| x < 0.0) => (min, 360.0 - max),
        Some(minmax) => minmax,
        None => (360.0, 0.0),
    }
}

/// Minimum interior angle in degrees (90 for a rectangle; 360 when an edge has zero length).
///
/// ```
/// assert_eq!(imesh_quality::quad::minimum_angle(&[[0.0, 0.0], [2.0, 0.0], [2.0, 1.0], [0.0, 1.0]]), 90.0);
/// ```
pub fn minimum_angle(q: &Quad) -> f64 {
    angles(q).0
}

/// Maximum interior angle in degrees; for a non-convex quad, the reflex angle (`360 − max`).
///
/// ```
/// let arrow = [[0.0, 0.0], [2.0, 1.0], [0.0, 2.0], [0.5, 1.0]];
/// assert!(imesh_quality::quad::maximum_angle(&arrow) > 180.0);
/// ```
pub fn maximum_angle(q: &Quad) -> f64 {
    angles(q).1
}

/// Aspect ratio: `L_max · perimeter / Σ α_k` (1 for a square).
///
/// ```
/// assert_eq!(imesh_quality::quad::aspect_ratio(&[[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]), 1.0);
/// ```
pub fn aspect_ratio(q: &Quad) -> f64 {
    let c = Corners::of(q);
    let len = c.scaled.map(|l| Corners::len2(l).sqrt());
    let max = len.iter().copied().fold(0.0, f64::max);
    let sum: f64 = len.iter().sum();
    let area4: f64 = c.alpha_scaled.iter().sum();
    clamp(max * sum / area4)
}

/// Edge ratio: longest over shortest edge (1e30 when an edge has zero length).
///
/// ```
/// assert_eq!(imesh_quality::quad::edge_ratio(&[[0.0, 0.0], [2.0, 0.0], [2.0, 1.0], [0.0, 1.0]]), 2.0);
/// ```
pub fn edge_ratio(q: &Quad) -> f64 {
    let c = Corners::of(q);
    let len2 = c.scaled.map(Corners::len2);
    let min = len2.iter().copied().fold(f64::INFINITY, f64::min);
    let max = len2.iter().copied().fold(0.0, f64::max);
    if min < DBL_MIN {
        return DBL_MAX;
    }
    clamp((max / min).sqrt())
}
