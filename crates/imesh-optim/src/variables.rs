//! The optimisation variables: which points may move, which quad vertices each one moves (and
//! by what weight), which quads it changes, the control-net polygon it must stay inside, and a
//! colouring so that points of one colour share no quad.

use imesh_geom::predicates::orient2d;
use imesh_geom::{Point, Triangulation};
use imesh_quad::{ControlNet, Element, ElementMesh, QuadMesh, Template, TRIANGLE_SLOTS};
use rayon::prelude::*;

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

    /// Where row `i`'s items are in `items` (and in any list built item for item from them).
    fn span(&self, i: usize) -> std::ops::Range<usize> {
        self.first[i] as usize..self.first[i + 1] as usize
    }

    /// Number of rows.
    pub(crate) fn len(&self) -> usize {
        self.first.len().saturating_sub(1)
    }

    /// Every row, to change in place (each its own slice, so that they can be changed in
    /// parallel).
    fn rows_mut(&mut self) -> Vec<&mut [T]> {
        let mut rows = Vec::with_capacity(self.len());
        let mut rest = &mut self.items[..];
        for w in self.first.windows(2) {
            let (row, tail) = rest.split_at_mut((w[1] - w[0]) as usize);
            rows.push(row);
            rest = tail;
        }
        rows
    }
}

impl<T: Copy> Rows<T> {
    /// Rows of `lengths[r]` items each, all `fill`, to be written in place.
    fn with_lengths(lengths: &[u32], fill: T) -> Self {
        let mut rows = Self::with_capacity(lengths.len(), 0);
        rows.push_lengths(lengths);
        rows.items = vec![fill; *rows.first.last().unwrap_or(&0) as usize];
        rows
    }

    /// The rows `r` that `keep[r]` says yes to, each with its first `lengths[r]` items.
    fn compacted(&self, lengths: &[u32], keep: &[bool]) -> Self {
        let kept = || (0..self.len()).filter(|&r| keep[r]);
        let total: usize = kept().map(|r| lengths[r] as usize).sum();
        let mut rows = Self::with_capacity(self.len(), total);
        for r in kept() {
            rows.push_row(self.row(r)[..lengths[r] as usize].iter().copied());
        }
        rows
    }

    /// No rows yet, room for `rows` rows of `items` items in all.
    fn with_capacity(rows: usize, items: usize) -> Self {
        let mut first = Vec::with_capacity(rows + 1);
        first.push(0);
        Self {
            first,
            items: Vec::with_capacity(items),
        }
    }

    /// Appends rows of `lengths` items each, taken in order from `items`.
    fn append_rows(&mut self, lengths: &[u32], items: &[T]) {
        self.items.extend_from_slice(items);
        self.push_lengths(lengths);
    }

    /// Ends of rows of `lengths` items each after the last row.
    fn push_lengths(&mut self, lengths: &[u32]) {
        let mut total = *self.first.last().unwrap_or(&0);
        for &n in lengths {
            total += n;
            self.first.push(total);
        }
    }

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
}

/// The quad rows and corner weights of a run of variables, as [`Variables::finish`] builds
/// them a chunk at a time.
#[derive(Default)]
struct QuadRows {
    lengths: Vec<u32>,
    quads: Vec<u32>,
    weights: Vec<[f64; 4]>,
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
        // Each free control point becomes a variable where it is first met (element by
        // element, slot by slot), and its rows list what each patch holding it gives, in that
        // order: counted in a first pass, written in place in a second.
        let kind_of = |k: usize| usize::from(matches!(m.elements[k], Element::Quad(_)));
        let slots = |kind: usize| if kind == 1 { 16 } else { 10 };
        let mut variable_of = vec![u32::MAX; net.points.len()];
        let mut ids = Vec::new();
        let (mut influence_len, mut ring_len) = (Vec::new(), Vec::new());
        for (k, patch) in net.patches.iter().enumerate().take(m.elements.len()) {
            let kind = kind_of(k);
            for (s, &c) in patch[..slots(kind)].iter().enumerate() {
                if fixed[c as usize] {
                    continue;
                }
                if variable_of[c as usize] == u32::MAX {
                    variable_of[c as usize] = ids.len() as u32;
                    ids.push(c);
                    influence_len.push(0);
                    ring_len.push(0);
                }
                let i = variable_of[c as usize] as usize;
                influence_len[i] += by_slot[kind][s].len() as u32;
                ring_len[i] += ring_of[kind][s].len() as u32;
            }
        }
        let mut influence = Rows::with_lengths(&influence_len, (0, 0.0));
        let mut ring = Rows::with_lengths(&ring_len, [0, 0]);
        let mut next_influence = influence.first.clone();
        let mut next_ring = ring.first.clone();
        for (k, patch) in net.patches.iter().enumerate().take(m.elements.len()) {
            let kind = kind_of(k);
            let vertices = mesh.element_vertices(k);
            for (s, &c) in patch[..slots(kind)].iter().enumerate() {
                let i = variable_of[c as usize] as usize;
                if i == u32::MAX as usize {
                    continue; // fixed
                }
                for &(point, w) in &by_slot[kind][s] {
                    influence.items[next_influence[i] as usize] = (vertices[point], w);
                    next_influence[i] += 1;
                }
                for &[a, b] in &ring_of[kind][s] {
                    ring.items[next_ring[i] as usize] = [patch[a], patch[b]];
                    next_ring[i] += 1;
                }
            }
        }
        // A vertex on a side shared by two patches appears in both, with the same weight: the
        // first is kept, and the rows sorted by vertex (stably: the first stays first).
        let kept: Vec<u32> = influence
            .rows_mut()
            .into_par_iter()
            .map(|row| {
                row.sort_by_key(|&(v, _)| v);
                let mut n = 0;
                for j in 0..row.len() {
                    if n == 0 || row[j].0 != row[n - 1].0 {
                        row[n] = row[j];
                        n += 1;
                    }
                }
                n as u32
            })
            .collect();
        // Control points that move exactly the same quad vertices are one degree of freedom
        // solved several times: at level 1 a quad patch's four inner points all move only its
        // centre, and an edge's two inner points the same midpoint and centres. The first of
        // each such set is kept.
        let keep = first_of_equal_rows(&influence, &kept);
        let ids = ids
            .into_iter()
            .zip(&keep)
            .filter(|&(_, &k)| k)
            .map(|(x, _)| x)
            .collect();
        Self::finish(
            ids,
            influence.compacted(&kept, &keep),
            ring.compacted(&ring_len, &keep),
            mesh,
        )
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
        // Per variable, the quads around its vertices (each once, sorted) and its weight in each
        // of their corners (0 for a corner it does not move); a chunk of variables per task,
        // the chunks' rows then laid end to end.
        const CHUNK: usize = 1024;
        let chunks: Vec<QuadRows> = (0..influence.len().div_ceil(CHUNK))
            .into_par_iter()
            .map(|c| {
                let mut chunk = QuadRows::default();
                let (mut row_quads, mut weights) = (Vec::new(), Vec::new());
                for i in c * CHUNK..((c + 1) * CHUNK).min(influence.len()) {
                    let row = influence.row(i);
                    row_quads.clear();
                    for &(v, _) in row {
                        row_quads.extend_from_slice(around.row(v as usize));
                    }
                    row_quads.sort_unstable();
                    row_quads.dedup();
                    weights.clear();
                    weights.resize(row_quads.len(), [0.0; 4]);
                    for &(v, w) in row {
                        for &q in around.row(v as usize) {
                            let corner = mesh.quads[q as usize].iter().position(|&u| u == v);
                            if let (Ok(at), Some(corner)) = (row_quads.binary_search(&q), corner) {
                                weights[at][corner] = w;
                            }
                        }
                    }
                    chunk.lengths.push(row_quads.len() as u32);
                    chunk.quads.extend_from_slice(&row_quads);
                    chunk.weights.extend_from_slice(&weights);
                }
                chunk
            })
            .collect();
        let (rows, total) = chunks
            .iter()
            .fold((0, 0), |(r, n), c| (r + c.lengths.len(), n + c.quads.len()));
        let mut quads = Rows::with_capacity(rows, total);
        let mut corner_weights = Rows::with_capacity(rows, total);
        for chunk in chunks {
            quads.append_rows(&chunk.lengths, &chunk.quads);
            corner_weights.append_rows(&chunk.lengths, &chunk.weights);
        }
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

/// Per row of `influence` (its first `lengths[r]` items), whether no earlier row moves the
/// same vertices (the same vertex keys in the same order). Equal rows start with the same vertex: rows are compared only with
/// the earlier rows starting with theirs (empty rows with one another).
fn first_of_equal_rows(influence: &Rows<(u32, f64)>, lengths: &[u32]) -> Vec<bool> {
    let row = |r: usize| &influence.row(r)[..lengths[r] as usize];
    let start = |r: usize| row(r).first().map_or(u32::MAX, |&(v, _)| v);
    let mut order: Vec<u64> = (0..influence.len())
        .map(|r| (u64::from(start(r)) << 32) | r as u64)
        .collect();
    order.par_sort_unstable();
    let same = |a: usize, b: usize| {
        let (x, y) = (row(a), row(b));
        x.len() == y.len() && x.iter().zip(y).all(|(p, q)| p.0 == q.0)
    };
    let mut keep = vec![true; influence.len()];
    let mut group = 0;
    while group < order.len() {
        let key = order[group] >> 32;
        let end = (group..order.len())
            .find(|&j| order[j] >> 32 != key)
            .unwrap_or(order.len());
        for j in group + 1..end {
            let r = order[j] as u32 as usize;
            keep[r] = !(group..j).any(|e| {
                let earlier = order[e] as u32 as usize;
                keep[earlier] && same(earlier, r)
            });
        }
        group = end;
    }
    keep
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
    use super::{first_of_equal_rows, Rows};
    use proptest::prelude::*;

    proptest! {
        /// A row is kept unless an earlier row moves the same vertices in the same order (its
        /// weights aside), as a set of the rows seen so far says; empty rows included.
        #[test]
        fn the_first_of_equal_rows_is_kept(
            rows in proptest::collection::vec(proptest::collection::vec((0u32..3, 0u8..2), 0..3), 0..40),
            cut in proptest::collection::vec(0u32..2, 40),
        ) {
            let mut influence = Rows::new();
            for row in &rows {
                influence.push_row(row.iter().map(|&(v, w)| (v, f64::from(w))));
            }
            let lengths: Vec<u32> =
                rows.iter().zip(&cut).map(|(r, &c)| (r.len() as u32).saturating_sub(c)).collect();
            let mut seen = std::collections::HashSet::new();
            let expected: Vec<bool> = rows
                .iter()
                .zip(&lengths)
                .map(|(r, &n)| seen.insert(r[..n as usize].iter().map(|&(v, _)| v).collect::<Vec<_>>()))
                .collect();
            prop_assert_eq!(first_of_equal_rows(&influence, &lengths), expected);
        }

        /// Rows from pairs hold, row by row, exactly the pairs' items in the pairs' order, as
        /// lists built by pushing would; rows written in place, cut short, compacted and
        /// appended agree with doing the same to those lists.
        #[test]
        fn rows_match_lists(
            pairs in proptest::collection::vec((0u32..7, any::<u16>()), 0..60),
            keep in proptest::collection::vec(any::<bool>(), 7),
            cut in proptest::collection::vec(0u32..4, 7),
        ) {
            let mut lists = vec![Vec::new(); 7];
            for &(r, x) in &pairs {
                lists[r as usize].push(x);
            }
            let rows = Rows::from_pairs(7, &pairs);
            prop_assert_eq!(rows.len(), 7);
            for (r, list) in lists.iter().enumerate() {
                prop_assert_eq!(rows.row(r), &list[..]);
            }
            // The same rows written in place, through `rows_mut`, each reversed there.
            let lengths: Vec<u32> = lists.iter().map(|l| l.len() as u32).collect();
            let mut written = Rows::with_lengths(&lengths, 0u16);
            for (row, list) in written.rows_mut().into_iter().zip(&lists) {
                row.copy_from_slice(list);
                row.reverse();
            }
            let short: Vec<u32> = lengths.iter().zip(&cut).map(|(&n, &c)| n.saturating_sub(c)).collect();
            let kept = written.compacted(&short, &keep);
            let expected: Vec<Vec<u16>> = lists
                .iter()
                .zip(&short)
                .zip(&keep)
                .filter(|(_, &k)| k)
                .map(|((l, &n), _)| l.iter().rev().take(n as usize).copied().collect())
                .collect();
            prop_assert_eq!(kept.len(), expected.len());
            for (r, list) in expected.iter().enumerate() {
                prop_assert_eq!(kept.row(r), &list[..]);
            }
            // Appended in two batches, the rows are the lists again.
            let mut appended = Rows::with_capacity(7, pairs.len());
            for batch in [0..3, 3..7] {
                let items: Vec<u16> = lists[batch.clone()].concat();
                appended.append_rows(&lengths[batch], &items);
            }
            for (r, list) in lists.iter().enumerate() {
                prop_assert_eq!(appended.row(r), &list[..]);
            }
        }
    }
}
