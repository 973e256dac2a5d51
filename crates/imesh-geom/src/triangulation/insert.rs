//! Point location and Bowyer–Watson insertion.
//!
//! To insert `p`: walk to the triangle that holds it, then dig the *cavity* — every triangle whose
//! open circumdisk holds `p` (for a ghost triangle: `p` strictly beyond its hull edge, or on the open
//! edge). The cavity is a topological disk with all its vertices on its boundary and `p` strictly
//! inside its kernel, so joining `p` to each boundary edge re-triangulates it, and the result is
//! Delaunay again. Using the *open* disk is what makes pixel grids cheap: a cocircular point does not
//! enlarge the cavity.
//!
//! The cavity's dual graph is a tree (no vertex inside the disk), so a depth-first search that visits
//! each triangle's edges counter-clockwise meets the boundary edges in counter-clockwise order: the new
//! triangles can be linked to each other without any lookup.

use std::collections::HashMap;
use std::sync::atomic::Ordering;

use super::{next, HalfEdgeId, TriangleId, Triangulation, VertexId, EXTERIOR, GHOST, NONE};
use crate::predicates::{incircle, orient2d, strictly_between};
use crate::{GeomError, Point, MAX_COORDINATE, MIN_COORDINATE};

/// Where a point lies in a [`Triangulation`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Location {
    /// On an existing vertex.
    OnVertex(VertexId),
    /// On the interior of an edge; the half-edge belongs to a real triangle holding the point.
    OnEdge(HalfEdgeId),
    /// Strictly inside a triangle.
    InTriangle(TriangleId),
    /// Outside the convex hull, strictly beyond the given hull half-edge (of a real triangle).
    OutsideHull(HalfEdgeId),
    /// The triangulation has no triangles yet (fewer than three non-collinear vertices).
    NoTriangles,
}

/// Reusable buffers for the cavity search.
#[derive(Default)]
pub(crate) struct Scratch {
    stack: Vec<u32>,
    cavity: Vec<u32>,
    /// Boundary edges of the cavity, counter-clockwise: (origin vertex, outside half-edge, the
    /// cavity half-edge it replaces).
    boundary: Vec<(u32, u32, u32)>,
    /// Deduplication of the pending (collinear) vertices.
    pending_index: HashMap<(u64, u64), u32>,
    /// The constrained edges an insertion would touch (see `insert_unless`).
    touched: Vec<u32>,
}

/// Result of a visibility walk.
enum Walk {
    /// A real triangle holding the point (inside or on its boundary).
    Inside(u32),
    /// A ghost triangle whose hull edge has the point strictly beyond it.
    Outside(u32),
}

/// Result of inserting a point: a new vertex, or the existing vertex it coincides with.
pub(crate) enum Inserted {
    New,
    Duplicate(u32),
}

/// Exact bits of a point, with −0 and +0 identified, for duplicate lookup.
fn point_key(p: Point) -> (u64, u64) {
    ((p.x + 0.0).to_bits(), (p.y + 0.0).to_bits())
}

impl Triangulation {
    /// Builds the Delaunay triangulation of `points`.
    ///
    /// Points are inserted in a biased randomised order along a Hilbert curve, which keeps every
    /// walk short; 10^6 points take well under a second. Duplicate points become one vertex. Returns
    /// the triangulation and, for each input point, its vertex: vertex ids follow the input order of
    /// the distinct points.
    ///
    /// # Errors
    /// [`GeomError::NonFinitePoint`] when a coordinate is NaN or infinite.
    ///
    /// ```
    /// use imesh_geom::{Point, Triangulation};
    /// let pts = [Point::new(0.0, 0.0), Point::new(4.0, 0.0), Point::new(0.0, 0.0), Point::new(0.0, 3.0)];
    /// let (t, ids) = Triangulation::from_points(&pts).unwrap();
    /// assert_eq!(t.num_vertices(), 3);
    /// assert_eq!(ids[2], ids[0]);
    /// assert_eq!(t.point(ids[3]), Point::new(0.0, 3.0));
    /// ```
    pub fn from_points(points: &[Point]) -> Result<(Self, Vec<VertexId>), GeomError> {
        validate(points)?;
        // Build with vertices numbered in insertion order, so that the points of neighbouring
        // vertices are neighbours in memory; renumber to input order once at the end.
        let order = crate::spatial_sort::brio_order(points);
        let mut tri = Self::with_capacity(points.len());
        tri.points.extend(order.iter().map(|&i| points[i as usize]));
        tri.out_edge.resize(points.len(), NONE);
        let mut duplicates = Vec::new();
        for rank in 0..points.len() as u32 {
            if let Inserted::Duplicate(kept) = tri.insert_vertex(rank) {
                duplicates.push((rank, kept));
            }
        }
        let ids = tri.renumber_to_input_order(&order, &duplicates);
        tri.created.clear();
        Ok((tri, ids))
    }

    /// Inserts `p` and returns its vertex, or the existing vertex at exactly the same position.
    ///
    /// The triangles this insertion created are then listed by
    /// [`created_triangles`](Self::created_triangles).
    ///
    /// # Errors
    /// [`GeomError::NonFinitePoint`] when a coordinate is NaN or infinite.
    ///
    /// ```
    /// use imesh_geom::{Point, Triangulation};
    /// let mut t = Triangulation::new();
    /// for p in [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0)] {
    ///     t.insert(p.into()).unwrap();
    /// }
    /// let v = t.insert(Point::new(0.25, 0.25)).unwrap();
    /// assert_eq!(t.created_triangles().len(), 3); // the old triangle split in three
    /// assert_eq!(t.insert(Point::new(0.25, 0.25)).unwrap(), v);
    /// ```
    pub fn insert(&mut self, p: Point) -> Result<VertexId, GeomError> {
        validate(std::slice::from_ref(&p))?;
        let v = self.points.len() as u32;
        self.points.push(p);
        self.out_edge.push(NONE);
        self.created.clear();
        match self.insert_vertex(v) {
            Inserted::New => Ok(VertexId(v)),
            Inserted::Duplicate(u) => {
                self.points.pop();
                self.out_edge.pop();
                Ok(VertexId(u))
            }
        }
    }

    /// [`insert`](Self::insert), starting the point location at triangle `near` (a triangle that
    /// holds `p` or is close to it makes the location immediate).
    ///
    /// ```
    /// use imesh_geom::{Point, Triangulation};
    /// let (mut t, _) = Triangulation::from_points(&[Point::new(0.0, 0.0), Point::new(4.0, 0.0), Point::new(0.0, 4.0)]).unwrap();
    /// let f = t.triangles().next().unwrap();
    /// let v = t.insert_near(Point::new(1.0, 1.0), f).unwrap();
    /// assert_eq!(t.point(v), Point::new(1.0, 1.0));
    /// ```
    pub fn insert_near(&mut self, p: Point, near: TriangleId) -> Result<VertexId, GeomError> {
        if 3 * near.index() < self.origin.len() {
            self.hint.store(near.0, Ordering::Relaxed);
        }
        self.insert(p)
    }

    /// Inserts `p`, which lies in the closed real triangle `seed`, unless `veto` objects once it
    /// has seen where: `veto` gets the constrained edges the insertion would touch (the cavity's
    /// constrained boundary half-edges, cavity side, and the constrained edge `p` lies on, if
    /// any) and returns its objection, and then nothing changes. Returns the new vertex, or the
    /// vertex of `seed` that `p` coincides with.
    ///
    /// Refinement asks whether a circumcentre would encroach a segment of its cavity before it
    /// inserts it: digging the cavity once serves both.
    pub(crate) fn insert_unless<R>(
        &mut self,
        p: Point,
        seed: u32,
        veto: impl FnOnce(&Self, &[u32]) -> Option<R>,
    ) -> Result<Result<Inserted, R>, GeomError> {
        validate(std::slice::from_ref(&p))?;
        if let Some(a) = self.vertex_at(seed, p) {
            return Ok(Ok(Inserted::Duplicate(a)));
        }
        let split = self.constrained_edge_through(seed, p);
        self.dig_cavity(seed, p, split);
        let mut touched = std::mem::take(&mut self.scratch.touched);
        touched.clear();
        if !self.segment.is_empty() {
            let boundary = self.scratch.boundary.iter().map(|b| b.2);
            touched.extend(boundary.filter(|&e| self.segment[e as usize] != NONE));
        }
        touched.extend(split);
        let objection = veto(self, &touched);
        self.scratch.touched = touched;
        if let Some(objection) = objection {
            return Ok(Err(objection));
        }
        self.fill_dug_cavity(p, split);
        Ok(Ok(Inserted::New))
    }

    /// Adds `p` as a new vertex and fills the cavity `dig_cavity` left in
    /// the scratch space with its fan; returns the vertex.
    fn fill_dug_cavity(&mut self, p: Point, split: Option<u32>) -> u32 {
        let v = self.points.len() as u32;
        self.points.push(p);
        self.out_edge.push(NONE);
        self.created.clear();
        self.fill_cavity(v, split);
        v
    }

    /// The vertex of real triangle `t` at exactly `p`, if any.
    fn vertex_at(&self, t: u32, p: Point) -> Option<u32> {
        (3 * t..3 * t + 3)
            .map(|e| self.origin[e as usize])
            .find(|&a| self.points[a as usize] == p)
    }

    /// The real triangles created by the last [`insert`](Self::insert) (they replace the triangles
    /// whose circumcircle held the new point). Empty after [`from_points`](Self::from_points).
    pub fn created_triangles(&self) -> &[TriangleId] {
        &self.created
    }

    /// Locates `p`, walking from the triangle of the last insertion or location.
    ///
    /// ```
    /// use imesh_geom::{Location, Point, Triangulation};
    /// let pts = [Point::new(0.0, 0.0), Point::new(2.0, 0.0), Point::new(0.0, 2.0)];
    /// let (t, ids) = Triangulation::from_points(&pts).unwrap();
    /// assert!(matches!(t.locate(Point::new(0.5, 0.5)), Location::InTriangle(_)));
    /// assert!(matches!(t.locate(Point::new(1.0, 1.0)), Location::OnEdge(_)));
    /// assert_eq!(t.locate(Point::new(2.0, 0.0)), Location::OnVertex(ids[1]));
    /// assert!(matches!(t.locate(Point::new(3.0, 3.0)), Location::OutsideHull(_)));
    /// ```
    pub fn locate(&self, p: Point) -> Location {
        if self.is_degenerate() {
            return Location::NoTriangles;
        }
        match self.walk(p) {
            Walk::Outside(g) => {
                Location::OutsideHull(HalfEdgeId(self.twin[self.ghost_real_edge(g) as usize]))
            }
            Walk::Inside(t) => {
                if let Some(a) = self.vertex_at(t, p) {
                    return Location::OnVertex(VertexId(a));
                }
                for e in 3 * t..3 * t + 3 {
                    let (a, b) = (self.origin[e as usize], self.origin[next(e) as usize]);
                    if orient2d(self.points[a as usize], self.points[b as usize], p) == 0.0 {
                        return Location::OnEdge(HalfEdgeId(e));
                    }
                }
                Location::InTriangle(TriangleId(t))
            }
        }
    }

    /// A real triangle to start walking from.
    fn start_triangle(&self) -> u32 {
        let mut t = self.hint.load(Ordering::Relaxed);
        if 3 * t as usize >= self.origin.len() {
            t = 0;
        }
        if self.is_ghost_slot(t) {
            t = self.twin[self.ghost_real_edge(t) as usize] / 3;
        }
        t
    }

    /// Visibility walk: cross any edge that has `p` strictly on its far side until none does. The
    /// edge tried first is drawn pseudo-randomly, which makes the walk terminate on any
    /// triangulation, not only Delaunay ones (Devillers–Pion–Teillaud).
    fn walk(&self, p: Point) -> Walk {
        let mut t = self.start_triangle();
        let mut entered = NONE;
        let mut rng = t.wrapping_mul(0x9e37_79b9) ^ (p.x.to_bits() as u32);
        'step: loop {
            rng ^= rng << 13;
            rng ^= rng >> 17;
            rng ^= rng << 5;
            let r = rng % 3;
            for k in 0..3 {
                let e = 3 * t + (r + k) % 3;
                if e == entered {
                    continue;
                }
                let a = self.points[self.origin[e as usize] as usize];
                let b = self.points[self.origin[next(e) as usize] as usize];
                if orient2d(a, b, p) < 0.0 {
                    let o = self.twin[e as usize];
                    let nt = o / 3;
                    if self.is_ghost_slot(nt) {
                        self.hint.store(t, Ordering::Relaxed);
                        return Walk::Outside(nt);
                    }
                    entered = o;
                    t = nt;
                    continue 'step;
                }
            }
            self.hint.store(t, Ordering::Relaxed);
            return Walk::Inside(t);
        }
    }

    /// True when triangle `t` (real or ghost) must be destroyed by inserting `p`.
    #[inline]
    fn in_cavity(&self, t: u32, p: Point) -> bool {
        let b = 3 * t as usize;
        let (a, bb, c) = (self.origin[b], self.origin[b + 1], self.origin[b + 2]);
        let pt = |v: u32| self.points[v as usize];
        let beyond_hull_edge = |u: u32, w: u32| {
            // Ghost (u, w, GHOST): the real triangle lies right of u → w, the outside to its left.
            let o = orient2d(pt(u), pt(w), p);
            o > 0.0 || (o == 0.0 && strictly_between(pt(u), pt(w), p))
        };
        if c == GHOST {
            beyond_hull_edge(a, bb)
        } else if a == GHOST {
            beyond_hull_edge(bb, c)
        } else if bb == GHOST {
            beyond_hull_edge(c, a)
        } else {
            incircle(pt(a), pt(bb), pt(c), p) > 0.0
        }
    }

    /// Inserts the stored vertex `v`.
    fn insert_vertex(&mut self, v: u32) -> Inserted {
        if self.is_degenerate() {
            return self.insert_collinear(v);
        }
        let p = self.points[v as usize];
        let seed = match self.walk(p) {
            Walk::Outside(g) => g,
            Walk::Inside(t) => {
                if let Some(a) = self.vertex_at(t, p) {
                    return Inserted::Duplicate(a);
                }
                t
            }
        };
        let split = self.constrained_edge_through(seed, p);
        self.dig_cavity(seed, p, split);
        self.fill_cavity(v, split);
        Inserted::New
    }

    /// Inserts `p` as a point of the edge of half-edge `e`, splitting it even when rounding puts the
    /// computed point a hair off the edge's line (a segment's midpoint or shell point between
    /// non-lattice ends): the halves keep the edge's segment. Returns the new vertex, or an end of
    /// the edge when `p` equals it.
    pub(crate) fn insert_on_edge(&mut self, e: u32, p: Point) -> Result<VertexId, GeomError> {
        validate(std::slice::from_ref(&p))?;
        for end in [self.origin[e as usize], self.origin[next(e) as usize]] {
            if self.points[end as usize] == p {
                return Ok(VertexId(end));
            }
        }
        // On a hull edge a point a hair inside would make the hull reflex: nudge it out, by the
        // least multiple of the rounding scale that puts it on or beyond the edge's line.
        let real = if self.is_ghost_slot(e / 3) {
            self.twin[e as usize]
        } else {
            e
        };
        let mut p = p;
        if self.is_ghost_slot(self.twin[real as usize] / 3) {
            let (a, b) = (
                self.points[self.origin[real as usize] as usize],
                self.points[self.origin[next(real) as usize] as usize],
            );
            let d = b - a;
            let outward =
                Point::new(d.y, -d.x) * (f64::EPSILON / d.x.hypot(d.y).max(f64::MIN_POSITIVE));
            let scale = a.magnitude_with(b);
            let mut k = 1.0;
            while orient2d(a, b, p) > 0.0 && k < 1e6 {
                p = p + outward * (k * scale);
                k *= 2.0;
            }
        }
        self.dig_cavity(real / 3, p, Some(e));
        Ok(VertexId(self.fill_dug_cavity(p, Some(e))))
    }

    /// When `p` lies on the interior of a constrained edge of real triangle `t`: that half-edge.
    fn constrained_edge_through(&self, t: u32, p: Point) -> Option<u32> {
        if self.segment.is_empty() || self.is_ghost_slot(t) {
            return None;
        }
        (3 * t..3 * t + 3).find(|&e| {
            self.segment[e as usize] != NONE && {
                let a = self.points[self.origin[e as usize] as usize];
                let b = self.points[self.origin[next(e) as usize] as usize];
                orient2d(a, b, p) == 0.0
            }
        })
    }

    /// Collects the cavity of `p` grown from `seed`, and its boundary in counter-clockwise order.
    ///
    /// The cavity never crosses a constrained edge (the triangulation stays constrained Delaunay),
    /// except `split`, the constrained edge `p` lies on, which the insertion splits.
    fn dig_cavity(&mut self, seed: u32, p: Point, split: Option<u32>) {
        let blocked = |tri: &Self, e: u32| {
            let seg = if tri.segment.is_empty() {
                NONE
            } else {
                tri.segment[e as usize]
            };
            let lifted =
                tri.unblock_conforming && seg != NONE && !tri.chains[seg as usize].is_empty();
            seg != NONE && !lifted && Some(e) != split && Some(tri.twin[e as usize]) != split
        };
        let mut s = std::mem::take(&mut self.scratch);
        self.grow_cavity(&mut s, seed, |e, t, _| {
            // Across the edge being split the neighbour always goes: the point is on that edge (at
            // least up to the rounding of a computed split point).
            let across_split = split.is_some_and(|h| h == e || self.twin[h as usize] == e);
            across_split || (!blocked(self, e) && self.in_cavity(t, p))
        });
        if !self.segment.is_empty() && !self.cavity_is_star_shaped(&s.boundary, p) {
            self.repair_cavity(&mut s, seed, p);
        }
        self.scratch = s;
    }

    /// Depth-first search of the cavity from `seed`: `include(e, t, cavity)` says whether the
    /// triangle `t` across half-edge `e` joins. Each triangle's edges are visited counter-clockwise,
    /// so the boundary edges come out in counter-clockwise order.
    fn grow_cavity(
        &self,
        s: &mut Scratch,
        seed: u32,
        mut include: impl FnMut(u32, u32, &[u32]) -> bool,
    ) {
        s.cavity.clear();
        s.boundary.clear();
        s.stack.clear();
        s.cavity.push(seed);
        s.stack.extend([3 * seed + 2, 3 * seed + 1, 3 * seed]);
        while let Some(e) = s.stack.pop() {
            let o = self.twin[e as usize];
            let t = o / 3;
            if include(e, t, &s.cavity) {
                s.cavity.push(t);
                let n1 = next(o);
                s.stack.push(next(n1));
                s.stack.push(n1);
            } else {
                s.boundary.push((self.origin[e as usize], o, e));
            }
        }
    }

    /// True when `p` sees every (real) boundary edge of the cavity strictly from inside.
    ///
    /// Only constrained edges and hull edges can fail. Across any other boundary edge the
    /// triangulation is locally Delaunay, so the part of the inner triangle's circumdisk beyond
    /// the edge lies inside the outer triangle's circumdisk: `p`, inside the first and outside
    /// the second, is strictly on the inner side.
    fn cavity_is_star_shaped(&self, boundary: &[(u32, u32, u32)], p: Point) -> bool {
        boundary.iter().all(|&(x, o, e)| {
            let y = self.origin[next(e) as usize];
            x == GHOST
                || y == GHOST
                || (self.segment[e as usize] == NONE && !self.is_ghost_slot(o / 3))
                || orient2d(self.points[x as usize], self.points[y as usize], p) > 0.0
        })
    }

    /// Constraints can make the cavity reach, around the free end of a segment, triangles that `p`
    /// cannot see; joining `p` to them would cross the segment. Drop the triangles owning boundary
    /// edges `p` does not see strictly, keep what stays connected to the seed, and repeat until the
    /// cavity is star-shaped from `p`. (The seed holds `p`, so it is never dropped.)
    fn repair_cavity(&self, s: &mut Scratch, seed: u32, p: Point) {
        let mut members: std::collections::HashSet<u32> = s.cavity.iter().copied().collect();
        loop {
            let hidden: Vec<u32> = s
                .boundary
                .iter()
                .filter(|&&(x, _, e)| {
                    let y = self.origin[next(e) as usize];
                    x != GHOST
                        && y != GHOST
                        && orient2d(self.points[x as usize], self.points[y as usize], p) <= 0.0
                })
                .map(|&(_, _, e)| e / 3)
                .filter(|&t| t != seed)
                .collect();
            if hidden.is_empty() {
                return;
            }
            for t in hidden {
                members.remove(&t);
            }
            self.grow_cavity(s, seed, |_, t, cavity| {
                t != seed && members.contains(&t) && !cavity.contains(&t)
            });
        }
    }

    /// Replaces the cavity by the fan of triangles joining `v` to its boundary. When `split` is the
    /// constrained edge `v` lies on, the two spokes to its ends inherit its segment; every new
    /// triangle inherits the label of the cavity triangle on its side.
    fn fill_cavity(&mut self, v: u32, split: Option<u32>) {
        let mut s = std::mem::take(&mut self.scratch);
        let m = s.boundary.len();
        debug_assert_eq!(m, s.cavity.len() + 2);
        let ghosts_removed = s.cavity.iter().filter(|&&t| self.is_ghost_slot(t)).count();
        let constrained = !self.segment.is_empty();
        let labelled = !self.label.is_empty();
        // Read everything the rewrite overwrites: labels of the replaced triangles, the split segment.
        let side_label: Vec<u32> = if labelled {
            s.boundary
                .iter()
                .map(|b| self.label[(b.2 / 3) as usize])
                .collect()
        } else {
            Vec::new()
        };
        let split_segment = split.map(|e| {
            (
                self.segment[e as usize],
                self.origin[e as usize],
                self.origin[next(e) as usize],
            )
        });
        for _ in 0..m - s.cavity.len() {
            s.cavity.push((self.origin.len() / 3) as u32);
            self.origin.extend([0; 3]);
            self.twin.extend([0; 3]);
            if constrained {
                self.segment.extend([NONE; 3]);
            }
            if labelled {
                self.label.push(EXTERIOR);
            }
        }
        let mut ghosts_added = 0;
        self.created.clear();
        // Indexed: triangle i is linked to triangle (i + 1) mod m around the fan.
        #[allow(clippy::needless_range_loop)]
        for i in 0..m {
            let t = s.cavity[i];
            let (x, outside, _) = s.boundary[i];
            let y = s.boundary[(i + 1) % m].0;
            let tn = s.cavity[(i + 1) % m];
            let b = 3 * t as usize;
            self.origin[b] = x;
            self.origin[b + 1] = y;
            self.origin[b + 2] = v;
            self.twin[b] = outside;
            self.twin[outside as usize] = 3 * t;
            // (y → v) here is the twin of (v → y) in the next triangle of the fan.
            self.twin[b + 1] = 3 * tn + 2;
            self.twin[3 * tn as usize + 2] = 3 * t + 1;
            if x != GHOST {
                self.out_edge[x as usize] = 3 * t;
            }
            if constrained {
                self.segment[b] = self.segment[outside as usize];
                // The spoke v–y (between this triangle and the next) continues a split segment
                // when y is one of its ends.
                let spoke = match split_segment {
                    Some((seg, a, c)) if y == a || y == c => seg,
                    _ => NONE,
                };
                self.segment[b + 1] = spoke;
                self.segment[3 * tn as usize + 2] = spoke;
            }
            if labelled {
                self.label[t as usize] = side_label[i];
            }
            if x == GHOST || y == GHOST {
                ghosts_added += 1;
            } else {
                self.created.push(TriangleId(t));
            }
        }
        self.out_edge[v as usize] = 3 * s.cavity[0] + 2;
        if let Some((seg, a, c)) = split_segment {
            // A split conforming segment keeps its vertex chain up to date.
            let chain = &mut self.chains[seg as usize];
            if let Some(i) = chain
                .windows(2)
                .position(|w| (w[0] == a && w[1] == c) || (w[0] == c && w[1] == a))
            {
                chain.insert(i + 1, v);
            }
        }
        self.ghost_count = self.ghost_count + ghosts_added - ghosts_removed;
        if let Some(t) = self.created.first() {
            self.hint.store(t.0, Ordering::Relaxed);
        }
        self.scratch = s;
    }

    /// Insertion while all vertices so far are collinear: keep the vertex pending until a point off
    /// their line arrives, then build the first triangle and insert the pending vertices into it.
    fn insert_collinear(&mut self, v: u32) -> Inserted {
        let p = self.points[v as usize];
        if let Some(&u) = self.scratch.pending_index.get(&point_key(p)) {
            return Inserted::Duplicate(u);
        }
        if let [a, b, ..] = self.pending[..] {
            let (pa, pb) = (self.points[a as usize], self.points[b as usize]);
            let o = orient2d(pa, pb, p);
            if o != 0.0 {
                let (a, b) = if o > 0.0 { (a, b) } else { (b, a) };
                self.first_triangle(a, b, v);
                let pending = std::mem::take(&mut self.pending);
                self.scratch.pending_index = HashMap::new();
                for &u in &pending[2..] {
                    self.insert_vertex(u);
                }
                self.created = self.triangles().collect();
                return Inserted::New;
            }
        }
        self.pending.push(v);
        self.scratch.pending_index.insert(point_key(p), v);
        Inserted::New
    }

    /// The counter-clockwise triangle `a b c` and its three ghosts.
    fn first_triangle(&mut self, a: u32, b: u32, c: u32) {
        // Slot 0: (a, b, c). Slots 1–3: ghosts (b, a, G), (c, b, G), (a, c, G).
        self.origin = vec![a, b, c, b, a, GHOST, c, b, GHOST, a, c, GHOST];
        self.twin = vec![3, 6, 9, 0, 11, 7, 1, 5, 10, 2, 8, 4];
        self.out_edge[a as usize] = 0;
        self.out_edge[b as usize] = 1;
        self.out_edge[c as usize] = 2;
        debug_assert!(self.segment.is_empty() && self.label.is_empty());
        self.ghost_count = 3;
        self.hint.store(0, Ordering::Relaxed);
    }

    /// After a bulk build in which vertex `rank` is input point `order[rank]`: drops the vertices
    /// that duplicated another (pairs `(duplicate, kept)`, as ranks) and renumbers the rest densely
    /// in input order. Returns the vertex of every input point.
    fn renumber_to_input_order(
        &mut self,
        order: &[u32],
        duplicates: &[(u32, u32)],
    ) -> Vec<VertexId> {
        let n = order.len();
        let mut dropped = vec![false; n]; // by input index
        for &(rank, _) in duplicates {
            dropped[order[rank as usize] as usize] = true;
        }
        let mut id_of_input = vec![NONE; n];
        let mut next_id = 0u32;
        for (input, &gone) in dropped.iter().enumerate() {
            if !gone {
                id_of_input[input] = next_id;
                next_id += 1;
            }
        }
        let mut new_id: Vec<u32> = order.iter().map(|&i| id_of_input[i as usize]).collect();
        for &(rank, kept) in duplicates {
            new_id[rank as usize] = new_id[kept as usize];
            id_of_input[order[rank as usize] as usize] = new_id[kept as usize];
        }
        for o in &mut self.origin {
            if *o != GHOST {
                *o = new_id[*o as usize];
            }
        }
        for p in &mut self.pending {
            *p = new_id[*p as usize];
        }
        let distinct = next_id as usize;
        let mut points = vec![Point::default(); distinct];
        let mut out_edge = vec![NONE; distinct];
        for rank in 0..n {
            let id = new_id[rank] as usize;
            if !dropped[order[rank] as usize] {
                points[id] = self.points[rank];
                out_edge[id] = self.out_edge[rank];
            }
        }
        self.points = points;
        self.out_edge = out_edge;
        if !self.scratch.pending_index.is_empty() {
            self.scratch.pending_index = self
                .pending
                .iter()
                .map(|&v| (point_key(self.points[v as usize]), v))
                .collect();
        }
        id_of_input.into_iter().map(VertexId).collect()
    }
}

fn validate(points: &[Point]) -> Result<(), GeomError> {
    if let Some(index) = points.iter().position(|p| !p.is_finite()) {
        let Point { x, y } = points[index];
        return Err(GeomError::NonFinitePoint { index, x, y });
    }
    let in_range = |c: f64| c == 0.0 || (MIN_COORDINATE..=MAX_COORDINATE).contains(&c.abs());
    match points
        .iter()
        .position(|p| !(in_range(p.x) && in_range(p.y)))
    {
        Some(index) => {
            let Point { x, y } = points[index];
            Err(GeomError::OutOfRange { index, x, y })
        }
        None => Ok(()),
    }
}
