//! Blunting sharp tips: where a region's corner at a vertex of G' stays narrower than a quad's
//! corner should be, the tip is cut off by a short edge across it and given to a neighbour.
//!
//! A quad at such a vertex has its corner inside the region's sector, so its scaled Jacobian is
//! at most the sector's sine whatever the optimiser does: sharper than 30°, under 0.5. Where
//! [`crate::open_sharp_corners`] could not open the sector within the curve tolerance (a spike
//! tip, a junction, a boundary meeting the border at a grazing angle), the only way to better
//! elements is to change the region there. Cutting the tip where it is a quad side wide gives
//! the region two corners of 90° + θ/2 and its neighbour a triangle of about one quad's area
//! whose corners are 90° − θ/2 and θ, the θ joining the neighbour's own corner at the vertex.
//! A tip one of whose sides ends before it is a quad side wide (the region turns away there)
//! is cut from that side's far vertex instead: its height over the other side is under a
//! quad side, so a cut a quad side long meets the other side beyond its foot, at an angle
//! of 30° or more for the neighbour and 150° or less for the region (where it ends too low
//! over the other side for that, the end of a sliver, square from its end to the other side;
//! a square cut under half a quad side is made by moving that end onto its foot, unless that
//! would leave a corner as sharp, rather than by an edge a fraction of a quad long); a tip
//! both of whose sides end that early, between their ends; and a spike that stays narrow one
//! vertex further (a pixel staircase), from that vertex. A cut's end that later cuts leave on
//! a stub under three quarters of a quad side merges into the stub's other end.

use imesh_geom::predicates::orient2d;
use imesh_geom::Point;

use crate::corners::chord;
use crate::simplify::{bounding_box, winds_around};
use crate::{CubicBezier, CurveGraph, GraphEdge};

/// The label of the outside of the domain: a tip is never given to it.
const OUTSIDE: u32 = u32::MAX;

/// The widths a tip is cut at, in [`TipOptions::width`]s: the widest its edges leave room for.
const WIDTHS: [f64; 3] = [2.0, 1.5, 1.0];

/// The lowest a side's far vertex may stand over the other side, in [`TipOptions::width`]s,
/// for a square cut from it (see [`through_depth`]): a lower one would make an edge, and
/// elements, a tenth of a quad side.
const SQUARE_CUT_MIN_HEIGHT: f64 = 0.1;

/// The longest square cut, in [`TipOptions::width`]s, made by moving its vertex onto its
/// foot rather than by a new edge (see [`cut_off`]): a shorter edge would hold elements a
/// fraction of a quad side across (aloe's two worst clusters were such edges of 0.34–0.37 px
/// at a junction, their quads 1 % of the mean area). A square cut is under half a width
/// anyway (a higher vertex takes a cut a width long), so every one is tried this way first.
/// Measured with the defaults (`cargo xtask bench random`): seed 52, two images changed, both
/// up (worst shape-and-size 0.0003 → 0.166 and 0.0032 → 0.206), quads under 0.25 3 694 →
/// 3 640; seeds 101 and 202 unchanged; seed 303 at `--size 3` five up, none down (mean of the
/// means 0.85780 → 0.85804); aloe's mean 0.7679 → 0.7684, the other nine fixtures unchanged.
/// At a quarter of a width: seed 52 unchanged, seed 303 0.85785, aloe 0.7681.
const SNAP_CUT: f64 = 0.5;

/// The longest stub, in [`TipOptions::width`]s, whose cut end merges into its other end
/// ([`merge_stubs`]). Against half a width (session 55's first measure), `cargo xtask bench
/// random` on seven sets of 150 images: 39 meshes changed, 32 up; the mean of the means up on
/// all seven (seed 52 0.89383 → 0.89390, 101 0.90087 → 0.90092, 202 0.89607 → 0.89611, 404
/// 0.89408 → 0.89413, 505 0.89966 → 0.89973; seeds 303 and 52 at `--size 3` 0.85957 → 0.85966
/// and 0.85974 → 0.85979), quads under 0.25 fewer on all seven (seed 52 3 413 → 3 381, seed
/// 303 at `--size 3` 11 418 → 11 300), under 0.5 in shape 215 → 212 and in scaled Jacobian 25
/// → 25 over them; fixtures: pyvista's worst shape 0.459 → 0.500, the means of coffee (0.9184
/// → 0.9207), aloe, gravel and coins up, grass's down (0.7192 → 0.7174, its worst shape 0.405
/// → 0.442), the other four identical.
const MERGED_STUB: f64 = 0.75;

/// Twice the largest area, in squared [`TipOptions::width`]s, of a tip cut between its sides'
/// ends when those are less than a width apart: a sliver's end, three eighths of a quad.
/// Against a quarter: quads under 0.5 in shape / scaled Jacobian over session 48's 150 images
/// 71 / 10 → 62 / 8 (aloe's 22.6° tip a pixel wide and 2.5 px long, one of noise11's), none
/// more on any image, the 46 held out unchanged.
const SMALL_PIECE: f64 = 0.75;

/// Options of [`blunt_sharp_tips`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TipOptions {
    /// Sectors narrower than this (degrees) are cut.
    pub min_angle_deg: f64,
    /// The narrowest cut (pixels): about a quad side, so that the new edge holds an element
    /// edge. Cuts of twice and 1.5 times this are tried first.
    pub width: f64,
    /// How far from the vertex (pixels) a boundary's curve direction is taken, as in
    /// [`crate::CornerOptions::reach`]; the sector is the narrower of the chords' and the
    /// curves'.
    pub reach: f64,
    /// The deepest cut, in widths from the vertex: a sharper tip is cut there, narrower than
    /// `width`, which still leaves right-ish corners. A sliver's end cut square may lie
    /// deeper when its piece is no larger (see `blunt_sharp_tips`).
    pub max_depth: f64,
}

impl Default for TipOptions {
    fn default() -> Self {
        Self {
            min_angle_deg: crate::MIN_CORNER_DEG,
            width: 2.0,
            reach: 2.0,
            max_depth: 3.0,
        }
    }
}

/// G' with its sharp tips cut off ([`blunt_sharp_tips`]).
#[derive(Clone, Debug)]
pub struct Blunted {
    /// The graph: the cut edges shortened, a new edge across each tip.
    pub graph: CurveGraph,
    /// One curve per edge of `graph`.
    pub curves: Vec<CubicBezier>,
    /// Tips cut.
    pub tips: usize,
    /// The area the tips' regions gave away, in square pixels, and the area merged cut ends
    /// swept from one side of their boundary to the other.
    pub area: f64,
    /// The farthest a boundary moved: the largest distance from a cut tip's vertex to its cut
    /// (or from a merged cut end to where it merged).
    pub moved: f64,
}

/// One end of an edge at a vertex.
#[derive(Clone, Copy, Debug)]
struct End {
    edge: u32,
    /// The vertex is the edge's `ends[0]`.
    at_start: bool,
    /// The far end: its vertex and its point.
    far_vertex: u32,
    far: Point,
    /// Directions (radians) of the chord and of the curve `reach` out.
    chord: f64,
    curve: f64,
}

impl End {
    /// The labels on the left and the right of the edge leaving the vertex.
    fn sides(&self, g: &CurveGraph) -> [u32; 2] {
        let l = g.edges()[self.edge as usize].labels;
        if self.at_start {
            l
        } else {
            [l[1], l[0]]
        }
    }
}

/// A tip to cut: the sector from `ends[0]` counter-clockwise to `ends[1]` at `vertex`.
#[derive(Clone, Copy, Debug)]
struct Tip {
    vertex: u32,
    ends: [End; 2],
    /// Per side, the region's next boundary edge, from the far vertex of the first.
    next: [Option<End>; 2],
    region: u32,
    receiver: u32,
    /// The narrower of the chord and curve sectors (radians).
    angle: f64,
    /// Where the cut meets each side.
    cut: [CutEnd; 2],
}

/// A tip to cut and its piece: the cut's two ends and the piece's outline (see
/// [`Tip::piece`]).
#[derive(Clone, Debug)]
struct Cut {
    tip: Tip,
    ends: [Point; 2],
    outline: Vec<Point>,
}

/// The cuts a sharp tip could take, in the order they are tried ([`sharp_tips`]): each cut
/// with its piece given to the region across the tip's first side, then to the one across its
/// second (a junction's other neighbour), before the next cut.
#[derive(Clone, Debug)]
struct TipCuts {
    tries: Vec<Tip>,
    /// The first of `tries` not yet tried.
    next: usize,
}

impl TipCuts {
    /// The next of the tries whose piece is sound and whose edges no other cut takes (`used`,
    /// per edge of `g`; none when `used` is empty), marked as tried.
    fn next_sound(&mut self, g: &CurveGraph, used: &[bool]) -> Option<Cut> {
        while let Some(&tip) = self.tries.get(self.next) {
            self.next += 1;
            if !used.is_empty() && tip.edges().any(|e| used[e as usize]) {
                continue;
            }
            let (outline, [i, j], on) = tip.piece(g);
            if sound_piece(g, &on, &outline, [i, j]) {
                return Some(Cut {
                    tip,
                    ends: [outline[i], outline[j]],
                    outline,
                });
            }
        }
        None
    }
}

/// Where a tip's cut meets one of its sides.
#[derive(Clone, Copy, Debug, PartialEq)]
enum CutEnd {
    /// At a new vertex this far from the tip's vertex along the side's first chord.
    Along(f64),
    /// At the far vertex of the side's first edge.
    First,
    /// At the far vertex of the next edge along the region's boundary.
    Second,
}

impl Tip {
    /// `labels` with the receiver for the region: an edge's piece the region gives away.
    fn relabel(&self, labels: [u32; 2]) -> [u32; 2] {
        labels.map(|l| if l == self.region { self.receiver } else { l })
    }

    /// The edges the cut takes in part or whole.
    fn edges(&self) -> impl Iterator<Item = u32> + '_ {
        (0..2).flat_map(move |k| {
            let second = (self.cut[k] == CutEnd::Second)
                .then_some(self.next[k])
                .flatten();
            std::iter::once(self.ends[k].edge).chain(second.map(|e| e.edge))
        })
    }

    /// The piece cut off: its outline (the tip's vertex, side 0 out to the cut, side 1 back),
    /// the indices in it of the cut's two ends, and the vertices of the graph on it.
    fn piece(&self, g: &CurveGraph) -> (Vec<Point>, [usize; 2], Vec<u32>) {
        let v = g.point(self.vertex);
        let mut ids = vec![self.vertex];
        let side = |k: usize, ids: &mut Vec<u32>| -> Vec<Point> {
            let e = &self.ends[k];
            match (self.cut[k], self.next[k]) {
                (CutEnd::Along(depth), _) => vec![v + (e.far - v) * (depth / norm(e.far - v))],
                (CutEnd::First, _) | (CutEnd::Second, None) => {
                    ids.push(e.far_vertex);
                    vec![e.far]
                }
                (CutEnd::Second, Some(n)) => {
                    ids.extend([e.far_vertex, n.far_vertex]);
                    vec![e.far, n.far]
                }
            }
        };
        let out = side(0, &mut ids);
        let mut back = side(1, &mut ids);
        back.reverse();
        let ends = [out.len(), out.len() + 1];
        let outline = std::iter::once(v).chain(out).chain(back).collect();
        (outline, ends, ids)
    }
}

/// Cuts off every sector of G' narrower than `options.min_angle_deg` (the narrower of the
/// straight edges' and of the fitted curves' directions `options.reach` out) where it is two,
/// 1.5 or one `options.width` wide, the widest its edges leave room for (at most
/// `options.max_depth` of those widths from the vertex): a new vertex on
/// each of the two straight edges, a straight edge between them, and the triangle beyond given
/// to the region across the first edge (the second's when the first is the domain's border).
/// The curves are cut at the new vertices' projections, their ends moved onto them. Where one
/// edge is too short for that (the region turns away at its far vertex), the cut runs from
/// that vertex to a new one on the other edge, two, 1.5 or one width away and meeting it at
/// `options.min_angle_deg` or more (or square to it, where the far vertex stands too low over
/// it for that: the end of a sliver; a square cut under half a width moves the far vertex onto
/// its foot instead where that leaves no sharp corner), the short edge going to the receiver
/// whole; where both
/// are, between their far vertices if those are a width or more apart; failing those, the
/// same from the next vertex along the region's boundary on either side (a staircase spike),
/// the cut then at most two widths long; failing all those, between the first vertices even
/// when they are closer than a width, if the piece is three eighths of a quad or less (a sliver's
/// end). The first of these cuts whose piece holds no other vertex of the graph is made; a
/// sector is left alone when none does. Cuts whose edges would cross are dropped. A cut whose
/// new corners would be sharp, within rounding, gives way to the same cut with the piece given
/// to a junction's other neighbour, then to the next of these cuts, in the same round; a tip
/// none of whose cuts passes is left, and not tried again. An edge is cut at one
/// end per round, the sharper tip's first: a tip whose edge was taken is looked at again on
/// the graph the round leaves, for up to four rounds. Last, a cut's new vertex left between
/// two edges of one boundary, one of them under three quarters of a width long, merges into
/// that edge's other end where that leaves no sharp corner. `None` when nothing was cut.
///
/// ```
/// use imesh_curves::{blunt_sharp_tips, CubicBezier, CurveGraph, GraphEdge, TipOptions};
/// use imesh_geom::Point;
/// // A 20° spike of region 1 in region 0, its sides 20 px long, closed by a third edge.
/// let a = 10f64.to_radians();
/// let points = vec![
///     Point::new(0.0, 0.0),
///     Point::new(20.0 * a.cos(), 20.0 * a.sin()),
///     Point::new(20.0 * a.cos(), -20.0 * a.sin()),
/// ];
/// let edges = vec![
///     GraphEdge { ends: [0, 1], labels: [0, 1] },
///     GraphEdge { ends: [1, 2], labels: [0, 1] },
///     GraphEdge { ends: [2, 0], labels: [0, 1] },
/// ];
/// let g = CurveGraph::new(points, edges)?;
/// let curves: Vec<_> = g.edges().iter().map(|e| CubicBezier::segment(g.point(e.ends[0]), g.point(e.ends[1]))).collect();
/// let b = blunt_sharp_tips(&g, &curves, &TipOptions { width: 2.0, ..TipOptions::default() }).unwrap();
/// assert_eq!(b.tips, 1);
/// // The tip is gone: no edge uses vertex 0; the two sides end at the cut, 4 px wide (the
/// // widest of 2, 1.5 and 1 widths the 20 px sides leave room for).
/// assert!(b.graph.edges().iter().all(|e| !e.ends.contains(&0)));
/// assert_eq!(b.graph.edges().len(), 4);
/// let cut = b.graph.edges()[3].ends.map(|v| b.graph.point(v));
/// assert!((cut[0].distance_squared(cut[1]).sqrt() - 4.0).abs() < 1e-9);
/// # Ok::<(), imesh_curves::CurveError>(())
/// ```
pub fn blunt_sharp_tips(
    g: &CurveGraph,
    curves: &[CubicBezier],
    options: &TipOptions,
) -> Option<Blunted> {
    if curves.len() != g.edges().len() || !(options.width > 0.0 && options.width.is_finite()) {
        return None;
    }
    // An edge is cut at one end per round: a tip whose edge a sharper one took is looked at
    // again on the graph that cut leaves (a long edge between two sharp tips, a sliver along
    // the border between two junctions).
    let mut blunted: Option<Blunted> = None;
    // The vertices of tips whose every cut was dropped for sharp new corners: not tried
    // again, so that the tips they kept from their edges are cut in the next round.
    let mut retries = Retries::default();
    for _ in 0..MAX_ROUNDS {
        let (graph, curves) = match &blunted {
            Some(b) => (&b.graph, b.curves.as_slice()),
            None => (g, curves),
        };
        let (round, deferred) = blunt_round(graph, curves, options, &mut retries);
        if let Some(round) = round {
            blunted = Some(match blunted {
                Some(b) => Blunted {
                    tips: b.tips + round.tips,
                    area: b.area + round.area,
                    moved: b.moved.max(round.moved),
                    ..round
                },
                None => round,
            });
        }
        if !deferred {
            break;
        }
    }
    blunted.map(|b| merge_stubs(b, g.points().len(), options))
}

/// A vertex a cut made that later cuts left between two edges of one boundary, one of them
/// shorter than [`MERGED_STUB`] widths: merged into that edge's other end (see [`merge_stubs`]).
#[derive(Clone, Copy, Debug)]
struct Stub {
    /// The vertex that goes.
    vertex: u32,
    /// The short edge, dropped, and the vertex it leads to.
    short: u32,
    to: u32,
    /// The other edge, whose end at `vertex` moves to `to`.
    long: u32,
    /// The area it sweeps from one side to the other.
    area: f64,
}

/// `b` with every vertex made by its cuts (indices from `first_new`) that is left between two
/// edges of the same two regions, one of them shorter than [`MERGED_STUB`] widths, merged into
/// that short edge's other end: the short edge goes, the other edge's end follows (its tangent
/// kept). A tip's cut at its deepest can be a fraction of a quad wide, and a later round's cut
/// of the sliver beyond it can end at the same vertex: the stub between them held elements a
/// sixth of a quad side across (aloe's worst, at a junction). A merge that would make edges
/// cross, or leave a corner sharper than [`TipOptions::min_angle_deg`], is not made.
fn merge_stubs(b: Blunted, first_new: usize, options: &TipOptions) -> Blunted {
    let g = &b.graph;
    let snap = MERGED_STUB * options.width;
    let mut taken = vec![false; g.edges().len()];
    let mut stubs = Vec::new();
    for v in first_new as u32..g.points().len() as u32 {
        let &[e0, e1] = g.incident(v) else {
            continue;
        };
        // Both walked through `v` (into it, then out of it): the same regions on each side,
        // neither the outside (the domain's border stays where it is).
        let walked_in = |e: u32| {
            let edge = g.edges()[e as usize];
            if edge.ends[1] == v {
                (edge.ends[0], edge.labels)
            } else {
                (edge.ends[1], [edge.labels[1], edge.labels[0]])
            }
        };
        let ((a, labels_in), (c, [right, left])) = (walked_in(e0), walked_in(e1));
        if labels_in != [left, right]
            || labels_in.contains(&OUTSIDE)
            || taken[e0 as usize]
            || taken[e1 as usize]
        {
            continue;
        }
        let p = g.point(v);
        let (la, lc) = (norm(g.point(a) - p), norm(g.point(c) - p));
        let ((short, to), (long, far)) = if la <= lc {
            ((e0, a), (e1, c))
        } else {
            ((e1, c), (e0, a))
        };
        let duplicate = g
            .incident(to)
            .iter()
            .any(|&e| g.edges()[e as usize].ends.contains(&far));
        if la.min(lc) >= snap || to == far || duplicate || g.is_pinned(v) {
            continue;
        }
        let area = 0.5 * cross(p - g.point(far), g.point(to) - g.point(far)).abs();
        taken[short as usize] = true;
        taken[long as usize] = true;
        stubs.push(Stub {
            vertex: v,
            short,
            to,
            long,
            area,
        });
    }
    let min = options.min_angle_deg.to_radians() - ANGLE_ROUNDING;
    loop {
        if stubs.is_empty() {
            return b;
        }
        // Per edge of `g`: the stub that drops or moves it.
        let mut stub_of = vec![usize::MAX; g.edges().len()];
        for (i, s) in stubs.iter().enumerate() {
            stub_of[s.short as usize] = i;
            stub_of[s.long as usize] = i;
        }
        let mut edges = Vec::with_capacity(g.edges().len());
        let mut curves = Vec::with_capacity(g.edges().len());
        let mut owner = Vec::with_capacity(g.edges().len());
        // Per stub: the ends of its moved edge.
        let mut moved_ends = vec![[0; 2]; stubs.len()];
        for (k, (&e, &c)) in g.edges().iter().zip(&b.curves).enumerate() {
            let i = stub_of[k];
            match stubs.get(i) {
                Some(s) if s.short == k as u32 => continue,
                Some(s) => {
                    let end = usize::from(e.ends[1] == s.vertex);
                    let mut ends = e.ends;
                    ends[end] = s.to;
                    moved_ends[i] = ends;
                    edges.push(GraphEdge { ends, ..e });
                    curves.push(moved_end(c, 3 * end, g.point(s.to)));
                }
                None => {
                    edges.push(e);
                    curves.push(c);
                }
            }
            owner.push(i);
        }
        let Some(graph) = with_pins_of(g, g.points().to_vec(), edges) else {
            return b;
        };
        let mut refused: Vec<usize> = match graph.crossing() {
            Some(pair) => {
                let crossing: Vec<usize> = pair
                    .iter()
                    .map(|&e| owner[e as usize])
                    .filter(|&i| i != usize::MAX)
                    .collect();
                if crossing.is_empty() {
                    return b;
                }
                crossing
            }
            None => (0..stubs.len())
                .filter(|&i| {
                    moved_ends[i].iter().any(|&v| {
                        sectors(&graph, &curves, v, options.reach)
                            .iter()
                            .any(|s| s.angle < min)
                    })
                })
                .collect(),
        };
        if refused.is_empty() {
            let area = b.area + stubs.iter().map(|s| s.area).sum::<f64>();
            let moved = stubs.iter().fold(b.moved, |m, s| {
                m.max(norm(g.point(s.to) - g.point(s.vertex)))
            });
            return Blunted {
                graph,
                curves,
                area,
                moved,
                ..b
            };
        }
        refused.sort_unstable();
        refused.dedup();
        for &i in refused.iter().rev() {
            stubs.remove(i);
        }
    }
}

/// How far under [`TipOptions::min_angle_deg`] (radians) a corner a cut makes may measure and
/// still pass: the cuts through a side's far vertex are made to meet the other side at that
/// angle or more, and the sectors measured afterwards, from other roundings, came out at
/// 29.9999999999984° for 30° (on aloe, 8 of 29 cuts refused as sharp, among them the tip
/// that held its worst scaled Jacobian, 0.406).
const ANGLE_ROUNDING: f64 = 1e-9;

/// The rounds of [`blunt_sharp_tips`] at most: each cuts at least one tip, and the tips left
/// for a later round share an edge with one cut.
const MAX_ROUNDS: usize = 4;

/// The tips whose every cut a round dropped for sharp new corners, by their vertex's point
/// (which no cut moves): not tried again.
#[derive(Debug, Default)]
struct Retries {
    refused: Vec<Point>,
}

/// One round of [`blunt_sharp_tips`]: the graph with every tip cut whose edges no sharper
/// tip's cut takes (`None` when nothing was cut), and whether a tip was left for that reason.
fn blunt_round(
    g: &CurveGraph,
    curves: &[CubicBezier],
    options: &TipOptions,
    retries: &mut Retries,
) -> (Option<Blunted>, bool) {
    let mut tips = sharp_tips(g, curves, options);
    tips.retain(|(cut, _)| !retries.refused.contains(&g.point(cut.tip.vertex)));
    // The sharpest first; an edge is cut at one end only.
    tips.sort_by(|a, b| a.0.tip.angle.total_cmp(&b.0.tip.angle));
    let mut used = vec![false; g.edges().len()];
    let mut cuts = Vec::new();
    let mut others = Vec::new();
    let mut deferred = false;
    for (cut, tries) in tips {
        if cut.tip.edges().any(|e| used[e as usize]) {
            deferred = true;
            continue;
        }
        for e in cut.tip.edges() {
            used[e as usize] = true;
        }
        cuts.push(cut);
        others.push(tries);
    }
    // A cut whose new corners would be sharp themselves (a curve turning back across its
    // chord near the cut, a side running on from the cut's end at the tip's angle) gives way
    // to the tip's next cut, and the cuts are made again; a tip none of whose cuts passes is
    // left. A cut made to meet a side at exactly the bar ([`through_depth`]) measures within
    // rounding of it: not sharp.
    let min = options.min_angle_deg.to_radians() - ANGLE_ROUNDING;
    // Per cut: whether a short square cut may move its vertex rather than add an edge. A cut
    // that would be sharp or cross with its vertex moved is first made again with an edge.
    let mut snaps = vec![true; cuts.len()];
    loop {
        if cuts.is_empty() {
            return (None, deferred);
        }
        let (blunted, ends) = match cut_off(g, curves, &cuts, &snaps, SNAP_CUT * options.width) {
            Ok(made) => made,
            // Two tips of one region folded onto each other can overlap: the cuts whose edges
            // cross are dropped, and the rest made again.
            Err(crossing) if !crossing.is_empty() => {
                for &i in crossing.iter().rev() {
                    if std::mem::replace(&mut snaps[i], false) {
                        continue;
                    }
                    cuts.remove(i);
                    others.remove(i);
                    snaps.remove(i);
                }
                continue;
            }
            Err(_) => return (None, false),
        };
        let sharp: Vec<usize> = (0..cuts.len())
            .filter(|&i| {
                ends[i].iter().any(|&v| {
                    sectors(&blunted.graph, &blunted.curves, v, options.reach)
                        .iter()
                        .any(|s| s.angle < min)
                })
            })
            .collect();
        if sharp.is_empty() {
            return (Some(blunted), deferred);
        }
        for &i in sharp.iter().rev() {
            // Made by moving its vertex: made again with an edge first.
            if ends[i][0] == ends[i][1] {
                snaps[i] = false;
                continue;
            }
            for e in cuts[i].tip.edges() {
                used[e as usize] = false;
            }
            match others[i].next_sound(g, &used) {
                Some(next) => {
                    for e in next.tip.edges() {
                        used[e as usize] = true;
                    }
                    cuts[i] = next;
                    snaps[i] = true;
                }
                None => {
                    retries.refused.push(g.point(cuts[i].tip.vertex));
                    cuts.remove(i);
                    others.remove(i);
                    snaps.remove(i);
                }
            }
        }
    }
}

/// G' with the tips of `cuts` cut off (each with its two cut points), and the vertices at
/// the ends of each cut (new ones, or the far vertex of a side cut through). A square cut
/// shorter than `snap` (pixels), where `snaps` allows it for that cut, is made by moving the
/// far vertex it runs from onto its foot on the other side, its other edges following, rather
/// than by an edge a fraction of a quad long (both its ends are then that vertex): only where
/// the vertex is free ([`snap_vertex`]) and the tip's region still loses area. When the graph
/// would cross itself, the cuts whose edges cross (in increasing order); no cut when it would
/// not be sound otherwise.
fn cut_off(
    g: &CurveGraph,
    curves: &[CubicBezier],
    cuts: &[Cut],
    snaps: &[bool],
    snap: f64,
) -> Result<(Blunted, Vec<[u32; 2]>), Vec<usize>> {
    let mut points = g.points().to_vec();
    let mut replaced: Vec<Option<Vec<(GraphEdge, CubicBezier)>>> = vec![None; g.edges().len()];
    // The cut each edge of `g` belongs to.
    let mut cut_of = vec![usize::MAX; g.edges().len()];
    for (i, cut) in cuts.iter().enumerate() {
        for e in cut.tip.edges() {
            cut_of[e as usize] = i;
        }
    }
    // Per vertex of `g`: the cut that moved it onto its foot (usize::MAX for none).
    let mut snapped = vec![usize::MAX; g.points().len()];
    let mut added = Vec::new();
    let mut cut_ends = Vec::with_capacity(cuts.len());
    let (mut area, mut moved) = (0.0, 0.0f64);
    for (
        i,
        Cut {
            tip,
            ends: cut,
            outline,
        },
    ) in cuts.iter().enumerate()
    {
        // A square cut shorter than `snap`: its vertex moves onto its foot, which becomes the
        // vertex where the two sides meet, and no edge is added.
        let piece = polygon_area(outline).abs();
        let square = snap_vertex(g, cuts, &cut_of, i, snap)
            .filter(|_| snaps[i])
            .map(|(v, to)| (v, to, swept(g, tip, v, to)))
            .filter(|&(_, _, swept)| piece + swept > 0.0);
        let mut ids = [0; 2];
        for (k, (end, &p)) in tip.ends.iter().zip(cut).enumerate() {
            // A side taken whole now bounds the receiver, if anything.
            let whole = |e: &End| Some(relabelled(g, curves, e.edge, tip));
            match (tip.cut[k], tip.next[k]) {
                (CutEnd::Along(_), _) => {
                    ids[k] = match square {
                        Some((v, _, _)) => {
                            points[v as usize] = p;
                            v
                        }
                        None => {
                            points.push(p);
                            points.len() as u32 - 1
                        }
                    };
                    replaced[end.edge as usize] = Some(split(g, curves, end, p, ids[k], tip));
                }
                (CutEnd::Second, Some(n)) => {
                    ids[k] = n.far_vertex;
                    replaced[end.edge as usize] = whole(end);
                    replaced[n.edge as usize] = whole(&n);
                }
                (CutEnd::First | CutEnd::Second, _) => {
                    ids[k] = end.far_vertex;
                    replaced[end.edge as usize] = whole(end);
                }
            }
        }
        cut_ends.push(ids);
        area += piece;
        // The farthest the boundary moved: its farthest vertex cut off from the cut's line.
        let across = cut[1] - cut[0];
        for &q in outline {
            moved = moved.max(cross(across, q - cut[0]).abs() / norm(across));
        }
        if let Some((v, to, swept)) = square {
            area += swept;
            snapped[v as usize] = i;
            moved = moved.max(norm(to - g.point(v)));
            continue;
        }
        // The piece is counter-clockwise, its cut walked from side 0 to side 1: the piece, now
        // the receiver's, on the cut's left.
        added.push((
            i,
            GraphEdge {
                ends: ids,
                labels: [tip.receiver, tip.region],
            },
            CubicBezier::segment(cut[0], cut[1]),
        ));
    }
    let mut edges = Vec::with_capacity(g.edges().len() + 2 * cuts.len());
    let mut new_curves = Vec::with_capacity(edges.capacity());
    // The cut each new edge belongs to (usize::MAX for none).
    let mut owner = Vec::with_capacity(edges.capacity());
    for (k, e) in g.edges().iter().enumerate() {
        match &replaced[k] {
            Some(pieces) => {
                for &(piece, curve) in pieces {
                    edges.push(piece);
                    new_curves.push(curve);
                    owner.push(cut_of[k]);
                }
            }
            None => {
                edges.push(*e);
                new_curves.push(curves[k]);
                owner.push(usize::MAX);
            }
        }
    }
    for (i, e, c) in added {
        edges.push(e);
        new_curves.push(c);
        owner.push(i);
    }
    // The edges that met a moved vertex follow it (their tangents kept there); they belong to
    // its cut, which a crossing they make drops.
    for ((e, c), o) in edges.iter().zip(&mut new_curves).zip(&mut owner) {
        for (end, &v) in e.ends.iter().enumerate() {
            if let Some(&i) = snapped.get(v as usize).filter(|&&i| i != usize::MAX) {
                *c = moved_end(*c, 3 * end, points[v as usize]);
                *o = i;
            }
        }
    }
    let graph = with_pins_of(g, points, edges).ok_or_else(Vec::new)?;
    // Each cut lies in its own piece, which holds no vertex; two tips of one region folded
    // onto each other could still overlap.
    if let Some(pair) = graph.crossing() {
        let mut crossing: Vec<usize> = pair
            .iter()
            .map(|&e| owner[e as usize])
            .filter(|&i| i != usize::MAX)
            .collect();
        crossing.sort_unstable();
        crossing.dedup();
        return Err(crossing);
    }
    let blunted = Blunted {
        graph,
        curves: new_curves,
        tips: cuts.len(),
        area,
        moved,
    };
    Ok((blunted, cut_ends))
}

/// The graph of `points` and `edges` (which keep `g`'s vertices first) with `g`'s vertices
/// pinned where they were; `None` where it is not a graph.
fn with_pins_of(g: &CurveGraph, points: Vec<Point>, edges: Vec<GraphEdge>) -> Option<CurveGraph> {
    let mut graph = CurveGraph::new(points, edges).ok()?;
    for v in (0..g.points().len() as u32).filter(|&v| g.is_pinned(v)) {
        graph.pin(v).ok()?;
    }
    Some(graph)
}

/// For cut `i` of `cuts` (the cut each edge belongs to in `cut_of`): the vertex it runs from,
/// and its foot, when it is a square cut shorter than `snap` (from a side's far vertex to a
/// new vertex on the other side) whose vertex may move onto its foot: not pinned, not on the
/// domain's border, and neither at another cut nor on one of its edges.
fn snap_vertex(
    g: &CurveGraph,
    cuts: &[Cut],
    cut_of: &[usize],
    i: usize,
    snap: f64,
) -> Option<(u32, Point)> {
    let Cut { tip, ends, .. } = &cuts[i];
    let along = tip.cut.iter().position(|c| matches!(c, CutEnd::Along(_)))?;
    let other = 1 - along;
    if matches!(tip.cut[other], CutEnd::Along(_)) || norm(ends[1] - ends[0]) >= snap {
        return None;
    }
    let v = match (tip.cut[other], tip.next[other]) {
        (CutEnd::Second, Some(n)) => n.far_vertex,
        _ => tip.ends[other].far_vertex,
    };
    let free = !g.is_pinned(v)
        && g.incident(v).iter().all(|&e| {
            let edge = &g.edges()[e as usize];
            !edge.labels.contains(&OUTSIDE)
                && (cut_of[e as usize] == usize::MAX || cut_of[e as usize] == i)
        })
        && cuts.iter().enumerate().all(|(j, c)| {
            j == i || (c.tip.vertex != v && c.tip.ends.iter().all(|e| e.far_vertex != v))
        });
    free.then_some((v, ends[along]))
}

/// The area the region of `tip` loses when vertex `v` of `g` moves to `to`, by the edges at
/// `v` the tip does not take: each sweeps the triangle between its old and new positions
/// from the region on the side it turns to onto the other (negative where the region gains).
fn swept(g: &CurveGraph, tip: &Tip, v: u32, to: Point) -> f64 {
    let from = g.point(v);
    g.incident(v)
        .iter()
        .filter(|&&e| !tip.edges().any(|x| x == e))
        .map(|&e| {
            let edge = g.edges()[e as usize];
            // Walked towards `v`: its left and right labels.
            let (far, [left, right]) = if edge.ends[1] == v {
                (edge.ends[0], edge.labels)
            } else {
                (edge.ends[1], [edge.labels[1], edge.labels[0]])
            };
            let far = g.point(far);
            let triangle = 0.5 * cross(from - far, to - far);
            if left == tip.region {
                triangle
            } else if right == tip.region {
                -triangle
            } else {
                0.0
            }
        })
        .sum()
}

/// A sector of a vertex of G': from `ends[0]` counter-clockwise to `ends[1]`.
#[derive(Clone, Copy, Debug)]
struct Sector {
    ends: [End; 2],
    /// Between the straight edges (radians).
    chord: f64,
    /// The narrower of that and the curves' sector `reach` out (when the curves keep their
    /// order).
    angle: f64,
}

/// The sectors of vertex `v` of `g` (none below valence 2), directions measured as in
/// [`crate::open_sharp_corners`].
fn sectors(g: &CurveGraph, curves: &[CubicBezier], v: u32, reach: f64) -> Vec<Sector> {
    if g.valence(v) < 2 {
        return Vec::new();
    }
    let ccw = |from: f64, to: f64| (to - from).rem_euclid(std::f64::consts::TAU);
    let p = g.point(v);
    let mut ends: Vec<End> = g
        .incident(v)
        .iter()
        .map(|&k| {
            let e = g.edges()[k as usize];
            let at_start = e.ends[0] == v;
            let far_vertex = if at_start { e.ends[1] } else { e.ends[0] };
            let far = g.point(far_vertex);
            // The curve's direction as `open_sharp_corners` measures it.
            let out = chord(&curves[k as usize], at_start, reach).unwrap_or(far - p);
            End {
                edge: k,
                at_start,
                far_vertex,
                far,
                chord: direction(far - p),
                curve: direction(out),
            }
        })
        .collect();
    ends.sort_by(|a, b| a.chord.total_cmp(&b.chord));
    (0..ends.len())
        .map(|i| {
            let [a, b] = [ends[i], ends[(i + 1) % ends.len()]];
            let chord = ccw(a.chord, b.chord);
            let curve = ccw(a.curve, b.curve);
            let angle = if curve < std::f64::consts::PI {
                chord.min(curve)
            } else {
                chord
            };
            Sector {
                ends: [a, b],
                chord,
                angle,
            }
        })
        .collect()
}

/// Every sector of `g` narrower than the options' angle that may be cut, with its cut.
fn sharp_tips(g: &CurveGraph, curves: &[CubicBezier], options: &TipOptions) -> Vec<(Cut, TipCuts)> {
    let min = options.min_angle_deg.to_radians();
    let mut tips = Vec::new();
    for v in 0..g.points().len() as u32 {
        let p = g.point(v);
        for Sector { ends, chord, angle } in sectors(g, curves, v, options.reach) {
            if chord >= std::f64::consts::PI || angle >= min {
                continue;
            }
            let [a, b] = ends;
            let (left, right) = (a.sides(g), b.sides(g));
            let region = left[0];
            if region == OUTSIDE || right[1] != region {
                continue;
            }
            // The region across the first side, then the second's (a junction's tip borders
            // two neighbours, and the piece given to one keeps the boundary to the other:
            // where the cut runs to a side's far vertex, that boundary can meet the cut at a
            // sharp corner, which the neighbour across that side, taking the side whole, does
            // not have; aloe: 8 of its tips).
            let across = [left[1], right[0]].map(|s| (s != OUTSIDE && s != region).then_some(s));
            let receivers = match across {
                [Some(a), Some(b)] if a != b => vec![a, b],
                [Some(s), _] | [None, Some(s)] => vec![s],
                [None, None] => continue,
            };
            // The region's boundary one edge further on each side (not back at the tip).
            let next = [0, 1].map(|k| {
                let e = ends[k];
                let n = sectors(g, curves, e.far_vertex, options.reach)
                    .into_iter()
                    .find(|s| s.ends[1 - k].edge == e.edge)
                    .map(|s| s.ends[k])?;
                (n.edge != e.edge && n.far_vertex != v).then_some(n)
            });
            let far = |k: usize, at: CutEnd| match (at, next[k]) {
                (CutEnd::First, _) => Some(ends[k].far),
                (CutEnd::Second, Some(n)) => Some(n.far),
                _ => None,
            };
            // The widest cut its edges leave room for, down to `width`: a cut one quad wide
            // leaves the rest of a thin spike a quad wide too, a strip of half-size quads.
            let across = || {
                WIDTHS.iter().map(|&k| k * options.width).find_map(|w| {
                    let depth = (w / (2.0 * (chord / 2.0).sin())).min(options.max_depth * w);
                    let long_enough = |e: &End| norm(e.far - p) - depth >= 0.5 * options.width;
                    (depth.is_finite() && long_enough(&a) && long_enough(&b))
                        .then_some([CutEnd::Along(depth); 2])
                })
            };
            // A side too short for that: from its far vertex (the shorter side's first), then
            // from the next vertex along the region's boundary, to the other side.
            let shorter = usize::from(norm(b.far - p) < norm(a.far - p));
            let through = |at: CutEnd| {
                [shorter, 1 - shorter].into_iter().find_map(|k| {
                    let depth = through_depth(p, far(k, at)?, &ends[1 - k], k == 0, options)?;
                    let mut cut = [CutEnd::Along(depth); 2];
                    cut[k] = at;
                    Some(cut)
                })
            };
            // Both too short: between the vertices where the sides end, if they are a width
            // or more apart (and at most two beyond the tip's first vertices), within the
            // deepest cut, and not already joined by an edge. Failing every other cut, the
            // first vertices closer than that too, when the piece is a sliver's end of at
            // most three eighths of a quad (`across · depth ≤ SMALL_PIECE · width²`): a notch a
            // fraction of a pixel wide that Imesh's sampling left.
            let small = SMALL_PIECE * options.width * options.width;
            let whole = |at: [CutEnd; 2], sliver: bool| {
                let (qa, qb) = (far(0, at[0])?, far(1, at[1])?);
                let across = norm(qb - qa);
                let depth = cross(qa - p, qb - p).abs() / across;
                let ids = [0, 1].map(|k| match at[k] {
                    CutEnd::Second => next[k].map_or(u32::MAX, |n| n.far_vertex),
                    _ => ends[k].far_vertex,
                });
                let first = at == [CutEnd::First; 2];
                ((across >= options.width || (sliver && first && across * depth <= small))
                    && (first || across <= WIDTHS[0] * options.width)
                    && depth <= options.max_depth * options.width
                    && !g
                        .incident(ids[0])
                        .iter()
                        .any(|&k| g.edges()[k as usize].ends.contains(&ids[1])))
                .then_some(at)
            };
            let (first, second) = (CutEnd::First, CutEnd::Second);
            // The first of these whose piece holds no other vertex of the graph.
            let candidates = [
                across(),
                through(first),
                whole([first; 2], false),
                through(second),
                whole([second, first], false),
                whole([first, second], false),
                whole([second; 2], false),
                whole([first; 2], true),
            ];
            // The last candidate can repeat the third (between the first vertices).
            let mut cuts: Vec<[CutEnd; 2]> = Vec::with_capacity(candidates.len());
            for cut in candidates.into_iter().flatten() {
                if !cuts.contains(&cut) {
                    cuts.push(cut);
                }
            }
            let tries = cuts
                .into_iter()
                .flat_map(|cut| {
                    receivers.iter().map(move |&receiver| Tip {
                        vertex: v,
                        ends,
                        next,
                        region,
                        receiver,
                        angle,
                        cut,
                    })
                })
                .collect();
            // The first sound one is cut; the others wait until a cut proves sharp.
            let mut tries = TipCuts { tries, next: 0 };
            if let Some(cut) = tries.next_sound(g, &[]) {
                tips.push((cut, tries));
            }
        }
    }
    tips
}

/// How far along `long`'s chord a cut from `q`, a vertex on the tip's other side, meets it,
/// for the tip at `p` (the region on the left of `long`, or on its right when `right`): the
/// widest of [`WIDTHS`] for which the cut meets `long` at [`TipOptions::min_angle_deg`] or
/// more beyond the foot of `q` (so that the region keeps at least 90° there), within `long`
/// (leaving half a width of it) and within [`TipOptions::max_depth`] widths of `p`.
///
/// Where no width fits and `q` stands less than a width over `long` (under half a width, a
/// cut a width long meets `long` at under 30°), the tip is the end of a sliver thinner than a
/// quad: a thin region along the image's border whose end the label clean-up has bevelled, a
/// grain boundary grazing the border. It is then cut square, from `q` to its foot, if that
/// lies within `long` and the piece cut off is no larger than the deepest width cut's
/// (`foot · height ≤ max_depth · width²`, however deep: a long sliver under a pixel thick,
/// which Imesh's sampling can leave across a narrow gap, is cut at its end): both regions
/// get 90° there, and the sliver's end is as wide as the sliver, whose quads are that small
/// anyway, where the tip left whole would hold a quad with the tip's angle (under 0.5 in
/// scaled Jacobian). `None` when no cut fits, or when `q` is not on the region's side of
/// `long`.
fn through_depth(p: Point, q: Point, long: &End, right: bool, options: &TipOptions) -> Option<f64> {
    let along = (long.far - p) * (1.0 / norm(long.far - p));
    // `q`'s foot on `long`'s line, and its height over it on the region's side.
    let (foot, height) = (dot(along, q - p), cross(along, q - p));
    let height = if right { -height } else { height };
    // A NaN height (a degenerate side) fails too.
    if height.is_nan() || height <= 0.0 {
        return None;
    }
    let min = options.min_angle_deg.to_radians();
    // Within `long`, half a width short of its end.
    let on_long = |depth: f64| depth <= norm(long.far - p) - 0.5 * options.width;
    WIDTHS
        .iter()
        .map(|&k| k * options.width)
        .find_map(|w| {
            let run = (w * w - height * height).sqrt();
            let depth = foot + run;
            (w >= height
                && height.atan2(run) >= min
                && on_long(depth)
                && depth <= options.max_depth * w)
                .then_some(depth)
        })
        .or_else(|| {
            (height < options.width
                && height >= SQUARE_CUT_MIN_HEIGHT * options.width
                && foot > 0.0
                && on_long(foot)
                && foot * height <= options.max_depth * options.width * options.width)
                .then_some(foot)
        })
}

/// `edge` whole, relabelled with the receiver for the region of `tip`, when it still
/// separates two regions.
fn relabelled(
    g: &CurveGraph,
    curves: &[CubicBezier],
    edge: u32,
    tip: &Tip,
) -> Vec<(GraphEdge, CubicBezier)> {
    let e = g.edges()[edge as usize];
    let labels = tip.relabel(e.labels);
    if labels[0] == labels[1] {
        Vec::new()
    } else {
        vec![(GraphEdge { labels, ..e }, curves[edge as usize])]
    }
}

/// The pieces of `end`'s edge once cut at `p` (new vertex `id`): the far piece with the
/// region's labels, and the near piece, relabelled with the receiver for the region, when it
/// still separates two regions. Each keeps the edge's direction and its part of the curve, the
/// end at the cut moved onto `p` (with the next control point, keeping the tangent).
fn split(
    g: &CurveGraph,
    curves: &[CubicBezier],
    end: &End,
    p: Point,
    id: u32,
    tip: &Tip,
) -> Vec<(GraphEdge, CubicBezier)> {
    let e = g.edges()[end.edge as usize];
    let curve = curves[end.edge as usize];
    let v = g.point(tip.vertex);
    let share = norm(p - v) / norm(end.far - v);
    let t = curve.closest_parameter(p, if end.at_start { share } else { 1.0 - share });
    let (first, second) = curve.split(t);
    let (first, second) = (moved_end(first, 3, p), moved_end(second, 0, p));
    let near_labels = tip.relabel(e.labels);
    let mut pieces = Vec::with_capacity(2);
    let (near, far) = if end.at_start {
        (
            (
                GraphEdge {
                    ends: [e.ends[0], id],
                    labels: near_labels,
                },
                first,
            ),
            (
                GraphEdge {
                    ends: [id, e.ends[1]],
                    labels: e.labels,
                },
                second,
            ),
        )
    } else {
        (
            (
                GraphEdge {
                    ends: [id, e.ends[1]],
                    labels: near_labels,
                },
                second,
            ),
            (
                GraphEdge {
                    ends: [e.ends[0], id],
                    labels: e.labels,
                },
                first,
            ),
        )
    };
    if near_labels[0] != near_labels[1] {
        pieces.push(near);
    }
    pieces.push(far);
    pieces
}

/// `c` with its control point `i` (0 or 3) moved to `p`, and its neighbour by the same offset.
fn moved_end(c: CubicBezier, i: usize, p: Point) -> CubicBezier {
    let mut control = c.control;
    let offset = p - control[i];
    let next = if i == 0 { 1 } else { 2 };
    control[i] = p;
    control[next] = control[next] + offset;
    CubicBezier::new(control)
}

/// True when the piece `outline` (counter-clockwise, its cut from `outline[cut[0]]` to
/// `outline[cut[1]]`, its other sides edges of `g`) is a simple polygon the cut does not leave,
/// and no vertex of `g` but those of `on` lies in it or on its outline.
fn sound_piece(g: &CurveGraph, on: &[u32], outline: &[Point], cut: [usize; 2]) -> bool {
    let n = outline.len();
    let (a, b) = (outline[cut[0]], outline[cut[1]]);
    // The cut crosses none of the other sides, and does not run back along a side it shares
    // an end with (pixel-corner vertices are often collinear).
    let crosses = (0..n).filter(|&k| k != cut[0]).any(|k| {
        let (c, d) = (outline[k], outline[(k + 1) % n]);
        match [a, b].iter().position(|&e| e == c || e == d) {
            Some(i) => {
                let (at, to) = ([a, b][i], [b, a][i]);
                let other = if c == at { d } else { c };
                orient2d(at, to, other) == 0.0 && dot(to - at, other - at) > 0.0
            }
            None => {
                orient2d(a, b, c) * orient2d(a, b, d) < 0.0
                    && orient2d(c, d, a) * orient2d(c, d, b) < 0.0
            }
        }
    });
    if crosses || polygon_area(outline) <= 0.0 {
        return false;
    }
    let (lo, hi) = bounding_box(outline.iter().copied());
    g.points().iter().enumerate().all(|(u, &q)| {
        on.contains(&(u as u32))
            || q.x < lo.x
            || q.x > hi.x
            || q.y < lo.y
            || q.y > hi.y
            || g.valence(u as u32) == 0
            || !winds_around((0..n).map(|k| (outline[k], outline[(k + 1) % n])), q)
    })
}

/// The signed (shoelace) area of `outline`: positive counter-clockwise.
fn polygon_area(outline: &[Point]) -> f64 {
    let n = outline.len();
    0.5 * (0..n)
        .map(|k| cross(outline[k], outline[(k + 1) % n]))
        .sum::<f64>()
}

/// The length of `d`.
fn norm(d: Point) -> f64 {
    (d.x * d.x + d.y * d.y).sqrt()
}

/// The cross product of `a` and `b`.
fn cross(a: Point, b: Point) -> f64 {
    a.x * b.y - a.y * b.x
}

/// The dot product of `a` and `b`.
fn dot(a: Point, b: Point) -> f64 {
    a.x * b.x + a.y * b.y
}

/// The direction of `d` in radians.
fn direction(d: Point) -> f64 {
    d.y.atan2(d.x)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use std::collections::HashMap;

    /// Cuts of 2 px (and twice that), directions 2 px out.
    fn two_px() -> TipOptions {
        at_width(2.0)
    }

    /// Cuts of `width` px, directions `width` px out.
    fn at_width(width: f64) -> TipOptions {
        TipOptions {
            width,
            reach: width,
            ..TipOptions::default()
        }
    }

    /// `g` with its one tip, at vertex 0, cut off with `options` (straight curves): asserts
    /// that one tip was cut, that vertex 0 is left unused and that the graph does not cross
    /// itself.
    fn cut_once(g: &CurveGraph, options: &TipOptions) -> Blunted {
        let b = blunt_sharp_tips(g, &straight(g), options).unwrap();
        assert_eq!(b.tips, 1);
        assert!(b.graph.crossing().is_none());
        assert_eq!(b.graph.valence(0), 0);
        b
    }

    /// The edge from `a` to `b` with `labels` (left, right).
    fn e(a: u32, b: u32, labels: [u32; 2]) -> GraphEdge {
        GraphEdge {
            ends: [a, b],
            labels,
        }
    }

    /// Straight curves for every edge of `g`.
    fn straight(g: &CurveGraph) -> Vec<CubicBezier> {
        g.edges()
            .iter()
            .map(|e| CubicBezier::segment(g.point(e.ends[0]), g.point(e.ends[1])))
            .collect()
    }

    /// Each label's area (its faces' signed areas summed: an island's hole counts against it).
    fn areas(g: &CurveGraph) -> HashMap<u32, f64> {
        let mut a = HashMap::new();
        for f in g.faces() {
            assert!(f.consistent, "a face walk with mixed labels");
            *a.entry(f.label).or_insert(0.0) += f.area;
        }
        a
    }

    /// The smallest angle (degrees) of a region at vertex `v`: between consecutive edges.
    fn sectors_at(g: &CurveGraph, v: u32) -> Vec<(u32, f64)> {
        let p = g.point(v);
        let mut out: Vec<(f64, u32, u32)> = g
            .incident(v)
            .iter()
            .map(|&k| {
                let e = g.edges()[k as usize];
                let (far, left) = if e.ends[0] == v {
                    (g.point(e.ends[1]), e.labels[0])
                } else {
                    (g.point(e.ends[0]), e.labels[1])
                };
                (direction(far - p), k, left)
            })
            .collect();
        out.sort_by(|a, b| a.0.total_cmp(&b.0));
        (0..out.len())
            .map(|i| {
                let (a, b) = (out[i], out[(i + 1) % out.len()]);
                let angle = (b.0 - a.0).rem_euclid(std::f64::consts::TAU).to_degrees();
                (a.2, if out.len() == 1 { 360.0 } else { angle })
            })
            .collect()
    }

    /// A wedge of region 1 from the origin between the directions 0° and `angle`, its sides
    /// `length` long, in a square of region 0 (with `junction`, the square's lower half, below
    /// the wedge's lower side and its extensions, is region 2), rotated by `turn` degrees.
    fn wedge(angle: f64, length: f64, turn: f64, junction: bool) -> CurveGraph {
        let t = turn.to_radians();
        let at = |x: f64, y: f64| {
            let (sin, cos) = t.sin_cos();
            Point::new(x * cos - y * sin, x * sin + y * cos)
        };
        let (a, s) = (angle.to_radians(), 3.0 * length);
        let points = vec![
            at(0.0, 0.0),
            at(length, 0.0),
            at(length * a.cos(), length * a.sin()),
            at(-s, 0.0),
            at(s, 0.0),
            at(-s, -s),
            at(s, -s),
            at(s, s),
            at(-s, s),
        ];
        let below = if junction { 2 } else { 0 };
        // Each label on the left of its edge's direction.
        let mut edges = vec![
            e(0, 1, [1, below]),
            e(1, 2, [1, 0]),
            e(2, 0, [1, 0]),
            e(5, 6, [below, OUTSIDE]),
            e(6, 4, [below, OUTSIDE]),
            e(4, 7, [0, OUTSIDE]),
            e(7, 8, [0, OUTSIDE]),
            e(8, 3, [0, OUTSIDE]),
            e(3, 5, [below, OUTSIDE]),
        ];
        if junction {
            edges.push(e(3, 0, [0, 2]));
            edges.push(e(1, 4, [0, 2]));
        }
        CurveGraph::new(points, edges).unwrap()
    }

    /// A spike of region 1 in region 0: cut where it is the width wide, the region's two new
    /// corners right-ish, the tip's area given to region 0, the tip vertex left unused.
    #[test]
    fn a_spike_tip_is_cut_where_it_is_one_width_wide() {
        let g = wedge(20.0, 30.0, 15.0, false);
        let options = two_px();
        let b = cut_once(&g, &options);
        // The widest cut that leaves room: two widths (4 px) across, 11.5 px from the tip.
        let cut = b.graph.edges().last().unwrap();
        let [p, q] = cut.ends.map(|v| b.graph.point(v));
        assert!((norm(q - p) - 4.0).abs() < 1e-9);
        for v in cut.ends {
            for (label, angle) in sectors_at(&b.graph, v) {
                if label == 1 {
                    assert!((angle - 100.0).abs() < 1e-6, "{angle}");
                }
            }
        }
        let (before, after) = (areas(&g), areas(&b.graph));
        assert!((before[&1] - after[&1] - b.area).abs() < 1e-9);
        assert!((after[&0] - before[&0] - b.area).abs() < 1e-9);
        assert!((b.moved - 4.0 / (2.0 * 10f64.to_radians().tan())).abs() < 1e-9);
    }

    /// A wedge between two other regions at a junction: the tip goes to the region across its
    /// first side (counter-clockwise: the lower one), and the piece of its other side near the
    /// junction stays, now between the two neighbours.
    #[test]
    fn a_junction_tip_keeps_the_boundary_between_its_neighbours() {
        let g = wedge(16.0, 30.0, -40.0, true);
        let b = blunt_sharp_tips(&g, &straight(&g), &TipOptions::default()).unwrap();
        assert_eq!(b.tips, 1);
        assert!(b.graph.crossing().is_none());
        let kept: Vec<&GraphEdge> = b
            .graph
            .edges()
            .iter()
            .filter(|e| e.ends.contains(&0))
            .collect();
        // The tip vertex keeps the boundary between regions 0 and 2 on its left, and the near
        // piece of the wedge's upper side, now between them too.
        assert_eq!(kept.len(), 2);
        assert!(kept.iter().all(|e| !e.labels.contains(&1)));
        let (before, after) = (areas(&g), areas(&b.graph));
        assert!((before[&0] - after[&0]).abs() < 1e-9);
        assert!((before[&1] - after[&1] - b.area).abs() < 1e-9);
        assert!((after[&2] - before[&2] - b.area).abs() < 1e-9);
        assert!(sectors_at(&b.graph, 0).iter().all(|&(_, a)| a > 30.0));
    }

    /// A junction's wedge (region 1) of 26.6° on the pixel lattice, as on aloe: its sides 2 and
    /// 2.2 px to their first vertices, where one turns up-left at 45° and the other runs on,
    /// between region 2 across its first side and region 3 across its second. The cut runs
    /// from the first side's vertex to the second side's next one; given to region 2, the
    /// piece would meet the boundary of region 3 it keeps there at 18.4°, so that cut was
    /// refused and the tip left whole. Given to region 3, which takes the second side whole,
    /// it is made: the junction is gone from region 1 and no sector is left under 30°.
    #[test]
    fn a_junction_tip_is_given_to_the_neighbour_that_takes_its_short_side() {
        let points: Vec<Point> = [
            (0.0, 0.0),  // 0: the tip
            (-2.0, 0.0), // 1, 2: its second side
            (-3.0, -1.0),
            (-2.0, 1.0), // 3, 4: its first side
            (-11.0, 8.0),
            (-30.0, 8.0), // 5, 6: region 1 meets the frame
            (-30.0, -1.0),
            (30.0, 2.0),  // 7: the boundary of regions 2 and 3 meets the frame
            (30.0, 30.0), // 8..=11: the frame's corners
            (-30.0, 30.0),
            (-30.0, -30.0),
            (30.0, -30.0),
        ]
        .map(Point::from)
        .to_vec();
        let regions = [
            (1, vec![0, 3, 4, 5, 6, 2, 1]),
            (2, vec![0, 7, 8, 9, 5, 4, 3]),
            (3, vec![0, 1, 2, 6, 10, 11, 7]),
        ];
        let pairs = [
            (0, 1),
            (1, 2),
            (2, 6),
            (6, 5),
            (5, 4),
            (4, 3),
            (3, 0),
            (0, 7),
            (7, 8),
            (8, 9),
            (9, 5),
            (6, 10),
            (10, 11),
            (11, 7),
        ];
        let g = labelled_graph(points, &regions, &pairs);
        let tip = sectors_at(&g, 0);
        assert!(
            tip.iter()
                .any(|&(l, a)| l == 1 && (a - 26.565).abs() < 1e-3),
            "{tip:?}"
        );
        let b = blunt_sharp_tips(&g, &straight(&g), &two_px()).unwrap();
        assert_eq!(b.tips, 1);
        assert!(b.graph.crossing().is_none());
        assert!(sectors_at(&b.graph, 0).iter().all(|&(l, _)| l != 1));
        for v in 0..b.graph.points().len() as u32 {
            for (label, angle) in sectors_at(&b.graph, v) {
                assert!(angle > 30.0 - 1e-6, "{v}: {label} {angle}");
            }
        }
        let (before, after) = (areas(&g), areas(&b.graph));
        assert!((before[&1] - after[&1] - b.area).abs() < 1e-9);
        assert!((after[&3] - before[&3] - b.area).abs() < 1e-9);
        assert!((before[&2] - after[&2]).abs() < 1e-9);
    }

    /// The graph of `pairs` of `points`, each edge labelled with the regions (`regions`: a label
    /// and its counter-clockwise ring of point indices) on its left and right.
    fn labelled_graph(
        points: Vec<Point>,
        regions: &[(u32, Vec<usize>)],
        pairs: &[(usize, usize)],
    ) -> CurveGraph {
        let label_at = |q: Point| {
            regions
                .iter()
                .find(|(_, ring)| {
                    let n = ring.len();
                    winds_around(
                        (0..n).map(|k| (points[ring[k]], points[ring[(k + 1) % n]])),
                        q,
                    )
                })
                .map_or(OUTSIDE, |r| r.0)
        };
        let edges: Vec<GraphEdge> = pairs
            .iter()
            .map(|&(a, b)| {
                let (p, q) = (points[a], points[b]);
                let (mid, d) = (p + (q - p) * 0.5, (q - p) * (1e-3 / norm(q - p)));
                let left = Point::new(-d.y, d.x);
                GraphEdge {
                    ends: [a as u32, b as u32],
                    labels: [label_at(mid + left), label_at(mid - left)],
                }
            })
            .collect();
        CurveGraph::new(points, edges).unwrap()
    }

    /// A junction's 26.6° wedge (region 1) at the end of a strip a pixel thick, as on aloe
    /// (its worst scaled Jacobian, 0.447): its sides 2.2 and 2 px to their first vertices, a
    /// pixel apart, the strip running on between region 2 above and region 3 below. The first
    /// cuts tried run from one side's first vertex to the other side's next one, and meet the
    /// side running on at 26.6° or 18.4°, whichever neighbour takes the piece; the cut
    /// between the first vertices, tried after them, leaves no corner under 30°.
    #[test]
    fn a_tip_whose_first_cuts_are_sharp_takes_a_later_one() {
        let points: Vec<Point> = [
            (0.0, 0.0), // 0: the tip
            (2.0, 0.0), // 1, 2: its lower side, then the strip's lower boundary
            (4.0, -1.0),
            (30.0, -1.0), // 3, 4: the strip meets the frame
            (30.0, 0.0),
            (4.0, 0.0), // 5, 6: the strip's upper boundary, then the tip's upper side
            (2.0, 1.0),
            (30.0, 30.0), // 7..=11: the frame and the boundary of regions 2 and 3
            (-30.0, 30.0),
            (-30.0, 0.0),
            (-30.0, -30.0),
            (30.0, -30.0),
        ]
        .map(Point::from)
        .to_vec();
        let regions = [
            (1, vec![0, 1, 2, 3, 4, 5, 6]),
            (2, vec![9, 0, 6, 5, 4, 7, 8]),
            (3, vec![9, 10, 11, 3, 2, 1, 0]),
        ];
        let pairs = [
            (0, 1),
            (1, 2),
            (2, 3),
            (3, 4),
            (4, 5),
            (5, 6),
            (6, 0),
            (9, 0),
            (4, 7),
            (7, 8),
            (8, 9),
            (9, 10),
            (10, 11),
            (11, 3),
        ];
        let g = labelled_graph(points, &regions, &pairs);
        assert!(sectors_at(&g, 0)
            .iter()
            .any(|&(l, a)| l == 1 && (a - 26.565).abs() < 1e-3));
        let b = blunt_sharp_tips(&g, &straight(&g), &two_px()).unwrap();
        assert_eq!(b.tips, 1);
        assert!(b.graph.crossing().is_none());
        // Cut between the first vertices: the piece is the triangle (0, 1, 6), 1 px².
        assert!((b.area - 1.0).abs() < 1e-9);
        assert!(b.graph.edges().iter().any(|e| {
            let mut ends = e.ends;
            ends.sort_unstable();
            ends == [1, 6]
        }));
        assert!(sectors_at(&b.graph, 0).iter().all(|&(l, _)| l != 1));
        for v in 0..b.graph.points().len() as u32 {
            for (label, angle) in sectors_at(&b.graph, v) {
                assert!(angle > 30.0 - 1e-6, "{v}: {label} {angle}");
            }
        }
    }

    /// Where one side of the tip is the domain's border, the tip goes to the region across the
    /// other side, and the border keeps its line.
    #[test]
    fn a_tip_on_the_border_goes_to_the_inner_neighbour() {
        // Region 1: a 20° sliver along the bottom border y = 0, from the corner (0, 0).
        let a = 20f64.to_radians();
        let points = vec![
            Point::new(0.0, 0.0),
            Point::new(30.0, 0.0),
            Point::new(30.0, 30.0 * a.tan()),
            Point::new(40.0, 0.0),
            Point::new(40.0, 40.0),
            Point::new(0.0, 40.0),
        ];
        let edges = vec![
            e(0, 1, [1, OUTSIDE]),
            e(1, 2, [1, 0]),
            e(2, 0, [1, 0]),
            e(1, 3, [0, OUTSIDE]),
            e(3, 4, [0, OUTSIDE]),
            e(4, 5, [0, OUTSIDE]),
            e(5, 0, [0, OUTSIDE]),
        ];
        let g = CurveGraph::new(points, edges).unwrap();
        let b = blunt_sharp_tips(&g, &straight(&g), &TipOptions::default()).unwrap();
        assert_eq!(b.tips, 1);
        assert!(b.graph.crossing().is_none());
        // The border near the corner now bounds region 0.
        let near = b.graph.edges().iter().find(|e| e.ends[0] == 0).unwrap();
        assert_eq!(near.labels, [0, OUTSIDE]);
        assert_eq!(b.graph.point(near.ends[1]).y, 0.0);
        let (before, after) = (areas(&g), areas(&b.graph));
        assert!((after[&0] - before[&0] - b.area).abs() < 1e-9);
    }

    /// A cut that would leave a sharp corner of its own is not made: the lower side's curve
    /// swings far below its chord and back, so that where it is cut it heads nearly along the
    /// cut edge.
    #[test]
    fn a_cut_that_would_be_sharp_itself_is_not_made() {
        let g = wedge(20.0, 30.0, 0.0, false);
        let options = two_px();
        // As straight curves the tip is cut.
        assert!(blunt_sharp_tips(&g, &straight(&g), &options).is_some());
        let mut curves = straight(&g);
        let (a, b) = (g.point(0), g.point(1));
        curves[0] = CubicBezier::new([a, Point::new(8.0, -120.0), Point::new(13.0, 120.0), b]);
        // The tip is still sharp and cut, but the cut's corner at the lower side would be
        // sharp too.
        assert_eq!(sharp_tips(&g, &curves, &options).len(), 1);
        assert!(blunt_sharp_tips(&g, &curves, &options).is_none());
    }

    /// Region 1 bounded by `outline` (counter-clockwise, its first point at the origin),
    /// rotated by `turn` degrees about the origin, in region 0 filling a square frame three
    /// times the outline's extent. `None` when the outline crosses itself.
    fn in_frame(outline: &[Point], turn: f64) -> Option<CurveGraph> {
        let (sin, cos) = turn.to_radians().sin_cos();
        let at = |p: Point| Point::new(p.x * cos - p.y * sin, p.x * sin + p.y * cos);
        let s = 3.0
            * outline
                .iter()
                .map(|p| p.x.abs().max(p.y.abs()))
                .fold(1.0, f64::max);
        let mut points: Vec<Point> = outline.iter().map(|&p| at(p)).collect();
        points.extend([(-s, -s), (s, -s), (s, s), (-s, s)].map(|(x, y)| at(Point::new(x, y))));
        let n = outline.len() as u32;
        let mut edges: Vec<GraphEdge> = (0..n).map(|k| e(k, (k + 1) % n, [1, 0])).collect();
        edges.extend((0..4).map(|k| e(n + k, n + (k + 1) % 4, [0, OUTSIDE])));
        let g = CurveGraph::new(points, edges).ok()?;
        (g.crossing().is_none() && polygon_area(outline) > 0.0).then_some(g)
    }

    /// The direction `deg` degrees from the x axis.
    fn dir(deg: f64) -> Point {
        let (sin, cos) = deg.to_radians().sin_cos();
        Point::new(cos, sin)
    }

    /// Region 1 from a `angle`° tip at the origin (rotated by `turn` degrees): its lower side
    /// `long` px along the x axis, its upper side `short` px long, from whose end `a` (vertex 4)
    /// the region's boundary turns straight up; region 0 around it, in a square frame. `None`
    /// when that outline crosses itself (`a` beyond the lower side's end).
    fn hook(angle: f64, short: f64, long: f64, turn: f64) -> Option<CurveGraph> {
        let a = dir(angle) * short;
        let outline = [
            Point::new(0.0, 0.0),
            Point::new(long, 0.0),
            Point::new(long, long),
            Point::new(a.x, long),
            a,
        ];
        in_frame(&outline, turn)
    }

    /// A 20° tip whose upper side ends 3 px out, where the region turns up: too short for a
    /// cut across both sides, it is cut from that side's end to the lower side, one width
    /// (2 px) long, the short side and the triangle given to region 0.
    #[test]
    fn a_tip_with_a_short_side_is_cut_from_its_end() {
        let g = hook(20.0, 3.0, 30.0, 35.0).unwrap();
        let b = cut_once(&g, &two_px());
        // One new vertex; the cut joins it to the short side's end, vertex 4.
        assert_eq!(b.graph.points().len(), g.points().len() + 1);
        let cut = b.graph.edges().last().unwrap();
        let new = g.points().len() as u32;
        assert!(cut.ends.contains(&4) && cut.ends.contains(&new));
        let [p, q] = cut.ends.map(|v| b.graph.point(v));
        assert!((norm(q - p) - 2.0).abs() < 1e-9);
        // Region 1 keeps more than 90° at the new vertex, region 0 gets 30° or more there.
        for (label, angle) in sectors_at(&b.graph, new) {
            assert!(
                angle >= if label == 1 { 90.0 } else { 30.0 },
                "{label}: {angle}"
            );
        }
        let (before, after) = (areas(&g), areas(&b.graph));
        assert!((before[&1] - after[&1] - b.area).abs() < 1e-9);
        assert!((after[&0] - before[&0] - b.area).abs() < 1e-9);
        // The triangle: the 3 px side and the 4.5 px run to the cut, at 20°.
        let run = 3.0 * 20f64.to_radians().cos()
            + (4.0 - (3.0 * 20f64.to_radians().sin()).powi(2)).sqrt();
        assert!((b.area - 0.5 * 3.0 * run * 20f64.to_radians().sin()).abs() < 1e-9);
    }

    /// The tip of a strip 2 px thick: its upper side rises to the strip's height and the
    /// region runs on along it, parallel to the lower side. The cut from the upper side's end
    /// meets the lower side at exactly the bar, 30°, a cut of the widest width (4 px, twice the
    /// strip), which leaves the strip 30° at both its ends by construction (the strip's sides
    /// are parallel), and the sectors measured afterwards give those as 30° within rounding
    /// either way (on aloe, 29.9999999999984°). Such a cut is made at every tip angle and turn
    /// of the frame, and leaves no sector under 30° by more than the rounding.
    #[test]
    fn a_cut_meeting_a_side_at_exactly_the_bar_is_made() {
        let options = two_px();
        let mut exact = 0;
        for angle in [18.0, 20.0, 22.0, 24.0, 26.0, 28.0] {
            let a = Point::new(2.0 / f64::to_radians(angle).tan(), 2.0);
            for turn in (0..36).map(|k| f64::from(k) * 10.0 + 3.0) {
                let outline = [
                    Point::new(0.0, 0.0),
                    Point::new(30.0, 0.0),
                    Point::new(30.0, 2.0),
                    a,
                ];
                let g = in_frame(&outline, turn).unwrap();
                let b = cut_once(&g, &options);
                let new = g.points().len() as u32;
                assert_eq!(
                    b.graph.points().len(),
                    g.points().len() + 1,
                    "{angle}° {turn}°"
                );
                let cut = b.graph.edges().last().unwrap();
                let [p, q] = cut.ends.map(|v| b.graph.point(v));
                if (norm(q - p) - 4.0).abs() < 1e-9 {
                    exact += 1;
                }
                for v in [3, new] {
                    for (label, sector) in sectors_at(&b.graph, v) {
                        assert!(sector > 30.0 - 1e-6, "{angle}° {turn}°: {label} {sector}");
                    }
                }
            }
        }
        // The widest cut, at exactly 30°, where the rounding let it be made at all.
        assert!(exact > 0);
    }

    /// A 12° tip whose upper side ends 2.45 px over the lower one (where the region turns up):
    /// a cut a width (6 px) long from there would meet the lower side at 24°, so the tip is cut
    /// square, from that side's end straight down to the lower side. That cut is under half a
    /// width long, so the side's end itself moves down onto its foot: the region's boundary
    /// turns straight up from the lower side there, with no edge a fraction of a quad long
    /// (the region keeps a right angle). Before session 54, the edge; before that, the cut
    /// between the sides' far vertices was sharp itself, and the tip was left whole.
    #[test]
    fn a_low_tip_end_moves_onto_the_other_side() {
        let (angle, short) = (12.0f64, 11.8);
        let g = hook(angle, short, 30.0, 35.0).unwrap();
        let b = cut_once(&g, &at_width(6.0));
        // No new vertex: vertex 4, the upper side's end, is now on the lower side (vertex 0
        // to vertex 1), square below where it was.
        assert_eq!(b.graph.points().len(), g.points().len());
        let (from, to) = (g.point(4), b.graph.point(4));
        let lower = g.point(1) - g.point(0);
        assert!(cross(lower, to - g.point(0)).abs() < 1e-9 * norm(lower));
        assert!(dot(to - from, lower).abs() < 1e-9 * norm(lower));
        let height = short * angle.to_radians().sin();
        assert!((norm(to - from) - height).abs() < 1e-9);
        // Region 1 keeps a right angle there; region 0, which takes the tip and the lower
        // side up to there, the rest.
        let sectors = sectors_at(&b.graph, 4);
        assert_eq!(sectors.len(), 2);
        for (label, sector) in sectors {
            let expected = if label == 1 { 90.0 } else { 270.0 };
            assert!((sector - expected).abs() < 1e-6, "{label}: {sector}");
        }
        let (before, after) = (areas(&g), areas(&b.graph));
        assert!((before[&1] - after[&1] - b.area).abs() < 1e-9);
        assert!((after[&0] - before[&0] - b.area).abs() < 1e-9);
        let foot = short * angle.to_radians().cos();
        assert!((b.area - 0.5 * foot * height).abs() < 1e-9);
    }

    /// The same tip with its upper side's end pinned: the end may not move, so the cut is an
    /// edge, square from it to the lower side, 2.45 px long: under half a width. Its foot is
    /// then left between the cut and the rest of the lower side, both between regions 1 and 0,
    /// and merges into the pinned end: the lower side runs from there, and region 1 keeps a
    /// corner of 90° or more at it.
    #[test]
    fn a_low_tip_end_that_may_not_move_takes_the_cut_s_foot() {
        let (angle, short, long) = (12.0f64, 11.8, 30.0);
        let mut g = hook(angle, short, long, 35.0).unwrap();
        g.pin(4).unwrap();
        let b = cut_once(&g, &at_width(6.0));
        assert_eq!(b.graph.point(4), g.point(4));
        assert!(b.graph.is_pinned(4));
        let new = g.points().len() as u32;
        assert_eq!(b.graph.points().len(), g.points().len() + 1);
        assert_eq!(b.graph.valence(new), 0);
        assert!(b
            .graph
            .edges()
            .iter()
            .any(|e| e.ends == [4, 1] || e.ends == [1, 4]));
        for (label, sector) in sectors_at(&b.graph, 4) {
            let least = if label == 1 { 90.0 } else { 30.0 };
            assert!(sector >= least, "{label}: {sector}");
        }
        // Region 1 loses the triangle from the tip to the lower side's end under vertex 4:
        // the tip's piece and the triangle the merge swept.
        let height = short * angle.to_radians().sin();
        let (before, after) = (areas(&g), areas(&b.graph));
        assert!((b.area - 0.5 * long * height).abs() < 1e-9);
        assert!((before[&1] - after[&1] - b.area).abs() < 1e-9);
        assert!((after[&0] - before[&0] - b.area).abs() < 1e-9);
    }

    /// A sliver's tip deeper than [`TipOptions::max_depth`] widths (a 4° tip whose upper side
    /// ends 17 px out, 1.2 px over the lower one, at 5 px quads) is still cut square from that
    /// side's end: the piece is a fraction of a quad's area, and the boundary moves by less
    /// than the sliver is thick. Before, the depth bound (15 px) left the tip whole. Where the
    /// region turns up there, the end moves onto its foot; where the sliver runs on at that
    /// height, moving it would leave the sliver's new end as sharp, and the cut is an edge.
    #[test]
    fn a_long_sliver_tip_is_cut_square_when_its_piece_is_small() {
        let (angle, short, width) = (4.0f64, 17.0, 5.0);
        let options = at_width(width);
        let (foot, height) = (
            short * angle.to_radians().cos(),
            short * angle.to_radians().sin(),
        );
        assert!(foot > options.max_depth * width);
        // The region turns up at the upper side's end (vertex 4): the end moves.
        let g = hook(angle, short, 60.0, -20.0).unwrap();
        let b = cut_once(&g, &options);
        assert_eq!(b.graph.points().len(), g.points().len());
        assert!((norm(b.graph.point(4) - g.point(4)) - height).abs() < 1e-9);
        assert!((b.area - 0.5 * foot * height).abs() < 1e-9);
        assert!(b.area < width * width);
        // The farthest the boundary moved, measured from the tip's vertex to the cut.
        assert!((b.moved - foot).abs() < 1e-9);
        // The sliver runs on at that height (its upper side's end is vertex 3): an edge.
        let a = dir(angle) * short;
        let sliver = [
            Point::new(0.0, 0.0),
            Point::new(60.0, 0.0),
            Point::new(60.0, a.y),
            a,
        ];
        let g = in_frame(&sliver, -20.0).unwrap();
        let b = cut_once(&g, &options);
        let cut = b.graph.edges().last().unwrap();
        assert!(cut.ends.contains(&3));
        assert_eq!(b.graph.point(3), g.point(3));
        let [p, q] = cut.ends.map(|v| b.graph.point(v));
        assert!((norm(q - p) - height).abs() < 1e-9);
        assert!((b.area - 0.5 * foot * height).abs() < 1e-9);
        assert!((b.moved - foot).abs() < 1e-9);
    }

    /// A tongue of region 0 reaching `length` px into region 1 from their straight boundary,
    /// 1.5 px wide at its root (a sliver's end, as Imesh's sampling leaves across a street's
    /// mouth), in a frame 60 px wide: its tip is vertex 0, its root's ends vertices 1 and 2.
    fn tongue(length: f64) -> CurveGraph {
        let points = vec![
            Point::new(10.0 + length, 0.0),
            Point::new(10.0, 0.75),
            Point::new(10.0, -0.75),
            Point::new(10.0, 20.0),
            Point::new(10.0, -20.0),
            Point::new(-20.0, -20.0),
            Point::new(40.0, -20.0),
            Point::new(40.0, 20.0),
            Point::new(-20.0, 20.0),
        ];
        let edges = vec![
            e(1, 0, [1, 0]),
            e(0, 2, [1, 0]),
            e(2, 4, [1, 0]),
            e(3, 1, [1, 0]),
            e(5, 4, [0, OUTSIDE]),
            e(4, 6, [1, OUTSIDE]),
            e(6, 7, [1, OUTSIDE]),
            e(7, 3, [1, OUTSIDE]),
            e(3, 8, [0, OUTSIDE]),
            e(8, 5, [0, OUTSIDE]),
        ];
        CurveGraph::new(points, edges).unwrap()
    }

    /// A tongue 8 px long (a 10.7° tip) at 6 px quads: no cut a width wide fits, and its sides
    /// end 1.5 px apart, but its piece is under three eighths of a quad, so it is cut between
    /// their ends and region 1 takes it. Before, the tip was left whole.
    #[test]
    fn a_small_sliver_tip_is_cut_between_its_sides_ends() {
        let g = tongue(8.0);
        let options = at_width(6.0);
        let b = cut_once(&g, &options);
        let cut = b.graph.edges().last().unwrap();
        assert!(cut.ends == [1, 2] || cut.ends == [2, 1], "{:?}", cut.ends);
        assert!((b.area - 0.5 * 1.5 * 8.0).abs() < 1e-9);
        let (before, after) = (areas(&g), areas(&b.graph));
        assert!((before[&0] - after[&0] - b.area).abs() < 1e-9);
        assert!((after[&1] - before[&1] - b.area).abs() < 1e-9);
    }

    /// A sliver's end is cut between its sides' ends up to three eighths of a quad: at 6 px
    /// quads, a tongue 15 px long (11.25 px², which a quarter of a quad left whole) is cut, one
    /// 20 px long (15 px²) is not.
    #[test]
    fn a_sliver_end_up_to_three_eighths_of_a_quad_is_cut() {
        let options = at_width(6.0);
        let b = cut_once(&tongue(15.0), &options);
        assert!((b.area - 0.5 * 1.5 * 15.0).abs() < 1e-9);
        assert!(b.area > 0.25 * 36.0 && b.area <= 0.375 * 36.0);
        let g = tongue(20.0);
        assert!(blunt_sharp_tips(&g, &straight(&g), &options).is_none());
    }

    /// A lens of region 1, 60 px long and 2 px thick, its two 3.8° tips sharing its straight
    /// upper side: the first tip's cut takes that edge, and the second is cut in a second
    /// round, on the edge the first left. Before, an edge was cut at one end only and the
    /// second tip stayed.
    #[test]
    fn two_tips_sharing_an_edge_are_both_cut() {
        let lens = [
            Point::new(0.0, 0.0),
            Point::new(30.0, -2.0),
            Point::new(60.0, 0.0),
        ];
        let g = in_frame(&lens, 0.0).unwrap();
        let b = blunt_sharp_tips(&g, &straight(&g), &two_px()).unwrap();
        assert_eq!(b.tips, 2);
        assert!(b.graph.crossing().is_none());
        for tip in [0, 2] {
            assert_eq!(b.graph.valence(tip), 0, "tip {tip} is left");
        }
        for v in g.points().len() as u32..b.graph.points().len() as u32 {
            assert!(sectors_at(&b.graph, v).iter().all(|&(_, a)| a >= 30.0));
        }
        let (before, after) = (areas(&g), areas(&b.graph));
        assert!((before[&1] - after[&1] - b.area).abs() < 1e-9);
        assert!((after[&0] - before[&0] - b.area).abs() < 1e-9);
    }

    /// Region 1 from a `angle`° tip at the origin (rotated by `turn` degrees): its lower side
    /// `lower` px along the x axis to vertex 1, its upper side `upper` px long to vertex 6, the
    /// region turning away from the tip at both (outwards at 45°), then closed far off;
    /// region 0 around it, in a square frame.
    fn spike(angle: f64, upper: f64, lower: f64, turn: f64) -> CurveGraph {
        let a = dir(angle) * upper;
        let (far, top) = (upper.max(lower) + 15.0, a.y + 13.0);
        let outline = [
            Point::new(0.0, 0.0),
            Point::new(lower, 0.0),
            Point::new(lower + 3.0, -3.0),
            Point::new(far, -3.0),
            Point::new(far, top),
            Point::new(a.x - 3.0, a.y + 3.0),
            a,
        ];
        in_frame(&outline, turn).unwrap()
    }

    /// Region 1 from a `angle`° tip at the origin (rotated by `turn` degrees) whose sides run
    /// `first` px, bend by `bend` degrees (the lower side down, the upper up), run `second`
    /// px more and then turn away from the tip; region 0 around it, in a square frame. `None`
    /// when that outline crosses itself.
    fn staircase(
        angle: f64,
        first: [f64; 2],
        bend: [f64; 2],
        second: [f64; 2],
        turn: f64,
    ) -> Option<CurveGraph> {
        let a1 = dir(0.0) * first[0];
        let a2 = a1 + dir(-bend[0]) * second[0];
        let b1 = dir(angle) * first[1];
        let b2 = b1 + dir(angle + bend[1]) * second[1];
        let a3 = a2 + Point::new(3.0, -3.0);
        let b3 = b2 + Point::new(-3.0, 3.0);
        let far = a3.x.max(b2.x).max(a2.x) + 15.0;
        let top = b3.y.max(b2.y) + 13.0;
        let outline = [
            Point::new(0.0, 0.0),
            a1,
            a2,
            a3,
            Point::new(far, a3.y),
            Point::new(far, top),
            Point::new(b3.x, top),
            b3,
            b2,
            b1,
        ];
        in_frame(&outline, turn)
    }

    /// A 20° spike whose sides bend outwards 1.5 px out and run 4 px on, where the region
    /// turns away: too narrow at the bends for any cut one width wide, it is cut between the
    /// sides' second vertices (2.6 px apart), the whole staircase given to region 0.
    #[test]
    fn a_staircase_tip_is_cut_at_its_second_vertices() {
        let g = staircase(20.0, [1.5, 1.5], [5.0, 5.0], [4.0, 4.0], 30.0).unwrap();
        let b = blunt_sharp_tips(&g, &straight(&g), &two_px()).unwrap();
        for v in [0, 1, 9] {
            assert_eq!(b.graph.valence(v), 0, "{v}");
        }
        assert_cut_between(&g, &b, [2, 8]);
    }

    /// The one cut of `b` joins the vertices `ends` of `g` (no new vertex), every corner there
    /// is 30° or more, and the area it cut off went from region 1 to region 0.
    fn assert_cut_between(g: &CurveGraph, b: &Blunted, ends: [u32; 2]) {
        assert_eq!(b.tips, 1);
        assert!(b.graph.crossing().is_none());
        assert_eq!(b.graph.points().len(), g.points().len());
        let cut = b.graph.edges().last().unwrap();
        assert!(
            cut.ends == ends || cut.ends == [ends[1], ends[0]],
            "{:?}",
            cut.ends
        );
        for v in cut.ends {
            for (label, angle) in sectors_at(&b.graph, v) {
                assert!(angle >= 30.0, "{label} at {v}: {angle}");
            }
        }
        let (before, after) = (areas(g), areas(&b.graph));
        assert!((before[&1] - after[&1] - b.area).abs() < 1e-9);
        assert!((after[&0] - before[&0] - b.area).abs() < 1e-9);
    }

    /// A 25° spike both of whose sides end 5 px out (2.5 widths), where the region turns away:
    /// too short for a cut across both or from either end, it is cut between their ends, 2.2
    /// px apart, and the triangle given to region 0.
    #[test]
    fn a_tip_with_two_short_sides_is_cut_between_their_ends() {
        let g = spike(25.0, 5.0, 5.0, -70.0);
        let b = blunt_sharp_tips(&g, &straight(&g), &two_px()).unwrap();
        assert_eq!(b.graph.valence(0), 0);
        assert_cut_between(&g, &b, [1, 6]);
        assert!((b.area - 0.5 * 25.0 * 25f64.to_radians().sin()).abs() < 1e-9);
    }

    /// A piece whose cut runs back along the side it starts from (collinear, overlapping it)
    /// is refused; the same cut meeting a side end to end on one line is not.
    #[test]
    fn a_cut_running_back_along_a_side_is_refused() {
        let points = vec![
            Point::new(0.0, 0.0),
            Point::new(4.0, 0.0),
            Point::new(4.0, 4.0),
        ];
        let e = |a, b| GraphEdge {
            ends: [a, b],
            labels: [1, 0],
        };
        let g = CurveGraph::new(points.clone(), vec![e(0, 1), e(1, 2)]).unwrap();
        let piece = |last: Point| [points[0], points[1], points[2], last];
        assert!(!sound_piece(
            &g,
            &[0, 1, 2],
            &piece(Point::new(4.0, 2.0)),
            [2, 3]
        ));
        assert!(sound_piece(
            &g,
            &[0, 1, 2],
            &piece(Point::new(2.0, 2.0)),
            [2, 3]
        ));
    }

    /// Nothing to cut: a sector of 40°, and a 20° tip whose sides are too short.
    #[test]
    fn wide_or_short_tips_are_left() {
        let g = wedge(40.0, 30.0, 0.0, false);
        assert!(blunt_sharp_tips(&g, &straight(&g), &TipOptions::default()).is_none());
        let g = wedge(20.0, 4.0, 0.0, false);
        assert!(blunt_sharp_tips(&g, &straight(&g), &TipOptions::default()).is_none());
    }

    /// `b` is `g` (region 1 in region 0) with one tip cut soundly: planar, consistent faces,
    /// the area (to within `1e-9 · scale`) moved only from region 1 to region 0, and every
    /// corner at the cut's ends 30° or more, region 1's at a new vertex 90° or more (unless a
    /// cut's end merged into a stub's other end).
    fn one_sound_cut(g: &CurveGraph, b: &Blunted, scale: f64) -> Result<(), TestCaseError> {
        prop_assert!(b.graph.crossing().is_none());
        let (before, after) = (areas(g), areas(&b.graph));
        prop_assert!(b.area > 0.0);
        prop_assert!((before[&1] - after[&1] - b.area).abs() < 1e-9 * scale);
        prop_assert!((after[&0] - before[&0] - b.area).abs() < 1e-9 * scale);
        // A cut made by moving a side's end onto the other side: every corner there 30° or
        // more.
        let moved: Vec<u32> = (0..g.points().len() as u32)
            .filter(|&v| b.graph.valence(v) > 0 && b.graph.point(v) != g.point(v))
            .collect();
        prop_assert!(moved.len() <= 1);
        if let [v] = moved[..] {
            prop_assert_eq!(b.graph.points().len(), g.points().len());
            for (label, a) in sectors_at(&b.graph, v) {
                prop_assert!(a >= 30.0 - 1e-6, "{} at {}: {}", label, v, a);
            }
            return Ok(());
        }
        // Where a cut's end merged into the other end of a stub (a new vertex left unused),
        // the region's corners there are 30° or more rather than 90°.
        let merged = (g.points().len() as u32..b.graph.points().len() as u32)
            .any(|v| b.graph.valence(v) == 0);
        let cut = b.graph.edges().last().unwrap();
        for v in cut.ends {
            let new = v as usize >= g.points().len();
            for (label, a) in sectors_at(&b.graph, v) {
                let least = if label == 1 && new && !merged {
                    90.0
                } else {
                    30.0
                };
                prop_assert!(a >= least - 1e-6, "{} at {}: {}", label, v, a);
            }
        }
        Ok(())
    }

    /// Aloe's poorest junction (its G' about pixel (660, 1036), shifted): region 1's 3° sliver
    /// runs into the junction B of regions 0, 1 and 2, and its side to region 2 turns back at
    /// J in a 9° spike of region 2. The sliver is cut at its deepest, 6 px (three 2 px widths)
    /// from B, where it is 0.34 px wide; the spike, in the next round, between the cut's end
    /// D and its other side's end E. D is then left between the two cuts, both edges between
    /// regions 1 and 2, one of them 0.34 px long: it goes, and E's cut runs to the cut's other
    /// end, where region 1 keeps a corner of 90° or more.
    #[test]
    fn a_cut_end_left_between_two_cuts_is_merged() {
        let p = |x, y| Point::new(x, y);
        let points = vec![
            p(0.0, 0.0),    // B
            p(-7.0, -8.5),  // A
            p(-6.0, -6.5),  // J
            p(-4.0, -3.5),  // E
            p(-30.0, 1.5),  // W
            p(-30.0, -8.5), // V
            p(5.0, 12.0),   // R
            p(-30.0, 12.0), // S
        ];
        let edges = vec![
            e(1, 0, [1, 0]),
            e(0, 2, [1, 2]),
            e(2, 3, [1, 2]),
            e(3, 4, [1, 2]),
            e(4, 5, [1, 0]),
            e(5, 1, [1, 0]),
            e(0, 6, [2, 0]),
            e(6, 7, [2, 0]),
            e(7, 4, [2, 0]),
        ];
        let g = CurveGraph::new(points, edges).unwrap();
        let b = blunt_sharp_tips(&g, &straight(&g), &two_px()).unwrap();
        assert_eq!(b.tips, 2);
        assert!(b.graph.crossing().is_none());
        // D, the first cut's end on B–J, is gone; N, its end on A–B, holds the junction.
        let (d, n) = (g.points().len() as u32, g.points().len() as u32 + 1);
        assert_eq!(b.graph.valence(d), 0);
        assert_eq!(b.graph.valence(n), 3);
        assert!((norm(b.graph.point(n) - g.point(0)) - 6.0).abs() < 1e-9);
        // No edge a fraction of a quad long (the stub was 0.34 px), and no sharp corner at N.
        for e in b.graph.edges() {
            let [a, c] = e.ends.map(|v| b.graph.point(v));
            assert!(norm(c - a) > SNAP_CUT * 2.0, "{e:?}");
        }
        for (label, sector) in sectors_at(&b.graph, n) {
            assert!(sector >= 30.0, "{label}: {sector}");
            if label == 1 {
                assert!(sector >= 90.0, "{sector}");
            }
        }
        // Area moves between regions 1 and 2 only.
        let (before, after) = (areas(&g), areas(&b.graph));
        assert!((after[&0] - before[&0]).abs() < 1e-9);
        assert!((before[&1] - after[&1] - (after[&2] - before[&2])).abs() < 1e-9);
        assert!((before[&1] - after[&1]).abs() <= b.area);
    }

    /// A cut's end left between a short edge and a longer one of the same boundary merges into
    /// the short edge's other end where that leaves no sharp corner (another boundary leaves
    /// it at 90°): a stub of 0.3 px and of 1.2 px at 2 px quads, under three quarters of a
    /// quad side; not one of 1.6 px, nor where the corner would be sharp (at 35°, against the
    /// longer edge's 36.5°).
    #[test]
    fn a_stub_merges_unless_it_would_leave_a_sharp_corner() {
        let cases = [
            (0.3, 90.0f64, true),
            (1.2, 90.0, true),
            (1.6, 90.0, false),
            (0.3, 35.0, false),
        ];
        for (stub, angle, merged) in cases {
            let other = dir(angle) * 10.0;
            let points = vec![
                Point::new(0.0, 0.0),
                Point::new(stub, 0.0),
                Point::new(3.0, 2.0),
                Point::new(-10.0, 0.0),
                other,
            ];
            let edges = vec![
                e(3, 0, [1, 0]),
                e(0, 1, [1, 0]),
                e(1, 2, [1, 0]),
                e(4, 0, [2, 1]),
            ];
            let g = CurveGraph::new(points, edges).unwrap();
            let b = Blunted {
                curves: straight(&g),
                graph: g.clone(),
                tips: 1,
                area: 0.0,
                moved: 0.0,
            };
            let m = merge_stubs(b, 1, &two_px());
            assert_eq!(
                m.graph.valence(1),
                usize::from(!merged) * 2,
                "{stub} {angle}"
            );
            if merged {
                assert!(m.graph.edges().iter().any(|e| e.ends == [0, 2]));
                let [a, c] = [0, 2].map(|v| g.point(v));
                assert!((m.area - 0.5 * cross(g.point(1) - a, c - a).abs()).abs() < 1e-12);
                assert!((m.moved - stub).abs() < 1e-12);
            } else {
                assert_eq!(m.graph.edges(), g.edges());
            }
        }
    }

    proptest! {
        /// Any wedge of 3–29°, any length and turn, with or without a junction: the graph stays
        /// planar with consistent faces, the area moves only from the wedge's region to the
        /// receiver, and the wedge's corners at the cut are at least 90° (30° where the cut's
        /// ends merged).
        #[test]
        fn cut_tips_keep_the_graph_sound(
            angle in 3.0f64..29.0,
            length in 5.0f64..60.0,
            turn in -180.0f64..180.0,
            junction: bool,
            width in 0.5f64..4.0,
        ) {
            let g = wedge(angle, length, turn, junction);
            let options = TipOptions { width, reach: width, ..TipOptions::default() };
            if let Some(b) = blunt_sharp_tips(&g, &straight(&g), &options) {
                prop_assert!(b.graph.crossing().is_none());
                let (before, after) = (areas(&g), areas(&b.graph));
                let scale = length * length;
                prop_assert!((before[&1] - after[&1] - b.area).abs() < 1e-9 * scale);
                prop_assert!(b.area > 0.0);
                // The cut's new vertices: region 1 keeps 90° or more at each, every region
                // 30° or more; where the cut, narrower than [`MERGED_STUB`], merged one into the
                // other (the lower side then runs from the upper side's cut), 30° or more.
                let made = g.points().len() as u32..b.graph.points().len() as u32;
                let merged = made.clone().any(|v| b.graph.valence(v) == 0);
                for v in made.filter(|&v| b.graph.valence(v) > 0) {
                    for (label, a) in sectors_at(&b.graph, v) {
                        let least = if label == 1 && !merged { 90.0 } else { 30.0 };
                        prop_assert!(a >= least - 1e-6, "{} at {}: {}", label, v, a);
                    }
                }
            }
        }

        /// Any tip of 3–29° whose one side ends early, where the region turns away, or both
        /// (a spike): the graph stays planar with consistent faces, the area moves only from
        /// the region to its neighbour, and every corner at the cut's ends is 30° or more (the
        /// region's at a new vertex 90° or more).
        #[test]
        fn tips_cut_from_a_short_side_keep_the_graph_sound(
            angle in 3.0f64..29.0,
            short in 0.5f64..12.0,
            long in 0.5f64..60.0,
            turn in -180.0f64..180.0,
            width in 0.5f64..4.0,
            both_short: bool,
        ) {
            let g = if both_short {
                Some(spike(angle, short, long.min(12.0), turn))
            } else {
                hook(angle, short, long.max(10.0), turn)
            };
            prop_assume!(g.is_some());
            let g = g.unwrap();
            let options = TipOptions { width, reach: width, ..TipOptions::default() };
            if let Some(b) = blunt_sharp_tips(&g, &straight(&g), &options) {
                one_sound_cut(&g, &b, long * long)?;
            }
        }

        /// A tip whose sides bend and run on before the region turns away (a staircase
        /// spike, cut as far as the second vertex of a side): the same.
        #[test]
        fn tips_cut_two_vertices_out_keep_the_graph_sound(
            angle in 3.0f64..29.0,
            first in (0.5f64..6.0, 0.5f64..6.0),
            bend in (-8.0f64..8.0, -8.0f64..8.0),
            second in (0.5f64..6.0, 0.5f64..6.0),
            turn in -180.0f64..180.0,
            width in 0.5f64..4.0,
        ) {
            let g = staircase(angle, [first.0, first.1], [bend.0, bend.1], [second.0, second.1], turn);
            prop_assume!(g.is_some());
            let g = g.unwrap();
            let options = TipOptions { width, reach: width, ..TipOptions::default() };
            if let Some(b) = blunt_sharp_tips(&g, &straight(&g), &options) {
                one_sound_cut(&g, &b, 1e3)?;
            }
        }
    }
}
