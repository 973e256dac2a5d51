//! The quad vertices along each curved boundary: per G' edge, the adapted pieces of its curve in
//! order and the quad vertices on them, each at a position along the chain. The optimiser
//! slides boundary vertices along these chains; a second-order mesh puts the middle node of each
//! boundary quad side on the chain between its two ends.

use imesh_curves::CubicBezier;
use imesh_geom::Point;

use crate::Remesh;

/// One G' edge's boundary path as the quad mesh follows it: its pieces (adapted M edges, each an
/// [`crate::EdgeCurve::path`]) in order along it, and the quad vertices on them; vertex `j`
/// lies at [`BoundaryChain::point`]`(along[j])`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BoundaryChain {
    /// The pieces in order, each from where the previous one ends.
    pub pieces: Vec<CubicBezier>,
    /// The quad vertices along the chain, in order.
    pub vertices: Vec<u32>,
    /// Where each vertex lies: piece `⌊along⌋`, at parameter `along − ⌊along⌋` on it
    /// (increasing along the chain).
    pub along: Vec<f64>,
}

impl BoundaryChain {
    /// The point at `along` on the chain (piece `⌊along⌋`, the last piece past its end).
    ///
    /// ```
    /// use imesh_curves::CubicBezier;
    /// use imesh_geom::Point;
    /// use imesh_quad::BoundaryChain;
    /// let line = |a: f64, b: f64| CubicBezier::new([0.0, 1.0, 2.0, 3.0].map(|k| Point::new(a + (b - a) * k / 3.0, 0.0)));
    /// let chain = BoundaryChain { pieces: vec![line(0.0, 1.0), line(1.0, 3.0)], vertices: vec![], along: vec![] };
    /// assert!(chain.point(1.5).distance_squared(Point::new(2.0, 0.0)) < 1e-24);
    /// assert_eq!(chain.point(2.0), Point::new(3.0, 0.0)); // the last piece's end
    /// ```
    pub fn point(&self, along: f64) -> Point {
        let last = self.pieces.len().saturating_sub(1);
        let p = (along.floor().max(0.0) as usize).min(last);
        self.pieces[p].eval(along - p as f64)
    }

    /// Each quad side along the chain (its two vertices, in chain order) with the point of the
    /// chain between them that is as far from either (on the perpendicular bisector of the side,
    /// found by bisection along the chain): where a second-order side's middle node goes, so
    /// that a straight piece gives the side's own middle.
    pub fn middles(&self) -> impl Iterator<Item = ([u32; 2], Point)> + '_ {
        (1..self.vertices.len()).map(|j| {
            let ends = [self.vertices[j - 1], self.vertices[j]];
            let (mut lo, mut hi) = (self.along[j - 1], self.along[j]);
            let (p, q) = (self.point(lo), self.point(hi));
            let (mx, my) = (0.5 * (p.x + q.x), 0.5 * (p.y + q.y));
            // Negative on p's side of the bisector, positive on q's.
            let side = |a: f64| {
                let r = self.point(a);
                (r.x - mx) * (q.x - p.x) + (r.y - my) * (q.y - p.y)
            };
            for _ in 0..MIDDLE_BISECTIONS {
                let mid = 0.5 * (lo + hi);
                if side(mid) < 0.0 {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            (ends, self.point(0.5 * (lo + hi)))
        })
    }
}

/// Halvings of a side's stretch of the chain in [`BoundaryChain::middles`]: 2⁻⁴⁰ of a piece.
const MIDDLE_BISECTIONS: usize = 40;

/// A vertex the template put at parameter `s` of its piece must be there to within this
/// (relative to the piece's size), or the piece is left out of the chains.
const ON_PATH: f64 = 1e-9;

impl Remesh {
    /// The boundary chains of the quad mesh as adaptation left it (every vertex on a curved
    /// boundary where the template put it, at `i / 2k` along its piece): per G' edge, its
    /// adapted pieces sorted along the curve. A gap between pieces, or a piece whose vertices
    /// are not on its path, ends a chain.
    ///
    /// ```
    /// # use imesh_curves::{fit_edges, simplify, CurveGraph, FitOptions, GraphEdge, SimplifyOptions};
    /// # use imesh_geom::Point;
    /// # use imesh_quad::{remesh, QuadOptions};
    /// # let mut points = vec![Point::new(0.0, 0.0), Point::new(20.0, 0.0), Point::new(20.0, 20.0), Point::new(0.0, 20.0)];
    /// # let mut edges: Vec<GraphEdge> = (0..4u32).map(|i| GraphEdge { ends: [i, (i + 1) % 4], labels: [0, u32::MAX] }).collect();
    /// # for i in 0..32u32 {
    /// #     let a = f64::from(i) * std::f64::consts::TAU / 32.0;
    /// #     points.push(Point::new(10.0 + 6.0 * a.cos(), 10.0 + 6.0 * a.sin()));
    /// #     edges.push(GraphEdge { ends: [4 + i, 4 + (i + 1) % 32], labels: [1, 0] });
    /// # }
    /// # let mut g = CurveGraph::new(points, edges)?;
    /// # g.pin_domain_corners(20.0, 20.0);
    /// # let s = simplify(&g, &SimplifyOptions::with_tolerance(0.5))?;
    /// # let curves: Vec<_> = fit_edges(&s, &g, &FitOptions::default()).fits.iter().map(|f| f.curve).collect();
    /// // A disc in a square: its circle's quad vertices lie on their chains.
    /// let r = remesh(&s.graph, &curves, &QuadOptions::default())?;
    /// let chains = r.boundary_chains();
    /// assert!(!chains.is_empty());
    /// for c in &chains {
    ///     for (&v, &a) in c.vertices.iter().zip(&c.along) {
    ///         assert!(c.point(a).distance_squared(r.mesh.vertices[v as usize]) < 1e-18);
    ///     }
    /// }
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn boundary_chains(&self) -> Vec<BoundaryChain> {
        let t = &self.dt.triangulation;
        let per_edge = 2 * self.mesh.level() as usize;
        let mut by_graph_edge: std::collections::BTreeMap<u32, Vec<usize>> = Default::default();
        for (i, ec) in self.edge_curves.iter().enumerate() {
            by_graph_edge.entry(ec.graph_edge).or_default().push(i);
        }
        let mut chains = Vec::new();
        for (_, mut list) in by_graph_edge {
            let lo = |i: &usize| {
                let p = self.edge_curves[*i].parameters;
                p[0].min(p[1])
            };
            list.sort_by(|a, b| lo(a).total_cmp(&lo(b)));
            let mut chain = BoundaryChain::default();
            for i in list {
                let ec = &self.edge_curves[i];
                let mut vertices = self.mesh.edge_vertices(t, &self.elements, ec.edge);
                let mut path = ec.path();
                if ec.parameters[0] > ec.parameters[1] {
                    vertices.reverse();
                    path = path.reversed();
                }
                let size = path.control[0].distance_squared(path.control[3]).sqrt();
                let on_path = vertices.iter().enumerate().all(|(k, &v)| {
                    let s = k as f64 / per_edge as f64;
                    path.eval(s)
                        .distance_squared(self.mesh.vertices[v as usize])
                        .sqrt()
                        <= ON_PATH * (1.0 + size)
                });
                let continues = chain.vertices.last().is_none_or(|&v| v == vertices[0]);
                if !on_path || !continues {
                    // A gap or a piece off its path: what came before is a chain of its own.
                    chains.push(std::mem::take(&mut chain));
                    if !on_path {
                        continue;
                    }
                }
                if chain.vertices.is_empty() {
                    chain.vertices.push(vertices[0]);
                }
                chain.vertices.extend_from_slice(&vertices[1..]);
                chain.pieces.push(path);
            }
            chains.push(chain);
        }
        chains.retain(|c| c.vertices.len() >= 2);
        for c in &mut chains {
            c.along = (0..c.vertices.len())
                .map(|j| j as f64 / per_edge as f64)
                .collect();
        }
        chains
    }
}
