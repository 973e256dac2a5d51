//! The staged predicates must agree in sign with Shewchuk's adaptive ones on every input.

use imesh_geom::predicates::{incircle, orient2d};
use imesh_geom::Point;
use proptest::prelude::*;

fn robust_orient(a: Point, b: Point, c: Point) -> f64 {
    let r = |p: Point| robust::Coord { x: p.x, y: p.y };
    robust::orient2d(r(a), r(b), r(c))
}

fn robust_incircle(a: Point, b: Point, c: Point, d: Point) -> f64 {
    let r = |p: Point| robust::Coord { x: p.x, y: p.y };
    robust::incircle(r(a), r(b), r(c), r(d))
}

fn lattice_point() -> impl Strategy<Value = Point> {
    // Multiples of 1/4 (pixel centres, corners, edge midpoints and their midpoints), some far out.
    (
        -40i64..40,
        -40i64..40,
        prop::sample::select(vec![1.0, 1.0, 1.0, 1e6, 3e9]),
    )
        .prop_map(|(x, y, s)| Point::new(x as f64 * 0.25 * s, y as f64 * 0.25 * s))
}

fn any_point() -> impl Strategy<Value = Point> {
    prop_oneof![
        lattice_point(),
        (-10.0f64..10.0, -10.0f64..10.0).prop_map(|(x, y)| Point::new(x, y)),
        // Tiny perturbations of lattice points: the hardest case for the filter.
        (lattice_point(), -3i32..4, -3i32..4).prop_map(|(p, i, j)| Point::new(
            p.x + f64::from(i) * 1e-15,
            p.y + f64::from(j) * 1e-13
        )),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(3000))]

    #[test]
    fn orient2d_sign_is_exact(a in any_point(), b in any_point(), c in any_point()) {
        prop_assert_eq!(orient2d(a, b, c).signum(), robust_orient(a, b, c).signum());
    }

    #[test]
    fn incircle_sign_is_exact(a in any_point(), b in any_point(), c in any_point(), d in any_point()) {
        prop_assert_eq!(incircle(a, b, c, d).signum(), robust_incircle(a, b, c, d).signum());
    }

    #[test]
    fn cocircular_lattice_quadruples_give_zero(cx in -50i32..50, cy in -50i32..50, k in 0usize..4) {
        // The four corners of an axis-aligned square, and of a 3-4-5 rectangle, are cocircular.
        let c = Point::new(f64::from(cx) + 0.5, f64::from(cy) + 0.5);
        let (w, h) = [(1.0, 1.0), (3.0, 4.0), (0.25, 7.5), (1e3, 2.0)][k];
        let q = [c, Point::new(c.x + w, c.y), Point::new(c.x + w, c.y + h), Point::new(c.x, c.y + h)];
        prop_assert_eq!(incircle(q[0], q[1], q[2], q[3]), 0.0);
        prop_assert_eq!(orient2d(q[0], q[1], Point::new(c.x + 2.0 * w, c.y)), 0.0);
    }
}

#[test]
fn far_apart_lattice_points_fall_back_to_the_adaptive_path() {
    // Differences beyond the integer stage's span still get an exact answer.
    let a = Point::new(0.0, 0.0);
    let b = Point::new(1.0e9, 1.0);
    let c = Point::new(2.0e9, 2.0);
    assert_eq!(orient2d(a, b, c), 0.0);
    assert!(orient2d(a, b, Point::new(2.0e9, 2.25)) > 0.0);
}
