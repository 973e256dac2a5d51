//! Boundary vertices sliding along their curves: the quad vertices on a G' edge, between its
//! two G' vertices, each moved along the edge's curve (one variable, its position along the
//! curve) to lower the energy of its quads.
//!
//! The control-point modes keep every c-edge's control points, so a quad along a boundary
//! keeps the spacing DT' gave its boundary vertices; but any spacing of points on the curve
//! follows the boundary equally well. Moving a vertex along the curve keeps it exactly on the
//! curve and changes only where, between its neighbours on the same curve, it sits.

use imesh_geom::Point;
use imesh_quad::{BoundaryChain, Remesh};
use rayon::prelude::*;

use crate::variables::{by_quad, colour, vertex_quads, Rows};
use crate::Setup;

/// The sliding vertices of a mesh.
#[derive(Clone, Debug, Default)]
pub(crate) struct Sliders {
    chains: Vec<BoundaryChain>,
    /// Per slider: its chain and its index there (never the first or the last).
    slot: Vec<(u32, u32)>,
    /// Per slider, the quads around its vertex.
    quads: Rows<u32>,
    /// Sliders by colour: two of one colour share no quad (so neither bounds the other).
    colours: Vec<Vec<u32>>,
}

impl Sliders {
    /// The boundary vertices of `remesh`'s quad mesh, on its [`Remesh::boundary_chains`]: every
    /// vertex of a chain but its two ends.
    pub fn new(remesh: &Remesh) -> Self {
        let mesh = &remesh.mesh;
        let mut chains = remesh.boundary_chains();
        chains.retain(|c| c.vertices.len() >= 3);
        let around = vertex_quads(mesh);
        let mut slot = Vec::new();
        let mut quads = Rows::new();
        for (c, chain) in chains.iter().enumerate() {
            for j in 1..chain.vertices.len() - 1 {
                slot.push((c as u32, j as u32));
                quads.push_row(around.row(chain.vertices[j] as usize).iter().copied());
            }
        }
        let colours = colour(&quads, &by_quad(&quads, mesh.quads.len()));
        Self {
            chains,
            slot,
            quads,
            colours,
        }
    }

    /// Where every chain's vertices are along it, to put them back with
    /// [`Sliders::restore`].
    pub fn positions(&self) -> Vec<Vec<f64>> {
        self.chains.iter().map(|c| c.along.clone()).collect()
    }

    /// Puts the vertices back where [`Sliders::positions`] found them (the mesh's vertices are
    /// the caller's to put back).
    pub fn restore(&mut self, positions: Vec<Vec<f64>>) {
        for (c, along) in self.chains.iter_mut().zip(positions) {
            c.along = along;
        }
    }

    /// The chains, each vertex where the sliding left it along its chain.
    pub fn into_chains(self) -> Vec<BoundaryChain> {
        self.chains
    }

    /// Number of sliding vertices.
    pub fn len(&self) -> usize {
        self.slot.len()
    }

    /// Per quad vertex of a mesh of `n` vertices (quads `quads`): true within `rings` quad
    /// rings of a sliding vertex (0: the sliding vertices themselves).
    pub fn near(&self, quads: &[[u32; 4]], n: usize, rings: usize) -> Vec<bool> {
        let mut near = vec![false; n];
        for &(c, j) in &self.slot {
            near[self.chains[c as usize].vertices[j as usize] as usize] = true;
        }
        for _ in 0..rings {
            let grown: Vec<bool> = quads
                .iter()
                .map(|q| q.iter().any(|&v| near[v as usize]))
                .collect();
            for (q, &g) in quads.iter().zip(&grown) {
                if g {
                    for &v in q {
                        near[v as usize] = true;
                    }
                }
            }
        }
        near
    }

    /// Per quad vertex of a mesh of `n` vertices: the slider that moves it, or `u32::MAX`.
    pub fn slider_of_vertices(&self, n: usize) -> Vec<u32> {
        let mut of = vec![u32::MAX; n];
        for (i, &(c, j)) in self.slot.iter().enumerate() {
            of[self.chains[c as usize].vertices[j as usize] as usize] = i as u32;
        }
        of
    }

    /// Slider `i`'s position along its chain, and its neighbours' on either side.
    pub fn gap(&self, i: usize) -> [f64; 3] {
        let (c, j) = self.slot[i];
        let along = &self.chains[c as usize].along;
        let j = j as usize;
        [along[j - 1], along[j], along[j + 1]]
    }

    /// The quad vertices before and after slider `i` on its chain, each with its slider if it
    /// is one (not at the chain's ends).
    pub fn neighbours(&self, i: usize) -> [(u32, Option<u32>); 2] {
        let (c, j) = self.slot[i];
        let vertices = &self.chains[c as usize].vertices;
        let j = j as usize;
        // A chain's sliders are numbered in order along it, from its second vertex to its
        // last but one.
        [
            (vertices[j - 1], (j > 1).then(|| i as u32 - 1)),
            (
                vertices[j + 1],
                (j + 2 < vertices.len()).then(|| i as u32 + 1),
            ),
        ]
    }

    /// Where slider `i` would be at `along` on its chain.
    pub fn point(&self, i: usize, along: f64) -> Point {
        self.chains[self.slot[i].0 as usize].point(along)
    }

    /// Puts slider `i` at `along` (not checked against its neighbours) and returns its point.
    pub fn place(&mut self, i: usize, along: f64) -> Point {
        let (c, j) = self.slot[i];
        self.chains[c as usize].along[j as usize] = along;
        self.point(i, along)
    }

    /// Sweeps over the sliders, colour by colour, until a sweep lowers the energy of the quads
    /// they move by less than `setup.tolerance` of it, or `sweeps` of them. Returns the sweeps.
    pub fn sweep(&mut self, vertices: &mut [Point], setup: &Setup<'_>, sweeps: usize) -> usize {
        let mut done = 0;
        for _ in 0..sweeps {
            done += 1;
            let mut gained = 0.0;
            let mut total = 0.0;
            for colour in &self.colours {
                let moves: Vec<(u32, f64, Point, f64, f64)> = colour
                    .par_iter()
                    .filter_map(|&i| self.solve(i as usize, vertices, setup))
                    .collect();
                for (i, along, p, before, after) in moves {
                    let (c, j) = self.slot[i as usize];
                    let chain = &mut self.chains[c as usize];
                    chain.along[j as usize] = along;
                    vertices[chain.vertices[j as usize] as usize] = p;
                    gained += before - after;
                    total += before;
                }
            }
            if total <= 0.0 || gained <= setup.tolerance * total {
                break;
            }
        }
        done
    }

    /// The worst corners next to the curves: each slider with a quad whose shape is under
    /// `bar` moves along its curve, between its neighbours, to raise the smallest scaled
    /// Jacobian of its quads and then their smallest shape (up to `bar`, every quad held to
    /// the floors of `setup`; [`crate::repair::corners_value`]), by a coarse scan of the gap and
    /// a search halving its step around the best. The free vertices' repair cannot turn a
    /// corner pinned between two boundary vertices; moving one of those along the boundary
    /// can. Sequential and in slider order; returns how many moved.
    pub fn repair(&mut self, vertices: &mut [Point], setup: &Setup<'_>, bar: f64) -> usize {
        let mut moved = 0;
        for i in 0..self.slot.len() {
            let quads = self.quads.row(i);
            let poor = quads
                .iter()
                .any(|&q| setup.shape(vertices, q as usize) < bar);
            if !poor {
                continue;
            }
            let (c, j) = self.slot[i];
            let chain = &mut self.chains[c as usize];
            let v = chain.vertices[j as usize] as usize;
            let (lo, hi) = (chain.along[j as usize - 1], chain.along[j as usize + 1]);
            let margin = 0.05 * (hi - lo);
            let (lo, hi) = (lo + margin, hi - margin);
            let start = (chain.along[j as usize], vertices[v]);
            // Where the slider at `a` beats `best`: its value there.
            let mut above = |a: f64, best: (f64, f64)| {
                vertices[v] = chain.point(a);
                crate::repair::corners_value_above(quads, vertices, setup, bar, best)
            };
            let below = (f64::NEG_INFINITY, f64::NEG_INFINITY);
            let Some(mut best) = above(start.0, below) else {
                vertices[v] = start.1;
                continue;
            };
            let mut at = start.0;
            for k in 0..=REPAIR_SCAN {
                let a = lo + (hi - lo) * k as f64 / REPAIR_SCAN as f64;
                if let Some(f) = above(a, best) {
                    (at, best) = (a, f);
                }
            }
            let mut step = (hi - lo) / REPAIR_SCAN as f64 / 2.0;
            for _ in 0..REPAIR_HALVINGS {
                for a in [at - step, at + step] {
                    if !(lo..=hi).contains(&a) {
                        continue;
                    }
                    if let Some(f) = above(a, best) {
                        (at, best) = (a, f);
                    }
                }
                step /= 2.0;
            }
            if at == start.0 {
                vertices[v] = start.1;
            } else {
                vertices[v] = chain.point(at);
                chain.along[j as usize] = at;
                moved += 1;
            }
        }
        moved
    }

    /// The best position of slider `i` between its neighbours: golden-section search of the
    /// energy of its quads, from where it is. `None` when it cannot improve.
    fn solve(
        &self,
        i: usize,
        vertices: &[Point],
        setup: &Setup<'_>,
    ) -> Option<(u32, f64, Point, f64, f64)> {
        let (c, j) = self.slot[i];
        let chain = &self.chains[c as usize];
        let along = &chain.along;
        let v = chain.vertices[j as usize];
        let (lo, hi) = (along[j as usize - 1], along[j as usize + 1]);
        // Stay clear of the neighbours: a vertex on top of one would make a degenerate quad.
        let margin = 0.05 * (hi - lo);
        let (lo, hi) = (lo + margin, hi - margin);
        let energy = |a: f64| -> f64 {
            let p = chain.point(a);
            let mut sum = 0.0;
            for &q in self.quads.row(i) {
                let corners =
                    setup.quads[q as usize].map(|u| if u == v { p } else { vertices[u as usize] });
                match setup.term(q as usize, &corners) {
                    Some(e) => sum += e,
                    None => return f64::INFINITY,
                }
            }
            sum
        };
        let start = along[j as usize];
        let before = energy(start);
        if !before.is_finite() || before <= setup.settled_term * self.quads.row(i).len() as f64 {
            return None;
        }
        // Golden section on [lo, hi]; the start is kept as the best until beaten.
        let ratio = 0.5 * (5f64.sqrt() - 1.0);
        let (mut a, mut b) = (lo, hi);
        let mut x1 = b - ratio * (b - a);
        let mut x2 = a + ratio * (b - a);
        let (mut f1, mut f2) = (energy(x1), energy(x2));
        for _ in 0..GOLDEN_STEPS {
            if f1 <= f2 {
                b = x2;
                (x2, f2) = (x1, f1);
                x1 = b - ratio * (b - a);
                f1 = energy(x1);
            } else {
                a = x1;
                (x1, f1) = (x2, f2);
                x2 = a + ratio * (b - a);
                f2 = energy(x2);
            }
        }
        let (best, after) = if f1 <= f2 { (x1, f1) } else { (x2, f2) };
        (after < before).then(|| (i as u32, best, chain.point(best), before, after))
    }
}

/// The repair's scan of a slider's gap: this many intervals, then the step (half an interval)
/// halved this many times around the best.
const REPAIR_SCAN: usize = 16;
const REPAIR_HALVINGS: usize = 10;

/// Golden-section steps per solve: the bracket shrinks to 0.618²⁰ ≈ 10⁻⁴ of the gap between
/// the neighbours.
const GOLDEN_STEPS: usize = 20;

#[cfg(test)]
mod tests {
    use super::Sliders;
    use crate::support;
    use imesh_quad::{remesh, QuadOptions};

    /// A disc's quad mesh.
    fn disc() -> imesh_quad::Remesh {
        let (w, h) = (24u32, 20u32);
        let labels = (0..w * h)
            .map(|i| {
                let (x, y) = (f64::from(i % w) + 0.5, f64::from(i / w) + 0.5);
                u32::from((x - 12.0).powi(2) + (y - 10.0).powi(2) < 40.0)
            })
            .collect();
        let (_, s, curves) = support::simplified_with_curves(&support::grid(w, h, labels));
        remesh(&s.graph, &curves, &QuadOptions::default()).unwrap()
    }

    /// Positions taken and restored put every slider back, and the chains handed out say so.
    #[test]
    fn restored_positions_put_the_sliders_back() {
        let r = disc();
        let mut sliders = Sliders::new(&r);
        let start = sliders.positions();
        for i in 0..sliders.len() {
            let [lo, at, _] = sliders.gap(i);
            sliders.place(i, 0.5 * (lo + at));
        }
        assert_ne!(sliders.positions(), start);
        sliders.restore(start.clone());
        assert_eq!(sliders.positions(), start);
        let chains = sliders.into_chains();
        assert_eq!(
            chains.iter().map(|c| c.along.clone()).collect::<Vec<_>>(),
            start
        );
    }

    /// On a disc's mesh: a slider's neighbours on its chain are the sliders numbered next to
    /// it, standing where its gap says, or the chain's ends.
    #[test]
    fn a_sliders_neighbours_are_the_next_sliders_on_its_chain() {
        let r = disc();
        let sliders = Sliders::new(&r);
        let slider_of = sliders.slider_of_vertices(r.mesh.vertices.len());
        let (mut inner, mut ends) = (0, 0);
        for i in 0..sliders.len() {
            let [lo, at, hi] = sliders.gap(i);
            for ((vertex, slider), (along, side)) in
                sliders.neighbours(i).into_iter().zip([(lo, 0), (hi, 2)])
            {
                match slider {
                    Some(n) => {
                        inner += 1;
                        assert_eq!(slider_of[vertex as usize], n);
                        // Its gap's middle is our side, and its other side our middle.
                        assert_eq!(sliders.gap(n as usize)[1], along);
                        assert_eq!(sliders.gap(n as usize)[2 - side], at);
                    }
                    None => {
                        ends += 1;
                        assert_eq!(slider_of[vertex as usize], u32::MAX);
                    }
                }
            }
        }
        assert!(inner > 0 && ends > 0, "{inner} inner, {ends} at chain ends");
    }
}
