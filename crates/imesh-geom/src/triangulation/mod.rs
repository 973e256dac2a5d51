//! The Delaunay triangulation: an index-based half-edge structure closed by ghost triangles.
//!
//! # Representation
//!
//! Triangle `t` owns the half-edges `3t`, `3t + 1`, `3t + 2`, which run counter-clockwise around it;
//! `origin[e]` is the vertex a half-edge leaves and `twin[e]` the opposite half-edge in the
//! neighbouring triangle. Plain `u32` arrays: no pointers, cheap to copy, cache-friendly.
//!
//! Every edge of the convex hull is also bounded, outside, by a *ghost triangle* whose third vertex is
//! the "vertex at infinity" ([`GHOST`]). Real and ghost triangles together tile a topological sphere,
//! so every half-edge has a twin and insertion outside the hull is the same operation as insertion
//! inside it (Shewchuk's convention): a ghost triangle's "circumcircle" is the open half-plane beyond
//! its hull edge plus the open edge itself.

mod check;
mod constrain;
mod insert;

use std::sync::atomic::{AtomicU32, Ordering};

use crate::Point;

pub use check::TriangulationDefect;
pub use constrain::{SegmentId, EXTERIOR};
pub(crate) use insert::Inserted;
pub use insert::Location;

/// The vertex at infinity, third vertex of every ghost triangle.
pub(crate) const GHOST: u32 = u32::MAX;
/// "No half-edge" (a vertex not yet in the triangulation).
pub(crate) const NONE: u32 = u32::MAX;

macro_rules! handle {
    ($(#[$doc:meta])* $name:ident) => {
        $(#[$doc])*
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
        pub struct $name(pub(crate) u32);

        impl $name {
            /// The handle with this raw index.
            pub const fn new(index: u32) -> Self {
                Self(index)
            }

            /// The raw index, for use in plain arrays indexed alongside the triangulation.
            pub const fn index(self) -> usize {
                self.0 as usize
            }
        }
    };
}

handle!(
    /// A vertex of a [`Triangulation`]. Vertex ids are dense: `0..num_vertices()`.
    VertexId
);
handle!(
    /// A triangle slot of a [`Triangulation`]. Slots are dense and reused: an insertion overwrites the
    /// triangles it destroys, and reports the triangles it created
    /// ([`Triangulation::created_triangles`]).
    TriangleId
);
handle!(
    /// A directed half-edge: half-edge `e` belongs to triangle `e / 3`.
    HalfEdgeId
);

/// A Delaunay triangulation of a set of points in the plane, built with exact predicates.
///
/// ```
/// use imesh_geom::{Point, Triangulation};
///
/// // The 3 × 3 pixel centres: all cocircular in groups of four, collinear in rows and columns.
/// let points: Vec<Point> = (0..9).map(|i| Point::pixel_centre(i % 3, i / 3)).collect();
/// let (tri, ids) = Triangulation::from_points(&points).unwrap();
/// assert_eq!(ids.len(), 9);
/// assert_eq!(tri.num_triangles(), 8); // 2n − h − 2 with n = 9, h = 8
/// tri.check().unwrap();
/// ```
pub struct Triangulation {
    pub(crate) points: Vec<Point>,
    pub(crate) origin: Vec<u32>,
    pub(crate) twin: Vec<u32>,
    /// A half-edge leaving each vertex, or `NONE` for a vertex not (yet) in a triangle.
    pub(crate) out_edge: Vec<u32>,
    pub(crate) ghost_count: usize,
    /// While every vertex so far is collinear there are no triangles: the vertices wait here.
    pub(crate) pending: Vec<u32>,
    /// A triangle near the last insertion: point location starts from it.
    pub(crate) hint: AtomicU32,
    pub(crate) created: Vec<TriangleId>,
    pub(crate) scratch: insert::Scratch,
    /// Per half-edge: the input segment it lies on, or `NONE`. Empty until the first constraint.
    pub(crate) segment: Vec<u32>,
    /// The input segments, as their two end vertices.
    pub(crate) segments: Vec<[u32; 2]>,
    /// Per segment: for a conforming segment, its vertices from one end to the other (empty for a
    /// constrained one).
    pub(crate) chains: Vec<Vec<u32>>,
    /// While a conforming segment is being recovered, conforming pieces do not block insertions.
    pub(crate) unblock_conforming: bool,
    /// Per triangle slot: its region label. Empty until labels are assigned.
    pub(crate) label: Vec<u32>,
}

impl Default for Triangulation {
    fn default() -> Self {
        Self::new()
    }
}

impl Clone for Triangulation {
    fn clone(&self) -> Self {
        Self {
            points: self.points.clone(),
            origin: self.origin.clone(),
            twin: self.twin.clone(),
            out_edge: self.out_edge.clone(),
            ghost_count: self.ghost_count,
            pending: self.pending.clone(),
            hint: AtomicU32::new(self.hint.load(Ordering::Relaxed)),
            created: self.created.clone(),
            scratch: insert::Scratch::default(),
            segment: self.segment.clone(),
            segments: self.segments.clone(),
            chains: self.chains.clone(),
            unblock_conforming: false,
            label: self.label.clone(),
        }
    }
}

impl std::fmt::Debug for Triangulation {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Triangulation")
            .field("vertices", &self.num_vertices())
            .field("triangles", &self.num_triangles())
            .field("hull_edges", &self.ghost_count)
            .finish()
    }
}

#[inline]
pub(crate) const fn next(e: u32) -> u32 {
    if e % 3 == 2 {
        e - 2
    } else {
        e + 1
    }
}

#[inline]
pub(crate) const fn prev(e: u32) -> u32 {
    if e % 3 == 0 {
        e + 2
    } else {
        e - 1
    }
}

impl Triangulation {
    /// An empty triangulation.
    pub fn new() -> Self {
        Self {
            points: Vec::new(),
            origin: Vec::new(),
            twin: Vec::new(),
            out_edge: Vec::new(),
            ghost_count: 0,
            pending: Vec::new(),
            hint: AtomicU32::new(0),
            created: Vec::new(),
            scratch: insert::Scratch::default(),
            segment: Vec::new(),
            segments: Vec::new(),
            chains: Vec::new(),
            unblock_conforming: false,
            label: Vec::new(),
        }
    }

    /// An empty triangulation with room for `n` vertices.
    pub fn with_capacity(n: usize) -> Self {
        let mut t = Self::new();
        t.points.reserve(n);
        t.out_edge.reserve(n);
        // A triangulation of n points has fewer than 2n triangles, ghosts included.
        t.origin.reserve(6 * n);
        t.twin.reserve(6 * n);
        t
    }

    /// Number of vertices (distinct points).
    pub fn num_vertices(&self) -> usize {
        self.points.len()
    }

    /// Number of (real) triangles.
    pub fn num_triangles(&self) -> usize {
        self.origin.len() / 3 - self.ghost_count
    }

    /// Number of triangle slots, real and ghost: every [`TriangleId`] indexes below it, so arrays
    /// indexed by [`TriangleId::index`] need this length.
    ///
    /// ```
    /// use imesh_geom::{Point, Triangulation};
    /// let (t, _) = Triangulation::from_points(&[Point::new(0.0, 0.0), Point::new(1.0, 0.0), Point::new(0.0, 1.0)]).unwrap();
    /// assert_eq!(t.num_triangle_slots(), 4); // one real triangle and three ghosts
    /// ```
    pub fn num_triangle_slots(&self) -> usize {
        self.origin.len() / 3
    }

    /// Number of edges on the convex hull (0 while all vertices are collinear).
    pub fn num_hull_edges(&self) -> usize {
        self.ghost_count
    }

    /// True while the vertices are all collinear (or fewer than three): there are no triangles yet.
    ///
    /// ```
    /// use imesh_geom::{Point, Triangulation};
    /// let mut t = Triangulation::new();
    /// t.insert(Point::new(0.0, 0.0)).unwrap();
    /// t.insert(Point::new(1.0, 1.0)).unwrap();
    /// assert!(t.is_degenerate());
    /// t.insert(Point::new(1.0, 0.0)).unwrap();
    /// assert!(!t.is_degenerate());
    /// ```
    pub fn is_degenerate(&self) -> bool {
        self.origin.is_empty()
    }

    /// The position of vertex `v`.
    pub fn point(&self, v: VertexId) -> Point {
        self.points[v.index()]
    }

    /// All vertex positions, indexed by [`VertexId::index`].
    pub fn points(&self) -> &[Point] {
        &self.points
    }

    /// All vertex ids.
    pub fn vertices(&self) -> impl Iterator<Item = VertexId> + '_ {
        (0..self.points.len() as u32).map(VertexId)
    }

    /// True when `t` is a live, real (not ghost) triangle slot.
    pub fn is_triangle(&self, t: TriangleId) -> bool {
        let b = 3 * t.index();
        b + 2 < self.origin.len() && self.origin[b..b + 3].iter().all(|&v| v != GHOST)
    }

    /// All real triangles.
    ///
    /// ```
    /// use imesh_geom::{Point, Triangulation};
    /// let pts = [Point::new(0.0, 0.0), Point::new(2.0, 0.0), Point::new(0.0, 2.0), Point::new(2.0, 2.0)];
    /// let (t, _) = Triangulation::from_points(&pts).unwrap();
    /// let area: f64 = t.triangles().map(|f| t.signed_area(f)).sum();
    /// assert_eq!(area, 4.0);
    /// ```
    pub fn triangles(&self) -> impl Iterator<Item = TriangleId> + '_ {
        self.origin
            .chunks_exact(3)
            .enumerate()
            .filter(|(_, v)| v[0] != GHOST && v[1] != GHOST && v[2] != GHOST)
            .map(|(t, _)| TriangleId(t as u32))
    }

    /// The vertices of triangle `t`, counter-clockwise.
    pub fn triangle_vertices(&self, t: TriangleId) -> [VertexId; 3] {
        let b = 3 * t.index();
        [
            VertexId(self.origin[b]),
            VertexId(self.origin[b + 1]),
            VertexId(self.origin[b + 2]),
        ]
    }

    /// The corner positions of triangle `t`, counter-clockwise.
    pub fn triangle_points(&self, t: TriangleId) -> [Point; 3] {
        self.triangle_vertices(t).map(|v| self.point(v))
    }

    /// Signed area of triangle `t` (positive: triangles are counter-clockwise).
    pub fn signed_area(&self, t: TriangleId) -> f64 {
        let [a, b, c] = self.triangle_points(t);
        0.5 * ((b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x))
    }

    /// Every real triangle as three vertex indices, counter-clockwise: the plain form writers use.
    pub fn triangle_indices(&self) -> Vec<[u32; 3]> {
        self.triangles()
            .map(|t| self.triangle_vertices(t).map(|v| v.0))
            .collect()
    }

    /// One half-edge of every undirected edge between two real vertices: those for which
    /// [`Triangulation::is_edge_representative`] holds, in increasing order.
    pub fn edges(&self) -> impl Iterator<Item = HalfEdgeId> + '_ {
        (0..self.origin.len() as u32)
            .map(HalfEdgeId)
            .filter(|&e| self.is_edge_representative(e))
    }

    /// True when `e` is the half-edge [`Triangulation::edges`] lists for its edge: it lies in a
    /// real triangle, and its twin does not or has a larger id. A filter over the half-edge
    /// slots `0..3 * num_triangle_slots()` that a caller can run in parallel.
    ///
    /// ```
    /// use imesh_geom::{HalfEdgeId, Point, Triangulation};
    /// let pts = [Point::new(0.0, 0.0), Point::new(2.0, 0.0), Point::new(0.0, 2.0), Point::new(2.0, 2.0)];
    /// let (t, _) = Triangulation::from_points(&pts).unwrap();
    /// let listed = (0..3 * t.num_triangle_slots() as u32)
    ///     .filter(|&e| t.is_edge_representative(HalfEdgeId::new(e)))
    ///     .count();
    /// assert_eq!(listed, 5); // the square's four sides and its diagonal
    /// ```
    pub fn is_edge_representative(&self, e: HalfEdgeId) -> bool {
        let o = self.twin[e.index()];
        !self.is_ghost_slot(e.0 / 3) && (e.0 < o || self.is_ghost_slot(o / 3))
    }

    /// The vertex half-edge `e` leaves.
    pub fn origin(&self, e: HalfEdgeId) -> VertexId {
        VertexId(self.origin[e.index()])
    }

    /// The vertex half-edge `e` points to.
    pub fn destination(&self, e: HalfEdgeId) -> VertexId {
        VertexId(self.origin[next(e.0) as usize])
    }

    /// The opposite half-edge, in the neighbouring triangle (a ghost triangle on the hull).
    pub fn twin(&self, e: HalfEdgeId) -> HalfEdgeId {
        HalfEdgeId(self.twin[e.index()])
    }

    /// The next half-edge counter-clockwise around the same triangle.
    pub fn next(&self, e: HalfEdgeId) -> HalfEdgeId {
        HalfEdgeId(next(e.0))
    }

    /// The previous half-edge counter-clockwise around the same triangle.
    pub fn prev(&self, e: HalfEdgeId) -> HalfEdgeId {
        HalfEdgeId(prev(e.0))
    }

    /// The triangle that owns half-edge `e`.
    pub fn triangle_of(&self, e: HalfEdgeId) -> TriangleId {
        TriangleId(e.0 / 3)
    }

    /// The half-edges of triangle `t`: the `i`-th leaves its `i`-th vertex.
    pub fn triangle_edges(&self, t: TriangleId) -> [HalfEdgeId; 3] {
        [
            HalfEdgeId(3 * t.0),
            HalfEdgeId(3 * t.0 + 1),
            HalfEdgeId(3 * t.0 + 2),
        ]
    }

    /// The real triangle on the other side of half-edge `e`, or `None` across the hull.
    pub fn neighbour(&self, e: HalfEdgeId) -> Option<TriangleId> {
        let t = self.twin[e.index()] / 3;
        (!self.is_ghost_slot(t)).then_some(TriangleId(t))
    }

    /// The vertices of the convex hull, counter-clockwise, including the vertices that lie on a hull
    /// edge. Empty while the triangulation is degenerate.
    ///
    /// ```
    /// use imesh_geom::{Point, Triangulation};
    /// let pts: Vec<Point> = (0..9).map(|i| Point::pixel_centre(i % 3, i / 3)).collect();
    /// let (t, _) = Triangulation::from_points(&pts).unwrap();
    /// assert_eq!(t.hull().len(), 8); // everything but the centre
    /// ```
    pub fn hull(&self) -> Vec<VertexId> {
        let Some(start) = (0..self.origin.len() as u32 / 3).find(|&t| self.is_ghost_slot(t)) else {
            return Vec::new();
        };
        let mut hull = Vec::with_capacity(self.ghost_count);
        let mut g = start;
        for _ in 0..self.ghost_count {
            hull.push(VertexId(self.ghost_hull_edge(g).0));
            g = self.next_ghost(g);
        }
        hull
    }

    #[inline]
    pub(crate) fn is_ghost_slot(&self, t: u32) -> bool {
        let b = 3 * t as usize;
        self.origin[b] == GHOST || self.origin[b + 1] == GHOST || self.origin[b + 2] == GHOST
    }

    /// The half-edge of ghost triangle `t` that runs between real vertices.
    #[inline]
    pub(crate) fn ghost_real_edge(&self, t: u32) -> u32 {
        let b = 3 * t;
        if self.origin[b as usize + 2] == GHOST {
            b
        } else if self.origin[b as usize] == GHOST {
            b + 1
        } else {
            b + 2
        }
    }

    /// For ghost triangle `t`: the hull edge `(from, to)` in counter-clockwise hull order.
    fn ghost_hull_edge(&self, t: u32) -> (u32, u32) {
        let e = self.ghost_real_edge(t);
        // The ghost's real half-edge runs clockwise along the hull.
        (self.origin[next(e) as usize], self.origin[e as usize])
    }

    /// The ghost triangle of the next hull edge counter-clockwise.
    fn next_ghost(&self, t: u32) -> u32 {
        // Ghost (u, w, G) holds hull edge w → u. Its half-edge G → u is the twin of u → G, which
        // belongs to the ghost of the hull edge leaving u: the next one counter-clockwise.
        let e = self.ghost_real_edge(t);
        let from_ghost = prev(e); // G → u
        self.twin[from_ghost as usize] / 3
    }
}
