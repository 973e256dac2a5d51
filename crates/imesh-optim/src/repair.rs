//! The worst corners last. The energy `Σ (1 − s)²` weighs a quad by its shape-and-size, so a
//! quad of fair size with one sharp corner costs it little, and the descent leaves it: a
//! triangle template's corner at a flat triangle's centroid, or a quad squeezed against a curve.
//! Here every free quad vertex within two rings of a quad whose scaled Jacobian or shape is
//! under the bar moves, by compass search, to raise the smallest scaled Jacobian of its own
//! quads, then at an equal one their smallest shape (both counted up to the bar only, so that
//! nothing moves for quads already good enough); then the free corners of each quad still under
//! the bar move together, two or more at a time. Every quad is held to [`REPAIR_FLOOR`] or
//! where it stood, if lower, and to the start's worst: the worst quality, worst shape and worst
//! scaled Jacobian never fall.

use imesh_geom::{Point, Triangulation};
use imesh_quad::{ElementMesh, QuadMesh};

use std::collections::VecDeque;

use rayon::prelude::*;

use crate::batches::{Scheduler, Subproblem};
use crate::variables::{vertex_quads, Variables};
use crate::Setup;

/// Quads with a scaled Jacobian or a shape under this are repaired
/// ([`crate::OptimOptions::repair`]), and a vertex's objective counts up to it: the sine of
/// 30°, issue 8's target, as pairing's and adaptation's bars (while those were 0.35, the
/// corners they left pinned held the worst scaled Jacobians under 0.4 whatever this was).
pub const REPAIR_JACOBIAN: f64 = 0.5;

/// The repair may lower a quad's shape and scaled Jacobian to this (or to where they were
/// when the repair began, if lower), for the worse quads around it. Measured with the defaults
/// on nine fixtures against the descent's floors (a quad of shape 0.5 or more stays there):
/// worst scaled Jacobian mean 0.400 → 0.424 (camera 0.450 → 0.498, brick 0.386 → 0.475),
/// worst shape 0.318 → 0.329; at 0.4, 0.421 and 0.320.
pub const REPAIR_FLOOR: f64 = 0.45;

/// The floors the repair holds `quad` of `points` to from where it stands: its shape and its
/// scaled Jacobian now, each capped at [`REPAIR_FLOOR`].
pub(crate) fn held_at(points: &[Point], quad: &[u32; 4]) -> [f64; 2] {
    held_up_to(points, quad, REPAIR_FLOOR)
}

/// The shape and the scaled Jacobian of `quad` of `points`, each capped at `cap`.
pub(crate) fn held_up_to(points: &[Point], quad: &[u32; 4], cap: f64) -> [f64; 2] {
    let p = quad.map(|v| [points[v as usize].x, points[v as usize].y]);
    [
        imesh_quality::quad::shape(&p).min(cap),
        imesh_quality::quad::scaled_jacobian(&p).min(cap),
    ]
}

/// Most passes over the vertices near poor quads (each pass finds them again; the passes stop
/// at one that moves nothing). Measured with the defaults on fourteen images against 4 (with
/// the joint repair's passes): worst shape brick 0.462 → 0.500, coffee 0.431 → 0.430, the
/// other twelve equal, mean shape-and-size within 0.00002; optimiser time +1 % to +9 % at the
/// default size and −3 % to +14 % graded (interleaved runs; no graded worst value moved).
const PASSES: usize = 8;

/// Compass directions: the axes, then the diagonals.
const DIRECTIONS: [(f64, f64); 8] = [
    (1.0, 0.0),
    (-1.0, 0.0),
    (0.0, 1.0),
    (0.0, -1.0),
    (1.0, 1.0),
    (-1.0, -1.0),
    (1.0, -1.0),
    (-1.0, 1.0),
];

/// The first step, as a share of the mean distance from the vertex to the other corners of its
/// quads, and how many times it is halved before the search stops. The search takes the first
/// direction that improves and stops once its quads reach the bar, so a long first step
/// overshoots: against 0.25, a twentieth gave a higher mean shape-and-size on 33 of 36 runs
/// (nine fixtures at the default size, 3 px, 4 px and graded; +0.0001 to +0.002, the other
/// three equal to four decimals) and fewer quads under 0.25 on 26 (more on 6), while the worst
/// single quads moved both ways
/// (coffee's worst scaled Jacobian 0.280 → 0.366 at the default size, MRI's 0.417 → 0.401 at
/// 3 px, coffee's worst shape 0.307 → 0.234 at 4 px). 0.1 and 0.02 did no better.
const FIRST_STEP: f64 = 0.05;
const HALVINGS: usize = 12;

/// Raises the worst scaled Jacobians and shapes of `mesh`'s quads towards `bar`, moving its
/// free vertices (those of the vertex mode: not on a constrained M edge of `elements`); returns
/// how many moved. The same as one search after the other in a fixed order, on any number of
/// threads: the searches run side by side where neither reads what the other moves
/// ([`Scheduler`]).
pub(crate) fn repair(
    t: &Triangulation,
    elements: &ElementMesh,
    mesh: &mut QuadMesh,
    setup: &Setup,
    bar: f64,
) -> usize {
    // The quads under the bar: by shape, which is at most the scaled Jacobian at every corner.
    let poor = |vertices: &[Point]| -> Vec<u32> {
        (0..setup.quads.len() as u32)
            .filter(|&q| setup.shape(vertices, q as usize) < bar)
            .collect()
    };
    let first = poor(&mesh.vertices);
    if first.is_empty() {
        return 0;
    }
    // Only the vertices within two rings of a poor quad can take part.
    let around = vertex_quads(mesh);
    let mut near = vec![false; mesh.vertices.len()];
    for &q in &first {
        for v in setup.quads[q as usize] {
            for &r in around.row(v as usize) {
                for u in setup.quads[r as usize] {
                    near[u as usize] = true;
                }
            }
        }
    }
    let vars = Variables::vertices_where(t, elements, mesh, |v| near[v as usize]);
    let vertices = &mut mesh.vertices;
    let mut moved = vec![false; vars.len()];
    // A search is a function of the corners of the quads it scores: one that found no move is
    // not run again until one of those corners has moved (the same result, unsearched).
    let mut searcher = Searcher {
        since: Unchanged::new(vertices.len()),
        scheduler: Scheduler::new(vertices.len()),
    };
    let mut vertex_failed = vec![NEVER; vars.len()];
    let mut variable_of = vec![u32::MAX; vertices.len()];
    for (i, &v) in vars.ids.iter().enumerate() {
        variable_of[v as usize] = i as u32;
    }
    let mut poor_quads = first;
    for pass in 0..PASSES {
        if pass > 0 {
            poor_quads = poor(vertices);
        }
        // The variables within two rings of a poor quad: those of the quads sharing a free
        // vertex with it (its own vertices' other quads).
        let mut wanted = vec![false; vars.len()];
        for &q in &poor_quads {
            for &i in vars.by_quad.row(q as usize) {
                for &r in vars.quads.row(i as usize) {
                    for &j in vars.by_quad.row(r as usize) {
                        wanted[j as usize] = true;
                    }
                }
            }
        }
        let searches = (0..vars.len()).filter(|&i| wanted[i]).map(|i| Search {
            slot: i,
            moving: std::slice::from_ref(&vars.ids[i]),
            quads: vars.quads.row(i),
            together: 1,
        });
        let found = searcher.run(searches.collect(), &mut vertex_failed, vertices, setup, bar);
        for &v in &found {
            moved[variable_of[v as usize] as usize] = true;
        }
        if found.is_empty() {
            break;
        }
    }
    // A quad whose bad corner is pinned (at a G' vertex, between boundary edges) can need two
    // of its free corners to move at once: one alone turns the pinned corner but bends the quad
    // at the other (measured: coffee's worst scaled Jacobian 0.396 → 0.420, the other eight
    // fixtures' equal).
    let mut quad_failed = vec![NEVER; setup.quads.len()];
    for _ in 0..PASSES {
        // Each poor quad with two free corners or more: those corners, and their quads.
        let corners: Vec<(usize, Vec<u32>, Vec<u32>)> = poor(vertices)
            .into_iter()
            .filter_map(|q| {
                let free: Vec<u32> = setup.quads[q as usize]
                    .into_iter()
                    .filter(|&v| variable_of[v as usize] != u32::MAX)
                    .collect();
                if free.len() < 2 {
                    return None;
                }
                let mut quads: Vec<u32> = free
                    .iter()
                    .flat_map(|&v| {
                        vars.quads
                            .row(variable_of[v as usize] as usize)
                            .iter()
                            .copied()
                    })
                    .collect();
                quads.sort_unstable();
                quads.dedup();
                Some((q as usize, free, quads))
            })
            .collect();
        let searches = corners.iter().map(|(q, free, quads)| Search {
            slot: *q,
            moving: free,
            quads,
            together: 2,
        });
        let found = searcher.run(searches.collect(), &mut quad_failed, vertices, setup, bar);
        for &v in &found {
            moved[variable_of[v as usize] as usize] = true;
        }
        if found.is_empty() {
            break;
        }
    }
    moved.iter().filter(|&&m| m).count()
}

/// A search that has not failed yet.
const NEVER: u32 = u32::MAX;

/// Which vertices moved since when: a clock that ticks at every move, and per vertex the tick
/// of its last move.
struct Unchanged {
    clock: u32,
    moved_at: Vec<u32>,
}

impl Unchanged {
    fn new(vertices: usize) -> Self {
        Self {
            clock: 0,
            moved_at: vec![0; vertices],
        }
    }

    /// The time now, to stamp a search that found no move.
    fn now(&self) -> u32 {
        self.clock
    }

    /// Vertices `moved` have just moved.
    fn moved(&mut self, moved: &[u32]) {
        self.clock += 1;
        for &v in moved {
            self.moved_at[v as usize] = self.clock;
        }
    }

    /// True when a search that found no move at time `failed` (or [`NEVER`]) would find none
    /// again: no corner of `quads` (of `corners`) has moved since.
    fn unchanged(&self, failed: u32, quads: &[u32], corners: &[[u32; 4]]) -> bool {
        failed != NEVER
            && quads.iter().all(|&q| {
                corners[q as usize]
                    .iter()
                    .all(|&u| self.moved_at[u as usize] <= failed)
            })
    }
}

/// Searches side by side at most ([`Scheduler::take`]): enough to keep a few threads busy; a
/// constant, not the thread count, so that the batches depend on nothing else.
const BATCH: usize = 64;

/// The corners of `quads` (of `setup`) into `out`.
fn corners(quads: &[u32], setup: &Setup, out: &mut Vec<u32>) {
    out.extend(quads.iter().flat_map(|&q| setup.quads[q as usize]));
}

/// One compass search of the repair: vertices `moving`, any `together` or more of them stepping
/// together, raising the corners of `quads` (all the quads they are corners of); `slot` is
/// where its last failure is kept.
struct Search<'a> {
    slot: usize,
    moving: &'a [u32],
    quads: &'a [u32],
    together: u32,
}

/// What runs the repair's searches: the clock of the vertices' moves, and the scheduler.
struct Searcher {
    since: Unchanged,
    scheduler: Scheduler,
}

impl Searcher {
    /// Runs `searches` in order, side by side where neither reads what the other moves; one
    /// whose quads' corners have not moved since it last found no move (at `failed[slot]`) is
    /// not run again. Returns the vertices moved, in the order of their searches.
    fn run(
        &mut self,
        mut queue: VecDeque<Search>,
        failed: &mut [u32],
        vertices: &mut [Point],
        setup: &Setup,
        bar: f64,
    ) -> Vec<u32> {
        let mut moved = Vec::new();
        while !queue.is_empty() {
            let since = &self.since;
            let now = self.scheduler.take(
                &mut queue,
                BATCH,
                |s, reads| corners(s.quads, setup, reads),
                |s, moves| moves.extend_from_slice(s.moving),
                |s| since.unchanged(failed[s.slot], s.quads, setup.quads),
            );
            let view = &*vertices;
            let found: Vec<Option<Vec<Point>>> = now
                .par_iter()
                .map(|s| {
                    let groups: Vec<u32> = (1..1u32 << s.moving.len())
                        .filter(|m| m.count_ones() >= s.together)
                        .collect();
                    let sub = Subproblem::new(s.quads, setup);
                    let mut points = sub.gather(view);
                    let moving: Vec<usize> =
                        s.moving.iter().filter_map(|&v| sub.index(v)).collect();
                    let all: Vec<u32> = (0..sub.len() as u32).collect();
                    compass(&moving, &groups, &all, &mut points, &sub.setup(setup), bar)
                        .then(|| moving.iter().map(|&k| points[k]).collect())
                })
                .collect();
            for (s, found) in now.iter().zip(found) {
                if let Some(found) = found {
                    for (&v, &p) in s.moving.iter().zip(&found) {
                        vertices[v as usize] = p;
                    }
                    moved.extend_from_slice(s.moving);
                    self.since.moved(s.moving);
                } else {
                    failed[s.slot] = self.since.now();
                }
            }
        }
        moved
    }
}

/// Compass search moving the vertices `moving` (each `groups` mask a set of them stepping
/// together, tried in order, each along every compass direction) to raise the smallest scaled
/// Jacobian of `quads` (all the quads they are corners of), then, at an equal one, their
/// smallest shape, both capped at `bar`; every quad held to the floors of `setup`. True when a
/// vertex moved.
pub(crate) fn compass(
    moving: &[usize],
    groups: &[u32],
    quads: &[u32],
    vertices: &mut [Point],
    setup: &Setup,
    bar: f64,
) -> bool {
    let Some(mut best) = corners_value(quads, vertices, setup, bar) else {
        return false;
    };
    let start: Vec<Point> = moving.iter().map(|&v| vertices[v]).collect();
    // The mean distance from a moving vertex to the other corners of its quads.
    let (mut sum, mut count) = (0.0, 0usize);
    for (&v, &at) in moving.iter().zip(&start) {
        for &q in quads {
            let corners = setup.quads[q as usize];
            if corners.contains(&(v as u32)) {
                for u in corners {
                    if u as usize != v {
                        sum += vertices[u as usize].distance_squared(at).sqrt();
                        count += 1;
                    }
                }
            }
        }
    }
    let mut step = FIRST_STEP * sum / count.max(1) as f64;
    let mut halvings = 0;
    let mut here = start.clone();
    while halvings <= HALVINGS && best.1 < bar {
        let mut stepped = false;
        'search: for &group in groups {
            for (dx, dy) in DIRECTIONS {
                for (k, &v) in moving.iter().enumerate() {
                    if group & (1 << k) != 0 {
                        vertices[v] = Point::new(here[k].x + dx * step, here[k].y + dy * step);
                    }
                }
                match corners_value_above(quads, vertices, setup, bar, best) {
                    Some(f) => {
                        best = f;
                        stepped = true;
                        break 'search;
                    }
                    _ => {
                        for (&v, &p) in moving.iter().zip(&here) {
                            vertices[v] = p;
                        }
                    }
                }
            }
        }
        if stepped {
            for (p, &v) in here.iter_mut().zip(moving) {
                *p = vertices[v];
            }
        } else {
            step *= 0.5;
            halvings += 1;
        }
    }
    moving.iter().zip(&start).any(|(&v, &p)| vertices[v] != p)
}

/// What the repair raises for `quads` over `vertices`: their smallest scaled Jacobian, then
/// their smallest shape, both capped at `bar` (compared in that order); `None` where a quad is
/// invalid or under a floor of `setup`.
pub(crate) fn corners_value(
    quads: &[u32],
    vertices: &[Point],
    setup: &Setup,
    bar: f64,
) -> Option<(f64, f64)> {
    corners_value_above(
        quads,
        vertices,
        setup,
        bar,
        (f64::NEG_INFINITY, f64::NEG_INFINITY),
    )
}

/// [`corners_value`] where it is above `best` (a higher smallest scaled Jacobian, or the same
/// and a higher smallest shape), else `None`: the searches' test of a trial point, which stops
/// scoring at the first quad that rules it out (both smallest values only fall, quad after
/// quad).
pub(crate) fn corners_value_above(
    quads: &[u32],
    vertices: &[Point],
    setup: &Setup,
    bar: f64,
    best: (f64, f64),
) -> Option<(f64, f64)> {
    let (mut jacobian, mut shape) = (bar, bar);
    let mut above = true;
    setup.visit_feasible(quads, vertices, |p, quality| {
        let Some((_, s)) = quality else {
            above = false;
            return false;
        };
        shape = shape.min(s);
        // The scaled Jacobian is at least the shape: only a shape under the bar can leave it
        // there.
        if s < bar {
            jacobian = jacobian.min(crate::energy::jacobian_under(p, jacobian));
        }
        above = jacobian > best.0 || (jacobian == best.0 && shape > best.1);
        above
    });
    above.then_some((jacobian, shape))
}

/// The 3 × 3 grid of points (row by row) of the repairs' tests: with every point pinned but the
/// middle one and its right neighbour, and each of the four quads held to the repair's floors,
/// moving one free vertex at a time stalls under [`REPAIR_JACOBIAN`].
#[cfg(test)]
pub(crate) fn stalling_grid() -> Vec<Point> {
    [
        (0.31, 0.1),
        (0.69, -0.22),
        (1.87, -0.15),
        (0.11, 1.32),
        (1.16, 1.21),
        (1.7, 1.18),
        (0.31, 2.34),
        (1.33, 1.68),
        (1.74, 2.35),
    ]
    .map(|(x, y)| Point::new(x, y))
    .to_vec()
}

#[cfg(test)]
mod tests {
    use super::{
        compass, corners_value, corners_value_above, stalling_grid, Unchanged, NEVER, REPAIR_FLOOR,
        REPAIR_JACOBIAN,
    };
    use crate::{Metric, Setup};
    use imesh_geom::Point;
    use proptest::prelude::*;

    proptest! {
        /// The value above a best is the value where it beats the best, and nothing where it
        /// does not, however early the scoring stopped: on a jittered 3 × 3 grid (some quads
        /// invalid or under a floor), against bests on either side of it, level with it in
        /// scaled Jacobian, and equal to it.
        #[test]
        fn the_value_above_a_best_is_the_value_where_it_beats_it(
            jitter in proptest::collection::vec((-0.45f64..0.45, -0.45f64..0.45), 9),
            best in (0.0f64..0.6, 0.0f64..0.6),
            tie in 0u8..3,
        ) {
            let vertices: Vec<Point> = stalling_grid()
                .iter()
                .zip(&jitter)
                .map(|(p, &(dx, dy))| Point::new(p.x + dx, p.y + dy))
                .collect();
            let quads = [[0, 1, 4, 3], [1, 2, 5, 4], [3, 4, 7, 6], [4, 5, 8, 7]];
            let floors = [0.2, 0.0, 0.1, 0.0];
            let setup = Setup::held(&quads, Metric::Shape, [&[0.0; 4], &floors, &floors]);
            let all = [0, 1, 2, 3];
            let value = corners_value(&all, &vertices, &setup, REPAIR_JACOBIAN);
            // Or the same smallest scaled Jacobian as the value, and either shape; or the value.
            let best = match (value, tie) {
                (Some((jacobian, _)), 1) => (jacobian, best.1),
                (Some(value), 2) => value,
                _ => best,
            };
            let beats = value.filter(|f| f.0 > best.0 || (f.0 == best.0 && f.1 > best.1));
            prop_assert_eq!(
                corners_value_above(&all, &vertices, &setup, REPAIR_JACOBIAN, best),
                beats
            );
        }
    }

    fn corners(quad: &[u32; 4], vertices: &[Point]) -> [[f64; 2]; 4] {
        quad.map(|v| [vertices[v as usize].x, vertices[v as usize].y])
    }

    /// The smallest scaled Jacobian of `quads` over `vertices`.
    fn worst(quads: &[[u32; 4]], vertices: &[Point]) -> f64 {
        quads
            .iter()
            .map(|q| imesh_quality::quad::scaled_jacobian(&corners(q, vertices)))
            .fold(f64::INFINITY, f64::min)
    }

    /// A failed search is skipped until a corner of one of its quads moves, and only then: not
    /// before it has failed, nor after a move of a vertex elsewhere.
    #[test]
    fn a_failed_search_is_skipped_until_its_corners_move() {
        let corners = [[0, 1, 4, 3], [1, 2, 5, 4], [3, 4, 7, 6], [4, 5, 8, 7]];
        let mut since = Unchanged::new(10);
        assert!(!since.unchanged(NEVER, &[0, 1], &corners));
        since.moved(&[9]);
        let failed = since.now();
        assert!(since.unchanged(failed, &[0, 1], &corners));
        since.moved(&[6, 9]); // corner of quad 2 only
        assert!(since.unchanged(failed, &[0, 1], &corners));
        assert!(!since.unchanged(failed, &[0, 2], &corners));
        since.moved(&[5]);
        assert!(!since.unchanged(failed, &[1], &corners));
        assert!(since.unchanged(since.now(), &[1], &corners));
    }

    /// Four quads on a 3 × 3 grid of points, all pinned but the middle one and its right
    /// neighbour, each quad held to the repair's floors: moving one free vertex at a time stalls
    /// under the bar (every move that opens the worst corner takes another quad under its
    /// floor), and moving the two together gets past it.
    #[test]
    fn moving_corners_together_passes_where_one_at_a_time_stalls() {
        let mut vertices = stalling_grid();
        let quads = [[0, 1, 4, 3], [1, 2, 5, 4], [3, 4, 7, 6], [4, 5, 8, 7]];
        let floors = |metric: fn(&[[f64; 2]; 4]) -> f64| -> Vec<f64> {
            quads
                .iter()
                .map(|q| metric(&corners(q, &vertices)).min(REPAIR_FLOOR))
                .collect()
        };
        let (shape_floors, jacobian_floors) = (
            floors(imesh_quality::quad::shape),
            floors(imesh_quality::quad::scaled_jacobian),
        );
        let setup = Setup::held(
            &quads,
            Metric::Shape,
            [&[0.0; 4], &shape_floors, &jacobian_floors],
        );
        let free = [4usize, 5];
        let quads_of = |v: usize| -> Vec<u32> {
            (0..4u32)
                .filter(|&q| quads[q as usize].contains(&(v as u32)))
                .collect()
        };
        let one = |v: usize, vertices: &mut [Point]| {
            compass(&[v], &[1], &quads_of(v), vertices, &setup, REPAIR_JACOBIAN)
        };
        // One at a time, until none moves.
        for _ in 0..100 {
            if !free
                .iter()
                .fold(false, |moved, &v| one(v, &mut vertices) | moved)
            {
                break;
            }
        }
        let stalled = worst(&quads, &vertices);
        assert!(stalled < REPAIR_JACOBIAN - 0.05, "{stalled}");
        assert!(free.iter().all(|&v| !one(v, &mut vertices)));
        // Together.
        assert!(compass(
            &free,
            &[0b11],
            &[0, 1, 2, 3],
            &mut vertices,
            &setup,
            REPAIR_JACOBIAN
        ));
        let after = worst(&quads, &vertices);
        assert!(after > stalled + 0.05, "{stalled} → {after}");
        // Every quad valid and above its floors.
        assert!((0..4).all(|q| setup
            .term(q, &quads[q].map(|v| vertices[v as usize]))
            .is_some()));
    }
}
