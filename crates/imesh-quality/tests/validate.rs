//! The validator finds every kind of broken invariant, and accepts valid meshes.

use imesh_quality::{validate, Domain, Element, MeshView, Violation};

/// A W × H grid of unit quads over [0, W] × [0, H], counter-clockwise.
fn grid(w: u32, h: u32) -> (Vec<[f64; 2]>, Vec<Element>) {
    let v: Vec<[f64; 2]> = (0..=h)
        .flat_map(|r| (0..=w).map(move |c| [f64::from(c), f64::from(r)]))
        .collect();
    let id = |c: u32, r: u32| r * (w + 1) + c;
    let e = (0..h)
        .flat_map(|r| {
            (0..w).map(move |c| {
                Element::Quad([id(c, r), id(c + 1, r), id(c + 1, r + 1), id(c, r + 1)])
            })
        })
        .collect();
    (v, e)
}

fn check(v: &[[f64; 2]], e: &[Element], domain: Domain) -> Vec<Violation> {
    let labels = vec![7; e.len()];
    validate(
        &MeshView {
            vertices: v,
            elements: e,
            labels: &labels,
        },
        &domain,
    )
    .violations
}

#[test]
fn a_grid_is_valid() {
    let (v, e) = grid(5, 3);
    assert!(check(&v, &e, Domain::image(5.0, 3.0)).is_empty());
}

#[test]
fn a_mixed_mesh_with_triangles_is_valid() {
    let (v, mut e) = grid(2, 2);
    // Split quad 0 into two triangles.
    if let Element::Quad([a, b, c, d]) = e[0] {
        e[0] = Element::Triangle([a, b, c]);
        e.push(Element::Triangle([a, c, d]));
    }
    assert!(check(&v, &e, Domain::image(2.0, 2.0)).is_empty());
}

#[test]
fn an_inverted_quad_is_reported_though_verdict_would_score_it_1() {
    let (v, mut e) = grid(3, 3);
    if let Element::Quad([a, b, c, d]) = e[4] {
        e[4] = Element::Quad([a, d, c, b]);
    }
    let found = check(&v, &e, Domain::image(3.0, 3.0));
    assert!(found
        .iter()
        .any(|x| matches!(x, Violation::NonPositiveCorner { element: 4, .. })));
    assert!(found
        .iter()
        .any(|x| matches!(x, Violation::EdgeSameDirection { .. })));
    assert!(found
        .iter()
        .any(|x| matches!(x, Violation::AreaMismatch { .. })));
}

#[test]
fn a_hanging_vertex_is_an_open_inner_edge() {
    // Two quads side by side on the left, and on the right one quad whose left edge holds a vertex
    // in the middle that its neighbours use: a T-junction.
    let v = [
        [0.0, 0.0],
        [1.0, 0.0],
        [2.0, 0.0],
        [0.0, 1.0],
        [1.0, 1.0],
        [0.0, 2.0],
        [1.0, 2.0],
        [2.0, 2.0],
    ];
    let e = [
        Element::Quad([0, 1, 4, 3]),
        Element::Quad([3, 4, 6, 5]),
        Element::Quad([1, 2, 7, 6]),
    ];
    let found = check(&v, &e, Domain::image(2.0, 2.0));
    assert!(
        found
            .iter()
            .any(|x| matches!(x, Violation::OpenEdgeInside { .. })),
        "{found:?}"
    );
}

#[test]
fn a_gap_changes_the_area_and_opens_edges() {
    let (v, mut e) = grid(3, 3);
    e.remove(4);
    let found = check(&v, &e, Domain::image(3.0, 3.0));
    assert_eq!(
        found
            .iter()
            .filter(|x| matches!(x, Violation::OpenEdgeInside { .. }))
            .count(),
        4
    );
    assert!(found.iter().any(|x| matches!(x, Violation::AreaMismatch { total, expected } if *total == 8.0 && *expected == 9.0)));
}

#[test]
fn index_repeat_duplicate_unused_outside_and_nonfinite_vertices() {
    let (mut v, mut e) = grid(2, 1);
    e.push(Element::Triangle([0, 1, 99]));
    e.push(Element::Triangle([0, 0, 1]));
    v.push([1.0, 1.0]); // duplicate of vertex 4, unused
    v.push([5.0, 0.5]); // outside, unused
    v.push([f64::NAN, 0.0]);
    let found = check(&v, &e, Domain::image(2.0, 1.0));
    let n = v.len() as u32;
    assert!(found.contains(&Violation::VertexOutOfRange {
        element: 2,
        vertex: 99
    }));
    assert!(found.contains(&Violation::RepeatedCorner { element: 3 }));
    assert!(found.contains(&Violation::DuplicateVertex {
        first: 4,
        second: n - 3
    }));
    assert!(found.contains(&Violation::UnusedVertex { vertex: n - 2 }));
    assert!(found.contains(&Violation::VertexOutsideDomain { vertex: n - 2 }));
    assert!(found.contains(&Violation::NonFiniteVertex { vertex: n - 1 }));
}

#[test]
fn overlapping_elements_and_label_count() {
    let (v, mut e) = grid(2, 2);
    e.push(e[0]);
    let labels = vec![1; e.len() - 1];
    let r = validate(
        &MeshView {
            vertices: &v,
            elements: &e,
            labels: &labels,
        },
        &Domain::image(2.0, 2.0),
    );
    assert!(r
        .violations
        .iter()
        .any(|x| matches!(x, Violation::EdgeSharedTooOften { count: 3, .. })));
    assert!(r.violations.contains(&Violation::LabelCount {
        labels: 4,
        elements: 5
    }));
    assert!(!r.is_valid());
    assert!(r.to_string().contains("violation"));
}

#[test]
fn a_non_convex_quad_fails_and_a_flat_corner_fails() {
    let v = [[0.0, 0.0], [2.0, 0.0], [2.0, 2.0], [0.0, 2.0], [1.6, 1.0]];
    // The square split through an inner vertex (1.6, 1): quad (1, 2, 3, 4) has its reflex corner there.
    let e = [Element::Quad([0, 1, 4, 3]), Element::Quad([1, 2, 3, 4])];
    let found = check(&v, &e, Domain::image(2.0, 2.0));
    assert!(
        found.iter().any(|x| matches!(
            x,
            Violation::NonPositiveCorner {
                element: 1,
                corner: 3
            }
        )),
        "{found:?}"
    );
    let v = [[0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [2.0, 1.0], [0.0, 1.0]];
    let e = [Element::Quad([0, 2, 3, 4]), Element::Triangle([0, 1, 2])];
    let found = check(&v, &e, Domain::image(2.0, 1.0));
    assert!(found
        .iter()
        .any(|x| matches!(x, Violation::NonPositiveCorner { element: 1, .. })));
}
