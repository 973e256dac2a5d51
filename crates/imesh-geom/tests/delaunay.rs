//! Delaunay kernel: exact checks against brute force, an independent hull, and spade.

use imesh_geom::predicates::{incircle, orient2d};
use imesh_geom::{GeomError, Location, Point, TriangleId, Triangulation, VertexId};
use proptest::prelude::*;
use spade::Triangulation as _;

/// Number of distinct points on the boundary of the convex hull, collinear ones included
/// (Andrew's monotone chain with exact orientation; independent of the kernel).
fn hull_boundary_count(points: &[Point]) -> usize {
    let mut p: Vec<Point> = points.to_vec();
    p.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    p.dedup();
    if p.len() < 3 {
        return p.len();
    }
    let half = |iter: &mut dyn Iterator<Item = Point>| {
        let mut h: Vec<Point> = Vec::new();
        for q in iter {
            // Pop only strict right turns: collinear boundary points stay on the chain.
            while h.len() >= 2 && orient2d(h[h.len() - 2], h[h.len() - 1], q) < 0.0 {
                h.pop();
            }
            h.push(q);
        }
        h
    };
    let lower = half(&mut p.iter().copied());
    let upper = half(&mut p.iter().rev().copied());
    lower.len() + upper.len() - 2
}

fn distinct(points: &[Point]) -> usize {
    let mut p: Vec<(u64, u64)> = points
        .iter()
        .map(|p| ((p.x + 0.0).to_bits(), (p.y + 0.0).to_bits()))
        .collect();
    p.sort_unstable();
    p.dedup();
    p.len()
}

fn all_collinear(points: &[Point]) -> bool {
    let Some(&a) = points.first() else {
        return true;
    };
    let Some(&b) = points.iter().find(|&&q| q != a) else {
        return true;
    };
    points.iter().all(|&q| orient2d(a, b, q) == 0.0)
}

fn spade_triangle_count(points: &[Point]) -> usize {
    let v: Vec<spade::Point2<f64>> = points
        .iter()
        .map(|p| spade::Point2::new(p.x, p.y))
        .collect();
    let t = spade::DelaunayTriangulation::<spade::Point2<f64>>::bulk_load(v).unwrap();
    t.num_inner_faces()
}

/// Every property the kernel promises for the triangulation of `points`.
fn assert_delaunay_of(points: &[Point]) {
    let (t, ids) = Triangulation::from_points(points).unwrap();
    t.check().unwrap();
    let n = distinct(points);
    assert_eq!(t.num_vertices(), n);
    assert_eq!(ids.len(), points.len());
    for (i, v) in ids.iter().enumerate() {
        assert_eq!(
            t.point(*v),
            points[i],
            "input {i} maps to a vertex at its own position"
        );
    }
    if all_collinear(points) {
        assert_eq!(t.num_triangles(), 0);
        assert!(t.is_degenerate());
    } else {
        let h = hull_boundary_count(points);
        assert_eq!(t.hull().len(), h);
        assert_eq!(t.num_triangles(), 2 * n - h - 2);
    }
    assert_eq!(t.num_triangles(), spade_triangle_count(points));
}

/// Global empty-circle property by brute force with exact predicates.
fn assert_globally_delaunay(t: &Triangulation) {
    for f in t.triangles() {
        let [a, b, c] = t.triangle_points(f);
        for v in t.vertices() {
            assert!(
                incircle(a, b, c, t.point(v)) <= 0.0,
                "vertex {v:?} inside triangle {f:?}'s circle"
            );
        }
    }
}

fn grid(w: u32, h: u32) -> Vec<Point> {
    (0..h)
        .flat_map(|r| (0..w).map(move |c| Point::pixel_centre(c, r)))
        .collect()
}

#[test]
fn single_triangle_and_its_orientation() {
    let pts = [
        Point::new(0.0, 0.0),
        Point::new(0.0, 1.0),
        Point::new(1.0, 0.0),
    ];
    let (t, _) = Triangulation::from_points(&pts).unwrap();
    assert_eq!(t.num_triangles(), 1);
    let f = t.triangles().next().unwrap();
    let [a, b, c] = t.triangle_points(f);
    assert!(orient2d(a, b, c) > 0.0);
    assert_eq!(t.signed_area(f), 0.5);
    t.check().unwrap();
}

#[test]
fn empty_one_and_two_points() {
    for n in 0..3 {
        let pts: Vec<Point> = (0..n).map(|i| Point::new(f64::from(i), 0.0)).collect();
        let (t, ids) = Triangulation::from_points(&pts).unwrap();
        assert_eq!(
            (t.num_vertices(), t.num_triangles(), ids.len()),
            (n as usize, 0, n as usize)
        );
        assert!(t.hull().is_empty());
        assert_eq!(t.locate(Point::new(0.0, 0.0)), Location::NoTriangles);
        t.check().unwrap();
    }
}

#[test]
fn collinear_points_wait_for_a_point_off_their_line() {
    let mut t = Triangulation::new();
    for i in 0..50 {
        t.insert(Point::new(f64::from(i), 2.0 * f64::from(i)))
            .unwrap();
    }
    assert!(t.is_degenerate());
    assert_eq!(t.insert(Point::new(7.0, 14.0)).unwrap(), VertexId::new(7));
    t.check().unwrap();
    t.insert(Point::new(0.0, 5.0)).unwrap();
    assert_eq!(t.num_vertices(), 51);
    assert_eq!(t.num_triangles(), 49);
    assert_eq!(t.created_triangles().len(), 49);
    t.check().unwrap();
    assert_globally_delaunay(&t);
}

#[test]
fn duplicates_map_to_the_first_vertex_in_input_order() {
    let pts = [
        Point::new(1.0, 1.0),
        Point::new(0.0, 0.0),
        Point::new(1.0, 1.0),
        Point::new(5.0, 0.0),
        Point::new(0.0, -0.0),
        Point::new(0.0, 5.0),
    ];
    let (t, ids) = Triangulation::from_points(&pts).unwrap();
    assert_eq!(t.num_vertices(), 4);
    assert_eq!(
        ids.iter().map(|v| v.index()).collect::<Vec<_>>(),
        [0, 1, 0, 2, 1, 3]
    );
    t.check().unwrap();
}

#[test]
fn pixel_grid_is_cocircular_everywhere_yet_exact() {
    for (w, h) in [(2, 2), (3, 7), (31, 17), (128, 128)] {
        let pts = grid(w, h);
        assert_delaunay_of(&pts);
    }
    let (t, _) = Triangulation::from_points(&grid(12, 9)).unwrap();
    assert_globally_delaunay(&t);
    // Every triangle of a unit grid is half a pixel square.
    assert!(t.triangles().all(|f| t.signed_area(f) == 0.5));
}

#[test]
fn incremental_insertion_reports_exactly_the_new_star() {
    let pts: Vec<Point> = (0..400u32)
        .map(|i| Point::new(f64::from(i * 7919 % 101), f64::from(i * 104_729 % 97)))
        .collect();
    let mut t = Triangulation::new();
    for &p in &pts {
        let before = t.num_vertices();
        let v = t.insert(p).unwrap();
        if t.num_vertices() == before || t.num_vertices() < 4 {
            continue;
        }
        let created = t.created_triangles();
        // The new star: every created triangle has the new vertex, and every triangle with the new
        // vertex was created.
        let star: Vec<TriangleId> = t
            .triangles()
            .filter(|&f| t.triangle_vertices(f).contains(&v))
            .collect();
        let mut c = created.to_vec();
        c.sort();
        assert_eq!(c, star);
    }
    t.check().unwrap();
    assert_globally_delaunay(&t);
    let (bulk, _) = Triangulation::from_points(&pts).unwrap();
    assert_eq!(bulk.num_triangles(), t.num_triangles());
}

#[test]
fn locate_classifies_every_kind_of_position() {
    let pts = grid(4, 4);
    let (t, ids) = Triangulation::from_points(&pts).unwrap();
    assert_eq!(t.locate(Point::new(1.5, 2.5)), Location::OnVertex(ids[9]));
    match t.locate(Point::new(1.5, 2.0)) {
        Location::OnEdge(e) => {
            let (a, b) = (t.point(t.origin(e)), t.point(t.destination(e)));
            assert_eq!(orient2d(a, b, Point::new(1.5, 2.0)), 0.0);
        }
        other => panic!("expected an edge, got {other:?}"),
    }
    assert!(matches!(
        t.locate(Point::new(1.2, 2.1)),
        Location::InTriangle(_)
    ));
    match t.locate(Point::new(10.0, 1.0)) {
        Location::OutsideHull(e) => {
            let (a, b) = (t.point(t.origin(e)), t.point(t.destination(e)));
            assert!(orient2d(a, b, Point::new(10.0, 1.0)) < 0.0);
            assert!(t.neighbour(t.twin(e)).is_some() && t.neighbour(e).is_none());
        }
        other => panic!("expected outside, got {other:?}"),
    }
}

#[test]
fn non_finite_points_are_refused_with_their_index() {
    let pts = [Point::new(0.0, 0.0), Point::new(f64::NAN, 1.0)];
    assert!(matches!(
        Triangulation::from_points(&pts),
        Err(GeomError::NonFinitePoint { index: 1, .. })
    ));
    let mut t = Triangulation::new();
    assert!(t.insert(Point::new(0.0, f64::INFINITY)).is_err());
    assert_eq!(t.num_vertices(), 0);
}

#[test]
fn edges_and_hull_are_consistent_with_euler() {
    let pts: Vec<Point> = (0..300u32)
        .map(|i| Point::new(f64::from(i % 17) * 1.3, f64::from(i * 31 % 23)))
        .collect();
    let (t, _) = Triangulation::from_points(&pts).unwrap();
    let edges = t.edges().count();
    // E = 3F/2 + h/2 for a triangulated disk.
    assert_eq!(2 * edges, 3 * t.num_triangles() + t.hull().len());
    let hull = t.hull();
    for i in 0..hull.len() {
        let [a, b, c] = [
            hull[i],
            hull[(i + 1) % hull.len()],
            hull[(i + 2) % hull.len()],
        ]
        .map(|v| t.point(v));
        assert!(orient2d(a, b, c) >= 0.0);
    }
}

#[test]
fn a_larger_random_set_and_a_sparse_grid() {
    let mut s = 12345u64;
    let mut rnd = || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 11) as f64 / (1u64 << 53) as f64
    };
    let pts: Vec<Point> = (0..20_000)
        .map(|_| Point::new(rnd() * 1000.0, rnd() * 1000.0))
        .collect();
    assert_delaunay_of(&pts);
    let sparse: Vec<Point> = grid(300, 200)
        .into_iter()
        .enumerate()
        .filter(|(i, _)| i % 3 != 1)
        .map(|(_, p)| p)
        .collect();
    assert_delaunay_of(&sparse);
}

fn small_int_points() -> impl Strategy<Value = Vec<Point>> {
    prop::collection::vec((0i32..12, 0i32..12), 0..60).prop_map(|v| {
        v.into_iter()
            .map(|(x, y)| Point::new(f64::from(x), f64::from(y)))
            .collect()
    })
}

fn collinear_runs() -> impl Strategy<Value = Vec<Point>> {
    // Runs of points along random integer directions, plus a few strays: long collinear hull sides.
    (
        prop::collection::vec(
            (-20i32..20, -20i32..20, -3i32..4, -3i32..4, 1usize..15),
            1..5,
        ),
        prop::collection::vec((-30.0f64..30.0, -30.0f64..30.0), 0..6),
    )
        .prop_map(|(runs, strays)| {
            let mut pts = Vec::new();
            for (x, y, dx, dy, n) in runs {
                for k in 0..n as i32 {
                    pts.push(Point::new(f64::from(x + k * dx), f64::from(y + k * dy)));
                }
            }
            pts.extend(strays.into_iter().map(|(x, y)| Point::new(x, y)));
            pts
        })
}

fn grid_subsets() -> impl Strategy<Value = Vec<Point>> {
    (
        1u32..25,
        1u32..25,
        prop::collection::vec(any::<bool>(), 625),
    )
        .prop_map(|(w, h, keep)| {
            grid(w, h)
                .into_iter()
                .enumerate()
                .filter(|(i, _)| keep[*i])
                .map(|(_, p)| p)
                .collect()
        })
}

fn float_points_with_duplicates() -> impl Strategy<Value = Vec<Point>> {
    prop::collection::vec((-1e3f64..1e3, -1e3f64..1e3, 0usize..3), 0..120).prop_map(|v| {
        let mut pts: Vec<Point> = Vec::new();
        for (x, y, copies) in v {
            for _ in 0..=copies {
                pts.push(Point::new(x, y));
            }
        }
        pts
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    #[test]
    fn integer_points_with_duplicates(pts in small_int_points()) {
        assert_delaunay_of(&pts);
    }

    #[test]
    fn collinear_runs_and_strays(pts in collinear_runs()) {
        assert_delaunay_of(&pts);
    }

    #[test]
    fn subsets_of_pixel_grids(pts in grid_subsets()) {
        assert_delaunay_of(&pts);
        let (t, _) = Triangulation::from_points(&pts).unwrap();
        assert_globally_delaunay(&t);
    }

    #[test]
    fn float_points(pts in float_points_with_duplicates()) {
        assert_delaunay_of(&pts);
    }

    #[test]
    fn incremental_equals_bulk(pts in small_int_points()) {
        let mut t = Triangulation::new();
        for &p in &pts {
            let v = t.insert(p).unwrap();
            prop_assert_eq!(t.point(v), p);
        }
        t.check().unwrap();
        assert_globally_delaunay(&t);
        let (bulk, _) = Triangulation::from_points(&pts).unwrap();
        prop_assert_eq!(bulk.num_triangles(), t.num_triangles());
        prop_assert_eq!(bulk.num_vertices(), t.num_vertices());
    }
}

/// Coordinates where exact predicates would overflow (hanging the insertion at 1e200, breaking
/// orientation at 1e100) or underflow (1e-150) are refused with a typed error; the bounds
/// themselves and 0 are accepted. Found while writing the fuzz harness (fuzz/regressions/delaunay).
#[test]
fn coordinates_out_of_the_exact_range_are_refused() {
    let lattice = |scale: f64| -> Vec<Point> {
        (0..50)
            .map(|i| {
                Point::new(
                    f64::from((i * 7) % 13) * scale,
                    f64::from((i * 5) % 11) * scale,
                )
            })
            .collect()
    };
    for scale in [1e200, 1e100, 1e-150, 1e-300] {
        assert!(
            matches!(
                Triangulation::from_points(&lattice(scale)),
                Err(GeomError::OutOfRange { .. })
            ),
            "scale {scale}"
        );
        let mut t = Triangulation::new();
        let refused = lattice(scale)
            .into_iter()
            .filter(|&p| matches!(t.insert(p), Err(GeomError::OutOfRange { .. })))
            .count();
        assert!(refused > 0, "scale {scale}");
        t.check().unwrap();
    }
    for scale in [1e25, 1e-25] {
        let (t, _) = Triangulation::from_points(&lattice(scale)).unwrap();
        t.check().unwrap();
    }
    let edge = [
        Point::new(0.0, 0.0),
        Point::new(imesh_geom::MAX_COORDINATE, 0.0),
        Point::new(0.0, -imesh_geom::MAX_COORDINATE),
        Point::new(imesh_geom::MIN_COORDINATE, imesh_geom::MIN_COORDINATE),
    ];
    let (t, _) = Triangulation::from_points(&edge).unwrap();
    t.check().unwrap();
    assert_eq!(t.num_triangles(), 2);
    let err = Triangulation::from_points(&[Point::new(1e31, 0.0)]).unwrap_err();
    assert!(err.to_string().contains("scale the input"), "{err}");
}
