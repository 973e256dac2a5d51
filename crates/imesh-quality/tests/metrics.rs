//! Known values and invariances of the quality metrics.

use imesh_quality::{quad, tri, Histogram, QuadQuality, Statistics};
use proptest::prelude::*;

const SQUARE: quad::Quad = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
const ARROW: quad::Quad = [[0.0, 0.0], [2.0, 1.0], [0.0, 2.0], [0.5, 1.0]];

#[test]
fn unit_square_is_perfect() {
    assert_eq!(quad::shape(&SQUARE), 1.0);
    assert_eq!(quad::scaled_jacobian(&SQUARE), 1.0);
    assert_eq!(quad::condition(&SQUARE), 1.0);
    assert_eq!(quad::shape_and_size(&SQUARE, 1.0), 1.0);
    assert_eq!(
        (quad::minimum_angle(&SQUARE), quad::maximum_angle(&SQUARE)),
        (90.0, 90.0)
    );
    assert_eq!(quad::aspect_ratio(&SQUARE), 1.0);
}

#[test]
fn rhombus_of_sixty_degrees() {
    let (s, c) = (60f64.to_radians().sin(), 60f64.to_radians().cos());
    let r = [[0.0, 0.0], [1.0, 0.0], [1.0 + c, s], [c, s]];
    assert!((quad::scaled_jacobian(&r) - s).abs() < 1e-15);
    // Shape of a rhombus: 2 sin θ / 2 = sin θ as well (equal edges at every corner).
    assert!((quad::shape(&r) - s).abs() < 1e-15);
    assert!((quad::minimum_angle(&r) - 60.0).abs() < 1e-12);
    assert!((quad::maximum_angle(&r) - 120.0).abs() < 1e-12);
}

#[test]
fn arrow_head_is_penalised() {
    assert!(quad::scaled_jacobian(&ARROW) < 0.0);
    assert_eq!(quad::shape(&ARROW), 0.0);
    assert_eq!(quad::shape_and_size(&ARROW, 1.0), 0.0);
    assert_eq!(quad::condition(&ARROW), imesh_quality::DBL_MAX);
    assert!(quad::maximum_angle(&ARROW) > 180.0);
}

#[test]
fn verdict_is_orientation_blind() {
    let q = [[0.0, 1.0], [1.0, 1.0], [2.0, 3.0], [0.0, 2.0]];
    let cw = [q[0], q[3], q[2], q[1]];
    for f in [
        quad::shape,
        quad::scaled_jacobian,
        quad::condition,
        quad::minimum_angle,
        quad::maximum_angle,
        quad::area,
    ] {
        assert!((f(&q) - f(&cw)).abs() < 1e-15);
    }
    let t = [[0.0, 0.0], [3.0, 0.5], [1.0, 2.0]];
    let t_cw = [t[0], t[2], t[1]];
    for f in [
        tri::shape,
        tri::scaled_jacobian,
        tri::minimum_angle,
        tri::maximum_angle,
        tri::aspect_ratio,
    ] {
        assert!((f(&t) - f(&t_cw)).abs() < 1e-15);
    }
}

#[test]
fn the_reference_documents_three_quad_cross_check() {
    // shared/reference/verdict-metrics.md: Q0 unit square, Q1 2 × 1, Q2 general; Ā = 5/3.
    let v = [
        [0.0, 0.0],
        [1.0, 0.0],
        [3.0, 0.0],
        [0.0, 1.0],
        [1.0, 1.0],
        [3.0, 1.0],
        [2.0, 3.0],
        [0.0, 2.0],
    ];
    let quads = [[0, 1, 4, 3], [1, 2, 5, 4], [3, 4, 6, 7]];
    let q = QuadQuality::of(&v, &quads);
    assert!((q.average_area - 5.0 / 3.0).abs() < 1e-15);
    let q2 = [[0.0, 1.0], [1.0, 1.0], [2.0, 3.0], [0.0, 2.0]];
    let close = |a: f64, b: f64| (a - b).abs() < 1e-12;
    assert!(close(quad::shape(&q2), 0.6));
    assert!(close(quad::shape_and_size(&q2, 5.0 / 3.0), 5.0 / 12.0));
    assert!(close(quad::shape_and_size(&SQUARE, 5.0 / 3.0), 0.36));
    assert!(close(quad::scaled_jacobian(&q2), 0.6));
    assert!(close(
        quad::minimum_angle(&q2),
        (3.0f64 / 4.0).atan().to_degrees()
    ));
    assert!(close(
        quad::maximum_angle(&q2),
        180.0 - 2f64.atan().to_degrees()
    ));
    assert!(close(quad::condition(&q2), 10.0 / 6.0));
    assert!(close(q.shape_and_size.min, 0.36));
    assert!(close(q.shape_and_size.max, 5.0 / 9.0));
    assert!(close(
        q.shape_and_size.mean,
        (0.36 + 5.0 / 9.0 + 5.0 / 12.0) / 3.0
    ));
}

#[test]
fn degenerate_elements_get_verdicts_values() {
    let collapsed = [[0.0, 0.0], [1.0, 0.0], [0.5, 1.0], [0.5, 1.0]];
    assert_eq!(quad::shape(&collapsed), 0.0);
    assert_eq!(
        quad::scaled_jacobian(&collapsed),
        tri::scaled_jacobian(&[[0.0, 0.0], [1.0, 0.0], [0.5, 1.0]])
    );
    let point = [[2.0, 2.0]; 4];
    assert_eq!(
        (quad::shape(&point), quad::scaled_jacobian(&point)),
        (0.0, imesh_quality::DBL_MAX.min(0.0))
    );
    assert_eq!(
        quad::minimum_angle(&point),
        tri::minimum_angle(&[[2.0, 2.0]; 3])
    );
    let flat = [[0.0, 0.0], [1.0, 1.0], [2.0, 2.0]];
    assert_eq!(tri::condition(&flat), imesh_quality::DBL_MAX);
    assert_eq!(tri::scaled_jacobian(&flat), 0.0);
    assert_eq!(
        tri::minimum_angle(&[[0.0, 0.0], [0.0, 0.0], [1.0, 0.0]]),
        0.0
    );
    // A flat corner (three collinear vertices) is degenerate for Verdict.
    let flat_corner = [[0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [0.0, 1.0]];
    assert_eq!(quad::shape(&flat_corner), 0.0);
    assert_eq!(quad::scaled_jacobian(&flat_corner), 0.0);
}

#[test]
fn statistics_use_the_sample_variance_and_skip_nans() {
    let s = Statistics::of(&[1.0, f64::NAN, 3.0], 2.0);
    assert_eq!(
        (s.count, s.min, s.max, s.mean, s.variance, s.below),
        (2, 1.0, 3.0, 2.0, 2.0, 1)
    );
    let empty = Statistics::of(&[], 0.2);
    assert_eq!(empty.count, 0);
    assert!(empty.min.is_nan());
    let h = Histogram::of(&[-1.0, 0.0, 0.2499, 0.25, 0.99], 0.0, 1.0, 4);
    assert_eq!(h.counts, vec![3, 1, 0, 1]);
    assert_eq!(h.bin_edges(1), (0.25, 0.5));
}

/// Verdict's quad shape written out plainly: 0 when an edge is tiny against the bounding box's
/// diagonal, else twice the least `α_k / (|L_k|² + |L_{k−1}|²)`, the corner areas signed by
/// the centre normal.
fn verdict_shape(q: &quad::Quad) -> f64 {
    let dbl_min = imesh_quality::DBL_MIN;
    let edge = |k: usize| [q[(k + 1) % 4][0] - q[k][0], q[(k + 1) % 4][1] - q[k][1]];
    let cross = |a: [f64; 2], b: [f64; 2]| a[0] * b[1] - a[1] * b[0];
    let len2: Vec<f64> = (0..4)
        .map(|k| edge(k)[0].powi(2) + edge(k)[1].powi(2))
        .collect();
    let (xs, ys) = (q.map(|p| p[0]), q.map(|p| p[1]));
    let span = |v: [f64; 4]| {
        v.iter().copied().fold(f64::MIN, f64::max) - v.iter().copied().fold(f64::MAX, f64::min)
    };
    let mut h2 = span(xs).powi(2) + span(ys).powi(2);
    if h2 < dbl_min * dbl_min {
        h2 = 1.0;
    }
    if len2.iter().any(|&l| l <= dbl_min * h2) {
        return 0.0;
    }
    let x1 = [edge(0)[0] - edge(2)[0], edge(0)[1] - edge(2)[1]];
    let x2 = [edge(1)[0] - edge(3)[0], edge(1)[1] - edge(3)[1]];
    let nc = cross(x1, x2);
    let sign = if nc.abs() <= 2.0 * dbl_min {
        0.0
    } else {
        nc.signum()
    };
    let worst = (0..4)
        .map(|k| sign * cross(edge((k + 3) % 4), edge(k)) / (len2[k] + len2[(k + 3) % 4]))
        .fold(f64::INFINITY, f64::min);
    let s = 2.0 * worst;
    if s < dbl_min {
        0.0
    } else {
        s
    }
}

fn convex_quad() -> impl Strategy<Value = quad::Quad> {
    // Four angles on an ellipse, in counter-clockwise order: a convex quad.
    (
        prop::collection::vec(0.0f64..std::f64::consts::TAU, 4),
        0.2f64..5.0,
        0.2f64..5.0,
    )
        .prop_map(|(mut a, rx, ry)| {
            a.sort_by(f64::total_cmp);
            [0, 1, 2, 3].map(|i| [rx * a[i].cos(), ry * a[i].sin()])
        })
}

fn transform(q: &quad::Quad, angle: f64, scale: f64, dx: f64, dy: f64) -> quad::Quad {
    let (s, c) = angle.sin_cos();
    q.map(|p| {
        [
            scale * (c * p[0] - s * p[1]) + dx,
            scale * (s * p[0] + c * p[1]) + dy,
        ]
    })
}

proptest! {
    #[test]
    fn shape_metrics_are_similarity_invariant(q in convex_quad(), angle in 0.0f64..6.3, scale in 0.01f64..100.0, dx in -1e3f64..1e3, dy in -1e3f64..1e3) {
        let t = transform(&q, angle, scale, dx, dy);
        for f in [quad::shape, quad::scaled_jacobian, quad::minimum_angle, quad::maximum_angle, quad::edge_ratio] {
            let (a, b) = (f(&q), f(&t));
            prop_assert!((a - b).abs() <= 1e-7 * a.abs().max(1.0), "{a} vs {b}");
        }
    }

    #[test]
    fn shape_is_two_over_the_worst_corner_condition(q in convex_quad()) {
        let s = quad::shape(&q);
        prop_assert!((0.0..=1.0).contains(&s));
        if s > 1e-6 {
            // condition = 1 / shape on convex quads
            prop_assert!((quad::condition(&q) * s - 1.0).abs() < 1e-9);
            prop_assert!(quad::scaled_jacobian(&q) > 0.0);
            prop_assert!(quad::scaled_jacobian(&q) <= 1.0 + 1e-15);
        }
    }

    #[test]
    fn cyclic_relabelling_does_not_change_anything(q in convex_quad(), k in 0usize..4, avg in 0.1f64..10.0) {
        let r = [q[k], q[(k + 1) % 4], q[(k + 2) % 4], q[(k + 3) % 4]];
        prop_assert!((quad::shape_and_size(&q, avg) - quad::shape_and_size(&r, avg)).abs() < 1e-12);
        prop_assert!((quad::scaled_jacobian(&q) - quad::scaled_jacobian(&r)).abs() < 1e-12);
    }

    #[test]
    fn a_tiny_edge_is_judged_against_the_bounding_box(q in convex_quad(), exponent in -9.0f64..-6.0, k in 0usize..4) {
        // Vertex k + 1 slid towards vertex k: edge k at 1e-9 to 1e-6 of its length, across
        // Verdict's tiny-edge bar (|L|² ≤ DBL_MIN · the box's squared diagonal).
        let mut t = q;
        let (a, b) = (q[k], q[(k + 1) % 4]);
        let f = 10f64.powf(exponent);
        t[(k + 1) % 4] = [a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1])];
        prop_assert_eq!(quad::shape(&t).to_bits(), verdict_shape(&t).to_bits());
    }

    #[test]
    fn area_is_the_shoelace_area(q in convex_quad()) {
        let shoelace = imesh_quality::signed_area(&q);
        prop_assert!((quad::area(&q) - shoelace.abs()).abs() <= 1e-12 * shoelace.abs().max(1.0));
    }
}
