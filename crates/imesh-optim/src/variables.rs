//! The optimisation variables: which points may move, which quad vertices each one moves (and
//! by what weight), which quads it changes, the control-net polygon it must stay inside, and a
//! colouring so that points of one colour share no quad.

use imesh_geom::predicates::orient2d;
use imesh_geom::{Point, Triangulation};
use imesh_quad::{ControlNet, Element, ElementMesh, QuadMesh, Template, TRIANGLE_SLOTS};

/// Compressed rows: `items[first[i]..first[i + 1]]` belong to row `i`.
#[derive(Clone, Debug, Default)]
pub(crate) struct Rows<T> {
    first: Vec<u32>,
    items: Vec<T>,
}

impl<T> Rows<T> {
    /// No rows yet: [`Rows::push_row`] adds them.
    pub(crate) fn new() -> Self {
        Self {
            first: vec![0],
            items: Vec::new(),
        }
    }

    /// Appends a row.
    pub(crate) fn push_row(&mut self, row: impl IntoIterator<Item = T>) {
        self.items.extend(row);
        self.first.push(self.items.len() as u32);
    }

    pub(crate) fn row(&self, i: usize) -> &[T] {
        &self.items[self.span(i)]
    }

    /// Row `i`, to change in place.
    fn row_mut(&mut self, i: usize) -> &mut [T] {
        let span = self.span(i);
        &mut self.items[span]
    }

    /// Where row `i`'s items are in `items` (and in any list built item for item from them).
    fn span(&self, i: usize) -> std::ops::Range<usize> {
        self.first[i] as usize..self.first[i + 1] as usize
    }

    /// Number of rows.
    pub(crate) fn len(&self) -> usize {
        self.first.len().saturating_sub(1)
    }
}

impl<T: Copy> Rows<T> {
    /// `rows` rows from `(row, item)` pairs, each row's items in the pairs' order (a counting
    /// sort: no list per row).
    pub(crate) fn from_pairs(rows: usize, pairs: &[(u32, T)]) -> Self {
        let mut first = vec![0u32; rows + 1];
        for &(r, _) in pairs {
            first[r as usize + 1] += 1;
        }
        for r in 0..rows {
            first[r + 1] += first[r];
        }
        let mut next: Vec<u32> = first[..rows].to_vec();
        let mut items = Vec::with_capacity(pairs.len());
        // Every slot is written once below; the first pair's item stands in until then.
        if let Some(&(_, x)) = pairs.first() {
            items.resize(pairs.len(), x);
        }
        for &(r, x) in pairs {
            items[next[r as usize] as usize] = x;
            next[r as usize] += 1;
        }
        Self { first, items }
    }

    /// Keeps, in every row, the items `keep` says yes to (given the row and the item's place
    /// in it).
    fn retain(&mut self, mut keep: impl FnMut(&[T], usize) -> bool) {
        let mut items = Vec::with_capacity(self.items.len());
        let mut first = Vec::with_capacity(self.first.len());
        first.push(0);
        for r in 0..self.len() {
            let row = self.row(r);
            for k in 0..row.len() {
                if keep(row, k) {
                    items.push(row[k]);
                }
            }
            first.push(items.len() as u32);
        }
        *self = Self { first, items };
    }

    /// Keeps the rows `keep` says yes to.
    fn keep_rows(&self, keep: &[bool]) -> Self {
        let mut rows = Self::new();
        for (r, &k) in keep.iter().enumerate() {
            if k {
                rows.push_row(self.row(r).iter().copied());
            }
        }
        rows
    }
}

/// The movable points of one optimisation.
#[derive(Clone, Debug)]
pub(crate) struct Variables {
    /// What each variable is: a control point index (control mode) or a quad vertex index
    /// (vertex mode).
    pub ids: Vec<u32>,
    /// Per variable, the quad vertices it moves and the weight of its move in each (sorted by
    /// vertex).
    pub influence: Rows<(u32, f64)>,
    /// Per variable, the quads it changes.
    pub quads: Rows<u32>,
    /// Per variable, for each of its quads (in the order of [`Variables::quads`]), its weight
    /// in each of the quad's corners (0 for a corner it does not move).
    pub corner_weights: Rows<[f64; 4]>,
    /// Per variable, directed control-net edges `(a, b)` its point must stay strictly left of:
    /// the edges of its neighbour polygon, so that the point stays inside it (in its kernel).
    pub ring: Rows<[u32; 2]>,
    /// Variables by colour: two variables of one colour share no quad.
    pub colours: Vec<Vec<u32>>,
    /// Per quad, the variables that change it.
    pub by_quad: Rows<u32>,
}

/// Quad patch net cells, counter-clockwise by slot (`i + 4 j`).
fn quad_cells() -> Vec<Vec<usize>> {
    let mut cells = Vec::new();
    for j in 0..3 {
        for i in 0..3 {
            let s = i + 4 * j;
            cells.push(vec![s, s + 1, s + 5, s + 4]);
        }
    }
    cells
}

/// Triangle patch net cells, counter-clockwise by slot ([`TRIANGLE_SLOTS`] order).
fn triangle_cells() -> Vec<Vec<usize>> {
    let slot = |a: u8, b: u8| {
        TRIANGLE_SLOTS
            .iter()
            .position(|&s| s == (a, b))
            .unwrap_or(0)
    };
    let mut cells = Vec::new();
    for b in 0..3u8 {
        for a in 0..3 - b {
            cells.push(vec![slot(a, b), slot(a + 1, b), slot(a, b + 1)]);
            if a + b < 2 {
                cells.push(vec![slot(a + 1, b), slot(a + 1, b + 1), slot(a, b + 1)]);
            }
        }
    }
    cells
}

/// The constrained M edges: those on a segment of DT' (a c-edge or the domain border).
fn constrained_edges(t: &Triangulation, m: &ElementMesh) -> Vec<bool> {
    m.edges.iter().map(|&h| t.is_constrained(h)).collect()
}

/// Per quad vertex, whether it is fixed in the vertex mode: on a constrained M edge (a c-edge
/// or the domain border).
pub(crate) fn fixed_vertices(t: &Triangulation, m: &ElementMesh, mesh: &QuadMesh) -> Vec<bool> {
    let mut fixed = vec![false; mesh.vertices.len()];
    for (e, &c) in constrained_edges(t, m).iter().enumerate() {
        if c {
            for v in mesh.edge_vertices(t, m, e as u32) {
                fixed[v as usize] = true;
            }
        }
    }
    fixed
}

/// Per quad vertex, the quads around it.
pub(crate) fn vertex_quads(mesh: &QuadMesh) -> Rows<u32> {
    let pairs: Vec<(u32, u32)> = (mesh.quads.iter().enumerate())
        .flat_map(|(q, quad)| quad.map(|v| (v, q as u32)))
        .collect();
    Rows::from_pairs(mesh.vertices.len(), &pairs)
}

impl Variables {
    /// The free control points of `net`: all but the corners and edge points of constrained M
    /// edges (so c-edges and the domain border keep their curves).
    pub fn control_points(
        t: &Triangulation,
        m: &ElementMesh,
        net: &ControlNet,
        mesh: &QuadMesh,
    ) -> Self {
        let mut fixed = vec![false; net.points.len()];
        for (e, &c) in constrained_edges(t, m).iter().enumerate() {
            if c {
                let h = m.edges[e];
                fixed[t.origin(h).index()] = true;
                fixed[t.destination(h).index()] = true;
                for p in net.edge_inner(e as u32) {
                    fixed[p as usize] = true;
                }
            }
        }
        let templates = [
            Template::triangle(mesh.level()),
            Template::quad(mesh.level()),
        ];
        // Per element kind and slot: the template points the slot's control point moves (with
        // their weights), and the edges of the net cells around it, opposite to it.
        let cells = [triangle_cells(), quad_cells()];
        let by_slot: [Vec<Vec<(usize, f64)>>; 2] = [0, 1].map(|kind| {
            (0..16)
                .map(|s| {
                    (templates[kind].weights.iter().enumerate())
                        .filter(|(_, w)| w[s] != 0.0)
                        .map(|(point, w)| (point, w[s]))
                        .collect()
                })
                .collect()
        });
        let ring_of: [Vec<Vec<[usize; 2]>>; 2] = [0, 1].map(|kind| {
            (0..16)
                .map(|s| {
                    let mut edges = Vec::new();
                    for cell in &cells[kind] {
                        if let Some(at) = cell.iter().position(|&x| x == s) {
                            let n = cell.len();
                            for step in 1..n - 1 {
                                edges.push([cell[(at + step) % n], cell[(at + step + 1) % n]]);
                            }
                        }
                    }
                    edges
                })
                .collect()
        });
        let mut variable_of = vec![u32::MAX; net.points.len()];
        let mut ids = Vec::new();
        let mut influence: Vec<(u32, (u32, f64))> = Vec::new();
        let mut ring: Vec<(u32, [u32; 2])> = Vec::new();
        for (k, element) in m.elements.iter().enumerate() {
            let kind = usize::from(matches!(element, Element::Quad(_)));
            let slots = if kind == 1 { 16 } else { 10 };
            let patch = &net.patches[k];
            let vertices = mesh.element_vertices(k);
            for s in 0..slots {
                let c = patch[s];
                if fixed[c as usize] {
                    continue;
                }
                if variable_of[c as usize] == u32::MAX {
                    variable_of[c as usize] = ids.len() as u32;
                    ids.push(c);
                }
                let i = variable_of[c as usize];
                influence.extend(
                    by_slot[kind][s]
                        .iter()
                        .map(|&(point, w)| (i, (vertices[point], w))),
                );
                ring.extend(
                    ring_of[kind][s]
                        .iter()
                        .map(|&[a, b]| (i, [patch[a], patch[b]])),
                );
            }
        }
        let mut influence = Rows::from_pairs(ids.len(), &influence);
        let ring = Rows::from_pairs(ids.len(), &ring);
        // A vertex on a side shared by two patches appears in both, with the same weight: the
        // first is kept, and the rows sorted by vertex.
        for r in 0..influence.len() {
            influence.row_mut(r).sort_by_key(|&(v, _)| v);
        }
        influence.retain(|row, k| k == 0 || row[k].0 != row[k - 1].0);
        // Control points that move exactly the same quad vertices are one degree of freedom
        // solved several times: at level 1 a quad patch's four inner points all move only its
        // centre, and an edge's two inner points the same midpoint and centres. The first of
        // each such set is kept.
        let keys: Vec<u32> = influence.items.iter().map(|&(v, _)| v).collect();
        let mut seen = std::collections::HashSet::new();
        let keep: Vec<bool> = (0..influence.len())
            .map(|r| seen.insert(&keys[influence.span(r)]))
            .collect();
        let ids = ids
            .into_iter()
            .zip(&keep)
            .filter(|&(_, &k)| k)
            .map(|(x, _)| x)
            .collect();
        Self::finish(ids, influence.keep_rows(&keep), ring.keep_rows(&keep), mesh)
    }

    /// The free quad vertices: all but those on constrained M edges (vertex mode).
    pub fn vertices(t: &Triangulation, m: &ElementMesh, mesh: &QuadMesh) -> Self {
        Self::vertices_where(t, m, mesh, |_| true)
    }

    /// The free quad vertices for which `wanted` holds.
    pub fn vertices_where(
        t: &Triangulation,
        m: &ElementMesh,
        mesh: &QuadMesh,
        wanted: impl Fn(u32) -> bool,
    ) -> Self {
        let fixed = fixed_vertices(t, m, mesh);
        let ids: Vec<u32> = (0..mesh.vertices.len() as u32)
            .filter(|&v| !fixed[v as usize] && wanted(v))
            .collect();
        let mut influence = Rows::new();
        let mut ring = Rows::new();
        for &v in &ids {
            influence.push_row([(v, 1.0)]);
            ring.push_row([]);
        }
        Self::finish(ids, influence, ring, mesh)
    }

    fn finish(
        ids: Vec<u32>,
        influence: Rows<(u32, f64)>,
        ring: Rows<[u32; 2]>,
        mesh: &QuadMesh,
    ) -> Self {
        let around = vertex_quads(mesh);
        // The quads around a variable's vertices, each once (a stamp per quad), sorted.
        let mut stamp = vec![u32::MAX; mesh.quads.len()];
        let mut quads = Rows::new();
        let mut row = Vec::new();
        for i in 0..influence.len() {
            row.clear();
            for &(v, _) in influence.row(i) {
                for &q in around.row(v as usize) {
                    if stamp[q as usize] != i as u32 {
                        stamp[q as usize] = i as u32;
                        row.push(q);
                    }
                }
            }
            row.sort_unstable();
            quads.push_row(row.iter().copied());
        }
        // Each quad corner's weight, found in the variable's short influence row.
        let mut items: Vec<[f64; 4]> = Vec::with_capacity(quads.items.len());
        for i in 0..influence.len() {
            let row = influence.row(i);
            for &q in quads.row(i) {
                let mut w = [0.0; 4];
                for (k, &v) in mesh.quads[q as usize].iter().enumerate() {
                    if let Some(&(_, x)) = row.iter().find(|&&(u, _)| u == v) {
                        w[k] = x;
                    }
                }
                items.push(w);
            }
        }
        let corner_weights = Rows {
            first: quads.first.clone(),
            items,
        };
        let by_quad = by_quad(&quads, mesh.quads.len());
        let colours = colour(&quads, &by_quad);
        Self {
            ids,
            influence,
            quads,
            corner_weights,
            ring,
            colours,
            by_quad,
        }
    }

    /// Number of variables (points; twice as many coordinates).
    pub fn len(&self) -> usize {
        self.ids.len()
    }

    /// True when `p` lies strictly left of every ring edge of variable `i` (control points
    /// `net`).
    pub fn inside_ring(&self, i: usize, net: &[Point], p: Point) -> bool {
        self.ring
            .row(i)
            .iter()
            .all(|&[a, b]| orient2d(net[a as usize], net[b as usize], p) > 0.0)
    }
}

/// Per quad (of `n_quads`), the items whose quad lists (`quads`) hold it.
pub(crate) fn by_quad(quads: &Rows<u32>, n_quads: usize) -> Rows<u32> {
    let pairs: Vec<(u32, u32)> = (0..quads.len())
        .flat_map(|i| quads.row(i).iter().map(move |&q| (q, i as u32)))
        .collect();
    Rows::from_pairs(n_quads, &pairs)
}

/// Greedy colouring of the variables: each takes the smallest colour no earlier variable sharing
/// one of its quads has.
pub(crate) fn colour(quads: &Rows<u32>, by_quad: &Rows<u32>) -> Vec<Vec<u32>> {
    let mut colour_of = vec![u32::MAX; quads.len()];
    let mut seen: Vec<usize> = Vec::new();
    let mut colours: Vec<Vec<u32>> = Vec::new();
    for i in 0..quads.len() {
        for &q in quads.row(i) {
            for &j in by_quad.row(q as usize) {
                let c = colour_of[j as usize];
                if c != u32::MAX {
                    if seen.len() <= c as usize {
                        seen.resize(c as usize + 1, usize::MAX);
                    }
                    seen[c as usize] = i;
                }
            }
        }
        let c = (0..)
            .find(|&c| seen.get(c).is_none_or(|&s| s != i))
            .unwrap_or(0);
        colour_of[i] = c as u32;
        if colours.len() <= c {
            colours.resize(c + 1, Vec::new());
        }
        colours[c].push(i as u32);
    }
    colours
}

#[cfg(test)]
mod tests {
    use super::Rows;
    use proptest::prelude::*;

    proptest! {
        /// Rows from pairs hold, row by row, exactly the pairs' items in the pairs' order, as
        /// lists built by pushing would; retaining and keeping rows agree with filtering those.
        #[test]
        fn rows_from_pairs_match_lists(
            pairs in proptest::collection::vec((0u32..7, any::<u16>()), 0..60),
            keep in proptest::collection::vec(any::<bool>(), 7),
        ) {
            let mut lists = vec![Vec::new(); 7];
            for &(r, x) in &pairs {
                lists[r as usize].push(x);
            }
            let mut rows = Rows::from_pairs(7, &pairs);
            prop_assert_eq!(rows.len(), 7);
            for (r, list) in lists.iter().enumerate() {
                prop_assert_eq!(rows.row(r), &list[..]);
            }
            let kept = rows.keep_rows(&keep);
            let expected: Vec<&Vec<u16>> = lists.iter().zip(&keep).filter(|(_, &k)| k).map(|(l, _)| l).collect();
            prop_assert_eq!(kept.len(), expected.len());
            for (r, list) in expected.iter().enumerate() {
                prop_assert_eq!(kept.row(r), &list[..]);
            }
            rows.retain(|row, k| row[k] % 2 == 0);
            for (r, list) in lists.iter().enumerate() {
                let even: Vec<u16> = list.iter().copied().filter(|x| x % 2 == 0).collect();
                prop_assert_eq!(rows.row(r), &even[..]);
            }
        }
    }
}
