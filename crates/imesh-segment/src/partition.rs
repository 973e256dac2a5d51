//! Imesh step 2: a label per triangle, and the c-edge graph (DESIGN.md §2, step 3).

use imesh_classify::LabelGrid;
use imesh_geom::{HalfEdgeId, Point, TriangleId, Triangulation, VertexId};
use rayon::prelude::*;

use crate::sample::{doubled, medians};
use crate::traverse::touched_pixels;

/// The label on the outer side of a domain-border c-edge.
pub const OUTSIDE: u32 = u32::MAX;

/// An edge of the partition: between two triangles of different labels, or on the domain border.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CEdge {
    /// Its two vertices.
    pub vertices: [VertexId; 2],
    /// The label to the left of `vertices[0] → vertices[1]` (y down: the side the triangle
    /// `(v0, v1, apex)` with a counter-clockwise orientation lies on) and the label to the right
    /// ([`OUTSIDE`] on the domain border).
    pub labels: [u32; 2],
}

/// `h(σ)`: the most frequent label among the pixels the triangle's medians touch; a tie goes to
/// the label of the pixel that holds the centroid.
///
/// ```
/// use imesh_classify::{LabelGrid, Region};
/// use imesh_geom::Point;
/// use imesh_segment::triangle_label;
/// let regions = vec![Region { name: "a".into(), colour: [0; 3] }, Region { name: "b".into(), colour: [255; 3] }];
/// let grid = LabelGrid::new(4, 1, vec![1, 1, 1, 0], regions).unwrap();
/// let t = [Point::new(0.0, 0.0), Point::new(4.0, 0.0), Point::new(0.5, 0.5)];
/// assert_eq!(triangle_label(&grid, t), 1);
/// ```
pub fn triangle_label(grid: &LabelGrid, p: [Point; 3]) -> u32 {
    let (w, h) = (grid.width(), grid.height());
    let labels = grid.labels();
    // Few labels meet in one triangle: a short list beats a map.
    let mut counts: Vec<(u32, u32)> = Vec::with_capacity(4);
    for (a, b) in medians(doubled(p)) {
        touched_pixels(a, b, w, h, |c, r| {
            let label = labels[(r * w + c) as usize];
            match counts.iter_mut().find(|(l, _)| *l == label) {
                Some((_, n)) => *n += 1,
                None => counts.push((label, 1)),
            }
        });
    }
    let centroid_label = || {
        let x = (p[0].x + p[1].x + p[2].x) / 3.0;
        let y = (p[0].y + p[1].y + p[2].y) / 3.0;
        let c = (x.floor().max(0.0) as u32).min(w - 1);
        let r = (y.floor().max(0.0) as u32).min(h - 1);
        labels[(r * w + c) as usize]
    };
    let Some(&(best, n)) = counts.iter().max_by_key(|(_, n)| *n) else {
        return centroid_label();
    };
    if counts.iter().filter(|(_, m)| *m == n).count() > 1 {
        let c = centroid_label();
        // The centroid's label settles a tie only when it is one of the tied labels.
        if counts.iter().any(|&(l, m)| l == c && m == n) {
            return c;
        }
        return counts
            .iter()
            .filter(|(_, m)| *m == n)
            .map(|&(l, _)| l)
            .min()
            .unwrap_or(best);
    }
    best
}

/// The label of every triangle slot of `t` (by [`TriangleId::index`]; ghost slots get
/// [`OUTSIDE`]), computed in parallel.
pub fn partition(grid: &LabelGrid, t: &Triangulation) -> Vec<u32> {
    let slots = t.num_triangle_slots();
    (0..slots as u32)
        .into_par_iter()
        .map(|i| {
            let f = TriangleId::new(i);
            if t.is_triangle(f) {
                triangle_label(grid, t.triangle_points(f))
            } else {
                OUTSIDE
            }
        })
        .collect()
}

/// The c-edges of a labelled triangulation: every edge whose two sides differ in label, and every
/// hull edge (the domain border).
pub fn c_edges(t: &Triangulation, label: &[u32]) -> Vec<CEdge> {
    t.edges()
        .filter_map(|e| {
            let left = side_label(t, e, label);
            let right = side_label(t, t.twin(e), label);
            (left != right).then_some(CEdge {
                vertices: [t.origin(e), t.destination(e)],
                labels: [left, right],
            })
        })
        .collect()
}

/// The label of the triangle half-edge `e` belongs to ([`OUTSIDE`] for a ghost).
fn side_label(t: &Triangulation, e: HalfEdgeId, label: &[u32]) -> u32 {
    let f = t.triangle_of(e);
    if t.is_triangle(f) {
        label[f.index()]
    } else {
        OUTSIDE
    }
}
