//! Constrained and conforming Delaunay triangulations, and region labels.

use imesh_geom::predicates::incircle;
use imesh_geom::{GeomError, Point, RefineOptions, SegmentId, Triangulation, VertexId, EXTERIOR};
use proptest::prelude::*;

mod common;
use common::{centroid, inside, star};

/// Every segment is exactly the chain of constrained edges through its vertices, which lie on it
/// (exactly for constrained segments, within rounding for conforming Steiner points).
fn assert_segments_are_edge_chains(t: &Triangulation) {
    let mut pieces = 0;
    for s in 0..t.num_segments() {
        let id = imesh_geom::SegmentId(s as u32);
        let [a, b] = t.segment_ends(id);
        let chain = t.segment_vertices(id);
        assert_eq!((chain[0], *chain.last().unwrap()), (a, b));
        let (pa, pb) = (t.point(a), t.point(b));
        let len = pa.distance_squared(pb).sqrt();
        for &v in &chain {
            let p = t.point(v);
            let off = ((pb.x - pa.x) * (p.y - pa.y) - (pb.y - pa.y) * (p.x - pa.x)).abs() / len;
            assert!(
                off < 1e-9 * len.max(1.0),
                "segment {s}: vertex {v:?} is {off} off the segment"
            );
        }
        for w in chain.windows(2) {
            let e = t
                .find_edge(w[0], w[1])
                .unwrap_or_else(|| panic!("segment {s}: no edge {:?}-{:?}", w[0], w[1]));
            assert_eq!(
                t.segment_of(e),
                Some(id),
                "segment {s}: edge {:?}-{:?}",
                w[0],
                w[1]
            );
        }
        pieces += chain.len() - 1;
    }
    // And nothing else is constrained.
    assert_eq!(t.constrained_edges().count(), pieces);
}

fn assert_globally_delaunay(t: &Triangulation) {
    for f in t.triangles() {
        let [a, b, c] = t.triangle_points(f);
        for v in t.vertices() {
            assert!(incircle(a, b, c, t.point(v)) <= 0.0);
        }
    }
}

/// A planar segment soup: edges of the Delaunay triangulation of a subset of the points.
fn soup() -> impl Strategy<Value = (Vec<Point>, Vec<(usize, usize)>)> {
    (
        prop::collection::vec((0i32..16, 0i32..16), 6..60),
        prop::collection::vec(any::<bool>(), 60),
        prop::collection::vec(any::<bool>(), 200),
    )
        .prop_map(|(xy, in_subset, keep)| {
            let pts: Vec<Point> = xy
                .iter()
                .map(|&(x, y)| Point::new(f64::from(x), f64::from(y)))
                .collect();
            let subset: Vec<usize> = (0..pts.len()).filter(|&i| in_subset[i]).collect();
            let sub_pts: Vec<Point> = subset.iter().map(|&i| pts[i]).collect();
            let mut segs = Vec::new();
            if let Ok((sub, ids)) = Triangulation::from_points(&sub_pts) {
                let first: Vec<usize> = (0..sub.num_vertices())
                    .map(|v| ids.iter().position(|id| id.index() == v).unwrap())
                    .collect();
                for (k, e) in sub.edges().enumerate() {
                    if keep[k % keep.len()] {
                        segs.push((
                            subset[first[sub.origin(e).index()]],
                            subset[first[sub.destination(e).index()]],
                        ));
                    }
                }
            }
            (pts, segs)
        })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(150))]

    #[test]
    fn constrained_delaunay_of_planar_soups((pts, segs) in soup()) {
        let (mut t, ids) = Triangulation::from_points(&pts).unwrap();
        prop_assume!(!t.is_degenerate() && segs.len() >= 3);
        for &(a, b) in &segs {
            if ids[a] != ids[b] {
                t.insert_segment(ids[a], ids[b]).unwrap();
            }
        }
        t.check().unwrap();
        assert_segments_are_edge_chains(&t);
        // Later insertions keep every segment (splitting it where a point falls on it).
        for &p in pts.iter().take(10) {
            t.insert(Point::new(p.x + 0.5, p.y + 0.25)).unwrap();
            t.insert(p.midpoint(Point::new(p.x + 1.0, p.y))).unwrap();
        }
        t.check().unwrap();
    }

    #[test]
    fn conforming_delaunay_of_planar_soups((pts, segs) in soup()) {
        let (mut t, ids) = Triangulation::from_points(&pts).unwrap();
        prop_assume!(!t.is_degenerate() && segs.len() >= 3);
        for &(a, b) in &segs {
            if ids[a] != ids[b] {
                t.insert_segment_conforming(ids[a], ids[b]).unwrap();
            }
        }
        t.check().unwrap();
        assert_segments_are_edge_chains(&t);
        assert_globally_delaunay(&t);
    }
}

#[test]
fn crossing_segments_are_an_error_naming_both() {
    let pts = [
        Point::new(0.0, 0.0),
        Point::new(4.0, 0.0),
        Point::new(4.0, 4.0),
        Point::new(0.0, 4.0),
    ];
    let (mut t, v) = Triangulation::from_points(&pts).unwrap();
    t.insert_segment(v[0], v[2]).unwrap();
    let e = t.insert_segment(v[1], v[3]).unwrap_err();
    assert_eq!(
        e,
        GeomError::CrossingSegments {
            new: [1, 3],
            existing: [0, 2],
            existing_id: 0
        }
    );
    assert!(e.to_string().contains("crosses"));
    t.check().unwrap();
    assert!(matches!(
        t.insert_segment(v[0], v[0]),
        Err(GeomError::BadSegment { .. })
    ));
    assert!(matches!(
        t.insert_segment(v[0], VertexId::new(99)),
        Err(GeomError::BadSegment { .. })
    ));
}

#[test]
fn a_vertex_on_a_segment_splits_it() {
    let pts = [
        Point::new(0.0, 0.0),
        Point::new(4.0, 0.0),
        Point::new(2.0, 0.0),
        Point::new(2.0, 3.0),
        Point::new(2.0, -3.0),
    ];
    let (mut t, v) = Triangulation::from_points(&pts).unwrap();
    let s = t.insert_segment(v[0], v[1]).unwrap();
    assert_eq!(t.segment_of(t.find_edge(v[0], v[2]).unwrap()), Some(s));
    assert_eq!(t.segment_of(t.find_edge(v[2], v[1]).unwrap()), Some(s));
    // A point inserted later on a segment splits it too.
    let m = t.insert(Point::new(1.0, 0.0)).unwrap();
    assert_eq!(t.segment_of(t.find_edge(v[0], m).unwrap()), Some(s));
    assert_eq!(t.segment_of(t.find_edge(m, v[2]).unwrap()), Some(s));
    t.check().unwrap();
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(60))]

    #[test]
    fn labels_of_a_polygon_with_a_hole_survive_insertions(outer in prop::collection::vec(6.0f64..10.0, 5..20), hole in prop::collection::vec(1.0f64..3.0, 3..10), extra in prop::collection::vec((-10.0f64..10.0, -10.0f64..10.0), 0..40)) {
        let c = Point::new(0.0, 0.0);
        let (po, ph) = (star(c, &outer), star(c, &hole));
        let mut pts = po.clone();
        pts.extend(&ph);
        let (mut t, ids) = Triangulation::from_points(&pts).unwrap();
        let ring = |t: &mut Triangulation, first: usize, n: usize| {
            for i in 0..n {
                t.insert_segment(ids[first + i], ids[first + (i + 1) % n]).unwrap();
            }
        };
        ring(&mut t, 0, po.len());
        ring(&mut t, po.len(), ph.len());
        // Seed the annulus at the midpoint of an outer vertex and the hole vertex nearest it.
        let seed = po[0].midpoint(Point::new(hole[0], 0.0));
        t.label_regions(&[(seed, 5)]);
        let expect = |p: Point| if inside(&po, p) && !inside(&ph, p) { 5 } else { EXTERIOR };
        for &(x, y) in &extra {
            t.insert(Point::new(x, y)).unwrap();
        }
        t.check().unwrap();
        for f in t.triangles() {
            prop_assert_eq!(t.label(f), expect(centroid(&t, f)));
        }
    }
}

#[test]
fn a_refused_segment_leaves_nothing_behind() {
    // The new segment runs through vertex 4 before it would cross segment 0–2: the piece up to
    // vertex 4 must not stay constrained when the whole segment is refused.
    let pts = [
        Point::new(0.0, 0.0),
        Point::new(8.0, 0.0),
        Point::new(8.0, 8.0),
        Point::new(0.0, 8.0),
        Point::new(6.0, 2.0),
    ];
    let (mut t, v) = Triangulation::from_points(&pts).unwrap();
    t.insert_segment(v[0], v[2]).unwrap();
    let before = t.constrained_edges().count();
    let e = t.insert_segment(v[1], v[3]).unwrap_err();
    assert!(matches!(
        e,
        GeomError::CrossingSegments { existing_id: 0, .. }
    ));
    assert_eq!(t.constrained_edges().count(), before);
    assert_eq!(t.num_segments(), 1);
    t.check().unwrap();
}

/// A segment given twice (either way round, either mode) is one segment: refinement that splits
/// it keeps one chain up to date. Twice-given segments left a stale second chain before
/// (found by `cargo fuzz run refine`; fuzz/regressions/refine).
#[test]
fn a_segment_given_twice_is_one_segment() {
    let pts = [
        Point::new(0.0, 31.0),
        Point::new(4.0, 1.0),
        Point::new(16.0, 29.0),
    ];
    for conforming in [false, true] {
        let (mut t, v) = Triangulation::from_points(&pts).unwrap();
        let insert = |t: &mut Triangulation, a: usize, b: usize| {
            if conforming {
                t.insert_segment_conforming(v[a], v[b]).map(|_| ()).unwrap();
            } else {
                t.insert_segment(v[a], v[b]).unwrap();
            }
        };
        insert(&mut t, 0, 1);
        insert(&mut t, 1, 0);
        insert(&mut t, 0, 1);
        insert(&mut t, 1, 2);
        insert(&mut t, 2, 0);
        assert_eq!(t.num_segments(), 3, "conforming {conforming}");
        if !conforming {
            assert_eq!(t.insert_segment(v[1], v[0]).unwrap(), SegmentId(0));
        }
        t.label_regions(&[(Point::new(6.0, 20.0), 1)]);
        t.refine(&RefineOptions {
            min_angle_deg: 30.0,
            max_steiner: 500,
            max_area: Some(4.0),
        })
        .unwrap();
        t.check().unwrap();
        assert_segments_are_edge_chains(&t);
        for s in 0..t.num_segments() {
            let chain = t.segment_vertices(SegmentId(s as u32));
            assert!(chain.len() > 2, "segment {s} was split");
        }
    }
}

/// A conforming segment that runs along part of an earlier one is refused before anything
/// changes (it used to be registered first, leaving a segment without edges behind).
#[test]
fn an_overlapping_conforming_segment_changes_nothing() {
    let pts = [
        Point::new(1.0, 0.0),
        Point::new(1.0, 1.0),
        Point::new(1.0, 29.0),
        Point::new(9.0, 12.0),
    ];
    let (mut t, v) = Triangulation::from_points(&pts).unwrap();
    t.insert_segment_conforming(v[1], v[2]).unwrap();
    let (vertices, triangles) = (t.num_vertices(), t.num_triangles());
    let err = t.insert_segment_conforming(v[0], v[2]).unwrap_err();
    assert!(
        matches!(err, GeomError::CrossingSegments { existing_id: 0, .. }),
        "{err}"
    );
    assert_eq!(t.num_segments(), 1);
    assert_eq!((t.num_vertices(), t.num_triangles()), (vertices, triangles));
    t.check().unwrap();
    // The part that does not overlap is a segment of its own.
    t.insert_segment_conforming(v[0], v[1]).unwrap();
    assert_eq!(t.num_segments(), 2);
    t.check().unwrap();
}

/// Conforming segments may not cross either: their crossing is rarely representable, and
/// splitting towards it used to end in "too short to split" with the earlier segment's pieces
/// left unconstrained (found by `cargo fuzz run refine`; fuzz/regressions/refine).
#[test]
fn crossing_conforming_segments_are_an_error_and_change_nothing() {
    let pts = [
        Point::new(1.0, 0.0),
        Point::new(0.0, 27.0),
        Point::new(31.0, 31.0),
        Point::new(27.0, 0.0),
    ];
    let (mut t, v) = Triangulation::from_points(&pts).unwrap();
    t.insert_segment_conforming(v[3], v[1]).unwrap();
    let (vertices, triangles) = (t.num_vertices(), t.num_triangles());
    let err = t.insert_segment_conforming(v[2], v[0]).unwrap_err();
    assert!(
        matches!(err, GeomError::CrossingSegments { existing_id: 0, .. }),
        "{err}"
    );
    assert!(err.to_string().contains("crosses segment 0"), "{err}");
    assert_eq!(t.num_segments(), 1);
    assert_eq!((t.num_vertices(), t.num_triangles()), (vertices, triangles));
    t.check().unwrap();
    assert_segments_are_edge_chains(&t);
}
