//! # imesh-geom
//!
//! The geometry kernel of imesh: exact predicates, and a Delaunay triangulation built for image
//! meshing, where pixel centres make cocircular and collinear points the normal case.
//!
//! - [`predicates`]: Shewchuk's adaptive exact `orient2d` / `incircle` (through `robust`), used for
//!   every geometric decision.
//! - [`Triangulation`]: index-based half-edges with ghost triangles; incremental Bowyer–Watson
//!   insertion that reports the triangles it created; bulk construction in a Hilbert-sorted biased
//!   randomised order; point location by a remembering stochastic walk; and [`Triangulation::check`],
//!   which verifies everything (including the empty-circle property) with exact predicates.
//! - [`spatial_sort`]: the insertion orders.
//!
//! ```
//! use imesh_geom::{Point, Triangulation};
//!
//! let mut points = Vec::new();
//! for row in 0..50 {
//!     for col in 0..80 {
//!         points.push(Point::pixel_centre(col, row));
//!     }
//! }
//! let (tri, _) = Triangulation::from_points(&points)?;
//! tri.check()?;
//! let hull = tri.hull().len();
//! assert_eq!(tri.num_triangles(), 2 * points.len() - hull - 2);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

#![warn(missing_docs)]

pub mod predicates;
pub mod sample;
pub mod spatial_sort;

mod point;
mod refine;
mod triangulation;

pub use point::Point;
pub use refine::{Candidate, RefineOptions, RefineReport, StopReason};
pub use triangulation::{
    HalfEdgeId, Location, SegmentId, TriangleId, Triangulation, TriangulationDefect, VertexId,
    EXTERIOR,
};

/// The largest coordinate magnitude accepted, 2^100: orientation and in-circle tests multiply
/// up to four coordinate differences, and past this their exact expansions could overflow.
pub const MAX_COORDINATE: f64 = 1_267_650_600_228_229_401_496_703_205_376.0;

/// The smallest non-zero coordinate magnitude accepted, 2^-100: two such coordinates differ by at
/// least 2^-152, and a product of four such differences (2^-608) with its rounding error stays
/// far above the smallest normal `f64`, so exact expansions never underflow.
pub const MIN_COORDINATE: f64 = 1.0 / MAX_COORDINATE;

/// Errors of the geometry kernel.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum GeomError {
    /// A point has a NaN or infinite coordinate.
    #[error("point {index} has a non-finite coordinate ({x}, {y}): give finite coordinates")]
    NonFinitePoint {
        /// Index of the point in the input.
        index: usize,
        /// Its x coordinate.
        x: f64,
        /// Its y coordinate.
        y: f64,
    },
    /// A coordinate too large or too small (but not 0) for the exact predicates.
    #[error("point {index} ({x}, {y}) is out of range: coordinates must be 0 or between {} and {} in magnitude (2^-100 and 2^100, where exact predicates can neither overflow nor underflow): scale the input", MIN_COORDINATE, MAX_COORDINATE)]
    OutOfRange {
        /// Index of the point in the input.
        index: usize,
        /// Its x coordinate.
        x: f64,
        /// Its y coordinate.
        y: f64,
    },
    /// A new segment crosses (or overlaps) an existing one.
    #[error("segment {new:?} crosses segment {existing_id} {existing:?}: segments may only meet at their ends")]
    CrossingSegments {
        /// The new segment's end vertices.
        new: [u32; 2],
        /// The existing segment's end vertices.
        existing: [u32; 2],
        /// The existing segment's id.
        existing_id: u32,
    },
    /// A refinement angle outside (0°, 34°].
    #[error("minimum angle {degrees}° is out of range: give an angle above 0° and at most 34° (Ruppert refinement does not terminate above; 33° is a practical maximum)")]
    BadAngle {
        /// The angle given.
        degrees: f64,
    },
    /// A segment that cannot be inserted.
    #[error("cannot insert segment {a}–{b}: {reason}")]
    BadSegment {
        /// One end.
        a: u32,
        /// The other end.
        b: u32,
        /// Why.
        reason: &'static str,
    },
}
