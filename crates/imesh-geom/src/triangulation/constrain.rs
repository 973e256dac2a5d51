//! Constraints: input segments that must be unions of edges, and region labels between them.
//!
//! A *constrained* triangulation keeps every input segment as a chain of edges. Two ways in:
//! - [`Triangulation::insert_segment`] (constrained Delaunay): the segment becomes an edge as it is,
//!   by flipping away the edges that cross it (Sloan's algorithm), then restoring the Delaunay
//!   property everywhere else by Lawson flips. The result is constrained Delaunay: no vertex
//!   *visible* from a triangle lies inside its circumcircle.
//! - [`Triangulation::insert_segment_conforming`]: the segment is split at Steiner points until each
//!   piece is already a Delaunay edge, so the triangulation stays truly Delaunay.
//!
//! Every later insertion respects the segments: a point is never joined across one, and a point on a
//! segment splits it (both halves keep the segment's id). Region labels, assigned by flood fill
//! between segments, are inherited by the triangles that replace a triangle.

use super::{next, prev, HalfEdgeId, TriangleId, Triangulation, VertexId, GHOST, NONE};
use crate::predicates::{incircle, orient2d, strictly_between};
use crate::{GeomError, Point};

/// The label of triangles outside every region (holes, and the outside of a closed boundary).
pub const EXTERIOR: u32 = u32::MAX;

/// An input segment, numbered in insertion order.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct SegmentId(pub u32);

/// Where a walk along a segment from `a` towards `b` goes next.
enum Step {
    /// `a → c` is an edge along the segment (`c` is `b` or a vertex on the segment).
    AlongEdge(u32, u32),
    /// The segment leaves `a` through the interior of the edge `u → w` (half-edge given).
    Crosses(u32),
}

/// The piece of a segment from one vertex to the next vertex on it.
enum Piece {
    /// It runs along this half-edge, to this vertex.
    Edge(u32, u32),
    /// It crosses these edges, to this vertex.
    Crossing { crossed: Vec<[u32; 2]>, end: u32 },
}

impl Triangulation {
    /// Makes the per-half-edge segment array exist.
    fn ensure_constraint_storage(&mut self) {
        if self.segment.is_empty() {
            self.segment = vec![NONE; self.origin.len()];
        }
    }

    /// The input segment half-edge `e` lies on, if any.
    pub fn segment_of(&self, e: HalfEdgeId) -> Option<SegmentId> {
        let s = *self.segment.get(e.index())?;
        (s != NONE).then_some(SegmentId(s))
    }

    /// True when half-edge `e` lies on an input segment.
    pub fn is_constrained(&self, e: HalfEdgeId) -> bool {
        self.segment_of(e).is_some()
    }

    /// The end vertices of input segment `s`, as given.
    pub fn segment_ends(&self, s: SegmentId) -> [VertexId; 2] {
        self.segments[s.0 as usize].map(VertexId)
    }

    /// The vertices along segment `s`, from its first end to its second: for a conforming segment
    /// its Steiner chain, for a constrained one the vertices lying on it.
    pub fn segment_vertices(&self, s: SegmentId) -> Vec<VertexId> {
        let chain = &self.chains[s.0 as usize];
        if !chain.is_empty() {
            return chain.iter().copied().map(VertexId).collect();
        }
        // Follow the segment's pieces from its first end: at each vertex, the constrained edge of
        // this segment that does not lead back.
        let [a, b] = self.segments[s.0 as usize];
        let mut out = vec![VertexId(a)];
        let (mut v, mut from) = (a, NONE);
        while v != b && out.len() <= self.points.len() {
            let Some(w) = self.next_on_segment(s.0, v, from) else {
                break;
            };
            out.push(VertexId(w));
            (from, v) = (v, w);
        }
        out
    }

    /// The neighbour of `v` along segment `s` other than `from`: the far end of the segment's
    /// other piece at `v`, if any.
    pub(crate) fn next_on_segment(&self, s: u32, v: u32, from: u32) -> Option<u32> {
        self.star(v)
            .filter(|&h| self.segment[h as usize] == s)
            .map(|h| self.origin[next(h) as usize])
            .find(|&w| w != from && w != GHOST)
    }

    /// Number of input segments.
    pub fn num_segments(&self) -> usize {
        self.segments.len()
    }

    /// One half-edge of every constrained edge (each a piece of an input segment).
    pub fn constrained_edges(&self) -> impl Iterator<Item = HalfEdgeId> + '_ {
        self.edges().filter(|&e| self.is_constrained(e))
    }

    /// The half-edge `a → b`, if `a b` is an edge.
    pub fn find_edge(&self, a: VertexId, b: VertexId) -> Option<HalfEdgeId> {
        self.star(a.0)
            .find(|&h| self.origin[next(h) as usize] == b.0)
            .map(HalfEdgeId)
    }

    /// The half-edges leaving vertex `v`, counter-clockwise (ghost ones included).
    pub(crate) fn star(&self, v: u32) -> impl Iterator<Item = u32> + '_ {
        let first = self.out_edge.get(v as usize).copied().unwrap_or(NONE);
        let mut h = first;
        let mut done = first == NONE;
        std::iter::from_fn(move || {
            if done {
                return None;
            }
            let out = h;
            h = self.twin[prev(h) as usize];
            done = h == first;
            Some(out)
        })
    }

    /// Flips the edge of half-edge `e` (shared by two real triangles forming a strictly convex
    /// quadrilateral): `a b` becomes `c d`. Returns the new diagonal's half-edge `c → d`.
    pub(crate) fn flip(&mut self, e: u32) -> u32 {
        let t = self.twin[e as usize];
        let (e1, e2, t1, t2) = (next(e), prev(e), next(t), prev(t));
        let (a, b) = (self.origin[e as usize], self.origin[t as usize]);
        let (c, d) = (self.origin[e2 as usize], self.origin[t2 as usize]);
        let (o_e1, o_e2, o_t1, o_t2) = (
            self.twin[e1 as usize],
            self.twin[e2 as usize],
            self.twin[t1 as usize],
            self.twin[t2 as usize],
        );
        let (b1, b2) = (3 * (e / 3), 3 * (t / 3));
        // Triangle 1 becomes (d, b, c), triangle 2 becomes (c, a, d): both counter-clockwise.
        self.origin[b1 as usize..b1 as usize + 3].copy_from_slice(&[d, b, c]);
        self.origin[b2 as usize..b2 as usize + 3].copy_from_slice(&[c, a, d]);
        let mut link = |x: u32, y: u32| {
            self.twin[x as usize] = y;
            self.twin[y as usize] = x;
        };
        link(b1, o_t2);
        link(b1 + 1, o_e1);
        link(b1 + 2, b2 + 2);
        link(b2, o_e2);
        link(b2 + 1, o_t1);
        if !self.segment.is_empty() {
            for h in [b1, b1 + 1, b2, b2 + 1] {
                self.segment[h as usize] = self.segment[self.twin[h as usize] as usize];
            }
            self.segment[(b1 + 2) as usize] = NONE;
            self.segment[(b2 + 2) as usize] = NONE;
        }
        self.out_edge[d as usize] = b1;
        self.out_edge[b as usize] = b1 + 1;
        self.out_edge[c as usize] = b2;
        self.out_edge[a as usize] = b2 + 1;
        b1 + 2
    }

    /// The first step of the straight walk from `a` to `b` (within the convex hull).
    fn first_step(&self, a: u32, b: u32) -> Option<Step> {
        // Most segments are edges already: find those by their ends before any geometry.
        if let Some(h) = self.star(a).find(|&h| self.origin[next(h) as usize] == b) {
            return Some(Step::AlongEdge(h, b));
        }
        let (pa, pb) = (self.points[a as usize], self.points[b as usize]);
        for h in self.star(a) {
            let u = self.origin[next(h) as usize];
            if u == GHOST {
                continue;
            }
            let pu = self.points[u as usize];
            if u == b || (orient2d(pa, pb, pu) == 0.0 && strictly_between(pa, pb, pu)) {
                return Some(Step::AlongEdge(h, u));
            }
            let w = self.origin[prev(h) as usize];
            if w == GHOST {
                continue;
            }
            let pw = self.points[w as usize];
            // b lies strictly inside the angle u a w (counter-clockwise from u to w).
            if orient2d(pa, pu, pb) > 0.0 && orient2d(pa, pb, pw) > 0.0 {
                return Some(Step::Crosses(next(h)));
            }
        }
        None
    }

    /// Inserts the segment between existing vertices `a` and `b` as a constraint (constrained
    /// Delaunay). A vertex lying on the segment splits it: each piece is its own chain of edges.
    /// A segment equal to an earlier one (either way round) is that segment: nothing changes.
    ///
    /// # Errors
    /// [`GeomError::CrossingSegments`] when it crosses or overlaps an earlier segment (nothing is
    /// changed then); [`GeomError::BadSegment`] for equal or unknown
    /// vertices, or a triangulation without triangles.
    ///
    /// ```
    /// use imesh_geom::{Point, Triangulation};
    /// // A square with a vertex near the diagonal that a Delaunay triangulation would connect across.
    /// let pts = [Point::new(0.0, 0.0), Point::new(4.0, 0.0), Point::new(4.0, 4.0), Point::new(0.0, 4.0), Point::new(2.5, 1.5)];
    /// let (mut t, v) = Triangulation::from_points(&pts).unwrap();
    /// let s = t.insert_segment(v[0], v[2]).unwrap();
    /// assert!(t.find_edge(v[0], v[2]).is_some_and(|e| t.segment_of(e) == Some(s)));
    /// t.check().unwrap();
    /// ```
    pub fn insert_segment(&mut self, a: VertexId, b: VertexId) -> Result<SegmentId, GeomError> {
        self.validate_segment(a, b)?;
        if let Some(s) = self.existing_segment(a.0, b.0) {
            return Ok(s);
        }
        self.ensure_constraint_storage();
        // Trace the whole segment first, so that a crossing leaves the triangulation unchanged.
        let mut from = a.0;
        while from != b.0 {
            from = match self.trace_piece(from, b.0)? {
                Piece::Edge(_, c) => c,
                Piece::Crossing { end, .. } => end,
            };
        }
        let id = self.segments.len() as u32;
        self.segments.push([a.0, b.0]);
        self.chains.push(Vec::new());
        let mut from = a.0;
        while from != b.0 {
            from = self.constrain_piece(from, b.0, id)?;
        }
        Ok(SegmentId(id))
    }

    /// The segment with ends `a` and `b` (either way round), if one was inserted: a piece of it
    /// leaves `a` (found through `a`'s edges, not along the line: the split points of a
    /// conforming segment are rounded a hair off it).
    fn existing_segment(&self, a: u32, b: u32) -> Option<SegmentId> {
        if self.segment.is_empty() {
            return None;
        }
        self.star(a)
            .map(|h| self.segment[h as usize])
            .find(|&s| {
                self.segments
                    .get(s as usize)
                    .is_some_and(|&ends| ends == [a, b] || ends == [b, a])
            })
            .map(SegmentId)
    }

    fn validate_segment(&self, a: VertexId, b: VertexId) -> Result<(), GeomError> {
        let n = self.points.len();
        let reason = if self.is_degenerate() {
            Some("the triangulation has no triangles yet (all vertices collinear)")
        } else if a.index() >= n || b.index() >= n {
            Some("unknown vertex")
        } else if a == b {
            Some("both ends are the same vertex")
        } else {
            None
        };
        match reason {
            Some(reason) => Err(GeomError::BadSegment {
                a: a.0,
                b: b.0,
                reason,
            }),
            None => Ok(()),
        }
    }

    /// Traces the piece of a segment from `a` towards `b` up to the first vertex on it, without
    /// changing anything: the edge it runs along, or the edges it crosses.
    /// A piece that runs along or crosses another segment is an error
    /// ([`GeomError::CrossingSegments`]).
    fn trace_piece(&self, a: u32, b: u32) -> Result<Piece, GeomError> {
        let (pa, pb) = (self.points[a as usize], self.points[b as usize]);
        let crossing = match self.first_step(a, b) {
            Some(Step::AlongEdge(h, c)) => {
                if let Some(&s) = self.segment.get(h as usize).filter(|&&s| s != NONE) {
                    // The same piece already belongs to another segment: overlapping segments.
                    return Err(GeomError::CrossingSegments {
                        new: [a, b],
                        existing: self.segments[s as usize],
                        existing_id: s,
                    });
                }
                return Ok(Piece::Edge(h, c));
            }
            Some(Step::Crosses(e)) => e,
            None => {
                return Err(GeomError::BadSegment {
                    a,
                    b,
                    reason: "the segment leaves the convex hull",
                })
            }
        };
        // Walk along the segment collecting the edges it crosses, up to b or a vertex on it.
        let mut crossed: Vec<[u32; 2]> = Vec::new();
        let mut e = crossing;
        loop {
            if let Some(&s) = self.segment.get(e as usize).filter(|&&s| s != NONE) {
                return Err(GeomError::CrossingSegments {
                    new: [a, b],
                    existing: self.segments[s as usize],
                    existing_id: s,
                });
            }
            crossed.push([self.origin[e as usize], self.origin[next(e) as usize]]);
            let t = self.twin[e as usize];
            let x = self.origin[prev(t) as usize];
            let px = self.points[x as usize];
            let side = orient2d(pa, pb, px);
            if x == b || side == 0.0 {
                return Ok(Piece::Crossing { crossed, end: x });
            }
            // Beyond the crossed edge lies the triangle (w, u, x): the walk leaves it through u → x
            // or x → w, whichever has its ends on opposite sides of the segment's line.
            let (n1, n2) = (next(t), prev(t));
            let u = self.origin[n1 as usize];
            let pu = self.points[u as usize];
            e = if (orient2d(pa, pb, pu) > 0.0) == (side > 0.0) {
                n2
            } else {
                n1
            };
        }
    }

    /// Makes the piece of segment `id` from `a` towards `b` an edge, up to the first vertex on the
    /// segment; returns that vertex.
    fn constrain_piece(&mut self, a: u32, b: u32, id: u32) -> Result<u32, GeomError> {
        let pa = self.points[a as usize];
        let (crossed, end) = match self.trace_piece(a, b)? {
            Piece::Edge(h, c) => {
                self.mark(h, id, a, c)?;
                return Ok(c);
            }
            Piece::Crossing { crossed, end } => (crossed, end),
        };
        // Sloan: flip crossing edges until none crosses; a flip is only legal on a strictly convex
        // quadrilateral, so non-convex ones wait for their turn.
        let mut queue: std::collections::VecDeque<[u32; 2]> = crossed.into_iter().collect();
        let mut new_edges: Vec<[u32; 2]> = Vec::new();
        let mut stalls = 0usize;
        while let Some([u, w]) = queue.pop_front() {
            let Some(h) = self.find_edge(VertexId(u), VertexId(w)).map(|h| h.0) else {
                continue;
            };
            let t = self.twin[h as usize];
            let (c, d) = (self.origin[prev(h) as usize], self.origin[prev(t) as usize]);
            let [pu, pw, pc, pd, pe] = [u, w, c, d, end].map(|v| self.points[v as usize]);
            let convex = orient2d(pc, pu, pd) > 0.0 && orient2d(pd, pw, pc) > 0.0;
            if !convex {
                queue.push_back([u, w]);
                stalls += 1;
                if stalls > 4 * queue.len() + 16 {
                    return Err(GeomError::BadSegment {
                        a,
                        b,
                        reason: "no progress while flipping crossing edges (please report)",
                    });
                }
                continue;
            }
            stalls = 0;
            self.flip(h);
            let (sc, sd) = (orient2d(pa, pe, pc), orient2d(pa, pe, pd));
            if (c == a && d == end) || (c == end && d == a) {
                continue;
            }
            if sc != 0.0 && sd != 0.0 && (sc > 0.0) != (sd > 0.0) {
                queue.push_back([c, d]);
            } else {
                new_edges.push([c, d]);
            }
        }
        let h = self
            .find_edge(VertexId(a), VertexId(end))
            .ok_or(GeomError::BadSegment {
                a,
                b,
                reason: "the segment could not be recovered (please report)",
            })?
            .0;
        self.mark(h, id, a, end)?;
        self.legalize(new_edges);
        Ok(end)
    }

    /// Marks the edge of half-edge `h` as part of segment `id`.
    fn mark(&mut self, h: u32, id: u32, a: u32, b: u32) -> Result<(), GeomError> {
        let old = self.segment[h as usize];
        if old != NONE && old != id {
            // The same piece already belongs to another segment: overlapping segments.
            return Err(GeomError::CrossingSegments {
                new: [a, b],
                existing: self.segments[old as usize],
                existing_id: old,
            });
        }
        self.segment[h as usize] = id;
        let t = self.twin[h as usize];
        self.segment[t as usize] = id;
        Ok(())
    }

    /// Lawson's flips: restores the empty-circle property across every unconstrained edge listed
    /// (and those the flips expose).
    fn legalize(&mut self, mut stack: Vec<[u32; 2]>) {
        while let Some([u, w]) = stack.pop() {
            let Some(h) = self.find_edge(VertexId(u), VertexId(w)).map(|h| h.0) else {
                continue;
            };
            let t = self.twin[h as usize];
            if self.segment[h as usize] != NONE
                || self.is_ghost_slot(h / 3)
                || self.is_ghost_slot(t / 3)
            {
                continue;
            }
            let [pa, pb, pc] = [
                self.origin[h as usize],
                self.origin[next(h) as usize],
                self.origin[prev(h) as usize],
            ]
            .map(|v| self.points[v as usize]);
            let d = self.origin[prev(t) as usize];
            if incircle(pa, pb, pc, self.points[d as usize]) > 0.0 {
                let c = self.origin[prev(h) as usize];
                self.flip(h);
                stack.extend([[u, c], [c, w], [w, d], [d, u]]);
            }
        }
    }

    /// Inserts the segment `a b` as a constraint by splitting it at Steiner points until every
    /// piece is a Delaunay edge (a *conforming* Delaunay triangulation: the triangulation stays
    /// Delaunay). Pieces are split at their midpoints, except a piece with exactly one end an input
    /// vertex, which is split where a circle centred there with a power-of-two radius crosses it
    /// (concentric shells: Ruppert's guard against endless splitting near small angles).
    ///
    /// Returns the Steiner vertices created, in order from `a` to `b` (none for a segment equal to
    /// an earlier one, either way round: nothing changes).
    ///
    /// # Errors
    /// As [`insert_segment`](Self::insert_segment): crossing or overlapping an earlier segment is
    /// refused before anything changes. A failure while splitting (a piece too short to split in
    /// floating point) gives the new segment up and leaves the earlier ones whole.
    ///
    /// ```
    /// use imesh_geom::{Point, Triangulation};
    /// let pts = [Point::new(0.0, 0.0), Point::new(8.0, 0.0), Point::new(4.0, 1.0), Point::new(4.0, -1.0)];
    /// let (mut t, v) = Triangulation::from_points(&pts).unwrap();
    /// let steiner = t.insert_segment_conforming(v[2], v[3]).unwrap();
    /// assert!(steiner.is_empty()); // already a Delaunay edge
    /// assert!(t.insert_segment_conforming(v[0], v[1]).is_err()); // it would cross v2–v3
    /// let (mut t, v) = Triangulation::from_points(&pts).unwrap();
    /// let steiner = t.insert_segment_conforming(v[0], v[1]).unwrap();
    /// assert_eq!(t.point(steiner[0]), Point::new(4.0, 0.0)); // v2 and v3 see it at 90°: split
    /// t.check().unwrap();
    /// ```
    pub fn insert_segment_conforming(
        &mut self,
        a: VertexId,
        b: VertexId,
    ) -> Result<Vec<VertexId>, GeomError> {
        self.validate_segment(a, b)?;
        if self.existing_segment(a.0, b.0).is_some() {
            return Ok(Vec::new());
        }
        self.ensure_constraint_storage();
        // Trace the whole segment first, so that a crossing or an overlap leaves the
        // triangulation unchanged. (Splitting both segments where they cross would need a
        // vertex at the crossing, which floating point cannot put on both lines.)
        let mut from = a.0;
        while from != b.0 {
            from = match self.trace_piece(from, b.0)? {
                Piece::Edge(_, c) => c,
                Piece::Crossing { end, .. } => end,
            };
        }
        let id = self.segments.len() as u32;
        self.segments.push([a.0, b.0]);
        self.chains.push(vec![a.0, b.0]);
        let n_input = self.points.len() as u32;
        let before = self.points.len();
        // Recover every conforming piece (a Steiner point may destroy an earlier segment's piece,
        // which is then recovered in turn), with conforming pieces not blocking the insertions, so
        // that the triangulation stays Delaunay.
        self.unblock_conforming = true;
        let result = self
            .recover_conforming_pieces(n_input)
            .and_then(|()| self.mark_conforming_pieces());
        if let Err(e) = result {
            // Give the new segment up. Its Steiner points stay (the triangulation is Delaunay
            // with them), but they may have split or flipped away pieces of earlier conforming
            // segments: recover and mark those again, so that the error leaves every earlier
            // segment whole.
            self.segments.pop();
            self.chains.pop();
            for s in &mut self.segment {
                if *s == id {
                    *s = NONE;
                }
            }
            let restored = self
                .recover_conforming_pieces(n_input)
                .and_then(|()| self.mark_conforming_pieces());
            self.unblock_conforming = false;
            restored?;
            return Err(e);
        }
        self.unblock_conforming = false;
        Ok(self.chains[id as usize]
            .iter()
            .copied()
            .filter(|&v| v as usize >= before)
            .map(VertexId)
            .collect())
    }

    /// Marks every piece of every conforming segment's chain as a constrained edge of its segment.
    fn mark_conforming_pieces(&mut self) -> Result<(), GeomError> {
        for s in 0..self.chains.len() {
            for i in 1..self.chains[s].len() {
                let (u, w) = (self.chains[s][i - 1], self.chains[s][i]);
                let h = self
                    .find_edge(VertexId(u), VertexId(w))
                    .ok_or(GeomError::BadSegment {
                        a: u,
                        b: w,
                        reason: "a conforming piece was lost (please report)",
                    })?;
                self.mark(h.0, s as u32, u, w)?;
            }
        }
        Ok(())
    }

    /// Splits conforming pieces that are not edges until all are.
    fn recover_conforming_pieces(&mut self, n_input: u32) -> Result<(), GeomError> {
        loop {
            let mut changed = false;
            for s in 0..self.chains.len() {
                let mut i = 1;
                while i < self.chains[s].len() {
                    let (u, w) = (self.chains[s][i - 1], self.chains[s][i]);
                    if self.find_edge(VertexId(u), VertexId(w)).is_some() {
                        i += 1;
                        continue;
                    }
                    changed = true;
                    // A vertex already on the piece splits it.
                    if let Some(Step::AlongEdge(_, c)) = self.first_step(u, w) {
                        self.chains[s].insert(i, c);
                        continue;
                    }
                    let m = self.split_point(u, w, n_input);
                    let len = self.chains[s].len();
                    let v = self.insert(m)?;
                    if v.0 == u || v.0 == w {
                        return Err(GeomError::BadSegment {
                            a: u,
                            b: w,
                            reason: "the segment is too short to split in floating point",
                        });
                    }
                    // Unless the insertion split this piece as a constrained edge (which updates
                    // the chain), the new — or coinciding — vertex joins the chain here.
                    if self.chains[s].len() == len {
                        self.chains[s].insert(i, v.0);
                    }
                }
            }
            if !changed {
                return Ok(());
            }
        }
    }

    /// Where to split the piece `u w` of a segment: the midpoint, or a concentric-shell point when
    /// exactly one end is an input vertex (ids below `n_input`).
    pub(crate) fn split_point(&self, u: u32, w: u32, n_input: u32) -> Point {
        let (pu, pw) = (self.points[u as usize], self.points[w as usize]);
        let (apex, other) = match (u < n_input, w < n_input) {
            (true, false) => (pu, pw),
            (false, true) => (pw, pu),
            _ => return pu.midpoint(pw),
        };
        let len = apex.distance_squared(other).sqrt();
        // The power of two nearest to half the length.
        let r = 2f64.powf((0.5 * len).log2().round());
        if !(r > 0.0 && r < len) {
            return pu.midpoint(pw);
        }
        // Rounding may put the point a hair off the segment; splits go through `insert_on_edge`,
        // which splits the edge topologically all the same.
        apex + (other - apex) * (r / len)
    }

    /// Assigns region labels by flood fill: each seed point's triangle gets the seed's label, which
    /// spreads to every triangle reachable without crossing a segment. Unreached triangles (and
    /// triangles reached by no seed) are [`EXTERIOR`]. A later seed overrides an earlier one.
    ///
    /// ```
    /// use imesh_geom::{Point, Triangulation, EXTERIOR};
    /// let pts = [Point::new(0.0, 0.0), Point::new(4.0, 0.0), Point::new(4.0, 4.0), Point::new(0.0, 4.0)];
    /// let (mut t, v) = Triangulation::from_points(&pts).unwrap();
    /// t.insert_segment(v[0], v[2]).unwrap();
    /// t.label_regions(&[(Point::new(3.0, 1.0), 7)]);
    /// let labels: Vec<u32> = t.triangles().map(|f| t.label(f)).collect();
    /// assert!(labels.contains(&7) && labels.contains(&EXTERIOR));
    /// ```
    pub fn label_regions(&mut self, seeds: &[(Point, u32)]) {
        self.label = vec![EXTERIOR; self.origin.len() / 3];
        for &(p, label) in seeds {
            let t = match self.locate(p) {
                super::Location::InTriangle(t) => t.0,
                super::Location::OnEdge(e) | super::Location::OutsideHull(e) => e.0 / 3,
                super::Location::OnVertex(v) => self.out_edge[v.index()] / 3,
                super::Location::NoTriangles => return,
            };
            if self.is_ghost_slot(t) {
                continue;
            }
            self.flood(t, label);
        }
    }

    /// Sets `label` on `t` and every triangle reachable from it without crossing a segment.
    fn flood(&mut self, t: u32, label: u32) {
        let mut stack = vec![t];
        let mut seen = vec![false; self.origin.len() / 3];
        seen[t as usize] = true;
        while let Some(t) = stack.pop() {
            self.label[t as usize] = label;
            for e in 3 * t..3 * t + 3 {
                let o = self.twin[e as usize] / 3;
                let blocked = self.segment.get(e as usize).is_some_and(|&s| s != NONE);
                if !blocked && !seen[o as usize] && !self.is_ghost_slot(o) {
                    seen[o as usize] = true;
                    stack.push(o);
                }
            }
        }
    }

    /// The real triangles around vertex `v`, counter-clockwise.
    ///
    /// ```
    /// use imesh_geom::{Point, Triangulation};
    /// let pts = [Point::new(0.0, 0.0), Point::new(2.0, 0.0), Point::new(2.0, 2.0), Point::new(0.0, 2.0), Point::new(1.0, 1.0)];
    /// let (t, v) = Triangulation::from_points(&pts).unwrap();
    /// assert_eq!(t.vertex_triangles(v[4]).count(), 4);
    /// assert_eq!(t.vertex_triangles(v[0]).count(), 2); // a corner: two of the four triangles
    /// ```
    pub fn vertex_triangles(&self, v: VertexId) -> impl Iterator<Item = TriangleId> + '_ {
        self.star(v.0)
            .map(|h| h / 3)
            .filter(|&t| !self.is_ghost_slot(t))
            .map(TriangleId)
    }

    /// Gives every triangle the label `labels(t)` (e.g. carried from another labelled mesh).
    pub fn set_labels(&mut self, mut labels: impl FnMut(TriangleId) -> u32) {
        self.label = (0..self.origin.len() as u32 / 3)
            .map(|t| {
                if self.is_ghost_slot(t) {
                    EXTERIOR
                } else {
                    labels(TriangleId(t))
                }
            })
            .collect();
    }

    /// The region label of triangle `t` ([`EXTERIOR`] when none was assigned).
    pub fn label(&self, t: TriangleId) -> u32 {
        self.label.get(t.index()).copied().unwrap_or(EXTERIOR)
    }
}
