//! The Jacobian of the 9-node (biquadratic) quadrilateral, bounded over the whole element.
//!
//! A second-order quad whose sides follow curved boundaries is valid only if the Jacobian
//! determinant of its map from the unit square stays positive everywhere, not only at its
//! corners. For the biquadratic map that determinant is a polynomial of degree 3 in each
//! parameter; written in the tensor Bernstein basis of that degree, its 16 coefficients bound
//! it (the basis is non-negative and sums to one), equal it at the four corners, and average
//! to the element's area. So a positive smallest coefficient proves the element valid, with no
//! sampling (the approach of Johnen, Remacle and Geuzaine for Gmsh's high-order meshes).

use crate::vec2::{cross, sub};
use crate::Point2;

/// The nodes of a 9-node quad in Gmsh's and VTK's order: the four corners, the middles of the
/// sides from corner 0 to 1, 1 to 2, 2 to 3 and 3 to 0, then the centre.
pub type Quad9 = [Point2; 9];

/// The 16 Bernstein coefficients of the Jacobian determinant of `q`'s biquadratic map from the
/// unit square (corner 0 at (0, 0), corner 1 at (1, 0), corner 3 at (0, 1)), row by row along
/// the first parameter; positive for a counter-clockwise element (by the sign of
/// [`crate::signed_area`]).
///
/// ```
/// use imesh_quality::curved::jacobian_coefficients;
/// // A 2 × 1 rectangle with its middle nodes halfway: the determinant is the constant 2.
/// let q = [[0.0, 0.0], [2.0, 0.0], [2.0, 1.0], [0.0, 1.0],
///          [1.0, 0.0], [2.0, 0.5], [1.0, 1.0], [0.0, 0.5], [1.0, 0.5]];
/// assert!(jacobian_coefficients(&q).iter().all(|&c| (c - 2.0).abs() < 1e-12));
/// ```
pub fn jacobian_coefficients(q: &Quad9) -> [f64; 16] {
    let p = control_points(q);
    // The first derivatives' Bézier coefficients: along u of degree (1, 2), along v (2, 1).
    let du = |i: usize, j: usize| scale(sub(p[i + 1][j], p[i][j]), 2.0);
    let dv = |i: usize, j: usize| scale(sub(p[i][j + 1], p[i][j]), 2.0);
    // B¹ᵢ · B²ₖ = C(1, i) C(2, k) / C(3, i + k) · B³ᵢ₊ₖ, in each parameter.
    const C1: [f64; 2] = [1.0, 1.0];
    const C2: [f64; 3] = [1.0, 2.0, 1.0];
    const C3: [f64; 4] = [1.0, 3.0, 3.0, 1.0];
    let mut c = [0.0; 16];
    for (i, &a) in C1.iter().enumerate() {
        for (k, &b) in C2.iter().enumerate() {
            for (j, &d) in C2.iter().enumerate() {
                for (l, &e) in C1.iter().enumerate() {
                    let (s, t) = (i + k, j + l);
                    let w = a * b / C3[s] * d * e / C3[t];
                    c[4 * t + s] += w * cross(du(i, j), dv(k, l));
                }
            }
        }
    }
    c
}

/// The smallest and largest values the Jacobian determinant of `q` can take: bounds from its
/// Bernstein coefficients ([`jacobian_coefficients`]), exact at the corners. A positive lower
/// bound proves a counter-clockwise element valid everywhere.
///
/// ```
/// use imesh_quality::curved::jacobian_bounds;
/// // The unit square with its bottom side bulging out by 0.2 at its middle node.
/// let q = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0],
///          [0.5, -0.2], [1.0, 0.5], [0.5, 1.0], [0.0, 0.5], [0.5, 0.4]];
/// let [lo, hi] = jacobian_bounds(&q);
/// assert!(lo > 0.0 && hi > 1.0);
/// ```
pub fn jacobian_bounds(q: &Quad9) -> [f64; 2] {
    jacobian_coefficients(q)
        .iter()
        .fold([f64::INFINITY, f64::NEG_INFINITY], |[lo, hi], &c| {
            [lo.min(c), hi.max(c)]
        })
}

/// Whether the Jacobian determinant of `q` is at least `target` everywhere in the element, to
/// a subdivision depth: where the Bernstein coefficients do not settle it (some under `target`,
/// every corner value above it), the square is halved both ways (de Casteljau) and each quarter
/// tried again with its own, tighter coefficients, at most [`SUBDIVISIONS`] times. `true`
/// proves it; `false` means a value under `target` was found at a corner of some quarter, or the
/// depth ran out (so the answer errs on the side of refusing).
///
/// ```
/// use imesh_quality::curved::{jacobian_at_least, jacobian_bounds};
/// // The bottom side bent 0.2 inwards: its smallest value is 0.6, which the coefficients alone
/// // (0.467 at the least) cannot show to clear 0.5, and the quarters do.
/// let q = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0],
///          [0.5, 0.2], [1.0, 0.5], [0.5, 1.0], [0.0, 0.5], [0.5, 0.55]];
/// assert!(jacobian_bounds(&q)[0] < 0.5);
/// assert!(jacobian_at_least(&q, 0.5));
/// assert!(!jacobian_at_least(&q, 0.9));
/// ```
pub fn jacobian_at_least(q: &Quad9, target: f64) -> bool {
    at_least(&jacobian_coefficients(q), target, SUBDIVISIONS)
}

/// Most halvings [`jacobian_at_least`] makes of the unit square before it refuses.
pub const SUBDIVISIONS: u32 = 4;

fn at_least(c: &[f64; 16], target: f64, depth: u32) -> bool {
    if c.iter().all(|&x| x >= target) {
        return true;
    }
    // The corner coefficients are the determinant's values there.
    if [c[0], c[3], c[12], c[15]].iter().any(|&x| x < target) || depth == 0 {
        return false;
    }
    quarters(c)
        .iter()
        .all(|quarter| at_least(quarter, target, depth - 1))
}

/// The coefficients of the four quarters of the square (u and v each halved), by de
/// Casteljau's split at ½ along each parameter.
fn quarters(c: &[f64; 16]) -> [[f64; 16]; 4] {
    let split = |a: [f64; 4]| {
        let (b0, b1, b2) = (
            (a[0] + a[1]) / 2.0,
            (a[1] + a[2]) / 2.0,
            (a[2] + a[3]) / 2.0,
        );
        let (c0, c1) = ((b0 + b1) / 2.0, (b1 + b2) / 2.0);
        let d = (c0 + c1) / 2.0;
        ([a[0], b0, c0, d], [d, c1, b2, a[3]])
    };
    let mut out = [[0.0; 16]; 4];
    // Along u (index s) in every row t, then along v in every column.
    let mut halves = [[0.0; 16]; 2];
    for t in 0..4 {
        let (lo, hi) = split([c[4 * t], c[4 * t + 1], c[4 * t + 2], c[4 * t + 3]]);
        halves[0][4 * t..4 * t + 4].copy_from_slice(&lo);
        halves[1][4 * t..4 * t + 4].copy_from_slice(&hi);
    }
    for (h, half) in halves.iter().enumerate() {
        for s in 0..4 {
            let (lo, hi) = split([half[s], half[4 + s], half[8 + s], half[12 + s]]);
            for t in 0..4 {
                out[h][4 * t + s] = lo[t];
                out[2 + h][4 * t + s] = hi[t];
            }
        }
    }
    out
}

/// Whether the Jacobian determinant of `q` stays at least `share` of the smallest corner value
/// of the straight (bilinear) quad of the same corners, everywhere ([`jacobian_at_least`]): how
/// far its bent sides may bend it.
///
/// ```
/// use imesh_quality::curved::keeps_share_of_straight;
/// // The unit square, its bottom side bent 0.2 inwards (smallest determinant 0.6).
/// let q = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0],
///          [0.5, 0.2], [1.0, 0.5], [0.5, 1.0], [0.0, 0.5], [0.5, 0.55]];
/// assert!(keeps_share_of_straight(&q, 0.5));
/// assert!(!keeps_share_of_straight(&q, 0.7));
/// ```
pub fn keeps_share_of_straight(q: &Quad9, share: f64) -> bool {
    let [a, b, c, d] = [q[0], q[1], q[2], q[3]];
    let straight = [
        cross(sub(b, a), sub(d, a)),
        cross(sub(b, a), sub(c, b)),
        cross(sub(c, d), sub(d, a)),
        cross(sub(c, d), sub(c, b)),
    ]
    .into_iter()
    .fold(f64::INFINITY, f64::min);
    jacobian_at_least(q, share * straight)
}

/// The area `q` covers: the integral of its Jacobian determinant over the unit square, the
/// mean of its Bernstein coefficients (each basis function integrates to 1/16).
///
/// ```
/// use imesh_quality::curved::area;
/// // The bottom side a parabola bulging 0.2 out at its middle node: 2/3 · 0.2 more area.
/// let q = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0],
///          [0.5, -0.2], [1.0, 0.5], [0.5, 1.0], [0.0, 0.5], [0.5, 0.4]];
/// assert!((area(&q) - (1.0 + 0.2 * 2.0 / 3.0)).abs() < 1e-12);
/// ```
pub fn area(q: &Quad9) -> f64 {
    jacobian_coefficients(q).iter().sum::<f64>() / 16.0
}

/// The centre node that makes the 9-node quad the 8-node serendipity quad of the same corners
/// and middles: half the middles' sum less a quarter of the corners'. With straight sides it is
/// the bilinear quad's centre, so the element is the bilinear one.
///
/// ```
/// use imesh_quality::curved::serendipity_centre;
/// let corners = [[0.0, 0.0], [2.0, 0.0], [3.0, 2.0], [0.0, 1.0]];
/// let middles = [[1.0, 0.0], [2.5, 1.0], [1.5, 1.5], [0.0, 0.5]];
/// assert_eq!(serendipity_centre(&corners, &middles), [1.25, 0.75]);
/// ```
pub fn serendipity_centre(corners: &[Point2; 4], middles: &[Point2; 4]) -> Point2 {
    let sum = |p: &[Point2; 4]| [0, 1].map(|k| p.iter().map(|x| x[k]).sum::<f64>());
    let (c, m) = (sum(corners), sum(middles));
    [0.5 * m[0] - 0.25 * c[0], 0.5 * m[1] - 0.25 * c[1]]
}

/// The tensor Bézier control points `p[i][j]` (i along u, j along v) of `q`'s biquadratic map:
/// the corners as they are, a side's middle control point `2 m − (a + b) / 2`, and the centre's
/// from the centre node, which the map takes through weights ¼, ½, ¼ in each parameter.
fn control_points(q: &Quad9) -> [[Point2; 3]; 3] {
    let mid = |m: Point2, a: Point2, b: Point2| {
        [
            2.0 * m[0] - 0.5 * (a[0] + b[0]),
            2.0 * m[1] - 0.5 * (a[1] + b[1]),
        ]
    };
    let mut p = [[[0.0; 2]; 3]; 3];
    p[0][0] = q[0];
    p[2][0] = q[1];
    p[2][2] = q[2];
    p[0][2] = q[3];
    p[1][0] = mid(q[4], q[0], q[1]);
    p[2][1] = mid(q[5], q[1], q[2]);
    p[1][2] = mid(q[6], q[2], q[3]);
    p[0][1] = mid(q[7], q[3], q[0]);
    const W: [f64; 3] = [0.25, 0.5, 0.25];
    let mut rest = [0.0; 2];
    for (i, row) in p.iter().enumerate() {
        for (j, x) in row.iter().enumerate() {
            if (i, j) != (1, 1) {
                rest[0] += W[i] * W[j] * x[0];
                rest[1] += W[i] * W[j] * x[1];
            }
        }
    }
    p[1][1] = [4.0 * (q[8][0] - rest[0]), 4.0 * (q[8][1] - rest[1])];
    p
}

fn scale(a: Point2, s: f64) -> Point2 {
    [a[0] * s, a[1] * s]
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// The biquadratic map of `q` at (u, v), from its nodes' Lagrange basis.
    fn map(q: &Quad9, u: f64, v: f64) -> Point2 {
        let l = |t: f64| {
            [
                (1.0 - t) * (1.0 - 2.0 * t),
                4.0 * t * (1.0 - t),
                t * (2.0 * t - 1.0),
            ]
        };
        let (a, b) = (l(u), l(v));
        // Node of each (i, j) grid position (0, ½, 1 along u and v).
        let node = [[0, 7, 3], [4, 8, 6], [1, 5, 2]];
        let mut p = [0.0; 2];
        for i in 0..3 {
            for j in 0..3 {
                let x = q[node[i][j]];
                p[0] += a[i] * b[j] * x[0];
                p[1] += a[i] * b[j] * x[1];
            }
        }
        p
    }

    /// The Jacobian determinant at (u, v) by central differences of [`map`].
    fn jacobian_at(q: &Quad9, u: f64, v: f64) -> f64 {
        let h = 1e-6;
        let d = |a: Point2, b: Point2| [(a[0] - b[0]) / (2.0 * h), (a[1] - b[1]) / (2.0 * h)];
        let xu = d(map(q, u + h, v), map(q, u - h, v));
        let xv = d(map(q, u, v + h), map(q, u, v - h));
        cross(xu, xv)
    }

    /// The determinant from the coefficients at (u, v).
    fn bernstein_at(c: &[f64; 16], u: f64, v: f64) -> f64 {
        let b = |t: f64| {
            let s = 1.0 - t;
            [s * s * s, 3.0 * t * s * s, 3.0 * t * t * s, t * t * t]
        };
        let (a, e) = (b(u), b(v));
        (0..16).map(|k| c[k] * a[k % 4] * e[k / 4]).sum()
    }

    /// The unit square with its middle nodes halfway and its centre in the middle.
    const UNIT_SQUARE: Quad9 = [
        [0.0, 0.0],
        [1.0, 0.0],
        [1.0, 1.0],
        [0.0, 1.0],
        [0.5, 0.0],
        [1.0, 0.5],
        [0.5, 1.0],
        [0.0, 0.5],
        [0.5, 0.5],
    ];

    fn jittered_quad() -> impl Strategy<Value = Quad9> {
        proptest::array::uniform9(proptest::array::uniform2(-0.2f64..0.2)).prop_map(|d| {
            let mut q = UNIT_SQUARE;
            for (p, d) in q.iter_mut().zip(d) {
                p[0] += d[0];
                p[1] += d[1];
            }
            q
        })
    }

    proptest! {
        /// The coefficients are the determinant: the Bernstein form agrees with finite
        /// differences of the Lagrange map everywhere, the corner coefficients are the corner
        /// values, and every sampled value lies within the bounds.
        #[test]
        fn coefficients_are_the_jacobian_of_the_map(q in jittered_quad()) {
            let c = jacobian_coefficients(&q);
            let [lo, hi] = jacobian_bounds(&q);
            for i in 0..=8 {
                for j in 0..=8 {
                    let (u, v) = (i as f64 / 8.0, j as f64 / 8.0);
                    let (u, v) = (u.clamp(1e-5, 1.0 - 1e-5), v.clamp(1e-5, 1.0 - 1e-5));
                    let exact = bernstein_at(&c, u, v);
                    prop_assert!((exact - jacobian_at(&q, u, v)).abs() < 1e-6);
                    prop_assert!(lo - 1e-12 <= exact && exact <= hi + 1e-12);
                }
            }
            for (k, (u, v)) in [(0, (0.0, 0.0)), (3, (1.0, 0.0)), (12, (0.0, 1.0)), (15, (1.0, 1.0))] {
                prop_assert!((c[k] - bernstein_at(&c, u, v)).abs() < 1e-12);
            }
        }

        /// The area is the integral of the determinant: a 6 × 6 Gauss rule (exact for degree
        /// 11) gives the same.
        #[test]
        fn area_is_the_integral_of_the_jacobian(q in jittered_quad()) {
            let (x, w) = gauss6();
            let c = jacobian_coefficients(&q);
            let mut integral = 0.0;
            for i in 0..6 {
                for j in 0..6 {
                    integral += w[i] * w[j] * bernstein_at(&c, x[i], x[j]);
                }
            }
            prop_assert!((integral - area(&q)).abs() < 1e-12);
        }

        /// With straight sides and the serendipity centre the element is the bilinear quad: its
        /// area is the corners' polygon area and its bounds the corner Jacobians'.
        #[test]
        fn straight_sides_give_the_bilinear_quad(q in jittered_quad()) {
            let corners = [q[0], q[1], q[2], q[3]];
            let half = |a: Point2, b: Point2| [(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0];
            let middles = [0, 1, 2, 3].map(|k| half(corners[k], corners[(k + 1) % 4]));
            let centre = serendipity_centre(&corners, &middles);
            let mut s = q;
            s[4..8].copy_from_slice(&middles);
            s[8] = centre;
            let polygon = crate::signed_area(&corners);
            prop_assert!((area(&s) - polygon).abs() < 1e-12);
            let [a, b, c, d] = corners;
            let corner_jacobians = [
                cross(sub(b, a), sub(d, a)),
                cross(sub(b, a), sub(c, b)),
                cross(sub(c, d), sub(d, a)),
                cross(sub(c, d), sub(c, b)),
            ];
            let [lo, _] = jacobian_bounds(&s);
            let smallest = corner_jacobians.iter().copied().fold(f64::INFINITY, f64::min);
            prop_assert!((lo - smallest).abs() < 1e-9, "{lo} {smallest}");
        }
    }

    proptest! {
        /// Each quarter's coefficients are the determinant over that quarter: evaluated at a
        /// point of the quarter (rescaled), they give the whole square's value there.
        #[test]
        fn quarters_are_the_determinant_on_each_quarter(q in jittered_quad(), u in 0.0f64..1.0, v in 0.0f64..1.0) {
            let c = jacobian_coefficients(&q);
            let parts = quarters(&c);
            for (k, (du, dv)) in [(0.0, 0.0), (0.5, 0.0), (0.0, 0.5), (0.5, 0.5)].into_iter().enumerate() {
                let (x, y) = (du + u / 2.0, dv + v / 2.0);
                prop_assert!((bernstein_at(&parts[k], u, v) - bernstein_at(&c, x, y)).abs() < 1e-12);
            }
        }

        /// A sampled value under the target is never passed, and a target under every
        /// coefficient always is.
        #[test]
        fn at_least_never_passes_a_sampled_value_under_it(q in jittered_quad()) {
            let c = jacobian_coefficients(&q);
            let mut smallest = f64::INFINITY;
            for i in 0..=16 {
                for j in 0..=16 {
                    smallest = smallest.min(bernstein_at(&c, i as f64 / 16.0, j as f64 / 16.0));
                }
            }
            prop_assert!(!jacobian_at_least(&q, smallest + 1e-9));
            prop_assert!(jacobian_at_least(&q, jacobian_bounds(&q)[0]));
        }
    }

    /// A side pushed across the element inverts it: the lower bound goes negative.
    #[test]
    fn a_side_bent_across_the_element_is_caught() {
        let mut q = UNIT_SQUARE;
        assert!(jacobian_bounds(&q)[0] > 0.0);
        q[4] = [0.5, 0.9];
        assert!(jacobian_bounds(&q)[0] < 0.0);
    }

    /// Gauss–Legendre points and weights of order 6 on [0, 1].
    fn gauss6() -> ([f64; 6], [f64; 6]) {
        let x = [
            0.238_619_186_083_196_9,
            0.661_209_386_466_264_5,
            0.932_469_514_203_152,
        ];
        let w = [
            0.467_913_934_572_691,
            0.360_761_573_048_138_6,
            0.171_324_492_379_170_3,
        ];
        let mut p = [0.0; 6];
        let mut v = [0.0; 6];
        for k in 0..3 {
            p[2 * k] = 0.5 - 0.5 * x[k];
            p[2 * k + 1] = 0.5 + 0.5 * x[k];
            v[2 * k] = 0.5 * w[k];
            v[2 * k + 1] = 0.5 * w[k];
        }
        (p, v)
    }
}
