//! Second-order elements: a node in the middle of every element side, on the curved boundary
//! where the side runs along one, and one at the centre of every quad. The writers then emit
//! 9-node quads and 6-node triangles (Gmsh, VTK) or 8-node quads and 6-node triangles (Abaqus,
//! whose plane elements have no 9-node quad): the centre node is the one that makes the
//! 9-node quad the 8-node one, so both files describe the same elements.

use imesh_quality::curved::{keeps_share_of_straight, serendipity_centre, Quad9};
use imesh_quality::Element;
use rayon::prelude::*;

use crate::SegmentedMeshData;

/// No node (a triangle's fourth side, a triangle's centre).
pub const NO_NODE: u32 = u32::MAX;

/// A curved quad's Jacobian determinant must stay at least this share of its straight
/// (bilinear) self's smallest corner value everywhere (proved by
/// [`imesh_quality::curved::keeps_share_of_straight`]); otherwise its curved sides are pulled
/// back towards straight.
pub const CURVED_JACOBIAN_SHARE: f64 = 0.5;

/// A curve point closer than this share of its side's length to the side's line leaves the
/// side straight.
const STRAIGHT: f64 = 1e-9;

/// The smallest share of a curve point's offset kept before a side is straightened.
const MIN_SHARE: f64 = 0.25;

/// The extra nodes of a second-order mesh, numbered after the mesh's vertices.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SecondOrder {
    /// Their positions, image coordinates: the side middles first (one per element side,
    /// shared by the two elements of an inner side), then the quads' centres.
    pub points: Vec<[f64; 2]>,
    /// Per element, the node in the middle of its side k (from corner k to corner k + 1, in
    /// the element's own order); [`NO_NODE`] past a triangle's third side.
    pub sides: Vec<[u32; 4]>,
    /// Per element, a quad's centre node; [`NO_NODE`] for a triangle.
    pub centres: Vec<u32>,
    /// Every element side (smaller vertex first), sorted, with its middle node.
    pub edges: Vec<([u32; 2], u32)>,
    /// Sides whose middle node lies off the straight side: on its curve, or part of the way
    /// there ([`SecondOrder::damped`]).
    pub curved: usize,
    /// Of those, sides whose middle node was moved back towards the straight middle (a half or
    /// a quarter of the curve's offset kept): the curve point would have let their quad's
    /// Jacobian fall under [`CURVED_JACOBIAN_SHARE`] of the straight quad's.
    pub damped: usize,
    /// Sides offered a curve point but left straight, even a quarter of its offset bending a
    /// quad too far.
    pub straightened: usize,
}

impl SecondOrder {
    /// The second-order nodes of `mesh`: each side's middle node halfway along it, or at the
    /// point `curved` gives for that side (an edge of two vertices, either way round) when both
    /// its elements are quads and stay valid with it: a quad whose Jacobian would fall under
    /// [`CURVED_JACOBIAN_SHARE`] of its straight self's anywhere has its curved sides
    /// straightened, and its neighbours across them checked again. The result is valid
    /// wherever the straight mesh is.
    ///
    /// ```
    /// use imesh_io::{SecondOrder, SegmentedMeshData};
    /// use imesh_quality::Element;
    /// // Two unit squares side by side; their shared side bulges 0.1 to the right.
    /// let mesh = SegmentedMeshData {
    ///     vertices: vec![[0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [0.0, 1.0], [1.0, 1.0], [2.0, 1.0]],
    ///     elements: vec![Element::Quad([0, 1, 4, 3]), Element::Quad([1, 2, 5, 4])],
    ///     labels: vec![0, 1], label_names: vec!["a".into(), "b".into()],
    ///     label_colours: vec![[0; 3]; 2], width: 2, height: 1, second_order: None,
    /// };
    /// let so = SecondOrder::new(&mesh, &[([4, 1], [1.1, 0.5])]);
    /// assert_eq!(so.curved, 1);
    /// // 7 sides and 2 centres; the shared side's middle node is the curve's point.
    /// assert_eq!(so.points.len(), 9);
    /// let middle = so.middle([1, 4]).unwrap();
    /// assert_eq!(so.points[(middle - 6) as usize], [1.1, 0.5]);
    /// assert_eq!(so.sides[0][1], middle);
    /// assert_eq!(so.sides[1][3], middle);
    /// ```
    pub fn new(mesh: &SegmentedMeshData, curved: &[([u32; 2], [f64; 2])]) -> Self {
        let n = mesh.vertices.len() as u32;
        // 1. A middle node per side, halfway along it, and a centre node per quad.
        let mut sides = Sides::of(mesh);
        let straight = sides.straight_middles(mesh);
        let mut so = SecondOrder {
            points: straight.clone(),
            sides: std::mem::take(&mut sides.nodes),
            centres: vec![NO_NODE; mesh.elements.len()],
            edges: std::mem::take(&mut sides.edges),
            ..Default::default()
        };
        let mut next = n + so.edges.len() as u32;
        for (centre, e) in so.centres.iter_mut().zip(&mesh.elements) {
            if matches!(e, Element::Quad(_)) {
                *centre = next;
                next += 1;
            }
        }
        so.points.resize((next - n) as usize, [0.0; 2]);
        // 2. The curve points offered to sides only quads hold, off the side's own line.
        let mut share = vec![0.0; so.edges.len()];
        let mut offset = vec![[0.0; 2]; so.edges.len()];
        for &(edge, p) in curved {
            let Some(k) = so.edge_index(edge) else {
                continue;
            };
            let off = [p[0] - straight[k][0], p[1] - straight[k][1]];
            let [a, b] = so.edges[k].0.map(|v| mesh.vertices[v as usize]);
            let along = [b[0] - a[0], b[1] - a[1]];
            let length = along[0].hypot(along[1]);
            let across = (off[0] * along[1] - off[1] * along[0]).abs() / length;
            if sides.quads_only[k]
                && off.iter().all(|x| x.is_finite())
                && across > STRAIGHT * length
            {
                so.points[k] = p;
                offset[k] = off;
                share[k] = 1.0;
            }
        }
        let offered = share.iter().filter(|&&w| w > 0.0).count();
        // 3. The quads with a curved side are checked; one that fails has its curved sides'
        // middle nodes moved halfway back to the straight middles (down to a quarter, then
        // straight), and both quads of each such side are checked again (a half may not be
        // enough), until none fails. A quad with straight sides is its bilinear self, valid
        // since its corners are.
        let mut check: Vec<usize> = (0..mesh.elements.len())
            .filter(|&i| so.side_indices(n, i).any(|k| share[k] > 0.0))
            .collect();
        while !check.is_empty() {
            check.sort_unstable();
            check.dedup();
            let failing: Vec<usize> = check
                .par_iter()
                .copied()
                .filter(|&i| !so.fits(mesh, i))
                .collect();
            check.clear();
            for i in failing {
                let own: Vec<usize> = so.side_indices(n, i).collect();
                for k in own {
                    if share[k] == 0.0 {
                        continue;
                    }
                    share[k] = if share[k] > MIN_SHARE {
                        share[k] / 2.0
                    } else {
                        0.0
                    };
                    so.points[k] = [0, 1].map(|d| straight[k][d] + share[k] * offset[k][d]);
                    check.extend(sides.elements_of(k));
                }
            }
        }
        so.curved = share.iter().filter(|&&w| w > 0.0).count();
        so.damped = share.iter().filter(|&&w| w > 0.0 && w < 1.0).count();
        so.straightened = offered - so.curved;
        so.place_centres(mesh, n);
        so
    }

    /// The middle node of the side between vertices `edge` (either way round), if it is one.
    pub fn middle(&self, edge: [u32; 2]) -> Option<u32> {
        self.edge_index(edge).map(|k| self.edges[k].1)
    }

    /// The index into [`SecondOrder::edges`] of the side between vertices `edge`.
    fn edge_index(&self, edge: [u32; 2]) -> Option<usize> {
        let key = [edge[0].min(edge[1]), edge[0].max(edge[1])];
        self.edges.binary_search_by(|x| x.0.cmp(&key)).ok()
    }

    /// The indices into [`SecondOrder::edges`] of element `i`'s sides (`n` vertices).
    fn side_indices(&self, n: u32, i: usize) -> impl Iterator<Item = usize> + '_ {
        self.sides[i]
            .iter()
            .filter(|&&node| node != NO_NODE)
            .map(move |&node| (node - n) as usize)
    }

    /// Puts every quad's centre node where the 8-node quad of its corners and middles has it.
    fn place_centres(&mut self, mesh: &SegmentedMeshData, n: u32) {
        for i in 0..mesh.elements.len() {
            if let Some(q) = self.quad9(mesh, i) {
                self.points[(self.centres[i] - n) as usize] = q[8];
            }
        }
    }

    /// Element `i`'s nine nodes (Gmsh's order: corners, side middles, centre), the centre the
    /// serendipity one its node holds; `None` for a triangle.
    pub fn quad9(&self, mesh: &SegmentedMeshData, i: usize) -> Option<Quad9> {
        let Element::Quad(c) = mesh.elements[i] else {
            return None;
        };
        let n = mesh.vertices.len();
        let corners = c.map(|v| mesh.vertices[v as usize]);
        let middles = self.sides[i].map(|node| self.points[node as usize - n]);
        let mut q = [[0.0; 2]; 9];
        q[..4].copy_from_slice(&corners);
        q[4..8].copy_from_slice(&middles);
        q[8] = serendipity_centre(&corners, &middles);
        Some(q)
    }

    /// Whether element `i` keeps its Jacobian above [`CURVED_JACOBIAN_SHARE`] of its straight
    /// self's smallest corner value (a triangle, always straight, does).
    fn fits(&self, mesh: &SegmentedMeshData, i: usize) -> bool {
        self.quad9(mesh, i)
            .is_none_or(|q| keeps_share_of_straight(&q, CURVED_JACOBIAN_SHARE))
    }
}

/// Every element side of a mesh, by edge.
struct Sides {
    /// Every side as (edge, element, side number), sorted: an edge's sides are consecutive.
    all: Vec<([u32; 2], u32, u8)>,
    /// Per edge, where its sides start in `all` (and the end, last).
    start: Vec<usize>,
    /// The edges, sorted, each with its middle node (numbered after the vertices); handed to
    /// [`SecondOrder::edges`].
    edges: Vec<([u32; 2], u32)>,
    /// Per element, the middle node of each side; handed to [`SecondOrder::sides`].
    nodes: Vec<[u32; 4]>,
    /// Per edge, whether only quads hold it.
    quads_only: Vec<bool>,
}

impl Sides {
    fn of(mesh: &SegmentedMeshData) -> Self {
        let n = mesh.vertices.len() as u32;
        let mut all: Vec<([u32; 2], u32, u8)> = Vec::with_capacity(4 * mesh.elements.len());
        for (i, e) in mesh.elements.iter().enumerate() {
            let c = e.corners();
            for k in 0..c.len() {
                let (a, b) = (c[k], c[(k + 1) % c.len()]);
                all.push(([a.min(b), a.max(b)], i as u32, k as u8));
            }
        }
        all.par_sort_unstable();
        let mut sides = Sides {
            start: Vec::new(),
            edges: Vec::new(),
            nodes: vec![[NO_NODE; 4]; mesh.elements.len()],
            quads_only: Vec::new(),
            all: Vec::new(),
        };
        let mut at = 0;
        for run in all.chunk_by(|x, y| x.0 == y.0) {
            let node = n + sides.edges.len() as u32;
            sides.edges.push((run[0].0, node));
            sides.start.push(at);
            at += run.len();
            sides.quads_only.push(
                run.iter()
                    .all(|&(_, i, _)| matches!(mesh.elements[i as usize], Element::Quad(_))),
            );
            for &(_, i, k) in run {
                sides.nodes[i as usize][k as usize] = node;
            }
        }
        sides.start.push(at);
        sides.all = all;
        sides
    }

    /// Each edge's midpoint.
    fn straight_middles(&self, mesh: &SegmentedMeshData) -> Vec<[f64; 2]> {
        self.edges
            .iter()
            .map(|&([a, b], _)| {
                let (p, q) = (mesh.vertices[a as usize], mesh.vertices[b as usize]);
                [0.5 * (p[0] + q[0]), 0.5 * (p[1] + q[1])]
            })
            .collect()
    }

    /// The elements holding edge `k`.
    fn elements_of(&self, k: usize) -> impl Iterator<Item = usize> + '_ {
        self.all[self.start[k]..self.start[k + 1]]
            .iter()
            .map(|x| x.1 as usize)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use imesh_quality::curved::{area, jacobian_coefficients};
    use proptest::prelude::*;

    /// A `w × h` grid of unit squares (counter-clockwise with y down), its inner vertices
    /// moved by `jitter`; the last column split into triangles when `triangles`.
    fn grid(w: u32, h: u32, jitter: &[[f64; 2]], triangles: bool) -> SegmentedMeshData {
        let id = |c: u32, r: u32| r * (w + 1) + c;
        let mut vertices: Vec<[f64; 2]> = (0..=h)
            .flat_map(|r| (0..=w).map(move |c| [f64::from(c), f64::from(r)]))
            .collect();
        for r in 1..h {
            for c in 1..w {
                let j = jitter[(id(c, r) as usize) % jitter.len()];
                let v = &mut vertices[id(c, r) as usize];
                v[0] += j[0];
                v[1] += j[1];
            }
        }
        let mut elements = Vec::new();
        for r in 0..h {
            for c in 0..w {
                let [a, b, d, e] = [id(c, r), id(c + 1, r), id(c + 1, r + 1), id(c, r + 1)];
                if triangles && c + 1 == w {
                    elements.push(Element::Triangle([a, b, d]));
                    elements.push(Element::Triangle([a, d, e]));
                } else {
                    elements.push(Element::Quad([a, b, d, e]));
                }
            }
        }
        let labels = vec![0; elements.len()];
        SegmentedMeshData {
            vertices,
            elements,
            labels,
            label_names: vec!["a".into()],
            label_colours: vec![[0; 3]],
            width: w,
            height: h,
            second_order: None,
        }
    }

    proptest! {
        /// Whatever curve points are offered (some would fold their quads): every quad ends up
        /// above half its straight self's Jacobian at every point of a fine sample, shares its
        /// sides' middle nodes with its neighbours, and the curved quads cover exactly the
        /// straight mesh's area (an inner side's bulge is one quad's gain and the other's
        /// loss); a kept offer is the point offered, a damped one a half or a quarter of the way
        /// there, a triangle's side is never bent, and the counts add up.
        #[test]
        fn curved_sides_keep_every_quad_valid_and_conforming(
            w in 1u32..6, h in 1u32..6,
            jitter in proptest::collection::vec(proptest::array::uniform2(-0.2f64..0.2), 1..8),
            offers in proptest::collection::vec((0usize..200, proptest::array::uniform2(-0.7f64..0.7)), 0..30),
            triangles: bool,
        ) {
            let mesh = grid(w, h, &jitter, triangles);
            // Offers on inner sides (two elements), each edge once.
            let mut inner: Vec<[u32; 2]> = Vec::new();
            for (i, e) in mesh.elements.iter().enumerate() {
                let c = e.corners();
                for k in 0..c.len() {
                    let (a, b) = (c[k], c[(k + 1) % c.len()]);
                    let shared = mesh.elements.iter().enumerate().any(|(j, f)| {
                        j != i && f.corners().contains(&a) && f.corners().contains(&b)
                    });
                    if shared && a < b {
                        inner.push([a, b]);
                    }
                }
            }
            inner.sort_unstable();
            inner.dedup();
            let mut curved: Vec<([u32; 2], [f64; 2])> = Vec::new();
            for &(k, d) in &offers {
                if inner.is_empty() {
                    break;
                }
                let e = inner[k % inner.len()];
                if curved.iter().any(|(x, _)| *x == e) {
                    continue;
                }
                let [p, q] = e.map(|v| mesh.vertices[v as usize]);
                curved.push((e, [(p[0] + q[0]) / 2.0 + d[0], (p[1] + q[1]) / 2.0 + d[1]]));
            }
            let so = SecondOrder::new(&mesh, &curved);
            let n = mesh.vertices.len();
            let quads = mesh.elements.iter().filter(|e| matches!(e, Element::Quad(_))).count();
            prop_assert_eq!(so.points.len(), so.edges.len() + quads);
            let mut total = 0.0;
            for (i, e) in mesh.elements.iter().enumerate() {
                let c = e.corners();
                for k in 0..c.len() {
                    prop_assert_eq!(Some(so.sides[i][k]), so.middle([c[(k + 1) % c.len()], c[k]]));
                }
                match e {
                    Element::Triangle(t) => {
                        total += imesh_quality::signed_area(&t.map(|v| mesh.vertices[v as usize]));
                        for k in 0..3 {
                            let [p, q] = [t[k], t[(k + 1) % 3]].map(|v| mesh.vertices[v as usize]);
                            let m = so.points[so.sides[i][k] as usize - n];
                            prop_assert_eq!(m, [0.5 * (p[0] + q[0]), 0.5 * (p[1] + q[1])]);
                        }
                    }
                    Element::Quad(_) => {
                        let q = so.quad9(&mesh, i).unwrap();
                        let coefficients = jacobian_coefficients(&q);
                        let corners = [coefficients[0], coefficients[3], coefficients[12], coefficients[15]];
                        let straight = {
                            let mut s = q;
                            for k in 0..4 {
                                let (a, b) = (q[k], q[(k + 1) % 4]);
                                s[4 + k] = [0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1])];
                            }
                            s[8] = serendipity_centre(&[s[0], s[1], s[2], s[3]], &[s[4], s[5], s[6], s[7]]);
                            jacobian_coefficients(&s)
                        };
                        let floor = CURVED_JACOBIAN_SHARE
                            * [straight[0], straight[3], straight[12], straight[15]].iter().copied().fold(f64::INFINITY, f64::min);
                        prop_assert!(corners.iter().all(|&x| x >= floor - 1e-12));
                        for a in 0..=12 {
                            for b in 0..=12 {
                                let (u, v) = (a as f64 / 12.0, b as f64 / 12.0);
                                let bu = [(1.0 - u).powi(3), 3.0 * u * (1.0 - u).powi(2), 3.0 * u * u * (1.0 - u), u.powi(3)];
                                let bv = [(1.0 - v).powi(3), 3.0 * v * (1.0 - v).powi(2), 3.0 * v * v * (1.0 - v), v.powi(3)];
                                let value: f64 = (0..16).map(|k| coefficients[k] * bu[k % 4] * bv[k / 4]).sum();
                                prop_assert!(value >= floor - 1e-12, "quad {} at ({}, {}): {} < {}", i, u, v, value, floor);
                            }
                        }
                        total += area(&q);
                    }
                }
            }
            prop_assert!((total - f64::from(w * h)).abs() < 1e-9 * f64::from(w * h));
            let mut kept = 0;
            for &(e, p) in &curved {
                let k = so.middle(e).unwrap() as usize - n;
                let [a, b] = e.map(|v| mesh.vertices[v as usize]);
                let half = [0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1])];
                let m = so.points[k];
                let bent = m != half;
                kept += usize::from(bent);
                if bent {
                    let share = [1.0, 0.5, 0.25].into_iter().find(|s| {
                        (0..2).all(|d| (half[d] + s * (p[d] - half[d]) - m[d]).abs() < 1e-12)
                    });
                    prop_assert!(share.is_some(), "{:?} is not on the way to {:?}", m, p);
                }
            }
            prop_assert_eq!(kept, so.curved);
            // Offers to a triangle's side, or of a point on the side's line, are not taken.
            let on_quads = curved
                .iter()
                .filter(|(e, p)| {
                    let [a, b] = e.map(|v| mesh.vertices[v as usize]);
                    let half = [0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1])];
                    let (off, along) = ([p[0] - half[0], p[1] - half[1]], [b[0] - a[0], b[1] - a[1]]);
                    let length = along[0].hypot(along[1]);
                    (off[0] * along[1] - off[1] * along[0]).abs() / length > STRAIGHT * length
                })
                .filter(|(e, _)| {
                    mesh.elements.iter().all(|x| {
                        matches!(x, Element::Quad(_))
                            || !(x.corners().contains(&e[0]) && x.corners().contains(&e[1]))
                    })
                })
                .count();
            prop_assert_eq!(so.curved + so.straightened, on_quads);
            prop_assert!(so.damped <= so.curved);
        }
    }

    /// A side bent across its quad is pulled back until the quad is valid again, and the
    /// counts say so.
    #[test]
    fn a_side_bent_across_its_quad_is_pulled_back() {
        let mesh = grid(2, 1, &[[0.0; 2]], false);
        // The shared side from (1, 0) to (1, 1), its middle pushed 0.9 into the right quad.
        let so = SecondOrder::new(&mesh, &[([1, 4], [1.9, 0.5])]);
        let m = so.points[so.middle([1, 4]).unwrap() as usize - mesh.vertices.len()];
        assert!(m[0] < 1.9 && m[0] > 1.0, "{m:?}");
        assert_eq!((so.curved, so.damped, so.straightened), (1, 1, 0));
        for i in 0..2 {
            assert!(so.fits(&mesh, i));
        }
    }
}
