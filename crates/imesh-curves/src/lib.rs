//! # imesh-curves
//!
//! The curves of a segmented image (DESIGN.md §2, steps 5 and 9; the paper's sections V-A and
//! V-C):
//!
//! - [`CurveGraph`]: the boundary graph (c-edges with the labels on their two sides), its
//!   [`faces`](CurveGraph::faces) and a planarity check;
//! - [`polylines`]: the maximal simple open polylines, cut at vertices of valence ≠ 2, at pinned
//!   vertices (the domain corners) and every closed loop into three pieces;
//! - [`contract_short_links`]: junctions that a boundary much shorter than the elements joins
//!   (four regions meeting at a pixel corner) merged into one;
//! - [`simplify`]: topology-preserving Douglas–Peucker, giving the PSLG G' whose every edge
//!   remembers the chain of original vertices it replaces;
//! - [`CubicBezier`] and [`fit_cubic`]: de Casteljau evaluation and exact splitting, and the
//!   least-squares cubic through a chain with its ends fixed; [`fit_edges`] fits every edge of
//!   G' and reports the errors;
//! - [`open_sharp_corners`]: where two boundaries leave a vertex closer than a quad corner
//!   should be (30°), the curves' ends turned apart within the tolerance
//!   ([`fit_cubic_with_tangents`]);
//! - [`blunt_sharp_tips`]: a region's tip still that sharp cut off where it is about a quad
//!   side wide, the triangle beyond given to a neighbour.
//!
//! ```
//! use imesh_curves::{fit_edges, simplify, CurveGraph, FitOptions, GraphEdge, SimplifyOptions};
//! use imesh_geom::Point;
//! // A disc of radius 20 (label 1) drawn as a 64-gon, inside label 0.
//! let points: Vec<Point> = (0..64)
//!     .map(|i| { let a = f64::from(i) * std::f64::consts::TAU / 64.0; Point::new(50.0 + 20.0 * a.cos(), 50.0 + 20.0 * a.sin()) })
//!     .collect();
//! let edges = (0..64u32).map(|i| GraphEdge { ends: [i, (i + 1) % 64], labels: [1, 0] }).collect();
//! let g = CurveGraph::new(points, edges)?;
//! let s = simplify(&g, &SimplifyOptions::with_tolerance(1.0))?;
//! assert!(s.graph.edges().len() < 64 && s.graph.edges().len() >= 3);
//! let report = fit_edges(&s, &g, &FitOptions::default());
//! assert!(report.max_error < 0.05); // cubics follow the circle far better than the chords
//! # Ok::<(), imesh_curves::CurveError>(())
//! ```

#![warn(missing_docs)]

mod bezier;
mod contract;
mod corners;
mod distance;
mod faces;
mod graph;
mod grid;
mod polyline;
mod simplify;
mod tips;

use rayon::prelude::*;

pub use bezier::{
    fit_cubic, fit_cubic_at, fit_cubic_with_tangents, CubicBezier, CurveFit, FitOptions,
};
pub use contract::{contract_short_links, Contraction};
pub use corners::{open_sharp_corners, CornerOptions, CornerReport, MIN_CORNER_DEG};
pub use distance::{segment_distance, segment_distance_squared, segment_parameter};
pub use graph::{CurveGraph, Face, GraphEdge};
pub use grid::SegmentIndex;
pub use polyline::{polylines, Polyline};
pub use simplify::{
    neck_vertices, sharp_vertices, simplify, Simplification, SimplifyOptions, DEFAULT_TOLERANCE,
    MERGE_SPAN, NECK_RATIO, SHARP_GAIN_DEG, SHARP_SECTOR_DEG, WEDGE_ANGLE_DEG,
};
pub use tips::{blunt_sharp_tips, Blunted, TipOptions};

/// Errors of the curve stage.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum CurveError {
    /// A point with a NaN or infinite coordinate.
    #[error("point {index} has a non-finite coordinate: give finite coordinates")]
    NonFinitePoint {
        /// Its index.
        index: usize,
    },
    /// An edge whose ends are equal or out of range.
    #[error("edge {index} {ends:?} is not an edge between two distinct existing vertices")]
    BadEdge {
        /// Its index.
        index: usize,
        /// Its ends.
        ends: [u32; 2],
    },
    /// Two edges join the same two vertices.
    #[error("two edges join vertices {ends:?}: give each boundary edge once")]
    DuplicateEdge {
        /// The ends.
        ends: [u32; 2],
    },
    /// A vertex index out of range.
    #[error("vertex {vertex} does not exist")]
    BadVertex {
        /// The index.
        vertex: u32,
    },
    /// A graph too large for 32-bit indices.
    #[error("the curve graph has too many points or edges for 32-bit indices")]
    TooLarge,
    /// A negative or non-finite tolerance.
    #[error("simplification tolerance {tolerance} is invalid: give a distance in pixels ≥ 0 (default 2)")]
    BadTolerance {
        /// The tolerance given.
        tolerance: f64,
    },
}

/// The fitted curves of every edge of G' and their errors.
#[derive(Clone, Debug, PartialEq)]
pub struct FitReport {
    /// One fit per edge of G' (same order as [`Simplification::chains`]).
    pub fits: Vec<CurveFit>,
    /// The largest distance from an original vertex to its edge's curve.
    pub max_error: f64,
    /// The root mean square of those distances over all chain points.
    pub rms_error: f64,
    /// The largest distance from a point of a curve to its chain.
    pub max_curve_deviation: f64,
}

/// Fits a cubic Bézier to the original chain of every edge of `s.graph` (`original` is the
/// graph `s` was simplified from; its points are the chains' points). Chains are fitted in
/// parallel (rayon); the result does not depend on the number of threads.
pub fn fit_edges(s: &Simplification, original: &CurveGraph, options: &FitOptions) -> FitReport {
    let fits: Vec<CurveFit> = s
        .chains
        .par_iter()
        .map_init(Vec::new, |chain_points, chain| {
            chain_points.clear();
            chain_points.extend(chain.iter().map(|&v| original.point(v)));
            fit_cubic(chain_points, options)
        })
        .collect();
    FitReport::of(fits, &s.chains)
}

impl FitReport {
    /// The report of `fits`, one per chain of `chains`.
    fn of(fits: Vec<CurveFit>, chains: &[Vec<u32>]) -> Self {
        let mut max_error: f64 = 0.0;
        let mut max_curve_deviation: f64 = 0.0;
        let (mut sum, mut count) = (0.0, 0usize);
        for (fit, chain) in fits.iter().zip(chains) {
            max_error = max_error.max(fit.max_error);
            max_curve_deviation = max_curve_deviation.max(fit.curve_deviation);
            sum += fit.rms_error * fit.rms_error * chain.len() as f64;
            count += chain.len();
        }
        FitReport {
            fits,
            max_error,
            rms_error: if count > 0 {
                (sum / count as f64).sqrt()
            } else {
                0.0
            },
            max_curve_deviation,
        }
    }
}
