//! # imesh-quad
//!
//! Quad remeshing of a segmented image (DESIGN.md §2, steps 6–9; the paper's sections V-B and
//! V-C), from the simplified boundary graph G' and its fitted curves (`imesh-curves`):
//!
//! 1. [`RegionTriangulation`]: DT', the Delaunay triangulation conforming to G' with a label per
//!    triangle, refined for angle and size ([`DensityOptions`]);
//! 2. [`ElementMesh::pair`]: M, triangles paired into strictly convex quads ([`Pairing`]);
//! 3. [`ControlNet`]: a Bézier patch per element (cubic triangular or bicubic), edge control
//!    points shared by neighbours, initially the straight element;
//! 4. [`QuadMesh::build`]: Q, every triangle into 3k² and every quad into 4k² quads
//!    ([`Template`]), with each vertex's canonical coordinates in every element holding it;
//! 5. [`adapt`]: boundary edges take the exact pieces of the fitted curves, and Q follows.
//!
//! [`remesh`] runs them all.
//!
//! ```
//! use imesh_curves::{fit_edges, simplify, CurveGraph, FitOptions, GraphEdge, SimplifyOptions};
//! use imesh_geom::Point;
//! use imesh_quad::{remesh, QuadOptions};
//! // A 20 × 20 domain (label 0) holding a disc of radius 6 (label 1), as a 32-gon.
//! let mut points = vec![Point::new(0.0, 0.0), Point::new(20.0, 0.0), Point::new(20.0, 20.0), Point::new(0.0, 20.0)];
//! let mut edges: Vec<GraphEdge> = (0..4u32).map(|i| GraphEdge { ends: [i, (i + 1) % 4], labels: [0, u32::MAX] }).collect();
//! for i in 0..32u32 {
//!     let a = f64::from(i) * std::f64::consts::TAU / 32.0;
//!     points.push(Point::new(10.0 + 6.0 * a.cos(), 10.0 + 6.0 * a.sin()));
//!     edges.push(GraphEdge { ends: [4 + i, 4 + (i + 1) % 32], labels: [1, 0] });
//! }
//! let mut g = CurveGraph::new(points, edges)?;
//! g.pin_domain_corners(20.0, 20.0);
//! let s = simplify(&g, &SimplifyOptions::with_tolerance(0.5))?;
//! let fits = fit_edges(&s, &g, &FitOptions::default());
//! let curves: Vec<_> = fits.fits.iter().map(|f| f.curve).collect();
//! let r = remesh(&s.graph, &curves, &QuadOptions::default())?;
//! assert!(r.mesh.quads.len() > 0);
//! assert!((0..r.mesh.quads.len()).all(|q| r.mesh.is_valid(q)));
//! assert!((r.mesh.area() - 400.0).abs() < 1e-9 * 400.0);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

#![warn(missing_docs)]

mod adapt;
mod chains;
mod density;
mod dt;
mod mesh;
mod pairing;
mod patch;
mod template;

pub use adapt::{adapt, adapt_within, AdaptReport, EdgeCurve, LOCAL_ROUNDS, POOR_SCALED_JACOBIAN};
pub use chains::BoundaryChain;
pub use density::{uniform_points, uniform_points_with_lattice, BOUNDARY_PIECE, CLEARANCE, STRIP};
pub use dt::{
    DensityOptions, RegionTriangulation, BOUNDARY_CLEARANCE, MAX_TRIANGLE_AREA, NONE,
    SHARP_UNPAIRED_CORNER,
};
pub use mesh::{Holder, QuadMesh, SURE_JACOBIAN};
pub use pairing::{
    Element, ElementMesh, Pairing, LARGE_PAIR, MIN_FEWEST_CORNER, MIN_MATCHING_CORNER,
    MIN_PINNED_CORNER_SHAPE, PINNED_OBTUSE_DEG, SPLIT_MARGIN,
};
pub use patch::{basis, ControlNet, TRIANGLE_SLOTS};
pub use template::{Place, Template};

use imesh_curves::{CubicBezier, CurveGraph};
use imesh_geom::GeomError;

/// Errors of the quad stage.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum QuadError {
    /// G' has no edges.
    #[error("the boundary graph is empty: there is nothing to mesh")]
    EmptyGraph,
    /// A template level out of range.
    #[error("template level {level} is out of range: give 1 to 8")]
    BadLevel {
        /// The level given.
        level: u32,
    },
    /// One curve per G' edge is needed.
    #[error("{curves} curves for {edges} boundary edges: give one fitted curve per edge of G'")]
    CurveCount {
        /// Curves given.
        curves: usize,
        /// Edges of G'.
        edges: usize,
    },
    /// From the geometry kernel (a bad angle, or a G' that is not planar).
    #[error(transparent)]
    Geometry(#[from] GeomError),
    /// The templates would make more quads than allowed.
    #[error("the mesh would have {quads} quads, over the limit of {limit}: raise the limit, or give a larger element size, a larger curve tolerance or a lower template level")]
    TooManyQuads {
        /// Quads the templates would make.
        quads: u64,
        /// The limit.
        limit: u64,
    },
    /// The uniform DT''s lattice would hold more points than refinement may insert.
    #[error("a uniform DT' of spacing {spacing} px would hold {points} lattice points, over the limit of {limit}: give a larger element size")]
    LatticeTooFine {
        /// The spacing asked for.
        spacing: f64,
        /// Lattice points over the domain.
        points: u64,
        /// The limit (the refinement cap).
        limit: u64,
    },
}

/// Options of [`remesh`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct QuadOptions {
    /// Density control of DT'.
    pub density: DensityOptions,
    /// How triangles are paired.
    pub pairing: Pairing,
    /// Template level k (1–8): each triangle gives 3k² quads, each quad 4k².
    pub level: u32,
    /// Most quads the templates may make: checked once the pairing is known, before any
    /// template is built (default: no limit).
    pub max_quads: u64,
}

impl Default for QuadOptions {
    fn default() -> Self {
        Self {
            density: DensityOptions::default(),
            pairing: Pairing::Greedy,
            level: 1,
            max_quads: u64::MAX,
        }
    }
}

/// Everything the quad stage built.
#[derive(Clone, Debug)]
pub struct Remesh {
    /// DT'.
    pub dt: RegionTriangulation,
    /// M.
    pub elements: ElementMesh,
    /// The patches' control net (after adaptation).
    pub net: ControlNet,
    /// Q (after adaptation).
    pub mesh: QuadMesh,
    /// Q's vertices before adaptation (on the straight edges of G').
    pub straight_vertices: Vec<imesh_geom::Point>,
    /// The curve each adapted M edge follows.
    pub edge_curves: Vec<EdgeCurve>,
    /// What adaptation did.
    pub adaptation: AdaptReport,
    /// Seconds spent in each step.
    pub seconds: RemeshSeconds,
}

/// Seconds spent in each step of [`remesh`].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RemeshSeconds {
    /// DT': the conforming Delaunay triangulation of G' and its refinement.
    pub triangulation: f64,
    /// Pairing DT''s triangles into M.
    pub pairing: f64,
    /// The control net and the templates.
    pub templates: f64,
    /// Boundary adaptation.
    pub adaptation: f64,
}

/// The whole quad stage: DT' of `g` (G'), pairing, patches, templates, and adaptation to
/// `curves` (one per edge of `g`, e.g. from [`imesh_curves::fit_edges`]).
///
/// # Errors
/// [`QuadError::BadLevel`], [`QuadError::CurveCount`], [`QuadError::TooManyQuads`], and those of
/// [`RegionTriangulation::new`].
pub fn remesh(
    g: &CurveGraph,
    curves: &[CubicBezier],
    options: &QuadOptions,
) -> Result<Remesh, QuadError> {
    if !(1..=8).contains(&options.level) {
        return Err(QuadError::BadLevel {
            level: options.level,
        });
    }
    if curves.len() != g.edges().len() {
        return Err(QuadError::CurveCount {
            curves: curves.len(),
            edges: g.edges().len(),
        });
    }
    let clock = std::time::Instant::now();
    let mut dt = RegionTriangulation::new(g, &options.density)?;
    let mut triangulation = clock.elapsed().as_secs_f64();
    let mut elements = ElementMesh::pair(&dt.triangulation, options.pairing);
    let paired = clock.elapsed().as_secs_f64();
    if dt.open_sharp_unpaired(&elements, &options.density)? > 0 {
        triangulation += clock.elapsed().as_secs_f64() - paired;
        elements = ElementMesh::pair(&dt.triangulation, options.pairing);
    }
    let pairing = clock.elapsed().as_secs_f64() - triangulation;
    let quads = elements.quad_count(options.level);
    if quads > options.max_quads {
        return Err(QuadError::TooManyQuads {
            quads,
            limit: options.max_quads,
        });
    }
    let mut net = ControlNet::straight(&dt.triangulation, &elements);
    let mut mesh = QuadMesh::build(&dt.triangulation, &elements, &net, options.level);
    let straight_vertices = mesh.vertices.clone();
    let templates = clock.elapsed().as_secs_f64() - triangulation - pairing;
    let (adaptation, edge_curves) = adapt_within(
        &dt,
        g,
        curves,
        &elements,
        &mut net,
        &mut mesh,
        &straight_vertices,
        LOCAL_ROUNDS,
    );
    mesh.snap_to_border(&dt.triangulation, &elements);
    let seconds = RemeshSeconds {
        triangulation,
        pairing,
        templates,
        adaptation: clock.elapsed().as_secs_f64() - triangulation - pairing - templates,
    };
    Ok(Remesh {
        seconds,
        dt,
        elements,
        net,
        mesh,
        straight_vertices,
        edge_curves,
        adaptation,
    })
}
