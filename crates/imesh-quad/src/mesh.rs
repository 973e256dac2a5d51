//! The quad mesh Q: template quads of every element of M, with provenance (DESIGN.md §2,
//! step 8).

use std::sync::OnceLock;

use imesh_geom::predicates::orient2d;
use imesh_geom::{Point, Triangulation};

use crate::pairing::{Element, ElementMesh};
use crate::patch::{eval_patch_terms, relaxed_inner, ControlNet};
use crate::template::{Place, Template};
use rayon::prelude::*;

/// An element of M that holds a vertex of Q, and the vertex's canonical coordinates there.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Holder {
    /// The element (index into [`ElementMesh::elements`]).
    pub element: u32,
    /// Canonical coordinates in that element (triangle: weights of corners 1 and 2; quad:
    /// `(s, t)` in the unit square).
    pub coords: [f64; 2],
}

/// Every vertex's [`Holder`]s, compressed by vertex (those of vertex `v` at
/// `first[v]..first[v + 1]`).
#[derive(Clone, Debug)]
struct Holders {
    first: Vec<u32>,
    holders: Vec<Holder>,
}

/// An all-quad mesh made of the templates of M's elements.
#[derive(Clone, Debug)]
pub struct QuadMesh {
    /// Vertex positions.
    pub vertices: Vec<Point>,
    /// Quads as four vertex indices, counter-clockwise (positive orientation).
    pub quads: Vec<[u32; 4]>,
    /// The region label of each quad (its parent's).
    pub labels: Vec<u32>,
    /// The element of M each quad comes from.
    pub parents: Vec<u32>,
    /// The holders of every vertex, indexed on the first call of [`QuadMesh::holders`]: the
    /// pipeline never asks, and building them was a fifth of the templates' time (13 MB of
    /// scattered writes at 10^5 triangles).
    holders: OnceLock<Holders>,
    /// Per element, the vertex of each of its template points (template order).
    point_first: Vec<u32>,
    points: Vec<u32>,
    /// Per element, its first quad (its quads are contiguous).
    quad_first: Vec<u32>,
    /// Per element, its first inner vertex (its inner vertices are consecutive, in the order
    /// of their [`Place::Inside`] numbers), and the end.
    inside_first: Vec<u32>,
    /// DT' vertices (the first vertices of Q).
    corner_count: u32,
    /// The triangle and the quad template.
    templates: Box<[Template; 2]>,
    /// The template level.
    level: u32,
    /// The cubic Bernstein weights of the template points along an M edge, at `along / 2k` for
    /// `along` = 1 … 2k − 1 (index `along − 1`).
    along_edge: Vec<[f64; 4]>,
    /// The ends of each M edge, from its origin.
    edge_ends: Vec<[u32; 2]>,
    /// Per template (triangle, quad), its inner points (template order).
    inside_places: [Vec<u32>; 2],
}

impl QuadMesh {
    /// The templates of level `k` laid over the elements of `m`; positions from `net`.
    ///
    /// Vertices are numbered once: first the DT' vertices (the elements' corners), then the
    /// `2k − 1` points along each M edge, then each element's inner points, so that neighbouring
    /// elements share their edge points without any search.
    pub fn build(t: &Triangulation, m: &ElementMesh, net: &ControlNet, k: u32) -> Self {
        let templates = [Template::triangle(k), Template::quad(k)];
        let template = |e: &Element| &templates[usize::from(matches!(e, Element::Quad(_)))];
        let nv = t.num_vertices() as u32;
        let per_edge = 2 * k - 1;
        let inside_base = nv + per_edge * m.edges.len() as u32;
        // Each element's template points, quads and inner vertices take the next places in
        // element order; their counts depend only on the element's kind, so the places are
        // known up front and the elements are filled in side by side.
        let mut point_first = Vec::with_capacity(m.elements.len() + 1);
        let mut quad_first = Vec::with_capacity(m.elements.len() + 1);
        let mut inside_first = Vec::with_capacity(m.elements.len() + 1);
        let (mut point_count, mut quad_count, mut next_inside) = (0u32, 0u32, inside_base);
        for element in &m.elements {
            let tp = template(element);
            point_first.push(point_count);
            quad_first.push(quad_count);
            inside_first.push(next_inside);
            point_count += tp.places.len() as u32;
            quad_count += tp.quads.len() as u32;
            next_inside += tp.inside;
        }
        point_first.push(point_count);
        quad_first.push(quad_count);
        let mut points = vec![0u32; point_count as usize];
        let mut quads = vec![[0u32; 4]; quad_count as usize];
        let mut labels = vec![0u32; quad_count as usize];
        let mut parents = vec![0u32; quad_count as usize];
        let spans = |first: &[u32]| -> Vec<(usize, usize)> {
            first
                .windows(2)
                .map(|w| (w[0] as usize, (w[1] - w[0]) as usize))
                .collect()
        };
        let (point_spans, quad_spans) = (spans(&point_first), spans(&quad_first));
        let point_slices = disjoint_slices(&mut points, point_spans.into_iter());
        let quad_slices = disjoint_slices(&mut quads, quad_spans.iter().copied());
        let label_slices = disjoint_slices(&mut labels, quad_spans.iter().copied());
        let parent_slices = disjoint_slices(&mut parents, quad_spans.into_iter());
        m.elements
            .par_iter()
            .zip(point_slices)
            .zip(quad_slices.into_par_iter().zip(label_slices))
            .zip(parent_slices)
            .enumerate()
            .for_each(|(index, (((element, ids), (out, label)), parent))| {
                let tp = template(element);
                let corners = element.corners();
                for (id, place) in ids.iter_mut().zip(&tp.places) {
                    *id = match *place {
                        Place::Corner(c) => corners[c as usize],
                        Place::Side { side, position } => {
                            let (e, forward) = m.side_edge(index, side as usize);
                            let along = if forward { position } else { 2 * k - position };
                            nv + per_edge * e + along - 1
                        }
                        Place::Inside(i) => inside_first[index] + i,
                    };
                }
                for (quad, q) in out.iter_mut().zip(&tp.quads) {
                    *quad = q.map(|i| ids[i as usize]);
                }
                label.fill(m.labels[index]);
                parent.fill(index as u32);
            });
        inside_first.push(next_inside);
        let n = next_inside as usize;
        let mut mesh = Self {
            vertices: vec![Point::new(0.0, 0.0); n],
            quads,
            labels,
            parents,
            holders: OnceLock::new(),
            point_first,
            points,
            quad_first,
            inside_first,
            corner_count: nv,
            level: k,
            along_edge: (1..2 * k)
                .map(|along| crate::patch::bernstein3(f64::from(along) / f64::from(2 * k)))
                .collect(),
            edge_ends: m
                .edges
                .iter()
                .map(|&h| [t.origin(h), t.destination(h)].map(|v| v.index() as u32))
                .collect(),
            inside_places: templates.each_ref().map(|tp| {
                (0u32..)
                    .zip(&tp.places)
                    .filter(|(_, place)| matches!(place, Place::Inside(_)))
                    .map(|(i, _)| i)
                    .collect()
            }),
            templates: Box::new(templates),
        };
        let mut edges: Vec<u32> = (0..m.edges.len() as u32).collect();
        mesh.evaluate_edges(net, &mut edges);
        let elements: Vec<usize> = (0..m.elements.len()).collect();
        mesh.evaluate_insides(m, net, &elements);
        mesh
    }

    /// The elements holding vertex `v`, with its canonical coordinates in each.
    pub fn holders(&self, v: u32) -> &[Holder] {
        let Holders { first, holders } = self.holders.get_or_init(|| self.index_holders());
        &holders[first[v as usize] as usize..first[v as usize + 1] as usize]
    }

    /// Every vertex's holders, compressed by vertex.
    fn index_holders(&self) -> Holders {
        let mut first = vec![0u32; self.vertices.len() + 1];
        for &v in &self.points {
            first[v as usize + 1] += 1;
        }
        for v in 0..self.vertices.len() {
            first[v + 1] += first[v];
        }
        let mut fill = first.clone();
        let mut holders = vec![
            Holder {
                element: 0,
                coords: [0.0; 2]
            };
            self.points.len()
        ];
        for index in 0..self.point_first.len() - 1 {
            let template = self.template_of(index);
            for (&v, &coords) in self.element_vertices(index).iter().zip(&template.coords) {
                holders[fill[v as usize] as usize] = Holder {
                    element: index as u32,
                    coords,
                };
                fill[v as usize] += 1;
            }
        }
        Holders { first, holders }
    }

    /// The template of element `index`, known by its quad count: 3k² for a triangle of M,
    /// 4k² for a quad.
    fn template_of(&self, index: usize) -> &Template {
        let quads = self.element_quads(index).len();
        &self.templates[usize::from(quads == self.templates[1].quads.len())]
    }

    /// The vertices of element `index`'s template points, in template order.
    pub fn element_vertices(&self, index: usize) -> &[u32] {
        &self.points[self.point_first[index] as usize..self.point_first[index + 1] as usize]
    }

    /// The vertices of Q along M edge `e`, from the origin of its canonical half-edge to its
    /// destination (`2k + 1` of them).
    pub fn edge_vertices(&self, t: &Triangulation, m: &ElementMesh, e: u32) -> Vec<u32> {
        let h = m.edges[e as usize];
        let per_edge = 2 * self.level - 1;
        let base = self.corner_count + per_edge * e;
        let mut out = Vec::with_capacity(per_edge as usize + 2);
        out.push(t.origin(h).index() as u32);
        out.extend(base..base + per_edge);
        out.push(t.destination(h).index() as u32);
        out
    }

    /// Puts the vertices along every hull edge of M that is parallel to an axis exactly on that
    /// edge's line (the image border, for DT' of an image). A template point on a straight
    /// side is a weighted sum of control points that all share the line's coordinate, and the
    /// weights sum to 1 only up to rounding: the point can land an ulp outside the domain, and
    /// its sides off the border. Returns the number of coordinates moved.
    ///
    /// ```
    /// use imesh_geom::{Point, Triangulation};
    /// use imesh_quad::{ControlNet, ElementMesh, Pairing, QuadMesh};
    /// let square = [(0.0, 0.0), (27.0, 0.0), (27.0, 27.0), (0.0, 27.0)].map(Point::from);
    /// let (t, _) = Triangulation::from_points(&square)?;
    /// let m = ElementMesh::pair(&t, Pairing::Greedy);
    /// let net = ControlNet::straight(&t, &m);
    /// let mut q = QuadMesh::build(&t, &m, &net, 3);
    /// // The right side's points an ulp outside, as a rounded weighted sum can put them.
    /// let outside = f64::from_bits(27f64.to_bits() + 1);
    /// q.vertices.iter_mut().filter(|p| p.x == 27.0).for_each(|p| p.x = outside);
    /// assert_eq!(q.snap_to_border(&t, &m), 7); // 3 · 2 + 1 points on that side
    /// assert!(q.vertices.iter().all(|p| (0.0..=27.0).contains(&p.x)));
    /// # Ok::<(), imesh_geom::GeomError>(())
    /// ```
    pub fn snap_to_border(&mut self, t: &Triangulation, m: &ElementMesh) -> usize {
        let mut moved = 0;
        for (e, &h) in m.edges.iter().enumerate() {
            if t.neighbour(h).is_some() && t.neighbour(t.twin(h)).is_some() {
                continue;
            }
            let (a, b) = (t.point(t.origin(h)), t.point(t.destination(h)));
            for v in self.edge_vertices(t, m, e as u32) {
                let p = &mut self.vertices[v as usize];
                if a.x == b.x && p.x != a.x {
                    p.x = a.x;
                    moved += 1;
                }
                if a.y == b.y && p.y != a.y {
                    p.y = a.y;
                    moved += 1;
                }
            }
        }
        moved
    }

    /// The template level.
    pub fn level(&self) -> u32 {
        self.level
    }

    /// The quads of element `index`.
    pub fn element_quads(&self, index: usize) -> std::ops::Range<usize> {
        self.quad_first[index] as usize..self.quad_first[index + 1] as usize
    }

    /// Re-evaluates the vertices of element `index` from its patch: its sides' M edges
    /// ([`QuadMesh::evaluate_edge`]) and its inner points ([`QuadMesh::evaluate_inside`]).
    pub fn evaluate_element(&mut self, m: &ElementMesh, net: &ControlNet, index: usize) {
        for side in 0..m.side_count(index) {
            self.evaluate_edge(net, m.side_edge(index, side).0);
        }
        self.evaluate_inside(m, net, index);
    }

    /// Re-evaluates the vertices along M edge `e` (its ends and its `2k − 1` template points)
    /// from its four control points: the cubic Bézier of the edge, in the edge's own direction,
    /// which is every patch that has the edge restricted to it. A vertex shared by two
    /// elements thus has the same bits whichever of them is evaluated, and last.
    pub fn evaluate_edge(&mut self, net: &ControlNet, e: u32) {
        let ends = self.edge_ends[e as usize];
        for v in ends {
            self.vertices[v as usize] = net.points[v as usize];
        }
        let per_edge = (2 * self.level - 1) as usize;
        let first = self.corner_count as usize + per_edge * e as usize;
        along_edge(
            &self.along_edge,
            edge_control(net, e, ends),
            &mut self.vertices[first..first + per_edge],
        );
    }

    /// [`QuadMesh::evaluate_edge`] for each of `edges` (distinct; sorted here), in parallel:
    /// each edge's template points are its own slice of the vertices.
    pub(crate) fn evaluate_edges(&mut self, net: &ControlNet, edges: &mut [u32]) {
        edges.sort_unstable();
        let per_edge = (2 * self.level - 1) as usize;
        let (corners, rest) = self.vertices.split_at_mut(self.corner_count as usize);
        let slices = disjoint_slices(
            rest,
            edges.iter().map(|&e| (per_edge * e as usize, per_edge)),
        );
        let (along, ends) = (&self.along_edge, &self.edge_ends);
        edges
            .par_iter()
            .zip(slices)
            .for_each(|(&e, out)| along_edge(along, edge_control(net, e, ends[e as usize]), out));
        for &e in edges.iter() {
            for v in ends[e as usize] {
                corners[v as usize] = net.points[v as usize];
            }
        }
    }

    /// Re-evaluates the inner template points of element `index` (those on no side) from its
    /// patch: all that changes when only its inner control points move.
    pub fn evaluate_inside(&mut self, m: &ElementMesh, net: &ControlNet, index: usize) {
        let (this, mut slices) = InsideView::split(self, &[index]);
        if let Some(out) = slices.pop() {
            this.evaluate(m, index, &net.patch_points(index), out);
        }
    }

    /// [`QuadMesh::evaluate_inside`] for each of `elements` (increasing), in parallel: each
    /// element's inner vertices are consecutive and its own.
    pub(crate) fn evaluate_insides(
        &mut self,
        m: &ElementMesh,
        net: &ControlNet,
        elements: &[usize],
    ) {
        let (this, slices) = InsideView::split(self, elements);
        elements.par_iter().zip(slices).for_each(|(&k, out)| {
            this.evaluate(m, k, &net.patch_points(k), out);
        });
    }

    /// [`ControlNet::relax_inner`] then [`QuadMesh::evaluate_inside`] for each of `elements`
    /// (increasing), in parallel: each element's inner control points and inner vertices are
    /// consecutive and its own.
    pub(crate) fn relax_insides(
        &mut self,
        m: &ElementMesh,
        net: &mut ControlNet,
        elements: &[usize],
    ) {
        let (this, slices) = InsideView::split(self, elements);
        let (boundary, inner, patches) = net.split_inner();
        let first_inner = boundary.len();
        let controls = disjoint_slices(
            inner,
            elements.iter().map(|&k| {
                let count = if matches!(m.elements[k], Element::Quad(_)) {
                    4
                } else {
                    1
                };
                (patches[k][5] as usize - first_inner, count)
            }),
        );
        elements
            .par_iter()
            .zip(controls.into_par_iter().zip(slices))
            .for_each(|(&k, (control, out))| {
                // The patch's boundary control points, and its own inner ones.
                let mut patch = patches[k].map(|c| {
                    if c == u32::MAX {
                        Point::new(0.0, 0.0) // a triangle's unused slot
                    } else if (c as usize) < first_inner {
                        boundary[c as usize]
                    } else {
                        control[(c - patches[k][5]) as usize]
                    }
                });
                let (relaxed, count) = relaxed_inner(&m.elements[k], &patch);
                for &(slot, p) in &relaxed[..count] {
                    patch[slot] = p;
                    control[(patches[k][slot] - patches[k][5]) as usize] = p;
                }
                this.evaluate(m, k, &patch, out);
            });
    }

    /// True when quad `q` has a positive Jacobian at all four corners (exact orientation).
    pub fn is_valid(&self, q: usize) -> bool {
        let p = self.quads[q].map(|v| self.vertices[v as usize]);
        (0..4).all(|i| orient2d(p[(i + 3) % 4], p[i], p[(i + 1) % 4]) > 0.0)
    }

    /// The scaled Jacobian of quad `q`: the least sine of its corner angles, signed (Verdict's
    /// definition for a counter-clockwise quad; negative at a reflex corner), 0 for a quad with a
    /// zero-length side.
    pub fn scaled_jacobian(&self, q: usize) -> f64 {
        scaled_jacobian(&self.quads[q].map(|v| self.vertices[v as usize]))
    }

    /// True when quad `q` is valid ([`QuadMesh::is_valid`]) and its scaled Jacobian is at least
    /// `floor`: the same answer as both tests, with the exact one only for a quad whose scaled
    /// Jacobian is under [`SURE_JACOBIAN`].
    ///
    /// ```
    /// use imesh_geom::{Point, Triangulation};
    /// use imesh_quad::{ControlNet, ElementMesh, Pairing, QuadMesh};
    /// let square = [(0.0, 0.0), (2.0, 0.0), (2.0, 2.0), (0.0, 2.0)].map(Point::from);
    /// let (t, _) = Triangulation::from_points(&square)?;
    /// let m = ElementMesh::pair(&t, Pairing::Greedy);
    /// let q = QuadMesh::build(&t, &m, &ControlNet::straight(&t, &m), 1);
    /// assert!(q.is_valid_above(0, 0.99)); // a square: every corner's sine is 1
    /// # Ok::<(), imesh_geom::GeomError>(())
    /// ```
    pub fn is_valid_above(&self, q: usize, floor: f64) -> bool {
        valid_above(&self.quads[q].map(|v| self.vertices[v as usize]), floor)
    }

    /// Whether every quad of element `index` would pass `passes` (given the quad's index in the
    /// mesh and its corners) if the element's patch had the control points `patch` (by slot):
    /// its template points, those on its sides too, are evaluated from `patch` into a scratch
    /// buffer; nothing is written.
    pub(crate) fn element_valid_with(
        &self,
        index: usize,
        patch: &[Point; 16],
        passes: impl Fn(usize, &[Point; 4]) -> bool,
    ) -> bool {
        let template = self.template_of(index);
        let points: Vec<Point> = template
            .terms
            .iter()
            .map(|terms| eval_patch_terms(patch, terms))
            .collect();
        let first = self.quad_first[index] as usize;
        template
            .quads
            .iter()
            .zip(first..)
            .all(|(quad, x)| passes(x, &quad.map(|i| points[i as usize])))
    }

    /// The total (signed) area of the quads.
    pub fn area(&self) -> f64 {
        self.quads
            .iter()
            .map(|q| {
                let p = q.map(|v| self.vertices[v as usize]);
                0.5 * ((p[2].x - p[0].x) * (p[3].y - p[1].y)
                    - (p[3].x - p[1].x) * (p[2].y - p[0].y))
            })
            .sum()
    }
}

/// What evaluating an element's inner points reads of a [`QuadMesh`], borrowed apart from its
/// vertices (which the evaluation writes).
#[derive(Clone, Copy)]
struct InsideView<'a> {
    templates: &'a [Template; 2],
    places: &'a [Vec<u32>; 2],
    points: &'a [u32],
    point_first: &'a [u32],
    inside_first: &'a [u32],
}

impl<'a> InsideView<'a> {
    /// The view of `q`, and the slices of `q`'s inner vertices of `elements` (increasing).
    fn split(q: &'a mut QuadMesh, elements: &[usize]) -> (Self, Vec<&'a mut [Point]>) {
        // The inner vertices of all come after the corners and edge points, the first
        // element's first.
        let inside_first = &q.inside_first;
        let first = inside_first[0] as usize;
        let (_, inner) = q.vertices.split_at_mut(first);
        let slices = disjoint_slices(
            inner,
            elements.iter().map(|&k| {
                let start = inside_first[k] as usize;
                (start - first, inside_first[k + 1] as usize - start)
            }),
        );
        let view = Self {
            templates: &q.templates,
            places: &q.inside_places,
            points: &q.points,
            point_first: &q.point_first,
            inside_first,
        };
        (view, slices)
    }

    /// Element `k`'s inner points from its control points `patch`, into `out` (its inner
    /// vertices).
    fn evaluate(&self, m: &ElementMesh, k: usize, patch: &[Point; 16], out: &mut [Point]) {
        let kind = usize::from(matches!(m.elements[k], Element::Quad(_)));
        inside_points(
            &self.templates[kind],
            &self.places[kind],
            &self.points[self.point_first[k] as usize..],
            self.inside_first[k],
            patch,
            out,
        );
    }
}

/// The four control points of M edge `e` with ends `ends`, from its origin.
fn edge_control(net: &ControlNet, e: u32, ends: [u32; 2]) -> [Point; 4] {
    let [i, j] = net.edge_inner(e).map(|c| c as usize);
    [
        net.points[ends[0] as usize],
        net.points[i],
        net.points[j],
        net.points[ends[1] as usize],
    ]
}

/// The template points along an edge with Bézier `control`, at the Bernstein weights `along`,
/// into `out`.
fn along_edge(along: &[[f64; 4]], control: [Point; 4], out: &mut [Point]) {
    // Exact on axis-parallel straight edges (the domain border, pixel-aligned boundaries),
    // whatever the rounding of the sum.
    let same_x = control.iter().all(|p| p.x == control[0].x);
    let same_y = control.iter().all(|p| p.y == control[0].y);
    for (v, w) in out.iter_mut().zip(along) {
        let (mut x, mut y) = (0.0, 0.0);
        for (w, p) in w.iter().zip(&control) {
            x += w * p.x;
            y += w * p.y;
        }
        if same_x {
            x = control[0].x;
        }
        if same_y {
            y = control[0].y;
        }
        *v = Point::new(x, y);
    }
}

/// The inner points of an element of template `template` (inner places `places`, vertex ids
/// `ids` by template point, the first inner one `first`) from its control points `patch`,
/// into `out` (its inner vertices, consecutive from `first`).
fn inside_points(
    template: &Template,
    places: &[u32],
    ids: &[u32],
    first: u32,
    patch: &[Point; 16],
    out: &mut [Point],
) {
    for &i in places {
        out[(ids[i as usize] - first) as usize] =
            eval_patch_terms(patch, &template.terms[i as usize]);
    }
}

/// The slices `[start, start + len)` of `data`, for ranges in increasing order that do not
/// overlap: each can be written by its own worker.
pub(crate) fn disjoint_slices<T>(
    mut data: &mut [T],
    ranges: impl Iterator<Item = (usize, usize)>,
) -> Vec<&mut [T]> {
    let mut out = Vec::with_capacity(ranges.size_hint().0);
    let mut offset = 0;
    for (start, len) in ranges {
        let (_, rest) = std::mem::take(&mut data).split_at_mut(start - offset);
        let (slice, rest) = rest.split_at_mut(len);
        out.push(slice);
        data = rest;
        offset = start + len;
    }
    out
}

/// A quad whose scaled Jacobian (as computed) is at least this is valid without the exact
/// test: at every corner the computed cross product `a × b` is then at least `10⁻¹⁰ |a| |b|`,
/// some 10⁵ times the bound on its rounding error (a few ε times `|aₓ b_y| + |a_y bₓ|`, itself at
/// most `2 |a| |b|`), so the exact orientation is positive too.
pub const SURE_JACOBIAN: f64 = 1e-10;

/// [`QuadMesh::is_valid_above`] of the quad with corners `p`.
pub(crate) fn valid_above(p: &[Point; 4], floor: f64) -> bool {
    if floor < SURE_JACOBIAN {
        let jacobian = scaled_jacobian(p);
        return jacobian >= floor
            && (jacobian >= SURE_JACOBIAN
                || (0..4).all(|i| orient2d(p[(i + 3) % 4], p[i], p[(i + 1) % 4]) > 0.0));
    }
    // A positive floor: every corner's sine `α / (|a| |b|)` at least `floor`, squared to
    // spare the roots and divisions (the same test up to a rounding of the last bit).
    let floor2 = floor * floor;
    (0..4).all(|i| {
        let (a, b) = (p[(i + 1) % 4] - p[i], p[(i + 3) % 4] - p[i]);
        let cross = a.x * b.y - a.y * b.x;
        cross > 0.0 && cross * cross >= floor2 * ((a.x * a.x + a.y * a.y) * (b.x * b.x + b.y * b.y))
    })
}

/// The scaled Jacobian of the quad `p`: the least sine of its corner angles, signed (Verdict's
/// definition for a counter-clockwise quad; negative at a reflex corner). 0 for a quad with a
/// zero-length side.
pub(crate) fn scaled_jacobian(p: &[Point; 4]) -> f64 {
    (0..4)
        .map(|i| {
            let (a, b) = (p[(i + 1) % 4] - p[i], p[(i + 3) % 4] - p[i]);
            let lengths = ((a.x * a.x + a.y * a.y) * (b.x * b.x + b.y * b.y)).sqrt();
            if lengths > 0.0 {
                (a.x * b.y - a.y * b.x) / lengths
            } else {
                0.0
            }
        })
        .fold(f64::INFINITY, f64::min)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Pairing;
    use proptest::prelude::*;

    /// A pairing of a jittered grid, its straight net with every control point moved by up to
    /// `shift` (from `moves`), and its level-`k` templates evaluated from the straight net.
    fn moved(
        k: u32,
        moves: &[(f64, f64)],
        shift: f64,
    ) -> (Triangulation, ElementMesh, ControlNet, QuadMesh) {
        let points: Vec<Point> = (0..36u32)
            .map(|i| {
                let (dx, dy) = moves[i as usize % moves.len()];
                Point::new(f64::from(i % 6) + 0.3 * dx, f64::from(i / 6) + 0.3 * dy)
            })
            .collect();
        let (t, _) = Triangulation::from_points(&points).expect("a jittered grid triangulates");
        let m = ElementMesh::pair(&t, Pairing::Greedy);
        let mut net = ControlNet::straight(&t, &m);
        let q = QuadMesh::build(&t, &m, &net, k);
        for (p, &(dx, dy)) in net.points.iter_mut().zip(moves.iter().cycle()) {
            *p = Point::new(p.x + shift * dx, p.y + shift * dy);
        }
        (t, m, net, q)
    }

    proptest! {
        /// The parallel passes write the same bits as the one-at-a-time evaluation, for any
        /// subset of edges (in any order) and of elements.
        #[test]
        fn parallel_passes_match_one_at_a_time(
            k in 1u32..4,
            moves in proptest::collection::vec((-1.0f64..1.0, -1.0f64..1.0), 7..40),
            pick in 1usize..4,
        ) {
            let (_, m, net, q) = moved(k, &moves, 0.05);
            // A subset of the edges, in decreasing order; every element but one in `pick`.
            let mut edges: Vec<u32> = (0..m.edges.len() as u32)
                .rev()
                .filter(|e| *e as usize % pick == 0)
                .collect();
            let elements: Vec<usize> = (0..m.elements.len()).filter(|e| e % pick != 1).collect();

            let (mut one_net, mut one) = (net.clone(), q.clone());
            for &e in &edges {
                one.evaluate_edge(&one_net, e);
            }
            for &index in &elements {
                one_net.relax_inner(&m.elements[index], index);
                one.evaluate_inside(&m, &one_net, index);
            }
            let (mut all_net, mut all) = (net.clone(), q.clone());
            all.evaluate_edges(&all_net, &mut edges);
            all.relax_insides(&m, &mut all_net, &elements);
            prop_assert_eq!(&one.vertices, &all.vertices);
            prop_assert_eq!(&one_net.points, &all_net.points);

            // Without relaxing: the inner points from the net as it is.
            let straight = q.clone();
            let (mut one, mut all) = (q.clone(), q);
            for &index in &elements {
                one.evaluate_inside(&m, &net, index);
            }
            all.evaluate_insides(&m, &net, &elements);
            prop_assert_eq!(&one.vertices, &all.vertices);
            // The net moved, so the passes had something to change.
            prop_assert!(all.vertices != straight.vertices);
        }

        /// The templates and the straight net, laid out element by element in parallel, are
        /// the one-at-a-time layout: each element's template points, quads, labels and
        /// parents, and its inner vertices and inner control points, follow the previous
        /// element's; the net's edge points are at a third and two thirds of their edges.
        #[test]
        fn templates_and_net_are_laid_out_in_element_order(
            k in 1u32..4,
            moves in proptest::collection::vec((-1.0f64..1.0, -1.0f64..1.0), 7..40),
        ) {
            let (t, m, _, q) = moved(k, &moves, 0.0);
            let net = ControlNet::straight(&t, &m);
            let templates = [Template::triangle(k), Template::quad(k)];
            let nv = t.num_vertices() as u32;
            let per_edge = 2 * k - 1;
            let (mut next_inside, mut next_inner) = (nv + per_edge * m.edges.len() as u32, 0);
            let (mut quads, mut points) = (Vec::new(), Vec::new());
            let (mut labels, mut parents) = (Vec::new(), Vec::new());
            for (index, element) in m.elements.iter().enumerate() {
                let tp = &templates[usize::from(matches!(element, Element::Quad(_)))];
                let ids: Vec<u32> = tp
                    .places
                    .iter()
                    .map(|place| match *place {
                        Place::Corner(c) => element.corners()[c as usize],
                        Place::Side { side, position } => {
                            let (e, forward) = m.side_edge(index, side as usize);
                            let along = if forward { position } else { 2 * k - position };
                            nv + per_edge * e + along - 1
                        }
                        Place::Inside(i) => next_inside + i,
                    })
                    .collect();
                next_inside += tp.inside;
                for quad in &tp.quads {
                    quads.push(quad.map(|i| ids[i as usize]));
                    labels.push(m.labels[index]);
                    parents.push(index as u32);
                }
                points.extend(ids);
                // The patch's inner control points: the next ones after the edges'.
                let inner: Vec<u32> = net.patches[index]
                    .iter()
                    .copied()
                    .filter(|&c| c != u32::MAX && c >= net.inner_base)
                    .collect();
                let expected: Vec<u32> = (0..inner.len() as u32)
                    .map(|i| net.inner_base + next_inner + i)
                    .collect();
                prop_assert_eq!(&inner, &expected);
                next_inner += inner.len() as u32;
            }
            prop_assert_eq!(&q.quads, &quads);
            prop_assert_eq!(&q.points, &points);
            prop_assert_eq!(&q.labels, &labels);
            prop_assert_eq!(&q.parents, &parents);
            prop_assert_eq!(q.vertices.len(), next_inside as usize);
            prop_assert_eq!(net.points.len(), (net.inner_base + next_inner) as usize);
            for (e, &h) in m.edges.iter().enumerate() {
                let (a, b) = (t.point(t.origin(h)), t.point(t.destination(h)));
                let at = |i: u32| net.points[(net.edge_base + 2 * e as u32 + i) as usize];
                prop_assert_eq!(at(0), a + (b - a) * (1.0 / 3.0));
                prop_assert_eq!(at(1), a + (b - a) * (2.0 / 3.0));
            }
        }
    }
}
