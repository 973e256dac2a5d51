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
    fn from_lists(lists: Vec<Vec<T>>) -> Self {
        let mut first = Vec::with_capacity(lists.len() + 1);
        first.push(0);
        let mut items = Vec::new();
        for list in lists {
            items.extend(list);
            first.push(items.len() as u32);
        }
        Self { first, items }
    }

    pub(crate) fn row(&self, i: usize) -> &[T] {
        &self.items[self.first[i] as usize..self.first[i + 1] as usize]
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

/// Per quad vertex, the quads around it.
pub(crate) fn vertex_quads(mesh: &QuadMesh) -> Rows<u32> {
    let mut lists = vec![Vec::new(); mesh.vertices.len()];
    for (q, quad) in mesh.quads.iter().enumerate() {
        for &v in quad {
            lists[v as usize].push(q as u32);
        }
    }
    Rows::from_lists(lists)
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
        let cells = [triangle_cells(), quad_cells()];
        let mut variable_of = vec![u32::MAX; net.points.len()];
        let mut ids = Vec::new();
        let mut influence: Vec<Vec<(u32, f64)>> = Vec::new();
        let mut ring: Vec<Vec<[u32; 2]>> = Vec::new();
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
                    influence.push(Vec::new());
                    ring.push(Vec::new());
                }
                let i = variable_of[c as usize] as usize;
                for (&v, w) in vertices.iter().zip(&templates[kind].weights) {
                    if w[s] != 0.0 {
                        influence[i].push((v, w[s]));
                    }
                }
                for cell in &cells[kind] {
                    if let Some(at) = cell.iter().position(|&x| x == s) {
                        let n = cell.len();
                        for step in 1..n - 1 {
                            let a = cell[(at + step) % n];
                            let b = cell[(at + step + 1) % n];
                            ring[i].push([patch[a], patch[b]]);
                        }
                    }
                }
            }
        }
        for list in &mut influence {
            // A vertex on a side shared by two patches appears in both, with the same weight.
            list.sort_by_key(|&(v, _)| v);
            list.dedup_by_key(|&mut (v, _)| v);
        }
        // Control points that move exactly the same quad vertices are one degree of freedom
        // solved several times: at level 1 a quad patch's four inner points all move only its
        // centre, and an edge's two inner points the same midpoint and centres. The first of
        // each such set is kept.
        let mut seen = std::collections::HashMap::new();
        let keep: Vec<bool> = influence
            .iter()
            .map(|list| {
                let key: Vec<u32> = list.iter().map(|&(v, _)| v).collect();
                seen.insert(key, ()).is_none()
            })
            .collect();
        fn pick<T>(list: Vec<T>, keep: &[bool]) -> Vec<T> {
            list.into_iter()
                .zip(keep)
                .filter(|&(_, &k)| k)
                .map(|(x, _)| x)
                .collect()
        }
        let (ids, influence, ring) = (pick(ids, &keep), pick(influence, &keep), pick(ring, &keep));
        Self::finish(ids, influence, ring, mesh)
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
        let mut fixed = vec![false; mesh.vertices.len()];
        for (e, &c) in constrained_edges(t, m).iter().enumerate() {
            if c {
                for v in mesh.edge_vertices(t, m, e as u32) {
                    fixed[v as usize] = true;
                }
            }
        }
        let ids: Vec<u32> = (0..mesh.vertices.len() as u32)
            .filter(|&v| !fixed[v as usize] && wanted(v))
            .collect();
        let influence = ids.iter().map(|&v| vec![(v, 1.0)]).collect();
        let ring = vec![Vec::new(); ids.len()];
        Self::finish(ids, influence, ring, mesh)
    }

    fn finish(
        ids: Vec<u32>,
        influence: Vec<Vec<(u32, f64)>>,
        ring: Vec<Vec<[u32; 2]>>,
        mesh: &QuadMesh,
    ) -> Self {
        let around = vertex_quads(mesh);
        let quads: Vec<Vec<u32>> = influence
            .iter()
            .map(|list| {
                let mut qs: Vec<u32> = list
                    .iter()
                    .flat_map(|&(v, _)| around.row(v as usize).iter().copied())
                    .collect();
                qs.sort_unstable();
                qs.dedup();
                qs
            })
            .collect();
        let by_quad = by_quad(&quads, mesh.quads.len());
        let colours = colour(&quads, &by_quad);
        Self {
            ids,
            influence: Rows::from_lists(influence),
            quads: Rows::from_lists(quads),
            ring: Rows::from_lists(ring),
            colours,
            by_quad,
        }
    }

    /// Number of variables (points; twice as many coordinates).
    pub fn len(&self) -> usize {
        self.ids.len()
    }

    /// The weight of variable `i` in vertex `v` (0 when it does not move it).
    pub fn weight(&self, i: usize, v: u32) -> f64 {
        // Rows are short (a point moves at most a patch's vertices): a scan beats a search.
        self.influence
            .row(i)
            .iter()
            .find(|&&(u, _)| u == v)
            .map_or(0.0, |&(_, w)| w)
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
pub(crate) fn by_quad(quads: &[Vec<u32>], n_quads: usize) -> Rows<u32> {
    let mut lists = vec![Vec::new(); n_quads];
    for (i, qs) in quads.iter().enumerate() {
        for &q in qs {
            lists[q as usize].push(i as u32);
        }
    }
    Rows::from_lists(lists)
}

/// Greedy colouring of the variables: each takes the smallest colour no earlier variable sharing
/// one of its quads has.
pub(crate) fn colour(quads: &[Vec<u32>], by_quad: &Rows<u32>) -> Vec<Vec<u32>> {
    let mut colour_of = vec![u32::MAX; quads.len()];
    let mut seen: Vec<usize> = Vec::new();
    let mut colours: Vec<Vec<u32>> = Vec::new();
    for (i, qs) in quads.iter().enumerate() {
        for &q in qs {
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
