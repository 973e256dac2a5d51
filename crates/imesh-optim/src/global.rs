//! The paper's global mode: one Powell run over the coordinates of all free control points.
//!
//! The energy is evaluated incrementally: against the best point seen so far (which is where
//! Powell's iterate is), only the quads moved by the variables that differ are recomputed, so
//! a line search along one coordinate costs the quads of one control point, not the mesh.

use std::cell::RefCell;

use argmin::core::{CostFunction, Error, Executor};
use imesh_geom::predicates::orient2d;
use imesh_geom::Point;

use crate::variables::Variables;
use crate::{Powell, Setup};

/// The energy as a function of all free control points' displacements (`2 n` coordinates).
struct GlobalEnergy<'a> {
    variables: &'a Variables,
    /// Per quad vertex, the variables moving it and their weights.
    movers: Vec<Vec<(u32, f64)>>,
    /// The variable of each control point (`u32::MAX` when fixed).
    variable_of: Vec<u32>,
    start_vertices: &'a [Point],
    start_net: &'a [Point],
    setup: Setup<'a>,
    cache: RefCell<Cache>,
}

/// The best point evaluated so far, with its vertex positions and energy terms.
struct Cache {
    base: Vec<f64>,
    vertices: Vec<Point>,
    terms: Vec<f64>,
    energy: f64,
    /// Scratch: stamps of affected quads and vertices, and new positions.
    quad_stamp: Vec<u32>,
    vertex_stamp: Vec<u32>,
    moved: Vec<Point>,
    epoch: u32,
}

impl GlobalEnergy<'_> {
    /// The position of vertex `v` at displacements `x`.
    fn vertex(&self, v: usize, x: &[f64]) -> Point {
        let mut p = self.start_vertices[v];
        for &(i, w) in &self.movers[v] {
            let i = i as usize;
            p = p + Point::new(x[2 * i], x[2 * i + 1]) * w;
        }
        p
    }

    /// The position of control point `c` at displacements `x`.
    fn control(&self, c: usize, x: &[f64]) -> Point {
        let p = self.start_net[c];
        match self.variable_of[c] {
            u32::MAX => p,
            i => p + Point::new(x[2 * i as usize], x[2 * i as usize + 1]),
        }
    }

    fn evaluate(&self, x: &[f64]) -> f64 {
        let mut cache = self.cache.borrow_mut();
        let cache = &mut *cache;
        let changed: Vec<usize> = (0..self.variables.len())
            .filter(|&i| x[2 * i] != cache.base[2 * i] || x[2 * i + 1] != cache.base[2 * i + 1])
            .collect();
        if changed.is_empty() {
            return cache.energy;
        }
        cache.epoch = cache.epoch.wrapping_add(1);
        let epoch = cache.epoch;
        let mut vertices = Vec::new();
        let mut quads = Vec::new();
        for &i in &changed {
            let c = self.variables.ids[i] as usize;
            let p = self.control(c, x);
            let inside_now = self.variables.ring.row(i).iter().all(|&[a, b]| {
                orient2d(self.control(a as usize, x), self.control(b as usize, x), p) > 0.0
            });
            let inside_start = self
                .variables
                .inside_ring(i, self.start_net, self.start_net[c]);
            if inside_start && !inside_now {
                return f64::INFINITY;
            }
            for &(v, _) in self.variables.influence.row(i) {
                if cache.vertex_stamp[v as usize] != epoch {
                    cache.vertex_stamp[v as usize] = epoch;
                    cache.moved[v as usize] = self.vertex(v as usize, x);
                    vertices.push(v);
                }
            }
            for &q in self.variables.quads.row(i) {
                if cache.quad_stamp[q as usize] != epoch {
                    cache.quad_stamp[q as usize] = epoch;
                    quads.push(q);
                }
            }
        }
        let position = |v: u32| {
            if cache.vertex_stamp[v as usize] == epoch {
                cache.moved[v as usize]
            } else {
                cache.vertices[v as usize]
            }
        };
        let mut new_terms = Vec::with_capacity(quads.len());
        let mut energy = cache.energy;
        for &q in &quads {
            let p = self.setup.quads[q as usize].map(position);
            match self.setup.term(q as usize, &p) {
                Some(e) => {
                    energy += e - cache.terms[q as usize];
                    new_terms.push(e);
                }
                None => return f64::INFINITY,
            }
        }
        if energy < cache.energy {
            for &i in &changed {
                cache.base[2 * i] = x[2 * i];
                cache.base[2 * i + 1] = x[2 * i + 1];
            }
            for &v in &vertices {
                cache.vertices[v as usize] = cache.moved[v as usize];
            }
            for (&q, e) in quads.iter().zip(new_terms) {
                cache.terms[q as usize] = e;
            }
            cache.energy = energy;
        }
        energy
    }
}

impl CostFunction for GlobalEnergy<'_> {
    type Param = Vec<f64>;
    type Output = f64;
    fn cost(&self, x: &Vec<f64>) -> Result<f64, Error> {
        Ok(self.evaluate(x))
    }
}

/// Minimises the energy over all free control points `variables` by Powell's method (at most
/// `iterations` iterations); moves `vertices` and `net` to the best point. Returns the
/// iterations run.
pub(crate) fn minimise(
    variables: &Variables,
    vertices: &mut [Point],
    net: &mut [Point],
    setup: Setup<'_>,
    iterations: u64,
) -> Result<usize, Error> {
    if variables.len() == 0 {
        return Ok(0);
    }
    let mut movers = vec![Vec::new(); vertices.len()];
    for i in 0..variables.len() {
        for &(v, w) in variables.influence.row(i) {
            movers[v as usize].push((i as u32, w));
        }
    }
    let mut variable_of = vec![u32::MAX; net.len()];
    for (i, &c) in variables.ids.iter().enumerate() {
        variable_of[c as usize] = i as u32;
    }
    let terms: Vec<f64> = (0..setup.quads.len())
        .map(|q| (1.0 - setup.value(vertices, q)).powi(2))
        .collect();
    let start_vertices = vertices.to_vec();
    let start_net = net.to_vec();
    let energy = GlobalEnergy {
        variables,
        movers,
        variable_of,
        start_vertices: &start_vertices,
        start_net: &start_net,
        setup,
        cache: RefCell::new(Cache {
            base: vec![0.0; 2 * variables.len()],
            vertices: start_vertices.clone(),
            energy: terms.iter().sum(),
            terms,
            quad_stamp: vec![0; setup.quads.len()],
            vertex_stamp: vec![0; vertices.len()],
            moved: vec![Point::new(0.0, 0.0); vertices.len()],
            epoch: 0,
        }),
    };
    let powell = Powell::new(0.2 * setup.average_area.sqrt())
        .with_tolerance(1e-5)
        .with_line_search(1e-3, 16);
    let result = Executor::new(energy, powell)
        .configure(|s| {
            s.param(vec![0.0; 2 * variables.len()])
                .max_iters(iterations)
        })
        .run()?;
    let state = result.state();
    let iterations = state.iter as usize;
    let energy = result
        .problem
        .problem
        .as_ref()
        .ok_or_else(|| Error::msg("the energy was lost"))?;
    let cache = energy.cache.borrow();
    // The cache holds the best point evaluated, which the final iterate is.
    for (v, p) in cache.vertices.iter().enumerate() {
        vertices[v] = *p;
    }
    for (c, p) in net.iter_mut().enumerate() {
        *p = energy.control(c, &cache.base);
    }
    Ok(iterations)
}
