//! Imesh on synthetic label grids with known shapes: termination, labels, c-edges, faithfulness,
//! mesh invariants, determinism.

use std::collections::HashMap;

use imesh_classify::{LabelGrid, Region};
use imesh_geom::{RefineOptions, StopReason, TriangleId, Triangulation};
use imesh_quality::{validate, Domain, Element, MeshView};
use imesh_segment::{
    sample, SampleOptions, SegmentError, SegmentedMesh, DEFAULT_MIN_ANGLE, OUTSIDE,
};
use proptest::prelude::*;

fn grid(w: u32, h: u32, labels: usize, f: impl Fn(u32, u32) -> u32) -> LabelGrid {
    let cells = (0..h)
        .flat_map(|r| (0..w).map(move |c| (c, r)))
        .map(|(c, r)| f(c, r))
        .collect();
    let regions = (0..labels)
        .map(|i| Region {
            name: format!("label {i}"),
            colour: [(40 * i) as u8; 3],
        })
        .collect();
    LabelGrid::new(w, h, cells, regions).unwrap()
}

fn dist(c: u32, r: u32, x: f64, y: f64) -> f64 {
    (f64::from(c) + 0.5 - x).hypot(f64::from(r) + 0.5 - y)
}

fn disk() -> LabelGrid {
    grid(64, 64, 2, |c, r| u32::from(dist(c, r, 31.3, 33.7) < 20.0))
}

/// Two blobs that touch, the first with a hole.
fn blobs_with_hole() -> LabelGrid {
    grid(64, 48, 3, |c, r| {
        if dist(c, r, 20.0, 24.0) < 5.0 {
            0
        } else if dist(c, r, 20.0, 24.0) < 14.0 {
            1
        } else if dist(c, r, 44.0, 24.0) < 11.0 {
            2
        } else {
            0
        }
    })
}

/// A thin curved band, 3 pixels wide.
fn thin_band() -> LabelGrid {
    grid(64, 64, 2, |c, r| {
        u32::from((dist(c, r, 0.0, 64.0) - 40.0).abs() < 1.5)
    })
}

/// Four quadrants of a checkerboard meeting at one corner.
fn checkerboard_corner() -> LabelGrid {
    grid(32, 32, 2, |c, r| (c / 16 + r / 16) % 2)
}

fn shapes() -> Vec<(&'static str, LabelGrid)> {
    vec![
        ("disk", disk()),
        ("blobs with hole", blobs_with_hole()),
        ("thin band", thin_band()),
        ("checkerboard corner", checkerboard_corner()),
        ("single label", grid(16, 16, 1, |_, _| 0)),
        ("1×1", grid(1, 1, 1, |_, _| 0)),
    ]
}

/// The mesh invariants of DESIGN.md §3, by the shared validator.
fn assert_valid(name: &str, m: &SegmentedMesh, labels: usize) {
    m.triangulation
        .check()
        .unwrap_or_else(|e| panic!("{name}: {e}"));
    let (vertices, triangles, label) = m.arrays();
    let elements: Vec<Element> = triangles.iter().map(|&t| Element::Triangle(t)).collect();
    let report = validate(
        &MeshView {
            vertices: &vertices,
            elements: &elements,
            labels: &label,
        },
        &Domain::image(f64::from(m.width), f64::from(m.height)),
    );
    assert!(report.is_valid(), "{name}: {report:?}");
    assert!(
        label.iter().all(|&l| (l as usize) < labels),
        "{name}: a triangle without a label"
    );
}

/// No c-edge ends in the open: every vertex of the c-edge graph has at least two c-edges (curves
/// close, or run into other curves or the border, which is itself made of c-edges).
fn assert_c_edges_close(name: &str, m: &SegmentedMesh) {
    let mut degree: HashMap<u32, usize> = HashMap::new();
    for e in &m.c_edges {
        assert_ne!(
            e.labels[0], e.labels[1],
            "{name}: a c-edge between equal labels"
        );
        for v in e.vertices {
            *degree.entry(v.index() as u32).or_default() += 1;
        }
    }
    assert!(
        degree.values().all(|&d| d >= 2),
        "{name}: a c-edge has a dangling end"
    );
    // The border is all c-edges, with OUTSIDE on one side.
    let border = m
        .c_edges
        .iter()
        .filter(|e| e.labels.contains(&OUTSIDE))
        .count();
    assert_eq!(border, m.triangulation.num_hull_edges(), "{name}");
}

#[test]
fn every_shape_gives_a_valid_labelled_partition() {
    for (name, g) in shapes() {
        let m = SegmentedMesh::from_grid(&g, &SampleOptions::default()).unwrap();
        assert_eq!(m.triangulation.num_vertices(), 4 + m.inserted, "{name}");
        assert_valid(name, &m, g.num_labels());
        assert_c_edges_close(name, &m);
        let agreement = m.label_agreement(&g);
        assert!(agreement > 0.85, "{name}: agreement {agreement}");
    }
}

/// Every region that touches the border reaches it: each border c-edge carries the label of
/// every border pixel along it (no strip of another label half a pixel wide in between).
#[test]
fn regions_reach_the_border() {
    let halves = grid(16, 12, 2, |c, _| u32::from(c >= 9));
    for (name, g) in shapes().into_iter().chain([("halves", halves)]) {
        let m = SegmentedMesh::from_grid(&g, &SampleOptions::default()).unwrap();
        let (w, h) = (f64::from(g.width()), f64::from(g.height()));
        let mut along = 0.0;
        for e in m.c_edges.iter().filter(|e| e.labels.contains(&OUTSIDE)) {
            let region = if e.labels[0] == OUTSIDE {
                e.labels[1]
            } else {
                e.labels[0]
            };
            let [a, b] = e.vertices.map(|v| m.triangulation.point(v));
            // The border pixels under the edge: their centres' projections lie between its ends.
            let pixels: Vec<(u32, u32)> = if a.y == b.y {
                let r = if a.y == 0.0 { 0 } else { g.height() - 1 };
                let (x0, x1) = (a.x.min(b.x), a.x.max(b.x));
                (0..g.width())
                    .filter(|&c| (x0..=x1).contains(&(f64::from(c) + 0.5)))
                    .map(|c| (c, r))
                    .collect()
            } else {
                assert_eq!(a.x, b.x, "{name}: a border c-edge off the border");
                let c = if a.x == 0.0 { 0 } else { g.width() - 1 };
                let (y0, y1) = (a.y.min(b.y), a.y.max(b.y));
                (0..g.height())
                    .filter(|&r| (y0..=y1).contains(&(f64::from(r) + 0.5)))
                    .map(|r| (c, r))
                    .collect()
            };
            for (c, r) in pixels {
                assert_eq!(
                    g.label(c, r),
                    region,
                    "{name}: border pixel ({c}, {r}) is {} but its border c-edge {a:?}–{b:?} is {region}",
                    g.label(c, r)
                );
            }
            along += a.distance_squared(b).sqrt();
        }
        assert_eq!(
            along,
            2.0 * (w + h),
            "{name}: the border c-edges cover the border"
        );
    }
}

#[test]
fn a_single_label_image_needs_no_vertex() {
    for g in [
        grid(16, 16, 1, |_, _| 0),
        grid(1, 1, 1, |_, _| 0),
        grid(7, 1, 1, |_, _| 0),
    ] {
        let m = SegmentedMesh::from_grid(&g, &SampleOptions::default()).unwrap();
        assert_eq!(m.inserted, 0);
        assert_eq!(m.label_agreement(&g), 1.0);
    }
}

#[test]
fn the_disk_is_followed_closely_at_the_default_threshold() {
    let g = disk();
    let m = SegmentedMesh::from_grid(&g, &SampleOptions::default()).unwrap();
    let agreement = m.label_agreement(&g);
    assert!(agreement >= 0.97, "agreement {agreement}");
}

#[test]
fn a_smaller_threshold_gives_more_vertices_and_higher_agreement() {
    let g = disk();
    let mut last = (0usize, 0.0f64);
    for te in [0.4, 0.2, 0.1, 0.05] {
        let m = SegmentedMesh::from_grid(
            &g,
            &SampleOptions {
                te,
                ..Default::default()
            },
        )
        .unwrap();
        let agreement = m.label_agreement(&g);
        assert!(
            m.inserted > last.0,
            "t_e {te}: {} vertices after {}",
            m.inserted,
            last.0
        );
        assert!(
            agreement >= last.1,
            "t_e {te}: agreement {agreement} after {}",
            last.1
        );
        last = (m.inserted, agreement);
    }
}

/// The smallest angle of a triangle and whether it lies between two constrained edges (an angle
/// between c-edges, which refinement cannot widen), or the triangle's shortest edge joins two
/// points on c-edges (it spans such an angle).
fn smallest_angle(t: &Triangulation, f: TriangleId) -> (f64, bool) {
    let p = t.triangle_points(f);
    let e = t.triangle_edges(f);
    let mut best = (f64::INFINITY, 0);
    for k in 0..3 {
        let (o, u, w) = (p[k], p[(k + 1) % 3], p[(k + 2) % 3]);
        let (a, b) = (u - o, w - o);
        let angle = (a.x * b.y - a.y * b.x)
            .abs()
            .atan2(a.x * b.x + a.y * b.y)
            .to_degrees();
        if angle < best.0 {
            best = (angle, k);
        }
    }
    let k = best.1;
    let at_input = t.is_constrained(e[k]) && t.is_constrained(e[(k + 2) % 3]);
    let on_segments = |v: imesh_geom::VertexId| {
        t.vertex_triangles(v)
            .flat_map(|g| t.triangle_edges(g))
            .any(|h| t.is_constrained(h) && (t.origin(h) == v || t.destination(h) == v))
    };
    let opposite = e[(k + 1) % 3];
    let spans = on_segments(t.origin(opposite)) && on_segments(t.destination(opposite));
    (best.0, at_input || spans)
}

#[test]
fn the_imesh_triangle_output_is_valid_and_well_shaped() {
    for (name, g) in shapes() {
        let mut m = SegmentedMesh::from_grid(&g, &SampleOptions::default()).unwrap();
        let before = m.label_agreement(&g);
        let report = m
            .refine(&RefineOptions {
                min_angle_deg: DEFAULT_MIN_ANGLE,
                max_steiner: 200_000,
                ..Default::default()
            })
            .unwrap();
        assert_eq!(report.stopped, StopReason::Done, "{name}");
        assert_valid(name, &m, g.num_labels());
        let t = &m.triangulation;
        let mut free_bad = 0;
        for f in t.triangles() {
            let (angle, excused) = smallest_angle(t, f);
            if angle < DEFAULT_MIN_ANGLE - 1e-9 && !excused {
                free_bad += 1;
            }
        }
        assert_eq!(
            free_bad, 0,
            "{name}: triangles below θ away from the c-edges"
        );
        // Refinement never moves a boundary: the agreement cannot drop.
        let after = m.label_agreement(&g);
        assert!(
            after >= before - 1e-12,
            "{name}: agreement {before} → {after}"
        );
    }
}

#[test]
fn sampling_does_not_depend_on_the_thread_count() {
    let g = blobs_with_hole();
    let run = |threads| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| sample(&g, &SampleOptions::default()).unwrap())
    };
    let (a, b) = (run(1), run(2));
    assert_eq!(a.triangulation.points(), b.triangulation.points());
    assert_eq!(
        a.triangulation.triangle_indices(),
        b.triangulation.triangle_indices()
    );
}

#[test]
fn bad_thresholds_are_refused_with_advice() {
    let e = sample(
        &disk(),
        &SampleOptions {
            te: 1.5,
            ..Default::default()
        },
    )
    .unwrap_err();
    assert_eq!(e, SegmentError::BadThreshold { te: 1.5 });
    assert!(e.to_string().contains("0.1"));
    assert!(sample(
        &disk(),
        &SampleOptions {
            te: f64::NAN,
            ..Default::default()
        }
    )
    .is_err());
}

#[test]
fn the_vertex_cap_stops_sampling() {
    let s = sample(
        &disk(),
        &SampleOptions {
            te: 0.1,
            max_vertices: 5,
        },
    )
    .unwrap();
    assert!(s.capped);
    assert_eq!(s.inserted, 5);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(32))]

    #[test]
    fn random_label_images_give_valid_partitions(w in 1u32..24, h in 1u32..24, cells in prop::collection::vec(0u32..3, 36), te in prop::sample::select(vec![0.05, 0.1, 0.3])) {
        // Blocks of a random 6 × 6 pattern, so that regions have some size.
        let g = grid(w, h, 3, |c, r| cells[((r * 6 / h) * 6 + c * 6 / w) as usize]);
        let m = SegmentedMesh::from_grid(&g, &SampleOptions { te, ..Default::default() }).unwrap();
        assert_valid("random", &m, 3);
        assert_c_edges_close("random", &m);
    }
}
