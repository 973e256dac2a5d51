//! Polylines and topology-preserving simplification on real and random boundary graphs.

mod support;

use imesh_curves::{
    contract_short_links, fit_edges, neck_vertices, polylines, segment_distance, sharp_vertices,
    simplify, CurveError, CurveGraph, FitOptions, GraphEdge, SegmentIndex, Simplification,
    SimplifyOptions, DEFAULT_TOLERANCE,
};
use imesh_geom::Point;
use proptest::prelude::*;

/// What identifies a face independently of simplification: its label, the sign of its area,
/// and the polylines around it with the direction each is walked in.
type Signature = (u32, bool, Vec<(u32, bool)>);

fn signatures(g: &CurveGraph, direction_of: impl Fn(u32, bool) -> (u32, bool)) -> Vec<Signature> {
    let mut all: Vec<Signature> = g
        .faces()
        .into_iter()
        .map(|f| {
            let mut around: Vec<(u32, bool)> = f
                .walk
                .iter()
                .map(|&(e, fwd)| direction_of(e, fwd))
                .collect();
            around.sort_unstable();
            around.dedup();
            (f.label, f.area > 0.0, around)
        })
        .collect();
    all.sort();
    all
}

/// Checks everything the issue asks of G' against G.
fn check_simplification(g: &CurveGraph, s: &Simplification, tolerance: f64) {
    // Every edge of G in exactly one polyline, and polylines are chains of G's edges.
    let mut owner = vec![(u32::MAX, false); g.edges().len()];
    for (l, line) in s.polylines.iter().enumerate() {
        assert_eq!(line.vertices.len(), line.edges.len() + 1);
        for (i, &e) in line.edges.iter().enumerate() {
            assert_eq!(owner[e as usize].0, u32::MAX, "edge {e} in two polylines");
            let ends = g.edges()[e as usize].ends;
            let forward = ends == [line.vertices[i], line.vertices[i + 1]];
            assert!(forward || ends == [line.vertices[i + 1], line.vertices[i]]);
            owner[e as usize] = (l as u32, forward);
        }
        // Open, or a loop of three edges or more whose cuts simplification freed.
        let [a, b] = line.ends();
        assert!(
            a != b || line.edges.len() >= 3,
            "a polyline is open or a loop"
        );
    }
    assert!(
        owner.iter().all(|o| o.0 != u32::MAX),
        "every edge is in a polyline"
    );

    // G' is planar, and every removed vertex is within the tolerance of its edge.
    assert_eq!(s.graph.crossing(), None, "simplified edges cross");
    for (k, chain) in s.chains.iter().enumerate() {
        let [a, b] = s.graph.edges()[k].ends;
        assert_eq!([chain[0], chain[chain.len() - 1]], [a, b]);
        let (pa, pb) = (g.point(a), g.point(b));
        for &v in chain {
            let d = segment_distance(pa, pb, g.point(v));
            assert!(
                d <= tolerance * (1.0 + 1e-12) + 1e-12,
                "vertex {v} is {d} px from its edge"
            );
        }
    }
    assert!(s.max_deviation <= tolerance * (1.0 + 1e-12) + 1e-12);

    // The same faces with the same labels, none of zero area, labels consistent around each.
    let before = signatures(g, |e, fwd| {
        let (l, forward) = owner[e as usize];
        (l, fwd == forward)
    });
    let after = signatures(&s.graph, |e, fwd| (s.polyline_of[e as usize], fwd));
    assert_eq!(before, after, "the faces changed");
    for f in s.graph.faces() {
        assert!(f.consistent, "a face of G' has two labels");
        assert!(f.area != 0.0, "a face of G' has no area");
    }
}

/// A random planar label image: nearest-seed regions plus isolated noise pixels.
fn label_image() -> impl Strategy<Value = (u32, u32, Vec<u32>)> {
    (3u32..22, 3u32..22).prop_flat_map(|(w, h)| {
        let seeds = prop::collection::vec((0..w, 0..h, 0u32..4), 1..7);
        let noise = prop::collection::vec((0..w, 0..h, 0u32..4), 0..8);
        (Just(w), Just(h), seeds, noise).prop_map(|(w, h, seeds, noise)| {
            let mut labels = vec![0u32; (w * h) as usize];
            for r in 0..h {
                for c in 0..w {
                    let nearest = seeds
                        .iter()
                        .min_by_key(|&&(x, y, _)| {
                            let (dx, dy) =
                                (i64::from(x) - i64::from(c), i64::from(y) - i64::from(r));
                            (dx * dx + dy * dy, x, y)
                        })
                        .map_or(0, |s| s.2);
                    labels[(r * w + c) as usize] = nearest;
                }
            }
            for (x, y, l) in noise {
                labels[(y * w + x) as usize] = l;
            }
            (w, h, labels)
        })
    })
}

const TOLERANCES: [f64; 4] = [0.5, 2.0, 5.0, 15.0];

proptest! {
    /// The segment index never misses a segment within its reach of the query point.
    #[test]
    fn the_segment_index_finds_every_segment_within_reach(
        ends in prop::collection::vec((-50.0..50.0f64, -50.0..50.0f64, -50.0..50.0f64, -50.0..50.0f64), 1..40),
        queries in prop::collection::vec((-60.0..60.0f64, -60.0..60.0f64), 1..40),
        reach in 0.0..8.0f64,
    ) {
        let segments: Vec<[Point; 2]> = ends
            .iter()
            .map(|&(ax, ay, bx, by)| [Point::new(ax, ay), Point::new(bx, by)])
            .collect();
        let index = SegmentIndex::new(&segments, reach);
        for &(x, y) in &queries {
            let p = Point::new(x, y);
            let near: Vec<u32> = index.near(p).collect();
            for (k, &[a, b]) in segments.iter().enumerate() {
                if segment_distance(a, b, p) <= reach {
                    prop_assert!(near.contains(&(k as u32)), "segment {} missed at {:?}", k, p);
                }
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    #[test]
    fn pixel_boundary_graphs_keep_their_topology((w, h, labels) in label_image()) {
        let g = support::pixel_boundaries(&support::grid(w, h, labels));
        prop_assert_eq!(g.crossing(), None);
        for tolerance in TOLERANCES {
            let s = simplify(&g, &SimplifyOptions::with_tolerance(tolerance)).unwrap();
            check_simplification(&g, &s, tolerance);
        }
    }

    /// The third pass (short pieces joined) keeps the topology too, within its looser bound.
    #[test]
    fn joining_short_pieces_keeps_the_topology((w, h, labels) in label_image()) {
        let g = support::imesh_boundaries(&support::grid(w, h, labels));
        for (tolerance, min_length) in [(0.5, 2.0), (2.0, 3.0), (2.0, 8.0)] {
            let s = simplify(&g, &SimplifyOptions { tolerance, min_length }).unwrap();
            check_simplification(&g, &s, tolerance.max(0.5 * min_length));
        }
    }

    #[test]
    fn imesh_c_edge_graphs_keep_their_topology((w, h, labels) in label_image()) {
        let g = support::imesh_boundaries(&support::grid(w, h, labels));
        prop_assert_eq!(g.crossing(), None);
        for tolerance in TOLERANCES {
            let s = simplify(&g, &SimplifyOptions::with_tolerance(tolerance)).unwrap();
            check_simplification(&g, &s, tolerance);
        }
    }
}

/// A contracted graph is a valid boundary graph: planar, every face of one label and of some
/// area, the domain corners where they were, each edge one of the input's (with its ends
/// merged), and simplification keeps its topology as it does any other's.
fn check_contraction(g: &CurveGraph, min_length: f64, w: u32, h: u32) -> usize {
    let c =
        contract_short_links(g, min_length, DEFAULT_TOLERANCE, f64::from(w), f64::from(h)).unwrap();
    assert_eq!(c.graph.crossing(), None, "contracted edges cross");
    for f in c.graph.faces() {
        assert!(f.consistent, "a contracted face has two labels");
        assert!(f.area != 0.0, "a contracted face has no area");
    }
    if c.contracted == 0 {
        assert_eq!(c.graph.edges(), g.edges());
    } else {
        assert!(c.graph.edges().len() < g.edges().len());
    }
    for v in 0..g.points().len() as u32 {
        if g.is_pinned(v) && g.valence(v) > 0 {
            assert_eq!(c.graph.point(v), g.point(v), "a pinned vertex moved");
            assert!(c.graph.valence(v) > 0 && c.graph.is_pinned(v));
        }
    }
    let labels: std::collections::HashSet<[u32; 2]> = g.edges().iter().map(|e| e.labels).collect();
    assert!(c.graph.edges().iter().all(|e| labels.contains(&e.labels)));
    let s = simplify(
        &c.graph,
        &SimplifyOptions::with_tolerance(DEFAULT_TOLERANCE),
    )
    .unwrap();
    check_simplification(&c.graph, &s, DEFAULT_TOLERANCE);
    c.contracted
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    #[test]
    fn contracting_short_links_keeps_a_valid_graph(
        (w, h, labels) in label_image(), min_length in 0.5f64..4.0,
    ) {
        let g = support::imesh_boundaries(&support::grid(w, h, labels));
        check_contraction(&g, min_length, w, h);
    }
}

/// Four labels meeting at pixel corners: the stardist fixture has such places, and each
/// contraction there leaves a valid graph.
#[test]
fn links_between_junctions_at_pixel_corners_are_contracted() {
    let grid = support::fixture("stardist-mask2d_labels.png");
    let g = support::imesh_boundaries(&grid);
    let contracted = check_contraction(&g, 2.0, grid.width(), grid.height());
    assert!(contracted >= 1, "{contracted} links contracted");
}

fn edge(a: u32, b: u32, labels: [u32; 2]) -> GraphEdge {
    GraphEdge {
        ends: [a, b],
        labels,
    }
}

/// A closed loop through `points`, label 1 on its positive side.
fn loop_graph(points: Vec<Point>) -> CurveGraph {
    let n = points.len() as u32;
    let edges = (0..n).map(|i| edge(i, (i + 1) % n, [1, 0])).collect();
    CurveGraph::new(points, edges).unwrap()
}

#[test]
fn a_loop_keeps_three_vertices_and_its_area_at_any_tolerance() {
    let points = (0..40)
        .map(|i| {
            let a = f64::from(i) * std::f64::consts::TAU / 40.0;
            Point::new(3.0 * a.cos(), 3.0 * a.sin())
        })
        .collect();
    let g = loop_graph(points);
    let s = simplify(&g, &SimplifyOptions::with_tolerance(1000.0)).unwrap();
    assert_eq!(s.graph.edges().len(), 3);
    check_simplification(&g, &s, 1000.0);
    let inner = s.graph.faces().into_iter().find(|f| f.label == 1).unwrap();
    assert!(
        inner.area > 5.0,
        "the loop kept a real triangle: {}",
        inner.area
    );
}

#[test]
fn a_chord_never_jumps_over_an_island() {
    // A U-shaped curve from (0, 0) to (10, 0) dipping to y = 1, closed by a box above it (label 3
    // inside, 2 outside), with a small island (a triangle of label 4) inside the U. At
    // tolerance 5 the whole U would be one chord.
    let mut points: Vec<Point> = (0..=10)
        .map(|i| Point::new(f64::from(i), if (1..10).contains(&i) { 1.0 } else { 0.0 }))
        .collect();
    let n = points.len() as u32;
    let mut edges: Vec<GraphEdge> = (0..n - 1).map(|i| edge(i, i + 1, [2, 3])).collect();
    points.extend([
        Point::new(4.0, 0.4),
        Point::new(6.0, 0.4),
        Point::new(5.0, 0.8),
    ]);
    edges.extend([
        edge(n, n + 1, [4, 3]),
        edge(n + 1, n + 2, [4, 3]),
        edge(n + 2, n, [4, 3]),
    ]);
    points.extend([Point::new(10.0, -2.0), Point::new(0.0, -2.0)]);
    edges.extend([
        edge(n - 1, n + 3, [2, 3]),
        edge(n + 3, n + 4, [2, 3]),
        edge(n + 4, 0, [2, 3]),
    ]);
    let g = CurveGraph::new(points, edges).unwrap();
    let s = simplify(&g, &SimplifyOptions::with_tolerance(5.0)).unwrap();
    assert!(s.refused > 0, "the chord over the island was refused");
    check_simplification(&g, &s, 5.0);
}

#[test]
fn two_curves_between_the_same_ends_do_not_merge() {
    // A lens: two arcs from (0, 0) to (10, 0), one on each side, whose ends have valence 3
    // (a tail leaves each end). Simplified to chords, both arcs would be the same segment.
    let mut points = vec![Point::new(0.0, 0.0), Point::new(10.0, 0.0)];
    let mut edges = Vec::new();
    for (sign, labels) in [(1.0, [0, 1]), (-1.0, [1, 0])] {
        let mut prev = 0;
        for i in 1..10 {
            let x = f64::from(i);
            points.push(Point::new(x, sign * 0.3 * (x * (10.0 - x)).sqrt()));
            let v = points.len() as u32 - 1;
            edges.push(edge(prev, v, labels));
            prev = v;
        }
        edges.push(edge(prev, 1, labels));
    }
    points.extend([Point::new(-5.0, 0.0), Point::new(15.0, 0.0)]);
    let n = points.len() as u32;
    edges.extend([edge(n - 2, 0, [0, 0]), edge(1, n - 1, [0, 0])]);
    let g = CurveGraph::new(points, edges).unwrap();
    let s = simplify(&g, &SimplifyOptions::with_tolerance(5.0)).unwrap();
    check_simplification(&g, &s, 5.0);
    assert_eq!(polylines(&g).len(), 4);
    assert!(s.refused > 0, "the second chord was refused");
}

#[test]
fn the_domain_border_is_cut_at_the_corners() {
    let (w, h) = (6, 4);
    let g = support::pixel_boundaries(&support::grid(w, h, vec![0; 24]));
    let lines = polylines(&g);
    assert_eq!(lines.len(), 4, "one polyline per side of the domain");
    let s = simplify(&g, &SimplifyOptions::default()).unwrap();
    assert_eq!(s.graph.edges().len(), 4);
    check_simplification(&g, &s, 2.0);
}

#[test]
fn a_loop_hanging_off_a_junction_is_cut_too() {
    // A square loop 0-1-2-3 with a tail 0-4: vertex 0 has valence 3, the loop starts and ends
    // there and must still become three pieces.
    let points = vec![
        Point::new(0.0, 0.0),
        Point::new(4.0, 0.0),
        Point::new(4.0, 4.0),
        Point::new(0.0, 4.0),
        Point::new(-3.0, -3.0),
    ];
    let edges = vec![
        edge(0, 1, [1, 0]),
        edge(1, 2, [1, 0]),
        edge(2, 3, [1, 0]),
        edge(3, 0, [1, 0]),
        edge(0, 4, [0, 0]),
    ];
    let g = CurveGraph::new(points, edges).unwrap();
    let lines = polylines(&g);
    assert_eq!(lines.len(), 4);
    assert!(lines.iter().all(|l| l.ends()[0] != l.ends()[1]));
}

/// The coins fixture thresholded into `classes` labels by multi-Otsu.
fn coins(classes: usize) -> imesh_classify::LabelGrid {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures/images/skimage-coins.png");
    let image = imesh_classify::load_image(&path, imesh_classify::DEFAULT_MAX_PIXELS).unwrap();
    let grey = imesh_classify::luminance(&image);
    imesh_classify::threshold(&grey, &imesh_classify::multi_otsu_levels(&grey, classes))
}

#[test]
fn real_fixture_boundaries_simplify_with_their_topology() {
    let grid = coins(2);
    for g in [
        support::pixel_boundaries(&grid),
        support::imesh_boundaries(&grid),
    ] {
        for tolerance in TOLERANCES {
            let s = simplify(&g, &SimplifyOptions::with_tolerance(tolerance)).unwrap();
            check_simplification(&g, &s, tolerance);
            assert!(s.graph.edges().len() < g.edges().len());
        }
    }
}

/// The two sides of the image are simplified side by side: the result must not depend on how
/// many threads do it.
#[test]
fn simplification_is_the_same_on_one_and_two_threads() {
    let grid = coins(3);
    let g = support::pixel_boundaries(&grid);
    let on = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| simplify(&g, &SimplifyOptions::default()).unwrap())
    };
    let (one, two) = (on(1), on(2));
    assert!(one.refused > 0, "the fixture exercises the topology tests");
    assert_eq!(one.chains, two.chains);
    assert_eq!(one.polyline_of, two.polyline_of);
    assert_eq!(one.refused, two.refused);
    assert_eq!(one.graph.edges(), two.graph.edges());
}

/// A straight boundary drawn as a zig-zag of needles (sliver triangles of alternating labels,
/// as Imesh's c-edges can be): every sub-chord Douglas–Peucker tries ends at a needle tip and is
/// 8 px off, so it keeps the tips; the second pass sees that the whole run is within 1 px of one
/// chord and joins it.
#[test]
fn a_zig_zag_within_the_tolerance_loses_its_needles() {
    let points: Vec<Point> = [
        (149.5, 159.5),
        (143.5, 161.5),
        (142.5, 169.5),
        (142.5, 161.5),
        (141.5, 169.5),
        (143.5, 179.5),
        (160.0, 185.0),
        (160.0, 150.0),
    ]
    .into_iter()
    .map(|(x, y)| Point::new(x, y))
    .collect();
    // The zig-zag is one side of a closed region; its ends are pinned so that it is one
    // polyline.
    let edges = (0..7).map(|i| edge(i, (i + 1) % 7, [1, 0])).collect();
    let mut g = CurveGraph::new(points, edges).unwrap();
    g.pin(0).unwrap();
    g.pin(5).unwrap();
    let s = simplify(&g, &SimplifyOptions::default()).unwrap();
    check_simplification(&g, &s, DEFAULT_TOLERANCE);
    let kept: Vec<u32> = s.graph.edges().iter().flat_map(|e| e.ends).collect();
    assert!(
        !kept.contains(&2) && !kept.contains(&3),
        "needle tips kept: {kept:?}"
    );
    assert!(s.merged >= 2);
}

#[test]
fn bad_graphs_and_tolerances_are_refused_with_typed_errors() {
    let p = vec![Point::new(0.0, 0.0), Point::new(1.0, 0.0)];
    assert_eq!(
        CurveGraph::new(p.clone(), vec![edge(0, 0, [0, 1])]).unwrap_err(),
        CurveError::BadEdge {
            index: 0,
            ends: [0, 0]
        }
    );
    assert_eq!(
        CurveGraph::new(p.clone(), vec![edge(0, 7, [0, 1])]).unwrap_err(),
        CurveError::BadEdge {
            index: 0,
            ends: [0, 7]
        }
    );
    assert_eq!(
        CurveGraph::new(p.clone(), vec![edge(0, 1, [0, 1]), edge(1, 0, [1, 0])]).unwrap_err(),
        CurveError::DuplicateEdge { ends: [1, 0] }
    );
    assert_eq!(
        CurveGraph::new(vec![Point::new(f64::NAN, 0.0)], vec![]).unwrap_err(),
        CurveError::NonFinitePoint { index: 0 }
    );
    let g = CurveGraph::new(p, vec![edge(0, 1, [0, 1])]).unwrap();
    for tolerance in [-1.0, f64::NAN, f64::INFINITY] {
        assert!(matches!(
            simplify(&g, &SimplifyOptions::with_tolerance(tolerance)),
            Err(CurveError::BadTolerance { .. })
        ));
    }
    let mut g = g;
    assert_eq!(g.pin(9), Err(CurveError::BadVertex { vertex: 9 }));
}

#[test]
fn crossing_edges_are_found() {
    let points = vec![
        Point::new(0.0, 0.0),
        Point::new(2.0, 2.0),
        Point::new(0.0, 2.0),
        Point::new(2.0, 0.0),
        Point::new(1.0, 1.0),
    ];
    let g = CurveGraph::new(points.clone(), vec![edge(0, 1, [0, 1]), edge(2, 3, [0, 1])]).unwrap();
    assert_eq!(g.crossing(), Some([0, 1]));
    // A vertex on another edge (a T without a shared vertex) is a crossing too.
    let g = CurveGraph::new(points, vec![edge(0, 1, [0, 1]), edge(4, 3, [0, 1])]).unwrap();
    assert_eq!(g.crossing(), Some([0, 1]));
}

#[test]
fn fitted_curves_join_the_simplified_vertices_within_the_tolerance() {
    let grid = coins(3);
    let g = support::imesh_boundaries(&grid);
    for tolerance in [0.5, 2.0, 5.0] {
        let s = simplify(&g, &SimplifyOptions::with_tolerance(tolerance)).unwrap();
        let report = fit_edges(&s, &g, &FitOptions::default());
        assert_eq!(report.fits.len(), s.graph.edges().len());
        for (fit, e) in report.fits.iter().zip(s.graph.edges()) {
            assert_eq!(fit.curve.control[0], g.point(e.ends[0]));
            assert_eq!(fit.curve.control[3], g.point(e.ends[1]));
            // Never worse than the simplified edge itself.
            assert!(
                fit.max_error <= tolerance + 1e-9,
                "{} > {tolerance}",
                fit.max_error
            );
        }
        assert!(report.rms_error <= report.max_error);
        // Curved boundaries: the cubics are closer to the chains than the straight edges.
        let straight_rms = rms_to_edges(&g, &s);
        assert!(
            report.rms_error < straight_rms,
            "{} vs {straight_rms}",
            report.rms_error
        );
    }
}

fn rms_to_edges(g: &CurveGraph, s: &Simplification) -> f64 {
    let (mut sum, mut count) = (0.0, 0usize);
    for chain in &s.chains {
        let (a, b) = (g.point(chain[0]), g.point(chain[chain.len() - 1]));
        for &v in chain {
            let d = segment_distance(a, b, g.point(v));
            sum += d * d;
            count += 1;
        }
    }
    (sum / count as f64).sqrt()
}

/// A short piece between two long ones loses an inner end when the joined chord stays within
/// half the smallest length of the original vertices, and keeps it when it would not.
#[test]
fn a_short_piece_is_joined_with_a_neighbour() {
    let points = vec![
        Point::new(0.0, 0.0),
        Point::new(10.0, 0.0),
        Point::new(11.0, 2.0),
        Point::new(21.0, 2.0),
    ];
    let edges = (0..3u32).map(|i| edge(i, i + 1, [1, 2])).collect();
    let g = CurveGraph::new(points, edges).unwrap();
    let run = |min_length: f64| {
        simplify(
            &g,
            &SimplifyOptions {
                tolerance: 0.5,
                min_length,
            },
        )
        .unwrap()
    };
    // Douglas–Peucker alone keeps both bends (each 1.79 px off the other chords).
    assert_eq!(run(0.0).graph.edges().len(), 3);
    // A 2.24 px piece under 3 px, but joining it moves the boundary 1.79 > 1.5 px: kept.
    assert_eq!(run(3.0).graph.edges().len(), 3);
    // Under 4 px it may move the boundary 2 px: joined, both ends of the polyline kept.
    let s = run(4.0);
    assert_eq!(s.graph.edges().len(), 2);
    assert!((s.max_deviation - 20.0 / 125f64.sqrt()).abs() < 1e-9);
    let ends: Vec<[u32; 2]> = s.graph.edges().iter().map(|e| e.ends).collect();
    assert!(ends.iter().any(|e| e.contains(&0)) && ends.iter().any(|e| e.contains(&3)));
}

/// Simplifies `g` at each `(tolerance, parameter)` of `runs` and pins the vertices `pick`
/// chooses there: each must be an inner vertex of a chain, not yet in G'; pinned, the graph
/// simplifies again with its topology kept, and each of them is a vertex of the new G'.
fn pinned_vertices_keep_the_topology(
    mut g: CurveGraph,
    runs: [(f64, f64); 3],
    pick: impl Fn(&CurveGraph, &Simplification, f64) -> Vec<u32>,
) -> Result<(), TestCaseError> {
    for (tolerance, parameter) in runs {
        let options = SimplifyOptions::with_tolerance(tolerance);
        let s = simplify(&g, &options).unwrap();
        let picked = pick(&g, &s, parameter);
        for &v in &picked {
            let inner = s
                .chains
                .iter()
                .any(|c| c.len() > 2 && c[1..c.len() - 1].contains(&v));
            prop_assert!(inner, "vertex {} is not inside a chain", v);
            prop_assert!(s.graph.valence(v) == 0, "vertex {} is already in G'", v);
        }
        for &v in &picked {
            g.pin(v).unwrap();
        }
        let again = simplify(&g, &options).unwrap();
        check_simplification(&g, &again, tolerance);
        for &v in &picked {
            prop_assert!(again.graph.valence(v) > 0, "pinned vertex {} left G'", v);
        }
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    /// The vertices kept at necks (chain vertices of G' edges that pass near another G'
    /// vertex, farther from it than the edge) keep the topology.
    #[test]
    fn vertices_kept_at_necks_keep_the_topology((w, h, labels) in label_image()) {
        let g = support::imesh_boundaries(&support::grid(w, h, labels));
        pinned_vertices_keep_the_topology(g, [(1.0, 0.5), (2.0, 1.0), (3.0, 2.0)], neck_vertices)?;
    }

    /// So do the vertices kept at sharp sectors.
    #[test]
    fn vertices_kept_at_sharp_sectors_keep_the_topology((w, h, labels) in label_image()) {
        let g = support::imesh_boundaries(&support::grid(w, h, labels));
        pinned_vertices_keep_the_topology(g, [(1.0, 1.0), (2.0, 2.0), (3.0, 3.0)], sharp_vertices)?;
    }
}

/// A spike whose sides run straight from its tip is as sharp in the image as in G': nothing
/// to keep. One whose sides leave the tip wider and then run parallel keeps a vertex.
#[test]
fn a_sharp_sector_is_widened_only_where_the_boundary_is_wider() {
    let p = Point::new;
    let spike = |side: [Point; 2]| -> Result<Vec<u32>, imesh_curves::CurveError> {
        // The tip 0, a side 0–1–2 and its mirror 0–3–4, closed by 2–4.
        let mirror = |q: Point| p(q.x, -q.y);
        let points = vec![
            p(0.0, 0.0),
            side[0],
            side[1],
            mirror(side[0]),
            mirror(side[1]),
        ];
        let edges = vec![
            edge(0, 1, [1, 0]),
            edge(1, 2, [1, 0]),
            edge(2, 4, [1, 0]),
            edge(4, 3, [1, 0]),
            edge(3, 0, [1, 0]),
        ];
        let mut g = CurveGraph::new(points, edges)?;
        g.pin(0)?;
        let s = simplify(&g, &SimplifyOptions::with_tolerance(1.5))?;
        Ok(sharp_vertices(&g, &s, 2.0))
    };
    // Straight sides 10° apart: the chords are the boundary.
    let a = 5f64.to_radians();
    let straight = [
        p(10.0 * a.cos(), 10.0 * a.sin()),
        p(30.0 * a.cos(), 30.0 * a.sin()),
    ];
    assert!(spike(straight).unwrap().is_empty());
    // A blunt tip: sides leave 37° apart, then run 2 px apart.
    assert!(!spike([p(3.0, 1.0), p(30.0, 1.0)]).unwrap().is_empty());
}

/// A thin wedge at a junction: an edge whose chord passes 0.2 px from the far end of another
/// edge leaving the same vertex 2.3° away is a neck; 60° away it is an ordinary junction.
#[test]
fn a_thin_wedge_at_a_junction_is_a_neck() {
    // Edge 0–1–2–3 (simplified at 1.5 px to its chord, 5.7° above the x axis); the edge 0–4 to
    // a junction 4, whose stem 4–5 leaves on the side away from the chord.
    let necks = |far: Point, stem: Point| -> Result<Vec<u32>, imesh_curves::CurveError> {
        let p = Point::new;
        let points = vec![
            p(0.0, 0.0),
            p(4.0, 1.6),
            p(10.0, 1.2),
            p(20.0, 2.0),
            far,
            stem,
        ];
        let edges = vec![
            edge(0, 1, [1, 0]),
            edge(1, 2, [1, 0]),
            edge(2, 3, [1, 0]),
            edge(0, 4, [2, 1]),
            edge(4, 5, [2, 3]),
        ];
        let g = CurveGraph::new(points, edges)?;
        let s = simplify(&g, &SimplifyOptions::with_tolerance(1.5))?;
        assert!(s.chains.contains(&vec![0, 1, 2, 3]));
        Ok(neck_vertices(&g, &s, 0.5))
    };
    // 3.4° above the x axis, 2.3° below the chord, 0.2 px from it: the chord's chain keeps the
    // vertex nearest the junction.
    let far = Point::new(5.0, 0.3);
    assert_eq!(necks(far, Point::new(5.0, -4.7)).unwrap(), [1]);
    // 60° above the chord, 0.22 px from it: an ordinary junction.
    let a = 65.7f64.to_radians();
    let far = Point::new(0.25 * a.cos(), 0.25 * a.sin());
    assert!(necks(far, Point::new(far.x, far.y + 5.0))
        .unwrap()
        .is_empty());
}

/// `g` simplified at `tolerance` with pieces of at least `min_length`, checked against `g`.
fn checked_simplify(g: &CurveGraph, tolerance: f64, min_length: f64) -> Simplification {
    let options = SimplifyOptions {
        tolerance,
        min_length,
    };
    let s = simplify(g, &options).unwrap();
    check_simplification(g, &s, tolerance.max(0.5 * min_length));
    s
}

#[test]
fn a_loop_s_cuts_beside_short_pieces_are_freed() {
    // Coins' island near pixel (40, 264) as its pixel-boundary loop (shifted to the origin).
    // Its thirds cut it at vertices 1 (the start), 5 and 9, and Douglas–Peucker keeps 0, 4 and
    // 8 (the tip of a 2.5 px spike) besides: six vertices, pieces of 3–4.1 px. With pieces of
    // at least 3.5 px asked for, the cuts at 5 and 9 go (the start stays), and the island is
    // the quadrilateral 0, 1, 4, 8.
    let corners = [
        (8.0, 1.0),
        (4.0, 0.0),
        (2.0, 4.0),
        (2.0, 5.0),
        (0.0, 6.0),
        (4.0, 7.0),
        (6.0, 7.0),
        (6.0, 6.0),
        (7.0, 8.0),
        (7.0, 5.0),
        (6.0, 4.0),
        (7.0, 3.0),
    ];
    let g = loop_graph(corners.iter().map(|&(x, y)| Point::new(x, y)).collect());
    let run = |min_length: f64| {
        let s = checked_simplify(&g, 2.0, min_length);
        let kept: Vec<u32> = (0..corners.len() as u32)
            .filter(|&v| s.graph.valence(v) > 0)
            .collect();
        (s, kept)
    };
    assert_eq!(run(0.0).1, [0, 1, 4, 5, 8, 9]);
    // Pieces of at least 3 px: none is shorter, nothing is freed.
    assert_eq!(run(3.0).1, [0, 1, 4, 5, 8, 9]);
    let (s, kept) = run(3.5);
    assert_eq!(kept, [0, 1, 4, 8]);
    assert_eq!(s.polylines.len(), 1, "the three pieces are one closed line");
    assert_eq!(s.polylines[0].ends(), [1, 1]);
    assert_eq!(s.merged, 2);
    // Only the start is pinned now.
    assert!(s.graph.is_pinned(1) && !s.graph.is_pinned(5) && !s.graph.is_pinned(9));

    // Three such islands side by side: each loses the same two cuts.
    let n = corners.len() as u32;
    let mut points = Vec::new();
    let mut edges = Vec::new();
    for island in 0..3u32 {
        let dx = 20.0 * f64::from(island);
        points.extend(corners.iter().map(|&(x, y)| Point::new(x + dx, y)));
        edges.extend((0..n).map(|i| edge(island * n + i, island * n + (i + 1) % n, [1, 0])));
    }
    let g = CurveGraph::new(points, edges).unwrap();
    let s = checked_simplify(&g, 2.0, 3.5);
    let kept: Vec<u32> = (0..3 * n).filter(|&v| s.graph.valence(v) > 0).collect();
    let expected: Vec<u32> = (0..3)
        .flat_map(|island| [0, 1, 4, 8].map(|v| island * n + v))
        .collect();
    assert_eq!(kept, expected);
    assert_eq!(s.polylines.len(), 3);
}

#[test]
fn a_hanging_loop_keeps_its_junction_when_a_cut_is_freed() {
    // A 4 px square with a vertex in the middle of each side, hanging off a tail at (0, 0).
    // Its thirds cut it at (4, 2) and (0, 4); Douglas–Peucker drops the other midpoints. The
    // cut at (4, 2) has 2 px pieces on both sides, under the 2.5 px asked for: it goes, and the
    // square keeps its four corners. The one at (0, 4) has 4 px pieces: it stays.
    let points = vec![
        Point::new(0.0, 0.0),
        Point::new(2.0, 0.0),
        Point::new(4.0, 0.0),
        Point::new(4.0, 2.0),
        Point::new(4.0, 4.0),
        Point::new(2.0, 4.0),
        Point::new(0.0, 4.0),
        Point::new(0.0, 2.0),
        Point::new(-3.0, -3.0),
    ];
    let mut edges: Vec<GraphEdge> = (0..8u32).map(|i| edge(i, (i + 1) % 8, [1, 0])).collect();
    edges.push(edge(0, 8, [0, 0]));
    let g = CurveGraph::new(points, edges).unwrap();
    let s = checked_simplify(&g, 0.5, 0.0);
    assert!(s.graph.valence(3) == 2 && s.graph.is_pinned(3));
    let s = checked_simplify(&g, 0.5, 2.5);
    let kept: Vec<u32> = (0..9).filter(|&v| s.graph.valence(v) > 0).collect();
    assert_eq!(kept, [0, 2, 4, 6, 8]);
    assert_eq!(s.polylines.len(), 3, "the tail and the square's two lines");
    assert!(s.graph.is_pinned(0) && s.graph.is_pinned(6));
    assert!(s.polylines.iter().all(|l| l.ends()[0] != l.ends()[1]));
}
