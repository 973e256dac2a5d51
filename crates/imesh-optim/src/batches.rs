//! Searches that run one after the other, run side by side where they are independent.
//!
//! The repairs move a few points at a time, each search reading the corners of a few quads and
//! moving some of them, every search seeing the moves before it. Two searches commute when
//! neither reads a point the other moves: a search may then run before an earlier one, or
//! beside it, and the result is the same to the bit. [`Scheduler`] picks, from a queue of
//! searches in order, those that can run now; each runs over its own copy of its points
//! ([`Subproblem`]), and the caller keeps the moves in order.

use std::collections::VecDeque;

use imesh_geom::Point;

use crate::Setup;

/// Some quads of a mesh as a problem of their own: their corners, the quads over those (in the
/// order given), and their floors, so that a search can run over its own copy of the points.
pub(crate) struct Subproblem {
    /// The mesh's points that are corners of the quads, in increasing order.
    pub points: Vec<u32>,
    quads: Vec<[u32; 4]>,
    quality_floors: Vec<f64>,
    shape_floors: Vec<f64>,
    jacobian_floors: Vec<f64>,
}

impl Subproblem {
    /// Quads `quads` of `setup`.
    pub fn new(quads: &[u32], setup: &Setup) -> Self {
        let mut points: Vec<u32> = quads
            .iter()
            .flat_map(|&q| setup.quads[q as usize])
            .collect();
        points.sort_unstable();
        points.dedup();
        let local = |v: u32| points.partition_point(|&u| u < v) as u32;
        let floors = |of: &[f64]| quads.iter().map(|&q| of[q as usize]).collect();
        Self {
            quads: quads
                .iter()
                .map(|&q| setup.quads[q as usize].map(local))
                .collect(),
            quality_floors: floors(setup.quality_floors),
            shape_floors: floors(setup.shape_floors),
            jacobian_floors: floors(setup.jacobian_floors),
            points,
        }
    }

    /// Mesh point `v`'s index among [`Subproblem::points`], if it is there.
    pub fn index(&self, v: u32) -> Option<usize> {
        self.points.binary_search(&v).ok()
    }

    /// The number of quads (numbered from 0 in the order given).
    pub fn len(&self) -> usize {
        self.quads.len()
    }

    /// The quads over their own points, held to their floors; the rest as in `setup`.
    pub fn setup<'a>(&'a self, setup: &Setup) -> Setup<'a> {
        Setup {
            quads: &self.quads,
            quality_floors: &self.quality_floors,
            shape_floors: &self.shape_floors,
            jacobian_floors: &self.jacobian_floors,
            ..*setup
        }
    }

    /// Its points' copy of `points`.
    pub fn gather(&self, points: &[Point]) -> Vec<Point> {
        self.points.iter().map(|&v| points[v as usize]).collect()
    }
}

/// Picks the searches of a queue that can run side by side: marks of the points that the
/// searches taken may move, and that the searches left waiting read.
pub(crate) struct Scheduler {
    moving: Vec<u32>,
    waiting: Vec<u32>,
    stamp: u32,
    scratch: Vec<u32>,
    /// Whether a search may be taken past one that waits.
    ahead: bool,
}

impl Scheduler {
    /// For a mesh of `points` points.
    pub fn new(points: usize) -> Self {
        Self {
            moving: vec![0; points],
            waiting: vec![0; points],
            stamp: 0,
            scratch: Vec::new(),
            ahead: true,
        }
    }

    /// For a mesh of `points` points, taking searches only up to the first that must wait:
    /// for searches whose moves are kept in order against a budget they share (the first of
    /// two may spend what the second would have).
    pub fn in_order(points: usize) -> Self {
        Self {
            ahead: false,
            ..Self::new(points)
        }
    }

    /// Takes from `queue` (in order) at most `most` searches to run now, side by side: each
    /// reads (`reads` lists the points, among them those it may move, `moves`) no point that a
    /// search before it in the queue may move, and moves no point that a search left waiting
    /// before it reads. A search that could run but that `idle` says has nothing to do is
    /// dropped. `queue` keeps the searches left, in order.
    pub fn take<T>(
        &mut self,
        queue: &mut VecDeque<T>,
        most: usize,
        reads: impl Fn(&T, &mut Vec<u32>),
        moves: impl Fn(&T, &mut Vec<u32>),
        mut idle: impl FnMut(&T) -> bool,
    ) -> Vec<T> {
        self.stamp += 1;
        let stamp = self.stamp;
        let mut now = Vec::new();
        // Those that wait, in order; they go back to the front of the queue, the searches not
        // looked at staying where they are.
        let mut waiting = Vec::new();
        while now.len() < most && (self.ahead || waiting.is_empty()) {
            let Some(task) = queue.pop_front() else {
                break;
            };
            self.scratch.clear();
            reads(&task, &mut self.scratch);
            // What it moves is among what it reads: one test covers both directions.
            let blocked = self
                .scratch
                .iter()
                .any(|&v| self.moving[v as usize] == stamp || self.waiting[v as usize] == stamp);
            if blocked {
                for &v in &self.scratch {
                    self.waiting[v as usize] = stamp;
                }
                waiting.push(task);
            } else if !idle(&task) {
                self.scratch.clear();
                moves(&task, &mut self.scratch);
                for &v in &self.scratch {
                    self.moving[v as usize] = stamp;
                }
                now.push(task);
            }
        }
        for task in waiting.into_iter().rev() {
            queue.push_front(task);
        }
        now
    }
}

#[cfg(test)]
mod tests {
    use super::{Scheduler, Subproblem};
    use crate::{Metric, Setup};
    use imesh_geom::Point;
    use proptest::prelude::*;
    use std::collections::VecDeque;

    /// Three quads picked out of a row of five, out of order: over their own points they
    /// score as they do in the mesh, each with its own floors, and every corner maps back.
    #[test]
    fn a_subproblem_scores_its_quads_as_the_mesh_does() {
        let points: Vec<Point> = (0..12)
            .map(|k| {
                Point::new(
                    f64::from(k % 6) + 0.1 * f64::from(k * k % 5),
                    f64::from(k / 6),
                )
            })
            .collect();
        let quads: Vec<[u32; 4]> = (0..5).map(|i| [i, i + 1, i + 7, i + 6]).collect();
        let floors: Vec<f64> = (0..5).map(|q| 0.1 * f64::from(q)).collect();
        let setup = Setup {
            average_area: 1.2,
            ..Setup::held(&quads, Metric::ShapeAndSize, [&floors; 3])
        };
        let picked = [3u32, 0, 4];
        let sub = Subproblem::new(&picked, &setup);
        let local = sub.setup(&setup);
        let own = sub.gather(&points);
        assert_eq!(sub.len(), 3);
        assert_eq!(sub.points, [0, 1, 3, 4, 5, 6, 7, 9, 10, 11]);
        for (k, &q) in picked.iter().enumerate() {
            assert_eq!(
                local.value(&own, k).to_bits(),
                setup.value(&points, q as usize).to_bits()
            );
            assert_eq!(local.shape_floors[k], floors[q as usize]);
            for (&v, &u) in quads[q as usize].iter().zip(&local.quads[k]) {
                assert_eq!(sub.index(v), Some(u as usize));
                assert_eq!(own[u as usize], points[v as usize]);
            }
        }
        assert_eq!(sub.index(2), None);
    }

    /// A search of the test: it reads `reads`, and moves the first `moves` of them to a value
    /// that depends on everything it read, unless what it reads sums to a multiple of 5 (it is
    /// idle then).
    #[derive(Clone, Debug)]
    struct Search {
        reads: Vec<u32>,
        moves: usize,
        id: u64,
    }

    impl Search {
        fn idle(&self, state: &[u64]) -> bool {
            self.reads.iter().map(|&v| state[v as usize]).sum::<u64>() % 5 == 0
        }

        fn run(&self, state: &[u64]) -> Vec<u64> {
            let seen = self.reads.iter().fold(self.id, |h, &v| {
                h.wrapping_mul(31).wrapping_add(state[v as usize])
            });
            (0..self.moves as u64)
                .map(|k| seen.wrapping_add(k) % 1000)
                .collect()
        }

        fn keep(&self, found: &[u64], state: &mut [u64]) {
            for (&v, &x) in self.reads.iter().zip(found) {
                state[v as usize] = x;
            }
        }
    }

    fn searches() -> impl Strategy<Value = Vec<Search>> {
        proptest::collection::vec(
            (proptest::collection::vec(0u32..24, 1..6), 1usize..4),
            1..60,
        )
        .prop_map(|list| {
            list.into_iter()
                .enumerate()
                .map(|(id, (mut reads, moves))| {
                    reads.sort_unstable();
                    reads.dedup();
                    let moves = moves.min(reads.len());
                    Search {
                        reads,
                        moves,
                        id: id as u64,
                    }
                })
                .collect()
        })
    }

    proptest! {
        /// Searches taken in batches, each batch run over the state as it was before it and
        /// kept in order, end where running them one after the other does, whatever the
        /// batches' size.
        #[test]
        fn batches_end_where_one_search_after_the_other_does(
            searches in searches(),
            most in 1usize..20,
            ahead in any::<bool>(),
        ) {
            let start: Vec<u64> = (0..24).map(|v| v * 7 % 11).collect();
            let mut one = start.clone();
            for s in &searches {
                if !s.idle(&one) {
                    let found = s.run(&one);
                    s.keep(&found, &mut one);
                }
            }
            let mut state = start;
            let mut scheduler = if ahead { Scheduler::new(24) } else { Scheduler::in_order(24) };
            let mut queue: VecDeque<Search> = searches.iter().cloned().collect();
            let mut rounds = 0;
            while !queue.is_empty() {
                let now = scheduler.take(
                    &mut queue,
                    most,
                    |s, reads| reads.extend_from_slice(&s.reads),
                    |s, moves| moves.extend_from_slice(&s.reads[..s.moves]),
                    |s| s.idle(&state),
                );
                let found: Vec<Vec<u64>> = now.iter().map(|s| s.run(&state)).collect();
                for (s, found) in now.iter().zip(&found) {
                    s.keep(found, &mut state);
                }
                rounds += 1;
                prop_assert!(rounds <= searches.len(), "no progress");
            }
            prop_assert_eq!(state, one);
        }
    }
}
