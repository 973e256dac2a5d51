//! Ruppert's Delaunay refinement, with the refinements Triangle made standard.
//!
//! Bad triangles (smallest angle below θ, or area above a maximum) are processed worst first from a
//! heap keyed on the smallest angle, which inserts markedly fewer points than a FIFO. Encroached
//! subsegments (a vertex strictly inside their diametral circle) are split before any triangle.
//! A bad triangle's circumcentre is found by a straight walk from the triangle: if a segment blocks
//! the walk, or the circumcentre would encroach a segment of its cavity, the segment is split
//! instead. Segments are split at midpoints, or on concentric power-of-two shells around an input
//! vertex, so that small input angles cannot make splitting cascade forever. Triangles whose
//! smallest angle lies between two segments (an input angle) cannot be improved and are left alone,
//! and an insertion cap bounds the work on any input. Triangles labelled [`EXTERIOR`] are never
//! refined.

use std::cmp::Ordering;
use std::collections::BinaryHeap;

use crate::predicates::orient2d;
use crate::triangulation::{next, prev, NONE};
use crate::{GeomError, Point, TriangleId, Triangulation, VertexId, EXTERIOR};

/// Parameters of [`Triangulation::refine`].
#[derive(Clone, Debug, PartialEq)]
pub struct RefineOptions {
    /// Smallest angle wanted, in degrees (default 20.7°; at most 34°).
    pub min_angle_deg: f64,
    /// Most points to insert (default: unlimited, `usize::MAX`).
    pub max_steiner: usize,
    /// Largest triangle area wanted, if any.
    pub max_area: Option<f64>,
}

impl Default for RefineOptions {
    fn default() -> Self {
        Self {
            min_angle_deg: 20.7,
            max_steiner: usize::MAX,
            max_area: None,
        }
    }
}

/// Why refinement stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StopReason {
    /// Every refinable triangle meets the criteria, or cannot be improved.
    Done,
    /// The insertion cap was reached.
    CapReached,
}

/// What [`Triangulation::refine`] did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RefineReport {
    /// Points inserted.
    pub inserted: usize,
    /// Refinable triangles still below the angle bound (near small input angles, or vetoed).
    pub bad_left: usize,
    /// Why it stopped.
    pub stopped: StopReason,
}

/// A queued bad triangle: its vertices (to detect a triangle that no longer exists) and its key.
struct Bad {
    key: f64,
    vertices: [u32; 3],
}

impl PartialEq for Bad {
    fn eq(&self, o: &Self) -> bool {
        self.cmp(o) == Ordering::Equal
    }
}
impl Eq for Bad {}
impl PartialOrd for Bad {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}
impl Ord for Bad {
    /// Smallest angle first (the heap is a max-heap on the reversed key), then by vertices for
    /// determinism.
    fn cmp(&self, o: &Self) -> Ordering {
        o.key
            .total_cmp(&self.key)
            .then_with(|| o.vertices.cmp(&self.vertices))
    }
}

/// Where the walk to a circumcentre ended.
enum Target {
    /// The point lies in a real triangle reached without crossing a segment.
    Found,
    /// A segment (or the hull) is in the way: its half-edge.
    Blocked(u32),
}

fn circumcentre(a: Point, b: Point, c: Point) -> Point {
    let (bx, by) = (b.x - a.x, b.y - a.y);
    let (cx, cy) = (c.x - a.x, c.y - a.y);
    let d = 2.0 * (bx * cy - by * cx);
    let (b2, c2) = (bx * bx + by * by, cx * cx + cy * cy);
    Point::new(a.x + (cy * b2 - by * c2) / d, a.y + (bx * c2 - cx * b2) / d)
}

/// Squared sine-free measure of the smallest angle: returns (smallest angle in radians, the corner).
fn smallest_angle(p: [Point; 3]) -> (f64, usize) {
    let mut best = (f64::INFINITY, 0);
    for k in 0..3 {
        let (o, u, w) = (p[k], p[(k + 1) % 3], p[(k + 2) % 3]);
        let (a, b) = (u - o, w - o);
        let angle = (a.x * b.y - a.y * b.x).abs().atan2(a.x * b.x + a.y * b.y);
        if angle < best.0 {
            best = (angle, k);
        }
    }
    best
}

impl Triangulation {
    /// Refines the triangulation until every refinable triangle has its smallest angle at least
    /// `options.min_angle_deg` (and area at most `options.max_area`), except next to small input
    /// angles. Hull edges become segments first. Returns what was done.
    ///
    /// # Errors
    /// [`GeomError::BadAngle`] for an angle above 34° (refinement would not terminate) or not
    /// positive.
    ///
    /// ```
    /// use imesh_geom::{Point, RefineOptions, Triangulation};
    /// let pts = [Point::new(0.0, 0.0), Point::new(10.0, 0.0), Point::new(10.0, 1.0), Point::new(0.0, 1.0)];
    /// let (mut t, _) = Triangulation::from_points(&pts).unwrap();
    /// let report = t.refine(&RefineOptions { min_angle_deg: 30.0, ..Default::default() }).unwrap();
    /// assert!(report.inserted > 0 && report.bad_left == 0);
    /// t.check().unwrap();
    /// ```
    pub fn refine(&mut self, options: &RefineOptions) -> Result<RefineReport, GeomError> {
        self.refine_with_policy(options, |_, _, _| true)
    }

    /// [`refine`](Self::refine), with a `policy` that may veto a circumcentre. Circumcentres that lie
    /// beyond a segment (outside the domain, or in another labelled region) or that encroach a
    /// segment are never inserted: the segment is split instead, before the policy is asked. The
    /// policy sees the rest — the bad triangle and a circumcentre reachable without crossing a
    /// segment — and a veto leaves that triangle as it is (counted in `bad_left`).
    ///
    /// # Errors
    /// As [`refine`](Self::refine).
    pub fn refine_with_policy(
        &mut self,
        options: &RefineOptions,
        mut policy: impl FnMut(&Triangulation, TriangleId, Point) -> bool,
    ) -> Result<RefineReport, GeomError> {
        let deg = options.min_angle_deg;
        if !(deg > 0.0 && deg <= 34.0) {
            return Err(GeomError::BadAngle { degrees: deg });
        }
        let mut report = RefineReport {
            inserted: 0,
            bad_left: 0,
            stopped: StopReason::Done,
        };
        if self.is_degenerate() {
            return Ok(report);
        }
        self.constrain_hull()?;
        let min_angle = deg.to_radians();
        let n_input = self.points.len() as u32;
        let mut heap = BinaryHeap::new();
        let all: Vec<u32> = (0..self.origin.len() as u32 / 3).collect();
        self.queue_bad(&all, min_angle, options.max_area, &mut heap);
        let mut encroached: Vec<[u32; 2]> = self.encroached_among(&all);
        // Segments that must be split whether or not a vertex encroaches them now: they block a
        // circumcentre, or the circumcentre would encroach them.
        let mut forced: Vec<[u32; 2]> = Vec::new();
        loop {
            if report.inserted >= options.max_steiner {
                report.stopped = StopReason::CapReached;
                break;
            }
            // Forced splits first, then splits of segments an existing vertex still encroaches.
            let pending_split = forced
                .pop()
                .map(|s| (s, true))
                .or_else(|| encroached.pop().map(|s| (s, false)));
            if let Some(([u, w], forced_split)) = pending_split {
                if let Some(h) = self.find_edge(VertexId(u), VertexId(w)) {
                    if (forced_split || self.is_encroached(h.0))
                        && self.split_segment(h.0, n_input)?
                    {
                        report.inserted += 1;
                        self.after_insertion(
                            min_angle,
                            options.max_area,
                            &mut heap,
                            &mut encroached,
                        );
                    }
                }
                continue;
            }
            let Some(bad) = heap.pop() else { break };
            let Some(t) = self.triangle_with(bad.vertices) else {
                continue;
            };
            let p = self.triangle_points(TriangleId(t));
            let (angle, corner) = smallest_angle(p);
            let too_big = options
                .max_area
                .is_some_and(|m| self.signed_area(TriangleId(t)) > m);
            if angle >= min_angle && !too_big {
                continue;
            }
            if !too_big && self.is_input_angle(t, corner) {
                report.bad_left += 1;
                continue;
            }
            let c = circumcentre(p[0], p[1], p[2]);
            if !c.is_finite() {
                report.bad_left += 1;
                continue;
            }
            match self.walk_to(t, c) {
                Target::Blocked(h) => {
                    if self.splittable(h) {
                        forced.push([self.origin[h as usize], self.origin[next(h) as usize]]);
                        heap.push(bad);
                    } else {
                        report.bad_left += 1;
                    }
                }
                Target::Found => {
                    let threatened = self.segments_encroached_by(t, c);
                    if !threatened.is_empty() {
                        if self.all_splittable(&threatened) {
                            forced.extend(threatened);
                            heap.push(bad);
                        } else {
                            report.bad_left += 1;
                        }
                    } else if !policy(self, TriangleId(t), c) {
                        report.bad_left += 1;
                    } else {
                        let before = self.points.len();
                        self.insert(c)?;
                        if self.points.len() > before {
                            report.inserted += 1;
                            self.after_insertion(
                                min_angle,
                                options.max_area,
                                &mut heap,
                                &mut encroached,
                            );
                        } else {
                            report.bad_left += 1;
                        }
                    }
                }
            }
        }
        if report.stopped == StopReason::Done {
            // Count what is left below the bound (input angles).
            report.bad_left = (0..self.origin.len() as u32 / 3)
                .filter(|&t| {
                    self.refinable(t)
                        && smallest_angle(self.triangle_points(TriangleId(t))).0 < min_angle
                })
                .count();
        }
        Ok(report)
    }

    /// Marks every hull edge as a segment (the domain border).
    fn constrain_hull(&mut self) -> Result<(), GeomError> {
        let hull = self.hull();
        for i in 0..hull.len() {
            let (a, b) = (hull[i], hull[(i + 1) % hull.len()]);
            if let Some(h) = self.find_edge(a, b) {
                if !self.is_constrained(h) {
                    self.insert_segment(a, b)?;
                }
            }
        }
        Ok(())
    }

    fn refinable(&self, t: u32) -> bool {
        !self.is_ghost_slot(t) && (self.label.is_empty() || self.label[t as usize] != EXTERIOR)
    }

    /// The live triangle with exactly these vertices (in this rotation order), if any.
    fn triangle_with(&self, v: [u32; 3]) -> Option<u32> {
        let h = self.find_edge(VertexId(v[0]), VertexId(v[1]))?.0;
        (self.origin[prev(h) as usize] == v[2]).then_some(h / 3)
    }

    fn queue_bad(
        &self,
        triangles: &[u32],
        min_angle: f64,
        max_area: Option<f64>,
        heap: &mut BinaryHeap<Bad>,
    ) {
        for &t in triangles {
            if !self.refinable(t) {
                continue;
            }
            let p = self.triangle_points(TriangleId(t));
            let (angle, _) = smallest_angle(p);
            let too_big = max_area.is_some_and(|m| self.signed_area(TriangleId(t)) > m);
            if angle < min_angle || too_big {
                let b = 3 * t as usize;
                heap.push(Bad {
                    key: angle,
                    vertices: [self.origin[b], self.origin[b + 1], self.origin[b + 2]],
                });
            }
        }
    }

    /// After an insertion: queue the new bad triangles and the segments their vertices encroach.
    fn after_insertion(
        &self,
        min_angle: f64,
        max_area: Option<f64>,
        heap: &mut BinaryHeap<Bad>,
        encroached: &mut Vec<[u32; 2]>,
    ) {
        let created: Vec<u32> = self.created.iter().map(|t| t.0).collect();
        self.queue_bad(&created, min_angle, max_area, heap);
        encroached.extend(self.encroached_among(&created));
    }

    /// Constrained edges of these triangles that are encroached by an adjacent apex.
    fn encroached_among(&self, triangles: &[u32]) -> Vec<[u32; 2]> {
        let mut out = Vec::new();
        if self.segment.is_empty() {
            return out;
        }
        for &t in triangles {
            if self.is_ghost_slot(t) {
                continue;
            }
            for e in 3 * t..3 * t + 3 {
                if self.segment[e as usize] != NONE && self.is_encroached(e) {
                    out.push([self.origin[e as usize], self.origin[next(e) as usize]]);
                }
            }
        }
        out
    }

    /// True when the apex of a real refinable triangle beside constrained half-edge `e` lies strictly
    /// inside the edge's diametral circle.
    fn is_encroached(&self, e: u32) -> bool {
        [e, self.twin[e as usize]].iter().any(|&h| {
            let t = h / 3;
            if !self.refinable(t) {
                return false;
            }
            let [u, w, apex] = [
                self.origin[h as usize],
                self.origin[next(h) as usize],
                self.origin[prev(h) as usize],
            ]
            .map(|v| self.points[v as usize]);
            in_diametral_circle(u, w, apex)
        })
    }

    /// Constrained edges of the cavity of `c` (grown from triangle `t`) whose diametral circle
    /// holds `c`.
    fn segments_encroached_by(&self, t: u32, c: Point) -> Vec<[u32; 2]> {
        let mut out = Vec::new();
        let mut stack = vec![t];
        let mut seen = vec![t];
        while let Some(t) = stack.pop() {
            for e in 3 * t..3 * t + 3 {
                let o = self.twin[e as usize] / 3;
                if self.segment[e as usize] != NONE {
                    let [u, w] = [self.origin[e as usize], self.origin[next(e) as usize]];
                    if in_diametral_circle(self.points[u as usize], self.points[w as usize], c) {
                        out.push([u, w]);
                    }
                    continue;
                }
                if seen.contains(&o) || self.is_ghost_slot(o) {
                    continue;
                }
                let [a, b, d] = self.triangle_points(TriangleId(o));
                if crate::predicates::incircle(a, b, d, c) > 0.0 {
                    seen.push(o);
                    stack.push(o);
                }
            }
        }
        out
    }

    /// True when the constrained edge of `h` is long enough to split in floating point: at least
    /// 1e-7 of its coordinates' magnitude. (Concentric-shell splitting near a tiny input angle can
    /// otherwise shrink pieces until a computed split point is off the piece by a visible fraction of
    /// its length; Triangle guards the same spot.)
    fn splittable(&self, h: u32) -> bool {
        let (a, b) = (
            self.points[self.origin[h as usize] as usize],
            self.points[self.origin[next(h) as usize] as usize],
        );
        a.distance_squared(b).sqrt() >= 1e-7 * a.magnitude_with(b)
    }

    /// True when every listed piece is still an edge long enough to split.
    fn all_splittable(&self, pieces: &[[u32; 2]]) -> bool {
        pieces.iter().all(|&[u, w]| {
            self.find_edge(VertexId(u), VertexId(w))
                .is_some_and(|h| self.splittable(h.0))
        })
    }

    /// Splits the constrained edge of half-edge `h` at its midpoint or concentric-shell point;
    /// false (nothing done) when the edge is too short to split.
    fn split_segment(&mut self, h: u32, n_input: u32) -> Result<bool, GeomError> {
        if !self.splittable(h) {
            return Ok(false);
        }
        let (u, w) = (self.origin[h as usize], self.origin[next(h) as usize]);
        let p = self.split_point(u, w, n_input);
        let before = self.points.len();
        self.insert_on_edge(h, p)?;
        Ok(self.points.len() > before)
    }

    /// True when the smallest angle of triangle `t`, at `corner`, lies between two segments: an
    /// input angle no insertion can widen.
    fn is_input_angle(&self, t: u32, corner: usize) -> bool {
        if self.segment.is_empty() {
            return false;
        }
        let leave = 3 * t + corner as u32; // leaves the corner
        let arrive = prev(leave); // arrives at the corner
        self.segment[leave as usize] != NONE && self.segment[arrive as usize] != NONE
    }

    /// Walks the straight line from triangle `t`'s centroid to `c`.
    fn walk_to(&self, t: u32, c: Point) -> Target {
        let [a, b, d] = self.triangle_points(TriangleId(t));
        let g = Point::new((a.x + b.x + d.x) / 3.0, (a.y + b.y + d.y) / 3.0);
        let mut t = t;
        let mut entered = NONE;
        for _ in 0..self.origin.len() {
            let mut exit = None;
            for e in 3 * t..3 * t + 3 {
                if e == entered {
                    continue;
                }
                let (x, y) = (
                    self.points[self.origin[e as usize] as usize],
                    self.points[self.origin[next(e) as usize] as usize],
                );
                // c beyond this edge, and the line g → c passes between its ends (half-open at y).
                if orient2d(x, y, c) < 0.0 && orient2d(g, c, x) >= 0.0 && orient2d(g, c, y) < 0.0 {
                    exit = Some(e);
                    break;
                }
            }
            let Some(e) = exit else { return Target::Found };
            let o = self.twin[e as usize];
            if self.segment[e as usize] != NONE || self.is_ghost_slot(o / 3) {
                return Target::Blocked(e);
            }
            entered = o;
            t = o / 3;
        }
        Target::Found
    }
}

/// True when `p` is strictly inside the circle with diameter `u w`.
fn in_diametral_circle(u: Point, w: Point, p: Point) -> bool {
    (u.x - p.x) * (w.x - p.x) + (u.y - p.y) * (w.y - p.y) < 0.0
}
