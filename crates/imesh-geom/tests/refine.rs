//! Ruppert refinement on random PSLGs: conformity, labels, angles, termination.

use imesh_geom::{
    GeomError, Point, RefineOptions, StopReason, TriangleId, Triangulation, VertexId, EXTERIOR,
};
use proptest::prelude::*;

mod common;
use common::{centroid, inside, star};

/// The smallest angle of a triangle (degrees) and whether it sits between two segments.
fn smallest(t: &Triangulation, f: TriangleId) -> (f64, bool) {
    let p = t.triangle_points(f);
    let e = t.triangle_edges(f);
    let mut best = (f64::INFINITY, false);
    for k in 0..3 {
        let (o, u, w) = (p[k], p[(k + 1) % 3], p[(k + 2) % 3]);
        let (a, b) = (u - o, w - o);
        let angle = (a.x * b.y - a.y * b.x)
            .abs()
            .atan2(a.x * b.x + a.y * b.y)
            .to_degrees();
        if angle < best.0 {
            // The edges at corner k: e[k] leaves it, e[(k + 2) % 3] arrives.
            best = (
                angle,
                t.is_constrained(e[k]) && t.is_constrained(e[(k + 2) % 3]),
            );
        }
    }
    best
}

fn assert_refined(t: &Triangulation, theta: f64) {
    t.check().unwrap();
    for f in t.triangles() {
        if t.label(f) == EXTERIOR {
            continue;
        }
        let (angle, input_corner) = smallest(t, f);
        assert!(
            angle >= theta - 1e-9 || input_corner,
            "triangle {f:?} has angle {angle}° < {theta}°: {:?} label {}",
            t.triangle_points(f),
            t.label(f)
        );
    }
}

/// True when the shortest edge of `f` joins points on two input segments that meet at a common end
/// at less than 60°: a triangle spanning a small input angle, which refinement may leave.
fn spans_small_angle(t: &Triangulation, f: TriangleId, segments: &[[Point; 2]]) -> bool {
    let p = t.triangle_points(f);
    let k = (0..3)
        .min_by(|&i, &j| {
            let l = |k: usize| p[k].distance_squared(p[(k + 1) % 3]);
            l(i).total_cmp(&l(j))
        })
        .unwrap();
    let (u, w) = (p[k], p[(k + 1) % 3]);
    let on = |q: Point, [a, b]: [Point; 2]| {
        let cross = (b.x - a.x) * (q.y - a.y) - (b.y - a.y) * (q.x - a.x);
        let dot = (q.x - a.x) * (b.x - a.x) + (q.y - a.y) * (b.y - a.y);
        cross.abs() <= 1e-9 * a.distance_squared(b) && dot >= 0.0 && dot <= a.distance_squared(b)
    };
    segments.iter().any(|&s| {
        on(u, s)
            && segments.iter().any(|&r| {
                if r == s || !on(w, r) {
                    return false;
                }
                // The common end and the angle between the two segments there.
                let apex = [s[0], s[1]].into_iter().find(|&x| x == r[0] || x == r[1]);
                apex.is_some_and(|a| {
                    let x = if s[0] == a { s[1] } else { s[0] } - a;
                    let y = if r[0] == a { r[1] } else { r[0] } - a;
                    let dot = x.x * y.x + x.y * y.y;
                    dot > 0.0 && 4.0 * dot * dot > (x.x * x.x + x.y * x.y) * (y.x * y.x + y.y * y.y)
                })
            })
    })
}

/// The PSLG of a `w` × `h` label image, labelled: unit segments between pixels of different
/// labels and on the border, and only the pixel corners they use (large empty regions, so
/// refinement has work to do).
fn label_grid_pslg(w: u32, h: u32, label: impl Fn(u32, u32) -> u32) -> Triangulation {
    let mut segs: Vec<((u32, u32), (u32, u32))> = Vec::new();
    for r in 0..=h {
        for c in 0..w {
            if r == 0 || r == h || label(c, r - 1) != label(c, r) {
                segs.push(((c, r), (c + 1, r)));
            }
        }
    }
    for c in 0..=w {
        for r in 0..h {
            if c == 0 || c == w || label(c - 1, r) != label(c, r) {
                segs.push(((c, r), (c, r + 1)));
            }
        }
    }
    let mut corners: Vec<(u32, u32)> = segs.iter().flat_map(|&(p, q)| [p, q]).collect();
    corners.sort_unstable();
    corners.dedup();
    let pts: Vec<Point> = corners
        .iter()
        .map(|&(c, r)| Point::new(f64::from(c), f64::from(r)))
        .collect();
    let (mut t, ids) = Triangulation::from_points(&pts).unwrap();
    let id = |p: (u32, u32)| ids[corners.binary_search(&p).unwrap()];
    for &(p, q) in &segs {
        t.insert_segment(id(p), id(q)).unwrap();
    }
    let seeds: Vec<(Point, u32)> = (0..h)
        .flat_map(|r| (0..w).map(move |c| (r, c)))
        .map(|(r, c)| {
            let centre = Point::new(f64::from(c) + 0.5, f64::from(r) + 0.5);
            (centre, label(c, r))
        })
        .collect();
    t.label_regions(&seeds);
    t
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    #[test]
    fn random_segment_soups_made_planar(coords in prop::collection::vec((0u32..40, 0u32..40), 4..30), pairs in prop::collection::vec((0usize..30, 0usize..30), 1..40), theta in prop::sample::select(vec![20.7, 28.0, 33.0])) {
        let pts: Vec<Point> = coords.iter().map(|&(x, y)| Point::new(f64::from(x), f64::from(y))).collect();
        let Ok((mut t, ids)) = Triangulation::from_points(&pts) else { return Ok(()) };
        // Planar by construction: a segment crossing an earlier one is refused (and dropped).
        let mut kept = Vec::new();
        for &(i, j) in &pairs {
            let (i, j) = (i % pts.len(), j % pts.len());
            if ids[i] == ids[j] {
                continue;
            }
            match t.insert_segment(ids[i], ids[j]) {
                Ok(_) => kept.push([pts[i], pts[j]]),
                Err(GeomError::CrossingSegments { .. }) => {}
                Err(e) => panic!("unexpected error {e}"),
            }
        }
        if t.is_degenerate() {
            return Ok(());
        }
        let hull = t.hull();
        for i in 0..hull.len() {
            kept.push([t.point(hull[i]), t.point(hull[(i + 1) % hull.len()])]);
        }
        // Input points lying on a segment cut it: the pieces meet there at an input angle.
        let kept: Vec<[Point; 2]> = kept
            .iter()
            .flat_map(|&[a, b]| {
                let mut on: Vec<Point> = pts
                    .iter()
                    .copied()
                    .filter(|&p| {
                        let cross = (b.x - a.x) * (p.y - a.y) - (b.y - a.y) * (p.x - a.x);
                        let dot = (p.x - a.x) * (b.x - a.x) + (p.y - a.y) * (b.y - a.y);
                        cross == 0.0 && dot > 0.0 && dot < a.distance_squared(b)
                    })
                    .collect();
                on.sort_by(|p, q| a.distance_squared(*p).total_cmp(&a.distance_squared(*q)));
                on.dedup();
                let mut chain = vec![a];
                chain.extend(on);
                chain.push(b);
                chain.windows(2).map(|w| [w[0], w[1]]).collect::<Vec<_>>()
            })
            .collect();
        let report = t.refine(&RefineOptions { min_angle_deg: theta, max_steiner: 50_000, ..Default::default() }).unwrap();
        prop_assert_eq!(report.stopped, StopReason::Done);
        t.check().unwrap();
        // Every kept segment is a union of constrained edges: its vertices, in order, are joined.
        for s in 0..t.num_segments() {
            let s = imesh_geom::SegmentId(s as u32);
            let chain = t.segment_vertices(s);
            for w in chain.windows(2) {
                let e = t.find_edge(w[0], w[1]);
                prop_assert!(e.is_some_and(|e| t.is_constrained(e)), "segment {:?} is not a union of edges", s);
            }
        }
        for f in t.triangles() {
            let (angle, input_corner) = smallest(&t, f);
            prop_assert!(angle >= theta - 1e-9 || input_corner || spans_small_angle(&t, f, &kept),
                "triangle {:?} has angle {}° < {}°", t.triangle_points(f), angle, theta);
        }
    }

    #[test]
    fn polygons_with_holes(outer in prop::collection::vec(6.0f64..10.0, 5..16), hole in prop::collection::vec(1.0f64..3.0, 3..8), theta in prop::sample::select(vec![20.7, 28.0, 33.0])) {
        let c = Point::new(0.0, 0.0);
        let (po, ph) = (star(c, &outer), star(c, &hole));
        let mut pts = po.clone();
        pts.extend(&ph);
        let (mut t, ids) = Triangulation::from_points(&pts).unwrap();
        for (first, n) in [(0, po.len()), (po.len(), ph.len())] {
            for i in 0..n {
                t.insert_segment(ids[first + i], ids[first + (i + 1) % n]).unwrap();
            }
        }
        t.label_regions(&[(po[0].midpoint(Point::new(hole[0], 0.0)), 5)]);
        let before = t.num_vertices();
        let report = t.refine(&RefineOptions { min_angle_deg: theta, max_steiner: 20_000, ..Default::default() }).unwrap();
        prop_assert_eq!(report.stopped, StopReason::Done);
        prop_assert_eq!(t.num_vertices(), before + report.inserted);
        assert_refined(&t, theta);
        // (Slivers of rounding size between the hull and a boundary chain whose split points were
        // nudged off a non-lattice segment cannot be judged by a point-in-polygon test.)
        for f in t.triangles().filter(|&f| t.signed_area(f) > 1e-9) {
            let p = centroid(&t, f);
            let expect = if inside(&po, p) && !inside(&ph, p) { 5 } else { EXTERIOR };
            prop_assert_eq!(t.label(f), expect, "triangle {:?} centroid {:?} area {}", t.triangle_points(f), p, t.signed_area(f));
        }
    }

    #[test]
    fn grid_boundaries_of_random_label_images(w in 2u32..9, h in 2u32..9, cells in prop::collection::vec(0u32..3, 81), theta in prop::sample::select(vec![20.7, 28.0, 33.0])) {
        let label = |c: u32, r: u32| cells[(r * 9 + c) as usize];
        let mut t = label_grid_pslg(w, h, label);
        let before = t.num_vertices();
        let report = t.refine(&RefineOptions { min_angle_deg: theta, max_steiner: 20_000, ..Default::default() }).unwrap();
        prop_assert_eq!(report.stopped, StopReason::Done);
        prop_assert_eq!(t.num_vertices(), before + report.inserted);
        assert_refined(&t, theta);
        for f in t.triangles() {
            let p = centroid(&t, f);
            prop_assert_eq!(t.label(f), label(p.x as u32, p.y as u32));
        }
    }

    #[test]
    fn a_restart_refines_the_named_triangles_to_their_stricter_angle(w in 2u32..9, h in 2u32..9, cells in prop::collection::vec(0u32..3, 81), strict in prop::sample::select(vec![25.0, 30.0, 34.0]), every in 1usize..4) {
        let label = |c: u32, r: u32| cells[(r * 9 + c) as usize];
        let mut t = label_grid_pslg(w, h, label);
        let options = RefineOptions { min_angle_deg: 20.7, max_steiner: 20_000, ..Default::default() };
        t.refine(&options).unwrap();
        let sorted = |t: &Triangulation, f: TriangleId| {
            let mut v = t.triangle_vertices(f).map(|v| v.index());
            v.sort_unstable();
            v
        };
        // Every `every`-th triangle under the stricter angle (and not at an input angle) is named.
        let named: Vec<TriangleId> = t
            .triangles()
            .filter(|&f| matches!(smallest(&t, f), (a, false) if a < strict))
            .step_by(every)
            .collect();
        let named_vertices: Vec<[usize; 3]> = named.iter().map(|&f| sorted(&t, f)).collect();
        let others: Vec<[usize; 3]> = t
            .triangles()
            .filter(|f| !named.contains(f))
            .map(|f| sorted(&t, f))
            .collect();
        let before = t.num_vertices();
        let report = t.refine_triangles_with_policy(&named, strict, &options, |_, _| true).unwrap();
        prop_assert_eq!(report.stopped, StopReason::Done);
        prop_assert_eq!(t.num_vertices(), before + report.inserted);
        prop_assert_eq!(report.inserted > 0, !named.is_empty());
        // Still a conforming Delaunay triangulation refined to the plain bound, with its labels.
        assert_refined(&t, 20.7);
        for f in t.triangles() {
            let p = centroid(&t, f);
            prop_assert_eq!(t.label(f), label(p.x as u32, p.y as u32));
        }
        // No named triangle is left; and the unnamed ones under the stricter angle were not
        // refined for it (with no named triangle, nothing at all changed).
        let now: Vec<[usize; 3]> = t.triangles().map(|f| sorted(&t, f)).collect();
        prop_assert!(named_vertices.iter().all(|v| !now.contains(v)));
        if named.is_empty() {
            prop_assert_eq!(now.len(), others.len());
            prop_assert!(others.iter().all(|v| now.contains(v)));
        }
    }
}

#[test]
fn a_checkerboard_boundary_needs_and_gets_refinement() {
    // Corners of a 4 × 4 checkerboard's boundary only: long thin Delaunay triangles at first.
    let pts: Vec<Point> = [
        (0.0, 0.0),
        (8.0, 0.0),
        (8.0, 8.0),
        (0.0, 8.0),
        (4.0, 0.0),
        (4.0, 8.0),
        (0.0, 4.0),
        (8.0, 4.0),
        (4.0, 4.0),
        (1.0, 7.0),
    ]
    .iter()
    .map(|&(x, y)| Point::new(x, y))
    .collect();
    let (mut t, _) = Triangulation::from_points(&pts).unwrap();
    let worst_before = t
        .triangles()
        .map(|f| smallest(&t, f).0)
        .fold(f64::INFINITY, f64::min);
    assert!(worst_before < 20.0);
    let r = t
        .refine(&RefineOptions {
            min_angle_deg: 33.0,
            ..Default::default()
        })
        .unwrap();
    assert!(r.inserted > 0 && r.bad_left == 0);
    assert_refined(&t, 33.0);
}

#[test]
fn angles_above_34_degrees_are_refused() {
    let (mut t, _) = Triangulation::from_points(&[
        Point::new(0.0, 0.0),
        Point::new(1.0, 0.0),
        Point::new(0.0, 1.0),
    ])
    .unwrap();
    let e = t
        .refine(&RefineOptions {
            min_angle_deg: 35.0,
            ..Default::default()
        })
        .unwrap_err();
    assert_eq!(e, GeomError::BadAngle { degrees: 35.0 });
    assert!(t
        .refine(&RefineOptions {
            min_angle_deg: 0.0,
            ..Default::default()
        })
        .is_err());
    // The stricter bound of a restart too.
    let all: Vec<TriangleId> = t.triangles().collect();
    let e = t
        .refine_triangles_with_policy(&all, 35.0, &RefineOptions::default(), |_, _| true)
        .unwrap_err();
    assert_eq!(e, GeomError::BadAngle { degrees: 35.0 });
}

#[test]
fn the_cap_stops_refinement_and_says_so() {
    let pts = [
        Point::new(0.0, 0.0),
        Point::new(100.0, 0.0),
        Point::new(100.0, 1.0),
        Point::new(0.0, 1.0),
    ];
    let (mut t, _) = Triangulation::from_points(&pts).unwrap();
    let r = t
        .refine(&RefineOptions {
            min_angle_deg: 30.0,
            max_steiner: 10,
            ..Default::default()
        })
        .unwrap();
    assert_eq!((r.inserted, r.stopped), (10, StopReason::CapReached));
    t.check().unwrap();
}

#[test]
fn maximum_area_is_honoured() {
    let pts = [
        Point::new(0.0, 0.0),
        Point::new(10.0, 0.0),
        Point::new(10.0, 10.0),
        Point::new(0.0, 10.0),
    ];
    let (mut t, _) = Triangulation::from_points(&pts).unwrap();
    t.refine(&RefineOptions {
        min_angle_deg: 25.0,
        max_area: Some(2.0),
        ..Default::default()
    })
    .unwrap();
    assert!(t.triangles().all(|f| t.signed_area(f) <= 2.0));
    assert_refined(&t, 25.0);
}

#[test]
fn a_policy_veto_splits_segments_instead() {
    // A long thin rectangle: refusing every circumcentre leaves only segment splits.
    let pts = [
        Point::new(0.0, 0.0),
        Point::new(20.0, 0.0),
        Point::new(20.0, 1.0),
        Point::new(0.0, 1.0),
    ];
    let (mut t, _) = Triangulation::from_points(&pts).unwrap();
    let n = t.num_vertices();
    let r = t
        .refine_with_policy(&RefineOptions::default(), |_, _| false)
        .unwrap();
    t.check().unwrap();
    // Every vertex added lies on the border.
    for v in (n..t.num_vertices()).map(|i| VertexId::new(i as u32)) {
        let p = t.point(v);
        assert!(
            p.x == 0.0 || p.x == 20.0 || p.y == 0.0 || p.y == 1.0,
            "{p:?}"
        );
    }
    assert!(r.inserted > 0);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(32))]

    /// Splitting long segments: every constrained edge ends no longer than the bound, every
    /// segment is still a chain of constrained edges from its first end to its second, its
    /// pieces are equal within rounding, and the triangulation stays constrained Delaunay.
    #[test]
    fn long_segments_split_into_equal_pieces(coords in prop::collection::vec((0u32..60, 0u32..60), 4..20), pairs in prop::collection::vec((0usize..20, 0usize..20), 1..20), max_length in 0.7..9.0f64) {
        let pts: Vec<Point> = coords.iter().map(|&(x, y)| Point::new(f64::from(x), f64::from(y))).collect();
        let Ok((mut t, ids)) = Triangulation::from_points(&pts) else { return Ok(()) };
        for &(i, j) in &pairs {
            let (i, j) = (i % pts.len(), j % pts.len());
            if ids[i] != ids[j] {
                let _ = t.insert_segment(ids[i], ids[j]);
            }
        }
        let lengths: Vec<(f64, usize)> = (0..t.num_segments())
            .map(|s| {
                let chain = t.segment_vertices(imesh_geom::SegmentId(s as u32));
                let [a, b] = [chain[0], chain[chain.len() - 1]].map(|v| t.point(v));
                (a.distance_squared(b).sqrt(), chain.len() - 1)
            })
            .collect();
        t.split_long_segments(max_length).unwrap();
        t.check().unwrap();
        for e in t.constrained_edges() {
            let (a, b) = (t.point(t.origin(e)), t.point(t.destination(e)));
            prop_assert!(a.distance_squared(b).sqrt() <= max_length * (1.0 + 1e-9));
        }
        for (s, &(length, pieces_before)) in lengths.iter().enumerate() {
            let chain = t.segment_vertices(imesh_geom::SegmentId(s as u32));
            for w in chain.windows(2) {
                prop_assert!(t.find_edge(w[0], w[1]).is_some_and(|e| t.is_constrained(e)));
            }
            // A segment without vertices on it is cut into ⌈length / bound⌉ equal pieces.
            if pieces_before == 1 {
                let pieces = (length / max_length).ceil().max(1.0);
                prop_assert_eq!(chain.len() - 1, pieces as usize);
                for w in chain.windows(2) {
                    let d = t.point(w[0]).distance_squared(t.point(w[1])).sqrt();
                    prop_assert!((d - length / pieces).abs() < 1e-9 * length.max(1.0));
                }
            }
        }
    }
}
