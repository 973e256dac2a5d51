//! Block coordinate descent: each free point in turn minimises the energy of the quads it
//! moves (two variables, by Powell's method), colour by colour so that the points of one colour
//! are independent and can be solved in parallel, sweep after sweep until the energy stops
//! falling.

use argmin::core::{CostFunction, Error, Executor, Gradient, State};
use argmin::solver::linesearch::condition::ArmijoCondition;
use argmin::solver::linesearch::BacktrackingLineSearch;
use argmin::solver::quasinewton::LBFGS;
use imesh_geom::Point;
use rayon::prelude::*;

use crate::variables::Variables;
use crate::{LocalSolver, Powell, Setup, LANES};

/// What one local solve sees: the corners of the quads it changes as `base + weight · δ`, and
/// the neighbour-polygon edges its point must stay left of.
struct LocalEnergy<'a> {
    corners: &'a [(usize, [(Point, f64); 4])],
    ring: &'a [[Point; 2]],
    /// A squared distance from `origin` within which every point is strictly left of every
    /// ring edge: the origin is, and no edge's line comes closer (with a margin far above the
    /// rounding of the distances). Most trial steps are that short, and skip the predicates.
    clear2: f64,
    origin: Point,
    setup: Setup<'a>,
}

/// The share of the nearest ring edge's distance within which [`LocalEnergy`] trusts a step
/// without the exact predicates.
const RING_MARGIN: f64 = 0.99;

/// A lower bound on the squared distance from `p` to the nearest line through a ring edge,
/// times [`RING_MARGIN`]² (0 for no edge: then nothing is tested anyway). The differences are
/// rounded to within a relative 2⁻⁵³ of their exact values, so the cross product is within
/// `4ε (|dₓ rᵧ| + |d_y rₓ|)` of the exact one: `1e-12` times that sum is taken off it.
fn ring_clearance(ring: &[[Point; 2]], p: Point) -> f64 {
    let nearest = ring
        .iter()
        .map(|&[a, b]| {
            let (d, r) = (b - a, p - a);
            let (u, v) = (d.x * r.y, d.y * r.x);
            let cross = ((u - v).abs() - 1e-12 * (u.abs() + v.abs())).max(0.0);
            cross * cross / (d.x * d.x + d.y * d.y)
        })
        .fold(f64::INFINITY, f64::min);
    if nearest.is_finite() {
        nearest * RING_MARGIN * RING_MARGIN
    } else {
        0.0
    }
}

/// `base + δ · w`, written once so that the solve and the update compute the same bits (a
/// weight of 0 leaves `base` as it is: δ is always finite).
#[inline]
pub(crate) fn moved(base: Point, delta: Point, w: f64) -> Point {
    Point::new(base.x + delta.x * w, base.y + delta.y * w)
}

impl LocalEnergy<'_> {
    fn energy(&self, delta: Point) -> f64 {
        let p = self.origin + delta;
        // The step as taken (`p` is rounded): within `clear2`, inside every ring edge.
        let step = p - self.origin;
        if step.x * step.x + step.y * step.y >= self.clear2
            && !self
                .ring
                .iter()
                .all(|&[a, b]| imesh_geom::predicates::orient2d(a, b, p) > 0.0)
        {
            return f64::INFINITY;
        }
        let mut sum = 0.0;
        // [`LANES`] quads at a time (the last group padded with its last quad, whose extra
        // results are not read), each term added in order as one by one. Its own loop rather
        // than `Setup::visit_feasible`: the corners are moved here per trial point, and a
        // shared loop taking them through a closure measured slower (coins on one thread
        // 0.260 → 0.293 s).
        for group in self.corners.chunks(LANES) {
            let quads: [[Point; 4]; LANES] = std::array::from_fn(|l| {
                group[l.min(group.len() - 1)]
                    .1
                    .map(|(base, w)| moved(base, delta, w))
            });
            let (s, shapes, areas) = self.setup.qualities_and_areas(&quads);
            for (l, (k, _)) in group.iter().enumerate() {
                match self
                    .setup
                    .term_given(*k, &quads[l], (s[l], shapes[l], areas[l]))
                {
                    Some(e) => sum += e,
                    None => return f64::INFINITY,
                }
            }
        }
        sum
    }
}

impl LocalEnergy<'_> {
    /// The gradient of [`LocalEnergy::energy`] (zero where that is infinite).
    fn gradient(&self, delta: Point) -> Point {
        let mut g = Point::new(0.0, 0.0);
        for (k, quad) in self.corners {
            let q = quad.map(|(base, w)| moved(base, delta, w));
            if let Some((_, d)) = self.setup.term_gradient(*k, &q) {
                for (corner, (_, w)) in d.iter().zip(quad) {
                    g = g + *corner * *w;
                }
            }
        }
        g
    }
}

impl Gradient for LocalEnergy<'_> {
    type Param = Vec<f64>;
    type Gradient = Vec<f64>;
    fn gradient(&self, x: &Vec<f64>) -> Result<Vec<f64>, Error> {
        let g = LocalEnergy::gradient(self, Point::new(x[0], x[1]));
        Ok(vec![g.x, g.y])
    }
}

impl CostFunction for LocalEnergy<'_> {
    type Param = Vec<f64>;
    type Output = f64;
    fn cost(&self, x: &Vec<f64>) -> Result<f64, Error> {
        Ok(self.energy(Point::new(x[0], x[1])))
    }
}

/// Most cost evaluations of each line search of a local Powell solve. Block coordinate descent
/// comes back to every point sweep after sweep, so one solve need not be exact: measured on nine
/// fixtures (all but aloe), 10 evaluations took 6.1–6.3 s of optimiser time in all for a mean
/// shape-and-size of 0.8170 averaged over them, 6 took 5.2 s for 0.8178, 5 took 5.0–5.1 s for
/// 0.8181 and 4 took 5.3 s for 0.8182 (more sweeps).
const LINE_EVALUATIONS: usize = 5;

/// Scratch buffers of one worker, its Powell solver's included.
struct Scratch {
    corners: Vec<(usize, [(Point, f64); 4])>,
    ring: Vec<[Point; 2]>,
    powell: Powell,
    x: Vec<f64>,
}

impl Default for Scratch {
    fn default() -> Self {
        Self {
            corners: Vec::new(),
            ring: Vec::new(),
            powell: Powell::new(1.0)
                .with_tolerance(1e-4)
                .with_line_search(1e-2, LINE_EVALUATIONS),
            x: Vec::new(),
        }
    }
}

/// Where moving variable `i` lowers the energy of its quads: its best move, if any.
fn solve(
    variables: &Variables,
    i: usize,
    vertices: &[Point],
    net: &[Point],
    origin: Point,
    setup: Setup<'_>,
    scratch: &mut Scratch,
) -> Option<Point> {
    scratch.corners.clear();
    let mut area = 0.0;
    for (&q, weights) in variables
        .quads
        .row(i)
        .iter()
        .zip(variables.corner_weights.row(i))
    {
        let quad = setup.quads[q as usize];
        let corners = [0, 1, 2, 3].map(|k| (vertices[quad[k] as usize], weights[k]));
        let p = corners.map(|(p, _)| p);
        area += crate::energy::area(&p);
        scratch.corners.push((q as usize, corners));
    }
    if scratch.corners.is_empty() {
        return None;
    }
    scratch.ring.clear();
    let ring = variables.ring.row(i);
    let inside = ring.iter().all(|&[a, b]| {
        imesh_geom::predicates::orient2d(net[a as usize], net[b as usize], origin) > 0.0
    });
    // A point already outside its neighbour polygon (next to a strongly curved boundary) is
    // held to the quads' validity alone.
    if inside {
        scratch.ring.extend(
            ring.iter()
                .map(|&[a, b]| [net[a as usize], net[b as usize]]),
        );
    }
    let local = LocalEnergy {
        corners: &scratch.corners,
        ring: &scratch.ring,
        clear2: ring_clearance(&scratch.ring, origin),
        origin,
        setup,
    };
    let start = local.energy(Point::new(0.0, 0.0));
    // Settled: its quads already score well (a settled term of 0 still skips a perfect start).
    if !start.is_finite() || start <= setup.settled_term * scratch.corners.len() as f64 {
        return None;
    }
    let size = (area / scratch.corners.len() as f64).abs().sqrt();
    let (best, cost) = match setup.local_solver {
        LocalSolver::Powell => {
            scratch.powell.set_initial_step(0.2 * size);
            let x = &mut scratch.x;
            x.clear();
            x.extend([0.0, 0.0]);
            let cost = scratch.powell.minimise_in_place(
                |x| local.energy(Point::new(x[0], x[1])),
                x,
                start,
                setup.local_iterations,
            );
            (Point::new(x[0], x[1]), cost)
        }
        LocalSolver::Lbfgs => {
            let line = BacktrackingLineSearch::new(ArmijoCondition::new(1e-4).ok()?);
            let lbfgs = LBFGS::new(line, 3);
            let result = Executor::new(local, lbfgs)
                .configure(|s| {
                    s.param(vec![0.0, 0.0])
                        .max_iters(2 * setup.local_iterations)
                })
                .run()
                .ok()?;
            let state = result.state();
            let best = state.get_best_param()?;
            (Point::new(best[0], best[1]), state.get_best_cost())
        }
    };
    (cost < start).then_some(best)
}

/// Runs sweeps of local solves over `variables`, moving `vertices` (and, in control mode,
/// `net`), and returns the number of sweeps run.
pub(crate) fn descend(
    variables: &Variables,
    vertices: &mut [Point],
    mut net: Option<&mut [Point]>,
    setup: Setup<'_>,
    total_energy: impl Fn(&[Point]) -> f64,
) -> usize {
    let mut energy = total_energy(vertices);
    let mut sweeps = 0;
    // Only points whose quads changed since they were last solved are solved again: each quad
    // carries the step it last moved at, each point the step it was last solved at (all
    // quads moved before any solve).
    let mut moved_at = vec![1u32; setup.quads.len()];
    let mut solved_at = vec![0u32; variables.len()];
    let changed = |i: usize, moved_at: &[u32], solved_at: &[u32]| {
        variables
            .quads
            .row(i)
            .iter()
            .any(|&q| moved_at[q as usize] > solved_at[i])
    };
    let mut step = 1u32;
    let still = 1e-3 * setup.average_area.sqrt();
    while sweeps < setup.max_sweeps {
        sweeps += 1;
        for colour in &variables.colours {
            let moves: Vec<(usize, Point)> = {
                let (vertices, net_view): (&[Point], &[Point]) =
                    (vertices, net.as_deref().unwrap_or(&[]));
                let (moved_at, solved_at) = (&moved_at[..], &solved_at[..]);
                colour
                    .par_iter()
                    .filter(|&&i| changed(i as usize, moved_at, solved_at))
                    .map_init(Scratch::default, |scratch, &i| {
                        let i = i as usize;
                        let id = variables.ids[i] as usize;
                        let origin = if net_view.is_empty() {
                            vertices[id]
                        } else {
                            net_view[id]
                        };
                        solve(variables, i, vertices, net_view, origin, setup, scratch)
                            .map(|d| (i, d))
                    })
                    .flatten()
                    .collect()
            };
            // Solved at this step; what the moves change, at the next (their own points
            // included: a point that moved is solved again).
            step += 2;
            for &i in colour {
                solved_at[i as usize] = step - 1;
            }
            for (i, delta) in moves {
                if delta.x.abs().max(delta.y.abs()) > still {
                    for &q in variables.quads.row(i) {
                        moved_at[q as usize] = step;
                    }
                }
                for &(v, w) in variables.influence.row(i) {
                    vertices[v as usize] = moved(vertices[v as usize], delta, w);
                }
                if let Some(net) = net.as_deref_mut() {
                    let c = variables.ids[i] as usize;
                    net[c] = net[c] + delta;
                }
            }
        }
        let next = total_energy(vertices);
        let drop = energy - next;
        energy = next;
        let any_changed = (0..variables.len())
            .into_par_iter()
            .any(|i| changed(i, &moved_at, &solved_at));
        if drop <= setup.tolerance * energy.max(f64::MIN_POSITIVE) || !any_changed {
            break;
        }
    }
    sweeps
}

#[cfg(test)]
mod tests {
    use super::ring_clearance;
    use imesh_geom::predicates::orient2d;
    use imesh_geom::Point;
    use proptest::prelude::*;

    proptest! {
        /// Every point within the clearance of a point strictly inside a ring is strictly
        /// inside it too (exact predicates), however close to an edge, and however far from
        /// the origin of coordinates.
        #[test]
        fn points_within_the_ring_clearance_are_inside(
            n in 3usize..9, radius in 1e-6f64..10.0, offset in -1e6f64..1e6,
            jitter in proptest::collection::vec(0.5f64..1.0, 9),
            at in (-1.0f64..1.0, -1.0f64..1.0), direction in 0.0f64..std::f64::consts::TAU,
        ) {
            let centre = Point::new(offset, -offset / 3.0);
            let corners: Vec<Point> = (0..n)
                .map(|k| {
                    let a = k as f64 * std::f64::consts::TAU / n as f64;
                    let r = radius * jitter[k];
                    Point::new(centre.x + r * a.cos(), centre.y + r * a.sin())
                })
                .collect();
            let ring: Vec<[Point; 2]> = (0..n).map(|k| [corners[k], corners[(k + 1) % n]]).collect();
            let p = Point::new(centre.x + 0.5 * radius * at.0, centre.y + 0.5 * radius * at.1);
            prop_assume!(ring.iter().all(|&[a, b]| orient2d(a, b, p) > 0.0));
            let clear = ring_clearance(&ring, p).sqrt();
            for scale in [0.999_999, 0.5, 1e-3, 1e-9] {
                let q = Point::new(
                    p.x + clear * scale * direction.cos(),
                    p.y + clear * scale * direction.sin(),
                );
                let step = q - p;
                if step.x * step.x + step.y * step.y < clear * clear {
                    prop_assert!(ring.iter().all(|&[a, b]| orient2d(a, b, q) > 0.0));
                }
            }
        }
    }
}
