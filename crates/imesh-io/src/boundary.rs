//! The boundaries of a labelled mesh: edges between two labels, and the domain border.

use std::collections::HashMap;

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
    // Edge (low, high) → labels of the elements on it, in order of appearance.
    let mut sides: HashMap<[u32; 2], (Vec<u32>, usize)> = HashMap::new();
    let mut order = 0usize;
    for (e, &l) in mesh.elements.iter().zip(&mesh.labels) {
        let c = e.corners();
        for i in 0..c.len() {
            let (a, b) = (c[i], c[(i + 1) % c.len()]);
            let entry = sides.entry([a.min(b), a.max(b)]).or_insert_with(|| {
                order += 1;
                (Vec::new(), order)
            });
            entry.0.push(l);
        }
    }
    let mut groups: HashMap<[u32; 2], Vec<(usize, [u32; 2])>> = HashMap::new();
    for (edge, (labels, seen)) in sides {
        let key = match labels.as_slice() {
            [a] => [*a, OUTSIDE],
            [a, b] if a != b => [*a.min(b), *a.max(b)],
            _ => continue,
        };
        groups.entry(key).or_default().push((seen, edge));
    }
    let mut out: Vec<Boundary> = groups
        .into_iter()
        .map(|(labels, mut edges)| {
            edges.sort_unstable();
            Boundary {
                labels,
                edges: edges.into_iter().map(|(_, e)| e).collect(),
            }
        })
        .collect();
    out.sort_by_key(|b| b.labels);
    out
}
