//! Boundary adaptation: the patches' boundary curves on G' edges take the fitted Béziers
//! (DESIGN.md §2, step 9; the paper's section V-C).

use imesh_curves::{CubicBezier, CurveGraph};
use imesh_geom::{Point, VertexId};
use rayon::prelude::*;

use crate::dt::{RegionTriangulation, NONE};
use crate::mesh::{scaled_jacobian, valid_above, QuadMesh};
use crate::pairing::ElementMesh;
use crate::patch::{relaxed_inner, side_slots, ControlNet};

/// What boundary adaptation did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct AdaptReport {
    /// M edges on G' edges, given their fitted sub-curve.
    pub adapted_edges: usize,
    /// Patches whose inner control points were relaxed because a quad inside had turned invalid
    /// or poor.
    pub relaxed_patches: usize,
    /// G' edges with a piece pulled back towards their straight segment (its vertices are then
    /// between the chord and the curve) because relaxing the patches was not enough.
    pub damped_curves: usize,
    /// Quads still invalid at the end (0 unless the input defeats both remedies).
    pub invalid_left: usize,
}

/// The curve piece an adapted M edge follows, in the edge's direction, and how much of its
/// G' edge's curve is kept (1 = the curve, 0 = the straight edge).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EdgeCurve {
    /// The M edge.
    pub edge: u32,
    /// The G' edge it lies on.
    pub graph_edge: u32,
    /// The piece's parameters on the G' edge's curve, in the M edge's direction.
    pub parameters: [f64; 2],
    /// The exact sub-curve of the G' edge's fitted curve.
    pub curve: CubicBezier,
    /// The straight piece's ends (the DT' vertices, on the straight G' edge).
    pub chord: [Point; 2],
    /// The share of the curve's bulge kept at the edge's origin and destination (1 = the
    /// curve, 0 = the straight edge); the inner control points take the shares a third and two
    /// thirds of the way. Damping lowers them near the quads the curve would spoil, not along
    /// the whole G' edge.
    pub weights: [f64; 2],
}

impl EdgeCurve {
    /// The piece as the mesh has it: the curve piece blended with the straight piece between
    /// the same DT' vertices by [`EdgeCurve::weights`], from the M edge's origin (parameter 0)
    /// to its destination (1). The edge's template points lie on it.
    ///
    /// ```
    /// use imesh_curves::CubicBezier;
    /// use imesh_geom::Point;
    /// use imesh_quad::EdgeCurve;
    /// let (a, b) = (Point::new(0.0, 0.0), Point::new(3.0, 0.0));
    /// let curve = CubicBezier::new([a, Point::new(1.0, 3.0), Point::new(2.0, 3.0), b]);
    /// let ec = EdgeCurve { edge: 0, graph_edge: 0, parameters: [0.0, 1.0], curve, chord: [a, b], weights: [0.5, 0.5] };
    /// // Half the bulge: the curve's midpoint is 2.25 above the chord, the path's 1.125.
    /// assert_eq!(ec.path().eval(0.5), Point::new(1.5, 1.125));
    /// // Damped at the destination only: the bulge fades out towards it.
    /// let fading = EdgeCurve { weights: [1.0, 0.0], ..ec };
    /// assert_eq!(fading.path().control[1], Point::new(1.0, 2.0));
    /// assert_eq!(fading.path().control[2], Point::new(2.0, 1.0));
    /// ```
    pub fn path(&self) -> CubicBezier {
        CubicBezier::new(blend(self))
    }
}

/// A quad that adaptation leaves with a scaled Jacobian below both this and its straight value
/// is repaired like an inverted one: the curve costs the element more than it is worth. The
/// same bar as pairing's corners (the sine of 30°): adaptation spoils no corner below what
/// pairing allowed, where the optimiser could not mend it (a corner at a G' vertex turns with
/// the curves' tangents there, and nothing moves them). Measured with the defaults on nine
/// fixtures against 0.35, pairing's and the repair's bars at 0.5 in both: worst scaled
/// Jacobian mean 0.363 → 0.424, mean shape-and-size 0.8353 → 0.8386, for 20–40 % more
/// damped curves and a label agreement 0.02–0.5 points lower (brick 97.9 → 97.4 %).
pub const POOR_SCALED_JACOBIAN: f64 = 0.5;

/// The floors adaptation holds the quads of the elements it touches to: a scaled Jacobian of
/// [`POOR_SCALED_JACOBIAN`], or the quad's straight one where that is lower (a quad of a
/// straight template is valid, but may be poorer than the bar). The straight value is needed
/// only for a quad under the bar, so it is computed from the straight template points
/// (`straight`, the vertices before adaptation) only then: most adapted quads clear the bar,
/// and computing it for every touched quad up front cost some 20–30 ms of CPU time on the
/// benchmark's 103 662 triangles of grass (8–11 ms of its adaptation on two threads).
struct Floors<'a> {
    straight: &'a [Point],
}

impl Floors<'_> {
    /// Whether quad `x` of `q`, with corners `p`, is valid and above its floor.
    fn passes(&self, q: &QuadMesh, x: usize, p: &[Point; 4]) -> bool {
        above_floor(p, || q.quads[x].map(|v| self.straight[v as usize]))
    }
}

/// Whether the quad `p` is valid and above its floor, the scaled Jacobian
/// [`POOR_SCALED_JACOBIAN`] or that of its straight corners (`straight`, asked for only if `p`
/// is under the bar) where lower, less 10⁻⁹: the floor is at most the bar, so a quad above the
/// bar is above its floor.
fn above_floor(p: &[Point; 4], straight: impl FnOnce() -> [Point; 4]) -> bool {
    const MARGIN: f64 = 1e-9;
    valid_above(p, POOR_SCALED_JACOBIAN - MARGIN)
        || valid_above(
            p,
            POOR_SCALED_JACOBIAN.min(scaled_jacobian(&straight())) - MARGIN,
        )
}

/// Moves the control points of every M edge on a G' edge onto the exact piece of that edge's
/// fitted curve (`curves[k]` for G' edge `k`), re-evaluates Q, and repairs quads that turned
/// invalid, or poor (a scaled Jacobian below both [`POOR_SCALED_JACOBIAN`] and the quad's
/// straight value): first the patch's inner control points are relaxed (Coons), then, if
/// needed, the bulge the curves keep is halved where they shape the element (at the ends of
/// its curved sides and at its corners on G' edges), as many times as the element needs
/// (tried on the element alone, its inner points relaxed), down to the straight edge, whose
/// templates are always valid and never poor; neighbouring Steiner vertices of a G' edge keep
/// shares at most `SHARE_STEP` (a quarter) apart, so the damping fades in along the curve. After
/// [`LOCAL_ROUNDS`], an element still poor has its G' edges straightened whole. Damping the
/// pieces near the element rather than the whole G' edge keeps the rest of the curve, and the
/// turn it was given at a sharp corner: measured against whole-edge halving with the defaults,
/// label agreement up to +0.34 points on nine fixtures (brick), none lower; the worst scaled Jacobian at a
/// corner of astronaut's 0.341 → 0.424, mean of nine at 3 px 0.365 → 0.398, for a mean
/// shape-and-size 0.0008 lower. The straight G' edge is within the simplification tolerance of
/// its chain and the fitted curve closer; a damped piece lies between the two.
pub fn adapt(
    dt: &RegionTriangulation,
    g: &CurveGraph,
    curves: &[CubicBezier],
    m: &ElementMesh,
    net: &mut ControlNet,
    q: &mut QuadMesh,
) -> (AdaptReport, Vec<EdgeCurve>) {
    let straight = q.vertices.clone();
    adapt_within(dt, g, curves, m, net, q, &straight, LOCAL_ROUNDS)
}

/// [`adapt`] given the straight template points (`straight`: `q`'s vertices as
/// [`QuadMesh::build`] placed them, which a caller may keep anyway), with the damping near the
/// poor elements limited to `local_rounds` rounds (the default is [`LOCAL_ROUNDS`]); from then
/// on a poor element's G' edges are straightened whole. With 0, every G' edge a poor element
/// needs damped is straightened at once: the bluntest repair, for comparison.
#[allow(clippy::too_many_arguments)]
pub fn adapt_within(
    dt: &RegionTriangulation,
    g: &CurveGraph,
    curves: &[CubicBezier],
    m: &ElementMesh,
    net: &mut ControlNet,
    q: &mut QuadMesh,
    straight: &[Point],
    local_rounds: u32,
) -> (AdaptReport, Vec<EdgeCurve>) {
    let t = &dt.triangulation;
    let mut report = AdaptReport::default();
    let mut curve_of_edge = vec![NONE; m.edges.len()];
    let mut pieces: Vec<Vec<u32>> = vec![Vec::new(); g.edges().len()];
    let parameter = curve_parameters(dt, g, curves);
    // The G' edge a Steiner vertex lies on: its move onto the curve affects every element
    // around it, not only those with a side on the curve.
    let mut curve_of_vertex = vec![NONE; t.num_vertices()];
    let mut adapted: Vec<EdgeCurve> = m
        .edges
        .par_iter()
        .enumerate()
        .filter_map(|(e, &h)| {
            let (k, _) = dt.graph_edge(g, h)?;
            let curve = curves.get(k as usize)?;
            let (u0, u1) = (
                parameter[t.origin(h).index()],
                parameter[t.destination(h).index()],
            );
            let (u0, u1) = if dt.graph_vertex[t.origin(h).index()] != NONE
                || dt.graph_vertex[t.destination(h).index()] != NONE
            {
                // A G' vertex: its parameter is 0 or 1 according to the end it is.
                let ends = g.edges()[k as usize].ends;
                let at = |v: VertexId, u: f64| match dt.graph_vertex[v.index()] {
                    x if x == ends[0] => 0.0,
                    x if x == ends[1] => 1.0,
                    _ => u,
                };
                (at(t.origin(h), u0), at(t.destination(h), u1))
            } else {
                (u0, u1)
            };
            (u0 != u1).then(|| EdgeCurve {
                edge: e as u32,
                graph_edge: k,
                parameters: [u0, u1],
                curve: piece_of(curve, u0, u1),
                chord: [t.point(t.origin(h)), t.point(t.destination(h))],
                weights: [1.0, 1.0],
            })
        })
        .collect();
    for (p, ec) in adapted.iter().enumerate() {
        let (e, k) = (ec.edge as usize, ec.graph_edge);
        curve_of_edge[e] = p as u32;
        pieces[k as usize].push(p as u32);
        let h = m.edges[e];
        for v in [t.origin(h), t.destination(h)] {
            if dt.graph_vertex[v.index()] == NONE {
                curve_of_vertex[v.index()] = k;
            }
        }
    }
    for ec in &adapted {
        place(dt, m, net, ec);
    }
    report.adapted_edges = adapted.len();
    // Only the elements with a moved corner or a curved side change; their quads' straight
    // scaled Jacobians are the bar adaptation must not push them under.
    let touched: Vec<usize> = (0..m.elements.len())
        .into_par_iter()
        .filter(|&index| {
            let moved = m.elements[index]
                .corners()
                .iter()
                .any(|&v| curve_of_vertex[v as usize] != NONE);
            moved
                || (0..m.side_count(index))
                    .any(|side| curve_of_edge[m.side_edge(index, side).0 as usize] != NONE)
        })
        .collect();
    let floors = Floors { straight };
    // Per round, which M edges it has evaluated.
    let mut edge_stamp = vec![0u32; m.edges.len()];
    let mut edges = Vec::new();
    let mut stamp = 1;
    evaluate(q, m, net, &touched, &mut edge_stamp, stamp);
    let needs_repair = |q: &QuadMesh, elements: &[usize]| -> Vec<usize> {
        elements
            .par_iter()
            .copied()
            .filter(|&index| {
                q.element_quads(index)
                    .any(|x| !floors.passes(q, x, &q.quads[x].map(|v| q.vertices[v as usize])))
            })
            .collect()
    };
    let mut bad = needs_repair(q, &touched);
    let mut relaxed = vec![false; m.elements.len()];
    let mut damping = Damping::new(dt, m, &adapted, &pieces, !bad.is_empty());
    for round in 1..=local_rounds + STRAIGHTENING_ROUNDS {
        if bad.is_empty() {
            break;
        }
        // The round's elements: the first round's bad ones were evaluated above; later rounds'
        // had a side or a corner moved by a damped piece, and their inner points follow from
        // the relaxation below.
        if round > 1 {
            stamp += 1;
            sides(m, &bad, &mut edge_stamp, stamp, &mut edges);
            q.evaluate_edges(net, &mut edges);
        }
        q.relax_insides(m, net, &bad);
        for &index in &bad {
            relaxed[index] = true;
        }
        let whole = round > local_rounds;
        let poor = needs_repair(q, &bad);
        let lookup = CurveLookup {
            curve_of_edge: &curve_of_edge,
            curve_of_vertex: &curve_of_vertex,
        };
        // How far each poor element's own pieces must be damped for its quads to pass, the
        // elements around left as they are: found at once rather than one halving a round,
        // each of which moved every element around the pieces again (measured on the grass
        // benchmark's 103 662 triangles: 11 rounds → 4).
        let halvings: Vec<u32> = if whole {
            vec![0; poor.len()]
        } else {
            let (q, net, adapted) = (&*q, &*net, &adapted[..]);
            poor.par_iter()
                .map(|&index| damping.halvings_needed(m, net, q, adapted, lookup, index, &floors))
                .collect()
        };
        for (index, halvings) in poor.into_iter().zip(halvings) {
            damping.mend(m, &adapted, lookup, index, round, whole, halvings);
        }
        damping.apply(dt, m, net, &mut adapted, &pieces, round);
        // Every element a damped curve moved (its sides, or a corner) is relaxed and evaluated
        // again at the start of the next round, before any check; in element order, which is
        // the order of their control points and template vertices in memory.
        bad.clear();
        bad.extend((0..m.elements.len()).filter(|&el| damping.element_round[el] == round));
    }
    // Unless the rounds ran out first.
    evaluate(q, m, net, &bad, &mut edge_stamp, stamp + 1);
    report.relaxed_patches = relaxed.iter().filter(|&&r| r).count();
    report.damped_curves = damping.damped_curves(g.edges().len(), &adapted);
    // Only the touched elements' quads moved: the rest are straight templates of strictly
    // convex elements, valid as built.
    report.invalid_left = touched
        .par_iter()
        .flat_map_iter(|&index| q.element_quads(index))
        .filter(|&x| !q.is_valid(x))
        .count();
    (report, adapted)
}

/// Re-evaluates the vertices of `elements` from their patches: each M edge they have once
/// (marked with `stamp` in `edge_stamp`), then their inner points.
fn evaluate(
    q: &mut QuadMesh,
    m: &ElementMesh,
    net: &ControlNet,
    elements: &[usize],
    edge_stamp: &mut [u32],
    stamp: u32,
) {
    let mut edges = Vec::new();
    sides(m, elements, edge_stamp, stamp, &mut edges);
    q.evaluate_edges(net, &mut edges);
    q.evaluate_insides(m, net, elements);
}

/// The M edges on the sides of `elements`, each once (marked with `stamp` in `edge_stamp`),
/// into `edges` (in increasing order when they are many).
fn sides(
    m: &ElementMesh,
    elements: &[usize],
    edge_stamp: &mut [u32],
    stamp: u32,
    edges: &mut Vec<u32>,
) {
    edges.clear();
    for &index in elements {
        for side in 0..m.side_count(index) {
            let e = m.side_edge(index, side).0;
            if std::mem::replace(&mut edge_stamp[e as usize], stamp) != stamp {
                edges.push(e);
            }
        }
    }
    // The evaluation wants them in order: when they are many, a pass over the stamps lists
    // them so faster than sorting them.
    if edges.len() > edge_stamp.len() / 16 {
        edges.clear();
        edges.extend((0..edge_stamp.len() as u32).filter(|&e| edge_stamp[e as usize] == stamp));
    }
}

/// The curve parameter of every Steiner vertex on a G' edge: that of its closest point on the
/// edge's fitted curve, so that adaptation moves it across the curve rather than along it (the
/// curve's parameter is not arc length, and the straight edge's parameter can be pixels away
/// along a long curve). Where the projections of a G' edge's vertices would not run in order,
/// that edge keeps the straight parameters.
fn curve_parameters(dt: &RegionTriangulation, g: &CurveGraph, curves: &[CubicBezier]) -> Vec<f64> {
    let t = &dt.triangulation;
    // Per segment, its vertices and their parameters; a G' vertex ends several segments, and
    // takes the last one's (adaptation reads a G' vertex's parameter from its end, not here).
    let per_segment: Vec<Vec<(VertexId, f64)>> = (0..t.num_segments())
        .into_par_iter()
        .map(|s| {
            let Some(&k) = dt.segment_edge.get(s) else {
                return Vec::new();
            };
            let Some(curve) = curves.get(k as usize) else {
                return Vec::new();
            };
            let chain = dt.segment_pieces(imesh_geom::SegmentId(s as u32));
            let straight: Vec<f64> = chain.iter().map(|&v| dt.edge_parameter(g, k, v)).collect();
            let n = chain.len();
            // The ends are the curve's ends, whichever way the segment was inserted; only the
            // Steiner vertices between them are projected.
            let projected: Vec<f64> = chain
                .iter()
                .zip(&straight)
                .enumerate()
                .map(|(i, (&v, &u))| {
                    if i == 0 || i + 1 == n {
                        u.round()
                    } else {
                        curve.closest_parameter(t.point(v), u)
                    }
                })
                .collect();
            let increasing = straight.first() <= straight.last();
            let ordered =
                projected
                    .windows(2)
                    .all(|w| if increasing { w[0] < w[1] } else { w[0] > w[1] });
            let chosen = if ordered { projected } else { straight };
            chain.into_iter().zip(chosen).collect()
        })
        .collect();
    let mut parameter = vec![0.0; t.num_vertices()];
    for (v, u) in per_segment.into_iter().flatten() {
        parameter[v.index()] = u;
    }
    parameter
}

/// The piece of `curve` between parameters `u0` and `u1`, running from `u0` to `u1`.
fn piece_of(curve: &CubicBezier, u0: f64, u1: f64) -> CubicBezier {
    if u0 < u1 {
        curve.sub_curve(u0, u1)
    } else {
        curve.sub_curve(u1, u0).reversed()
    }
}

/// Sets the control points of an adapted M edge: its curve piece blended with the straight
/// piece between the same parameters of the G' edge, by the edge's weight.
fn place(dt: &RegionTriangulation, m: &ElementMesh, net: &mut ControlNet, ec: &EdgeCurve) {
    let t = &dt.triangulation;
    let h = m.edges[ec.edge as usize];
    let (a, b) = (t.origin(h), t.destination(h));
    let blended = blend(ec);
    let inner = net.edge_inner(ec.edge);
    net.points[a.index()] = blended[0];
    net.points[b.index()] = blended[3];
    net.points[inner[0] as usize] = blended[1];
    net.points[inner[1] as usize] = blended[2];
}

/// The control points of `ec` as the mesh has them.
fn blend(ec: &EdgeCurve) -> [Point; 4] {
    let c = ec.curve.control;
    if ec.weights == [1.0, 1.0] {
        return c;
    }
    // The straight piece between the DT' vertices: the same for both pieces at a Steiner
    // vertex, as are the curve point and the weight there, so the blended corner is shared
    // exactly.
    let chord = ec.chord;
    let [w0, w1] = ec.weights;
    let straight = CubicBezier::segment(chord[0], chord[1]).control;
    [0, 1, 2, 3].map(|i| {
        let w = w0 + (w1 - w0) * i as f64 / 3.0;
        straight[i] + (c[i] - straight[i]) * w
    })
}

/// Rounds in which a poor element's pieces are damped where they meet it (its sides' ends and
/// its corners on G' edges); after them, its G' edges are straightened whole, for at most
/// `STRAIGHTENING_ROUNDS` (ten) more: an element whose sides are straight is a straight template,
/// never poor. A round halves a piece as many times as its poor elements need, at most five
/// (then it is straight); later rounds mend what the damping spreading along a curve spoils
/// in the elements beside it (the fixtures need 1–3 rounds at the default size, 3 px and
/// graded; one halving a round, they needed 6–11).
pub const LOCAL_ROUNDS: u32 = 30;

/// Largest difference between the shares of the bulge kept at two neighbouring Steiner vertices
/// of a G' edge.
const SHARE_STEP: f64 = 0.25;

/// Rounds of straightening whole G' edges after the local ones.
const STRAIGHTENING_ROUNDS: u32 = 10;

/// The next damping of a share of the bulge: half of it, down to a sixteenth, then none.
fn halved(w: f64) -> f64 {
    if w > 1.0 / 16.0 {
        w / 2.0
    } else {
        0.0
    }
}

/// A share halved `times` times ([`halved`]).
fn halved_times(w: f64, times: u32) -> f64 {
    (0..times).fold(w, |w, _| halved(w))
}

/// Most halvings before any share is none (1 → ½ → ¼ → ⅛ → 1/16 → 0).
const MAX_HALVINGS: u32 = 5;

/// Asks `halvings` of a share for this round (its last round `stamp`, the halvings asked of it
/// `asked`: the most any element asks); true the first time this round.
fn ask(stamp: &mut u32, asked: &mut u32, round: u32, halvings: u32) -> bool {
    let first = std::mem::replace(stamp, round) != round;
    *asked = if first {
        halvings
    } else {
        (*asked).max(halvings)
    };
    first
}

/// Where the curves are: per M edge, its adapted piece (an index into the pieces), and per
/// DT' vertex, the G' edge it is a Steiner vertex of ([`NONE`] for neither).
#[derive(Clone, Copy)]
struct CurveLookup<'a> {
    curve_of_edge: &'a [u32],
    curve_of_vertex: &'a [u32],
}

/// The damping of adapted pieces near the elements they spoil. The share of the bulge kept is
/// per end of a piece: at a Steiner vertex, one share for both pieces there (the vertex is
/// theirs to share); at a G' vertex, the piece's own (the vertex stays where it is, the share
/// turns the curve's tangent there towards the chord).
struct Damping {
    /// Per piece, its end vertices (DT' ids), in the M edge's direction.
    ends: Vec<[u32; 2]>,
    /// Per G' edge, its pieces in order along it.
    chains: Vec<Vec<u32>>,
    /// Per DT' vertex: the share a Steiner vertex on a G' edge keeps...
    at_vertex: Vec<f64>,
    /// ... the two pieces ending at a Steiner vertex ...
    pieces_at: Vec<[u32; 2]>,
    /// ... and the round it was last damped in.
    vertex_round: Vec<u32>,
    /// Per piece and end: the round it was last damped in (G' vertex ends).
    end_round: Vec<[u32; 2]>,
    /// The halvings this round asks of each listed Steiner vertex and G' vertex end: the most
    /// any poor element around it needs.
    vertex_halvings: Vec<u32>,
    end_halvings: Vec<[u32; 2]>,
    /// Per G' edge: straightened whole.
    straight: Vec<bool>,
    /// Per element: the last round that moved it.
    element_round: Vec<u32>,
    /// The round's Steiner vertices, their G' edges, the G' vertex ends and the G' edges to
    /// straighten.
    vertices: Vec<u32>,
    smoothed: Vec<u32>,
    graph_ends: Vec<(u32, usize)>,
    curves: Vec<u32>,
}

impl Damping {
    /// Empty (and free) unless something is to be repaired.
    fn new(
        dt: &RegionTriangulation,
        m: &ElementMesh,
        adapted: &[EdgeCurve],
        pieces: &[Vec<u32>],
        needed: bool,
    ) -> Self {
        let t = &dt.triangulation;
        let (mut ends, mut pieces_at, mut at_vertex) = (Vec::new(), Vec::new(), Vec::new());
        let mut chains = Vec::new();
        if needed {
            chains = pieces
                .iter()
                .map(|pieces| {
                    let mut chain = pieces.clone();
                    let start = |p: &u32| {
                        let [u0, u1] = adapted[*p as usize].parameters;
                        u0.min(u1)
                    };
                    chain.sort_by(|a, b| start(a).total_cmp(&start(b)));
                    chain
                })
                .collect();
            ends = adapted
                .iter()
                .map(|ec| {
                    let h = m.edges[ec.edge as usize];
                    [t.origin(h), t.destination(h)].map(|v| v.index() as u32)
                })
                .collect();
            pieces_at = vec![[NONE; 2]; t.num_vertices()];
            at_vertex = vec![1.0; t.num_vertices()];
            for (p, e) in ends.iter().enumerate() {
                for &v in e.iter().filter(|&&v| dt.graph_vertex[v as usize] == NONE) {
                    let slot = &mut pieces_at[v as usize];
                    if slot[0] == NONE {
                        slot[0] = p as u32;
                    } else {
                        slot[1] = p as u32;
                    }
                }
            }
        }
        Self {
            end_round: vec![[0; 2]; ends.len()],
            end_halvings: vec![[0; 2]; ends.len()],
            vertex_round: vec![0; at_vertex.len()],
            vertex_halvings: vec![0; at_vertex.len()],
            straight: vec![false; if needed { pieces.len() } else { 0 }],
            element_round: vec![0; if needed { m.elements.len() } else { 0 }],
            ends,
            chains,
            at_vertex,
            pieces_at,
            vertices: Vec::new(),
            smoothed: Vec::new(),
            graph_ends: Vec::new(),
            curves: Vec::new(),
        }
    }

    /// The halvings (1 to [`MAX_HALVINGS`]) of what shapes element `index` (the shares at the
    /// ends of its curved sides and at its corners on G' edges) after which its quads pass
    /// their floors `bar`, its inner control points relaxed; the other elements as they are.
    /// [`MAX_HALVINGS`] (its sides straight) if none does.
    #[allow(clippy::too_many_arguments)]
    fn halvings_needed(
        &self,
        m: &ElementMesh,
        net: &ControlNet,
        q: &QuadMesh,
        adapted: &[EdgeCurve],
        lookup: CurveLookup<'_>,
        index: usize,
        floors: &Floors,
    ) -> u32 {
        let element = &m.elements[index];
        let start = net.patch_points(index);
        let share = |v: u32, times: u32| halved_times(self.at_vertex[v as usize], times);
        for times in 1..MAX_HALVINGS {
            // Once every share is none, a further halving gives the same patch.
            let mut bulging = false;
            let mut patch = start;
            for (corner, &v) in element.corners().iter().enumerate() {
                let piece = self.pieces_at[v as usize][0];
                if lookup.curve_of_vertex[v as usize] != NONE && piece != NONE {
                    // The vertex between the chord and the curve, where a piece there
                    // puts it.
                    let mut ec = adapted[piece as usize];
                    let end = usize::from(self.ends[piece as usize][0] != v);
                    ec.weights[end] = share(v, times);
                    bulging |= ec.weights[end] > 0.0;
                    patch[side_slots(element, corner)[0]] = blend(&ec)[3 * end];
                }
            }
            for side in 0..m.side_count(index) {
                let (e, forward) = m.side_edge(index, side);
                let piece = lookup.curve_of_edge[e as usize];
                if piece == NONE {
                    continue;
                }
                let mut ec = adapted[piece as usize];
                for (end, &v) in self.ends[piece as usize].iter().enumerate() {
                    ec.weights[end] = if lookup.curve_of_vertex[v as usize] != NONE {
                        share(v, times)
                    } else {
                        halved_times(ec.weights[end], times)
                    };
                    bulging |= ec.weights[end] > 0.0;
                }
                let mut points = blend(&ec);
                if !forward {
                    points.reverse();
                }
                for (slot, p) in side_slots(element, side).into_iter().zip(points) {
                    patch[slot] = p;
                }
            }
            let (inner, count) = relaxed_inner(element, &patch);
            for &(slot, p) in &inner[..count] {
                patch[slot] = p;
            }
            if q.element_valid_with(index, &patch, |x, p| floors.passes(q, x, p)) {
                return times;
            }
            if !bulging {
                break;
            }
        }
        MAX_HALVINGS
    }

    /// Lists for this round what shapes element `index` (the ends of its curved sides, its
    /// corners on G' edges): to halve `halvings` times, or if `whole`, their G' edges to
    /// straighten.
    #[allow(clippy::too_many_arguments)]
    fn mend(
        &mut self,
        m: &ElementMesh,
        adapted: &[EdgeCurve],
        lookup: CurveLookup<'_>,
        index: usize,
        round: u32,
        whole: bool,
        halvings: u32,
    ) {
        let CurveLookup {
            curve_of_edge,
            curve_of_vertex,
        } = lookup;
        let pieces = (0..m.side_count(index))
            .map(|side| curve_of_edge[m.side_edge(index, side).0 as usize])
            .filter(|&p| p != NONE);
        let corners = m.elements[index]
            .corners()
            .iter()
            .copied()
            .filter(|&v| curve_of_vertex[v as usize] != NONE);
        if whole {
            let curves: Vec<u32> = pieces
                .map(|p| adapted[p as usize].graph_edge)
                .chain(corners.map(|v| curve_of_vertex[v as usize]))
                .collect();
            for k in curves {
                if !std::mem::replace(&mut self.straight[k as usize], true) {
                    self.curves.push(k);
                }
            }
            return;
        }
        for p in pieces {
            for end in 0..2 {
                let v = self.ends[p as usize][end];
                if curve_of_vertex[v as usize] != NONE {
                    self.damp_vertex(v, curve_of_vertex[v as usize], round, halvings);
                } else if adapted[p as usize].weights[end] > 0.0
                    && ask(
                        &mut self.end_round[p as usize][end],
                        &mut self.end_halvings[p as usize][end],
                        round,
                        halvings,
                    )
                {
                    self.graph_ends.push((p, end));
                }
            }
        }
        for v in corners {
            self.damp_vertex(v, curve_of_vertex[v as usize], round, halvings);
        }
    }

    /// Lists Steiner vertex `v` of G' edge `k` for this round's damping by `halvings`, once
    /// (by the most halvings asked).
    fn damp_vertex(&mut self, v: u32, k: u32, round: u32, halvings: u32) {
        let v = v as usize;
        if self.at_vertex[v] > 0.0
            && ask(
                &mut self.vertex_round[v],
                &mut self.vertex_halvings[v],
                round,
                halvings,
            )
        {
            self.vertices.push(v as u32);
            self.smoothed.push(k);
        }
    }

    /// Damps what this round listed, places the pieces it changed and marks the elements they
    /// moved (both sides of a piece, all around a Steiner vertex) with `round`.
    fn apply(
        &mut self,
        dt: &RegionTriangulation,
        m: &ElementMesh,
        net: &mut ControlNet,
        adapted: &mut [EdgeCurve],
        pieces: &[Vec<u32>],
        round: u32,
    ) {
        let t = &dt.triangulation;
        let mut changed = Vec::new();
        let mut moved_vertices = Vec::new();
        for k in std::mem::take(&mut self.curves) {
            for &p in &pieces[k as usize] {
                for v in self.ends[p as usize] {
                    if dt.graph_vertex[v as usize] == NONE {
                        self.at_vertex[v as usize] = 0.0;
                        moved_vertices.push(v);
                    }
                }
                adapted[p as usize].weights = [0.0; 2];
                changed.push(p);
            }
        }
        for v in std::mem::take(&mut self.vertices) {
            let w = halved_times(self.at_vertex[v as usize], self.vertex_halvings[v as usize]);
            self.set_vertex(v, w, adapted, &mut changed, &mut moved_vertices);
        }
        let mut smoothed = std::mem::take(&mut self.smoothed);
        smoothed.sort_unstable();
        smoothed.dedup();
        for k in smoothed {
            self.smooth(k, adapted, &mut changed, &mut moved_vertices);
        }
        for (p, end) in std::mem::take(&mut self.graph_ends) {
            let w = &mut adapted[p as usize].weights[end];
            *w = halved_times(*w, self.end_halvings[p as usize][end]);
            changed.push(p);
        }
        changed.sort_unstable();
        changed.dedup();
        let mut mark = |f: imesh_geom::TriangleId| {
            if let Some(&el) = m.element_of_triangle.get(f.index()) {
                if el != NONE {
                    self.element_round[el as usize] = round;
                }
            }
        };
        for p in changed {
            let ec = &adapted[p as usize];
            place(dt, m, net, ec);
            let h = m.edges[ec.edge as usize];
            mark(t.triangle_of(h));
            mark(t.triangle_of(t.twin(h)));
        }
        for v in moved_vertices {
            for f in t.vertex_triangles(VertexId::new(v)) {
                mark(f);
            }
        }
    }

    /// Sets the share Steiner vertex `v` keeps, in both pieces there.
    fn set_vertex(
        &mut self,
        v: u32,
        w: f64,
        adapted: &mut [EdgeCurve],
        changed: &mut Vec<u32>,
        moved_vertices: &mut Vec<u32>,
    ) {
        self.at_vertex[v as usize] = w;
        moved_vertices.push(v);
        for p in self.pieces_at[v as usize] {
            if p != NONE {
                let end = usize::from(self.ends[p as usize][0] != v);
                adapted[p as usize].weights[end] = w;
                changed.push(p);
            }
        }
    }

    /// Lowers the shares of G' edge `k`'s Steiner vertices until neighbours differ by at most
    /// [`SHARE_STEP`]: the damping fades in along the curve instead of kinking it at one vertex.
    fn smooth(
        &mut self,
        k: u32,
        adapted: &mut [EdgeCurve],
        changed: &mut Vec<u32>,
        moved_vertices: &mut Vec<u32>,
    ) {
        // The Steiner vertex between each two pieces in a row (none where a piece is missing).
        let inner: Vec<Option<u32>> = self.chains[k as usize]
            .windows(2)
            .map(|w| {
                let next = self.ends[w[1] as usize];
                self.ends[w[0] as usize]
                    .into_iter()
                    .find(|v| next.contains(v) && self.pieces_at[*v as usize][1] != NONE)
            })
            .collect();
        let share = |v: Option<u32>| v.map(|v| self.at_vertex[v as usize]);
        let mut w: Vec<Option<f64>> = inner.iter().map(|&v| share(v)).collect();
        for i in 1..w.len() {
            if let (Some(before), Some(here)) = (w[i - 1], w[i]) {
                w[i] = Some(here.min(before + SHARE_STEP));
            }
        }
        for i in (1..w.len()).rev() {
            if let (Some(before), Some(here)) = (w[i - 1], w[i]) {
                w[i - 1] = Some(before.min(here + SHARE_STEP));
            }
        }
        for (v, w) in inner.into_iter().zip(w) {
            if let (Some(v), Some(w)) = (v, w) {
                if w < self.at_vertex[v as usize] {
                    self.set_vertex(v, w, adapted, changed, moved_vertices);
                }
            }
        }
    }

    /// The G' edges with a damped piece.
    fn damped_curves(&self, curves: usize, adapted: &[EdgeCurve]) -> usize {
        let mut damped = vec![false; curves];
        for ec in adapted {
            if ec.weights != [1.0, 1.0] {
                damped[ec.graph_edge as usize] = true;
            }
        }
        damped.iter().filter(|&&d| d).count()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// The unit square's corners moved by `moves` (times `shift`).
    fn jittered(moves: [(f64, f64); 4], shift: f64) -> [Point; 4] {
        let square = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)];
        std::array::from_fn(|i| {
            Point::new(
                square[i].0 + shift * moves[i].0,
                square[i].1 + shift * moves[i].1,
            )
        })
    }

    proptest! {
        /// Asking for the straight corners only under the bar decides as the floor computed
        /// for every quad did: valid and at least `min(bar, straight) − 10⁻⁹`.
        #[test]
        fn the_floor_asked_for_under_the_bar_decides_as_the_eager_one(
            adapted in proptest::array::uniform4((-1.0f64..1.0, -1.0f64..1.0)),
            straight in proptest::array::uniform4((-1.0f64..1.0, -1.0f64..1.0)),
            shift in 0.0f64..0.6,
        ) {
            let (p, s) = (jittered(adapted, shift), jittered(straight, shift / 2.0));
            let eager = valid_above(&p, POOR_SCALED_JACOBIAN.min(scaled_jacobian(&s)) - 1e-9);
            let mut asked = false;
            let lazy = above_floor(&p, || {
                asked = true;
                s
            });
            prop_assert_eq!(lazy, eager);
            // The straight corners are read only for a quad under the bar.
            prop_assert_eq!(asked, !valid_above(&p, POOR_SCALED_JACOBIAN - 1e-9));
        }
    }
}
