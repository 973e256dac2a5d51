//! The quad mesh Q: template quads of every element of M, with provenance (DESIGN.md §2,
//! step 8).

use imesh_geom::predicates::orient2d;
use imesh_geom::{Point, Triangulation};

use crate::pairing::{Element, ElementMesh};
use crate::patch::ControlNet;
use crate::template::{Place, Template};

/// An element of M that holds a vertex of Q, and the vertex's canonical coordinates there.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Holder {
    /// The element (index into [`ElementMesh::elements`]).
    pub element: u32,
    /// Canonical coordinates in that element (triangle: weights of corners 1 and 2; quad:
    /// `(s, t)` in the unit square).
    pub coords: [f64; 2],
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
    holder_first: Vec<u32>,
    holders: Vec<Holder>,
    /// Per element, the vertex of each of its template points (template order).
    point_first: Vec<u32>,
    points: Vec<u32>,
    /// Per element, its first quad (its quads are contiguous).
    quad_first: Vec<u32>,
    /// DT' vertices (the first vertices of Q).
    corner_count: u32,
    /// The triangle and the quad template.
    templates: Box<[Template; 2]>,
    /// The template level.
    level: u32,
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
        let mut quads = Vec::new();
        let mut labels = Vec::new();
        let mut parents = Vec::new();
        let mut point_first = vec![0u32];
        let mut points = Vec::new();
        let mut quad_first = vec![0u32];
        let mut next_inside = inside_base;
        for (index, element) in m.elements.iter().enumerate() {
            let tp = template(element);
            let corners = element.corners();
            let start = points.len();
            for place in &tp.places {
                let id = match *place {
                    Place::Corner(c) => corners[c as usize],
                    Place::Side { side, position } => {
                        let (e, forward) = m.side_edge(index, side as usize);
                        let along = if forward { position } else { 2 * k - position };
                        nv + per_edge * e + along - 1
                    }
                    Place::Inside(i) => next_inside + i,
                };
                points.push(id);
            }
            next_inside += tp.inside;
            point_first.push(points.len() as u32);
            for q in &tp.quads {
                quads.push(q.map(|i| points[start + i as usize]));
                labels.push(m.labels[index]);
                parents.push(index as u32);
            }
            quad_first.push(quads.len() as u32);
        }
        let n = next_inside as usize;
        // Holders, compressed by vertex.
        let mut holder_first = vec![0u32; n + 1];
        for &v in &points {
            holder_first[v as usize + 1] += 1;
        }
        for v in 0..n {
            holder_first[v + 1] += holder_first[v];
        }
        let mut fill = holder_first.clone();
        let mut holders = vec![
            Holder {
                element: 0,
                coords: [0.0; 2]
            };
            points.len()
        ];
        for (index, element) in m.elements.iter().enumerate() {
            let tp = template(element);
            let ids = &points[point_first[index] as usize..point_first[index + 1] as usize];
            for (&v, &coords) in ids.iter().zip(&tp.coords) {
                holders[fill[v as usize] as usize] = Holder {
                    element: index as u32,
                    coords,
                };
                fill[v as usize] += 1;
            }
        }
        let mut mesh = Self {
            vertices: vec![Point::new(0.0, 0.0); n],
            quads,
            labels,
            parents,
            holder_first,
            holders,
            point_first,
            points,
            quad_first,
            corner_count: nv,
            level: k,
            templates: Box::new(templates),
        };
        for index in 0..m.elements.len() {
            mesh.evaluate_element(m, net, index);
        }
        mesh
    }

    /// The elements holding vertex `v`, with its canonical coordinates in each.
    pub fn holders(&self, v: u32) -> &[Holder] {
        &self.holders
            [self.holder_first[v as usize] as usize..self.holder_first[v as usize + 1] as usize]
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

    /// Re-evaluates the vertices of element `index` from its patch.
    pub fn evaluate_element(&mut self, m: &ElementMesh, net: &ControlNet, index: usize) {
        let element = &m.elements[index];
        let template = &self.templates[usize::from(matches!(element, Element::Quad(_)))];
        let first = self.point_first[index] as usize;
        for (i, (terms, place)) in template.terms.iter().zip(&template.places).enumerate() {
            let v = self.points[first + i] as usize;
            self.vertices[v] = match *place {
                Place::Side { side, .. } => {
                    net.eval_terms_on_side(element, index, terms, side as usize)
                }
                _ => net.eval_terms(index, terms),
            };
        }
    }

    /// True when quad `q` has a positive Jacobian at all four corners (exact orientation).
    pub fn is_valid(&self, q: usize) -> bool {
        let p = self.quads[q].map(|v| self.vertices[v as usize]);
        (0..4).all(|i| orient2d(p[(i + 3) % 4], p[i], p[(i + 1) % 4]) > 0.0)
    }

    /// The scaled Jacobian of quad `q` (see [`scaled_jacobian`]).
    pub fn scaled_jacobian(&self, q: usize) -> f64 {
        scaled_jacobian(&self.quads[q].map(|v| self.vertices[v as usize]))
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
