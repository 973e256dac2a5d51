//! Ruppert's Delaunay refinement, with the refinements Triangle made standard.
//!
//! Bad triangles (smallest angle below θ, or area above a maximum) are processed shortest edge
//! first, as Triangle does (see `BadQueue`), which inserts markedly fewer points. Encroached
//! subsegments (a vertex strictly inside their diametral circle) are split before any triangle.
//! A bad triangle's circumcentre is found by a straight walk from the triangle: if a segment blocks
//! the walk, or the circumcentre would encroach a segment of its cavity, the segment is split
//! instead. Segments are split at midpoints, or on concentric power-of-two shells around an input
//! vertex, so that small input angles cannot make splitting cascade forever. Triangles whose
//! smallest angle lies between two segments (an input angle) cannot be improved and are left alone,
//! and an insertion cap bounds the work on any input. Triangles labelled [`EXTERIOR`] are never
//! refined.

use crate::predicates::orient2d;
use crate::triangulation::{next, prev, Inserted, GHOST, NONE};
use crate::{GeomError, Point, TriangleId, Triangulation, VertexId, EXTERIOR};

use std::collections::HashSet;

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

/// A queued bad triangle: its vertices and its slot. Slots are reused as insertions replace
/// triangles, so an entry whose slot no longer holds these vertices (in this order) is stale; a
/// triangle that reappears elsewhere was queued again when it was made.
#[derive(Clone, Copy)]
struct Bad {
    vertices: [u32; 3],
    slot: u32,
}

/// Bad triangles by the squared length of their shortest edge, shortest first, as Triangle
/// orders them: splitting the smallest triangles first lets their new points fix the larger bad
/// triangles around them too, which inserts far fewer points than splitting the skinniest first
/// (about 0.6× at 33°).
///
/// The order is kept in buckets, as Triangle keeps it: [`BUCKETS`] stacks, one per step of
/// 1/16 octave of the key (the key's single-precision exponent and four leading mantissa bits),
/// and a two-level bitmap of the stacks that hold something, so that a push and a pop cost a few
/// word operations instead of a heap's logarithmic sift (three quarters of the pops are of
/// triangles that later insertions replaced).
struct BadQueue {
    stacks: Vec<Vec<Bad>>,
    /// Bit `i` of word `w`: stack `64 w + i` holds something.
    full: [u64; BUCKETS / 64],
    /// Bit `w`: word `w` of `full` is not zero.
    summary: u64,
}

/// Stacks of [`BadQueue`]: 2¹² (the sign bit of a non-negative key is 0).
const BUCKETS: usize = 1 << 12;

impl Default for BadQueue {
    fn default() -> Self {
        Self {
            stacks: vec![Vec::new(); BUCKETS],
            full: [0; BUCKETS / 64],
            summary: 0,
        }
    }
}

impl BadQueue {
    fn push(&mut self, key: f64, bad: Bad) {
        // A non-negative float orders as its bit pattern; NaN (from coordinates too large) and
        // anything negative go last.
        let bucket = if key >= 0.0 {
            ((key as f32).to_bits() >> 19) as usize
        } else {
            BUCKETS - 1
        };
        self.stacks[bucket].push(bad);
        self.full[bucket / 64] |= 1 << (bucket % 64);
        self.summary |= 1 << (bucket / 64);
    }

    fn pop(&mut self) -> Option<Bad> {
        if self.summary == 0 {
            return None;
        }
        let w = self.summary.trailing_zeros() as usize;
        let bucket = 64 * w + self.full[w].trailing_zeros() as usize;
        let stack = &mut self.stacks[bucket];
        let bad = stack.pop();
        if stack.is_empty() {
            self.full[w] &= !(1 << (bucket % 64));
            if self.full[w] == 0 {
                self.summary &= !(1 << w);
            }
        }
        bad
    }
}

/// Where the walk to a circumcentre ended.
enum Target {
    /// The point lies in this real triangle, reached without crossing a segment.
    Found { triangle: u32 },
    /// A segment or the hull is in the way: its half-edge.
    Blocked(u32),
    /// The walk did not arrive (a safeguard: it cannot happen on a valid triangulation).
    Lost,
}

/// The sub-segment (pair of bounding input vertices) of every Steiner vertex refinement put on a
/// segment: the frame of Shewchuk's concentric shells and seditious edges.
struct Shells {
    /// Vertices below this id are input vertices.
    n_input: u32,
    /// Indexed by vertex id minus `n_input`; `[NONE, NONE]` for free vertices.
    ends: Vec<[u32; 2]>,
}

impl Shells {
    fn record(&mut self, v: u32, ends: [u32; 2]) {
        let i = (v - self.n_input) as usize;
        if self.ends.len() <= i {
            self.ends.resize(i + 1, [NONE; 2]);
        }
        self.ends[i] = ends;
    }
}

/// The work refinement has queued, and the criteria that fill the queues.
struct Queues {
    /// Bad triangles, the one with the shortest shortest edge first.
    bad: BadQueue,
    /// Segment pieces an existing vertex encroaches.
    encroached: Vec<[u32; 2]>,
    /// cos²θ for the angle bound θ.
    cos2_bound: f64,
    /// Triangles held to a stricter bound (their vertices, as [`Triangulation::triangle_vertices`]
    /// gives them: a slot that another triangle takes over is not one of them), and that bound's
    /// cos²; empty for a plain refinement.
    strict: HashSet<[u32; 3]>,
    cos2_strict: f64,
    /// The area bound.
    max_area: Option<f64>,
    /// How far off-centres lie from their edge, in shortest-edge lengths.
    off_constant: f64,
    /// cos²(2θ): the diametral lens of encroachment.
    lens: f64,
}

impl Queues {
    /// cos² of the angle bound of the triangle with these vertices.
    fn bound_of(&self, vertices: &[u32; 3]) -> f64 {
        if !self.strict.is_empty() && self.strict.contains(vertices) {
            self.cos2_strict
        } else {
            self.cos2_bound
        }
    }
}

/// Refinement's angle bounds: positive, and at most 34° (above it refinement need not stop).
fn check_angle(degrees: f64) -> Result<(), GeomError> {
    if degrees > 0.0 && degrees <= 34.0 {
        Ok(())
    } else {
        Err(GeomError::BadAngle { degrees })
    }
}

/// Where to split a segment piece that a vertex of another segment encroaches.
enum ShellSplit {
    /// On the encroaching vertex's circle around the segments' common end.
    At(Point),
    /// Not at all: the piece already ends on that circle.
    Skip,
    /// At the usual midpoint or power-of-two shell point.
    Usual,
}

/// What to do about one bad triangle.
enum Plan {
    /// Split these segment pieces first (the triangle is queued again).
    Split(Vec<[u32; 2]>),
    /// Leave the triangle as it is.
    GiveUp,
}

/// A circumcentre (or off-centre) that refinement is about to insert, as shown to a policy
/// ([`Triangulation::refine_with_policy`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Candidate {
    /// The bad triangle being refined.
    pub bad: TriangleId,
    /// Its circumcentre.
    pub point: Point,
    /// The triangle that holds the circumcentre (reached from the bad triangle without crossing a
    /// segment).
    pub containing: TriangleId,
}

fn circumcentre(a: Point, b: Point, c: Point) -> Point {
    let (bx, by) = (b.x - a.x, b.y - a.y);
    let (cx, cy) = (c.x - a.x, c.y - a.y);
    let d = 2.0 * (bx * cy - by * cx);
    let (b2, c2) = (bx * bx + by * by, cx * cx + cy * cy);
    Point::new(a.x + (cy * b2 - by * c2) / d, a.y + (bx * c2 - cx * b2) / d)
}

/// Üngör's off-centre of a bad triangle whose smallest angle is at `corner`: on the bisector of
/// the shortest edge (opposite `corner`), at `off_constant` edge lengths from its midpoint, or the
/// circumcentre if that is nearer. It makes a new triangle on the shortest edge just good enough
/// instead of as large as possible, which inserts markedly fewer points (Triangle does the same).
fn off_centre(p: [Point; 3], corner: usize, off_constant: f64) -> Point {
    let c = circumcentre(p[0], p[1], p[2]);
    let (u, w) = (p[(corner + 1) % 3], p[(corner + 2) % 3]);
    let m = u.midpoint(w);
    let (to_c, edge) = (c - m, w - u);
    let (dc, de) = (to_c.x.hypot(to_c.y), edge.x.hypot(edge.y));
    let d = off_constant * de;
    if dc > d && dc.is_finite() {
        m + to_c * (d / dc)
    } else {
        c
    }
}

/// The smallest angle of a triangle, found without trigonometry: it sits at the corner opposite
/// the shortest edge (the law of sines), and it is below the bound θ exactly when its cosine
/// squared exceeds cos²θ (the smallest angle is at most 60°, so its cosine is positive).
struct SmallestAngle {
    /// The corner (0, 1 or 2) where it is.
    corner: usize,
    /// The squared length of the shortest edge, opposite it: the refinement order's key.
    shortest: f64,
    /// True when the angle is below the bound.
    bad: bool,
}

fn smallest_angle(p: [Point; 3], cos2_bound: f64) -> SmallestAngle {
    let lengths = [1, 2, 0].map(|k| p[k].distance_squared(p[(k + 1) % 3]));
    let corner = (0..3)
        .min_by(|&i, &j| lengths[i].total_cmp(&lengths[j]))
        .unwrap_or(0);
    let o = p[corner];
    let (a, b) = (p[(corner + 1) % 3] - o, p[(corner + 2) % 3] - o);
    let dot = a.x * b.x + a.y * b.y;
    let (a2, b2) = (a.x * a.x + a.y * a.y, b.x * b.x + b.y * b.y);
    SmallestAngle {
        corner,
        shortest: lengths[corner],
        // A degenerate triangle (a zero-length edge, three collinear points) is bad.
        bad: !(dot * dot <= cos2_bound * a2 * b2 && dot > 0.0),
    }
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
        self.refine_with_policy(options, |_, _| true)
    }

    /// [`refine`](Self::refine), with a `policy` that may veto a point. Points beyond a segment
    /// (outside the hull, in another region) or encroaching a segment are never inserted: the
    /// segment is split instead, before the policy is asked. The policy sees the rest as a
    /// [`Candidate`]; a veto leaves the triangle as it is (counted in `bad_left`).
    ///
    /// ```
    /// use imesh_geom::{Point, RefineOptions, Triangulation};
    /// let pts = [Point::new(0.0, 0.0), Point::new(8.0, 0.0), Point::new(8.0, 8.0), Point::new(0.0, 8.0), Point::new(4.0, 0.0), Point::new(4.0, 8.0)];
    /// let (mut t, v) = Triangulation::from_points(&pts).unwrap();
    /// t.insert_segment(v[4], v[5]).unwrap();
    /// t.label_regions(&[(Point::new(1.0, 4.0), 1), (Point::new(7.0, 4.0), 2)]);
    /// // Keep every circumcentre in the region of its triangle.
    /// t.refine_with_policy(&RefineOptions::default(), |t, c| t.label(c.containing) == t.label(c.bad))
    ///     .unwrap();
    /// assert!(t.triangles().all(|f| {
    ///     let [a, b, c] = t.triangle_points(f);
    ///     let x = (a.x + b.x + c.x) / 3.0;
    ///     t.label(f) == if x < 4.0 { 1 } else { 2 }
    /// }));
    /// ```
    ///
    /// # Errors
    /// As [`refine`](Self::refine).
    pub fn refine_with_policy(
        &mut self,
        options: &RefineOptions,
        policy: impl FnMut(&Triangulation, &Candidate) -> bool,
    ) -> Result<RefineReport, GeomError> {
        self.refine_from(options, None, policy)
    }

    /// Refinement restarted on a few `triangles` of a triangulation already refined to
    /// `options`: each of them is bad while its smallest angle is under `angle_deg` (which may
    /// exceed `options.min_angle_deg`, up to 34°), and the triangles their new points make are
    /// held to `options`, with `policy` as in [`refine_with_policy`](Self::refine_with_policy).
    /// The rest of the triangulation is not looked at (it met `options` already), and the
    /// points of the earlier refinement count as input points here (the concentric shells of
    /// segment splits are drawn around them too). A caller that knows which few triangles a
    /// coarse bound leaves too sharp for its use refines only those.
    ///
    /// ```
    /// use imesh_geom::{Point, RefineOptions, Triangulation};
    /// // A 4 × 1.7 rectangle: two triangles with a 23° corner, which 20.7° leaves.
    /// let pts = [(0.0, 0.0), (4.0, 0.0), (4.0, 1.7), (0.0, 1.7)].map(|(x, y)| Point::new(x, y));
    /// let (mut t, _) = Triangulation::from_points(&pts).unwrap();
    /// let options = RefineOptions::default();
    /// assert_eq!(t.refine(&options).unwrap().inserted, 0);
    /// // The first of them refined to 25°.
    /// let first: Vec<_> = t.triangles().take(1).collect();
    /// let report = t.refine_triangles_with_policy(&first, 25.0, &options, |_, _| true).unwrap();
    /// assert!(report.inserted > 0);
    /// t.check().unwrap();
    /// ```
    ///
    /// # Errors
    /// As [`refine`](Self::refine), for `angle_deg` too.
    pub fn refine_triangles_with_policy(
        &mut self,
        triangles: &[TriangleId],
        angle_deg: f64,
        options: &RefineOptions,
        policy: impl FnMut(&Triangulation, &Candidate) -> bool,
    ) -> Result<RefineReport, GeomError> {
        check_angle(angle_deg)?;
        let strict = triangles.iter().map(|&t| self.corner_ids(t.0)).collect();
        self.refine_from(options, Some((strict, angle_deg)), policy)
    }

    /// Refinement of every triangle to `options`, or, with `strict`, of those triangles to its
    /// stricter bound (and of the triangles their points make to `options`).
    fn refine_from(
        &mut self,
        options: &RefineOptions,
        strict: Option<(HashSet<[u32; 3]>, f64)>,
        mut policy: impl FnMut(&Triangulation, &Candidate) -> bool,
    ) -> Result<RefineReport, GeomError> {
        let deg = options.min_angle_deg;
        check_angle(deg)?;
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
        let mut shells = Shells {
            n_input,
            ends: Vec::new(),
        };
        let all = 0..self.origin.len() as u32 / 3;
        let lens = (2.0 * min_angle).cos().powi(2);
        let restart = strict.is_some();
        let (strict, strict_deg) = strict.unwrap_or_default();
        let mut queues = Queues {
            bad: BadQueue::default(),
            encroached: Vec::new(),
            cos2_bound: min_angle.cos().powi(2),
            strict,
            cos2_strict: strict_deg.to_radians().cos().powi(2),
            max_area: options.max_area,
            // Üngör's off-centre distance, as a multiple of the shortest edge: 0.475·cot(θ/2),
            // just short of the apex of the isosceles triangle with angle θ on that edge.
            off_constant: 0.475 / (0.5 * min_angle).tan(),
            lens,
        };
        if restart {
            // Only the strict triangles: the rest met `options` when they were made.
            let slots: Vec<u32> = all
                .filter(|&t| queues.strict.contains(&self.corner_ids(t)))
                .collect();
            self.queue_bad(slots, &mut queues);
        } else {
            self.encroached_among(all.clone(), lens, &mut queues.encroached);
            self.queue_bad(all, &mut queues);
        }
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
                .or_else(|| queues.encroached.pop().map(|s| (s, false)));
            if let Some(([u, w], forced_split)) = pending_split {
                // (A stale pair may have become an unconstrained edge again.)
                if let Some(h) = self
                    .find_edge(VertexId(u), VertexId(w))
                    .filter(|&h| self.is_constrained(h))
                {
                    // A forced split ignores existing encroachers: it makes room for a point.
                    let encroacher = if forced_split {
                        None
                    } else {
                        self.encroacher(h.0, queues.lens)
                    };
                    if (forced_split || encroacher.is_some())
                        && self.split_segment(h.0, &mut shells, encroacher)?
                    {
                        self.after_insertion(&mut queues, &mut report);
                    }
                }
                continue;
            }
            let Some(bad) = queues.bad.pop() else { break };
            let t = bad.slot;
            if self.corner_ids(t) != bad.vertices {
                continue;
            }
            let p = self.triangle_points(TriangleId(t));
            let SmallestAngle {
                corner,
                shortest,
                bad: skinny,
            } = smallest_angle(p, queues.bound_of(&bad.vertices));
            let too_big = options
                .max_area
                .is_some_and(|m| self.signed_area(TriangleId(t)) > m);
            if !skinny && !too_big {
                continue;
            }
            if !too_big && (self.is_input_angle(t, corner) || self.is_seditious(t, corner, &shells))
            {
                report.bad_left += 1;
                continue;
            }
            let c = if skinny {
                off_centre(p, corner, queues.off_constant)
            } else {
                circumcentre(p[0], p[1], p[2])
            };
            if !c.is_finite() {
                report.bad_left += 1;
                continue;
            }
            let mut plan = match self.walk_to(t, c) {
                Target::Lost => Plan::GiveUp,
                Target::Blocked(h) => Plan::Split(vec![self.edge_ends(h)]),
                Target::Found { triangle } => {
                    let lens = queues.lens;
                    // A segment of the triangle that holds the point bounds its cavity: when the
                    // point encroaches one, the cavity need not be dug to know it.
                    let early = self.encroached_sides(triangle, c, lens);
                    if !early.is_empty() {
                        Plan::Split(early)
                    } else {
                        let objection = self.insert_unless(c, triangle, |tri, touched| {
                            // Segments of the cavity that the point would encroach go first.
                            let threatened: Vec<[u32; 2]> = touched
                                .iter()
                                .map(|&e| tri.edge_ends(e))
                                .filter(|&[u, w]| {
                                    let [pu, pw] = [u, w].map(|x| tri.points[x as usize]);
                                    in_diametral_lens(pu, pw, c, lens)
                                })
                                .collect();
                            if !threatened.is_empty() {
                                return Some(Plan::Split(threatened));
                            }
                            let candidate = Candidate {
                                bad: TriangleId(t),
                                point: c,
                                containing: TriangleId(triangle),
                            };
                            (!(tri.refinable(triangle) && policy(tri, &candidate)))
                                .then_some(Plan::GiveUp)
                        })?;
                        match objection {
                            Err(plan) => plan,
                            Ok(Inserted::New) => {
                                self.after_insertion(&mut queues, &mut report);
                                continue;
                            }
                            // The point is a vertex already.
                            Ok(Inserted::Duplicate(_)) => Plan::GiveUp,
                        }
                    }
                }
            };
            if let Plan::Split(pieces) = &plan {
                if !self.all_splittable(pieces) {
                    plan = Plan::GiveUp;
                }
            }
            match plan {
                Plan::GiveUp => report.bad_left += 1,
                Plan::Split(pieces) => {
                    forced.extend(pieces);
                    queues.bad.push(shortest, bad);
                }
            }
        }
        if report.stopped == StopReason::Done {
            // Count what is left below the bound (input angles).
            report.bad_left = (0..self.origin.len() as u32 / 3)
                .filter(|&t| {
                    self.refinable(t)
                        && smallest_angle(self.triangle_points(TriangleId(t)), queues.cos2_bound)
                            .bad
                })
                .count();
        }
        Ok(report)
    }

    /// Splits every constrained edge longer than `max_length` into the fewest equal pieces no
    /// longer than it, and returns the number of points inserted. The split points lie on their
    /// segment's line (exactly, when its ends are on a coarse lattice) and the halves keep the
    /// segment and the labels on both sides. A uniform spacing along the boundaries is what a
    /// uniformly sized mesh starts from: refinement alone grades from short boundary pieces.
    ///
    /// ```
    /// use imesh_geom::{Point, Triangulation};
    /// let pts = [Point::new(0.0, 0.0), Point::new(10.0, 0.0), Point::new(0.0, 3.0)];
    /// let (mut t, v) = Triangulation::from_points(&pts).unwrap();
    /// let s = t.insert_segment(v[0], v[1]).unwrap();
    /// t.split_long_segments(4.0).unwrap();
    /// let xs: Vec<f64> = t.segment_vertices(s).iter().map(|&u| t.point(u).x).collect();
    /// assert_eq!(xs.len(), 4); // 10 / 4 → 3 pieces of 10/3
    /// assert!(xs.windows(2).all(|w| (w[1] - w[0] - 10.0 / 3.0).abs() < 1e-9));
    /// t.check().unwrap();
    /// ```
    ///
    /// # Errors
    /// [`GeomError::OutOfRange`] if a split point cannot be represented (it cannot happen for
    /// points the triangulation accepted).
    pub fn split_long_segments(&mut self, max_length: f64) -> Result<usize, GeomError> {
        if !(max_length.is_finite() && max_length > 0.0) || self.segment.is_empty() {
            return Ok(0);
        }
        let edges: Vec<[u32; 2]> = self
            .constrained_edges()
            .map(|h| [self.origin[h.index()], self.origin[next(h.0) as usize]])
            .collect();
        let before = self.points.len();
        for [u, w] in edges {
            let (pu, pw) = (self.points[u as usize], self.points[w as usize]);
            let pieces = (pu.distance_squared(pw).sqrt() / max_length).ceil();
            // (NaN for coincident ends fails this too.)
            if pieces.is_nan() || pieces < 2.0 {
                continue;
            }
            self.split_piece(u, w, pieces as usize)?;
        }
        Ok(self.points.len() - before)
    }

    /// Splits each constrained edge `(u, w, pieces)` of `splits` into `pieces` equal parts as
    /// [`Triangulation::split_long_segments`] does (an edge that is not a constrained edge of
    /// the triangulation, or is split already, is left), and returns the number of points
    /// inserted.
    ///
    /// ```
    /// use imesh_geom::{Point, Triangulation};
    /// let pts = [Point::new(0.0, 0.0), Point::new(9.0, 0.0), Point::new(0.0, 3.0)];
    /// let (mut t, v) = Triangulation::from_points(&pts).unwrap();
    /// let s = t.insert_segment(v[0], v[1]).unwrap();
    /// assert_eq!(t.split_segment_pieces(&[(v[0], v[1], 3), (v[0], v[2], 2)]).unwrap(), 2);
    /// let xs: Vec<f64> = t.segment_vertices(s).iter().map(|&u| t.point(u).x).collect();
    /// // On the segment (snapped to its line), a third of it apart up to rounding.
    /// assert!(xs.iter().zip([0.0, 3.0, 6.0, 9.0]).all(|(x, want)| (x - want).abs() < 1e-9));
    /// t.check().unwrap();
    /// ```
    ///
    /// # Errors
    /// As [`Triangulation::split_long_segments`].
    pub fn split_segment_pieces(
        &mut self,
        splits: &[(VertexId, VertexId, usize)],
    ) -> Result<usize, GeomError> {
        let before = self.points.len();
        for &(u, w, pieces) in splits {
            if pieces >= 2 {
                self.split_piece(u.0, w.0, pieces)?;
            }
        }
        Ok(self.points.len() - before)
    }

    /// Splits the constrained edge from `u` to `w` at `p` (projected onto its input segment's
    /// line, so that the segment stays straight), and returns the new vertex; `None` (nothing
    /// done) when `u w` is not a constrained edge or `p` does not lie strictly between its ends.
    ///
    /// ```
    /// use imesh_geom::{Point, Triangulation};
    /// let pts = [Point::new(0.0, 0.0), Point::new(0.0, 9.0), Point::new(4.0, 3.0)];
    /// let (mut t, v) = Triangulation::from_points(&pts).unwrap();
    /// let s = t.insert_segment(v[0], v[1]).unwrap();
    /// // Peeled off from the front: each split leaves the rest of the piece to the next one.
    /// let a = t.split_piece_at(v[0], v[1], Point::new(0.0, 3.0)).unwrap().unwrap();
    /// let b = t.split_piece_at(a, v[1], Point::new(0.0, 7.5)).unwrap().unwrap();
    /// assert_eq!(t.segment_vertices(s), vec![v[0], a, b, v[1]]);
    /// // Not a constrained edge (the piece is gone), or not inside the piece: nothing to split.
    /// assert_eq!(t.split_piece_at(v[0], v[1], Point::new(0.0, 5.0)).unwrap(), None);
    /// assert_eq!(t.split_piece_at(a, b, Point::new(0.0, 2.0)).unwrap(), None);
    /// t.check().unwrap();
    /// ```
    ///
    /// # Errors
    /// As [`Triangulation::split_long_segments`].
    pub fn split_piece_at(
        &mut self,
        u: VertexId,
        w: VertexId,
        p: Point,
    ) -> Result<Option<VertexId>, GeomError> {
        let Some(h) = self.find_edge(u, w).filter(|&h| self.is_constrained(h)) else {
            return Ok(None);
        };
        // Along the piece, and clear of its ends by more than the snapping can move it.
        let (pu, pw) = (self.points[u.index()], self.points[w.index()]);
        let d = pw - pu;
        let f = ((p.x - pu.x) * d.x + (p.y - pu.y) * d.y) / (d.x * d.x + d.y * d.y);
        if !(f > 1e-9 && f < 1.0 - 1e-9) {
            return Ok(None);
        }
        // A point exactly on the line (an axis-parallel segment's) stays as it is.
        let [a, b] = self.segment_line(h.0);
        let p = if orient2d(a, b, p) == 0.0 {
            p
        } else {
            self.snap_to_segment(h.0, p)
        };
        let v = self.insert_on_edge(h.0, p)?;
        Ok((v != u && v != w).then_some(v))
    }

    /// Splits the constrained edge from `u` to `w` into `pieces` equal parts.
    fn split_piece(&mut self, u: u32, w: u32, pieces: usize) -> Result<(), GeomError> {
        let pw = self.points[w as usize];
        // Peel one piece off the front at a time: the next point splits what is left into
        // the remaining number of equal parts, so rounding does not accumulate.
        let mut at = u;
        for left in (2..=pieces).rev() {
            let Some(h) = self
                .find_edge(VertexId(at), VertexId(w))
                .filter(|&h| self.is_constrained(h))
            else {
                break;
            };
            let pa = self.points[at as usize];
            let p = self.snap_to_segment(h.0, pa + (pw - pa) * (1.0 / left as f64));
            let v = self.insert_on_edge(h.0, p)?.0;
            if v == at || v == w {
                break;
            }
            at = v;
        }
        Ok(())
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

    /// The vertices of the triangle in slot `t`, as a [`Bad`] entry records them.
    fn corner_ids(&self, t: u32) -> [u32; 3] {
        let b = 3 * t as usize;
        [self.origin[b], self.origin[b + 1], self.origin[b + 2]]
    }

    fn refinable(&self, t: u32) -> bool {
        !self.is_ghost_slot(t) && (self.label.is_empty() || self.label[t as usize] != EXTERIOR)
    }

    /// Queues the bad triangles among `triangles`.
    fn queue_bad(&self, triangles: impl IntoIterator<Item = u32>, queues: &mut Queues) {
        for t in triangles {
            if !self.refinable(t) {
                continue;
            }
            let p = self.triangle_points(TriangleId(t));
            let vertices = self.corner_ids(t);
            let SmallestAngle { shortest, bad, .. } = smallest_angle(p, queues.bound_of(&vertices));
            let too_big = queues
                .max_area
                .is_some_and(|m| self.signed_area(TriangleId(t)) > m);
            if bad || too_big {
                queues.bad.push(shortest, Bad { vertices, slot: t });
            }
        }
    }

    /// After an insertion: count it, queue the new bad triangles and the segments their vertices
    /// encroach.
    fn after_insertion(&self, queues: &mut Queues, report: &mut RefineReport) {
        report.inserted += 1;
        let created = || self.created.iter().map(|t| t.0);
        self.queue_bad(created(), queues);
        self.encroached_among(created(), queues.lens, &mut queues.encroached);
    }

    /// Appends to `out` the constrained edges of these triangles that are encroached by an
    /// adjacent apex.
    fn encroached_among(
        &self,
        triangles: impl IntoIterator<Item = u32>,
        lens: f64,
        out: &mut Vec<[u32; 2]>,
    ) {
        if self.segment.is_empty() {
            return;
        }
        for t in triangles {
            if self.is_ghost_slot(t) {
                continue;
            }
            for e in 3 * t..3 * t + 3 {
                if self.segment[e as usize] != NONE && self.encroacher(e, lens).is_some() {
                    out.push([self.origin[e as usize], self.origin[next(e) as usize]]);
                }
            }
        }
    }

    /// The constrained edges of triangle `t` that `p` encroaches.
    fn encroached_sides(&self, t: u32, p: Point, lens: f64) -> Vec<[u32; 2]> {
        if self.segment.is_empty() {
            return Vec::new();
        }
        (3 * t..3 * t + 3)
            .filter(|&e| self.segment[e as usize] != NONE)
            .map(|e| self.edge_ends(e))
            .filter(|&[u, w]| {
                in_diametral_lens(self.points[u as usize], self.points[w as usize], p, lens)
            })
            .collect()
    }

    /// The apex of a real refinable triangle beside constrained half-edge `e` that lies strictly
    /// inside the edge's diametral circle, if any.
    fn encroacher(&self, e: u32, lens: f64) -> Option<u32> {
        [e, self.twin[e as usize]].into_iter().find_map(|h| {
            if !self.refinable(h / 3) {
                return None;
            }
            let apex = self.origin[prev(h) as usize];
            let [u, w, a] = [self.origin[h as usize], self.origin[next(h) as usize], apex]
                .map(|v| self.points[v as usize]);
            in_diametral_lens(u, w, a, lens).then_some(apex)
        })
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
    fn split_segment(
        &mut self,
        h: u32,
        shells: &mut Shells,
        encroacher: Option<u32>,
    ) -> Result<bool, GeomError> {
        if !self.splittable(h) {
            return Ok(false);
        }
        let (u, w) = (self.origin[h as usize], self.origin[next(h) as usize]);
        let n_input = shells.n_input;
        let p = match encroacher.map_or(ShellSplit::Usual, |v| self.shell_split(h, v, shells)) {
            ShellSplit::Skip => return Ok(false),
            ShellSplit::At(p) => p,
            ShellSplit::Usual => self.split_point(u, w, n_input),
        };
        let piece_ends = self.piece_ends(u, w, shells);
        let p = self.snap_to_segment(h, p);
        let before = self.points.len();
        let v = self.insert_on_edge(h, p)?.0;
        if self.points.len() > before {
            shells.record(v, piece_ends);
        }
        Ok(self.points.len() > before)
    }

    /// How to split the constrained edge of `h` encroached by vertex `v`. When `v` is a Steiner
    /// vertex of another segment meeting this one at an input vertex `a`, the edge is split at
    /// `v`'s distance from `a` (when that lies well inside the edge): the two vertices then sit on
    /// one circle around `a`, the edge joining them is seditious, and the mutual encroachment of
    /// two segments at a small angle stops there instead of halving both forever (Triangle does
    /// the same). When an end of the edge already sits on `v`'s circle, the encroachment is an
    /// artefact of rounding the shell points, and splitting would only halve the edge towards
    /// `v` without end: it is not split.
    fn shell_split(&self, h: u32, v: u32, shells: &Shells) -> ShellSplit {
        let (u, w) = (self.origin[h as usize], self.origin[next(h) as usize]);
        let Some(sv) = self.sub_segment(v, shells) else {
            return ShellSplit::Usual;
        };
        let Some((apex, _, _)) = common_end(self.piece_ends(u, w, shells), sv) else {
            return ShellSplit::Usual;
        };
        let [pa, pu, pw, pv] = [apex, u, w, v].map(|x| self.points[x as usize]);
        let (du, dw, r) = (
            pa.distance_squared(pu).sqrt(),
            pa.distance_squared(pw).sqrt(),
            pa.distance_squared(pv).sqrt(),
        );
        if (du - r).abs() <= 1e-3 * r || (dw - r).abs() <= 1e-3 * r {
            return ShellSplit::Skip;
        }
        let f = (r - du) / (dw - du);
        if f.is_finite() && (0.2..=0.8).contains(&f) {
            ShellSplit::At(pu + (pw - pu) * f)
        } else {
            ShellSplit::Usual
        }
    }

    /// The ends of the input segment the constrained half-edge `h` lies on.
    fn segment_line(&self, h: u32) -> [Point; 2] {
        self.segments[self.segment[h as usize] as usize].map(|v| self.points[v as usize])
    }

    /// `p` (a split point of the constrained edge of `h`) moved onto the exact line of its input
    /// segment when possible: its parameter along the segment, rounded to a multiple of 2^-36, gives
    /// an exactly representable point on the line whenever the segment's ends lie on a coarse
    /// lattice (pixel corners and centres). Split points computed from Steiner ends would drift off
    /// the line by rounding; on the hull that drift changes the hull.
    fn snap_to_segment(&self, h: u32, p: Point) -> Point {
        let [a, b] = self.segment_line(h);
        let d = b - a;
        let f = ((p.x - a.x) * d.x + (p.y - a.y) * d.y) / (d.x * d.x + d.y * d.y);
        let scale = 2f64.powi(36);
        let q = a + d * ((f * scale).round() / scale);
        let (u, w) = (
            self.points[self.origin[h as usize] as usize],
            self.points[self.origin[next(h) as usize] as usize],
        );
        if orient2d(a, b, q) == 0.0 && crate::predicates::strictly_between(u, w, q) {
            q
        } else {
            p
        }
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

    /// True when the edge opposite the smallest angle of triangle `t` (at `corner`) is *seditious*
    /// (Shewchuk): its ends are Steiner points on two segments that meet at an input vertex at
    /// less than 60°, at the same distance from it (the same concentric shell). Splitting such a
    /// triangle only inserts a point that encroaches one of the two segments again, whose split
    /// makes a shorter seditious edge: the cascade that keeps Ruppert's algorithm from stopping at
    /// small input angles. Such triangles are left as they are.
    fn is_seditious(&self, t: u32, corner: usize, shells: &Shells) -> bool {
        if self.segment.is_empty() {
            return false;
        }
        let opposite = 3 * t + (corner as u32 + 1) % 3;
        let (u, w) = (
            self.origin[opposite as usize],
            self.origin[next(opposite) as usize],
        );
        let (Some(su), Some(sw)) = (self.sub_segment(u, shells), self.sub_segment(w, shells))
        else {
            return false;
        };
        let Some((apex, eu, ew)) = common_end(su, sw) else {
            return false;
        };
        let [pa, pu, pw] = [apex, u, w].map(|v| self.points[v as usize]);
        let (du, dw) = (
            pa.distance_squared(pu).sqrt(),
            pa.distance_squared(pw).sqrt(),
        );
        if !(du < 1.001 * dw && dw < 1.001 * du) {
            return false;
        }
        // The segments' angle at the apex, from their far ends: below 60° (cos > 1/2).
        let (x, y) = (self.points[eu as usize] - pa, self.points[ew as usize] - pa);
        let dot = x.x * y.x + x.y * y.y;
        dot > 0.0 && 4.0 * dot * dot > (x.x * x.x + x.y * x.y) * (y.x * y.x + y.y * y.y)
    }

    /// The two input vertices between which Steiner vertex `v` lies on its segment (the segment's
    /// ends, or input vertices lying on it), if `v` is a Steiner vertex on a segment.
    fn sub_segment(&self, v: u32, shells: &Shells) -> Option<[u32; 2]> {
        if v < shells.n_input {
            return None;
        }
        if let Some(&ends) = shells.ends.get((v - shells.n_input) as usize) {
            if ends[0] != NONE {
                return Some(ends);
            }
        }
        // Not split by refinement (a circumcentre that landed on a segment): follow the segment's
        // pieces both ways to the first input vertices.
        let s = self
            .star(v)
            .map(|h| self.segment[h as usize])
            .find(|&s| s != NONE)?;
        let mut ends = [NONE; 2];
        let mut k = 0;
        for first in self.star(v).filter(|&h| self.segment[h as usize] == s) {
            let (mut from, mut at) = (v, self.origin[next(first) as usize]);
            while at != GHOST && at >= shells.n_input {
                let Some(step) = self.next_on_segment(s, at, from) else {
                    break;
                };
                (from, at) = (at, step);
            }
            if k < 2 {
                ends[k] = at;
                k += 1;
            }
        }
        (k == 2 && ends.iter().all(|&e| e < shells.n_input)).then_some(ends)
    }

    /// The input vertices bounding the piece `u w` of a segment (its sub-segment).
    fn piece_ends(&self, u: u32, w: u32, shells: &Shells) -> [u32; 2] {
        self.sub_segment(u, shells)
            .or_else(|| self.sub_segment(w, shells))
            .unwrap_or([u, w])
    }

    /// Walks from triangle `t`'s centroid towards `c` along the straight line, crossing only edges
    /// (never passing through a vertex), so that every chain of segments between the two is met.
    /// Where the line runs exactly through a vertex, the step crosses another edge that has `c`
    /// strictly beyond it instead (a visibility-walk step, which still moves towards `c`). The
    /// first segment (or hull edge) on the way stops the walk: a circumcentre beyond a segment is
    /// never inserted, the segment is split instead (as Triangle does: with diametral lenses a
    /// point beyond a segment need not encroach it, and inserting it would leave the bad triangle
    /// as it is).
    fn walk_to(&self, t: u32, c: Point) -> Target {
        let [a, b, d] = self.triangle_points(TriangleId(t));
        let g = Point::new((a.x + b.x + d.x) / 3.0, (a.y + b.y + d.y) / 3.0);
        let mut t = t;
        let mut entered = NONE;
        for step in 0..self.origin.len() {
            let ends = |e: u32| {
                (
                    self.points[self.origin[e as usize] as usize],
                    self.points[self.origin[next(e) as usize] as usize],
                )
            };
            let beyond = |e: u32| {
                let (x, y) = ends(e);
                orient2d(x, y, c) < 0.0
            };
            // c beyond the edge, and the line g → c passes between its ends (half-open at y).
            let straight = (3 * t..3 * t + 3).find(|&e| {
                let (x, y) = ends(e);
                e != entered && beyond(e) && orient2d(g, c, x) >= 0.0 && orient2d(g, c, y) < 0.0
            });
            // Otherwise any edge with c strictly beyond, tried from a rotating start.
            let exit = straight.or_else(|| {
                (0..3)
                    .map(|k| 3 * t + (k + step as u32) % 3)
                    .find(|&e| e != entered && beyond(e))
            });
            let Some(e) = exit else {
                return Target::Found { triangle: t };
            };
            let o = self.twin[e as usize];
            if self.segment[e as usize] != NONE || self.is_ghost_slot(o / 3) {
                return Target::Blocked(e);
            }
            entered = o;
            t = o / 3;
        }
        Target::Lost
    }

    /// The two end vertices of half-edge `h`.
    fn edge_ends(&self, h: u32) -> [u32; 2] {
        [self.origin[h as usize], self.origin[next(h) as usize]]
    }
}

/// The end two different sub-segments share, with the far end of each: `(apex, far a, far b)`.
fn common_end([a0, a1]: [u32; 2], [b0, b1]: [u32; 2]) -> Option<(u32, u32, u32)> {
    if [a0, a1] == [b0, b1] || [a0, a1] == [b1, b0] {
        return None;
    }
    let other_b = |x: u32| if x == b0 { b1 } else { b0 };
    if a0 == b0 || a0 == b1 {
        Some((a0, a1, other_b(a0)))
    } else if a1 == b0 || a1 == b1 {
        Some((a1, a0, other_b(a1)))
    } else {
        None
    }
}

/// True when `p` encroaches the segment `u w`: it lies strictly inside the segment's diametral
/// circle and, with `lens` = cos²(2θ), inside its diametral lens — the angle `u p w` is at least
/// 180° − 2θ (Triangle's default). A vertex in the circle but outside the lens cannot make a
/// triangle on the segment worse than θ, so the segment need not be split for it; this saves many
/// splits at large angles. `lens` = 0 gives the plain diametral circle.
fn in_diametral_lens(u: Point, w: Point, p: Point, lens: f64) -> bool {
    let (a, b) = (u - p, w - p);
    let dot = a.x * b.x + a.y * b.y;
    dot < 0.0 && dot * dot >= lens * (a.x * a.x + a.y * a.y) * (b.x * b.x + b.y * b.y)
}
