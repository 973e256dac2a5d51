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

    /// The vertices on the boundary, sorted.
    pub fn vertices(&self) -> Vec<u32> {
        let mut v: Vec<u32> = self.edges.iter().flatten().copied().collect();
        v.sort_unstable();
        v.dedup();
        v
    }
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
