//! # imesh-optim
//!
//! Quality optimisation of the quad mesh Q (DESIGN.md §2, step 10; the paper's section V-C):
//! minimise `q_s = Σ (1 − s(ν))²` over the quads ν, `s` being Verdict's shape-and-size against
//! the mesh's fixed average quad area ([`Metric::ShapeAndSize`]) or shape ([`Metric::Shape`]),
//! by moving the free Bézier control points: those not on a c-edge or on the domain border, so
//! that every region keeps its fitted boundary. Quad vertices follow their patches.
//!
//! A move is feasible only if every quad keeps positive Jacobians at its four corners (exact
//! orientation), every moved control point stays strictly inside the polygon of its
//! neighbours in the control net, and no quad falls below the mesh's starting worst quality:
//! the result is never worse than the start.
//!
//! [`Method`]s: [`Method::Local`] (default) is block coordinate descent, one control point at a
//! time by [`Powell`]'s method, points coloured so that one colour shares no quad and is solved
//! in parallel; [`Method::Global`] is the paper's single Powell run over all variables;
//! [`Method::Laplacian`] and [`Method::Vertex`] are baselines that move the quad vertices
//! directly.
//!
//! ```
//! use imesh_curves::{fit_edges, simplify, CurveGraph, FitOptions, GraphEdge, SimplifyOptions};
//! use imesh_geom::Point;
//! use imesh_optim::{optimise, Method, OptimOptions};
//! use imesh_quad::{remesh, QuadOptions};
//! // A 20 × 20 domain holding a disc of radius 6, as a 32-gon.
//! let mut points = vec![Point::new(0.0, 0.0), Point::new(20.0, 0.0), Point::new(20.0, 20.0), Point::new(0.0, 20.0)];
//! let mut edges: Vec<GraphEdge> = (0..4u32).map(|i| GraphEdge { ends: [i, (i + 1) % 4], labels: [0, u32::MAX] }).collect();
//! for i in 0..32u32 {
//!     let a = f64::from(i) * std::f64::consts::TAU / 32.0;
//!     points.push(Point::new(10.0 + 6.0 * a.cos(), 10.0 + 6.0 * a.sin()));
//!     edges.push(GraphEdge { ends: [4 + i, 4 + (i + 1) % 32], labels: [1, 0] });
//! }
//! let mut g = CurveGraph::new(points, edges)?;
//! g.pin_domain_corners(20.0, 20.0);
//! let s = simplify(&g, &SimplifyOptions { tolerance: 0.5 })?;
//! let fits = fit_edges(&s, &g, &FitOptions::default());
//! let curves: Vec<_> = fits.fits.iter().map(|f| f.curve).collect();
//! let mut r = remesh(&s.graph, &curves, &QuadOptions::default())?;
//! let report = optimise(&mut r, &OptimOptions::default())?;
//! assert!(report.energy_after < report.energy_before);
//! assert!(report.after.shape_and_size.min >= report.before.shape_and_size.min);
//! assert!((0..r.mesh.quads.len()).all(|q| r.mesh.is_valid(q)));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod energy;
mod global;
mod laplacian;
mod local;
mod powell;
mod variables;

pub use energy::{is_valid, Metric};
pub use powell::Powell;

use std::time::Instant;

use imesh_geom::Point;
use imesh_quad::Remesh;
use imesh_quality::QuadQuality;
use rayon::prelude::*;

use crate::variables::Variables;

/// How the mesh is optimised.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Method {
    /// Leave the mesh as it is.
    None,
    /// Baseline: Laplacian smoothing of the free quad vertices (each to the mean of its edge
    /// neighbours, kept only when its quads stay valid).
    Laplacian,
    /// Baseline: the local optimisation moving free quad vertices instead of control points.
    Vertex,
    /// Block coordinate descent over the free control points (default).
    #[default]
    Local,
    /// One Powell run over all free control points at once, as the paper does (slow: for
    /// comparison and small meshes).
    Global,
}

/// Options of [`optimise`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OptimOptions {
    /// The method.
    pub method: Method,
    /// The quality the energy is built on.
    pub metric: Metric,
    /// Sweeps stop when one lowers the energy by less than this fraction.
    pub tolerance: f64,
    /// Most sweeps (local, vertex and Laplacian modes).
    pub max_sweeps: usize,
    /// Most Powell iterations of each local solve.
    pub local_iterations: u64,
    /// Most Powell iterations of the global run.
    pub global_iterations: u64,
}

impl Default for OptimOptions {
    fn default() -> Self {
        Self {
            method: Method::Local,
            metric: Metric::ShapeAndSize,
            tolerance: 1e-2,
            max_sweeps: 40,
            local_iterations: 1,
            global_iterations: 20,
        }
    }
}

/// Errors of [`optimise`].
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum OptimError {
    /// The mesh given has an invalid quad: nothing can be moved feasibly around it.
    #[error("quad {quad} of the mesh to optimise is inverted or degenerate: the quad stage should never give one; please report it")]
    InvalidStart {
        /// The first invalid quad.
        quad: usize,
    },
    /// The global solver failed.
    #[error("the global optimiser failed: {0}")]
    Solver(String),
}

/// What [`optimise`] did.
#[derive(Clone, Debug, PartialEq)]
pub struct OptimReport {
    /// The method run.
    pub method: Method,
    /// The metric of the energy.
    pub metric: Metric,
    /// Points free to move (control points, or quad vertices for the baselines).
    pub variables: usize,
    /// Colours of the local modes (independent sets solved in parallel).
    pub colours: usize,
    /// The fixed average quad area of shape-and-size.
    pub average_area: f64,
    /// Energy `Σ (1 − s)²` before.
    pub energy_before: f64,
    /// Energy after.
    pub energy_after: f64,
    /// Sweeps (local modes) or Powell iterations (global).
    pub sweeps: usize,
    /// Wall-clock seconds.
    pub seconds: f64,
    /// Quality before.
    pub before: QuadQuality,
    /// Quality after.
    pub after: QuadQuality,
}

/// What every solver needs to know about the energy.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Setup<'a> {
    pub quads: &'a [[u32; 4]],
    pub metric: Metric,
    pub average_area: f64,
    /// No quad may fall below this quality (the start's worst)...
    pub floor: f64,
    /// ... nor below this shape (the start's worst), whatever the metric: sizes are never
    /// evened out at the price of the worst shape.
    pub shape_floor: f64,
    pub max_sweeps: usize,
    pub tolerance: f64,
    pub local_iterations: u64,
}

impl Setup<'_> {
    /// The metric of quad `q` over `vertices`.
    pub fn value(&self, vertices: &[Point], q: usize) -> f64 {
        let p = self.quads[q].map(|v| vertices[v as usize]);
        self.metric.value(&p, self.average_area)
    }

    /// The energy term `(1 − s)²` of quad `p`, or `None` when the quad is invalid or falls
    /// below a floor.
    #[inline]
    pub fn term(&self, p: &[Point; 4]) -> Option<f64> {
        if !is_valid(p) {
            return None;
        }
        let q = p.map(|p| [p.x, p.y]);
        let shape = imesh_quality::quad::shape(&q);
        let s = match self.metric {
            Metric::Shape => shape,
            Metric::ShapeAndSize => {
                shape * imesh_quality::quad::relative_size_squared(&q, self.average_area)
            }
        };
        (s >= self.floor && shape >= self.shape_floor).then_some((1.0 - s) * (1.0 - s))
    }

    /// The whole energy over `vertices`. The terms are computed in parallel but summed in
    /// order, so that the sum (and the sweeps' stopping test) is the same on any number of
    /// threads.
    pub fn energy(&self, vertices: &[Point]) -> f64 {
        let terms: Vec<f64> = (0..self.quads.len())
            .into_par_iter()
            .map(|q| (1.0 - self.value(vertices, q)).powi(2))
            .collect();
        terms.iter().sum()
    }
}

fn quality(vertices: &[Point], quads: &[[u32; 4]]) -> QuadQuality {
    let v: Vec<[f64; 2]> = vertices.iter().map(|p| [p.x, p.y]).collect();
    QuadQuality::of(&v, quads)
}

/// Optimises the quad mesh of `remesh` in place (its control net too, in the control-point
/// modes), keeping every quad valid and every constrained point where it was.
///
/// # Errors
/// [`OptimError::InvalidStart`] when the mesh given has an invalid quad;
/// [`OptimError::Solver`] if argmin fails in the global mode.
pub fn optimise(remesh: &mut Remesh, options: &OptimOptions) -> Result<OptimReport, OptimError> {
    let clock = Instant::now();
    let Remesh {
        dt,
        elements,
        net,
        mesh,
        ..
    } = remesh;
    if let Some(quad) = (0..mesh.quads.len()).find(|&q| !mesh.is_valid(q)) {
        return Err(OptimError::InvalidStart { quad });
    }
    let before = quality(&mesh.vertices, &mesh.quads);
    let quads = mesh.quads.clone();
    let average_area = if quads.is_empty() {
        0.0
    } else {
        mesh.area() / quads.len() as f64
    };
    let mut setup = Setup {
        quads: &quads,
        metric: options.metric,
        average_area,
        floor: 0.0,
        shape_floor: 0.0,
        max_sweeps: options.max_sweeps,
        tolerance: options.tolerance,
        local_iterations: options.local_iterations.max(1),
    };
    setup.floor = (0..quads.len())
        .into_par_iter()
        .map(|q| setup.value(&mesh.vertices, q))
        .reduce(|| f64::INFINITY, f64::min);
    setup.shape_floor = before.shape.min;
    let energy_before = setup.energy(&mesh.vertices);
    let t = &dt.triangulation;
    let (variables, colours, sweeps) = match options.method {
        Method::None => (0, 0, 0),
        Method::Laplacian => {
            let vars = Variables::vertices(t, elements, mesh);
            let sweeps = laplacian::smooth(&vars, &mut mesh.vertices, &setup);
            (vars.len(), 0, sweeps)
        }
        Method::Vertex => {
            let vars = Variables::vertices(t, elements, mesh);
            let sweeps =
                local::descend(&vars, &mut mesh.vertices, None, setup, |v| setup.energy(v));
            (vars.len(), vars.colours.len(), sweeps)
        }
        Method::Local => {
            let vars = Variables::control_points(t, elements, net, mesh);
            let sweeps = local::descend(
                &vars,
                &mut mesh.vertices,
                Some(&mut net.points),
                setup,
                |v| setup.energy(v),
            );
            (vars.len(), vars.colours.len(), sweeps)
        }
        Method::Global => {
            let vars = Variables::control_points(t, elements, net, mesh);
            let iterations = global::minimise(
                &vars,
                &mut mesh.vertices,
                &mut net.points,
                setup,
                options.global_iterations,
            )
            .map_err(|e| OptimError::Solver(e.to_string()))?;
            (vars.len(), 0, iterations)
        }
    };
    let energy_after = setup.energy(&mesh.vertices);
    let after = quality(&mesh.vertices, &mesh.quads);
    Ok(OptimReport {
        method: options.method,
        metric: options.metric,
        variables,
        colours,
        average_area,
        energy_before,
        energy_after,
        sweeps,
        seconds: clock.elapsed().as_secs_f64(),
        before,
        after,
    })
}
