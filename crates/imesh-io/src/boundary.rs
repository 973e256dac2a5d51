//! The boundaries of a labelled mesh: edges between two labels, and the domain border.

use rayon::prelude::*;

use crate::SegmentedMeshData;

/// The label outside the domain, on the far side of a border edge.
pub const OUTSIDE: u32 = u32::MAX;

/// The edges between two regions (or a region and the outside), as element edges.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Boundary {
    /// The two labels, smaller first ([`OUTSIDE`] last for the domain border).
    pub labels: [u32; 2],
    /// Its edges, each as two vertex indices.
    pub edges: Vec<[u32; 2]>,
}

impl Boundary {
    /// A name for the boundary: `border_NAME` or `NAME1_NAME2`, made of letters, digits and `_`.
    pub fn name(&self, mesh: &SegmentedMeshData) -> String {
        let label = |l: u32| {
            mesh.label_names
                .get(l as usize)
                .map_or_else(|| format!("label{l}"), |n| sanitize(n))
        };
        match self.labels {
            [a, OUTSIDE] => format!("border_{}", label(a)),
            [a, b] => format!("{}_{}", label(a), label(b)),
        }
    }

    /// A label's border split by the side of the domain each edge runs along ([`Side::ALL`]
    /// order, each side's edges in the boundary's order); all four empty for a boundary between
    /// two labels.
    ///
    /// ```
    /// use imesh_io::{boundaries, SegmentedMeshData, Side};
    /// use imesh_quality::Element;
    /// // One 2 × 1 quad: its border has one edge on each side.
    /// let mesh = SegmentedMeshData {
    ///     vertices: vec![[0.0, 0.0], [2.0, 0.0], [2.0, 1.0], [0.0, 1.0]],
    ///     elements: vec![Element::Quad([0, 3, 2, 1])],
    ///     labels: vec![0], label_names: vec!["a".into()], label_colours: vec![[0; 3]],
    ///     width: 2, height: 1, second_order: None,
    /// };
    /// let border = &boundaries(&mesh)[0];
    /// let sides = border.sides(&mesh);
    /// assert_eq!(sides[Side::Right as usize].len(), 1);
    /// assert!(sides.iter().all(|edges| edges.len() == 1));
    /// ```
    pub fn sides(&self, mesh: &SegmentedMeshData) -> [Vec<[u32; 2]>; 4] {
        let mut sides: [Vec<[u32; 2]>; 4] = Default::default();
        if self.labels[1] == OUTSIDE {
            for &e in &self.edges {
                sides[Side::of_edge(mesh, e) as usize].push(e);
            }
        }
        sides
    }
}

/// A side of the domain rectangle `[0, W] × [0, H]`, named as the image shows it: the top is
/// row 0 (y = 0 in image coordinates), and stays the top in the written frame, whose y is up.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Side {
    /// x = 0.
    Left,
    /// x = W.
    Right,
    /// The image's last row: y = H in image coordinates, y = 0 in the written frame.
    Bottom,
    /// The image's first row: y = 0 in image coordinates, y = H in the written frame.
    Top,
}

impl Side {
    /// The four sides, in the order the writers list them.
    pub const ALL: [Side; 4] = [Side::Left, Side::Right, Side::Bottom, Side::Top];

    /// The side's name in the written files: `left`, `right`, `bottom` or `top`.
    pub fn name(self) -> &'static str {
        match self {
            Side::Left => "left",
            Side::Right => "right",
            Side::Bottom => "bottom",
            Side::Top => "top",
        }
    }

    /// The side of `mesh`'s domain that border edge `edge` lies along: the one nearest its
    /// midpoint (a border edge lies on one side's line; nearest, rather than equal, so that a
    /// vertex a rounding away from the line does not lose its edge).
    ///
    /// ```
    /// use imesh_io::{SegmentedMeshData, Side};
    /// use imesh_quality::Element;
    /// let mesh = SegmentedMeshData {
    ///     vertices: vec![[0.0, 0.0], [3.0, 0.0], [3.0, 2.0], [0.0, 2.0]],
    ///     elements: vec![Element::Quad([0, 3, 2, 1])],
    ///     labels: vec![0], label_names: vec!["a".into()], label_colours: vec![[0; 3]],
    ///     width: 3, height: 2, second_order: None,
    /// };
    /// assert_eq!(Side::of_edge(&mesh, [0, 3]), Side::Left);
    /// assert_eq!(Side::of_edge(&mesh, [0, 1]), Side::Top); // image row 0
    /// assert_eq!(Side::of_edge(&mesh, [3, 2]), Side::Bottom);
    /// ```
    pub fn of_edge(mesh: &SegmentedMeshData, edge: [u32; 2]) -> Side {
        let [a, b] = edge.map(|v| mesh.vertices[v as usize]);
        let (x, y) = ((a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0);
        let (w, h) = (f64::from(mesh.width), f64::from(mesh.height));
        let distances = [x, w - x, h - y, y].map(f64::abs);
        let nearest = (1..4).fold(0, |best, k| {
            if distances[k] < distances[best] {
                k
            } else {
                best
            }
        });
        Side::ALL[nearest]
    }
}

/// The vertices of `edges`, sorted, each once.
pub(crate) fn edge_vertices(edges: &[[u32; 2]]) -> Vec<u32> {
    let mut v: Vec<u32> = edges.iter().flatten().copied().collect();
    v.sort_unstable();
    v.dedup();
    v
}

/// A name fit for solver keywords: letters, digits and `_`, starting with a letter.
pub fn sanitize(name: &str) -> String {
    let mut s: String = name
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect();
    if !s.starts_with(|c: char| c.is_ascii_alphabetic()) {
        s.insert(0, 'L');
    }
    s
}

/// Every boundary of `mesh`, sorted by labels; each edge once, in the order of the elements.
pub fn boundaries(mesh: &SegmentedMeshData) -> Vec<Boundary> {
    // Every element side as (edge, when it was met, label), sorted: the sides of one edge are
    // then consecutive, the first met first. A sort of plain tuples, not a map of edges to
    // growing lists (aloe's 1.4 M sides: 0.3 s that way).
    let mut sides: Vec<([u32; 2], usize, u32)> = Vec::with_capacity(4 * mesh.elements.len());
    for (e, &l) in mesh.elements.iter().zip(&mesh.labels) {
        let c = e.corners();
        for i in 0..c.len() {
            let (a, b) = (c[i], c[(i + 1) % c.len()]);
            sides.push(([a.min(b), a.max(b)], sides.len(), l));
        }
    }
    sides.par_sort_unstable();
    // An edge with one side is on the border, with two of different labels between them;
    // anything else is inside a region.
    let mut found: Vec<([u32; 2], usize, [u32; 2])> = sides
        .chunk_by(|x, y| x.0 == y.0)
        .filter_map(|edge| {
            let labels = match edge {
                [(_, _, a)] => [*a, OUTSIDE],
                [(_, _, a), (_, _, b)] if a != b => [*a.min(b), *a.max(b)],
                _ => return None,
            };
            Some((labels, edge[0].1, edge[0].0))
        })
        .collect();
    found.par_sort_unstable();
    found
        .chunk_by(|x, y| x.0 == y.0)
        .map(|edges| Boundary {
            labels: edges[0].0,
            edges: edges.iter().map(|&(_, _, e)| e).collect(),
        })
        .collect()
}
