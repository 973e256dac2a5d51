//! Opening sharp corners: where two boundaries leave a vertex of G' closer than a quad's corner
//! should be, the fitted curves' end tangents are turned apart, within the fitting tolerance.
//!
//! A quad at such a vertex has its corner between the two boundaries, and nothing downstream
//! can widen it: the optimiser moves neither G' vertices nor boundary control points, so the
//! corner's sine is the mesh's worst scaled Jacobian. A spike tip or a junction at 20° in the
//! pixels is rarely a feature of the object imaged; turning each curve a few degrees at the
//! vertex moves it a fraction of a pixel there, and the fit is kept only when the curve stays
//! within the tolerance of its chain.

use imesh_geom::Point;
use rayon::prelude::*;

use crate::bezier::{fit_cubic_with_tangents, CubicBezier, CurveFit};
use crate::simplify::Simplification;
use crate::{CurveGraph, FitReport};

/// The narrowest corner [`open_sharp_corners`] leaves where it can, in degrees: a quad's scaled
/// Jacobian there is at least its sine, 0.5.
pub const MIN_CORNER_DEG: f64 = 30.0;

/// Options of [`open_sharp_corners`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CornerOptions {
    /// The narrowest sector left between two boundaries at a vertex, in degrees.
    pub min_angle_deg: f64,
    /// How far (pixels) a turned curve may stray from its chain, both ways (or as far as the
    /// fit it replaces did, if farther).
    pub tolerance: f64,
    /// How far from the vertex (pixels) a boundary's direction is taken: the chord to its
    /// curve's point that far, about where the first element edge along it ends (a cubic bends
    /// back to its chain within a few pixels of a turned tangent).
    pub reach: f64,
}

impl Default for CornerOptions {
    fn default() -> Self {
        Self {
            min_angle_deg: MIN_CORNER_DEG,
            tolerance: 2.0,
            reach: 2.0,
        }
    }
}

/// What [`open_sharp_corners`] did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CornerReport {
    /// Sectors narrower than the angle asked for, at vertices of G'.
    pub sharp: usize,
    /// Curves refitted with a turned end tangent.
    pub refitted: usize,
}

/// One end of an edge of G' at a vertex: the edge, which end, the curve's direction there.
#[derive(Clone, Copy, Debug)]
struct End {
    edge: u32,
    at_start: bool,
    angle: f64,
    /// Turned by this much (radians, counter-clockwise positive).
    turn: f64,
    fixed: bool,
}

/// Turns the ends of the fitted curves in `fits` (one per edge of `s.graph`, fitted to the
/// chains of `original`, e.g. by [`crate::fit_edges`]) so that no two consecutive boundaries
/// leave a vertex of G' closer than `options.min_angle_deg`, their directions taken
/// `options.reach` from it, where the neighbouring sectors leave room: each side of a sharp
/// sector turns away from it by half the shortfall (all of it when the other side is `fixed`,
/// e.g. the domain's border, which stays straight), no neighbouring sector closing below that
/// angle. A turned curve is refitted to its chain with its end tangents given, and kept only
/// when it stays within `options.tolerance` of the chain, both ways (or no farther than the fit
/// it replaces); `fits`' errors are updated.
///
/// ```
/// use imesh_curves::{fit_edges, open_sharp_corners, simplify, CornerOptions, CurveGraph, FitOptions, GraphEdge, SimplifyOptions};
/// use imesh_geom::Point;
/// // A spike: two boundaries leave (0, 0) 20° apart, along chains of ten points, joined at
/// // their far ends.
/// let mut points = vec![Point::new(0.0, 0.0)];
/// for side in [10.0f64, -10.0] {
///     let a = side.to_radians();
///     points.extend((1..=10).map(|i| Point::new(f64::from(i) * 2.0 * a.cos(), f64::from(i) * 2.0 * a.sin())));
/// }
/// let mut edges = vec![GraphEdge { ends: [0, 1], labels: [1, 0] }, GraphEdge { ends: [0, 11], labels: [0, 1] }];
/// for i in 1..10 {
///     edges.push(GraphEdge { ends: [i, i + 1], labels: [1, 0] });
///     edges.push(GraphEdge { ends: [10 + i, 11 + i], labels: [0, 1] });
/// }
/// edges.push(GraphEdge { ends: [10, 20], labels: [1, 0] });
/// let mut g = CurveGraph::new(points, edges)?;
/// g.pin(0)?;
/// let s = simplify(&g, &SimplifyOptions::with_tolerance(1.0))?;
/// let mut fits = fit_edges(&s, &g, &FitOptions::default());
/// let options = CornerOptions { tolerance: 1.0, ..CornerOptions::default() };
/// let report = open_sharp_corners(&s, &g, &mut fits, &options, |_| false);
/// assert_eq!((report.sharp, report.refitted), (1, 2));
/// assert!(fits.max_error.max(fits.max_curve_deviation) <= 1.0);
/// # Ok::<(), imesh_curves::CurveError>(())
/// ```
pub fn open_sharp_corners(
    s: &Simplification,
    original: &CurveGraph,
    fits: &mut FitReport,
    options: &CornerOptions,
    fixed: impl Fn(u32) -> bool,
) -> CornerReport {
    let g = &s.graph;
    let mut report = CornerReport::default();
    let min = options.min_angle_deg.to_radians();
    let (tolerance, reach) = (options.tolerance, options.reach);
    if !(min > 0.0 && min < std::f64::consts::PI && reach > 0.0 && tolerance >= 0.0)
        || fits.fits.len() != g.edges().len()
    {
        return report;
    }
    // Per edge, the turn of its start and of its end.
    let mut turns = vec![[0.0f64; 2]; fits.fits.len()];
    let mut ends: Vec<End> = Vec::new();
    for v in 0..g.points().len() as u32 {
        ends.clear();
        for &k in g.incident(v) {
            let edge = g.edges()[k as usize];
            // A loop's two ends are both here; each is its own end.
            for (at_start, end) in [(true, edge.ends[0]), (false, edge.ends[1])] {
                if end != v {
                    continue;
                }
                if let Some(d) = chord(&fits.fits[k as usize].curve, at_start, reach) {
                    ends.push(End {
                        edge: k,
                        at_start,
                        angle: d.y.atan2(d.x),
                        turn: 0.0,
                        fixed: fixed(k),
                    });
                }
            }
        }
        if ends.len() < 2 {
            continue;
        }
        ends.sort_by(|a, b| a.angle.total_cmp(&b.angle));
        open_sectors(&mut ends, min, &mut report);
        for e in &ends {
            turns[e.edge as usize][usize::from(!e.at_start)] = e.turn;
        }
    }
    // Each turned curve is refitted on its own: in parallel, kept in edge order.
    let refits: Vec<(usize, CurveFit)> = turns
        .par_iter()
        .enumerate()
        .filter(|(_, turn)| turn[0] != 0.0 || turn[1] != 0.0)
        .filter_map(|(k, turn)| {
            let chain: Vec<Point> = s.chains[k].iter().map(|&v| original.point(v)).collect();
            turned(&chain, &fits.fits[k], *turn, tolerance, reach).map(|fit| (k, fit))
        })
        .collect();
    report.refitted = refits.len();
    for (k, fit) in refits {
        fits.fits[k] = fit;
    }
    if report.refitted > 0 {
        *fits = FitReport::of(std::mem::take(&mut fits.fits), &s.chains);
    }
    report
}

/// The fit of `chain` whose chords at `reach` from its ends are turned by `turn` (radians, start
/// then end) from those of `old`, within `tolerance` of the chain (or `old`'s distance, if
/// larger): the end tangents turned by the chords' turns or more, their arms fitted; then, as a
/// least-squares arm can shrink until the curve bends straight back to its chain, the turned
/// ends' arms held at a few `reach`es, the other end's fitted. Only a fit that
/// [`runs_forward`] is taken (four or five chain points fit an S-loop reaching several pixels
/// past the chain's ends as closely as a turned arc: measured on the astronaut and grass images,
/// and the adaptation then straightens the curve, turn and all). The first fit whose chords
/// turned all the way, else the one that turned them most.
fn turned(
    chain: &[Point],
    old: &CurveFit,
    turn: [f64; 2],
    tolerance: f64,
    reach: f64,
) -> Option<CurveFit> {
    let bound = tolerance.max(old.hausdorff());
    let start = tangent(old, true)?;
    let end = tangent(old, false)?;
    let before = [true, false].map(|at_start| chord(&old.curve, at_start, reach));
    // A fitted arm can overshoot the far end on a short chain: then both arms are held, the
    // fitted ones at a third of the chord (a cubic's arms on a straight line).
    let third = chain[0].distance_squared(chain[chain.len() - 1]).sqrt() / 3.0;
    let mut best: Option<(f64, CurveFit)> = None;
    for arm in ARMS {
        for factor in TANGENT_FACTORS {
            let arms = turn.map(|t| arm.filter(|_| t != 0.0).map(|a| a * reach));
            let (start, end) = (
                rotate(start, turn[0] * factor),
                rotate(end, turn[1] * factor),
            );
            let forward = |arms| {
                fit_cubic_with_tangents(chain, start, end, arms).filter(|f| runs_forward(&f.curve))
            };
            let held = arms.map(|a| a.or(Some(third)));
            let Some(fit) = forward(arms)
                .or_else(|| (held != arms).then(|| forward(held)).flatten())
                .filter(|f| f.hausdorff() <= bound)
            else {
                continue;
            };
            // The least share of its turn an end's chord made.
            let mut share = f64::INFINITY;
            for (i, at_start) in [true, false].into_iter().enumerate() {
                if turn[i] == 0.0 {
                    continue;
                }
                let made = match (before[i], chord(&fit.curve, at_start, reach)) {
                    (Some(a), Some(b)) => angle_between(a, b),
                    _ => f64::NEG_INFINITY,
                };
                share = share.min(made / turn[i]);
            }
            if share >= 1.0 {
                return Some(fit);
            }
            if share > best.as_ref().map_or(0.0, |b| b.0) {
                best = Some((share, fit));
            }
        }
    }
    best.map(|(_, fit)| fit)
}

/// The turned arms' lengths tried, in `reach`es (see [`turned`]): first fitted, then held.
const ARMS: [Option<f64>; 5] = [None, Some(1.0), Some(1.5), Some(2.0), Some(3.0)];

/// The multiples of a chord's turn tried on the tangent (see [`turned`]).
const TANGENT_FACTORS: [f64; 4] = [1.0, 1.5, 2.0, 3.0];

/// The direction from `curve`'s start (`at_start`) or end to its first point `reach` away (its
/// other end if none is), or `None` for a curve with no length.
pub(crate) fn chord(curve: &CubicBezier, at_start: bool, reach: f64) -> Option<Point> {
    let from = if at_start {
        curve.control[0]
    } else {
        curve.control[3]
    };
    let at = |s: f64| curve.eval(if at_start { s } else { 1.0 - s });
    let far = |s: f64| at(s).distance_squared(from) >= reach * reach;
    // The first of 64 samples that far, then bisection between it and the one before.
    let Some(k) = (1..=CHORD_SAMPLES).find(|&k| far(f64::from(k) / f64::from(CHORD_SAMPLES)))
    else {
        let d = at(1.0) - from;
        return (d.x != 0.0 || d.y != 0.0).then_some(d);
    };
    let (mut lo, mut hi) = (
        f64::from(k - 1) / f64::from(CHORD_SAMPLES),
        f64::from(k) / f64::from(CHORD_SAMPLES),
    );
    for _ in 0..20 {
        let mid = 0.5 * (lo + hi);
        if far(mid) {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    let d = at(hi) - from;
    (d.x != 0.0 || d.y != 0.0).then_some(d)
}

/// Samples of [`chord`]'s search.
const CHORD_SAMPLES: u32 = 64;

/// Widens the sectors between consecutive `ends` (two or more, sorted by angle,
/// counter-clockwise) that are narrower than `min`, each end turning once.
fn open_sectors(ends: &mut [End], min: f64, report: &mut CornerReport) {
    let n = ends.len();
    let tau = std::f64::consts::TAU;
    // The sector from end i to end i + 1, counter-clockwise (as turned so far; the last wraps
    // round to the first).
    let width = |ends: &[End], i: usize| {
        let (a, b) = (&ends[i], &ends[(i + 1) % n]);
        let w = (b.angle + b.turn) - (a.angle + a.turn);
        if i + 1 == n {
            w + tau
        } else {
            w
        }
    };
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&i, &j| width(ends, i).total_cmp(&width(ends, j)));
    for i in order {
        let w = width(ends, i);
        if w >= min {
            continue;
        }
        report.sharp += 1;
        let (a, b) = (i, (i + 1) % n);
        // Room on each side: what the neighbouring sector can give and stay at `min`.
        let room = |ends: &[End], side: usize, sector: usize| {
            if ends[side].fixed || ends[side].turn != 0.0 {
                0.0
            } else {
                (width(ends, sector) - min).max(0.0)
            }
        };
        let (room_a, room_b) = (room(ends, a, (i + n - 1) % n), room(ends, b, b));
        let need = min - w;
        let half = need / 2.0;
        let (mut turn_a, mut turn_b) = (half.min(room_a), half.min(room_b));
        // One side short of room: the other takes what it can of the rest.
        turn_a = (need - turn_b).min(room_a).max(turn_a);
        turn_b = (need - turn_a).min(room_b).max(turn_b);
        // End a turns clockwise (away from the sector), end b counter-clockwise.
        ends[a].turn -= turn_a;
        ends[b].turn += turn_b;
    }
}

/// The direction `fit`'s curve leaves its start (`at_start`) or its end along, into the curve.
fn tangent(fit: &CurveFit, at_start: bool) -> Option<Point> {
    let c = fit.curve.control;
    let (from, towards) = if at_start {
        (c[0], [c[1], c[2], c[3]])
    } else {
        (c[3], [c[2], c[1], c[0]])
    };
    towards
        .into_iter()
        .map(|p| p - from)
        .find(|d| d.x != 0.0 || d.y != 0.0)
}

/// The angle (radians, counter-clockwise positive) from direction `a` to direction `b`.
fn angle_between(a: Point, b: Point) -> f64 {
    (a.x * b.y - a.y * b.x).atan2(a.x * b.x + a.y * b.y)
}

/// True when `curve` runs forward all along its chord: the chord's direction has a positive
/// component in every control-polygon leg, hence (the hodograph being the Bézier of those legs)
/// in the curve's derivative everywhere. A turned tangent on a short chain can otherwise be fitted
/// as a hook past its end, within the tolerance of the chain but folding the elements along it.
fn runs_forward(curve: &CubicBezier) -> bool {
    let c = curve.control;
    let chord = c[3] - c[0];
    c.windows(2).all(|leg| {
        let d = leg[1] - leg[0];
        d.x * chord.x + d.y * chord.y > 0.0
    })
}

/// `d` turned by `angle` radians counter-clockwise.
fn rotate(d: Point, angle: f64) -> Point {
    let (sin, cos) = angle.sin_cos();
    Point::new(d.x * cos - d.y * sin, d.x * sin + d.y * cos)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{fit_edges, simplify, FitOptions, GraphEdge, SimplifyOptions};
    use proptest::prelude::*;

    /// A wedge of `angle_deg` at (0, 0) between two chains of `n` points `step` apart, the
    /// first along the x axis; closed at the far end. Edge 0 is on the x axis's chain.
    fn wedge(angle_deg: f64, n: u32, step: f64) -> CurveGraph {
        let a = angle_deg.to_radians();
        let mut points = vec![Point::new(0.0, 0.0)];
        points.extend((1..=n).map(|i| Point::new(f64::from(i) * step, 0.0)));
        points.extend(
            (1..=n)
                .map(|i| Point::new(f64::from(i) * step * a.cos(), f64::from(i) * step * a.sin())),
        );
        let mut edges = vec![GraphEdge {
            ends: [0, 1],
            labels: [1, 0],
        }];
        edges.extend((1..n).map(|i| GraphEdge {
            ends: [i, i + 1],
            labels: [1, 0],
        }));
        edges.push(GraphEdge {
            ends: [0, n + 1],
            labels: [0, 1],
        });
        edges.extend((1..n).map(|i| GraphEdge {
            ends: [n + i, n + i + 1],
            labels: [0, 1],
        }));
        edges.push(GraphEdge {
            ends: [n, 2 * n],
            labels: [1, 0],
        });
        let mut g = CurveGraph::new(points, edges).expect("a wedge is a valid graph");
        g.pin(0).expect("the tip exists");
        g
    }

    /// The angle (degrees) between the chords `reach` along the two G' edges at the tip.
    fn tip_angle(s: &Simplification, fits: &FitReport, reach: f64) -> f64 {
        let dirs: Vec<Point> = s
            .graph
            .incident(0)
            .iter()
            .filter_map(|&k| {
                let at_start = s.graph.edges()[k as usize].ends[0] == 0;
                chord(&fits.fits[k as usize].curve, at_start, reach)
            })
            .collect();
        angle_between(dirs[0], dirs[1]).abs().to_degrees()
    }

    /// [`wedge`] simplified at a tolerance of 1 px, and its fitted curves.
    fn fitted(angle_deg: f64, n: u32, step: f64) -> (CurveGraph, Simplification, FitReport) {
        let g = wedge(angle_deg, n, step);
        let s = simplify(&g, &SimplifyOptions::with_tolerance(1.0)).expect("simplifies");
        let fits = fit_edges(&s, &g, &FitOptions::default());
        (g, s, fits)
    }

    #[test]
    fn wide_sectors_are_left_alone() {
        let (g, s, mut fits) = fitted(50.0, 10, 2.0);
        let before = fits.clone();
        let report = open_sharp_corners(&s, &g, &mut fits, &CornerOptions::default(), |_| false);
        assert_eq!(report, CornerReport::default());
        assert_eq!(fits, before);
    }

    #[test]
    fn a_fixed_side_stays_and_the_other_turns_alone() {
        let (g, s, mut fits) = fitted(15.0, 12, 2.0);
        let before = fits.clone();
        // The x axis's side is the domain's border.
        let on_axis = |k: u32| {
            s.graph.edges()[k as usize]
                .ends
                .iter()
                .all(|&v| s.graph.point(v).y == 0.0)
        };
        let options = CornerOptions {
            tolerance: 1.0,
            ..CornerOptions::default()
        };
        let report = open_sharp_corners(&s, &g, &mut fits, &options, on_axis);
        assert_eq!((report.sharp, report.refitted), (1, 1));
        for (k, (now, was)) in fits.fits.iter().zip(&before.fits).enumerate() {
            if on_axis(k as u32) {
                assert_eq!(now, was);
            }
        }
        assert!(
            tip_angle(&s, &fits, options.reach) > 29.9,
            "{}",
            tip_angle(&s, &fits, options.reach)
        );
        assert!(fits.max_error.max(fits.max_curve_deviation) <= options.tolerance);
    }

    proptest! {
        /// Short chains (four to six pixel-corner points, as at the tip of a thin spike) with
        /// an end turned by up to 15°: whatever fit is kept runs forward along its chord and
        /// stays within the tolerance. Unchecked, the least-squares arms of such a chain often
        /// swing past its far end.
        #[test]
        fn turned_short_chains_run_forward(
            steps in proptest::collection::vec((0u8..3, -1i8..=1), 3..6),
            turn_deg in proptest::collection::vec(-15.0f64..15.0, 2),
            both in any::<bool>(),
        ) {
            let mut chain = vec![Point::new(0.5, 0.5)];
            for &(dx, dy) in &steps {
                let last = chain[chain.len() - 1];
                chain.push(Point::new(last.x + f64::from(dx.max(1)), last.y + f64::from(dy)));
            }
            let old = fit_cubic_with_tangents(
                &chain,
                chain[chain.len() - 1] - chain[0],
                chain[0] - chain[chain.len() - 1],
                [None, None],
            );
            prop_assume!(old.as_ref().is_some_and(|f| runs_forward(&f.curve)));
            let old = old.expect("assumed");
            let turn = [
                turn_deg[0].to_radians(),
                if both { turn_deg[1].to_radians() } else { 0.0 },
            ];
            if let Some(fit) = turned(&chain, &old, turn, 2.0, 2.0) {
                prop_assert!(runs_forward(&fit.curve), "{:?}", fit.curve.control);
                prop_assert!(fit.hausdorff() <= 2.0_f64.max(old.hausdorff()));
            }
        }

        /// Spikes of 6°–28°: the turned curves stay within the tolerance of their chains (1 px
        /// here), and where the chains are long enough to bend back within it (ten pieces of
        /// 2 px or more), the tip opens to the angle asked for.
        #[test]
        fn spikes_open_within_the_tolerance(angle in 6.0f64..28.0, n in 3u32..14, step in 0.5f64..3.0) {
            let (g, s, mut fits) = fitted(angle, n, step);
            let before = fits.clone();
            let options = CornerOptions { tolerance: 1.0, ..CornerOptions::default() };
            let report = open_sharp_corners(&s, &g, &mut fits, &options, |_| false);
            prop_assert!(report.sharp >= 1);
            for (now, was) in fits.fits.iter().zip(&before.fits) {
                prop_assert!(now == was || now.hausdorff() <= 1.0_f64.max(was.hausdorff()));
            }
            if n >= 10 && step >= 2.0 {
                prop_assert!(tip_angle(&s, &fits, options.reach) > 29.9);
            }
        }
    }
}
