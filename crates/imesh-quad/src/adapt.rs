//! Boundary adaptation: the patches' boundary curves on G' edges take the fitted Béziers
//! (DESIGN.md §2, step 9; the paper's section V-C).

use imesh_curves::{CubicBezier, CurveGraph};
use imesh_geom::{Point, VertexId};
use rayon::prelude::*;

use crate::dt::{RegionTriangulation, NONE};
use crate::mesh::QuadMesh;
use crate::pairing::ElementMesh;
use crate::patch::ControlNet;

/// What boundary adaptation did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct AdaptReport {
    /// M edges on G' edges, given their fitted sub-curve.
    pub adapted_edges: usize,
    /// Patches whose inner control points were relaxed because a quad inside had turned invalid
    /// or poor.
    pub relaxed_patches: usize,
    /// G' edges pulled back towards their straight segment (their vertices are then between the
    /// chord and the curve) because relaxing the patches was not enough.
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
    /// The share of the curve's bulge kept (that of its G' edge).
    pub weight: f64,
}

impl EdgeCurve {
    /// The piece as the mesh has it: the curve piece blended with the straight piece between
    /// the same DT' vertices by [`EdgeCurve::weight`], from the M edge's origin (parameter 0)
    /// to its destination (1). The edge's template points lie on it.
    ///
    /// ```
    /// use imesh_curves::CubicBezier;
    /// use imesh_geom::Point;
    /// use imesh_quad::EdgeCurve;
    /// let (a, b) = (Point::new(0.0, 0.0), Point::new(3.0, 0.0));
    /// let curve = CubicBezier::new([a, Point::new(1.0, 3.0), Point::new(2.0, 3.0), b]);
    /// let ec = EdgeCurve { edge: 0, graph_edge: 0, parameters: [0.0, 1.0], curve, chord: [a, b], weight: 0.5 };
    /// // Half the bulge: the curve's midpoint is 2.25 above the chord, the path's 1.125.
    /// assert_eq!(ec.path().eval(0.5), Point::new(1.5, 1.125));
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

/// Moves the control points of every M edge on a G' edge onto the exact piece of that edge's
/// fitted curve (`curves[k]` for G' edge `k`), re-evaluates Q, and repairs quads that turned
/// invalid, or poor (a scaled Jacobian below both [`POOR_SCALED_JACOBIAN`] and the quad's
/// straight value): first the patch's inner control points are relaxed (Coons), then, if
/// needed, the offending G' edges' bulge is halved (all their pieces, Steiner corners included),
/// down to the straight edge, whose templates are always valid and never poor. A straight G'
/// edge is within the simplification tolerance of its chain, so damping keeps the mesh within
/// it too; the fitted curve is only closer.
pub fn adapt(
    dt: &RegionTriangulation,
    g: &CurveGraph,
    curves: &[CubicBezier],
    m: &ElementMesh,
    net: &mut ControlNet,
    q: &mut QuadMesh,
) -> (AdaptReport, Vec<EdgeCurve>) {
    let t = &dt.triangulation;
    let mut report = AdaptReport::default();
    let mut adapted = Vec::new();
    let mut curve_of_edge = vec![NONE; m.edges.len()];
    let mut pieces: Vec<Vec<u32>> = vec![Vec::new(); g.edges().len()];
    let parameter = curve_parameters(dt, g, curves);
    // The G' edge a Steiner vertex lies on: its move onto the curve affects every element
    // around it, not only those with a side on the curve.
    let mut curve_of_vertex = vec![NONE; t.num_vertices()];
    let found: Vec<EdgeCurve> = m
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
                weight: 1.0,
            })
        })
        .collect();
    for ec in found {
        let (e, k) = (ec.edge as usize, ec.graph_edge);
        curve_of_edge[e] = adapted.len() as u32;
        pieces[k as usize].push(adapted.len() as u32);
        let h = m.edges[e];
        for v in [t.origin(h), t.destination(h)] {
            if dt.graph_vertex[v.index()] == NONE {
                curve_of_vertex[v.index()] = k;
            }
        }
        adapted.push(ec);
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
    let mut bar = vec![f64::NEG_INFINITY; q.quads.len()];
    let bars: Vec<(usize, f64)> = touched
        .par_iter()
        .flat_map_iter(|&index| {
            let q = &*q;
            q.element_quads(index)
                .map(move |x| (x, POOR_SCALED_JACOBIAN.min(q.scaled_jacobian(x)) - 1e-9))
        })
        .collect();
    for (x, b) in bars {
        bar[x] = b;
    }
    // Per round, which M edges it has evaluated.
    let mut edge_stamp = vec![0u32; m.edges.len()];
    let mut edges = Vec::new();
    let mut stamp = 1;
    evaluate(q, m, net, &touched, &mut edge_stamp, stamp);
    let needs_repair = |q: &QuadMesh, elements: &[usize]| -> Vec<usize> {
        elements
            .par_iter()
            .copied()
            .filter(|&index| q.element_quads(index).any(|x| !q.is_valid_above(x, bar[x])))
            .collect()
    };
    let mut bad = needs_repair(q, &touched);
    // Per-round stamps: a G' edge is damped at most once a round, an element listed once.
    let mut curve_round = vec![0u32; g.edges().len()];
    let mut element_round = vec![0u32; m.elements.len()];
    // The elements a G' edge's damping moves: those on both sides of its pieces, and all
    // around their (Steiner) ends; only needed if something is to be repaired.
    let moved_by: Vec<Vec<u32>> = if bad.is_empty() {
        Vec::new()
    } else {
        pieces
            .par_iter()
            .map(|pieces| {
                let mut elements = Vec::new();
                for &p in pieces {
                    let h = m.edges[adapted[p as usize].edge as usize];
                    let around = |v: VertexId| {
                        (dt.graph_vertex[v.index()] == NONE)
                            .then(|| t.vertex_triangles(v))
                            .into_iter()
                            .flatten()
                    };
                    let sides = [t.triangle_of(h), t.triangle_of(t.twin(h))];
                    elements.extend(
                        sides
                            .into_iter()
                            .chain(around(t.origin(h)))
                            .chain(around(t.destination(h)))
                            .filter_map(|f| m.element_of_triangle.get(f.index()).copied())
                            .filter(|&el| el != NONE),
                    );
                }
                elements.sort_unstable();
                elements.dedup();
                elements
            })
            .collect()
    };
    let mut relaxed = vec![false; m.elements.len()];
    let mut damped = vec![false; g.edges().len()];
    let mut weight = vec![1.0f64; g.edges().len()];
    for round in 1..=40u32 {
        if bad.is_empty() {
            break;
        }
        // The round's elements: the first round's bad ones were evaluated above; later rounds'
        // had a side or a corner moved by a damped curve, and their inner points follow from
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
        for index in needs_repair(q, &bad) {
            let element = &m.elements[index];
            let sides = (0..m.side_count(index)).filter_map(|side| {
                let c = curve_of_edge[m.side_edge(index, side).0 as usize];
                (c != NONE).then(|| adapted[c as usize].graph_edge)
            });
            let corners = element
                .corners()
                .iter()
                .map(|&v| curve_of_vertex[v as usize])
                .filter(|&k| k != NONE);
            let mut touching = [NONE; 8];
            let mut count = 0;
            for k in sides.chain(corners) {
                touching[count] = k;
                count += 1;
            }
            for &k in &touching[..count] {
                let k = k as usize;
                if weight[k] == 0.0 || curve_round[k] == round {
                    continue;
                }
                curve_round[k] = round;
                weight[k] = if weight[k] > 1.0 / 16.0 {
                    weight[k] / 2.0
                } else {
                    0.0
                };
                damped[k] = true;
                for &p in &pieces[k] {
                    let ec = &mut adapted[p as usize];
                    ec.weight = weight[k];
                    place(dt, m, net, ec);
                }
                for &el in &moved_by[k] {
                    element_round[el as usize] = round;
                }
            }
        }
        // Every element a damped curve moved (its sides, or a corner) is relaxed and evaluated
        // again at the start of the next round, before any check; in element order, which is
        // the order of their control points and template vertices in memory.
        bad.clear();
        bad.extend((0..m.elements.len()).filter(|&el| element_round[el] == round));
    }
    // Unless the rounds ran out first.
    evaluate(q, m, net, &bad, &mut edge_stamp, stamp + 1);
    report.relaxed_patches = relaxed.iter().filter(|&&r| r).count();
    report.damped_curves = damped.iter().filter(|&&d| d).count();
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
/// into `edges`.
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
    if ec.weight == 1.0 {
        return c;
    }
    // The straight piece between the DT' vertices: the same for both pieces at a Steiner
    // vertex, as is the curve point, so the blended corner is shared exactly.
    let chord = ec.chord;
    let w = ec.weight;
    let straight = CubicBezier::segment(chord[0], chord[1]).control;
    [0, 1, 2, 3].map(|i| straight[i] + (c[i] - straight[i]) * w)
}
