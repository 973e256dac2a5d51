//! The quads still poor after the repairs, each with its whole neighbourhood moved at once.
//!
//! The repairs move one vertex at a time (or a quad's free corners by one step together), and
//! a boundary vertex only along its curve with everything else still. A quad pinned in a small
//! region (a kite of four quads in a 37° wedge, a row of quads in a strip thinner than a quad)
//! is held by its neighbours: raising its corners spoils the quad next to it, whose other
//! corners would have to move too. Here every free vertex and every slider of the quads around
//! a poor quad is one variable of a single [`Powell`] minimisation of how far the patch's
//! quads are under the bar ([`Shortfall`]: the Euclidean norms of the scaled Jacobians' and the
//! shapes' shortfalls), every quad held to the floors of the repair. The result is kept only
//! when the patch's smallest scaled Jacobian, then its smallest shape, rose (the worst of
//! neither falls), and when the energy it adds fits in what the optimiser may still give back.
//!
//! Measured with the defaults against the smallest scaled Jacobian's and shape's shortfalls
//! plus a tenth of the mean one, worst shape: camera 0.450 → 0.480, pyvista 0.449 → 0.473,
//! grass 0.345 → 0.388, astronaut 0.490 → 0.500, brick 0.459 → 0.462, coffee 0.442 → 0.431,
//! aloe 0.283 → 0.294. The norms of powers 1.5, 3 and 4 did less on the sum of the seven (the
//! power 1 spreads the gain and left most worst quads where they were; 8 gave astronaut
//! 0.490 → 0.427).
//!
//! The vertices of G' (corners and junctions of the boundaries) are held by the rest of the
//! optimiser; here, given a reach ([`Reach`], `OptimOptions::corner_reach`), they move too, as
//! free vertices within that distance of where the optimiser found them, pass after pass: a
//! quad corner at a G' vertex whose sector it shares with other quads keeps a share of the
//! sector's angle wherever everything else goes, and only the vertex itself can widen it.
//!
//! The same patches lift the quads of poor shape-and-size last ([`Aim::Quality`]): a quad a
//! third of the mean area at a tip or in a strip grows only if its neighbours give it room, and
//! they are held there by their own corners and by the energy, in which it is one term among
//! thousands.

use std::collections::VecDeque;

use imesh_geom::Point;
use rayon::prelude::*;

use crate::batches::{Scheduler, Subproblem};
use crate::repair::{corners_value, held_up_to, REPAIR_FLOOR, REPAIR_JACOBIAN};
use crate::slide::Sliders;
use crate::variables::Rows;
use crate::{Powell, Setup};

/// Powell iterations per patch, and its first steps (in the movers' scales: a free vertex's
/// mean edge, half a slider's gap).
const ITERATIONS: u64 = 8;
const FIRST_STEP: f64 = 0.05;

/// Raising quality ([`Aim::Quality`]): the patch's cost adds this times the energy of its
/// quads to the norm of their shortfalls, so that the quads over the bar are not spent for
/// little. Measured with the defaults against 0, 0.1 and 0.3 (quads under 0.35 lifted, 8
/// iterations), quads under 0.25 after and mean shape-and-size: coins 11 / 0.8659, 11 /
/// 0.8680, 12 / 0.8682 (54 / 0.8689 before); MRI 56 / 0.9084, 56 / 0.9112, 55 / 0.9115 (80 /
/// 0.9122); camera 119 / 0.9072, 112 / 0.9095, 116 / 0.9104 (156 / 0.9108).
const QUALITY_ENERGY_WEIGHT: f64 = 0.2;

/// Raising quality: Powell iterations of a patch, and most cost evaluations of each line
/// search (the corners' repair: 8 and 40). Measured with the defaults at 2, 4 and 8 iterations
/// (6 evaluations), quads under 0.25 after: stardist 102, 83, 76; brick 294, 261, 237; MRI 55,
/// 50, 52; coins 15, 13, 12; optimiser time from 4 to 8 iterations +1 % to +22 %, from 2 to 4
/// +2 % to +7 %. At 40 evaluations, the same quads lifted in twice the time.
const QUALITY_ITERATIONS: u64 = 4;
const QUALITY_LINE_EVALUATIONS: usize = 6;

/// A slider stays this share of its starting gap away from either neighbour on its chain.
const MARGIN: f64 = 0.05;

/// The poor quads a pass after the first solves in the optimiser ([`Budget::later`]): the
/// poorest only. Later passes are for the worst quads, and a graded mesh leaves thousands
/// under the bar, whose second pass took as long as the first for nothing (graded MRI and
/// brick: optimiser time +46 % and +38 %).
pub(crate) const LATER_PASS_QUADS: usize = 64;

/// Most patches solved side by side ([`repair_jointly`]). A constant, not the thread count, so
/// that the batches depend on nothing else.
pub(crate) const BATCH: usize = 32;

/// How far a G' vertex may move ([`repair_jointly`]): within `reach` of `origin`, along the
/// axes `axes` leaves free (1 free, 0 held: a vertex on the domain's border moves along it).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Reach {
    pub origin: Point,
    pub reach: f64,
    pub axes: Point,
}

/// One moving point of a patch; `at` is its index among the patch's points.
#[derive(Clone, Copy, Debug)]
enum Mover {
    /// A free quad vertex at `base`, moved by `scale` times its two variables.
    Free { at: u32, base: Point, scale: f64 },
    /// A G' vertex (a corner or a junction of the boundaries, which nothing else moves) at
    /// `base`, moved like a free vertex along the free `axes` of its [`Reach`], never farther
    /// than `reach` from `origin`, where the optimiser found it (passes and patches after the
    /// first start where the last left it).
    Corner {
        at: u32,
        base: Point,
        scale: f64,
        origin: Point,
        reach: f64,
        axes: Point,
    },
    /// Slider `slider` at `base` along its chain, moved by `scale` times its variable, at least
    /// `margin` from its neighbours along the chain (`ends`).
    Slider {
        slider: u32,
        at: u32,
        base: f64,
        scale: f64,
        margin: f64,
        ends: [Along; 2],
    },
}

/// Where a slider's neighbour on its chain is: held where it is, or the patch's mover `k`.
#[derive(Clone, Copy, Debug)]
enum Along {
    Held(f64),
    Mover(usize),
}

/// What a joint repair raises, up to its bar.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Aim {
    /// The corners of the quads whose shape is under the bar: a patch's smallest scaled
    /// Jacobian, then its smallest shape ([`corners_value`]).
    Corners(f64),
    /// The quality (the optimiser's metric) of the quads under `poor`: a patch's smallest, up
    /// to `bar`. Every quad is held to its quality up to the bar, and its shape and scaled
    /// Jacobian up to [`REPAIR_JACOBIAN`](crate::REPAIR_JACOBIAN).
    Quality { poor: f64, bar: f64 },
}

impl Aim {
    /// The bar.
    fn bar(self) -> f64 {
        let (Aim::Corners(bar) | Aim::Quality { bar, .. }) = self;
        bar
    }

    /// The quads scoring under this ([`Aim::score`]) are repaired.
    fn poor(self) -> f64 {
        let (Aim::Corners(poor) | Aim::Quality { poor, .. }) = self;
        poor
    }

    /// Most Powell iterations of a patch.
    fn iterations(self) -> u64 {
        match self {
            Aim::Corners(_) => ITERATIONS,
            Aim::Quality { .. } => QUALITY_ITERATIONS,
        }
    }

    /// The minimiser of a patch.
    fn powell(self) -> Powell {
        match self {
            Aim::Corners(_) => Powell::new(FIRST_STEP),
            Aim::Quality { .. } => {
                Powell::new(FIRST_STEP).with_line_search(1e-2, QUALITY_LINE_EVALUATIONS)
            }
        }
    }

    /// How poor quad `q` of `points` is, by what the aim raises (its shape, or its quality).
    fn score(self, setup: &Setup, points: &[Point], q: usize) -> f64 {
        match self {
            Aim::Corners(_) => setup.shape(points, q),
            Aim::Quality { .. } => setup.value(points, q),
        }
    }

    /// What the aim raises over `quads` of `points`, compared in order; `None` where a quad
    /// is invalid or under a floor of `setup`.
    fn value(self, quads: &[u32], points: &[Point], setup: &Setup) -> Option<(f64, f64)> {
        match self {
            Aim::Corners(bar) => corners_value(quads, points, setup, bar),
            Aim::Quality { bar, .. } => {
                let mut worst = Some(bar);
                setup.visit_feasible(quads, points, |_, quality| {
                    worst = worst.zip(quality).map(|(w, (s, _))| w.min(s));
                    worst.is_some()
                });
                worst.map(|w| (w, 0.0))
            }
        }
    }

    /// The squared shortfalls under the bar of a feasible quad `p` whose metric and shape are
    /// `quality`: of its scaled Jacobian and its shape, or of its quality alone.
    fn shortfalls(self, p: &[Point; 4], (s, shape): (f64, f64)) -> [f64; 2] {
        match self {
            Aim::Corners(bar) if shape < bar => {
                let j = crate::energy::jacobian_under(p, bar);
                [(bar - j).max(0.0).powi(2), (bar - shape) * (bar - shape)]
            }
            Aim::Quality { bar, .. } => [(1.0 - s) * (1.0 - s), (bar - s).max(0.0).powi(2)],
            Aim::Corners(_) => [0.0; 2],
        }
    }

    /// A patch's cost from the sums of its quads' [`Aim::shortfalls`].
    fn combine(self, [a, b]: [f64; 2]) -> f64 {
        match self {
            Aim::Corners(_) => a.sqrt() + b.sqrt(),
            Aim::Quality { .. } => QUALITY_ENERGY_WEIGHT * a + b.sqrt(),
        }
    }
}

/// Moves the free vertices (not `fixed`) and the sliders around each poor quad of `aim` (the
/// poorest first) together, by [`Powell`]'s method, to raise what the aim raises (the patch's
/// smallest scaled Jacobian and then its smallest shape, [`corners_value`], or its smallest
/// quality), every quad held to the floors of `setup` (and, raising quality, to where it
/// stands), the energy the patches add (over all of them) at most `slack`; at most
/// `B` patches side by side ([`BATCH`] in the optimiser). `around` lists the quads around each
/// vertex of `points`. Returns how many patches moved.
///
/// Up to `budget.passes` passes: a patch is solved with its neighbours where the patches before
/// it left them, and once they have moved on it may reach further. The first pass takes the
/// `budget.first` poorest quads, a pass after it the `budget.later` poorest the last left poor,
/// each quad held to where the last pass left it too (up to
/// [`REPAIR_FLOOR`](crate::REPAIR_FLOOR)); the passes stop at one that keeps no patch or leaves
/// the worst (by the aim's score) where it was.
///
/// Within a pass, a patch is solved ahead of earlier ones that must wait ([`Scheduler::new`])
/// where neither reads what the other moves, and its moves are kept or dropped as it comes: the
/// slack is then spent in another order than the poor quads'. Whether that changed which
/// patches fit is checked once all are solved; if it did (never on the fixtures), the pass runs
/// again from its start, taking the patches only in order ([`Scheduler::in_order`]). Either way
/// the result is that of solving the patches one after the other.
#[allow(clippy::too_many_arguments)]
pub(crate) fn repair_jointly<const B: usize>(
    points: &mut [Point],
    around: &Rows<u32>,
    fixed: &[bool],
    reach: &[Reach],
    sliders: &mut Sliders,
    setup: &Setup,
    aim: Aim,
    budget: Budget,
) -> usize {
    let slider_of = sliders.slider_of_vertices(points.len());
    let (mut moved, mut slack, bar) = (0, budget.slack, aim.bar());
    // Each pass holds every quad to the repair's floors and to where the last pass left it,
    // up to REPAIR_FLOOR: a pass never takes back what the last gave a quad under it. Raising
    // quality, every quad is held from the start to where it stands.
    let mut floors = Floors {
        quality: setup.quality_floors.to_vec(),
        shape: setup.shape_floors.to_vec(),
        jacobian: setup.jacobian_floors.to_vec(),
    };
    for pass_index in 0..budget.passes {
        // The scores read the points only, not the floors.
        let mut poor: Vec<(f64, u32)> = (0..setup.quads.len() as u32)
            .map(|q| (aim.score(setup, points, q as usize), q))
            .filter(|&(s, _)| s < aim.poor())
            .collect();
        if pass_index == 0 && poor.len() > budget.graded {
            break;
        }
        poor.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        if pass_index > 0 || matches!(aim, Aim::Quality { .. }) {
            floors.raise(points, setup, aim);
        }
        let setup = &Setup {
            quality_floors: &floors.quality,
            shape_floors: &floors.shape,
            jacobian_floors: &floors.jacobian,
            ..*setup
        };
        let context = Context {
            around,
            fixed,
            reach,
            slider_of: &slider_of,
            setup,
        };
        if pass_index > 0 {
            poor.truncate(budget.later);
        } else {
            poor.truncate(budget.first);
        }
        let candidates: Vec<Candidate> = {
            let sliders = &*sliders;
            poor.par_iter()
                .map(|&(_, q)| context.candidate(q, sliders))
                .collect()
        };
        let (kept, spent) = pass::<B>(&context, &candidates, points, sliders, aim, slack);
        (moved, slack) = (moved + kept, slack - spent);
        // Later passes are for the worst quads: once a pass leaves the worst where it was, the
        // next would mostly spend time on the others.
        let worst_before = poor.first().map_or(bar, |&(s, _)| s);
        let worst_after = poor
            .iter()
            .map(|&(_, q)| aim.score(setup, points, q as usize))
            .fold(bar, f64::min);
        if kept == 0 || worst_after <= worst_before {
            break;
        }
    }
    moved
}

/// The floors a joint repair holds each quad to.
struct Floors {
    quality: Vec<f64>,
    shape: Vec<f64>,
    jacobian: Vec<f64>,
}

impl Floors {
    /// Raises each quad's shape and scaled Jacobian floors to where it is now, up to
    /// [`REPAIR_FLOOR`]; raising quality, up to [`REPAIR_JACOBIAN`], and its quality floor to
    /// where it is now, up to the bar.
    fn raise(&mut self, points: &[Point], setup: &Setup, aim: Aim) {
        // Raising quality trades no corner under the worst-quad targets.
        let quality = matches!(aim, Aim::Quality { .. });
        let cap = if quality {
            REPAIR_JACOBIAN
        } else {
            REPAIR_FLOOR
        };
        self.quality
            .par_iter_mut()
            .zip(self.shape.par_iter_mut())
            .zip(self.jacobian.par_iter_mut())
            .enumerate()
            .for_each(|(q, ((quality_floor, shape), jacobian))| {
                let [now_shape, now_jacobian] = held_up_to(points, &setup.quads[q], cap);
                (*shape, *jacobian) = (shape.max(now_shape), jacobian.max(now_jacobian));
                if quality {
                    let now = setup.value(points, q).min(aim.bar());
                    *quality_floor = quality_floor.max(now);
                }
            });
    }
}

/// How far [`repair_jointly`] may go.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Budget {
    /// The energy its patches may add, over all of them and all passes.
    pub slack: f64,
    /// Its most passes.
    pub passes: usize,
    /// The most poor quads the first pass takes, the poorest (all of them in the corners'
    /// repair; a share of the quads when raising quality, [`crate::QUALITY_SHARE`]).
    pub first: usize,
    /// The most poor quads a pass after the first takes, the poorest ([`LATER_PASS_QUADS`] in
    /// the optimiser).
    pub later: usize,
    /// With more poor quads than this at the start, none is repaired: the mesh is graded by
    /// design, its poor quads many and small (all of them in the corners' repair;
    /// [`crate::GRADED_SHARE`] of the quads when raising quality).
    pub graded: usize,
}

/// One pass of [`repair_jointly`] over `candidates`: how many patches moved, and the energy
/// they added.
fn pass<const B: usize>(
    context: &Context,
    candidates: &[Candidate],
    points: &mut [Point],
    sliders: &mut Sliders,
    aim: Aim,
    slack: f64,
) -> (usize, f64) {
    let (start, start_sliders) = (points.to_vec(), sliders.clone());
    let run = |scheduler, points: &mut [Point], sliders: &mut Sliders| {
        run::<B>(context, candidates, scheduler, points, sliders, aim, slack)
    };
    let (mut moved, mut log) = run(Scheduler::new(points.len()), points, sliders);
    if !kept_in_order(&mut log, slack) {
        points.copy_from_slice(&start);
        *sliders = start_sliders;
        (moved, log) = run(Scheduler::in_order(points.len()), points, sliders);
    }
    let spent = log
        .iter()
        .filter(|&&(_, _, kept)| kept)
        .map(|&(_, added, _)| added)
        .sum();
    (moved, spent)
}

/// Solves the patches of `candidates` (in order, at most `B` side by side, as `scheduler` takes
/// them) and keeps those whose corners rose and whose added energy fits in what is left of
/// `slack`. Returns how many moved, and for each patch whose corners rose: its place in
/// `candidates`, the energy it adds, and whether it was kept.
fn run<const B: usize>(
    context: &Context,
    candidates: &[Candidate],
    mut scheduler: Scheduler,
    points: &mut [Point],
    sliders: &mut Sliders,
    aim: Aim,
    mut slack: f64,
) -> (usize, Vec<(usize, f64, bool)>) {
    let setup = context.setup;
    let mut queue: VecDeque<usize> = (0..candidates.len()).collect();
    let mut moved = 0;
    let mut log = Vec::new();
    while !queue.is_empty() {
        let now = scheduler.take(
            &mut queue,
            B,
            |&c, reads| reads.extend_from_slice(&candidates[c].reads),
            |&c, moves| moves.extend_from_slice(&candidates[c].movers),
            |&c| {
                let c = &candidates[c];
                c.movers.is_empty() || aim.score(setup, points, c.quad as usize) >= aim.poor()
            },
        );
        let (view, sliders_view) = (&*points, &*sliders);
        let solved: Vec<(Patch, Option<Outcome>)> = now
            .par_iter()
            .map(|&c| {
                let patch = context.patch(&candidates[c], view, sliders_view);
                let outcome = patch.solve(view, sliders_view, setup, aim);
                (patch, outcome)
            })
            .collect();
        for (&c, (patch, outcome)) in now.iter().zip(solved) {
            let Some(outcome) = outcome else {
                continue;
            };
            let fits = outcome.added <= slack;
            log.push((c, outcome.added, fits));
            if fits {
                slack -= outcome.added;
                moved += 1;
                for (m, &along) in patch.movers.iter().zip(&outcome.along) {
                    if let Mover::Slider { slider, .. } = *m {
                        sliders.place(slider as usize, along);
                    }
                    points[patch.sub.points[m.at()] as usize] = outcome.points[m.at()];
                }
            }
        }
    }
    (moved, log)
}

/// Whether spending `slack` on the patches of `log` ([`run`]'s) in the poor quads' order keeps
/// the same ones.
fn kept_in_order(log: &mut [(usize, f64, bool)], mut slack: f64) -> bool {
    log.sort_unstable_by_key(|&(c, _, _)| c);
    log.iter().all(|&(_, added, kept)| {
        let fits = added <= slack;
        if fits {
            slack -= added;
        }
        fits == kept
    })
}

/// A poor quad and what its patch is, whatever the points: its movers (the free vertices and
/// the sliders among the corners of the quads around its corners), the quads they are corners
/// of, and the points its search reads (those quads' corners and the sliders' neighbours on
/// their chains).
struct Candidate {
    quad: u32,
    movers: Vec<u32>,
    touched: Vec<u32>,
    reads: Vec<u32>,
}

/// The mesh's fixed data a patch is planned from.
struct Context<'a> {
    around: &'a Rows<u32>,
    fixed: &'a [bool],
    /// Per vertex, how far from where it may move if it is fixed and no slider (a G' vertex);
    /// empty: none moves.
    reach: &'a [Reach],
    slider_of: &'a [u32],
    setup: &'a Setup<'a>,
}

/// A poor quad's patch: every quad a mover is a corner of, as a problem of its own, and the
/// movers.
struct Patch {
    sub: Subproblem,
    movers: Vec<Mover>,
}

/// Where a solved patch's points went, and its movers along their chains (a free one's entry
/// unused, a corner's its squared distance from its origin), and the energy that added.
struct Outcome {
    points: Vec<Point>,
    along: Vec<f64>,
    added: f64,
}

impl Context<'_> {
    /// Poor quad `q`'s candidate patch.
    fn candidate(&self, q: u32, sliders: &Sliders) -> Candidate {
        let setup = self.setup;
        let corners = setup.quads[q as usize];
        // The corners of the quads around the poor quad's corners that may move.
        let mut movers: Vec<u32> = corners
            .iter()
            .flat_map(|&v| self.around.row(v as usize))
            .flat_map(|&r| setup.quads[r as usize])
            .collect();
        movers.sort_unstable();
        movers.dedup();
        movers.retain(|&v| {
            !self.fixed[v as usize] || self.slider_of[v as usize] != u32::MAX || self.reach(v) > 0.0
        });
        let mut touched: Vec<u32> = movers
            .iter()
            .flat_map(|&v| self.around.row(v as usize).iter().copied())
            .collect();
        touched.sort_unstable();
        touched.dedup();
        let mut reads: Vec<u32> = touched
            .iter()
            .flat_map(|&r| setup.quads[r as usize])
            .chain(corners)
            .chain(
                movers
                    .iter()
                    .filter(|&&v| self.slider_of[v as usize] != u32::MAX)
                    .flat_map(|&v| self.ends(v, sliders).map(|(u, _)| u)),
            )
            .collect();
        reads.sort_unstable();
        reads.dedup();
        Candidate {
            quad: q,
            movers,
            touched,
            reads,
        }
    }

    /// How far vertex `v` may move from its origin if it is fixed and no slider.
    fn reach(&self, v: u32) -> f64 {
        self.reach.get(v as usize).map_or(0.0, |r| r.reach)
    }

    /// The quad vertices before and after slider vertex `v` on its chain, and their sliders.
    fn ends(&self, v: u32, sliders: &Sliders) -> [(u32, Option<u32>); 2] {
        sliders.neighbours(self.slider_of[v as usize] as usize)
    }

    /// Candidate `c`'s patch over `points` and `sliders` as they are.
    fn patch(&self, c: &Candidate, points: &[Point], sliders: &Sliders) -> Patch {
        let setup = self.setup;
        let sub = Subproblem::new(&c.touched, setup);
        let slider_mover = |slider: u32| {
            c.movers
                .iter()
                .position(|&v| self.fixed[v as usize] && self.slider_of[v as usize] == slider)
        };
        let movers = c
            .movers
            .iter()
            .map(|&v| {
                // A mover is a corner of the quads it touches.
                let at = sub.index(v).unwrap_or(usize::MAX) as u32;
                let free = !self.fixed[v as usize];
                if free || self.slider_of[v as usize] == u32::MAX {
                    let base = points[v as usize];
                    let (mut sum, mut count) = (0.0, 0usize);
                    for &r in self.around.row(v as usize) {
                        for u in setup.quads[r as usize] {
                            if u != v {
                                sum += points[u as usize].distance_squared(base).sqrt();
                                count += 1;
                            }
                        }
                    }
                    let scale = sum / count.max(1) as f64;
                    if free {
                        Mover::Free { at, base, scale }
                    } else {
                        let Reach {
                            origin,
                            reach,
                            axes,
                        } = self.reach[v as usize];
                        Mover::Corner {
                            at,
                            base,
                            scale,
                            origin,
                            reach,
                            axes,
                        }
                    }
                } else {
                    let slider = self.slider_of[v as usize];
                    let [lo, at_now, hi] = sliders.gap(slider as usize);
                    let [(_, before), (_, after)] = self.ends(v, sliders);
                    let end = |neighbour: Option<u32>, held: f64| match neighbour
                        .and_then(slider_mover)
                    {
                        Some(k) => Along::Mover(k),
                        None => Along::Held(held),
                    };
                    Mover::Slider {
                        slider,
                        at,
                        base: at_now,
                        scale: 0.5 * (hi - lo),
                        margin: MARGIN * (hi - lo),
                        ends: [end(before, lo), end(after, hi)],
                    }
                }
            })
            .collect();
        Patch { sub, movers }
    }
}

impl Patch {
    /// Solves the patch over `points` and `sliders` as they are: its outcome if its smallest
    /// scaled Jacobian, then its smallest shape, rose.
    fn solve(
        &self,
        points: &[Point],
        sliders: &Sliders,
        setup: &Setup,
        aim: Aim,
    ) -> Option<Outcome> {
        let setup = self.sub.setup(setup);
        let all: Vec<u32> = (0..self.sub.len() as u32).collect();
        let mut local = self.sub.gather(points);
        let start = aim.value(&all, &local, &setup)?;
        let energy_before = energy(&all, &local, &setup);
        let n = self.movers.iter().map(Mover::variables).sum();
        let mut along = vec![0.0; self.movers.len()];
        let mut shortfall = Shortfall::new(&self.movers, setup.quads, n);
        let cost = |x: &Vec<f64>| -> f64 {
            shortfall.at(
                x,
                &self.movers,
                &mut local,
                &mut along,
                sliders,
                &setup,
                aim,
            )
        };
        let (x, _) = aim.powell().minimise(cost, vec![0.0; n], aim.iterations());
        let better = place(&self.movers, &x, &mut local, &mut along, sliders)
            && aim
                .value(&all, &local, &setup)
                .is_some_and(|f| f.0 > start.0 || (f.0 == start.0 && f.1 > start.1));
        better.then(|| Outcome {
            added: energy(&all, &local, &setup) - energy_before,
            points: local,
            along,
        })
    }
}

impl Mover {
    /// Its index among its patch's points.
    fn at(&self) -> usize {
        let (Mover::Free { at, .. } | Mover::Corner { at, .. } | Mover::Slider { at, .. }) = *self;
        at as usize
    }

    /// Puts it at its variables, the first of `x` (into `points`, and a slider's position
    /// along its chain into `along`, a corner's squared distance from its origin).
    fn place(&self, x: &[f64], points: &mut [Point], along: &mut f64, sliders: &Sliders) {
        match *self {
            Mover::Free { at, base, scale } => {
                points[at as usize] = Point::new(base.x + scale * x[0], base.y + scale * x[1]);
            }
            Mover::Corner {
                at,
                base,
                scale,
                origin,
                axes,
                ..
            } => {
                let (dx, dy) = (axes.x * scale * x[0], axes.y * scale * x[1]);
                let p = Point::new(base.x + dx, base.y + dy);
                *along = p.distance_squared(origin);
                points[at as usize] = p;
            }
            Mover::Slider {
                slider,
                at,
                base,
                scale,
                ..
            } => {
                *along = base + scale * x[0];
                points[at as usize] = sliders.point(slider as usize, *along);
            }
        }
    }

    /// Its number of variables: a free vertex's or a corner's two coordinates, a slider's
    /// position.
    fn variables(&self) -> usize {
        match self {
            Mover::Free { .. } | Mover::Corner { .. } => 2,
            Mover::Slider { .. } => 1,
        }
    }
}

/// Puts the movers at `x` (into `points`, and each slider's position along its chain into
/// `along`); false when a slider comes within its margin of a neighbour (or passes it), or a
/// corner goes farther than its reach.
fn place(
    movers: &[Mover],
    x: &[f64],
    points: &mut [Point],
    along: &mut [f64],
    sliders: &Sliders,
) -> bool {
    let mut k = 0;
    for (m, a) in movers.iter().zip(along.iter_mut()) {
        m.place(&x[k..], points, a, sliders);
        k += m.variables();
    }
    clear_of_neighbours(movers, along)
}

/// Whether every slider among `movers` (at `along`) is more than its margin from either
/// neighbour on its chain, and every corner within its reach.
fn clear_of_neighbours(movers: &[Mover], along: &[f64]) -> bool {
    movers.iter().zip(along).all(|(m, &at)| match *m {
        Mover::Free { .. } => true,
        Mover::Corner { reach, .. } => at <= reach * reach,
        Mover::Slider { margin, ends, .. } => {
            let [lo, hi] = ends.map(|end| match end {
                Along::Held(a) => a,
                Along::Mover(k) => along[k],
            });
            at - lo > margin && hi - at > margin
        }
    })
}

/// How far a patch's quads are under the bar: the Euclidean norms of their scaled Jacobians'
/// and their shapes' shortfalls (the quads under `bar` only), or raising quality, the norm of
/// their quality's shortfalls plus a share of their energy ([`Aim::combine`]); infinite where
/// a quad is invalid or under a floor, or a slider too close to a neighbour. The smallest alone
/// leaves the line searches flat wherever two quads share it; the sum spreads the gain over
/// many quads instead of raising the worst.
///
/// Kept quad by quad: most of Powell's line searches move one variable, hence one mover, and
/// only the quads of the movers that moved since the last call are scored again. The sums run
/// over every quad in order, so the value is the one scoring them all gives, to the bit.
struct Shortfall {
    /// Per mover, the quads it is a corner of.
    quads_of: Rows<u32>,
    /// Per quad, its terms ([`Aim::shortfalls`]: squared shortfalls, 0 at or over the bar),
    /// `None` where it is invalid or under a floor.
    terms: Vec<Option<[f64; 2]>>,
    /// The variables of the last call (NaN before the first: every mover moves).
    last: Vec<f64>,
    /// Scratch: the quads to score, and whether each is listed.
    stale: Vec<u32>,
    listed: Vec<bool>,
}

impl Shortfall {
    fn new(movers: &[Mover], quads: &[[u32; 4]], variables: usize) -> Self {
        let points = quads.iter().flatten().max().map_or(0, |&v| v as usize + 1);
        let mut mover_of = vec![u32::MAX; points];
        for (k, m) in movers.iter().enumerate() {
            mover_of[m.at()] = k as u32;
        }
        let pairs: Vec<(u32, u32)> = quads
            .iter()
            .enumerate()
            .flat_map(|(q, quad)| quad.map(|v| (mover_of[v as usize], q as u32)))
            .filter(|&(m, _)| m != u32::MAX)
            .collect();
        Self {
            quads_of: Rows::from_pairs(movers.len(), &pairs),
            terms: vec![None; quads.len()],
            last: vec![f64::NAN; variables],
            stale: Vec::new(),
            listed: vec![false; quads.len()],
        }
    }

    /// The shortfall with the movers at `x` (put there, as [`place`] does).
    #[allow(clippy::too_many_arguments)]
    fn at(
        &mut self,
        x: &[f64],
        movers: &[Mover],
        points: &mut [Point],
        along: &mut [f64],
        sliders: &Sliders,
        setup: &Setup,
        aim: Aim,
    ) -> f64 {
        let mut k = 0;
        for (i, (m, a)) in movers.iter().zip(along.iter_mut()).enumerate() {
            let n = m.variables();
            // Not `==`: the NaN of the first call differs from everything.
            if x[k..k + n] != self.last[k..k + n] {
                m.place(&x[k..], points, a, sliders);
                for &q in self.quads_of.row(i) {
                    if !std::mem::replace(&mut self.listed[q as usize], true) {
                        self.stale.push(q);
                    }
                }
            }
            k += n;
        }
        self.last.copy_from_slice(x);
        let mut stale = self.stale.iter();
        setup.visit_feasible(&self.stale, points, |p, quality| {
            let Some(&q) = stale.next() else {
                return false;
            };
            self.listed[q as usize] = false;
            self.terms[q as usize] = quality.map(|quality| aim.shortfalls(p, quality));
            true
        });
        self.stale.clear();
        if !clear_of_neighbours(movers, along) {
            return f64::INFINITY;
        }
        let mut sums = [0.0; 2];
        for term in &self.terms {
            let Some([a, b]) = *term else {
                return f64::INFINITY;
            };
            sums[0] += a;
            sums[1] += b;
        }
        aim.combine(sums)
    }
}

/// The energy `Σ (1 − s)²` of `quads`.
fn energy(quads: &[u32], points: &[Point], setup: &Setup) -> f64 {
    quads
        .iter()
        .map(|&q| (1.0 - setup.value(points, q as usize)).powi(2))
        .sum()
}

#[cfg(test)]
mod tests {
    use super::{repair_jointly, Aim, Budget, Mover, Reach, Shortfall};
    use crate::repair::{compass, stalling_grid, REPAIR_FLOOR, REPAIR_JACOBIAN};
    use crate::slide::Sliders;
    use crate::variables::Rows;
    use crate::{Metric, Setup};
    use imesh_geom::Point;
    use imesh_quality::quad::{scaled_jacobian, shape};
    use proptest::prelude::*;

    /// The joint repair, solving a given number of patches side by side.
    type Repair =
        fn(&mut [Point], &Rows<u32>, &[bool], &[Reach], &mut Sliders, &Setup, Aim, Budget) -> usize;

    fn corners(quad: &[u32; 4], points: &[Point]) -> [[f64; 2]; 4] {
        quad.map(|v| [points[v as usize].x, points[v as usize].y])
    }

    /// The smallest of `metric` over `quads`.
    fn worst(quads: &[[u32; 4]], points: &[Point], metric: fn(&[[f64; 2]; 4]) -> f64) -> f64 {
        quads
            .iter()
            .map(|q| metric(&corners(q, points)))
            .fold(f64::INFINITY, f64::min)
    }

    /// The quads of an `n × n` grid of points, counter-clockwise.
    fn grid_quads(n: u32) -> Vec<[u32; 4]> {
        rectangle_quads(n, n)
    }

    /// The quads of a grid of points `w` wide and `h` high, row by row, counter-clockwise.
    fn rectangle_quads(w: u32, h: u32) -> Vec<[u32; 4]> {
        (0..h - 1)
            .flat_map(|j| {
                (0..w - 1).map(move |i| {
                    [
                        j * w + i,
                        j * w + i + 1,
                        (j + 1) * w + i + 1,
                        (j + 1) * w + i,
                    ]
                })
            })
            .collect()
    }

    /// The floors of the repair: every quad's shape and scaled Jacobian at [`REPAIR_FLOOR`] or
    /// where it is, if lower.
    fn floors(quads: &[[u32; 4]], points: &[Point]) -> (Vec<f64>, Vec<f64>) {
        quads
            .iter()
            .map(|q| {
                let p = corners(q, points);
                (
                    shape(&p).min(REPAIR_FLOOR),
                    scaled_jacobian(&p).min(REPAIR_FLOOR),
                )
            })
            .unzip()
    }

    fn setup<'a>(
        quads: &'a [[u32; 4]],
        floors: &'a (Vec<f64>, Vec<f64>),
        none: &'a [f64],
    ) -> Setup<'a> {
        Setup::held(quads, Metric::Shape, [none, &floors.0, &floors.1])
    }

    fn around(quads: &[[u32; 4]], n: usize) -> Rows<u32> {
        let pairs: Vec<(u32, u32)> = (0..quads.len() as u32)
            .flat_map(|q| quads[q as usize].map(|v| (v, q)))
            .collect();
        Rows::from_pairs(n, &pairs)
    }

    /// The repair's 3 × 3 grid, all pinned but the middle vertex and its right neighbour:
    /// one vertex at a time stalls under the bar, and the patch moved as a whole gets past it,
    /// every quad valid and held to its floors, the pinned vertices where they were.
    #[test]
    fn moving_the_whole_patch_passes_where_one_vertex_at_a_time_stalls() {
        let mut points = stalling_grid();
        let quads = grid_quads(3);
        let floors = floors(&quads, &points);
        let none = [0.0; 4];
        let setup = setup(&quads, &floors, &none);
        let mut fixed = vec![true; 9];
        (fixed[4], fixed[5]) = (false, false);
        let around = around(&quads, 9);
        for _ in 0..100 {
            let mut moved = false;
            for v in [4usize, 5] {
                let own: Vec<u32> = around.row(v).to_vec();
                moved |= compass(&[v], &[1], &own, &mut points, &setup, REPAIR_JACOBIAN);
            }
            if !moved {
                break;
            }
        }
        let stalled = worst(&quads, &points, scaled_jacobian);
        assert!(stalled < REPAIR_JACOBIAN - 0.05, "{stalled}");
        let before = points.clone();
        let aim = Aim::Corners(REPAIR_JACOBIAN);
        let moved = repair_once(&mut points, &around, &fixed, &setup, aim);
        let after = worst(&quads, &points, scaled_jacobian);
        assert!(moved > 0 && after > stalled + 0.05, "{stalled} → {after}");
        assert!((0..4).all(|q| setup
            .term(q, &quads[q].map(|v| points[v as usize]))
            .is_some()));
        assert!((0..9).all(|v| !fixed[v] || points[v] == before[v]));
    }

    /// Two quads in a 56° wedge share its tip, a fixed vertex of the boundaries: each keeps a
    /// 28° corner there whatever their free middle vertex does (the two corners sum to the
    /// tip's angle). Given a reach, the tip moves into the wedge, which opens both corners past
    /// 30°, and no farther than its reach; without one it stays, and so does the worst corner.
    #[test]
    fn a_corner_with_a_reach_opens_the_quads_sharing_it() {
        let half = 28f64.to_radians();
        let (c, s) = (2.0 * half.cos(), 2.0 * half.sin());
        // The tip, the middle (free), the wedge's sides and the far corners (fixed).
        let before = vec![
            Point::new(0.0, 0.0),
            Point::new(2.0, 0.0),
            Point::new(c, -s),
            Point::new(2.6, -0.6),
            Point::new(c, s),
            Point::new(2.6, 0.6),
        ];
        let quads = vec![[0, 2, 3, 1], [0, 1, 5, 4]];
        let fixed = [true, false, true, true, true, true];
        let around = around(&quads, before.len());
        let floors = floors(&quads, &before);
        let none = [0.0; 2];
        let setup = setup(&quads, &floors, &none);
        let start = worst(&quads, &before, scaled_jacobian);
        assert!((start - half.sin()).abs() < 1e-9, "{start}");
        let reach = 0.3;
        let run = |reach: &[Reach]| {
            let mut points = before.clone();
            let mut sliders = Sliders::default();
            let aim = Aim::Corners(REPAIR_JACOBIAN);
            let budget = everything(3);
            let moved = repair_jointly::<{ super::BATCH }>(
                &mut points,
                &around,
                &fixed,
                reach,
                &mut sliders,
                &setup,
                aim,
                budget,
            );
            (moved, points)
        };
        let held = run(&[]);
        assert!(held.1[0] == before[0]);
        assert!(worst(&quads, &held.1, scaled_jacobian) <= start + 1e-9);
        let reaches: Vec<Reach> = before
            .iter()
            .enumerate()
            .map(|(v, &origin)| Reach {
                origin,
                reach: if v == 0 { reach } else { 0.0 },
                axes: Point::new(1.0, 1.0),
            })
            .collect();
        let (moved, points) = run(&reaches);
        let end = worst(&quads, &points, scaled_jacobian);
        assert!(
            moved > 0 && end >= REPAIR_JACOBIAN - 1e-3,
            "{start} → {end}"
        );
        let shift = points[0].distance_squared(before[0]).sqrt();
        assert!(shift > 0.0 && shift <= reach, "{shift}");
        assert!(points[0].x > 0.0, "into the wedge: {:?}", points[0]);
        assert!((2..6).all(|v| points[v] == before[v]));
    }

    /// A 7 × 7 grid of unit squares whose middle quad is shrunk to a square 0.4 wide (a
    /// fortieth of the mean area: shape-and-size 0.026), its neighbours trapezoids still of fair
    /// shape, the border fixed. The corners' repair sees nothing to repair; raising quality
    /// grows the small quad, every quad held to its shape-and-size up to the bar and to its
    /// shape and scaled Jacobian up to 0.5, the border where it was.
    #[test]
    fn raising_quality_grows_a_small_quad_the_corners_repair_leaves() {
        let n = 7u32;
        let middle = [(3, 3), (4, 3), (4, 4), (3, 4)].map(|(i, j)| j * n + i);
        let before: Vec<Point> = (0..n * n)
            .map(|k| {
                let (x, y) = (f64::from(k % n), f64::from(k / n));
                if middle.contains(&k) {
                    // Towards the middle quad's centre (3.5, 3.5), 0.3 on each axis.
                    Point::new(x + 0.3 * (3.5 - x).signum(), y + 0.3 * (3.5 - y).signum())
                } else {
                    Point::new(x, y)
                }
            })
            .collect();
        let quads = grid_quads(n);
        let fixed: Vec<bool> = (0..n * n)
            .map(|k| k % n == 0 || k / n == 0 || k % n == n - 1 || k / n == n - 1)
            .collect();
        let around = around(&quads, (n * n) as usize);
        let floors = floors(&quads, &before);
        let none = vec![0.0; quads.len()];
        let setup = Setup {
            metric: Metric::ShapeAndSize,
            ..setup(&quads, &floors, &none)
        };
        let quality = |points: &[Point]| -> Vec<f64> {
            (0..quads.len()).map(|q| setup.value(points, q)).collect()
        };
        let small = quads.iter().position(|q| q[0] == middle[0]).unwrap();
        let start = quality(&before);
        assert!(start[small] < 0.03, "{}", start[small]);
        assert!(worst(&quads, &before, shape) > REPAIR_JACOBIAN);
        let repaired = |aim: Aim| {
            let mut points = before.clone();
            let moved = repair_once(&mut points, &around, &fixed, &setup, aim);
            (moved, points)
        };
        assert_eq!(repaired(Aim::Corners(REPAIR_JACOBIAN)).0, 0);
        let bar = 0.35;
        let (moved, points) = repaired(Aim::Quality { poor: 0.25, bar });
        let end = quality(&points);
        assert!(
            moved > 0 && end[small] > 0.5,
            "{} → {}",
            start[small],
            end[small]
        );
        for (q, quad) in quads.iter().enumerate() {
            assert!(
                end[q] >= start[q].min(bar),
                "quad {q}: {} → {}",
                start[q],
                end[q]
            );
            for metric in [shape, scaled_jacobian] {
                let (was, is) = (
                    metric(&corners(quad, &before)),
                    metric(&corners(quad, &points)),
                );
                assert!(is >= was.min(REPAIR_JACOBIAN), "quad {q}: {was} → {is}");
            }
        }
        assert!((0..(n * n) as usize).all(|v| !fixed[v] || points[v] == before[v]));
    }

    /// A strip of 40 × 6 points, its border fixed, its inside jittered by up to 0.35, its rows
    /// [`Strip::SQUEEZE`] apart (flat quads: many under the bar, their patches overlapping).
    struct Strip {
        fixed: Vec<bool>,
        before: Vec<Point>,
        quads: Vec<[u32; 4]>,
        around: Rows<u32>,
    }

    impl Strip {
        const W: u32 = 40;
        const H: u32 = 6;
        const SQUEEZE: f64 = 0.4;

        fn new(jitter: &[(f64, f64)]) -> Self {
            let (w, h) = (Self::W, Self::H);
            let fixed: Vec<bool> = (0..w * h)
                .map(|k| k % w == 0 || k / w == 0 || k % w == w - 1 || k / w == h - 1)
                .collect();
            let before: Vec<Point> = (0..w * h)
                .map(|k| {
                    let inside = !fixed[k as usize];
                    let (dx, dy) = if inside {
                        jitter[k as usize]
                    } else {
                        (0.0, 0.0)
                    };
                    Point::new(
                        f64::from(k % w) + dx,
                        Self::SQUEEZE * (f64::from(k / w) + dy),
                    )
                })
                .collect();
            let quads = rectangle_quads(w, h);
            let around = around(&quads, (w * h) as usize);
            Strip {
                fixed,
                before,
                quads,
                around,
            }
        }

        /// Whether every quad of the jittered strip is valid.
        fn is_valid(&self) -> bool {
            self.quads
                .iter()
                .all(|q| scaled_jacobian(&corners(q, &self.before)) > 0.0)
        }

        /// The moves and the points of the joint repair of the strip within `budget`.
        fn passes(&self, setup: &Setup, budget: Budget) -> (usize, Vec<Point>) {
            let mut points = self.before.clone();
            let moved = self.repair(
                repair_jointly::<{ super::BATCH }>,
                &mut points,
                setup,
                budget,
            );
            (moved, points)
        }

        /// `repair` of `points` on the strip at the repair's bar.
        fn repair(
            &self,
            repair: Repair,
            points: &mut [Point],
            setup: &Setup,
            budget: Budget,
        ) -> usize {
            let (around, fixed, aim) = (&self.around, &self.fixed, Aim::Corners(REPAIR_JACOBIAN));
            repair(
                points,
                around,
                fixed,
                &[],
                &mut Sliders::default(),
                setup,
                aim,
                budget,
            )
        }
    }

    /// One pass of the joint repair aimed at `aim`, with all the slack there is and no slider.
    fn repair_once(
        points: &mut [Point],
        around: &Rows<u32>,
        fixed: &[bool],
        setup: &Setup,
        aim: Aim,
    ) -> usize {
        let mut sliders = Sliders::default();
        repair_jointly::<{ super::BATCH }>(
            points,
            around,
            fixed,
            &[],
            &mut sliders,
            setup,
            aim,
            everything(1),
        )
    }

    /// `passes` passes with all the slack there is, later ones over the 64 poorest quads.
    fn everything(passes: usize) -> Budget {
        Budget {
            slack: f64::INFINITY,
            passes,
            first: usize::MAX,
            later: 64,
            graded: usize::MAX,
        }
    }

    /// Later passes lift what the first left, and take back from no quad what it gave it under
    /// [`REPAIR_FLOOR`]: on some of 48 jittered strips (a fixed sequence), four passes move more
    /// patches than one, and no quad ends under where one pass left it (or the floor).
    #[test]
    fn later_passes_move_patches_the_first_left() {
        let mut state = 0x9e37_79b9_7f4a_7c15_u64;
        let mut uniform = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut lifted = 0;
        for _ in 0..48 {
            let jitter: Vec<(f64, f64)> = (0..Strip::W * Strip::H)
                .map(|_| (0.7 * uniform() - 0.35, 0.7 * uniform() - 0.35))
                .collect();
            let strip = Strip::new(&jitter);
            if !strip.is_valid() {
                continue;
            }
            let (floors, none) = (
                floors(&strip.quads, &strip.before),
                vec![0.0; strip.quads.len()],
            );
            let setup = setup(&strip.quads, &floors, &none);
            let (once, four) = (
                strip.passes(&setup, everything(1)),
                strip.passes(&setup, everything(4)),
            );
            assert!(four.0 >= once.0);
            if four.0 > once.0 {
                lifted += 1;
            }
            for quad in &strip.quads {
                for metric in [shape, scaled_jacobian] {
                    let (after_one, after_four) = (
                        metric(&corners(quad, &once.1)),
                        metric(&corners(quad, &four.1)),
                    );
                    assert!(
                        after_four >= after_one.min(REPAIR_FLOOR),
                        "{after_one} → {after_four}"
                    );
                }
            }
        }
        assert!(lifted > 0);
    }

    proptest! {
        /// On a jittered 5 × 5 grid with its inside free: the worst scaled Jacobian (up to the
        /// bar) never falls, every quad stays valid and above its floors, and the border stays.
        #[test]
        fn the_joint_repair_never_makes_the_worst_quad_worse(
            jitter in proptest::collection::vec((-0.45f64..0.45, -0.45f64..0.45), 25),
        ) {
            let n = 5u32;
            let mut points: Vec<Point> = (0..n * n)
                .map(|k| {
                    let (i, j) = (k % n, k / n);
                    let inside = i > 0 && j > 0 && i < n - 1 && j < n - 1;
                    let (dx, dy) = if inside { jitter[k as usize] } else { (0.0, 0.0) };
                    Point::new(f64::from(i) + dx, f64::from(j) + dy)
                })
                .collect();
            let quads = grid_quads(n);
            prop_assume!(quads.iter().all(|q| scaled_jacobian(&corners(q, &points)) > 0.0));
            let floors = floors(&quads, &points);
            let none = vec![0.0; quads.len()];
            let setup = setup(&quads, &floors, &none);
            let fixed: Vec<bool> = (0..n * n)
                .map(|k| k % n == 0 || k / n == 0 || k % n == n - 1 || k / n == n - 1)
                .collect();
            let before = points.clone();
            let all: Vec<u32> = (0..quads.len() as u32).collect();
            let around = around(&quads, (n * n) as usize);
            let repaired = |slack: f64| {
                let mut points = before.clone();
                let mut sliders = Sliders::default();
                repair_jointly::<{ super::BATCH }>(&mut points, &around, &fixed, &[], &mut sliders, &setup, Aim::Corners(REPAIR_JACOBIAN), Budget { slack, passes: 3, first: usize::MAX, later: 64, graded: usize::MAX });
                points
            };
            let start = worst(&quads, &points, scaled_jacobian).min(REPAIR_JACOBIAN);
            points = repaired(f64::INFINITY);
            let end = worst(&quads, &points, scaled_jacobian).min(REPAIR_JACOBIAN);
            prop_assert!(end >= start, "{start} → {end}");
            for (q, quad) in quads.iter().enumerate() {
                prop_assert!(setup.term(q, &quad.map(|v| points[v as usize])).is_some());
            }
            for v in 0..(n * n) as usize {
                prop_assert!(!fixed[v] || points[v] == before[v]);
            }
            // With no energy to give back, no patch may raise the energy.
            let held = repaired(0.0);
            let energy = |points: &[Point]| super::energy(&all, points, &setup);
            prop_assert!(energy(&held) <= energy(&before) + 1e-12);
        }

        /// On a jittered 5 × 5 grid, its nine inside vertices moving: the shortfall kept quad by
        /// quad, after moves of one variable or of all, is the one scoring every quad again,
        /// to the bit.
        #[test]
        fn the_shortfall_kept_quad_by_quad_is_the_shortfall_of_all_the_quads(
            jitter in proptest::collection::vec((-0.3f64..0.3, -0.3f64..0.3), 25),
            moves in proptest::collection::vec((0usize..19, -0.6f64..0.6), 1..40),
        ) {
            let n = 5u32;
            let inside = |k: u32| k % n != 0 && k / n != 0 && k % n != n - 1 && k / n != n - 1;
            let mut points: Vec<Point> = (0..n * n)
                .map(|k| {
                    let (dx, dy) = if inside(k) { jitter[k as usize] } else { (0.0, 0.0) };
                    Point::new(f64::from(k % n) + dx, f64::from(k / n) + dy)
                })
                .collect();
            let quads = grid_quads(n);
            prop_assume!(quads.iter().all(|q| scaled_jacobian(&corners(q, &points)) > 0.0));
            // No floors, and a bar most quads are under: every quad counts.
            let floors = (vec![0.0; quads.len()], vec![f64::NEG_INFINITY; quads.len()]);
            let setup = setup(&quads, &floors, &floors.0);
            let bar = Aim::Corners(0.95);
            let movers: Vec<Mover> = (0..n * n)
                .filter(|&k| inside(k))
                .map(|k| Mover::Free { at: k, base: points[k as usize], scale: 0.5 })
                .collect();
            let sliders = Sliders::default();
            let mut along = vec![0.0; movers.len()];
            let mut kept = Shortfall::new(&movers, &quads, 18);
            let mut x = vec![0.0; 18];
            // Where the grid starts, every quad valid: a finite shortfall.
            let start = kept.at(&x, &movers, &mut points, &mut along, &sliders, &setup, bar);
            prop_assert!(start.is_finite());
            for (i, value) in moves {
                // 18 moves every variable at once.
                if i == 18 {
                    x.iter_mut().for_each(|x| *x = value);
                } else {
                    x[i] = value;
                }
                let got = kept.at(&x, &movers, &mut points, &mut along, &sliders, &setup, bar);
                let mut fresh_points = points.clone();
                let mut fresh = Shortfall::new(&movers, &quads, 18);
                let all = fresh.at(&x, &movers, &mut fresh_points, &mut along, &sliders, &setup, bar);
                prop_assert_eq!(got.to_bits(), all.to_bits(), "{} against {}", got, all);
            }
        }

        /// On a jittered strip of 40 × 6 points, its inside free, with energy to give back,
        /// none, or some to win back first (a negative slack, which patches that lower the
        /// energy enough raise: then the order they are kept in decides which fit): patches
        /// solved side by side, a few or many at a time, ahead of those that wait, end where
        /// solving them one after the other does, to the bit, over three passes (later ones
        /// over the 2 or 64 poorest quads).
        #[test]
        fn batches_of_patches_end_where_one_patch_at_a_time_does(
            jitter in proptest::collection::vec((-0.35f64..0.35, -0.35f64..0.35), 240),
            slack in prop_oneof![Just(0.0), -1.5f64..0.3, Just(f64::INFINITY)],
            later in prop_oneof![Just(2usize), Just(64)],
        ) {
            let strip = Strip::new(&jitter);
            prop_assume!(strip.is_valid());
            let (floors, none) = (floors(&strip.quads, &strip.before), vec![0.0; strip.quads.len()]);
            let setup = setup(&strip.quads, &floors, &none);
            let repaired = |batched: Repair| {
                let mut points = strip.before.clone();
                let budget = Budget { slack, passes: 3, first: usize::MAX, later, graded: usize::MAX };
                let moved = strip.repair(batched, &mut points, &setup, budget);
                (moved, points)
            };
            let one = repaired(repair_jointly::<1>);
            let batched: [(usize, Repair); 3] = [
                (2, repair_jointly::<2>),
                (5, repair_jointly::<5>),
                (64, repair_jointly::<64>),
            ];
            for (batch, repair) in batched {
                let many = repaired(repair);
                prop_assert_eq!(many.0, one.0);
                prop_assert!(many.1 == one.1, "batches of {} differ", batch);
            }
        }
    }
}
